#include "medspring/medial/reconstruction.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include "medspring/core/check.hpp"
#include "medspring/geometry/phantoms.hpp"

namespace medspring {

namespace {

inline Vec3 row3(const MatX3& M, Index i) {
  return {M(i, 0), M(i, 1), M(i, 2)};
}

// Rodrigues rotation of w by angle th about the unit axis k.
inline Vec3 rotate(const Vec3& k, double th, const Vec3& w) {
  const double c = std::cos(th), s = std::sin(th);
  return c * w + s * k.cross(w) + (k.dot(w) * (1.0 - c)) * k;
}

// Axis and angle of the relative rotation F_i^T F_{i+1} (Log of §5.9), angle in [0, pi].
void relative_rotation(const FrameField& F, Index i, Vec3& axis, double& angle) {
  const Mat3 R = F.frame(i).transpose() * F.frame(i + 1);
  Eigen::Quaterniond q(R);
  if (q.w() < 0) q.coeffs() = -q.coeffs();
  const double s = q.vec().norm();
  angle = 2.0 * std::atan2(s, q.w());
  axis = s > 0 ? Vec3(q.vec() / s) : Vec3(Vec3::UnitZ());
}

// Buffer size of the structured-tube normals: 6 planes (positions, normals) of rings x (spokes + 2).
inline std::size_t tube_size(Index rings, Index spokes) {
  return static_cast<std::size_t>(6) * static_cast<std::size_t>(rings) * static_cast<std::size_t>(spokes + 2);
}

// Structured-tube vertex normals (§1.1 grid). The area-weighted normal of vertex P = (i, j) is twice the
// vector area of the polygon of its incident triangles. With the neighbours A = (i, j+1), B = (i+1, j+1),
// C = (i+1, j), D = (i, j-1), E = (i-1, j-1), G = (i-1, j), and the exact quad identity
// 2 area(q0 q1 q2 q3) = (q2 - q0) x (q3 - q1):
//   interior ring, hexagon A B C D E G = quads A B C D + A D E G:
//     (C - A) x (D - B) + (E - A) x (G - D)
//   first ring, polygon P A B C D = quad P A B C + triangle P C D:
//     (B - P) x (C - A) + (C - P) x (D - P)
//   last ring, polygon P D E G A = quad P D E G + triangle P G A:
//     (E - P) x (G - D) + (G - P) x (A - P)
// Positions and normals live in struct-of-arrays planes of n rings x W = M + 2 entries (spoke M - 1,
// spokes 0 .. M - 1, spoke 0), so that a vertex and its six neighbours are at fixed offsets and the
// interior rings form one long, contiguous, vectorised loop (entries computed across a ring boundary
// are never used).
struct Plane {  // x, y, z planes, or a shifted view of them
  const double* x;
  const double* y;
  const double* z;
  Plane at(Index k) const { return {x + k, y + k, z + k}; }
};

// The three ring kinds, over `count` vertices from the start of the views: d, r, u are the rings
// i - 1, i, i + 1 aligned on the vertex (D = r[c-1], P = r[c], A = r[c+1], C = u[c], B = u[c+1],
// E = d[c-1], G = d[c]); only constant offsets from 9 base pointers, so the loops vectorise without
// running out of registers.
void normals_first(Index count, Plane r, Plane u, double* __restrict ox, double* __restrict oy,
                   double* __restrict oz) {  // (B - P) x (C - A) + (C - P) x (D - P)
  const double* __restrict rx = r.x, * __restrict ry = r.y, * __restrict rz = r.z;
  const double* __restrict ux = u.x, * __restrict uy = u.y, * __restrict uz = u.z;
  for (std::ptrdiff_t c = 0; c < count; ++c) {
    const double ax = ux[c + 1] - rx[c], ay = uy[c + 1] - ry[c], az = uz[c + 1] - rz[c];
    const double bx = ux[c] - rx[c + 1], by = uy[c] - ry[c + 1], bz = uz[c] - rz[c + 1];
    const double cx = ux[c] - rx[c], cy = uy[c] - ry[c], cz = uz[c] - rz[c];
    const double dx = rx[c - 1] - rx[c], dy = ry[c - 1] - ry[c], dz = rz[c - 1] - rz[c];
    const double nx = ay * bz - az * by + (cy * dz - cz * dy);
    const double ny = az * bx - ax * bz + (cz * dx - cx * dz);
    const double nz = ax * by - ay * bx + (cx * dy - cy * dx);
    const double l2 = nx * nx + ny * ny + nz * nz;
    const double sc = 1.0 / std::sqrt(l2 + static_cast<double>(l2 == 0.0));  // zero vectors stay zero
    ox[c] = nx * sc;
    oy[c] = ny * sc;
    oz[c] = nz * sc;
  }
}

void normals_interior(Index count, Plane d, Plane r, Plane u, double* __restrict ox, double* __restrict oy,
                      double* __restrict oz) {  // (C - A) x (D - B) + (E - A) x (G - D)
  const double* __restrict dx_ = d.x, * __restrict dy_ = d.y, * __restrict dz_ = d.z;
  const double* __restrict rx = r.x, * __restrict ry = r.y, * __restrict rz = r.z;
  const double* __restrict ux = u.x, * __restrict uy = u.y, * __restrict uz = u.z;
  for (std::ptrdiff_t c = 0; c < count; ++c) {
    const double ax = ux[c] - rx[c + 1], ay = uy[c] - ry[c + 1], az = uz[c] - rz[c + 1];
    const double bx = rx[c - 1] - ux[c + 1], by = ry[c - 1] - uy[c + 1], bz = rz[c - 1] - uz[c + 1];
    const double cx = dx_[c - 1] - rx[c + 1], cy = dy_[c - 1] - ry[c + 1], cz = dz_[c - 1] - rz[c + 1];
    const double dx = dx_[c] - rx[c - 1], dy = dy_[c] - ry[c - 1], dz = dz_[c] - rz[c - 1];
    const double nx = ay * bz - az * by + (cy * dz - cz * dy);
    const double ny = az * bx - ax * bz + (cz * dx - cx * dz);
    const double nz = ax * by - ay * bx + (cx * dy - cy * dx);
    const double l2 = nx * nx + ny * ny + nz * nz;
    const double sc = 1.0 / std::sqrt(l2 + static_cast<double>(l2 == 0.0));  // zero vectors stay zero
    ox[c] = nx * sc;
    oy[c] = ny * sc;
    oz[c] = nz * sc;
  }
}

void normals_last(Index count, Plane d, Plane r, double* __restrict ox, double* __restrict oy,
                  double* __restrict oz) {  // (E - P) x (G - D) + (G - P) x (A - P)
  const double* __restrict dx_ = d.x, * __restrict dy_ = d.y, * __restrict dz_ = d.z;
  const double* __restrict rx = r.x, * __restrict ry = r.y, * __restrict rz = r.z;
  for (std::ptrdiff_t c = 0; c < count; ++c) {
    const double ax = dx_[c - 1] - rx[c], ay = dy_[c - 1] - ry[c], az = dz_[c - 1] - rz[c];
    const double bx = dx_[c] - rx[c - 1], by = dy_[c] - ry[c - 1], bz = dz_[c] - rz[c - 1];
    const double cx = dx_[c] - rx[c], cy = dy_[c] - ry[c], cz = dz_[c] - rz[c];
    const double dx = rx[c + 1] - rx[c], dy = ry[c + 1] - ry[c], dz = rz[c + 1] - rz[c];
    const double nx = ay * bz - az * by + (cy * dz - cz * dy);
    const double ny = az * bx - ax * bz + (cz * dx - cx * dz);
    const double nz = ax * by - ay * bx + (cx * dy - cy * dx);
    const double l2 = nx * nx + ny * ny + nz * nz;
    const double sc = 1.0 / std::sqrt(l2 + static_cast<double>(l2 == 0.0));  // zero vectors stay zero
    ox[c] = nx * sc;
    oy[c] = ny * sc;
    oz[c] = nz * sc;
  }
}

void tube_normals(Index n, Index M, const MatX3& V, double* buf, MatX3& N) {
  const Index W = M + 2, plane = n * W;
  double* X = buf;
  double* Y = X + plane;
  double* Z = Y + plane;
  double* NX = Z + plane;
  double* NY = NX + plane;
  double* NZ = NY + plane;
  const double* v = V.data();
  for (Index i = 0; i < n; ++i) {  // deinterleave with the wrap-around entries
    const double* __restrict vi = v + 3 * i * M;
    double* __restrict x = X + i * W;
    double* __restrict y = Y + i * W;
    double* __restrict z = Z + i * W;
    for (Index j = 0; j < M; ++j) {
      x[j + 1] = vi[3 * j];
      y[j + 1] = vi[3 * j + 1];
      z[j + 1] = vi[3 * j + 2];
    }
    x[0] = x[M];
    y[0] = y[M];
    z[0] = z[M];
    x[M + 1] = x[1];
    y[M + 1] = y[1];
    z[M + 1] = z[1];
  }
  // Vertex (i, j) at c = i W + j + 1; views start at vertex (i, 0) of the first ring of a range.
  const Plane P{X, Y, Z};
  normals_first(M, P.at(1), P.at(W + 1), NX + 1, NY + 1, NZ + 1);
  if (n > 2)  // all interior rings in one range
    normals_interior((n - 2) * W - 2, P.at(1), P.at(W + 1), P.at(2 * W + 1), NX + W + 1, NY + W + 1,
                     NZ + W + 1);
  const Index c = (n - 1) * W + 1;
  normals_last(M, P.at(c - W), P.at(c), NX + c, NY + c, NZ + c);
  double* nd = N.data();
  for (Index i = 0; i < n; ++i) {  // interleave
    const double* __restrict x = NX + i * W + 1;
    const double* __restrict y = NY + i * W + 1;
    const double* __restrict z = NZ + i * W + 1;
    double* __restrict o = nd + 3 * i * M;
    for (Index j = 0; j < M; ++j) {
      o[3 * j] = x[j];
      o[3 * j + 1] = y[j];
      o[3 * j + 2] = z[j];
    }
  }
}

}  // namespace

void finalize_binding(SurfaceBinding& b) {
  b.atom_begin.clear();
  b.ou.clear();
  b.ov.clear();
  b.ot.clear();
  b.planar = false;
  if (b.generic() || !std::is_sorted(b.atom.begin(), b.atom.end())) return;
  b.atom_begin.assign(static_cast<std::size_t>(b.num_atoms) + 1, 0);
  for (Index a : b.atom) ++b.atom_begin[static_cast<std::size_t>(a) + 1];
  for (std::size_t a = 1; a < b.atom_begin.size(); ++a) b.atom_begin[a] += b.atom_begin[a - 1];
  const Index m = b.size();
  b.ou.resize(static_cast<std::size_t>(m));
  b.ov.resize(static_cast<std::size_t>(m));
  b.ot.resize(static_cast<std::size_t>(m));
  b.planar = true;
  for (Index k = 0; k < m; ++k) {
    b.ou[static_cast<std::size_t>(k)] = b.offset(k, 0);
    b.ov[static_cast<std::size_t>(k)] = b.offset(k, 1);
    b.ot[static_cast<std::size_t>(k)] = b.offset(k, 2);
    b.planar = b.planar && b.offset(k, 2) == 0.0;
  }
}

SurfaceBinding bind_offsets(const std::vector<Index>& atom, const MatX3& offsets, Index num_atoms) {
  const Index m = static_cast<Index>(atom.size());
  require(offsets.rows() == m, "binding: ", offsets.rows(), " offsets for ", m, " nodes");
  for (Index k = 0; k < m; ++k) require_index(atom[k], num_atoms, cat("binding: node ", k, ": atom"));
  require_finite_points(offsets, "binding: offset of node");
  SurfaceBinding b;
  b.atom = atom;
  b.offset = offsets;
  b.num_atoms = num_atoms;
  finalize_binding(b);
  return b;
}

SurfaceBinding bind_to_atoms(const MatX3& P0, const std::vector<Index>& atom, const FrameReference& ref) {
  const Index m = static_cast<Index>(atom.size());
  require(P0.rows() == m, "binding: ", P0.rows(), " surface nodes but ", m, " atom indices");
  require_finite_points(P0, "binding: surface node");
  MatX3 O(m, 3);
  for (Index k = 0; k < m; ++k) {
    require_index(atom[k], ref.size(), cat("binding: node ", k, ": atom"));
    const Index a = atom[k];
    O.row(k) = (ref.F0.frame(a).transpose() * (row3(P0, k) - row3(ref.C0, a))).transpose();  // D-13
  }
  return bind_offsets(atom, O, ref.size());
}

PolylinePoint closest_point_on_polyline(const MatX3& C, const Vec3& p) {
  const Index n = static_cast<Index>(C.rows());
  PolylinePoint best;
  best.distance = std::numeric_limits<double>::infinity();
  for (Index i = 0; i + 1 < n; ++i) {
    const Vec3 a = row3(C, i), d = row3(C, i + 1) - a;
    const double dd = d.squaredNorm();
    const double lam = dd > 0 ? std::clamp((p - a).dot(d) / dd, 0.0, 1.0) : 0.0;
    const double dist = (a + lam * d - p).norm();
    if (dist < best.distance) best = {i, lam, dist};
  }
  if (best.lambda == 1.0 && best.segment + 2 < n) best = {best.segment + 1, 0.0, best.distance};
  return best;
}

Mat3 interpolated_frame(const FrameField& F, Index i, double lambda) {
  if (lambda == 0.0) return F.frame(i);
  if (lambda == 1.0) return F.frame(i + 1);
  Vec3 k;
  double th;
  relative_rotation(F, i, k, th);
  return F.frame(i) * Eigen::AngleAxisd(lambda * th, k).toRotationMatrix();
}

SurfaceBinding bind_to_polyline(const MatX3& P0, const FrameReference& ref, VecX* distance) {
  const Index m = static_cast<Index>(P0.rows());
  const Index n = ref.size();
  require(n >= 2, "binding: the polyline needs at least 2 atoms (got ", n, ")");
  require_finite_points(P0, "binding: surface node");
  SurfaceBinding b;
  b.num_atoms = n;
  b.atom.resize(static_cast<std::size_t>(m));
  b.lambda.resize(static_cast<std::size_t>(m));
  b.offset.resize(m, 3);
  if (distance) distance->resize(m);
  MatX3 axis(n - 1, 3);
  VecX angle(n - 1);
  segment_rotations(ref.F0, axis, angle);
  for (Index k = 0; k < m; ++k) {  // §5.9: o = F0(lambda)^T (p0 - C0(lambda))
    const Vec3 p = row3(P0, k);
    const PolylinePoint cp = closest_point_on_polyline(ref.C0, p);
    const Index i = cp.segment;
    const double lam = cp.lambda;
    b.atom[static_cast<std::size_t>(k)] = i;
    b.lambda[static_cast<std::size_t>(k)] = lam;
    if (distance) (*distance)[k] = cp.distance;
    Vec3 o;
    if (lam == 0.0) {
      o = ref.F0.frame(i).transpose() * (p - row3(ref.C0, i));
    } else if (lam == 1.0) {
      o = ref.F0.frame(i + 1).transpose() * (p - row3(ref.C0, i + 1));
    } else {
      const Vec3 c = (1.0 - lam) * row3(ref.C0, i) + lam * row3(ref.C0, i + 1);
      o = rotate(row3(axis, i), -lam * angle[i], ref.F0.frame(i).transpose() * (p - c));
    }
    b.offset.row(k) = o.transpose();
  }
  finalize_binding(b);
  return b;
}

ReconstructionScratch::ReconstructionScratch(Index num_atoms, Index num_faces, Index tube_rings,
                                             Index tube_spokes)
    : axis(std::max<Index>(num_atoms - 1, 0), 3),
      angle(std::max<Index>(num_atoms - 1, 0)),
      face_normals(tube_rings > 0 ? 0 : num_faces, 3),
      tube(tube_rings > 0 ? tube_size(tube_rings, tube_spokes) : 0) {}

void segment_rotations(const FrameField& F, MatX3& axis, VecX& angle) {
  const Index n = F.size();
  for (Index i = 0; i + 1 < n; ++i) {
    Vec3 k;
    double th;
    relative_rotation(F, i, k, th);
    axis.row(i) = k.transpose();
    angle[i] = th;
  }
}

void reconstruct(const SurfaceBinding& b, const MatX3& C, const FrameField& F, ReconstructionScratch& scratch,
                 MatX3& S) {
  if (S.rows() != b.size()) S.resize(b.size(), 3);
  reconstruct(b, C, F, scratch, S.data());
}

void reconstruct(const SurfaceBinding& b, const MatX3& C, const FrameField& F, ReconstructionScratch& scratch,
                 double* P) {  // §5.7: S = C + F o
  const Index m = b.size();
  const double* O = b.offset.data();
  const double* Cd = C.data();
  const double* U = F.u.data();
  const double* V = F.v.data();
  const double* T = F.t.data();
  if (b.generic()) {
    segment_rotations(F, scratch.axis, scratch.angle);
    for (Index k = 0; k < m; ++k) {
      const Index i = b.atom[static_cast<std::size_t>(k)];
      const double lam = b.lambda[static_cast<std::size_t>(k)];
      Vec3 o(O[3 * k], O[3 * k + 1], O[3 * k + 2]);
      Vec3 c;
      Index a = i;
      if (lam == 0.0) {
        c = row3(C, i);
      } else if (lam == 1.0) {
        a = i + 1;
        c = row3(C, a);
      } else {
        c = (1.0 - lam) * row3(C, i) + lam * row3(C, i + 1);
        o = rotate(row3(scratch.axis, i), lam * scratch.angle[i], o);
      }
      const Vec3 p = c + o.x() * row3(F.u, a) + o.y() * row3(F.v, a) + o.z() * row3(F.t, a);
      P[3 * k] = p.x();
      P[3 * k + 1] = p.y();
      P[3 * k + 2] = p.z();
    }
    return;
  }
  if (!b.atom_begin.empty()) {  // structured, grouped by atom: vectorised over the nodes of an atom
    const double* __restrict ou = b.ou.data();
    const double* __restrict ov = b.ov.data();
    const double* __restrict ot = b.ot.data();
    for (Index a = 0; a < b.num_atoms; ++a) {
      const double cx = Cd[3 * a], cy = Cd[3 * a + 1], cz = Cd[3 * a + 2];
      const double ux = U[3 * a], uy = U[3 * a + 1], uz = U[3 * a + 2];
      const double vx = V[3 * a], vy = V[3 * a + 1], vz = V[3 * a + 2];
      const Index k0 = b.atom_begin[a], k1 = b.atom_begin[a + 1];
      double* __restrict out = P + 3 * k0;
      if (b.planar) {
        for (Index k = 0; k < k1 - k0; ++k) {
          const double su = ou[k0 + k], sv = ov[k0 + k];
          out[3 * k] = cx + su * ux + sv * vx;
          out[3 * k + 1] = cy + su * uy + sv * vy;
          out[3 * k + 2] = cz + su * uz + sv * vz;
        }
      } else {
        const double tx = T[3 * a], ty = T[3 * a + 1], tz = T[3 * a + 2];
        for (Index k = 0; k < k1 - k0; ++k) {
          const double su = ou[k0 + k], sv = ov[k0 + k], st = ot[k0 + k];
          out[3 * k] = cx + su * ux + sv * vx + st * tx;
          out[3 * k + 1] = cy + su * uy + sv * vy + st * ty;
          out[3 * k + 2] = cz + su * uz + sv * vz + st * tz;
        }
      }
    }
    return;
  }
  for (Index k = 0; k < m; ++k) {  // structured, unsorted
    const Index a = b.atom[static_cast<std::size_t>(k)];
    const double su = O[3 * k], sv = O[3 * k + 1], st = O[3 * k + 2];
    for (int d = 0; d < 3; ++d)
      P[3 * k + d] = Cd[3 * a + d] + su * U[3 * a + d] + sv * V[3 * a + d] + st * T[3 * a + d];
  }
}

VecX discrete_curvature(const MatX3& C) {
  const Index n = static_cast<Index>(C.rows());
  VecX kappa = VecX::Zero(n);
  for (Index i = 1; i + 1 < n; ++i) {
    const Vec3 e1 = row3(C, i) - row3(C, i - 1), e2 = row3(C, i + 1) - row3(C, i);
    const double l1 = e1.norm(), l2 = e2.norm();
    if (l1 <= 0 || l2 <= 0) continue;
    kappa[i] = (e2 / l2 - e1 / l1).norm() / (0.5 * (l1 + l2));  // 2 sin(alpha/2) / h
  }
  return kappa;
}

CurvatureCheck check_curvature(const MatX3& C, const VecX& rho_max) {
  const VecX kappa = discrete_curvature(C);
  CurvatureCheck r;
  for (Index i = 0; i < kappa.size() && i < rho_max.size(); ++i) {
    const double rk = rho_max[i] * kappa[i];
    r.max_rho_kappa = std::max(r.max_rho_kappa, rk);
    if (rk >= 1.0) {
      ++r.violations;
      if (r.first_atom < 0) r.first_atom = i;
    }
  }
  return r;
}

NormalPlan make_normal_plan(Index num_vertices, const MatX3i& F, Index rings, Index spokes) {
  NormalPlan plan;
  if (rings >= 2 && spokes >= 3 && rings * spokes == num_vertices && F == tube_grid_faces(rings, spokes)) {
    plan.tube_rings = rings;
    plan.tube_spokes = spokes;
  }
  plan.F = F;
  plan.num_vertices = num_vertices;
  plan.offsets.assign(static_cast<std::size_t>(num_vertices) + 1, 0);
  for (Index f = 0; f < F.rows(); ++f)
    for (int c = 0; c < 3; ++c) {
      require_index(F(f, c), num_vertices, cat("normals: face ", f, " vertex"));
      ++plan.offsets[static_cast<std::size_t>(F(f, c)) + 1];
    }
  for (std::size_t i = 1; i < plan.offsets.size(); ++i) plan.offsets[i] += plan.offsets[i - 1];
  plan.faces.resize(static_cast<std::size_t>(3 * F.rows()));
  std::vector<Index> fill(plan.offsets.begin(), plan.offsets.end() - 1);
  for (Index f = 0; f < F.rows(); ++f)
    for (int c = 0; c < 3; ++c) plan.faces[static_cast<std::size_t>(fill[F(f, c)]++)] = f;
  return plan;
}

void vertex_normals(const NormalPlan& plan, const MatX3& V, ReconstructionScratch& scratch, MatX3& N) {
  const Index nf = static_cast<Index>(plan.F.rows());
  const Index nv = plan.num_vertices;
  if (N.rows() != nv) N.resize(nv, 3);
  if (plan.tube_rings > 0) {
    const std::size_t need = tube_size(plan.tube_rings, plan.tube_spokes);
    if (scratch.tube.size() != need) scratch.tube.resize(need);
    tube_normals(plan.tube_rings, plan.tube_spokes, V, scratch.tube.data(), N);
    return;
  }
  if (scratch.face_normals.rows() != nf) scratch.face_normals.resize(nf, 3);
  const double* X = V.data();
  const Index* Fi = plan.F.data();
  double* FN = scratch.face_normals.data();
  for (Index f = 0; f < nf; ++f) {
    const double* a = X + 3 * Fi[3 * f];
    const double* b = X + 3 * Fi[3 * f + 1];
    const double* c = X + 3 * Fi[3 * f + 2];
    const double e1x = b[0] - a[0], e1y = b[1] - a[1], e1z = b[2] - a[2];
    const double e2x = c[0] - a[0], e2y = c[1] - a[1], e2z = c[2] - a[2];
    FN[3 * f] = e1y * e2z - e1z * e2y;
    FN[3 * f + 1] = e1z * e2x - e1x * e2z;
    FN[3 * f + 2] = e1x * e2y - e1y * e2x;
  }
  double* Nd = N.data();
  const Index* off = plan.offsets.data();
  const Index* inc = plan.faces.data();
  for (Index i = 0; i < nv; ++i) {
    double x = 0, y = 0, z = 0;
    for (Index q = off[i]; q < off[i + 1]; ++q) {
      const double* n = FN + 3 * inc[q];
      x += n[0];
      y += n[1];
      z += n[2];
    }
    const double l2 = x * x + y * y + z * z;
    const double s = l2 > 0 ? 1.0 / std::sqrt(l2) : 0.0;
    Nd[3 * i] = x * s;
    Nd[3 * i + 1] = y * s;
    Nd[3 * i + 2] = z * s;
  }
}

}  // namespace medspring
