#include "medspring/sim/checkpoint.hpp"

#include <atomic>
#include <cmath>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <system_error>

#include "medspring/core/check.hpp"

namespace medspring {

namespace {

constexpr std::size_t kHeaderSize = 8 + 4 + 4 + 8 + 8;  // magic, version, flags, payload size, checksum
constexpr std::size_t kMaxName = 4096;                  // bytes of a stored name

// Little-endian encoding of fixed-size values, independent of the host byte order.
class Writer {
 public:
  void u8(std::uint8_t v) { out_.push_back(static_cast<char>(v)); }
  void u32(std::uint32_t v) {
    for (int b = 0; b < 4; ++b) u8(static_cast<std::uint8_t>(v >> (8 * b)));
  }
  void u64(std::uint64_t v) {
    for (int b = 0; b < 8; ++b) u8(static_cast<std::uint8_t>(v >> (8 * b)));
  }
  void i32(std::int32_t v) { u32(static_cast<std::uint32_t>(v)); }
  void f64(double v) {
    std::uint64_t u;
    std::memcpy(&u, &v, sizeof u);
    u64(u);
  }
  void str(const std::string& s) {
    u32(static_cast<std::uint32_t>(s.size()));
    out_ += s;
  }
  void doubles(const double* p, Index n) {
    for (Index k = 0; k < n; ++k) f64(p[k]);
  }
  std::string& bytes() { return out_; }

 private:
  std::string out_;
};

class Reader {
 public:
  Reader(std::string_view bytes, const std::string& what) : b_(bytes), what_(what) {}
  std::uint8_t u8() {
    need(1);
    return static_cast<std::uint8_t>(b_[pos_++]);
  }
  std::uint32_t u32() {
    need(4);
    std::uint32_t v = 0;
    for (int b = 0; b < 4; ++b) v |= std::uint32_t{static_cast<std::uint8_t>(b_[pos_++])} << (8 * b);
    return v;
  }
  std::uint64_t u64() {
    need(8);
    std::uint64_t v = 0;
    for (int b = 0; b < 8; ++b) v |= std::uint64_t{static_cast<std::uint8_t>(b_[pos_++])} << (8 * b);
    return v;
  }
  std::int32_t i32() { return static_cast<std::int32_t>(u32()); }
  double f64() {
    const std::uint64_t u = u64();
    double v;
    std::memcpy(&v, &u, sizeof v);
    return v;
  }
  bool flag(const char* field) {
    const std::uint8_t v = u8();
    if (v > 1) fail(cat(field, ": expected 0 or 1 (got ", int{v}, ")"));
    return v == 1;
  }
  std::string str(const char* field) {
    const std::uint32_t n = u32();
    if (n > kMaxName) fail(cat(field, ": length ", n, " exceeds ", kMaxName));
    need(n);
    std::string s(b_.substr(pos_, n));
    pos_ += n;
    return s;
  }
  /// A count of items of `item_bytes` each that must fit in the remaining bytes.
  Index count(const char* field, std::size_t item_bytes) {
    const std::uint64_t n = u64();
    if (n > static_cast<std::uint64_t>(std::numeric_limits<Index>::max()) || n * item_bytes > left())
      fail(cat(field, ": count ", n, " does not fit in the remaining ", left(), " bytes"));
    return static_cast<Index>(n);
  }
  void doubles(double* p, Index n) {
    for (Index k = 0; k < n; ++k) p[k] = f64();
  }
  std::size_t left() const { return b_.size() - pos_; }
  [[noreturn]] void fail(const std::string& msg) const {
    throw IoError(cat(what_, ": malformed checkpoint: ", msg, " (at payload byte ", pos_, ")"));
  }

