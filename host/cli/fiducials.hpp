// `kincal fiducials IMAGE`: Doty's fiducial identification (firmware/core/fiducial_id.hpp) on an
// image of a calibration square, after the same streaming labeler as `kincal blobs` (dark
// fiducials on light vellum, automatic threshold unless --threshold). Prints JSON: status, the
// identified fiducials (id p1..p6, x, y in pixels), the square's axes as image unit vectors, the
// fiducial side in pixels, and every blob's verdict. Unreadable input: a message naming the
// file and exit status 1; an image where no square is found prints its status and exits 2.
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

void add_fiducials_command(CLI::App& app, int& status);

}  // namespace kincal::cli
