#include "medspring/sim/checkpoint.hpp"

#include <cmath>
#include <limits>

#include "medspring/core/binary.hpp"
#include "medspring/core/check.hpp"

namespace medspring {

namespace {

constexpr std::size_t kMaxName = 4096;  // bytes of a stored name
const std::string kKind = "checkpoint";
constexpr std::size_t kMaxExtra = std::size_t{1} << 30;  // application section, bytes

void require_finite_matrix(const MatX3& P, const std::string& what, const char* field) {
  const Index r = first_nonfinite_row(P);
  if (r >= 0) throw InvalidInput(cat(what, ": ", field, "[", r, "] is not finite"));
}

}  // namespace

Checkpoint make_checkpoint(const Simulation& sim) {
  Checkpoint c;
  c.fingerprint = model_fingerprint(sim.model());
  c.model_name = sim.model().name;
  c.body_kind = sim.body().kind();
  c.step = sim.settings().step;
  c.state = sim.state();
  c.loads = sim.loads();
  return c;
}

static_assert(static_cast<int>(Integrator::SymplecticEuler) == 0 &&
              static_cast<int>(Integrator::ImplicitEuler) == 1 &&
              static_cast<int>(Integrator::LinearStatic) == 2);  // the step's integrator byte

std::string encode_checkpoint(const Checkpoint& c) {
  ByteWriter p;  // payload
  p.u64(c.fingerprint);
  p.str(c.model_name, kMaxName);
  p.str(c.body_kind, kMaxName);
  const StepSettings& s = c.step;
  p.f64(s.dt);
  p.u8(static_cast<std::uint8_t>(s.integrator));  // 0 symplectic, 1 implicit, 2 linear static
  p.u8(s.substep ? 1 : 0);
  p.f64(s.safety);
  p.i32(s.max_substeps);
  p.u8(s.guard ? 1 : 0);
  p.f64(s.v_max);
  p.i32(s.max_rollbacks);
  p.f64(s.cg_tolerance);
  p.i32(s.cg_max_iterations);
  p.i32(s.newton_iterations);
  const State& st = c.state;
  p.f64(st.t);
  p.u64(st.frames);
  p.u64(st.substeps);
  p.f64(st.stiffening);
  const Warnings& w = st.warnings;
  for (std::uint64_t v : {w.nonfinite, w.velocity_limit, w.rollbacks, w.unstable_refused, w.substeps_capped,
                          w.cg_not_converged, w.failed})
    p.u64(v);
  const Index n = static_cast<Index>(st.x.rows());
  p.u64(static_cast<std::uint64_t>(n));
  p.doubles(st.x.data(), 3 * n);
  p.doubles(st.v.data(), 3 * n);
  const bool has_fext = st.f_ext.rows() == n;
  const bool has_dv = st.dv.size() == 3 * n;
  p.u8(has_fext ? 1 : 0);
  if (has_fext) p.doubles(st.f_ext.data(), 3 * n);
  p.u8(has_dv ? 1 : 0);
  if (has_dv) p.doubles(st.dv.data(), 3 * n);
  p.u64(c.loads.size());
  for (const PointLoad& L : c.loads) {
    p.i32(L.node);
    p.doubles(L.force.data(), 3);
    p.f64(L.t_on);
    p.f64(L.t_ramp);
    p.f64(L.t_release);
    p.u8(L.ramp_down ? 1 : 0);
  }
  p.str(c.extra, kMaxExtra);
  return frame_payload(kCheckpointMagic, kCheckpointVersion, p.bytes());
}

Checkpoint decode_checkpoint(std::string_view bytes, const std::string& what) {
  std::uint32_t version = 0;
  const std::string_view payload =
      unframe_payload(bytes, kCheckpointMagic, 1, kCheckpointVersion, kKind, what, &version);
  ByteReader r(payload, what, kKind);
  Checkpoint c;
  c.fingerprint = r.u64();
  c.model_name = r.str("model name");
  c.body_kind = r.str("body kind");
  StepSettings& s = c.step;
  s.dt = r.f64();
  const std::uint8_t integ = r.u8();
  if (integ > 2) r.fail(cat("step.integrator: unknown value ", int{integ}));
  s.integrator = static_cast<Integrator>(integ);
  s.substep = r.flag("step.substep");
  s.safety = r.f64();
  s.max_substeps = r.i32();
  s.guard = r.flag("step.guard");
  s.v_max = r.f64();
  s.max_rollbacks = r.i32();
  s.cg_tolerance = r.f64();
  s.cg_max_iterations = r.i32();
  s.newton_iterations = r.i32();
  State& st = c.state;
  st.t = r.f64();
  st.frames = r.u64();
  st.substeps = r.u64();
  st.stiffening = r.f64();
  Warnings& w = st.warnings;
  for (std::uint64_t* v : {&w.nonfinite, &w.velocity_limit, &w.rollbacks, &w.unstable_refused,
                           &w.substeps_capped, &w.cg_not_converged, &w.failed})
    *v = r.u64();
  const Index n = r.count("state nodes", 2 * 3 * sizeof(double));
  st.x.resize(n, 3);
  st.v.resize(n, 3);
  r.doubles(st.x.data(), 3 * n);
  r.doubles(st.v.data(), 3 * n);
  if (r.flag("state.f_ext present")) {
    if (r.left() < 3 * sizeof(double) * static_cast<std::size_t>(n)) r.fail("state.f_ext: truncated");
    st.f_ext.resize(n, 3);
    r.doubles(st.f_ext.data(), 3 * n);
  }
  if (r.flag("state.dv present")) {
    if (r.left() < 3 * sizeof(double) * static_cast<std::size_t>(n)) r.fail("state.dv: truncated");
    st.dv.resize(3 * n);
    r.doubles(st.dv.data(), 3 * n);
  }
  const Index nl = r.count("loads", 4 + 6 * sizeof(double) + 1);
  c.loads.resize(static_cast<std::size_t>(nl));
  for (PointLoad& L : c.loads) {
    L.node = r.i32();
    r.doubles(L.force.data(), 3);
    L.t_on = r.f64();
    L.t_ramp = r.f64();
    L.t_release = r.f64();
    L.ramp_down = r.flag("loads.ramp_down");
  }
  if (version >= 2) c.extra = r.str("extra", kMaxExtra);
  r.finish();
  return c;
}

void apply_checkpoint(const Checkpoint& c, Simulation& sim, const std::string& what) {
  const Model& m = sim.model();
  const std::uint64_t fp = model_fingerprint(m);
  const Index n = m.num_nodes();
  if (c.fingerprint != fp || c.state.x.rows() != n || c.body_kind != sim.body().kind())
    throw InvalidInput(cat(what, ": saved from another model: '", c.model_name, "' (", c.body_kind, ", ",
                           c.state.x.rows(), " nodes, fingerprint ", hex64(c.fingerprint),
                           "), this simulation runs '", m.name, "' (", sim.body().kind(), ", ", n,
                           " nodes, fingerprint ", hex64(fp), ")",
                           c.body_kind == "volumetric" && c.body_kind == sim.body().kind()
                               ? "; a volumetric model's fingerprint covers its volume_precision (float by "
                                 "default; a run saved while double was the default resumes with "
                                 "volume_precision \"double\")"
                               : ""));
  // validate everything before changing the simulation
  const State& in = c.state;
  require_state_in_reach(m, in.x, in.v, what);
  if (in.f_ext.rows() == n) require_finite_matrix(in.f_ext, what, "state.f_ext");
  if (in.dv.size() == 3 * n) require(in.dv.allFinite(), what, ": state.dv is not finite");
  require_finite(in.t, what, ": state.t");
  require(std::isfinite(in.stiffening) && in.stiffening > 0, what, ": state.stiffening must be > 0 (got ",
          in.stiffening, ")");
  try {
    validate_step_settings(m, c.step);
    validate_loads(c.loads, sim.body().num_surface_nodes());
  } catch (const InvalidInput& e) {
    throw InvalidInput(cat(what, ": ", e.what()));
  }
  SimulationSettings settings = sim.settings();
  settings.step = c.step;
  sim.set_settings(settings);
  sim.set_loads(c.loads);
  sim.set_state(in);
  State& st = sim.state();
  if (in.f_ext.rows() == n) st.f_ext = in.f_ext;
  if (in.dv.size() == 3 * n) st.dv = in.dv;  // implicit Euler warm start
}

void save_checkpoint(const std::filesystem::path& path, const Simulation& sim) {
  write_file_atomically(path, encode_checkpoint(make_checkpoint(sim)), kKind);
}

Checkpoint read_checkpoint(const std::filesystem::path& path) {
  return decode_checkpoint(read_file_bytes(path, kKind), path.string());
}

void restore_checkpoint(const std::filesystem::path& path, Simulation& sim) {
  apply_checkpoint(read_checkpoint(path), sim, path.string());
}

}  // namespace medspring
