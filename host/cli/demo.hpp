// `kincal demo`: the main job -- the whole calibration loop on the simulated ARID platform rig
// and the simulated Kapucu & Baysec stereo rig, with the report (host/demo/demo.hpp).
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

// Registers the subcommand; when it runs, its exit status goes to `status`.
void add_demo_command(CLI::App& app, int& status);

}  // namespace kincal::cli
