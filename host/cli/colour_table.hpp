// `kincal colour-table --positive IMAGE... [--negative IMAGE...] --space rgb565|yuv422 -o FILE`:
// builds the beacon's colour-class table from sample pixels (every pixel of the positive images,
// e.g. crops of the beacon under the rig's lighting; optionally scene pixels that must not
// count) and writes the platform's parameter block (firmware/core/colour_class.hpp).
#pragma once

#include <string>

#include <CLI/App.hpp>

#include "firmware/core/colour_class.hpp"

namespace kincal::cli {

void add_colour_table_command(CLI::App& app, int& status);

// A table file as `kincal colour-table` writes it, read through files::read_text as bytes
// (kColourTableFile: a regular file of at most 1 MiB; directories, devices, FIFOs refused by
// name); std::runtime_error naming the file and what is wrong with it (size, magic, version,
// colour space, CRC).
core::ColourClassTable read_colour_table(const std::string& path);

}  // namespace kincal::cli
