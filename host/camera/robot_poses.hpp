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
//  - timed poses (issue #43): a CSV as above whose header also names a time column, as a motion
//    capture or a robot's state log writes them (Vicon's, EuRoC's, Kalibr's and yac's
//    "timestamp [ns],x,y,z,qx,qy,qz,qw"): `timestamp`, `time`, `t` or `stamp` followed by its
//    unit, " [ns]", "[ns]" or "_ns" (a whole number of nanoseconds) or " [s]", "[s]" or "_s"
//    (seconds). RobotPose::time_ns holds it; without such a column it is empty and the file
//    reads as before. read_timed_poses requires it and times that increase row by row.
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

#include <cstdint>
#include <iosfwd>
#include <optional>
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
  int line = 0;                         // 1-based line of the pose (its first line for a 4x4 matrix over four lines)
  std::optional<std::int64_t> time_ns;  // timed poses only
};

std::vector<RobotPose> read_robot_poses(const std::string& path, RotationColumns rotation);
std::vector<RobotPose> parse_robot_poses(std::istream& in, const std::string& source, RotationColumns rotation);

// Timed poses: the file read as above; CalibrationError "FILE:LINE: what" when it has no time
// column (the header names it) or a row's time is not after the previous row's.
std::vector<RobotPose> read_timed_poses(const std::string& path, RotationColumns rotation);
std::vector<RobotPose> parse_timed_poses(std::istream& in, const std::string& source, RotationColumns rotation);

// The pose at an image's time between two timed poses: the translation linear in time, the
// rotation by spherical linear interpolation (Eigen's slerp, the shorter way). A pose whose time
// is the image's is taken as it is. None, with `refusal` saying why, when the time lies before
// the first pose or after the last, or when the two poses around it are more than max_gap_s
// apart (the motion capture lost the body between them: a 20 Hz stream that drops one sample
// leaves 0.1 s).
inline constexpr double kMaxPoseGap_s = 0.1;
struct PoseAtTime {
  std::optional<Eigen::Isometry3d> pose;
  int line_before = 0, line_after = 0;  // the rows interpolated
  std::string refusal;
};
PoseAtTime pose_at_time(const std::vector<RobotPose>& timed, std::int64_t time_ns, double max_gap_s = kMaxPoseGap_s);

// An image's time from its file name, as Kalibr's, EuRoC's and ROS bag exports name them: the
// name without folder and extension is a whole number of nanoseconds (1606153907495166540.jpg)
// or seconds with a decimal point (1606153907.495166540.png); none otherwise.
std::optional<std::int64_t> image_time_ns(const std::string& path);

}  // namespace kincal::camera
