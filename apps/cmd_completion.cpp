// `medspring completion bash` (hidden): the bash completion script, generated from the declarations in
// commands.cpp; the build writes it to build/apps/medspring.bash and installs it as
// share/bash-completion/completions/medspring.
#include <fstream>
#include <iostream>

#include "commands.hpp"
#include "medspring/core/check.hpp"

namespace medspring::cli {

int cmd_completion(const Args& args) {
  args.require_known({"out"});
  if (args.positional().size() != 1 || args.positional()[0] != "bash")
    throw UsageError("completion: name the shell: medspring completion bash [--out FILE]");
  if (const auto out = args.get("out")) {
    std::ofstream f(*out);
    print_bash_completion(commands(), f);
    if (!f.flush()) throw IoError(cat(*out, ": cannot write the completion script"));
  } else {
    print_bash_completion(commands(), std::cout);
  }
  return 0;
}

}  // namespace medspring::cli