 private:
  void need(std::size_t n) const {
    if (left() < n) fail(cat("needs ", n, " more bytes, ", left(), " left"));
  }
  std::string_view b_;
  const std::string& what_;
  std::size_t pos_ = 0;
};

template <class T>
std::uint64_t hash_vector(const std::vector<T>& v, std::uint64_t h) {
  const std::uint64_t n = v.size();
  h = fnv1a64(&n, sizeof n, h);
  return v.empty() ? h : fnv1a64(v.data(), v.size() * sizeof(T), h);
}
template <class Derived>
std::uint64_t hash_dense(const Eigen::DenseBase<Derived>& m, std::uint64_t h) {
  const std::uint64_t n = static_cast<std::uint64_t>(m.size());
  h = fnv1a64(&n, sizeof n, h);
  for (Index r = 0; r < m.rows(); ++r)
    for (Index c = 0; c < m.cols(); ++c) {
      const auto v = m.derived()(r, c);
      h = fnv1a64(&v, sizeof v, h);
    }
  return h;
}

std::string hex(std::uint64_t v) {
  static const char* digits = "0123456789abcdef";
  std::string s = "0x";
  for (int b = 15; b >= 0; --b) s += digits[(v >> (4 * b)) & 0xF];
  return s;
}

void require_finite_matrix(const MatX3& P, const std::string& what, const char* field) {
  const Index r = first_nonfinite_row(P);
  if (r >= 0) throw InvalidInput(cat(what, ": ", field, "[", r, "] is not finite"));
}

}  // namespace

std::uint64_t fnv1a64(const void* data, std::size_t n, std::uint64_t h) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t k = 0; k < n; ++k) {
    h ^= p[k];
    h *= 0x100000001b3ULL;
  }
  return h;
}

std::uint64_t model_fingerprint(const Model& m) {
  std::uint64_t h = fnv1a64("medspring-model-v1", 18);
  const std::uint64_t n = static_cast<std::uint64_t>(m.num_nodes());
  h = fnv1a64(&n, sizeof n, h);
  h = hash_dense(m.x0, h);
  h = hash_dense(m.mass, h);
  h = hash_dense(m.damping, h);
  h = hash_dense(m.kr, h);
  h = hash_vector(m.fixed, h);
  const Springs& S = m.springs;
  h = hash_vector(S.i, h);
  h = hash_vector(S.j, h);
  h = hash_vector(S.L0, h);
  h = hash_vector(S.k, h);
  h = hash_vector(S.kp, h);
  const BendingTerms& B = m.bending;
  h = hash_vector(B.a, h);
  h = hash_vector(B.b, h);
  h = hash_vector(B.c, h);
  h = hash_dense(B.kb, h);
  return h;
}

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

std::string encode_checkpoint(const Checkpoint& c) {
  Writer p;  // payload
  p.u64(c.fingerprint);
  p.str(c.model_name.substr(0, kMaxName));
  p.str(c.body_kind.substr(0, kMaxName));
  const StepSettings& s = c.step;
  p.f64(s.dt);
  p.u8(s.integrator == Integrator::ImplicitEuler ? 1 : 0);
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
  const std::string& payload = p.bytes();

  Writer out;
  for (int k = 0; k < 8; ++k) out.u8(static_cast<std::uint8_t>(kCheckpointMagic[k]));
  out.u32(kCheckpointVersion);
  out.u32(0);  // flags (reserved)
  out.u64(payload.size());
  out.u64(fnv1a64(payload.data(), payload.size()));
  out.bytes() += payload;
  return std::move(out.bytes());
}

