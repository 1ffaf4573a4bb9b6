// `kincal camera calibrate --report FILE` (issue #22): the camera report (host/report/
// camera_report.hpp) filled from an intrinsic calibration and the detections it used -- each used
// corner's residual at the view's solved pose, the distortion field and the projection sigma on
// a 16 x 12 grid (host/camera/uncertainty.hpp), the summary from describe()'s first lines.
#pragma once

#include <vector>

#include "host/camera/board.hpp"
#include "host/camera/intrinsics.hpp"
#include "host/report/camera_report.hpp"

namespace kincal::cli {

// `detections` as given to calibrate_intrinsics (the same order as calibration.views).
report::CameraReport camera_report(const camera::IntrinsicCalibration& calibration,
                                   const std::vector<camera::BoardDetection>& detections);

}  // namespace kincal::cli
