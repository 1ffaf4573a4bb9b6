// `kincal identify`: kinematic identification from a measurement CSV (host/identify), writing the
// calibrated model in the same YAML schema, optionally checked on held-out measurements.
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

// Registers the subcommand; when it runs, its exit status goes to `status`.
void add_identify_command(CLI::App& app, int& status);

}  // namespace kincal::cli
