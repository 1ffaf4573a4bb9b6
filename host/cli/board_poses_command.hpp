// `kincal board-poses` (issue #26): board views recorded with their joint readings, turned into
// a pose-measurement dataset for `kincal identify` -- a camera and a printed board as the
// measuring device.
//
//   kincal board-poses --camera camera.yaml --board BOARD --mount hand|world --images IMAGES...
//                      --joints joints.csv -o dataset.csv [--min-corners N]
//
// IMAGES: image files (in the order given), one directory (its images in natural order) or one
// video, one view per row of joints.csv (q1..qN; other columns ignored, so a dataset works), in
// the same order. Each view's board pose and its 6x6 covariance come from host/camera/
// board_pose.hpp (the camera file's intrinsics covariance propagated when it has one). Mounts:
//   hand   the camera on the flange, the board fixed: the device frame is the board's and each
//          row is board_T_camera (the inverse of the view's camera_T_board, its covariance
//          carried over to first order); identify's tool is then flange_T_camera (hand-eye).
//   world  the camera fixed, the board on the flange: the device frame is the camera's and each
//          row is camera_T_board; identify's tool is flange_T_board.
// Either way identify's base is the device registration. The dataset has the orientation
// (device_R_tool), the position covariance and the full pose covariance (host/model/dataset.hpp:
// position and rotation error in the device frame, the rotation error applied on the left).
// Prints one line per view: used (corners, RMS, corner sigma, tilt, position and rotation sigma)
// or refused and why (pattern not found, half out of view as too few corners or not found, an
// outlier, nearly edge-on); views refused are left out of the dataset.
// Errors (message on stderr, exit status 1): a file through the input layer (host/files/
// input_file.hpp; a joints file's faults as FILE:LINE), a bad board text, a board of another size
// than the one given (the view named, with the board that fits), images of another size than the
// camera's (named), a joints file whose row count differs from the images', no usable view, an
// output path equal to an input.
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

void add_board_poses_command(CLI::App& app, int& status);

}  // namespace kincal::cli
