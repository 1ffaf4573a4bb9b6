// `kincal urdf`: a model file as URDF with the (calibrated) geometry in the joint origins.
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

// Registers the subcommand; when it runs, its exit status goes to `status`.
void add_urdf_command(CLI::App& app, int& status);

}  // namespace kincal::cli
