// Entry point of the `kincal` command: parses the command line (CLI11) and dispatches to the
// subcommands, each registered by its own file in host/cli/.
#include <iostream>

#include <CLI/CLI.hpp>

#include "host/cli/blobs.hpp"
#include "host/cli/board_poses_command.hpp"
#include "host/cli/camera_command.hpp"
#include "host/cli/colour_table.hpp"
#include "host/cli/command_line.hpp"
#include "host/cli/correct_command.hpp"
#include "host/cli/dbc_command.hpp"
#include "host/cli/demo.hpp"
#include "host/cli/discover_command.hpp"
#include "host/cli/exercise.hpp"
#include "host/cli/export_command.hpp"
#include "host/cli/fiducials.hpp"
#include "host/cli/identify_command.hpp"
#include "host/cli/import_command.hpp"
#include "host/cli/monitor.hpp"
#include "host/cli/plan_command.hpp"
#include "host/cli/platform_command.hpp"
#include "host/cli/predict_command.hpp"
#include "host/cli/session_command.hpp"
#include "host/cli/urdf_command.hpp"

int main(int argc, char** argv) {
  CLI::App app{"kincal: find the true kinematic parameters of a serial robot and correct it online", "kincal"};
  app.set_version_flag("--version", KINCAL_VERSION);
  app.require_subcommand(1);
  app.footer("Run 'kincal COMMAND --help' for a command's options.\n");

  int status = 0;
  kincal::cli::add_demo_command(app, status);
  kincal::cli::add_session_command(app, status);
  kincal::cli::add_monitor_command(app, status);
  kincal::cli::add_exercise_command(app, status);
  kincal::cli::add_platform_command(app, status);
  kincal::cli::add_dbc_command(app, status);
  kincal::cli::add_blobs_command(app, status);
  kincal::cli::add_fiducials_command(app, status);
  kincal::cli::add_colour_table_command(app, status);

  kincal::cli::add_identify_command(app, status);
  kincal::cli::add_discover_command(app, status);
  kincal::cli::add_import_command(app, status);
  kincal::cli::add_predict_command(app, status);
  kincal::cli::add_plan_command(app, status);
  kincal::cli::add_urdf_command(app, status);
  kincal::cli::add_export_command(app, status);
  kincal::cli::add_correct_command(app, status);
  kincal::cli::add_camera_command(app, status);
  kincal::cli::add_board_poses_command(app, status);

  if (const auto stop = kincal::cli::parse_command_line(app, argc, argv)) return *stop;
  // Whatever a command printed is its output (a URDF, the blobs' JSON, a decoded log): if standard
  // output could not take it (a full disk, a closed pipe), the command failed.
  std::cout.flush();
  if (!std::cout) {
    std::cerr << "kincal: standard output: cannot write (a full disk or a closed pipe?): the output is lost\n";
    return status != 0 ? status : 1;
  }
  return status;
}
