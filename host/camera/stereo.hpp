// Stereo calibration (issue #6): the pose of the right camera relative to the left from views
// of the same board seen by both at once (cv::stereoCalibrate), then the rectification that
// makes their epipolar lines image rows (cv::stereoRectify).
//
// Conventions: right_R_left, right_t_left_m map a point from the left camera frame to the right
// one (x_right = R x_left + t), as OpenCV's R and T; baseline_m = |t|. The rectification
// (R1 R2 P1 P2 Q) is OpenCV's, with alpha = 0 (only valid pixels) and CALIB_ZERO_DISPARITY.
// With refine_intrinsics false (the default) both cameras keep the intrinsics given
// (CALIB_FIX_INTRINSIC); otherwise they are the start of a joint refinement
// (CALIB_USE_INTRINSIC_GUESS) and the refined models are returned.
//
// Pairs: detections[i] of the left and right lists are one pair (same instant; see
// host/capture/stereo_source.hpp for pairing by time). A pair is used with the corners both
// images found (matched by id); it is left out, with its reason, when either side has no board
// or they share fewer than min_common_corners corners.
// Gates (exit 0 must mean a result a user can trust): every pair sees the same rigid rig, so
//  - pair consistency, before the solve: each usable pair's own right_T_left (the board's pose
//    in each camera by cv::solvePnP with the cameras given, right_T_board * left_T_board^-1) is
//    compared with the consensus, the pair whose pose most others agree with, the smallest
//    median distance among equals (distance: the larger of rotation / max_pair_rotation_rad and
//    translation / (max_pair_translation_fraction * baseline); agreeing: distance at most 1); a
//    pair beyond distance 1 is refused, the first in list order named with its numbers, and
//    when the consensus has no majority the message says so and names its group (a list
//    shifted part-way: the pairs before the shift). A right list shifted by one frame makes
//    every pair disagree (tens of degrees; OpenCV's 13 sample pairs agree within 0.4 degrees and
//    2.5 mm of their 83 mm baseline);
//  - epipolar residuals, after the solve: a pair whose RMS exceeds both outlier_over_median
//    times the median pair's and outlier_floor_px is refused, named;
//  - refuse_wrong_board and refuse_other_image_sizes (host/camera/intrinsics.hpp) on both lists.
// Uncertainty: with both cameras' intrinsics covariances given in the options (from their camera
// files, load_camera_uncertainty) and the intrinsics held (refine_intrinsics false),
// pose_uncertainty is right_T_left's covariance with the intrinsics' share
// (stereo_pose_covariance, host/camera/uncertainty.hpp); otherwise it is empty (without the
// intrinsics' share it would understate the error many times over: tested).
// Errors: CalibrationError when the lists differ in length, the two cameras' image sizes
// differ, any gate refuses, or fewer than min_pairs pairs are usable
// (the message lists each pair left out and why), or a baseline below
// kMinBaselineOverBoardDistance of the median board distance (the same images left and right,
// or one camera twice: the message gives both numbers).
// Cost: one Levenberg-Marquardt solve in OpenCV (milliseconds for tens of pairs).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <opencv2/core.hpp>

#include "host/camera/board.hpp"
#include "host/camera/intrinsics.hpp"
#include "host/camera/uncertainty.hpp"

namespace kincal::camera {

inline constexpr double kMinBaselineOverBoardDistance = 0.01;

struct StereoOptions {
  bool refine_intrinsics = false;
  int min_common_corners = 6;
  int min_pairs = 3;
  double max_pair_rotation_rad = 2 * 3.14159265358979323846 / 180;
  double max_pair_translation_fraction = 0.1;
  double outlier_over_median = 3;
  double outlier_floor_px = 1.0;
  const IntrinsicsCovariance* left_intrinsics = nullptr;  // both or neither: see Uncertainty above
  const IntrinsicsCovariance* right_intrinsics = nullptr;
};

struct StereoPairReport {
  std::string left_view, right_view;
  bool used = false;
  std::string rejection;
  int common_corners = 0;
  double rms_px = 0;                         // used pairs: RMS over both images
  double left_rms_px = 0, right_rms_px = 0;  // used pairs: each camera's (OpenCV's per-view errors)
  // Used pairs: the RMS distance (px) of each corner from the epipolar line of its match, both
  // ways, on the corners undistorted by each camera (reproject to its pinhole) and the solved F.
  double epipolar_rms_px = 0;
  // Used pairs whose board poses were found (posed): the pair's own right_T_left, as the
  // pair-consistency gate computes it; its distance from the gate's consensus in the gate's
  // units (above 1 refused; NaN with fewer than 3 posed pairs, when the gate does not judge);
  // and its difference from the calibrated right_T_left.
  bool posed = false;
  double consensus_distance = 0;
  double pose_rotation_rad = 0, pose_translation_m = 0;
};

struct StereoCalibration {
  CameraModel left, right;
  cv::Matx33d right_R_left = cv::Matx33d::eye();
  cv::Vec3d right_t_left_m;
  double baseline_m = 0;
  double rms_px = 0;
  double pair_rms_limit_px = 0;  // the epipolar-residual gate's limit (see Gates above)
  cv::Matx33d essential, fundamental;
  cv::Matx33d rectify_left, rectify_right;        // R1, R2
  cv::Matx34d projection_left, projection_right;  // P1, P2
  cv::Matx44d disparity_to_depth;                 // Q
  std::vector<StereoPairReport> pairs;
  std::optional<StereoPoseCovariance> pose_uncertainty;  // see Uncertainty above
};

StereoCalibration calibrate_stereo(const std::vector<BoardDetection>& left, const std::vector<BoardDetection>& right,
                                   const CameraModel& left_camera, const CameraModel& right_camera,
                                   const StereoOptions& options = {});

std::string describe(const StereoCalibration& calibration);

}  // namespace kincal::camera