Checkpoint decode_checkpoint(std::string_view bytes, const std::string& what) {
  if (bytes.size() < kHeaderSize)
    throw IoError(cat(what, ": truncated checkpoint (", bytes.size(), " bytes, the header alone has ",
                      kHeaderSize, ")"));
  if (bytes.substr(0, 8) != std::string_view(kCheckpointMagic, 8))
    throw IoError(cat(what, ": not a MedSpring checkpoint (bad magic)"));
  Reader h(bytes.substr(8, kHeaderSize - 8), what);
  const std::uint32_t version = h.u32();
  if (version != kCheckpointVersion)
    throw IoError(cat(what, ": unsupported checkpoint version ", version, " (this build reads version ",
                      kCheckpointVersion, ")"));
  const std::uint32_t flags = h.u32();
  if (flags != 0) throw IoError(cat(what, ": unsupported checkpoint flags ", flags));
  const std::uint64_t size = h.u64();
  const std::uint64_t sum = h.u64();
  const std::string_view payload = bytes.substr(kHeaderSize);
  if (payload.size() < size)
    throw IoError(cat(what, ": truncated checkpoint (payload has ", payload.size(), " of ", size, " bytes)"));
  if (payload.size() > size)
    throw IoError(cat(what, ": corrupted checkpoint (", payload.size() - size, " bytes after the payload)"));
  const std::uint64_t actual = fnv1a64(payload.data(), payload.size());
  if (actual != sum)
    throw IoError(
        cat(what, ": corrupted checkpoint (checksum ", hex(actual), ", the header says ", hex(sum), ")"));

  Reader r(payload, what);
  Checkpoint c;
  c.fingerprint = r.u64();
  c.model_name = r.str("model name");
  c.body_kind = r.str("body kind");
  StepSettings& s = c.step;
  s.dt = r.f64();
  const std::uint8_t integ = r.u8();
  if (integ > 1) r.fail(cat("step.integrator: unknown value ", int{integ}));
  s.integrator = integ == 1 ? Integrator::ImplicitEuler : Integrator::SymplecticEuler;
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
  if (r.left() != 0) r.fail(cat(r.left(), " unread bytes at the end of the payload"));
  return c;
}

void apply_checkpoint(const Checkpoint& c, Simulation& sim, const std::string& what) {
  const Model& m = sim.model();
  const std::uint64_t fp = model_fingerprint(m);
  const Index n = m.num_nodes();
  if (c.fingerprint != fp || c.state.x.rows() != n || c.body_kind != sim.body().kind())
    throw InvalidInput(cat(what, ": saved from another model: '", c.model_name, "' (", c.body_kind, ", ",
                           c.state.x.rows(), " nodes, fingerprint ", hex(c.fingerprint),
                           "), this simulation runs '", m.name, "' (", sim.body().kind(), ", ", n,
                           " nodes, fingerprint ", hex(fp), ")"));
  // validate everything before changing the simulation
  const State& in = c.state;
  require_finite_matrix(in.x, what, "state.x");
  require_finite_matrix(in.v, what, "state.v");
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
  namespace fs = std::filesystem;
  const std::string bytes = encode_checkpoint(make_checkpoint(sim));
  static std::atomic<unsigned> counter{0};
  std::random_device rd;
  const fs::path tmp = fs::path(path).concat(cat(".tmp-", rd(), "-", counter++));
  auto fail = [&](const std::string& why) {
    std::error_code ec;
    fs::remove(tmp, ec);
    throw IoError(cat(path.string(), ": cannot write checkpoint: ", why));
  };
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) fail(cat("cannot create ", tmp.string()));
    f.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    f.flush();
    if (!f) fail(cat("write to ", tmp.string(), " failed"));
    f.close();
    if (f.fail()) fail(cat("closing ", tmp.string(), " failed"));
  }
  std::error_code ec;
  fs::rename(tmp, path, ec);  // atomic replacement on POSIX file systems
  if (ec) fail(cat("rename from ", tmp.string(), " failed: ", ec.message()));
}

Checkpoint read_checkpoint(const std::filesystem::path& path) {
  std::ifstream f(path, std::ios::binary);
  if (!f) throw IoError(cat(path.string(), ": cannot open checkpoint"));
  const std::string bytes((std::istreambuf_iterator<char>(f)), std::istreambuf_iterator<char>());
  if (f.bad()) throw IoError(cat(path.string(), ": read error"));
  return decode_checkpoint(bytes, path.string());
}

void restore_checkpoint(const std::filesystem::path& path, Simulation& sim) {
  apply_checkpoint(read_checkpoint(path), sim, path.string());
}

}  // namespace medspring
