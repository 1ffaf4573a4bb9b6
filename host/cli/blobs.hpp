// `kincal blobs IMAGE...`: the firmware core's streaming labeler on image files, as JSON.
// Grey images by threshold (--polarity, --threshold N|auto) or colour images by a colour-class
// table (--colour-table FILE, written by `kincal colour-table`). Unreadable or non-image input:
// a message naming the file on stderr and exit status 1, with nothing on stdout.
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

// Registers the subcommand; when it runs, its exit status goes to `status`.
void add_blobs_command(CLI::App& app, int& status);

}  // namespace kincal::cli
