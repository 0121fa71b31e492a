// C++ reference runs for the Python tests (python/tests/test_reference.py): the same scenes run through
// the engine directly, every array written in hexadecimal floating point ("%a", exact), so the tests can
// check that the Python package gives bit-identical results. Output format, one block per array:
//   <name> <rows> <cols>
//   <rows lines of <cols> hex floats>
#include <cstdio>
#include <memory>
#include <string>

#include "medspring/geometry/phantoms.hpp"
#include "medspring/medial/chain.hpp"
#include "medspring/medial/vessel_phantoms.hpp"
#include "medspring/models/hybrid_kidney.hpp"
#include "medspring/models/smrm_vessel.hpp"
#include "medspring/models/surface_body.hpp"
#include "medspring/physics/static_solve.hpp"
#include "medspring/sim/simulation.hpp"

using namespace medspring;

namespace {

template <class Derived>
void emit(const std::string& name, const Eigen::MatrixBase<Derived>& M) {
  std::printf("%s %ld %ld\n", name.c_str(), static_cast<long>(M.rows()), static_cast<long>(M.cols()));
  for (Eigen::Index r = 0; r < M.rows(); ++r) {
    for (Eigen::Index c = 0; c < M.cols(); ++c) std::printf(c ? " %a" : "%a", static_cast<double>(M(r, c)));
    std::printf("\n");
  }
}

void emit_scalar(const std::string& name, double x) {
  emit(name, Eigen::Matrix<double, 1, 1>::Constant(x));
}

// The CLI demo's kidney press: 1 N on surface node 223 towards atom 21, ramp 20 ms, release at 500 ms.
void kidney_press() {
  auto kidney = std::make_shared<HybridKidney>(hybrid_kidney_phantom());
  const Model& m = kidney->model();
  const Vec3 F = -(m.x0.row(223) - m.x0.row(kidney->atom_dof(21))).normalized().transpose();
  Simulation sim(kidney);
  sim.set_loads({{.node = 223, .force = F, .t_ramp = 20, .t_release = 500}});
  emit("kidney_press.force", F.transpose());
  sim.advance(1000);
  emit("kidney_press.surface_500", sim.surface());
  emit("kidney_press.velocities_500", sim.state().v);
  emit_scalar("kidney_press.hold_mm", (sim.surface().row(223) - kidney->rest_surface().row(223)).norm());
  sim.advance(1000);
  emit("kidney_press.surface_1000", sim.surface());
}

// SMRM vessel phantom with the local overlay: 0.5 N on the contact node of atom 20 along -u_20.
void vessel_local() {
  auto vessel = std::make_shared<SmrmVessel>(smrm_phantom(VesselPath::Arc, CrossSectionShape::Elliptical));
  SimulationSettings s;
  s.local.enabled = true;
  Simulation sim(vessel, s);
  const Vec3 F(0.0, -0.5, 0.2);
  const Index node = vessel->contact_node(20, F);
  emit_scalar("vessel_local.node", node);
  sim.set_loads({{.node = node, .force = F, .t_ramp = 20, .t_release = 300}});
  sim.advance(400);
  emit("vessel_local.surface_200", sim.surface());
  emit("vessel_local.local_displacement_200", sim.local_displacement());
  emit("vessel_local.atoms_200", sim.state().x);
}

// Surface tube with the implicit integrator at dt = 1 ms.
void tube_implicit() {
  SurfaceBodyParams p;
  p.k = 0.08;
  p.duffing.mode = DuffingMode::Absolute;
  auto body = std::make_shared<SurfaceBody>(tube(40, 30, 2.5, 3.0), p, "tube", GridLayout{40, 30});
  SimulationSettings s;
  s.step.dt = 1.0;
  s.step.integrator = Integrator::ImplicitEuler;
  Simulation sim(body, s);
  sim.set_loads({{.node = 607, .force = Vec3(0, -0.5, 0), .t_ramp = 10}});
  sim.advance(150);
  emit("tube_implicit.x_150", sim.state().x);
}

// ALGORITHMS.md §8.2-9: straight-x chain, k_cl 0.2, k_r 0.05, ends fixed, (0, 0.5, 0) N on atom 19.
void chain_static() {
  ChainSettings cs;
  cs.k = 0.2;
  cs.kr = 0.05;
  const Model m = make_chain_model(vessel_phantom_atoms(VesselPath::StraightX, 40, 2.5), cs);
  MatX3 f = MatX3::Zero(40, 3);
  f(19, 1) = 0.5;
  const StaticResult r = static_equilibrium(m, f);
  emit("chain_static.x", r.x);
}

}  // namespace

int main() {
  kidney_press();
  vessel_local();
  tube_implicit();
  chain_static();
  return 0;
}
