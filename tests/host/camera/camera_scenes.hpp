// Simulated scenes for the camera-calibration tests and the CLI test images: a known camera,
// board views that cover the image with varied tilts, a stereo rig and a robot carrying the
// camera, all rendered by kincal::sim (host/sim/render.hpp).
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "host/camera/board.hpp"
#include "host/camera/intrinsics.hpp"
#include "host/sim/render.hpp"

namespace kincal::camera::scenes {

// 640 x 480, fx 610, fy 606, principal point off centre, barrel distortion.
sim::CameraSpec test_camera();

// The boards the tests use: a 9 x 6 chessboard (COLS + ROWS odd) of 30 mm squares, a 7 x 5
// ChArUco board of 40 mm squares and a 6 x 5 AprilGrid of 40 mm tags 12 mm apart.
const char* chessboard_text();
const char* charuco_text();
const char* aprilgrid_text();

// n camera_T_board poses, 0.5..0.75 m away, tilted 15..35 degrees in turning directions, aimed
// at points spread over the board so that it moves over the image, rolled by up to 15 degrees.
std::vector<Eigen::Isometry3d> board_views(const camera::Board& board, int n);

// The camera scaled by `scale` in focal length and image size (pixel centres kept): the same
// scene at a higher resolution.
sim::CameraSpec scaled(sim::CameraSpec spec, int scale);

// The board's reflectance: sim::chessboard, or OpenCV's ChArUco or kincal's AprilGrid drawing as
// a texture.
sim::PlanarTarget target_of(const camera::Board& board);

// One rendered view (2x supersampling, mild noise; `seed` varies the noise).
cv::Mat render(const sim::CameraSpec& camera, const Eigen::Isometry3d& camera_T_board, const sim::PlanarTarget& target,
               std::uint64_t seed);

// The spec as host/camera's model.
CameraModel model_of(const sim::CameraSpec& spec);

// The board's corners projected by OpenCV at camera_T_board with Gaussian noise of sigma_px in
// x and in y: a detection without rendering (all corners, ids in order, found).
BoardDetection projected(const camera::Board& board, const CameraModel& camera, const Eigen::Isometry3d& camera_T_board,
                         const std::string& view, cv::RNG& rng, double sigma_px = 0.1);

// The stereo rig: the right camera 0.12 m along the left's x, turned 3 degrees about y.
Eigen::Isometry3d left_T_right();

// The robot: the camera on the gripper at gripper_T_camera, the board fixed at base_T_target;
// base_T_gripper for camera_T_board = views[i].
Eigen::Isometry3d gripper_T_camera();
Eigen::Isometry3d base_T_target();
std::vector<Eigen::Isometry3d> gripper_poses(const std::vector<Eigen::Isometry3d>& camera_T_board);

}  // namespace kincal::camera::scenes
