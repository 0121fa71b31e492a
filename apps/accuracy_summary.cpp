// The accuracy summary of `medspring paper`'s report (accuracy_summary.hpp).
#include "accuracy_summary.hpp"

#include <cstdlib>
#include <fstream>
#include <iomanip>
#include <map>
#include <sstream>
#include <system_error>

#include "medspring/core/binary.hpp"

namespace medspring::cli {

namespace fs = std::filesystem;
using nlohmann::json;

fs::path latest_accuracy_path() {
  fs::path dir;
  if (const char* e = std::getenv("MEDSPRING_FEM_CACHE"); e && *e)
    dir = e;
  else if (const char* x = std::getenv("XDG_CACHE_HOME"); x && *x)
    dir = fs::path(x) / "medspring" / "fem";
  else if (const char* h = std::getenv("HOME"); h && *h)
    dir = fs::path(h) / ".cache" / "medspring" / "fem";
  else
    dir = fs::temp_directory_path() / "medspring-fem";
  return dir / "accuracy-latest.json";
}

bool keep_latest_accuracy(const json& accuracy) {
  const fs::path target = latest_accuracy_path();
  std::error_code ec;
  fs::create_directories(target.parent_path(), ec);
  try {
    write_file_atomically(target, accuracy.dump(1) + "\n", "accuracy summary");
  } catch (const IoError&) {
    return false;
  }
  return true;
}

namespace {

std::string fmt(double v, int digits) {
  std::ostringstream s;
  s << std::fixed << std::setprecision(digits) << v;
  return s.str();
}

struct Mean {
  double sum = 0;
  int n = 0;
  void add(double v) {
    sum += v;
    ++n;
  }
  std::string str() const { return n ? fmt(sum / n, 1) + " %" : "—"; }
};

}  // namespace

std::string accuracy_summary_markdown(const json& acc, const std::string& source) {
  std::ostringstream md;
  md << "## Accuracy against the FEM reference (CalculiX)\n\n"
     << "From " << source << " (`medspring accuracy`, docs/accuracy.md";
  if (acc.value("quick", false)) md << "; a `--quick` run: phantom, 2 sites, 0.5 N";
  const json material = acc.value("material", json::object());
  md << "). Material E = " << fmt(material.value("E_kPa", 0.0), 1)
     << " kPa, ν = " << fmt(material.value("nu", 0.0), 2) << ", contact disk radius "
     << fmt(acc.value("contact_radius_mm", 0.0), 1)
     << " mm. Errors are means over the held-out cases (never the calibration's training loads), in % of the "
        "FEM contact displacement.\n\n"
     << "| organ | model | contact error, default | contact error, calibrated | RMS error, default | RMS "
        "error, calibrated | update (µs) |\n|---|---|---|---|---|---|---|\n";
  for (const auto& organ : acc.value("organs", json::array())) {
    // kind -> (default, calibrated) means
    std::map<std::string, Mean> contact[2], rms[2];
    std::map<std::string, double> update_us;
    std::vector<std::string> order;
    for (const auto& m : organ.value("models", json::array())) {
      const std::string kind = m.value("kind", std::string("?"));
      const int c = m.value("calibrated", false) ? 1 : 0;
      if (!update_us.count(kind)) order.push_back(kind);
      update_us[kind] = m.value("update_us", 0.0);
      for (const auto& cs : m.value("cases", json::array())) {
        if (cs.value("train", false) || !cs.contains("contact_error_pct")) continue;
        contact[c][kind].add(cs["contact_error_pct"].get<double>());
        rms[c][kind].add(cs.value("rms_pct", 0.0));
      }
    }
    for (const auto& kind : order)
      md << "| " << organ.value("organ", std::string("?")) << " | " << kind << " | " << contact[0][kind].str()
         << " | " << contact[1][kind].str() << " | " << rms[0][kind].str() << " | " << rms[1][kind].str()
         << " | " << fmt(update_us[kind], 1) << " |\n";
  }
  md << "\n";
  for (const auto& organ : acc.value("organs", json::array()))
    if (organ.contains("fem"))
      md << "- " << organ.value("organ", std::string("?")) << ": one CalculiX static solve takes "
         << fmt(organ["fem"].value("median_solve_s", 0.0), 1) << " s (median) for comparison.\n";
  // The vessel (SMRM centerline against the FEM wall), when the run has one.
  for (const auto& v : acc.value("vessels", json::array())) {
    md << "\n"
       << v.value("vessel", std::string("vessel"))
       << ": SMRM centerline against the FEM wall's mid-surface (E = "
       << fmt(v.value("material", json::object()).value("E_kPa", 0.0), 1)
       << " kPa), mean over the held-out cases, in % of the FEM displacement of the loaded atom; one "
          "CalculiX solve "
       << fmt(v.value("fem", json::object()).value("median_solve_s", 0.0), 1) << " s (median).\n\n"
       << "| model | parameters | loaded-atom error | centerline RMS | update (µs) "
          "|\n|---|---|---|---|---|\n";
    for (const auto& m : v.value("models", json::array())) {
      Mean loaded, rms;
      for (const auto& cs : m.value("cases", json::array())) {
        if (cs.value("train", false) || !cs.contains("loaded_error_pct")) continue;
        loaded.add(cs["loaded_error_pct"].get<double>());
        rms.add(cs.value("rms_pct", 0.0));
      }
      md << "| " << m.value("kind", std::string("?")) << " | " << m.value("params", std::string("?")) << " | "
         << loaded.str() << " | " << rms.str() << " | " << fmt(m.value("update_us", 0.0), 1) << " |\n";
    }
  }
  md << "\nTargets: calibrated hybrid kidney contact error within 10 %, RMS within 15 %; calibrated SMRM "
        "centerline within 10 % (docs/accuracy.md says "
        "which are hit and by how much they are missed).\n\n";
  return md.str();
}

}  // namespace medspring::cli
