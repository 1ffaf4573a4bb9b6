// `kincal correct` (issue #24): targets rewritten for the calibrated arm -- joint targets and
// Cartesian targets from CSV tables, or a URScript program's motion lines (host/correct/).
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

void add_correct_command(CLI::App& app, int& status);

}  // namespace kincal::cli
