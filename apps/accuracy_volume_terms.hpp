// `medspring accuracy`: the small-strain diagnostic of the volume term's form (issue 23,
// docs/volumetric-mesh.md, "Locking and the nodal volume term"): per tetrahedron, per node (average nodal
// pressure) and blends.
#pragma once

#include <nlohmann/json.hpp>
#include <vector>

#include "medspring/fem/organ.hpp"
#include "medspring/models/body.hpp"
#include "medspring/models/volumetric_body.hpp"

namespace medspring::cli::accuracy {

struct VolumeTermCase {
  fem::ContactLoad load;
  MatX3 u_fem;                   // the FEM's displacement of the organ's surface nodes
  Vec3 fem_mean = Vec3::Zero();  // the FEM's disk mean
  Index contact = 0;             // the organ's surface node under the disk centre
  bool train = false;
};

/// The linear (rest-stiffness) response of the volumetric springs with the volume term per tetrahedron, per
/// node and blended (beta per tetrahedron + (1 - beta) per node), and of the P1 element with its volumetric
/// part per tetrahedron and per node, against the FEM: held-out contact / RMS / disk-mean errors from E and
/// nu, and after a fit of (scale, volume ratio) on the training cases with either site read-out. `full` is
/// the body from E and nu (springs + volume terms), `springs` the same with volume_scale 0; `organ_nodes`
/// the number of the organ's own surface nodes (the first rows), where the FEM is compared.
nlohmann::json volume_term_variants(const VolumetricMesh& vm, const Body& full, const Body& springs,
                                    double mu, double lambda, Index organ_nodes,
                                    const std::vector<VolumeTermCase>& cases);

}  // namespace medspring::cli::accuracy
