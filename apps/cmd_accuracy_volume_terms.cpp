// `medspring accuracy`: the small-strain diagnostic of the volume term's form (issue 23,
// docs/volumetric-mesh.md, "Locking and the nodal volume term"). Linear tetrahedra lock at nu -> 1/2: one
// volume constraint per tetrahedron is about five per node. The per-tetrahedron volume term of the volumetric
// kind inherits it; the average nodal pressure (Bonet & Burton 1998, physics/nodal_volume.hpp) constrains one
// volume per node. Here both, and blends, are solved at rest stiffness on the held-out loads, beside P1 with
// either form.
#include <Eigen/SparseCholesky>
#include <algorithm>
#include <cmath>
#include <functional>
#include <string>

#include "accuracy_volume_terms.hpp"
#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/fem/matching.hpp"
#include "medspring/models/volumetric_moduli.hpp"
#include "medspring/physics/forces.hpp"
#include "medspring/physics/nodal_volume.hpp"

namespace medspring::cli::accuracy {

using json = nlohmann::json;
using Sparse = Eigen::SparseMatrix<double>;

namespace {

Sparse rest_stiffness(const Body& b) {
  return tangent_stiffness(b.model(), b.model().x0, {.clamp_transverse = false, .include_return = true});
}

Sparse nodal_stiffness(const VolumetricMesh& vm, double k) {
  const NodalVolumeTerms N = make_nodal_volume_terms(
      vm.X, vm.T, std::vector<double>(static_cast<std::size_t>(vm.T.rows()), k), "accuracy");
  std::vector<Eigen::Triplet<double>> trip;
  add_nodal_volume_stiffness_triplets(N, vm.X, trip);
  Sparse K(3 * vm.X.rows(), 3 * vm.X.rows());
  K.setFromTriplets(trip.begin(), trip.end());
  return K;
}

// Held-out means and maxima (% of the FEM contact displacement; disk mean: of the FEM disk mean).
struct HeldOut {
  double contact = 0, contact_max = 0, rms = 0, rms_max = 0, mean = 0, mean_max = 0;
  double contact_ratio = 0, mean_ratio = 0;  // model / FEM: |u| at the contact node, disk mean along the load
  json to_json() const {
    return {
        {"contact_pct", contact},         {"contact_max_pct", contact_max}, {"rms_pct", rms},
        {"rms_max_pct", rms_max},         {"disk_mean_pct", mean},          {"disk_mean_max_pct", mean_max},
        {"contact_ratio", contact_ratio}, {"disk_mean_ratio", mean_ratio}};
  }
};

}  // namespace

json volume_term_variants(const VolumetricMesh& vm, const Body& full, const Body& springs, double mu,
                          double lambda, Index organ_nodes, const std::vector<VolumeTermCase>& cases) {
  const Model& m = full.model();
  Index nf = 0;
  const std::vector<Index> map = fem::free_dof_map(m, nf);
  const MatX3 XS = vm.X.topRows(vm.surface_nodes);
  const Index n = static_cast<Index>(vm.X.rows());
  const double kv = std::max(lambda - mu, 0.0), K_bulk = lambda + 2.0 * mu / 3.0;

  // the families: A (springs / P1 deviatoric) and B (the volume term in its form)
  const Sparse Ks = rest_stiffness(springs), Kvt = rest_stiffness(full) - Ks, Kvn = nodal_stiffness(vm, kv);
  const Sparse Kdev = p1_stiffness(vm.X, vm.T, mu, -2.0 * mu / 3.0),
               Kpt = p1_stiffness(vm.X, vm.T, 0, K_bulk), Kpn = nodal_stiffness(vm, K_bulk);

  struct Variant {
    std::string name;
    double beta;  // the per-tetrahedron share of the volume term
    const Sparse* A;
    Sparse B;
  };
  std::vector<Variant> variants;
  for (double beta : {1.0, 0.75, 0.5, 0.25, 0.0})
    variants.push_back({"springs", beta, &Ks, beta * Kvt + (1 - beta) * Kvn});
  variants.push_back({"P1", 1.0, &Kdev, Kpt});
  variants.push_back({"P1", 0.0, &Kdev, Kpn});

  std::vector<fem::ContactLoad> loads;
  for (const auto& c : cases) loads.push_back(c.load);
  // the linear response of a variant with its families scaled by mm: the model's own surface, per load
  auto solve = [&](const Variant& v, const VecX& mm, const std::vector<fem::ContactLoad>& ls) {
    const Sparse K = mm(0) * *v.A + mm(1) * v.B;
    const Eigen::SimplicialLDLT<Sparse> ldlt(fem::restrict_to_free(K, map, nf));
    if (ldlt.info() != Eigen::Success || !(ldlt.vectorD().array() > 0).all())
      throw SolverError("accuracy: volume-term variant: the stiffness at rest is not positive definite");
    std::vector<MatX3> out;
    for (const auto& l : ls) {
      const MatX3 fs = fem::disk_load_linear(XS, vm.F, l.centre, l.radius, l.force);
      VecX r = VecX::Zero(nf);
      for (Index a = 0; a < fs.rows(); ++a)
        for (int d = 0; d < 3; ++d)
          if (const Index q = map[static_cast<std::size_t>(3 * a + d)]; q >= 0) r[q] = fs(a, d);
      const VecX u = ldlt.solve(r);
      if (!u.allFinite()) throw SolverError("accuracy: volume-term variant: the solve is not finite");
      MatX3 us = MatX3::Zero(vm.surface_nodes, 3);
      for (Index a = 0; a < vm.surface_nodes; ++a)
        for (int d = 0; d < 3; ++d)
          if (const Index q = map[static_cast<std::size_t>(3 * a + d)]; q >= 0) us(a, d) = u[q];
      out.push_back(std::move(us));
    }
    return out;
  };
  auto held_out = [&](const std::vector<MatX3>& us) {
    HeldOut h;
    double nh = 0;
    for (std::size_t i = 0; i < cases.size(); ++i) {
      const auto& c = cases[i];
      if (c.train) continue;
      const fem::SurfaceError e = fem::compare(us[i].topRows(organ_nodes), c.u_fem, c.contact);
      const Vec3 dm = fem::disk_mean_linear(XS, vm.F, c.load, us[i]), fd = c.load.force.normalized();
      const double ct = 100 * e.rel(e.contact_error), rms = 100 * e.rel(e.rms),
                   mean = 100 * (dm - c.fem_mean).norm() / c.fem_mean.norm();
      h.contact += ct, h.rms += rms, h.mean += mean, nh += 1;
      h.contact_ratio += e.contact_model / e.contact_fem, h.mean_ratio += dm.dot(fd) / c.fem_mean.dot(fd);
      h.contact_max = std::max(h.contact_max, ct), h.rms_max = std::max(h.rms_max, rms);
      h.mean_max = std::max(h.mean_max, mean);
    }
    if (nh > 0) h.contact /= nh, h.rms /= nh, h.mean /= nh, h.contact_ratio /= nh, h.mean_ratio /= nh;
    return h;
  };
  auto training = [&](bool disk_mean) {
    std::vector<fem::CalibrationCase> t;
    for (const auto& c : cases) {
      if (!c.train) continue;
      fem::CalibrationCase cc{c.load, c.u_fem, c.contact};
      if (disk_mean) {
        cc.mean_weights = fem::disk_mean_weights(XS, vm.F, c.load);
        cc.fem_mean = c.fem_mean;
      }
      t.push_back(std::move(cc));
    }
    return t;
  };

  json rows = json::array();
  for (const Variant& v : variants) {
    json row = {{"model", v.name}, {"beta", v.beta}};
    try {
      row["from_E_nu"] = held_out(solve(v, VecX::Ones(2), loads)).to_json();
      for (bool disk_mean : {false, true}) {
        const std::vector<fem::CalibrationCase> t = training(disk_mean);
        if (t.empty()) continue;
        const VecX mm = fem::calibrate_scale_and_ratio(
            [&](const VecX& x, const std::vector<fem::ContactLoad>& ls) { return solve(v, x, ls); }, t);
        const std::vector<MatX3> us = solve(v, mm, loads);
        json r = held_out(us).to_json();
        r["multipliers"] = {mm(0), mm(1)};
        double cost = 0;  // the fit's training cost (fem::calibration_cost's), to compare the forms
        for (std::size_t i = 0, q = 0; i < cases.size(); ++i) {
          if (!cases[i].train) continue;
          const fem::CalibrationCase& cc = t[q++];
          const double s2 = std::pow(std::max(cc.u_fem.rowwise().norm().maxCoeff(), 1e-12), 2);
          cost +=
              (us[i].topRows(organ_nodes) - cc.u_fem).squaredNorm() / (s2 * static_cast<double>(organ_nodes));
          cost += (fem::site_readout(cc, us[i]) - fem::fem_site_readout(cc)).squaredNorm() / s2;
        }
        r["train_cost"] = cost;
        row[disk_mean ? "fit_disk_mean" : "fit_node"] = r;
      }
    } catch (const Error& e) {
      row["error"] = e.what();
    }
    rows.push_back(row);
  }
  return {{"nodes", n}, {"tetrahedra", vm.T.rows()}, {"variants", rows}};
}

}  // namespace medspring::cli::accuracy
