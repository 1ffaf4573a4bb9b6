// Robot poses for hand-eye calibration (issue #22), as controllers give them: one pose per
// image, in the images' order, the gripper (flange) pose in the robot base frame (or its
// inverse: host/camera/hand_eye.hpp's PoseConvention says which). Metres.
//
// Two file forms, told apart by the first line that is not blank and not a '#' comment:
//  - CSV with a header row (it holds a letter): columns named x,y,z and either qw,qx,qy,qz (a
//    unit quaternion, within 1e-3; normalized; in any order, so ROS's x,y,z,w order too) or
//    rx,ry,rz, whose meaning must be named by `rotation` (names in any case):
//      kRotationVector  rx,ry,rz is the rotation vector (axis times angle, radians; Universal
//                       Robots' pose format)
//      kRpy, kRpyDeg    roll, pitch, yaw about the fixed x, y, z axes, R = Rz(rz) Ry(ry) Rx(rx),
//                       in radians or degrees (also KUKA's A,B,C as rz,ry,rx and Fanuc's W,P,R)
//    Other columns (joints q1..qN, time stamps, a kincal dataset's columns) are ignored, so a
//    kincal dataset CSV is also a poses file. Fields are separated by ',' or, if the header has
//    no ',', by ';', or, if it has neither, by spaces and tabs.
//  - 4x4 matrices, row-major: each line holds 16 numbers (one pose), 12 (its top three rows, as
//    KITTI's poses files) or 4 numbers (one row; four such lines make a pose), separated by
//    spaces, tabs or commas. The last row must be 0 0 0 1 and the rotation orthonormal with
//    determinant +1, within 1e-3. Lines of 7 or 8 numbers without a header (a trajectory's rows,
//    as TUM's t x y z qx qy qz qw) are refused, asking for a header that names the columns.
// read_robot_poses reads through files::read_text (kDatasetFile: a regular file of at most
// 256 MiB, UTF-8 with an optional byte-order mark, CRLF accepted; directories, devices, FIFOs,
// UTF-16/Latin-1 refused by name).
// Errors (CalibrationError "FILE:LINE: what"): an unreadable file, no poses, a header without
// x,y,z or a rotation, with both qw,qx,qy,qz and rx,ry,rz, or naming one of those columns twice,
// rx,ry,rz without `rotation` named, `rotation` named for quaternions or matrices, a field that is
// not a finite number, a row with too few fields, a quaternion or rotation out of tolerance, a
// rotation vector longer than 2 pi or a roll, pitch or yaw beyond +-2 pi (+-360 deg: degrees
// given as radians, most likely), an incomplete matrix, and a translation longer than
// kMaxRobotReach_m (a file in millimetres, most likely).
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace kincal::camera {

enum class RotationColumns { kUnnamed, kRotationVector, kRpy, kRpyDeg };

// "rotvec", "rpy", "rpy-deg" (the command line's names); throws std::invalid_argument otherwise.
RotationColumns rotation_columns(const std::string& name);

inline constexpr double kMaxRobotReach_m = 20;

struct RobotPose {
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  int line = 0;  // 1-based line of the pose (its first line for a 4x4 matrix over four lines)
};

std::vector<RobotPose> read_robot_poses(const std::string& path, RotationColumns rotation);
std::vector<RobotPose> parse_robot_poses(std::istream& in, const std::string& source, RotationColumns rotation);

}  // namespace kincal::camera
