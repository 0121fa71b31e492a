// Force–indentation of a rigid sphere in the accuracy report (issue 18, docs/accuracy.md, docs/tools.md):
// the CalculiX reference with a frictionless rigid sphere (fem/indentation.hpp) against the Hertz law on a
// half-space block, and MedSpring's sphere tool (sim/tool_sim.hpp) against that reference on an organ.
#pragma once

#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "medspring/fem/indentation.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/models/tissue.hpp"

namespace medspring::cli {

struct IndentationOrgan {
  std::string name;
  SurfaceMesh surface;
  MatX3 atoms;
  TissueOrgan calibration = TissueOrgan::RealKidney;  // which shipped calibration the spring model gets
  Vec3 site = Vec3::Zero();                           // surface point the sphere's axis goes through, mm
  Vec3 direction = Vec3(0, 0, -1);                    // unit, into the organ
  fem::SupportRule support;                           // the same rule as the accuracy tables
};

struct IndentationSettings {
  fem::Material material = fem::Material::from_kpa(10, 0.45);
  double radius = 12.0;                            // sphere radius, mm
  std::vector<double> depths{1.0, 2.0, 3.0, 4.0};  // mm
  int level = 1;                                   // FEM mesh level of the organ (1: the surface as is)
  int hertz_level = 2;                             // level of the Hertz block validation (1..3)
  std::function<void(const std::string&)> note;    // progress lines (may be empty)
};

/// The Hertz validation of the FEM indentation (fem::validate_hertz) as JSON rows.
nlohmann::json hertz_validation_json(int level);

/// The organ study: FEM force per depth, the hybrid (Duffing) model with default and calibrated
/// stiffnesses pressed by a sphere tool to each depth and held to rest, and a Hertz estimate with the
/// organ's local curvature.
nlohmann::json indentation_study(const IndentationOrgan& organ, const IndentationSettings& s);

/// Markdown section of `accuracy.md` from {"hertz": [...], "organs": [...]}.
std::string indentation_markdown(const nlohmann::json& indentation);

}  // namespace medspring::cli
