// Tables I and II as JSON (tables.json): every timing case, the table cells next to the paper's, and the
// paper's ordering claims checked against the measured medians and the timing noise.
#include <cmath>
#include <iomanip>
#include <sstream>

#include "internal.hpp"

namespace medspring::paper::detail {

namespace {

struct Check {
  std::string what;
  double lhs, rhs;  // the claim is lhs > rhs (or >= for nonlinear vs linear)
  bool strict;
  double noise = 0;  // the larger round-to-round spread of the two cases
  bool holds() const { return strict ? lhs > rhs : lhs >= rhs; }
  std::string verdict() const {
    if (holds()) return "yes";
    if (std::abs(lhs / rhs - 1) <= noise) {
      std::ostringstream os;
      os << "equal within the timing noise (±" << std::fixed << std::setprecision(1) << 100 * noise << " %)";
      return os.str();
    }
    return "no";
  }
};

}  // namespace

json tables_json(const std::vector<TimedCase>& timed, const TimingProtocol& p, const std::string& machine) {
  json cases = json::array();
  for (const auto& t : timed)
    cases.push_back({{"name", t.c.name},
                     {"model", t.c.model},
                     {"nonlinear", t.c.nonlinear},
                     {"local", t.c.local},
                     {"median_us", t.median},
                     {"mean_us", t.mean},
                     {"p90_us", t.p90},
                     {"round_medians_us", t.round_medians},
                     {"round_spread", t.spread},
                     {"median_ms", t.median / 1000},
                     {"mean_ms", t.mean / 1000},
                     {"samples", t.us.size()},
                     {"masses", t.info.masses},
                     {"springs", t.info.springs},
                     {"surface_nodes", t.info.surface_nodes},
                     {"dt_safe_rest_ms", t.info.dt_safe_rest_ms},
                     {"substeps_per_update", t.info.substeps_per_update}});
  auto med_ms = [&](const std::string& m, bool nl, const std::string& loc) {
    return find_case(timed, m, nl, loc).median / 1000.0;
  };
  auto noise = [&](const std::string& m1, bool n1, const std::string& l1, const std::string& m2, bool n2,
                   const std::string& l2) {
    return std::max(find_case(timed, m1, n1, l1).spread, find_case(timed, m2, n2, l2).spread);
  };
  const std::vector<Check> checks = {
      {"Table I, mass-spring: nonlinear >= linear", med_ms("MS", true, "off"), med_ms("MS", false, "off"),
       false, noise("MS", true, "off", "MS", false, "off")},
      {"Table I, SMRM: nonlinear >= linear", med_ms("SMRM", true, "off"), med_ms("SMRM", false, "off"), false,
       noise("SMRM", true, "off", "SMRM", false, "off")},
      {"Table I, linear: SMRM < mass-spring", med_ms("MS", false, "off"), med_ms("SMRM", false, "off"), true,
       noise("MS", false, "off", "SMRM", false, "off")},
      {"Table I, nonlinear: SMRM < mass-spring", med_ms("MS", true, "off"), med_ms("SMRM", true, "off"), true,
       noise("MS", true, "off", "SMRM", true, "off")},
      {"Table II, with local: SMRM < mass-spring", med_ms("MS", true, "no_cache"),
       med_ms("SMRM", true, "no_cache"), true, noise("MS", true, "no_cache", "SMRM", true, "no_cache")},
      {"Table II, mass-spring: with local > without", med_ms("MS", true, "no_cache"),
       med_ms("MS", true, "off"), true, noise("MS", true, "no_cache", "MS", true, "off")},
      {"Table II, SMRM: with local > without", med_ms("SMRM", true, "no_cache"), med_ms("SMRM", true, "off"),
       true, noise("SMRM", true, "no_cache", "SMRM", true, "off")},
  };
  json checks_json = json::array();
  for (const auto& c : checks)
    checks_json.push_back({{"claim", c.what},
                           {"ratio", c.lhs / c.rhs},
                           {"holds", c.holds()},
                           {"noise", c.noise},
                           {"verdict", c.verdict()}});
  auto cell = [&](const std::string& m, bool nl, const std::string& loc, double paper_s) {
    const TimedCase& t = find_case(timed, m, nl, loc);
    return json{{"measured_median_ms", t.median / 1000},
                {"measured_mean_ms", t.mean / 1000},
                {"paper_ms", std::isfinite(paper_s) ? json(1000 * paper_s) : json(nullptr)}};
  };
  const PaperTimes& ms = kPaperMassSpring;
  const PaperTimes& sm = kPaperSmrm;
  return {
      {"definition",
       "ALGORITHMS.md D-18: one update = loads -> step -> surface map (SMRM: frames + reconstruction) -> "
       "local overlay -> vertex normals; force held at the strong value; single thread"},
      {"warmup_updates", p.warmup},
      {"timed_updates", p.rounds * p.per_round},
      {"rounds", p.rounds},
      {"machine", machine},
      {"table1",
       {{"mass_spring",
         {{"linear", cell("MS", false, "off", ms.linear)},
          {"nonlinear", cell("MS", true, "off", ms.nonlinear)}}},
        {"smrm",
         {{"linear", cell("SMRM", false, "off", sm.linear)},
          {"nonlinear", cell("SMRM", true, "off", sm.nonlinear)}}}}},
      {"table2",
       {{"mass_spring",
         {{"without_local", cell("MS", true, "off", ms.nonlinear)},
          {"with_local", cell("MS", true, "no_cache", ms.local)},
          {"with_local_cached", cell("MS", true, "cache", NAN)}}},
        {"smrm",
         {{"without_local", cell("SMRM", true, "off", sm.nonlinear)},
          {"with_local", cell("SMRM", true, "no_cache", sm.local)},
          {"with_local_cached", cell("SMRM", true, "cache", NAN)}}}}},
      {"kidney_mass_spring",
       {{"linear", cell("kidney MS", false, "off", NAN)},
        {"nonlinear", cell("kidney MS", true, "off", NAN)},
        {"with_local", cell("kidney MS", true, "no_cache", NAN)},
        {"with_local_cached", cell("kidney MS", true, "cache", NAN)}}},
      {"paper_ms",
       {{"MS",
         {{"linear", 1000 * ms.linear}, {"nonlinear", 1000 * ms.nonlinear}, {"local", 1000 * ms.local}}},
        {"SMRM",
         {{"linear", 1000 * sm.linear}, {"nonlinear", 1000 * sm.nonlinear}, {"local", 1000 * sm.local}}}}},
      {"cases", cases},
      {"ordering_checks", checks_json}};
}

}  // namespace medspring::paper::detail
