// The calibration file of Universal Robots' ROS description (Universal_Robots_ROS2_Description,
// the `kinematics_params_file` its ur_macro.xacro loads): `kincal export --format ur-kinematics`.
//
//   kinematics:
//     shoulder:  {x, y, z, roll, pitch, yaw}   # origin of shoulder_pan_joint (m, rad)
//     upper_arm: ...                           # shoulder_lift_joint
//     forearm:   ...                           # elbow_joint
//     wrist_1:   ...   wrist_2: ...   wrist_3: ...
//     hash: kincal_<16 hex digits>
//
// The description composes, from its base_link_inertia (the controller's base frame), per joint:
// translate (x, y, z), rotate by R = Rz(yaw) Ry(pitch) Rx(roll), then rotate by the joint's
// reading about z. So link frame i here is the joint-i frame of the model's own links: frame
// i-1 times the part of link i before the joint's motion where the axis is its z (standard
// DH: Rz(theta) Tz(d); Doty: Tz(d) Rz(theta); modified DH: the whole link, whose axis is z of
// frame i), with the joint offsets in theta. The model's frame 0 is taken as the controller's
// base (as in UR's DH table and in a model read from UR's URDF, whose frame 0 is
// base_link_inertia).
//
// What this file cannot carry is returned as notes, with its size: the base transform
// (base_T_frame0: the device-to-robot registration), the rest of the last link after the
// wrist_3 frame (a, alpha, beta of link 6; the description's flange joint is fixed) and the
// tool (flange_T_tool: set the TCP on the controller). The hash is ours (a digest of the
// numbers); the driver compares it with the controller's own calibration checksum and warns that
// they differ, which is true: this calibration is not the controller's.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "host/model/robot_model.hpp"

namespace kincal::model {

struct UrKinematics {
  std::array<Transform, 6> joint_origins{};  // parent link (frame 0 for the first) to joint frame
  Transform wrist_3_T_flange{};              // what the file cannot carry after wrist_3
  std::vector<std::string> notes;
};

inline constexpr std::array<const char*, 6> kUrKinematicsSections = {"shoulder", "upper_arm", "forearm",
                                                                     "wrist_1",  "wrist_2",   "wrist_3"};

// Throws InputError unless the model is a UR arm: six revolute joints in UR's layout (at zero
// readings axis 2 across axis 1, axes 2, 3 and 4 parallel, 5 across 4, 6 across 5, each within
// 5 degrees), naming the first pair that is not.
UrKinematics ur_kinematics(const RobotModel& model);
std::string write_ur_kinematics(const UrKinematics& kinematics);

}  // namespace kincal::model
