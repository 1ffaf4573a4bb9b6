// `kincal camera`: camera calibration from image files (host/camera, host/capture).
//
//   kincal camera calibrate --board BOARD IMAGES... -o camera.yaml [--report report.html]
//   kincal camera stereo --board BOARD --left IMAGES... --right IMAGES... -o stereo.yaml
//                        [--left-camera L.yaml --right-camera R.yaml] [--refine-intrinsics]
//   kincal camera hand-eye --board BOARD --camera camera.yaml --poses robot_poses.csv
//                          --images IMAGES... -o hand_eye.yaml [--convention gripper2base|base2gripper]
//                          [--rotation rotvec|rpy|rpy-deg]
//
// BOARD: chessboard:COLSxROWS:SQUARE_M (inner corners) or charuco:COLSxROWS:SQUARE_M:MARKER_M[:DICT]
// (squares); see host/camera/board.hpp. IMAGES: image files (in the order given), one directory
// (its images in natural order) or one video file. Stereo pairs left and right frames by their
// timestamps (image i at i seconds, video frames at index / fps), within --tolerance seconds,
// and lists the frames left unpaired. Without camera files, stereo first calibrates each camera
// from its own images.
// Robot poses (host/camera/robot_poses.hpp), one per image in the same order, as controllers give
// them: a CSV with x,y,z and qw,qx,qy,qz or rx,ry,rz (--rotation names what rx,ry,rz are; joint
// and other columns are ignored, so a kincal dataset CSV works too), or 4x4 matrices row-major;
// metres. They are the gripper (flange) pose in the robot base frame, base_T_gripper (OpenCV's
// gripper2base) -- or gripper_T_base with --convention base2gripper.
//
// Each command prints its report (parameters, residuals, every view used or rejected and why,
// the detector that found each view's corners, warnings) and writes OpenCV YAML
// (host/camera/calibration_file.hpp); calibrate --report also writes the camera report (HTML:
// residuals, coverage, distortion field, projection uncertainty; host/cli/camera_report.hpp).
// Every output path is checked before any work (host/files/output_file.hpp). Any error -- a missing or unreadable file,
// a bad board text, a board of another size than the one given, images of another size, outlier views beyond the gates,
// stereo pairs that disagree (a list shifted by one), too few usable views, a refused hand-eye pose set -- is a message
// on stderr naming the file or what was wrong, and exit status 1.
#pragma once

#include <CLI/App.hpp>

namespace kincal::cli {

void add_camera_command(CLI::App& app, int& status);

}  // namespace kincal::cli
