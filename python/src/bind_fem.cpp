// The FEM reference (docs/accuracy.md) from NumPy: medspring.fem_reference (CalculiX displacement of a
// closed surface under a contact-disk load, at its vertices) and medspring.calibrate (hybrid-model
// stiffnesses fitted to that reference). Needs ccx (calculix-ccx) and tetgen; the GIL is released while
// they run.
#include <optional>
#include <vector>

#include "bind_common.hpp"
#include "bind_params.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/physics/loads.hpp"
#include "medspring/scene/study_settings.hpp"

namespace medspring::python {

using namespace pybind11::literals;

namespace {

fem::SupportRule support_rule(py::handle direction, double depth) {
  return {vec3_arg(direction, "support_direction"), depth};
}

// The training loads of medspring.calibrate and medspring.training_loads: each force row at its centre, or
// with train_forces each centre at each of those magnitudes along its row's direction (the CLI's training
// sites x --train-force, checked by fem::checked_train_forces), centre-major.
std::vector<fem::ContactLoad> training_loads(const MatX3& C, const MatX3& Fs, py::object train_forces,
                                             double radius) {
  std::vector<fem::ContactLoad> loads;
  if (train_forces.is_none()) {
    for (Index i = 0; i < C.rows(); ++i)
      loads.push_back({C.row(i).transpose(), Fs.row(i).transpose(), radius});
    return loads;
  }
  std::vector<double> mags;
  try {
    if (py::isinstance<py::float_>(train_forces) || py::isinstance<py::int_>(train_forces))
      mags.push_back(train_forces.cast<double>());
    else
      for (py::handle f : train_forces.cast<py::sequence>()) mags.push_back(f.cast<double>());
  } catch (const py::cast_error&) {
    throw InvalidInput("calibrate: train_forces must be a force in N or a list of such");
  }
  try {
    mags = fem::checked_train_forces(mags);
  } catch (const InvalidInput& e) {
    throw InvalidInput(cat("calibrate: train_forces ", e.what()));
  }
  for (Index i = 0; i < C.rows(); ++i) {
    const Vec3 dir = Fs.row(i).transpose();
    if (!(dir.norm() > 0))
      throw InvalidInput(cat("calibrate: forces[", i, "] is zero: with train_forces it gives the direction"));
    for (double f : mags) loads.push_back({C.row(i).transpose(), f * dir.normalized(), radius});
  }
  return loads;
}

}  // namespace

void bind_fem(py::module_& m) {
  // One FEM reference case (declared in scene/study_settings.hpp): the defaults of fem_reference below and
  // of medspring.study.fem.
  py::class_<FemCaseSettings> fem_case(m, "FemCaseSettings",
                                       "One FEM reference case of a calibration: E_kPa, nu, radius, "
                                       "support_depth, level (docs/parameters.md).");
  def_params(fem_case);
  settings_helpers(fem_case);
  const FemCaseSettings kCase{};
  m.def(
      "fem_reference",
      [](py::handle vertices, py::handle faces, py::handle centre, py::handle force, double E_kPa, double nu,
         double radius, py::handle support_direction, double support_depth, int level) {
        SurfaceMesh s;
        s.V = points_arg(vertices, "vertices", -1, "V");
        s.F = faces_arg(faces, "faces", s.num_vertices());
        const fem::ContactLoad load{vec3_arg(centre, "centre"), vec3_arg(force, "force"), radius};
        const fem::SupportRule rule = support_rule(support_direction, support_depth);
        if (level < 1 || level > 3) throw InvalidInput("fem_reference: level must be 1, 2 or 3");
        MatX3 u;
        Vec3 disk_mean = Vec3::Zero();
        double secs = 0;
        Index nodes = 0, elements = 0, fixed = 0;
        {
          py::gil_scoped_release release;
          fem::OrganMeshSettings ms;
          ms.subdivisions = level - 1;
          const fem::OrganReference ref(s, fem::Material::from_kpa(E_kPa, nu), rule, ms);
          u = ref.surface_displacement(load, &secs, nullptr, &disk_mean);
          nodes = ref.mesh().num_nodes();
          elements = ref.mesh().num_elements();
          fixed = static_cast<Index>(ref.fixed_fem_nodes().size());
        }
        py::dict out;
        out["displacement"] = py::array_t<double>({u.rows(), Eigen::Index(3)}, u.data());
        out["disk_mean"] = py::array_t<double>(Eigen::Index(3), disk_mean.data());
        out["solve_seconds"] = secs;
        out["fem_nodes"] = nodes;
        out["fem_elements"] = elements;
        out["fixed_fem_nodes"] = fixed;
        return out;
      },
      // the defaults are the declaration's (FemCaseSettings, scene/study_settings.hpp)
      "vertices"_a, "faces"_a, "centre"_a, "force"_a, "E_kPa"_a = kCase.E_kPa, "nu"_a = kCase.nu,
      "radius"_a = kCase.radius, "support_direction"_a = py::make_tuple(0.0, 0.0, -1.0),
      "support_depth"_a = kCase.support_depth, "level"_a = static_cast<int>(kCase.level),
      "FEM displacement (V, 3) in mm of the vertices of a closed surface (mm) under a force (N) spread\n"
      "uniformly over the contact disk |x - centre| < radius (mm), with the surface points within\n"
      "support_depth mm of the extreme point along support_direction fixed. Compressible Neo-Hookean\n"
      "(E in kPa, nu < 0.5), quadratic tetrahedra from TetGen (level 1: the surface as given; 2, 3:\n"
      "subdivided), CalculiX NLGEOM static solve, cached. Returns a dict: displacement, disk_mean (the\n"
      "mean displacement over the loaded disk, (3,) mm), solve_seconds, fem_nodes, fem_elements,\n"
      "fixed_fem_nodes. Raises IoError without ccx, SolverError when it fails.");

  m.def(
      "spring_displacement",
      [](const Body& body, py::handle centre, py::handle force, double radius, bool local) {
        const fem::ContactLoad load{vec3_arg(centre, "centre"), vec3_arg(force, "force"), radius};
        MatX3 u;
        {
          py::gil_scoped_release release;
          u = local ? fem::spring_displacement_local(body, load) : fem::spring_displacement(body, load);
        }
        return py::array_t<double>({u.rows(), Eigen::Index(3)}, u.data());
      },
      "body"_a, "centre"_a, "force"_a, "radius"_a = 8.0, "local"_a = false,
      "Static displacement (S, 3) in mm of a body's surface nodes under a force (N) spread uniformly over\n"
      "the contact disk |x - centre| < radius (mm), exactly as fem_reference loads the FEM (pin the support\n"
      "nodes in the body's settings). local=True adds the local-deformation overlay of the contact node.");

  m.def(
      "calibrate",
      [](py::handle vertices, py::handle faces, py::handle atoms, py::handle centres, py::handle forces,
         double E_kPa, double nu, double radius, py::handle support_direction, double support_depth,
         bool nonlinear, py::object fem_displacements, const std::string& site_readout,
         py::object train_forces, py::object fem_disk_means, double site_weight) {
        SurfaceMesh s;
        s.V = points_arg(vertices, "vertices", -1, "V");
        s.F = faces_arg(faces, "faces", s.num_vertices());
        const MatX3 A = points_arg(atoms, "atoms", -1, "A");
        const MatX3 C = points_arg(centres, "centres", -1, "L");
        const MatX3 Fs = points_arg(forces, "forces", static_cast<Index>(C.rows()), "L");
        const fem::SupportRule rule = support_rule(support_direction, support_depth);
        // The site read-out and the training forces: the same rules as `medspring calibrate --site-readout
        // --train-force` (fem::SiteReadout, fem::checked_train_forces).
        fem::SiteReadout readout = fem::SiteReadout::Node;
        try {
          readout = parse_enum(site_readout, static_cast<fem::SiteReadout*>(nullptr));
        } catch (const InvalidInput& e) {
          throw InvalidInput(cat("calibrate: site_readout ", e.what()));
        }
        const std::vector<fem::ContactLoad> loads = training_loads(C, Fs, train_forces, radius);
        double w_site = fem::kDefaultSiteWeight;  // the rule of `medspring calibrate --site-weight`
        try {
          w_site = fem::checked_site_weight(site_weight);
        } catch (const InvalidInput& e) {
          throw InvalidInput(cat("calibrate: site_weight ", e.what()));
        }
        const Index L = static_cast<Index>(loads.size());
        // Precomputed FEM displacements (one (V, 3) array per training load, e.g. solved as Dask tasks by
        // medspring.study.fem): the fit then runs no CalculiX solve of its own.
        std::vector<MatX3> given;
        if (!fem_displacements.is_none()) {
          const py::sequence seq = fem_displacements.cast<py::sequence>();
          if (static_cast<Index>(py::len(seq)) != L)
            throw InvalidInput(
                cat("calibrate: fem_displacements has ", py::len(seq), " arrays for ", L, " training loads"));
          for (std::size_t i = 0; i < py::len(seq); ++i)
            given.push_back(points_arg(seq[i], cat("fem_displacements[", i, "]"), s.num_vertices(), "V"));
        }
        MatX3 given_means;  // the FEM's disk means of the given displacements (disk-mean read-out)
        if (!fem_disk_means.is_none()) {
          if (given.empty())
            throw InvalidInput(
                "calibrate: fem_disk_means goes with fem_displacements (else they are solved here)");
          if (readout != fem::SiteReadout::DiskMean)
            throw InvalidInput("calibrate: fem_disk_means is read only with site_readout 'disk-mean'");
          given_means = points_arg(fem_disk_means, "fem_disk_means", L, "L");
        } else if (!given.empty() && readout == fem::SiteReadout::DiskMean) {
          throw InvalidInput(
              "calibrate: site_readout 'disk-mean' with fem_displacements needs fem_disk_means (L, 3): each "
              "load's FEM disk mean (fem_reference's 'disk_mean')");
        }
        VecX mult;
        std::vector<fem::CalibrationCase> training;
        {
          py::gil_scoped_release release;
          std::optional<fem::OrganReference> ref;
          if (given.empty()) ref.emplace(s, fem::Material::from_kpa(E_kPa, nu), rule);
          for (Index i = 0; i < L; ++i) {
            fem::CalibrationCase c;
            c.load = loads[static_cast<std::size_t>(i)];
            Vec3 mean = Vec3::Zero();
            if (given.empty())
              c.u_fem = ref->surface_displacement(c.load, nullptr, nullptr, &mean);
            else {
              c.u_fem = given[static_cast<std::size_t>(i)];
              if (given_means.rows() > 0) mean = given_means.row(i).transpose();
            }
            c.contact = nearest_node(s.V, c.load.centre);
            c.site_weight = w_site;
            if (readout == fem::SiteReadout::DiskMean) {  // the model's disk mean on the same surface
              c.mean_weights = fem::disk_mean_weights(s.V, s.F, c.load);
              c.fem_mean = mean;
            }
            training.push_back(std::move(c));
          }
          const std::vector<Index> support = fem::support_nodes(s.V, rule);
          auto response = [&](const VecX& mm, const fem::ContactLoad& load) {
            HybridSettings hs;
            hs.k_surf *= mm(0);
            hs.k_spoke *= mm(1);
            hs.k_cl *= mm(2);
            hs.surface_node.return_k *= mm(3);
            hs.atom_node.return_k *= mm(3);
            hs.nonlinear = nonlinear;
            hs.fixed = support;
            return fem::spring_displacement(HybridKidney(s, A, hs), load);
          };
          mult = fem::calibrate_multipliers(response, 4, training);
        }
        const HybridSettings d;
        py::dict out;
        out["k_surf"] = d.k_surf * mult(0);
        out["k_spoke"] = d.k_spoke * mult(1);
        out["k_cl"] = d.k_cl * mult(2);
        out["k_r"] = d.surface_node.return_k * mult(3);
        out["k_loc"] = d.k_surf * mult(0);
        out["support"] = fem::support_nodes(s.V, rule);
        out["site_readout"] = std::string(to_string(readout));
        out["site_weight"] = w_site;
        out["training_loads"] = L;
        return out;
      },
      "vertices"_a, "faces"_a, "atoms"_a, "centres"_a, "forces"_a, "E_kPa"_a = kCase.E_kPa, "nu"_a = kCase.nu,
      "radius"_a = kCase.radius, "support_direction"_a = py::make_tuple(0.0, 0.0, -1.0),
      "support_depth"_a = kCase.support_depth, "nonlinear"_a = true, "fem_displacements"_a = py::none(),
      "site_readout"_a = std::string(to_string(fem::SiteReadout::Node)), "train_forces"_a = py::none(),
      "fem_disk_means"_a = py::none(), "site_weight"_a = fem::kDefaultSiteWeight,
      "Fits the hybrid model's stiffnesses (k_surf, k_spoke, k_cl, k_r; N/mm) on the surface (vertices,\n"
      "faces; mm) with centerline atoms to the FEM response of a tissue (E in kPa, nu) on the training\n"
      "loads: force rows (L, 3) in N over contact disks at centres (L, 3). The support rule pins the same\n"
      "nodes in both (returned as 'support'). Returns a dict of the fitted parameters; evaluate them on\n"
      "loads you did not train on (see examples/python/fit_kidney_to_tissue.py). fem_displacements: the\n"
      "training loads' FEM displacements (L arrays (V, 3), from fem_reference with the same material,\n"
      "radius and support) instead of solving them here (medspring.study.fem solves them as Dask tasks).\n"
      "site_readout: the fit's site term, 'node' (the surface node nearest the disk centre) or 'disk-mean'\n"
      "(the mean displacement over the loaded disk, the FEM's read-out; with fem_displacements give\n"
      "fem_disk_means (L, 3), fem_reference's 'disk_mean'), as `medspring calibrate --site-readout`.\n"
      "train_forces: a force in N or a list of such (each > 0): every centre is then loaded at each\n"
      "magnitude along its force row's direction, centre-major (L = centres x forces training loads), as\n"
      "`medspring calibrate --train-force`. site_weight: the weight w >= 0 of the site term against the\n"
      "surface term (default 1), as `medspring calibrate --site-weight`. The dict also says 'site_readout',\n"
      "'site_weight' and 'training_loads'.");

  m.def(
      "training_loads",
      [](py::handle centres, py::handle forces, py::object train_forces) {
        const MatX3 C = points_arg(centres, "centres", -1, "L");
        const MatX3 Fs = points_arg(forces, "forces", static_cast<Index>(C.rows()), "L");
        const std::vector<fem::ContactLoad> loads = training_loads(C, Fs, train_forces, 0.0);
        MatX3 Co(static_cast<Index>(loads.size()), 3), Fo(static_cast<Index>(loads.size()), 3);
        for (std::size_t i = 0; i < loads.size(); ++i) {
          Co.row(static_cast<Index>(i)) = loads[i].centre.transpose();
          Fo.row(static_cast<Index>(i)) = loads[i].force.transpose();
        }
        return py::make_tuple(py::array_t<double>({Co.rows(), Eigen::Index(3)}, Co.data()),
                              py::array_t<double>({Fo.rows(), Eigen::Index(3)}, Fo.data()));
      },
      "centres"_a, "forces"_a, "train_forces"_a = py::none(),
      "The training loads medspring.calibrate fits with these arguments, as (centres, forces) arrays (L, "
      "3):\n"
      "the rows as given, or with train_forces (a force in N or a list, each > 0) every centre at each\n"
      "magnitude along its force row's direction, centre-major; refused with calibrate's words otherwise.\n"
      "medspring.study.fem.calibrate solves these loads (the same doubles) before it fits.");
}

}  // namespace medspring::python
