// `kincal colour-table --positive IMAGE... [--negative IMAGE...] --space rgb565|yuv422 -o FILE`:
// builds the beacon's colour-class table from sample pixels (every pixel of the positive images,
// e.g. crops of the beacon under the rig's lighting; optionally scene pixels that must not
// count) and writes the platform's parameter block (firmware/core/colour_class.hpp).
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

void add_colour_table_command(CLI::App& app, int& status);

}  // namespace kincal::cli
