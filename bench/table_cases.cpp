// The timing cases of Tables I and II as benchmark cases: the paper module's cases (paper/timing.hpp).
#include "table_cases.hpp"

namespace medspring::bench {

namespace {

TableCase from(const paper::TimingCase& t) {
  TableCase c;
  c.model = t.model;
  c.nonlinear = t.nonlinear;
  c.local = t.local;
  c.timing = t;
  c.bench.name = t.name;
  c.bench.group = "table";
  c.bench.nodes = t.nodes;
  c.bench.springs = t.springs;
  c.bench.setup = t.setup;
  return c;
}

}  // namespace

std::vector<TableCase> table_cases() {
  std::vector<TableCase> out;
  for (const paper::TimingCase& t : paper::timing_cases()) out.push_back(from(t));
  return out;
}

TableCaseInfo table_case_info(const TableCase& c) {
  return paper::timing_case_info(c.timing);
}

}  // namespace medspring::bench
