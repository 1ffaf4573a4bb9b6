// `kincal export --format ur-kinematics`: a calibrated model in a robot controller's own format
// (host/model/ur_kinematics.hpp: Universal Robots' ROS description's kinematics_params_file).
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

// Registers the subcommand; when it runs, its exit status goes to `status`.
void add_export_command(CLI::App& app, int& status);

}  // namespace kincal::cli
