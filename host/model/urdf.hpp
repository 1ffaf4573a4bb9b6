// URDF export: the model's geometry, calibrated or not, in the joint origins themselves (no
// <calibration> tags, which most consumers ignore), so any URDF consumer (robot_state_publisher,
// MoveIt, Pinocchio) computes the same tool pose as forward_kinematics() for the same readings.
//
// Every link of link_model.hpp factors as P_i * M_i(q) * S_i with M_i = Rz(q) (revolute) or
// Tz(q) (prismatic): standard DH and Doty have P_i = I and S_i the whole link at q = 0 (the
// joint motion commutes to the front); modified DH has P_i = Rx(alpha) Tx(a), S_i = Rz(theta) Tz(d).
// The URDF chain is then: link "device" (the measurement frame) -> joint i with origin
// S_{i-1} P_i (S_0 = base_T_frame0) and axis z -> link i ... -> fixed joint "tool" with origin
// S_n flange_T_tool -> link "tool". Joint offsets are folded into the origins, so URDF joint
// values are the controller's readings. Revolute joints without limits become "continuous";
// prismatic joints without limits get +-1e9 m (URDF requires a limit). effort and velocity,
// which URDF requires and kinematics does not know, are written as 0.
#pragma once

#include <string>

#include "host/model/robot_model.hpp"

namespace kincal::model {

std::string write_urdf(const RobotModel& model);

}  // namespace kincal::model
