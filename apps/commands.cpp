#include "commands.hpp"

namespace medspring::cli {

const std::vector<Command>& commands() {
  static const std::vector<Command> list = {
      {"bench",
       "usage: medspring bench [--filter TEXT] [--quick] [--samples N] [--json]\n\n"
       "Times one update of every benchmark case (ALGORITHMS.md D-18): 200 warm-up updates, then N timed\n"
       "updates (default 2000), single thread. Prints median, p99 and mean in microseconds, and ns per "
       "spring.\n"
       "  --filter TEXT  only cases whose name contains TEXT\n"
       "  --quick        200 samples, no 1M-node case\n"
       "  --json         {\"results\": [{\"name\", \"median_us\", \"p99_us\", \"mean_us\", \"nodes\", "
       "\"springs\", ...}]}\n",
       {"json", "quick"},
       cmd_bench},
      {"info",
       "usage: medspring info FILE [--unit mm|cm|m] [--radius-array NAME] [--json]\n\n"
       "Summarises a mesh (.obj .stl .ply .vtp .vtk), a label volume (.nii .nii.gz .mha .mhd .nrrd) or a\n"
       "centerline (.vtp .vtk polylines with a radius array): counts, bounds in mm, units, validity.\n",
       {"json"},
       cmd_info},
      {"demo",
       "usage: medspring demo [--force N] [--json]\n\n"
       "Presses and releases the bundled models (hybrid kidney phantom, surface tube) and prints the\n"
       "contact displacement under the force, the time to return to rest and the cost per update.\n",
       {"json"},
       cmd_demo},
  };
  return list;
}

void extra_usage(std::ostream&) {}

}  // namespace medspring::cli
