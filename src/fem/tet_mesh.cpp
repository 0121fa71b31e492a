#include "medspring/fem/tet_mesh.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "process.hpp"

namespace medspring::fem {

namespace fs = std::filesystem;

namespace {

// C3D10 mid-edge slots 4..9 and the corners they join.
constexpr std::array<std::array<int, 2>, 6> kEdges = {{{0, 1}, {1, 2}, {2, 0}, {0, 3}, {1, 3}, {2, 3}}};
// Outward faces of a positively oriented tetrahedron.
constexpr std::array<std::array<int, 3>, 4> kFaces = {{{0, 2, 1}, {0, 1, 3}, {1, 2, 3}, {0, 3, 2}}};

double signed_tet_volume(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  return (b - a).cross(c - a).dot(d - a) / 6.0;
}

int edge_slot(int a, int b) {
  for (int e = 0; e < 6; ++e)
    if ((kEdges[e][0] == a && kEdges[e][1] == b) || (kEdges[e][0] == b && kEdges[e][1] == a)) return 4 + e;
  return -1;
}

// The sizing function of -m: input.mtr (a size per input vertex, TetGen manual §5.2.8) and, when given, the
// background mesh input.b.node / input.b.ele / input.b.mtr that TetGen interpolates sizes from.
void write_sizing(const fs::path& dir, Index num_vertices, const TetgenSettings& s) {
  auto positive = [](const std::vector<double>& v, const char* what) {
    for (std::size_t i = 0; i < v.size(); ++i)
      if (!(std::isfinite(v[i]) && v[i] > 0))
        throw InvalidInput(cat("tet mesh: ", what, " ", i, " is ", v[i], " (sizes must be > 0 mm)"));
  };
  require(static_cast<Index>(s.vertex_sizes.size()) == num_vertices, "tet mesh: ", s.vertex_sizes.size(),
          " vertex sizes for a surface of ", num_vertices, " vertices");
  positive(s.vertex_sizes, "vertex size");
  auto write_mtr = [](const fs::path& file, const std::vector<double>& h) {
    std::ofstream out(file);
    out << std::setprecision(17) << h.size() << " 1\n";
    for (double x : h) out << x << '\n';
    if (!out) throw IoError(cat("cannot write ", file.string()));
  };
  write_mtr(dir / "input.mtr", s.vertex_sizes);
  if (s.background_T.rows() == 0) return;
  const Index nb = static_cast<Index>(s.background_X.rows());
  require(static_cast<Index>(s.background_sizes.size()) == nb, "tet mesh: ", s.background_sizes.size(),
          " background sizes for ", nb, " background nodes");
  positive(s.background_sizes, "background size");
  require(s.background_X.allFinite(), "tet mesh: background nodes must be finite");
  {
    std::ofstream out(dir / "input.b.node");
    out << std::setprecision(17) << nb << " 3 0 0\n";
    for (Index i = 0; i < nb; ++i)
      out << i + 1 << ' ' << s.background_X(i, 0) << ' ' << s.background_X(i, 1) << ' '
          << s.background_X(i, 2) << '\n';
    if (!out) throw IoError(cat("cannot write ", (dir / "input.b.node").string()));
  }
  {
    std::ofstream out(dir / "input.b.ele");
    out << s.background_T.rows() << " 4 0\n";
    for (Index e = 0; e < s.background_T.rows(); ++e) {
      out << e + 1;
      for (int k = 0; k < 4; ++k) {
        const Index v = s.background_T(e, k);
        require(v >= 0 && v < nb, "tet mesh: background element ", e, ": node ", v, " out of range [0, ", nb,
                ")");
        out << ' ' << v + 1;
      }
      out << '\n';
    }
    if (!out) throw IoError(cat("cannot write ", (dir / "input.b.ele").string()));
  }
  write_mtr(dir / "input.b.mtr", s.background_sizes);
}

}  // namespace

TetMesh make_quadratic(const MatX3& X, const MatX4i& T4) {
  const Index n = static_cast<Index>(X.rows());
  require(X.allFinite(), "tet mesh: node coordinates must be finite");
  double scale = 0;
  if (n > 0) scale = (X.colwise().maxCoeff() - X.colwise().minCoeff()).norm();
  TetMesh m;
  std::map<std::pair<Index, Index>, Index> mid;
  std::vector<Vec3> extra;
  m.T.resize(T4.rows(), 10);
  for (Index e = 0; e < T4.rows(); ++e) {
    std::array<Index, 4> c{T4(e, 0), T4(e, 1), T4(e, 2), T4(e, 3)};
    for (Index v : c)
      require(v >= 0 && v < n, "tet mesh: element ", e, ": node ", v, " out of range [0, ", n, ")");
    double vol = signed_tet_volume(X.row(c[0]), X.row(c[1]), X.row(c[2]), X.row(c[3]));
    if (std::abs(vol) <= 1e-14 * scale * scale * scale)
      throw InvalidInput(cat("tet mesh: element ", e, " is flat (volume ", vol, " mm^3)"));
    if (vol < 0) std::swap(c[1], c[2]);
    for (int k = 0; k < 4; ++k) m.T(e, k) = c[k];
    for (int s = 0; s < 6; ++s) {
      Index a = c[kEdges[s][0]], b = c[kEdges[s][1]];
      const auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it == mid.end()) {
        it = mid.emplace(key, n + static_cast<Index>(extra.size())).first;
        extra.push_back(0.5 * (X.row(a) + X.row(b)).transpose());
      }
      m.T(e, 4 + s) = it->second;
    }
  }
  m.X.resize(n + static_cast<Index>(extra.size()), 3);
  m.X.topRows(n) = X;
  for (std::size_t i = 0; i < extra.size(); ++i) m.X.row(n + static_cast<Index>(i)) = extra[i].transpose();
  return m;
}

