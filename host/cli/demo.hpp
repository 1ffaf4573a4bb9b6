// `kincal demo`: the main job. Until the calibration loop lands (issue #6) it says so and
// shows what the build already does: the firmware core's pixel-path number formats.
#pragma once

#include <iosfwd>

namespace kincal::cli {

int run_demo(std::ostream& out);

}  // namespace kincal::cli
