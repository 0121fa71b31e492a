#include "medspring/fem/calculix.hpp"

#include <Eigen/SVD>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <sstream>

#include "medspring/core/binary.hpp"
#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"
#include "medspring/fem/frd.hpp"
#include "process.hpp"

namespace medspring::fem {

namespace fs = std::filesystem;

void validate_material(const Material& m, const std::string& what) {
  if (!(std::isfinite(m.E) && m.E > 0)) throw InvalidInput(cat(what, ": E must be > 0 (got ", m.E, " MPa)"));
  if (!(std::isfinite(m.nu) && m.nu > -1.0 && m.nu < 0.5))
    throw InvalidInput(cat(what, ": nu must be in (-1, 0.5) (got ", m.nu, ")"));
}

void validate_problem(const FemProblem& p) {
  validate_material(p.material);
  const TetMesh& m = p.mesh;
  const Index n = m.num_nodes();
  require(n > 0 && m.num_elements() > 0, "fem problem: empty mesh");
  require(m.X.allFinite(), "fem problem: node coordinates must be finite");
  require(m.T.minCoeff() >= 0 && m.T.maxCoeff() < n, "fem problem: element node out of range");
  for (Index e = 0; e < m.num_elements(); ++e) {
    const Vec3 a = m.X.row(m.T(e, 0)), b = m.X.row(m.T(e, 1)), c = m.X.row(m.T(e, 2)), d = m.X.row(m.T(e, 3));
    if (!((b - a).cross(c - a).dot(d - a) > 0))
      throw InvalidInput(cat("fem problem: element ", e, " has a non-positive volume"));
  }
  for (std::size_t i = 0; i < p.fixed.size(); ++i)
    require(p.fixed[i] >= 0 && p.fixed[i] < n, "fem problem: fixed[", i, "] = ", p.fixed[i], " out of range");
  for (std::size_t i = 0; i < p.constraints.size(); ++i) {
    const auto& c = p.constraints[i];
    require(c.node >= 0 && c.node < n, "fem problem: constraints[", i, "].node out of range");
    require(c.dof >= 0 && c.dof <= 2, "fem problem: constraints[", i, "].dof must be 0, 1 or 2");
    require(std::isfinite(c.value), "fem problem: constraints[", i, "].value must be finite");
  }
  for (std::size_t i = 0; i < p.loads.size(); ++i) {
    require(p.loads[i].node >= 0 && p.loads[i].node < n, "fem problem: loads[", i, "].node out of range");
    require(p.loads[i].force.allFinite(), "fem problem: loads[", i, "].force must be finite");
  }
  // Rigid motions u = t + w x (x - c): the held dofs must see all six (rank 6).
  const Vec3 c = m.X.colwise().mean();
  std::vector<std::pair<Index, int>> dofs;
  for (Index v : p.fixed)
    for (int d = 0; d < 3; ++d) dofs.emplace_back(v, d);
  for (const auto& k : p.constraints) dofs.emplace_back(k.node, k.dof);
  const double scale = (m.X.colwise().maxCoeff() - m.X.colwise().minCoeff()).norm();
  Eigen::MatrixXd R(static_cast<Index>(dofs.size()), 6);
  for (std::size_t r = 0; r < dofs.size(); ++r) {
    const auto [v, d] = dofs[r];
    const Vec3 x = (Vec3(m.X.row(v)) - c) / scale;
    const Index row = static_cast<Index>(r);
    R.row(row).setZero();
    R(row, d) = 1.0;
    for (int k = 0; k < 3; ++k) R(row, 3 + k) = Vec3::Unit(k).cross(x)(d);
  }
  Index rank = 0;
  if (R.rows() > 0) {
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(R);
    const auto& sv = svd.singularValues();
    for (Index i = 0; i < sv.size(); ++i) rank += sv(i) > 1e-8 * sv(0) ? 1 : 0;
  }
  if (rank < 6)
    throw InvalidInput(cat("fem problem: the supports leave ", 6 - rank,
                           " rigid motion(s) free (fix more nodes, not all on one line)"));
}

std::string write_inp(const FemProblem& p, const FemSettings& s) {
  const TetMesh& m = p.mesh;
  std::ostringstream o;
  o << std::setprecision(13);  // CalculiX reads at most 20 characters a number
  o << "** MedSpring FEM reference (mm, N, MPa)\n*NODE, NSET=NALL\n";
  for (Index i = 0; i < m.num_nodes(); ++i)
    o << i + 1 << ", " << m.X(i, 0) << ", " << m.X(i, 1) << ", " << m.X(i, 2) << '\n';
  o << "*ELEMENT, TYPE=C3D10, ELSET=EALL\n";
  for (Index e = 0; e < m.num_elements(); ++e) {
    o << e + 1;
    for (int k = 0; k < 10; ++k) o << ", " << m.T(e, k) + 1;
    o << '\n';
  }
  o << "*MATERIAL, NAME=TISSUE\n*HYPERELASTIC, NEO HOOKE\n"
    << p.material.c10() << ", " << p.material.d1() << '\n';
  o << "*SOLID SECTION, ELSET=EALL, MATERIAL=TISSUE\n";
  if (!p.fixed.empty()) {
    o << "*BOUNDARY\n";
    for (Index v : p.fixed) o << v + 1 << ", 1, 3\n";
  }
  const int inc = std::max(1, s.increments);
  // initial increment 1 / increments; CalculiX grows it when iterations converge quickly
  o << "*STEP, NLGEOM, INC=1000\n*STATIC\n" << 1.0 / inc << ", 1.0, 1e-6, 1.0\n";
  if (!p.constraints.empty()) {
    o << "*BOUNDARY\n";
    for (const auto& c : p.constraints)
      o << c.node + 1 << ", " << c.dof + 1 << ", " << c.dof + 1 << ", " << c.value << '\n';
  }
  if (!p.loads.empty()) {
    o << "*CLOAD\n";
    for (const auto& l : p.loads)
      for (int d = 0; d < 3; ++d)
        if (l.force(d) != 0.0) o << l.node + 1 << ", " << d + 1 << ", " << l.force(d) << '\n';
  }
  o << (s.reaction_forces ? "*NODE FILE\nU, RF\n*END STEP\n" : "*NODE FILE\nU\n*END STEP\n");
  return o.str();
}

namespace {

fs::path cache_folder(const FemSettings& s) {
  if (!s.cache_dir.empty()) return s.cache_dir;
  if (const char* e = std::getenv("MEDSPRING_FEM_CACHE"); e && *e) return e;
  if (const char* e = std::getenv("XDG_CACHE_HOME"); e && *e) return fs::path(e) / "medspring" / "fem";
  if (const char* e = std::getenv("HOME"); e && *e) return fs::path(e) / ".cache" / "medspring" / "fem";
  return fs::temp_directory_path() / "medspring-fem-cache";
}

constexpr char kCacheMagic[8] = {'M', 'S', 'F', 'E', 'M', 'U', '0', '1'};

bool load_cache(const fs::path& file, Index n, FemResult& r) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return false;
  char magic[8];
  std::int64_t rows = 0;
  double secs = 0;
  if (!in.read(magic, 8) || std::string_view(magic, 8) != std::string_view(kCacheMagic, 8)) return false;
  if (!in.read(reinterpret_cast<char*>(&rows), sizeof rows) || rows != n) return false;
  if (!in.read(reinterpret_cast<char*>(&secs), sizeof secs)) return false;
  MatX3 u(n, 3);
  if (!in.read(reinterpret_cast<char*>(u.data()), static_cast<std::streamsize>(sizeof(double) * 3 * n)))
    return false;
  if (!u.allFinite() || !std::isfinite(secs)) return false;
  r.u = std::move(u);
  r.solve_seconds = secs;
  r.from_cache = true;
  return true;
}

void store_cache(const fs::path& file, const FemResult& r) {
  std::error_code ec;
  fs::create_directories(file.parent_path(), ec);
  const std::int64_t rows = r.u.rows();
  std::string bytes(kCacheMagic, 8);
  bytes.append(reinterpret_cast<const char*>(&rows), sizeof rows);
  bytes.append(reinterpret_cast<const char*>(&r.solve_seconds), sizeof r.solve_seconds);
  bytes.append(reinterpret_cast<const char*>(r.u.data()),
               sizeof(double) * static_cast<std::size_t>(r.u.size()));
  try {
    write_file_atomically(file, bytes, "FEM cache");
  } catch (const IoError&) {
    // a cache that cannot be written is no error: the result is still returned
  }
}

}  // namespace

