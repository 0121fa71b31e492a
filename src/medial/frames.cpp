#include "medspring/medial/frames.hpp"

#include <Eigen/SVD>
#include <cmath>

#include "medspring/core/check.hpp"

namespace medspring {

namespace {

constexpr double kChordEps = 1e-9;      // mm, §5.3 degenerate chord
constexpr double kPaperEps = 1e-6;      // |e_z x t| below which eq. (3) is degenerate (§5.4)
constexpr double kReflectEps = 1e-18;   // c1, c2 below which a reflection is skipped (§5.5)
constexpr double kOrthoFallback = 0.5;  // |r - (r.t) t| below this: numerical trouble, use MinRot

inline Vec3 row3(const MatX3& M, Index i) {
  return {M(i, 0), M(i, 1), M(i, 2)};
}
inline void set_row(MatX3& M, Index i, const Vec3& p) {
  M(i, 0) = p.x();
  M(i, 1) = p.y();
  M(i, 2) = p.z();
}

// w projected onto the plane perpendicular to unit t and normalised; falls back to e_x, then e_y.
Vec3 perpendicular_unit(const Vec3& w, const Vec3& t) {
  for (const Vec3& c : {w, Vec3(Vec3::UnitX()), Vec3(Vec3::UnitY())}) {
    Vec3 p = c - c.dot(t) * t;
    const double l = p.norm();
    if (l > 1e-9) return p / l;
  }
  return Vec3::UnitZ();  // unreachable for a unit t
}

// The paper-compatible start of the rest frames (§5.5).
Vec3 paper_compatible_start(const Vec3& t0) {
  const Vec3 c(-t0.y(), t0.x(), 0.0);  // e_z x t0
  if (c.norm() >= 0.1) return c.normalized();
  return perpendicular_unit(Vec3::UnitX(), t0);
}

// Eq. (3) per atom with the documented fallback for degenerate atoms (§5.4).
void paper_frames(const MatX3& T, MatX3& U, MatX3& V, FrameReport& rep) {
  const Index n = static_cast<Index>(T.rows());
  for (Index i = 0; i < n; ++i) {
    const Vec3 t = row3(T, i);
    Vec3 u;
    if (!paper_xoy_spoke(t, u)) {
      ++rep.degenerate;
      if (rep.first_degenerate < 0) rep.first_degenerate = i;
      u = perpendicular_unit(i == 0 ? Vec3(Vec3::UnitX()) : row3(U, i - 1), t);
    }
    set_row(U, i, u);
    set_row(V, i, t.cross(u));
  }
}

// sin and cos of x: Taylor polynomials (Horner in x^2, remainder below 1e-19) for |x| <= 0.8, the library
// otherwise. The TwoEnd roll angles are small, and this keeps 2 n library calls off every update.
inline void sin_cos(double x, double& s, double& c) {
  if (!(std::abs(x) <= 0.8)) {
    s = std::sin(x);
    c = std::cos(x);
    return;
  }
  const double y = x * x;
  double ps = 1.0 / 355687428096000.0;  // 1/17!
  for (const double k : {-1.0 / 1307674368000.0, 1.0 / 6227020800.0, -1.0 / 39916800.0, 1.0 / 362880.0,
                         -1.0 / 5040.0, 1.0 / 120.0, -1.0 / 6.0, 1.0})
    ps = ps * y + k;
  s = x * ps;
  double pc = 1.0 / 6402373705728000.0;  // 1/18!
  for (const double k : {-1.0 / 20922789888000.0, 1.0 / 87178291200.0, -1.0 / 479001600.0, 1.0 / 3628800.0,
                         -1.0 / 40320.0, 1.0 / 720.0, -1.0 / 24.0, 1.0 / 2.0, -1.0})
    pc = pc * y + k;
  c = -pc;
}

}  // namespace

FrameMode parse_frame_mode(const std::string& text) {
  if (text == "rmf" || text == "RMF") return FrameMode::RMF;
  if (text == "paper_xoy" || text == "PaperXOY" || text == "paper") return FrameMode::PaperXOY;
  throw InvalidInput(cat("frame mode: unknown value '", text, "' (expected rmf or paper_xoy)"));
}

FrameAnchor parse_frame_anchor(const std::string& text) {
  if (text == "one_end" || text == "OneEnd") return FrameAnchor::OneEnd;
  if (text == "two_end" || text == "TwoEnd") return FrameAnchor::TwoEnd;
  if (text == "best_fit" || text == "BestFit") return FrameAnchor::BestFit;
  throw InvalidInput(cat("frame anchor: unknown value '", text, "' (expected one_end, two_end or best_fit)"));
}

std::string to_string(FrameMode mode) {
  return mode == FrameMode::PaperXOY ? "paper_xoy" : "rmf";
}

std::string to_string(FrameAnchor anchor) {
  switch (anchor) {
    case FrameAnchor::OneEnd:
      return "one_end";
    case FrameAnchor::TwoEnd:
      return "two_end";
    case FrameAnchor::BestFit:
      return "best_fit";
  }
  return "two_end";
}

void FrameField::resize(Index n) {
  u.resize(n, 3);
  v.resize(n, 3);
  t.resize(n, 3);
  sigma.resize(n);
}

Mat3 FrameField::frame(Index i) const {
  Mat3 R;
  R.col(0) = u.row(i).transpose();
  R.col(1) = v.row(i).transpose();
  R.col(2) = t.row(i).transpose();
  return R;
}

Index compute_tangents(const MatX3& C, MatX3& T, const Vec3* t0_fallback) {  // §5.3, D-10
  const Index n = static_cast<Index>(C.rows());
  Index fallbacks = 0;
  for (Index i = 0; i < n; ++i) {
    const Index lo = i == 0 ? 0 : i - 1;
    const Index hi = i == n - 1 ? n - 1 : i + 1;
    Vec3 d = row3(C, hi) - row3(C, lo);
    double l = d.norm();
    if (l >= kChordEps) {
      set_row(T, i, d / l);
      continue;
    }
    ++fallbacks;
    if (i > 0 && i < n - 1) {  // chain folded back: one-sided chord C_{i+1} - C_i
      d = row3(C, i + 1) - row3(C, i);
      l = d.norm();
      if (l >= kChordEps) {
        set_row(T, i, d / l);
        continue;
      }
    }
    if (i > 0) {
      set_row(T, i, row3(T, i - 1));
    } else {
      set_row(T, i, t0_fallback ? *t0_fallback : Vec3(Vec3::UnitX()));
    }
  }
  return fallbacks;
}

bool paper_xoy_spoke(const Vec3& t, Vec3& u) {  // eq. (3): u = e_z x t / |e_z x t|
  const Vec3 c(-t.y(), t.x(), 0.0);
  const double l = c.norm();
  if (!(l >= kPaperEps * t.norm())) return false;
  u = c / l;
  return true;
}

Vec3 min_rotation(const Vec3& a, const Vec3& b, const Vec3& w, const Vec3& axis) {  // §5.5 MinRot
  const double c = a.dot(b);
  if (c <= -1.0 + 1e-12) return 2.0 * axis.dot(w) * axis - w;  // 180 degrees about axis (perp. to a)
  const Vec3 k = a.cross(b);
  return c * w + k.cross(w) + (k.dot(w) / (1.0 + c)) * k;
}

Index rmf_transport(const MatX3& C, const MatX3& T, const Vec3& u0, MatX3& U, MatX3& V) {  // D-12
  const Index n = static_cast<Index>(C.rows());
  const double* Cd = C.data();
  const double* Td = T.data();
  double* Ud = U.data();
  // Step i maps r_i to r_{i+1} = H2 H1 r_i with the two reflections H1 = I - k1 v1 v1^T, H2 = I - k2 v2 v2^T
  // of Wang et al. (k = 2 / c, or 0 where §5.5 skips the reflection). H2 H1 is orthogonal and takes t_i to
  // t_{i+1}, so r stays unit and perpendicular to the tangent up to rounding: the re-orthonormalisation of
  // §5.5 is applied once per atom in the second loop (equal to the per-step form up to rounding). Only the
  // 3 x 3 product M = H2 H1 = H1 - k2 v2 (H1 v2)^T acts on the serial chain.
  double r0 = u0.x(), r1 = u0.y(), r2 = u0.z();
  Ud[0] = r0;
  Ud[1] = r1;
  Ud[2] = r2;
  for (Index i = 0; i + 1 < n; ++i) {
    const double* c = Cd + 3 * i;
    const double* t = Td + 3 * i;
    const double a0 = c[3] - c[0], a1 = c[4] - c[1], a2 = c[5] - c[2];  // v1
    const double c1 = a0 * a0 + a1 * a1 + a2 * a2;
    const double k1 = c1 >= kReflectEps ? 2.0 / c1 : 0.0;
    const double at = k1 * (a0 * t[0] + a1 * t[1] + a2 * t[2]);
    const double b0 = t[3] - (t[0] - at * a0), b1 = t[4] - (t[1] - at * a1),
                 b2 = t[5] - (t[2] - at * a2);  // v2
    const double c2 = b0 * b0 + b1 * b1 + b2 * b2;
    const double k2 = c2 >= kReflectEps ? 2.0 / c2 : 0.0;
    const double ab = k1 * (a0 * b0 + a1 * b1 + a2 * b2);
    const double w0 = k2 * (b0 - ab * a0), w1 = k2 * (b1 - ab * a1), w2 = k2 * (b2 - ab * a2);  // k2 H1 v2
    const double m00 = 1.0 - k1 * a0 * a0 - b0 * w0, m01 = -k1 * a0 * a1 - b0 * w1,
                 m02 = -k1 * a0 * a2 - b0 * w2;
    const double m10 = -k1 * a1 * a0 - b1 * w0, m11 = 1.0 - k1 * a1 * a1 - b1 * w1,
                 m12 = -k1 * a1 * a2 - b1 * w2;
    const double m20 = -k1 * a2 * a0 - b2 * w0, m21 = -k1 * a2 * a1 - b2 * w1,
                 m22 = 1.0 - k1 * a2 * a2 - b2 * w2;
    const double s0 = m00 * r0 + m01 * r1 + m02 * r2;
    const double s1 = m10 * r0 + m11 * r1 + m12 * r2;
    const double s2 = m20 * r0 + m21 * r1 + m22 * r2;
    r0 = s0;
    r1 = s1;
    r2 = s2;
    double* u = Ud + 3 * (i + 1);
    u[0] = r0;
    u[1] = r1;
    u[2] = r2;
  }
  Index fallbacks = 0;
  for (Index i = 0; i < n; ++i) {  // re-orthonormalise: u_i = normalize(r_i - (r_i.t_i) t_i), v_i = t_i x u_i
    const Vec3 t = row3(T, i);
    Vec3 r = row3(U, i);
    if (i > 0) {
      r -= r.dot(t) * t;
      const double l = r.norm();
      if (l > kOrthoFallback) {
        r /= l;
      } else {  // numerical trouble only (e.g. non-finite atoms): minimal rotation of the previous spoke
        ++fallbacks;
        const Vec3 up = row3(U, i - 1);
        r = perpendicular_unit(min_rotation(row3(T, i - 1), t, up, up), t);
      }
      set_row(U, i, r);
    }
    set_row(V, i, t.cross(r));
  }
  return fallbacks;
}

Mat3 best_fit_rotation(const MatX3& C0, const Vec3& centroid0, const MatX3& C) {  // Kabsch
  const Index n = static_cast<Index>(C.rows());
  Vec3 c = Vec3::Zero();
  for (Index i = 0; i < n; ++i) c += row3(C, i);
  c /= static_cast<double>(n);
  Mat3 H = Mat3::Zero();
  for (Index i = 0; i < n; ++i) H += (row3(C0, i) - centroid0) * (row3(C, i) - c).transpose();
  const Eigen::JacobiSVD<Mat3> svd(H, Eigen::ComputeFullU | Eigen::ComputeFullV);
  const Mat3 Um = svd.matrixU(), Vm = svd.matrixV();
  Mat3 D = Mat3::Identity();
  D(2, 2) = (Vm * Um.transpose()).determinant() < 0 ? -1.0 : 1.0;
  return Vm * D * Um.transpose();
}

FrameReference make_frame_reference(const MatX3& C0, const FrameSettings& settings) {
  const Index n = static_cast<Index>(C0.rows());
  require(n >= 2, "frames: need at least 2 atoms (got ", n, ")");
  require_finite_points(C0, "frames: rest atoms");
  require((C0.row(1) - C0.row(0)).norm() >= kChordEps, "frames: rest atoms 0 and 1 coincide (",
          (C0.row(1) - C0.row(0)).norm(), " mm apart)");
  FrameReference ref;
  ref.settings = settings;
  ref.C0 = C0;
  ref.centroid0 = C0.colwise().mean().transpose();
  ref.F0.resize(n);
  FrameField& F = ref.F0;
  ref.report.degenerate_chords = compute_tangents(C0, F.t, nullptr);
  if (settings.mode == FrameMode::PaperXOY) {
    paper_frames(F.t, F.u, F.v, ref.report);
  } else {
    ref.report.transport_fallbacks = rmf_transport(C0, F.t, paper_compatible_start(row3(F.t, 0)), F.u, F.v);
  }
  return ref;
}

FrameReport compute_frames(const MatX3& C, const FrameReference& ref, FrameField& F) {
  FrameReport rep;
  const Index n = ref.size();
  const Vec3 t00 = row3(ref.F0.t, 0);
  rep.degenerate_chords = compute_tangents(C, F.t, &t00);
  if (ref.settings.mode == FrameMode::PaperXOY) {
    paper_frames(F.t, F.u, F.v, rep);
    return rep;
  }
  const Vec3 t0 = row3(F.t, 0);
  const Vec3 u00 = row3(ref.F0.u, 0);
  Vec3 r0;
  if (ref.settings.anchor == FrameAnchor::BestFit) {
    r0 = best_fit_rotation(ref.C0, ref.centroid0, C) * u00;
  } else {
    r0 = min_rotation(t00, t0, u00, u00);
  }
  r0 = perpendicular_unit(r0, t0);
  rep.transport_fallbacks = rmf_transport(C, F.t, r0, F.u, F.v);
  if (ref.settings.anchor != FrameAnchor::TwoEnd) return rep;
  // TwoEnd: spread the roll mismatch at the last atom along the chain, proportional to chord length.
  const Index l = n - 1;
  const Vec3 tl = row3(F.t, l), ul = row3(F.u, l);
  const Vec3 ustar = min_rotation(row3(ref.F0.t, l), tl, row3(ref.F0.u, l), row3(ref.F0.u, l));
  const double gamma = std::atan2(ul.cross(ustar).dot(tl), ul.dot(ustar));
  rep.gamma = gamma;
  if (gamma == 0.0) return rep;
  F.sigma[0] = 0.0;
  for (Index i = 1; i < n; ++i) F.sigma[i] = F.sigma[i - 1] + (row3(C, i) - row3(C, i - 1)).norm();
  const double total = F.sigma[l];
  if (!(total > 0)) return rep;
  for (Index i = 1; i < n; ++i) {
    const double phi = gamma * F.sigma[i] / total;
    double s, c;
    sin_cos(phi, s, c);
    const Vec3 u = row3(F.u, i), v = row3(F.v, i);
    set_row(F.u, i, c * u + s * v);
    set_row(F.v, i, c * v - s * u);
  }
  return rep;
}

}  // namespace medspring
