// `kincal discover`: the model of an unknown arm from single-joint sweeps alone (host/identify/
// discover.hpp) -- joint count, types with their test p-values, axes, ranges, the link table
// with standard deviations -- written as a model file (and optionally URDF).
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

// Registers the subcommand; when it runs, its exit status goes to `status`.
void add_discover_command(CLI::App& app, int& status);

}  // namespace kincal::cli
