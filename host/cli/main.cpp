// Entry point of the `kincal` command: parses the command line (CLI11) and dispatches.
#include <CLI/CLI.hpp>

#include <iostream>

#include "host/cli/demo.hpp"

int main(int argc, char** argv) {
  CLI::App app{"kincal: find the true kinematic parameters of a serial robot and correct it online", "kincal"};
  app.set_version_flag("--version", KINCAL_VERSION);
  app.require_subcommand(1);

  int status = 0;
  auto* demo = app.add_subcommand("demo", "Run the main job end to end (today: what the build already does)");
  demo->callback([&status] { status = kincal::cli::run_demo(std::cout); });

  CLI11_PARSE(app, argc, argv);
  return status;
}
