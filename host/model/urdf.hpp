// URDF out, two ways.
//
// write_urdf: a URDF made from the model alone. The model's geometry, calibrated or not, in the joint origins
// themselves (no <calibration> tags, which most consumers ignore), so any URDF consumer (robot_state_publisher, MoveIt,
// Pinocchio) computes the same tool pose as forward_kinematics() for the same readings.
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
//
// write_calibrated_urdf: the robot's own URDF with the calibrated geometry in its joint origins
// and everything else kept (link and joint names, meshes, inertias, limits, axes, other
// branches, comments). The text is edited in place, found by the parser's own element order
// (urdf_text.hpp), so any spelling the reader accepts works: of the chain's <origin> elements
// only the xyz or rpy values that changed by more than 1e-11 m or 1e-11 rad (times the arm's
// size in metres beyond a metre: the round trip's rounding grows with it) are rewritten (in
// the element's own quotes; a number of three within that of its old value keeps its old
// spelling, and the white space around and between the three stays as it was (tabs, several
// spaces, a line end); a missing attribute is added after the element's name, a missing <origin> after
// the joint's start tag). So a joint whose origin did not change keeps its text byte for byte,
// and the same model written back gives the original text plus the comment. The comment goes
// after the XML declaration (or after a byte-order mark, which stays first, when there is no
// declaration) with the file's own line end (CRLF when its first line ends so). Every other byte
// is kept: the encoding, line ends, white space, comments and what follows the root element.
// Which frames move and why:
//   - The calibrated model (any conventions) is registered to the URDF: device_T_base_link =
//     calibrated base_T_frame0 * (nominal base_T_frame0)^-1, nominal = model_from_urdf of the
//     same chain. So the base link keeps its nominal place relative to the first joint axis;
//     the device-to-robot registration (e.g. tracker to base) is returned and written in a
//     comment, not into the robot.
//   - Each link frame that a movable joint carries stays where it sits on its own body: its
//     nominal pose relative to the body's kincal frame (the frame on the next joint axis, or
//     the flange), carried over to the calibrated body, then slid along and turned about its
//     own calibrated joint axis only as much as needed to lie on that axis with the URDF's
//     <axis> unchanged. The DH drift of nearly parallel axes (d of metres that cancel) never
//     reaches the link frames, so meshes stay on their bodies (the reason UR's description
//     moves offsets along the joint axes). A body whose lines did not move (its joint axis and
//     the next, or the tool after the last) keeps its nominal pose as it is, so no frame of it
//     turns by the rounding of frames built on nearly parallel axes.
//   - Every fixed joint keeps its origin byte for byte, those beyond the last movable joint
//     included: the tip link (the flange, --tip-link) and the hand, fingers and TCP links after
//     it stay on the last body where the URDF puts them (issue #42). The model's tool is the
//     measured point (a tracker's reflector, a marker: robot_model.hpp), never a joint of the
//     robot: it is written only when `measured_point_link` names a new link, placed in the tip
//     link by a new fixed joint "<name>_joint" (a frame tool: the whole pose; a point tool: the
//     position, the tip link's axes); otherwise a note says how far it is from the tip link.
// Forward kinematics of the written URDF, mapped by device_T_base_link, equal the calibrated
// model's for every reading at the measured point's link when it is written, and otherwise at
// the tip link up to the measured point's fixed offset (tests/host/model/urdf_test.cpp, to 1e-9 m).
#pragma once

#include <string>
#include <vector>

#include "host/model/robot_model.hpp"
#include "host/model/urdf_chain.hpp"

namespace kincal::model {

std::string write_urdf(const RobotModel& model);

// "" for a purely geometric model; otherwise a note naming the joints whose coupling, scale or
// compliance a file of joint origins (URDF, ur-kinematics) leaves out.
std::string non_geometric_note(const RobotModel& model);

struct CalibratedUrdf {
  std::string text;
  Transform device_T_base_link{};  // the registration the model's base transform held
  std::vector<std::string> notes;  // what the URDF could not carry
};

// Throws InputError when the URDF is bad (urdf_chain.hpp), its chain does not match the model
// (joint count or types), or it has a link named `measured_point_link` or a joint named
// "<measured_point_link>_joint" already. The joint map (coupling, scale, compliance:
// robot_model.hpp) has no place in a URDF; a model with one gets a note (non_geometric_note).
CalibratedUrdf write_calibrated_urdf(const std::string& original_text, const std::string& source,
                                     const UrdfChainEnds& ends, const RobotModel& calibrated,
                                     const std::string& measured_point_link = {});

}  // namespace kincal::model
