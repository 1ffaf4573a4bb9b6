// The `--threshold N|auto` option of the subcommands that label grey images (`kincal blobs`,
// `kincal fiducials`): a grey level 0..255 (what std::stoi reads, whole text), or auto for the
// core's Otsu threshold over the image (firmware/core/auto_threshold.hpp). Anything else is a
// usage error when the command line is parsed, before the subcommand runs.
#pragma once

#include <CLI/App.hpp>

#include <cstdint>
#include <optional>

namespace kincal::cli {

// Adds --threshold to `command` (help default "auto"). A given level is stored in `level`, which
// the caller keeps alive while the command line is parsed; auto, given or not, leaves it empty.
// Returns the option, for the options that exclude it.
CLI::Option* add_threshold_option(CLI::App& command, std::optional<std::uint8_t>& level);

}  // namespace kincal::cli