FemResult solve(const FemProblem& p, const FemSettings& s) {
  validate_problem(p);
  const std::string deck = write_inp(p, s);
  FemResult r;
  r.key = fnv1a64(deck.data(), deck.size());
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(r.key));
  const fs::path cache_file = cache_folder(s) / (std::string(hex) + ".u");
  const Index n = p.mesh.num_nodes();
  if (s.use_cache && load_cache(cache_file, s.reaction_forces ? 2 * n : n, r)) {
    if (s.reaction_forces) {  // cached as [u; rf]
      r.rf = r.u.bottomRows(n);
      r.u = MatX3(r.u.topRows(n));
    }
    return r;
  }

  const fs::path exe = s.executable.empty() ? detail::find_tool("ccx", "MEDSPRING_CCX",
                                                                "install the Debian package calculix-ccx")
                                            : fs::path(s.executable);
  detail::TempDir dir("medspring-ccx");
  {
    std::ofstream out(dir.path() / "job.inp");
    out << deck;
    if (!out) throw IoError(cat("cannot write ", (dir.path() / "job.inp").string()));
  }
  const auto t0 = std::chrono::steady_clock::now();
  const int rc = detail::run_in(dir.path(), exe, "job", "ccx.log");
  r.solve_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const fs::path log = dir.path() / "ccx.log";
  std::string first_error;  // the first *ERROR line and the two after it
  {
    std::ifstream in(log);
    std::string line;
    int after = -1;
    while (std::getline(in, line) && after < 2) {
      if (after < 0 && line.find("*ERROR") != std::string::npos) after = 0;
      if (after >= 0) {
        const auto b = line.find_first_not_of(" \t");
        if (b != std::string::npos) {
          if (!first_error.empty()) first_error.push_back(' ');
          first_error.append(line, b, std::string::npos);
        }
        ++after;
      }
    }
  }
  if (rc != 0 || !first_error.empty())
    throw SolverError(cat("CalculiX failed (exit ", rc, ")", first_error.empty() ? "" : ": " + first_error,
                          "; log ends: ", detail::last_lines(log, 4)));
  try {
    const FrdData frd = read_frd((dir.path() / "job.frd").string());
    r.u = last_displacement(frd, p.mesh.num_nodes(), 1.0, "job.frd");
    if (s.reaction_forces) r.rf = last_reaction(frd, p.mesh.num_nodes(), 1.0, "job.frd");
  } catch (const IoError& e) {
    throw SolverError(
        cat("CalculiX did not reach the full load (", e.what(), "): ", detail::last_lines(log, 4)));
  }
  if (s.use_cache && s.reaction_forces) {
    FemResult both = r;
    both.u = MatX3(2 * n, 3);
    both.u << r.u, r.rf;
    store_cache(cache_file, both);
  } else if (s.use_cache) {
    store_cache(cache_file, r);
  }
  return r;
}

}  // namespace medspring::fem
