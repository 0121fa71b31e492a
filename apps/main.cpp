// The medspring command: one entry point, one subcommand per task (apps/commands.cpp declares them).
#include "cli.hpp"
#include "commands.hpp"

int main(int argc, char** argv) {
  return medspring::cli::main(medspring::cli::commands(), argc, argv);
}
