// Entry point of the `kincal` command: parses the command line (CLI11) and dispatches to the
// subcommands, each registered by its own file in host/cli/.
#include <CLI/CLI.hpp>

#include "host/cli/demo.hpp"

int main(int argc, char** argv) {
  CLI::App app{"kincal: find the true kinematic parameters of a serial robot and correct it online", "kincal"};
  app.set_version_flag("--version", KINCAL_VERSION);
  app.require_subcommand(1);

  int status = 0;
  kincal::cli::add_demo_command(app, status);

  CLI11_PARSE(app, argc, argv);
  return status;
}
