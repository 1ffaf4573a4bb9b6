// The zoo benchmark's own robot (issue #41): a serial chain read from a URDF's text by urdfdom
// (Debian's, not kincal's reader) and its forward kinematics in Eigen, child = parent * origin *
// motion(q), written here so that the benchmark judges kincal's model code instead of sharing it.
//
// Frames: `root` is the URDF's root link (the robot's base frame here); `flange` is the chain's
// last link (tool0 when the file has one, else the last moving joint's child). Units SI: metres,
// radians, kilograms, newtons.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Geometry>

namespace zoo {

using Pose = Eigen::Isometry3d;
using Vector6 = Eigen::Matrix<double, 6, 1>;

// A small rigid motion: translation t (m) then rotation by the rotation vector r (rad).
Pose small_motion(const Vector6& t_r);

struct ChainJoint {
  std::string name;
  Pose parent_T_joint;   // every fixed joint since the previous moving joint, then this joint's origin
  Eigen::Vector3d axis;  // unit, in the joint's frame
  bool prismatic = false;
  double lower = 0.0, upper = 0.0;                  // the limits the configurations are drawn in (rad or m)
  double mass_kg = 0.0;                             // the links moving with this joint up to the next moving joint
  Eigen::Vector3d com_m = Eigen::Vector3d::Zero();  // their centre of mass, in this joint's frame
};

struct Chain {
  std::string urdf_path, urdf_text, root_link, flange_link;
  std::vector<ChainJoint> joints;  // the moving joints from the root to the flange
  Pose last_T_flange;              // the fixed joints after the last moving one
  bool masses_from_urdf = false;   // else assumed: 8 kg per link at the middle of the link
};

// The main arm chain of a URDF: root to `tip_link` when named, else to `tool0`, else to `flange`,
// else to the leaf with the most moving joints. Throws std::runtime_error naming the file when
// urdfdom refuses it, when the named link is absent, when the chain holds a mimic joint or a joint
// type other than revolute, continuous, prismatic and fixed.
Chain read_chain(const std::string& urdf_path, const std::string& tip_link = "");

// What the truth changes on the nominal chain, and what the oracle fits (one structure for both).
struct ChainErrors {
  std::vector<Vector6> origin;                // per moving joint: parent_T_joint * small_motion(origin[i])
  std::vector<double> zero;                   // per joint: added to the reading (rad or m)
  std::vector<double> scale;                  // per joint: the reading is multiplied by (1 + scale[i])
  std::vector<double> compliance_rad_per_nm;  // per revolute joint: deflection = c * gravity torque
  int coupled_from = -1, coupled_to = -1;     // joint[to] += coupling * reading[from] (Fanuc J2 -> J3)
  double coupling = 0.0;
  explicit ChainErrors(std::size_t joints = 0);
};

// root_T_joint_i after each joint's motion (the frame its axis turns or slides it in), at joint
// values theta (after the readings' scale, zero and coupling; no compliance).
std::vector<Pose> joint_frames(const Chain& chain, const ChainErrors& errors, const std::vector<double>& theta);

// root_T_flange of the chain with errors at the controller's readings q.
Pose forward(const Chain& chain, const ChainErrors& errors, const std::vector<double>& q);

// Each joint's static gravity torque (N m; 0 for prismatic joints) at joint values theta, gravity
// along the root's -z.
std::vector<double> gravity_torques(const Chain& chain, const ChainErrors& errors, const std::vector<double>& theta);

// Every fixed joint below the last moving joint's child, by name: its origin in the URDF text.
std::vector<std::pair<std::string, Pose>> fixed_joints_beyond_chain(const std::string& urdf_text,
                                                                    const std::string& last_moving_joint);

}  // namespace zoo
