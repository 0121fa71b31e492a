#include "medspring/fem/frd.hpp"

#include <charconv>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <sstream>
#include <unordered_map>

#include "medspring/core/check.hpp"
#include "medspring/core/error.hpp"

namespace medspring::fem {

namespace {

constexpr Index kMaxNodes = 50'000'000;

class Lines {
 public:
  Lines(std::string_view text, const std::string& name) : text_(text), name_(name) {}
  bool next(std::string_view& line) {
    if (pos_ >= text_.size()) return false;
    const auto end = text_.find('\n', pos_);
    line = text_.substr(pos_, end == std::string_view::npos ? std::string_view::npos : end - pos_);
    pos_ = end == std::string_view::npos ? text_.size() : end + 1;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    ++number_;
    return true;
  }
  [[noreturn]] void fail(const std::string& what) const {
    throw IoError(cat(name_, ": line ", number_, ": ", what));
  }
  std::size_t number() const { return number_; }

 private:
  std::string_view text_;
  const std::string& name_;
  std::size_t pos_ = 0;
  std::size_t number_ = 0;
};

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

// Record key: the first token (" -1", "    2C", "  100CL", "9999").
std::string_view first_token(std::string_view line) {
  line = trim(line);
  const auto sp = line.find_first_of(" \t");
  return line.substr(0, sp);
}

std::vector<std::string_view> tokens(std::string_view s) {
  std::vector<std::string_view> out;
  std::size_t i = 0;
  while (i < s.size()) {
    while (i < s.size() && (s[i] == ' ' || s[i] == '\t')) ++i;
    std::size_t j = i;
    while (j < s.size() && s[j] != ' ' && s[j] != '\t') ++j;
    if (j > i) out.push_back(s.substr(i, j - i));
    i = j;
  }
  return out;
}

bool parse_long(std::string_view s, long long& v) {
  s = trim(s);
  if (s.empty()) return false;
  const auto r = std::from_chars(s.data(), s.data() + s.size(), v);
  return r.ec == std::errc() && r.ptr == s.data() + s.size();
}

bool parse_double(std::string_view s, double& v) {
  s = trim(s);
  if (s.empty() || s.size() > 40) return false;
  char buf[48];
  s.copy(buf, s.size());
  buf[s.size()] = '\0';
  char* end = nullptr;
  v = std::strtod(buf, &end);
  return end == buf + s.size() && std::isfinite(v);
}

// A " -1" data row: node id in columns [3, 13), then `nvals` fields of 12 columns.
void parse_row(std::string_view line, int nvals, Lines& lines, long long& id, double* vals) {
  const std::size_t need = 13 + 12 * static_cast<std::size_t>(nvals);
  if (line.size() < need) lines.fail(cat("data row too short (", line.size(), " < ", need, " characters)"));
  if (!parse_long(line.substr(3, 10), id) || id <= 0 || id > std::numeric_limits<Index>::max())
    lines.fail("bad node number");
  for (int k = 0; k < nvals; ++k)
    if (!parse_double(line.substr(13 + 12 * static_cast<std::size_t>(k), 12), vals[k]))
      lines.fail(cat("bad value in field ", k + 1));
}

}  // namespace

FrdData parse_frd(std::string_view text, const std::string& name) {
  FrdData out;
  Lines lines(text, name);
  std::unordered_map<long long, Index> row_of;
  std::string_view line;
  bool have_nodes = false, ended = false;
  double pending_time = std::numeric_limits<double>::quiet_NaN();
  while (lines.next(line)) {
    const std::string_view key = first_token(line);
    if (key.empty()) continue;
    if (key == "9999") {
      ended = true;
      break;
    }
    if (key == "2C") {
      if (have_nodes) lines.fail("a second node block");
      const auto t = tokens(line);
      long long count = 0;
      if (t.size() < 2 || !parse_long(t[1], count) || count <= 0 || count > kMaxNodes)
        lines.fail("bad node count in the node block header");
      std::vector<Vec3> X;
      X.reserve(static_cast<std::size_t>(std::min<long long>(count, 1'000'000)));
      while (true) {
        if (!lines.next(line)) lines.fail("node block not closed by -3");
        const auto k = first_token(line);
        if (k == "-3") break;
        if (k != "-1") lines.fail("expected a -1 node row or -3");
        long long id = 0;
        double v[3];
        parse_row(line, 3, lines, id, v);
        if (!row_of.emplace(id, static_cast<Index>(X.size())).second)
          lines.fail(cat("node ", id, " repeated"));
        if (static_cast<long long>(X.size()) >= count)
          lines.fail(cat("more nodes than the ", count, " announced"));
        out.ids.push_back(static_cast<Index>(id));
        X.emplace_back(v[0], v[1], v[2]);
      }
      if (static_cast<long long>(X.size()) != count)
        lines.fail(cat("node block has ", X.size(), " nodes, ", count, " announced"));
      out.X.resize(static_cast<Index>(X.size()), 3);
      for (std::size_t i = 0; i < X.size(); ++i) out.X.row(static_cast<Index>(i)) = X[i].transpose();
      have_nodes = true;
      continue;
    }
    if (key.size() >= 4 && key.substr(0, 4) == "100C") {
      const auto t = tokens(line);
      double time = 0;
      if (t.size() < 3 || !parse_double(t[2], time)) lines.fail("bad step time in the result block header");
      pending_time = time;
      continue;
    }
    if (key == "-4") {
      const auto t = tokens(line);
      if (t.size() < 3) lines.fail("bad result block header");
      const bool is_forc = t[1] == "FORC";  // reaction forces: like DISP, rows may be a subset
      const bool is_disp = t[1] == "DISP" || is_forc;
      long long ncomp = 0;
      if (!parse_long(t[2], ncomp) || ncomp < 1 || ncomp > 64) lines.fail("bad component count");
      if (is_disp && !have_nodes) lines.fail("DISP block before the node block");
      if (is_disp && std::isnan(pending_time)) lines.fail("DISP block without a 100C header");
      FrdDisplacementBlock block;
      std::vector<std::uint8_t> seen;
      if (is_disp) {
        block.time = pending_time;
        block.u = MatX3::Zero(static_cast<Index>(out.ids.size()), 3);
        seen.assign(out.ids.size(), 0);
      }
      std::size_t rows = 0;
      while (true) {
        if (!lines.next(line)) lines.fail("result block not closed by -3");
        const auto k = first_token(line);
        if (k == "-3") break;
        if (k == "-5" || k == "-2") continue;
        if (k != "-1") lines.fail("expected -5, -1, -2 or -3 in a result block");
        if (!is_disp) continue;
        long long id = 0;
        double v[3];
        parse_row(line, 3, lines, id, v);
        const auto it = row_of.find(id);
        if (it == row_of.end()) lines.fail(cat("node ", id, " is not in the node block"));
        if (seen[it->second])
          lines.fail(cat("node ", id, " repeated in the ", is_forc ? "FORC" : "DISP", " block"));
        seen[it->second] = 1;
        block.u.row(it->second) << v[0], v[1], v[2];
        ++rows;
      }
      if (is_forc) {
        out.forc.push_back(std::move(block));
      } else if (is_disp) {
        if (rows != out.ids.size())
          lines.fail(cat("DISP block has ", rows, " rows for ", out.ids.size(), " nodes"));
        out.disp.push_back(std::move(block));
      }
      pending_time = std::numeric_limits<double>::quiet_NaN();
      continue;
    }
    if (key == "3C") {  // element block: skipped
      while (true) {
        if (!lines.next(line)) lines.fail("element block not closed by -3");
        const auto k = first_token(line);
        if (k == "-3") break;
        if (k != "-1" && k != "-2") lines.fail("expected -1, -2 or -3 in the element block");
      }
      continue;
    }
    if (key == "-1" || key == "-2" || key == "-3" || key == "-5") lines.fail("data record outside a block");
    // Other header records (1C, 1U..., 1P...) carry no data we need.
  }
  if (!ended) lines.fail("file ends without the 9999 record");
  if (!have_nodes) lines.fail("no node block");
  return out;
}

FrdData read_frd(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(cat(path, ": cannot open"));
  in.seekg(0, std::ios::end);
  const auto size = static_cast<long long>(in.tellg());
  if (size < 0 || size > (2LL << 30)) throw IoError(cat(path, ": bad size"));
  in.seekg(0);
  std::string text(static_cast<std::size_t>(size), '\0');
  if (!in.read(text.data(), size)) throw IoError(cat(path, ": read failed"));
  return parse_frd(text, path);
}

MatX3 last_displacement(const FrdData& frd, Index n, double expect_time, const std::string& name) {
  if (frd.disp.empty()) throw IoError(cat(name, ": no DISP block"));
  const auto& b = frd.disp.back();
  if (!(std::abs(b.time - expect_time) <= 1e-6))
    throw IoError(cat(name, ": the last DISP block is at step time ", b.time, ", not ", expect_time));
  MatX3 u(n, 3);
  std::vector<std::uint8_t> have(static_cast<std::size_t>(n), 0);
  for (std::size_t r = 0; r < frd.ids.size(); ++r) {
    const Index id = frd.ids[r];
    if (id >= 1 && id <= n) {
      u.row(id - 1) = b.u.row(static_cast<Index>(r));
      have[static_cast<std::size_t>(id - 1)] = 1;
    }
  }
  for (Index i = 0; i < n; ++i)
    if (!have[static_cast<std::size_t>(i)])
      throw IoError(cat(name, ": node ", i + 1, " has no displacement"));
  return u;
}

MatX3 last_reaction(const FrdData& frd, Index n, double expect_time, const std::string& name) {
  if (frd.forc.empty()) throw IoError(cat(name, ": no FORC block"));
  const auto& b = frd.forc.back();
  if (!(std::abs(b.time - expect_time) <= 1e-6))
    throw IoError(cat(name, ": the last FORC block is at step time ", b.time, ", not ", expect_time));
  MatX3 f = MatX3::Zero(n, 3);
  for (std::size_t r = 0; r < frd.ids.size(); ++r) {
    const Index id = frd.ids[r];
    if (id >= 1 && id <= n) f.row(id - 1) = b.u.row(static_cast<Index>(r));
  }
  return f;
}

}  // namespace medspring::fem
