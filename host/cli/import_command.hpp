// `kincal import`: a measurement export (laser-tracker software, spreadsheet CSV) into a kincal
// dataset (host/model/measurement_import.hpp), columns picked by their header names, units and
// the Euler convention named on the command line.
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

// Registers the subcommand; when it runs, its exit status goes to `status`.
void add_import_command(CLI::App& app, int& status);

}  // namespace kincal::cli
