// `kincal plan`: calibration configurations within the joint limits that maximize the
// observability index of the identification Jacobian, compared with random ones.
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

// Registers the subcommand; when it runs, its exit status goes to `status`.
void add_plan_command(CLI::App& app, int& status);

}  // namespace kincal::cli
