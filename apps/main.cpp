// The medspring command: one entry point, one subcommand per task.
#include <cstring>
#include <iostream>
#include <string>

#include "cli.hpp"
#include "commands.hpp"

namespace {

void usage(std::ostream& os) {
  os << "medspring — real-time soft-tissue simulation (nonlinear mass-spring + simplified medial "
        "representation)\n\n"
        "usage: medspring <command> [options]   (medspring <command> --help for details)\n\n"
        "commands:\n"
        "  demo     press and release the bundled phantoms and real anatomy, print what happened\n"
        "  bench    time one update of every model (median, p99; --json for scripts)\n"
        "  info     summarise a mesh, volume or centerline file (counts, bounds, units, validity)\n";
  medspring::cli::extra_usage(os);
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") ||
      !std::strcmp(argv[1], "help")) {
    usage(std::cout);
    return argc < 2 ? 2 : 0;
  }
  const std::string cmd = argv[1];
  for (const auto& c : medspring::cli::commands()) {
    if (c.name != cmd) continue;
    for (int i = 2; i < argc; ++i)
      if (!std::strcmp(argv[i], "--help") || !std::strcmp(argv[i], "-h")) {
        std::cout << c.help;
        return 0;
      }
    try {
      const medspring::cli::Args args(argc, argv, 2, c.flags);
      return medspring::cli::guarded(c.name, c.run, args);
    } catch (const std::exception& e) {
      std::cerr << "medspring " << cmd << ": error: " << e.what() << "\n";
      return 2;
    }
  }
  std::cerr << "medspring: unknown command '" << cmd << "' (see medspring --help)\n";
  return 2;
}
