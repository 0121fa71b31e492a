#include <iostream>

#include "commands.hpp"
#include "medspring/core/check.hpp"
#include "medspring/core/units.hpp"
#include "medspring/io/info.hpp"
#include "medspring/scene/parameter_docs.hpp"

namespace medspring::cli {

int cmd_info(const Args& args) {
  args.require_known({"json", "unit", "radius-array", "params"});
  if (args.flag("params")) {  // the declared parameter sets (docs/parameters.md)
    if (!args.positional().empty()) throw InvalidInput("info --params: takes no FILE");
    std::cout << parameter_tables_markdown();
    return 0;
  }
  if (args.positional().size() != 1)
    throw InvalidInput("info: expected exactly one FILE (see medspring info --help)");
  DescribeOptions opt;
  if (auto u = args.get("unit")) opt.unit = parse_length_unit(*u);
  if (auto r = args.get("radius-array")) opt.radius_array = *r;
  const FileInfo info = describe_file(args.positional()[0], opt);
  std::cout << (args.flag("json") ? info.to_json() : info.text()) << "\n";
  return 0;
}

}  // namespace medspring::cli
