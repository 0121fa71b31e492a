// `medspring bench` cases of the volumetric spring kidney (issue 23, docs/volumetric-speed.md): the
// kidney phantom meshed inside by TetGen to about 500, 1,000 and 2,000 nodes, 10 kPa, nu = 0.45, supports on
// the bottom 20 %, 0.5 N on the top node; one update = Simulation::update (a 0.5 ms frame with the sub-steps
// its stable step needs). The same set-up as bench/volumetric_bench.cpp. Needs the fem layer (TetGen).
// kidney_volumetric_2000_explicit_linear_refresh: the same with the opt-in tangent refresh
// (StepSettings::stable_step = refresh; its re-estimate is spread over 15 frames, one product each). Every
// case without a suffix runs the default volume pass, single precision (VolumetricSettings::volume_precision
// = float, the default since h23b); the _f64 cases are the plain, mass-scaled and refresh cases with the
// volume pass in double (the default before h23b, which measured the _f32 cases of then against them).
// kidney_volumetric_2000_explicit_linear_threads2: the default case with StepSettings::threads = 2 (the
// threaded float passes, threaded_volume.hpp; docs/threads.md "Volumetric models").
// kidney_volumetric_2000_linear_static(_disk): the quasi-static linear response (Integrator::LinearStatic,
// docs/linear-response.md) under the 0.5 N on the top node, and spread over the surface nodes within 12 mm of
// it; the warm-up caches the loaded nodes' response.
#include <memory>
#include <string>
#include <vector>

#include "cases.hpp"

#ifdef MEDSPRING_HAVE_FEM
#include "medspring/core/check.hpp"
#include "medspring/fem/organ.hpp"
#include "medspring/fem/volumetric.hpp"
#include "medspring/geometry/phantoms.hpp"
#include "medspring/models/volumetric_body.hpp"
#include "medspring/sim/simulation.hpp"
#endif

namespace medspring::cli {

std::vector<bench::BenchCase> volumetric_bench_cases(const std::string& filter) {
  std::vector<bench::BenchCase> cases;
#ifdef MEDSPRING_HAVE_FEM
  for (const Index target : {500, 1000, 2000})
    for (const int variant :
         {0, 1, 2, 3, 4, 5, 6, 7, 8}) {  // the default; opt-in selective mass scaling;
                                         // the tangent refresh; 3, 4: 0, 1 with the volume
                                         // pass in double; 5: 2 with it; 6: 0 on two
                                         // threads; 7, 8: linear static, point and disk
      // StepSettings::stable_step = refresh, two threads and linear static: 2,000 nodes only
      if (variant >= 5 && target != 2000) continue;
      if (variant == 2 && target != 2000) continue;
      const double mass_scaling_dt = variant == 1 || variant == 4 ? 0.25 : 0.0;
      const bool refresh = variant == 2 || variant == 5, f64 = variant >= 3 && variant <= 5;
      const int threads = variant == 6 ? 2 : 1;
      const bool linear_static = variant >= 7;
      const double disk = variant == 8 ? 12.0 : 0.0;  // mm
      const std::string name =
          linear_static ? cat("kidney_volumetric_", target, "_linear_static", disk > 0 ? "_disk" : "")
                        : cat("kidney_volumetric_", target, "_explicit_linear",
                              mass_scaling_dt > 0 ? "_mass_scaled" : (refresh ? "_refresh" : ""),
                              f64 ? "_f64" : "", threads > 1 ? "_threads2" : "");
      if (!filter.empty() && name.find(filter) == std::string::npos) continue;
      const SurfaceMesh s = kidney_phantom();
      const double zmin = s.V.col(2).minCoeff(), zmax = s.V.col(2).maxCoeff();
      VolumetricSettings st;  // 10 kPa, nu = 0.45
      st.mass_scaling_dt = mass_scaling_dt;
      if (f64) st.volume_precision = VolumePrecision::Double;
      st.fixed = fem::support_nodes(s.V, {Vec3(0, 0, -1), 0.2 * (zmax - zmin)});
      auto body = std::make_shared<const VolumetricBody>(fem::volumetric_mesh(s, {.target_nodes = target}),
                                                         st, "volumetric kidney");
      bench::BenchCase b;
      b.name = name;
      b.group = "kidney";
      b.nodes = body->model().num_nodes();
      b.springs = body->model().num_springs();
      b.setup = [body, refresh, threads, linear_static, disk] {
        SimulationSettings ss;
        ss.normals = false;
        ss.local.enabled = false;
        ss.step.threads = threads;
        if (refresh) ss.step.stable_step = StableStep::Refresh;
        if (linear_static) ss.step.integrator = Integrator::LinearStatic;
        auto sim = std::make_shared<Simulation>(body, ss);
        const MatX3& S = body->rest_surface();
        Index top = 0;
        for (Index i = 0; i < S.rows(); ++i)
          if (S(i, 2) > S(top, 2)) top = i;
        std::vector<Index> loaded{top};
        if (disk > 0) {
          loaded.clear();
          for (Index i = 0; i < S.rows(); ++i)
            if ((S.row(i) - S.row(top)).norm() <= disk) loaded.push_back(i);
        }
        std::vector<PointLoad> loads;
        for (Index i : loaded)
          loads.push_back(
              {.node = i, .force = Vec3(0, 0, -0.5 / static_cast<double>(loaded.size())), .t_ramp = 0});
        sim->set_loads(loads);
        return std::function<void()>([sim] { sim->update(); });
      };
      cases.push_back(std::move(b));
    }
#else
  (void)filter;
#endif
  return cases;
}

}  // namespace medspring::cli
