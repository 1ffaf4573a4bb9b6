// `kincal camera calibrate|stereo|hand-eye --report FILE` (issue #22): the camera reports
// (host/report/camera_report.hpp) filled from the calibrations and the detections they used.
//  - calibrate: each used corner's residual at the view's solved pose, the distortion field and
//    the projection sigma on a 16 x 12 grid (host/camera/uncertainty.hpp), the summary from
//    describe()'s first lines;
//  - stereo: describe()'s lines (baseline, rotation and their sigmas when the cameras' covariances
//    are known), a table of every pair with the numbers calibrate_stereo measured for it
//    (StereoPairReport: each camera's RMS, the epipolar RMS, its own right_T_left against the
//    calibrated one, its distance from the consistency gate's consensus) and why a pair was left
//    out, then each camera's sections -- a camera calibrated in the run as calibrate's report, a
//    camera from its file with its distortion field and (when the file has its covariance) its
//    projection uncertainty;
//  - hand-eye: describe()'s lines, a table of every view with its residuals
//    (HandEyeViewReport: the board pose's own RMS, the RMS at the refined chain, the AX = XB and
//    AX = ZB residuals) and why a view was left out, and the corners' residuals at the refined
//    hand-eye and board pose.
#pragma once

#include <optional>
#include <vector>

#include "host/camera/board.hpp"
#include "host/camera/hand_eye.hpp"
#include "host/camera/intrinsics.hpp"
#include "host/camera/stereo.hpp"
#include "host/camera/uncertainty.hpp"
#include "host/report/camera_report.hpp"

namespace kincal::cli {

// `detections` as given to calibrate_intrinsics (the same order as calibration.views).
report::CameraReport camera_report(const camera::IntrinsicCalibration& calibration,
                                   const std::vector<camera::BoardDetection>& detections);

// A camera known only by its model (a camera file): the distortion field, and the projection
// uncertainty when `uncertainty` is given; `source` is said in its summary.
report::CameraReport lens_report(const camera::CameraModel& camera,
                                 const std::optional<camera::IntrinsicsCovariance>& uncertainty,
                                 const std::string& source);

// `left`, `right`: each camera's report (camera_report or lens_report), shown under its title.
report::CameraPage stereo_report(const camera::StereoCalibration& calibration, const camera::StereoOptions& options,
                                 report::CameraReport left, report::CameraReport right);

// `views` as given to calibrate_hand_eye (the same order as calibration.views).
report::CameraPage hand_eye_report(const camera::HandEyeCalibration& calibration,
                                   const std::vector<camera::HandEyeView>& views, const camera::CameraModel& camera);

}  // namespace kincal::cli