std::vector<double> graded(double a, double b, int n, double grading) {
  require(n >= 1, "graded: need at least one cell (got ", n, ")");
  require(std::isfinite(a) && std::isfinite(b) && b > a, "graded: need a < b");
  require(std::isfinite(grading) && grading > 0, "graded: grading must be > 0");
  std::vector<double> w(n);
  double total = 0;
  for (int i = 0; i < n; ++i) total += (w[i] = std::pow(grading, i));
  std::vector<double> out(n + 1);
  out[0] = a;
  double acc = 0;
  for (int i = 0; i < n; ++i) {
    acc += w[i];
    out[i + 1] = a + (b - a) * acc / total;
  }
  out[n] = b;
  return out;
}

TetMesh box_mesh(const std::vector<double>& xs, const std::vector<double>& ys,
                 const std::vector<double>& zs) {
  for (const auto* c : {&xs, &ys, &zs}) {
    require(c->size() >= 2, "box mesh: each axis needs >= 2 coordinates");
    for (std::size_t i = 1; i < c->size(); ++i)
      require(std::isfinite((*c)[i]) && (*c)[i] > (*c)[i - 1], "box mesh: coordinates must increase");
  }
  const Index nx = static_cast<Index>(xs.size()), ny = static_cast<Index>(ys.size()),
              nz = static_cast<Index>(zs.size());
  MatX3 X(nx * ny * nz, 3);
  auto id = [&](Index i, Index j, Index k) { return i + nx * (j + ny * k); };
  for (Index k = 0; k < nz; ++k)
    for (Index j = 0; j < ny; ++j)
      for (Index i = 0; i < nx; ++i) X.row(id(i, j, k)) << xs[i], ys[j], zs[k];
  MatX4i T((nx - 1) * (ny - 1) * (nz - 1) * 6, 4);
  Index e = 0;
  const std::array<std::array<int, 3>, 6> perms = {
      {{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};
  for (Index k = 0; k + 1 < nz; ++k)
    for (Index j = 0; j + 1 < ny; ++j)
      for (Index i = 0; i + 1 < nx; ++i)
        for (const auto& p : perms) {
          std::array<Index, 3> o{0, 0, 0};
          T(e, 0) = id(i, j, k);
          for (int s = 0; s < 3; ++s) {
            o[p[s]] = 1;
            T(e, s + 1) = id(i + o[0], j + o[1], k + o[2]);
          }
          ++e;
        }
  return make_quadratic(X, T);
}

TetMesh tet_mesh_from_surface(const SurfaceMesh& surface, const TetgenSettings& settings) {
  const MeshReport rep = require_valid_mesh(surface, "tet mesh: surface", {.closed = true, .manifold = true});
  if (rep.inconsistent_edges > 0)
    throw InvalidInput(
        cat("tet mesh: surface: ", rep.inconsistent_edges, " edges with inconsistent orientation"));
  if (!(rep.signed_volume > 0))
    throw InvalidInput(
        cat("tet mesh: surface: normals point inwards (signed volume ", rep.signed_volume, " mm^3)"));
  require(std::isfinite(settings.max_volume) && settings.max_volume >= 0,
          "tet mesh: max_volume must be >= 0");
  require(settings.radius_edge == 0 || (std::isfinite(settings.radius_edge) && settings.radius_edge >= 1.0),
          "tet mesh: radius_edge must be 0 (no quality bound) or >= 1");
  const fs::path exe = settings.executable.empty() ? detail::find_tool("tetgen", "MEDSPRING_TETGEN",
                                                                       "install the Debian package tetgen")
                                                   : fs::path(settings.executable);
  detail::TempDir dir("medspring-tetgen");
  {
    std::ofstream out(dir.path() / "input.smesh");
    out << std::setprecision(17);
    out << surface.num_vertices() << " 3 0 0\n";
    for (Index i = 0; i < surface.num_vertices(); ++i)
      out << i + 1 << ' ' << surface.V(i, 0) << ' ' << surface.V(i, 1) << ' ' << surface.V(i, 2) << '\n';
    out << surface.num_faces() << " 0\n";
    for (Index f = 0; f < surface.num_faces(); ++f)
      out << "3 " << surface.F(f, 0) + 1 << ' ' << surface.F(f, 1) + 1 << ' ' << surface.F(f, 2) + 1 << '\n';
    out << "0\n0\n";
    if (!out) throw IoError(cat("cannot write ", (dir.path() / "input.smesh").string()));
  }
  const bool metric = !settings.vertex_sizes.empty();
  if (metric) write_sizing(dir.path(), surface.num_vertices(), settings);
  std::ostringstream sw;
  sw << "-p";
  if (settings.radius_edge > 0) sw << "q" << settings.radius_edge;
  if (settings.max_volume > 0) sw << "a" << settings.max_volume;
  if (settings.preserve_surface) sw << "Y";
  if (metric) sw << "m";
  sw << "Q input.smesh";
  const int rc = detail::run_in(dir.path(), exe, sw.str(), "tetgen.log");
  if (rc != 0 || !fs::exists(dir.path() / "input.1.ele"))
    throw SolverError(
        cat("tetgen failed (exit ", rc, "): ", detail::last_lines(dir.path() / "tetgen.log", 6)));
  auto open = [&](const char* name, Index& count, int& per) {
    auto in = std::make_unique<std::ifstream>(dir.path() / name);
    if (!(*in >> count >> per) || count <= 0) throw IoError(cat("tetgen output ", name, ": bad header"));
    std::string rest;
    std::getline(*in, rest);
    return in;
  };
  Index nn = 0, ne = 0;
  int dim = 0, per = 0;
  auto nin = open("input.1.node", nn, dim);
  MatX3 X(nn, 3);
  Index base = 1;
  for (Index i = 0; i < nn; ++i) {
    std::string line;
    if (!std::getline(*nin, line))
      throw IoError(cat("tetgen output input.1.node: ", nn, " nodes announced, ", i, " read"));
    std::istringstream ls(line);
    Index idx = 0;
    if (!(ls >> idx >> X(i, 0) >> X(i, 1) >> X(i, 2)))
      throw IoError(cat("tetgen output input.1.node: node ", i));
    if (i == 0) base = idx;
  }
  auto ein = open("input.1.ele", ne, per);
  require(per == 4, "tetgen output: expected 4 nodes per element (got ", per, ")");
  MatX4i T(ne, 4);
  for (Index e = 0; e < ne; ++e) {
    Index idx = 0;
    if (!(*ein >> idx >> T(e, 0) >> T(e, 1) >> T(e, 2) >> T(e, 3)))
      throw IoError(cat("tetgen output input.1.ele: element ", e));
    T.row(e).array() -= base;
    std::string rest;
    std::getline(*ein, rest);
  }
  return make_quadratic(X, T);
}

MatX6i boundary_faces(const TetMesh& mesh) {
  std::map<std::array<Index, 3>, std::pair<Index, int>> seen;  // sorted corners -> (element, face)
  std::map<std::array<Index, 3>, int> count;
  for (Index e = 0; e < mesh.num_elements(); ++e)
    for (int f = 0; f < 4; ++f) {
      std::array<Index, 3> key{mesh.T(e, kFaces[f][0]), mesh.T(e, kFaces[f][1]), mesh.T(e, kFaces[f][2])};
      std::sort(key.begin(), key.end());
      seen[key] = {e, f};
      ++count[key];
    }
  std::vector<std::pair<Index, int>> faces;
  for (const auto& [key, ef] : seen)
    if (count[key] == 1) faces.push_back(ef);
  MatX6i B(static_cast<Index>(faces.size()), 6);
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const auto [e, f] = faces[i];
    const auto& c = kFaces[f];
    const Index r = static_cast<Index>(i);
    for (int k = 0; k < 3; ++k) {
      B(r, k) = mesh.T(e, c[k]);
      B(r, 3 + k) = mesh.T(e, edge_slot(c[k], c[(k + 1) % 3]));
    }
  }
  return B;
}

double mesh_volume(const TetMesh& mesh) {
  double v = 0;
  for (Index e = 0; e < mesh.num_elements(); ++e)
    v += signed_tet_volume(mesh.X.row(mesh.T(e, 0)), mesh.X.row(mesh.T(e, 1)), mesh.X.row(mesh.T(e, 2)),
                           mesh.X.row(mesh.T(e, 3)));
  return v;
}

std::vector<Index> boundary_nodes(const TetMesh& mesh) {
  const MatX6i B = boundary_faces(mesh);
  std::vector<Index> out(B.data(), B.data() + B.size());
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

PeakStrain peak_strain(const TetMesh& mesh, const MatX3& u) {
  require(u.rows() == mesh.num_nodes(), "peak strain: the displacement has ", u.rows(), " rows, the mesh ",
          mesh.num_nodes(), " nodes");
  require(u.allFinite(), "peak strain: the displacement must be finite");
  PeakStrain p;
  double smin = 1, smax = 1;
  for (Index e = 0; e < mesh.num_elements(); ++e) {
    Mat3 Dm, Ds;
    for (int k = 0; k < 3; ++k) {
      const Index a = mesh.T(e, k + 1), o = mesh.T(e, 0);
      Dm.col(k) = (mesh.X.row(a) - mesh.X.row(o)).transpose();
      Ds.col(k) = Dm.col(k) + (u.row(a) - u.row(o)).transpose();
    }
    const Mat3 F = Ds * Dm.inverse();
    const Eigen::SelfAdjointEigenSolver<Mat3> es(F.transpose() * F, Eigen::EigenvaluesOnly);
    const Vec3 l = es.eigenvalues().cwiseMax(0.0).cwiseSqrt();  // ascending
    if (l(0) < smin) {
      smin = l(0);
      p.compressive_element = e;
    }
    if (l(2) > smax) {
      smax = l(2);
      p.tensile_element = e;
    }
  }
  p.compressive = 1 - smin;
  p.tensile = smax - 1;
  return p;
}

}  // namespace medspring::fem
