// `kincal demo`: the main job. Until the calibration loop lands (issue #6) it says so and
// shows what the build already does: the firmware core's pixel-path number formats.
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

// Registers the subcommand; when it runs, its exit status goes to `status`.
void add_demo_command(CLI::App& app, int& status);

}  // namespace kincal::cli
