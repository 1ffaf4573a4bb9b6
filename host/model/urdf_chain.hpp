// URDF in: the serial chain between a base link and a tip link of a robot's URDF, and that chain
// as a kincal model (`--model robot.urdf`), without changing its kinematics.
//
// Reading (tinyxml2, so every error names the file and the line): links and joints form one tree
// (as urdfdom requires); the chain is the path from `base_link` to `tip_link`. Defaults: the base
// is the tree's root;
// the tip is the leaf below the base with the most movable joints on its way, when that leaf is
// unique -- otherwise InputError lists the candidate chains ("base_link -> tool0 (6 joints)";
// the first kMaxListedChains of them, then how many more) and asks for --tip-link. Choosing the
// default costs O(links log links), however many leaves there are.
//
// Accepted: any XML spelling tinyxml2 reads (either quote, spaces around '=', attributes in any
// order, tabs, comments, CDATA, LF, CRLF or mixed line ends, no line end after the last line, a
// UTF-8 byte-order mark). Joint types: revolute, continuous (no limits), prismatic (movable);
// fixed (folded into the neighbours); floating and planar off the chain. A missing <origin> is
// the identity, a missing <axis> is (1, 0, 0) as URDF says; the axis is normalized.
// Limits of a revolute or prismatic joint: a <limit> without lower and upper (effort and
// velocity only) means no limits -- not [0, 0], URDF's default for the two, which would hold
// the joint at 0 (issue #25: `plan` did); with one of them, the other is URDF's default 0.
// Limits that come to 0 and 0 (lower="0" upper="0", as CAD exporters such as SolidWorks' write
// for "not set", which every ROS tool loads) are no limits either: a revolute joint reads as
// continuous, a prismatic one as unbounded, and a chain joint's UrdfChain::warnings says so with
// the <limit>'s file:line.
//
// Refused, with InputError "FILE:LINE: reason" (LINE: the offending element's line, or 1 for
// unknown --base-link/--tip-link names): XML errors and NUL bytes,
// a link's <mass> without a value or with one that is not a finite number from 0 to kMaxMassKg,
// an end tag that closes no element (tinyxml2 would ignore the rest of the file silently), a
// tag written "</a .../>" (tinyxml2 would read an element a);
// what is no URDF for any tool, anywhere in the file (what urdfdom's check_urdf refuses, and
// beyond it the two ways its tree check misses): no <robot> or one without a name, no links, a
// link or joint name defined twice (both lines named), a joint naming an undefined link, a joint
// type URDF does not have, a second root (a link no joint has as child besides the first: a
// forest or a stray link, whichever --base-link), a cycle of joints (on the chain or off it:
// urdfdom takes a cycle that leaves one root for a tree), a link that is the child of two
// joints (urdfdom keeps the last); a joint without name, type, <parent> or <child>; numbers that
// are not finite (decimal commas included), an origin more than kMaxOriginM from its parent
// frame; a revolute or prismatic joint without <limit>. On the chain only (their values are
// used nowhere else; urdfdom loads them): a zero axis on a movable joint, lower limit above upper,
// equal limits other than 0 and 0 (it cannot move: make it fixed); floating and planar joints and
// <mimic> joints (their values are not readings of their own), no movable joint at all, more
// than core::kMaxJoints of them.
// Names are taken as the bytes they are: the text is expected to be UTF-8, which the input layer
// (host/files) checks for every file read by path; a robot, link or joint name holding a control
// character (raw or as "&#1;", which tinyxml2 takes and XML 1.0 does not) is refused.
//
// URDF's kinematics (what urdf_link_poses computes, as robot_state_publisher does): the child
// link of joint k sits at parent * origin_k * M_k(q_k), M_k a rotation by q_k about axis_k
// (revolute, continuous) or a translation by q_k along it (prismatic); origin = translation
// xyz times R = Rz(yaw) Ry(pitch) Rx(roll).
//
// The model (model_from_urdf): device frame = the base link's frame; joint i = the i-th movable
// joint (its name, type and limits); frame 0 = the frame of the first movable joint's parent
// link, moved onto that joint's axis (for a UR description: base_link_inertia, the controller's
// base); links by chain_from_axes (axes.hpp: standard DH, Doty's convention where consecutive
// axes are within 0.1 rad of parallel), joint offsets folded into theta/d so that a reading of 0
// is the URDF's 0; the tip link is the flange (flange_link, frame_n_T_flange) and the TCP
// (flange_T_tcp identity), and the tool -- the measured point, robot_model.hpp -- a frame there
// until identified. Masses (for model selection's gravity
// candidate, model_selection.hpp): joint i carries the <inertial> masses of the chain's links it
// moves up to the next movable joint and of the links hanging off them outside the chain -- a
// gripper's fingers, a mobile robot's head, at their joints' zero (a Kinova Gen3's Robotiq fingers,
// 0.1 kg behind their knuckle joints, left out, took the zoo's service cases on it to 1.55 times
// the oracle; a floating or planar joint's child is not carried) -- their centre of mass in
// frame i; gravity is the base link's -z (REP 103). Forward kinematics of the model equal the
// URDF's to rounding (tests/host/model/urdf_test.cpp: 1e-9 m and 1e-9 rad against urdfdom over
// random readings, for the robots of host/model/robots and every chain of the real URDFs in
// ../shared/realdata/urdf-corpus).
#pragma once

#include <cstddef>
#include <limits>
#include <span>
#include <string>
#include <vector>

#include "host/model/robot_model.hpp"

namespace kincal::model {

// Which links the chain runs between; empty: the defaults above.
struct UrdfChainEnds {
  std::string base_link;
  std::string tip_link;
};

enum class UrdfJointType { revolute, continuous, prismatic, fixed };

struct UrdfJoint {
  std::string name;
  UrdfJointType type = UrdfJointType::fixed;
  std::string parent_link, child_link;
  Transform parent_T_joint{};                               // <origin>
  Vector3 axis = Vector3::UnitX();                          // unit, in the joint frame
  double lower = -std::numeric_limits<double>::infinity();  // rad or m
  double upper = std::numeric_limits<double>::infinity();
  int line = 0;  // of the <joint> element
  // The <joint> element and its <origin> (the first, as URDF reads it; kNoElement without one)
  // among the document's elements in document order: the index into XmlTextMap::elements
  // (urdf_text.hpp) by which the writer finds their text.
  static constexpr std::size_t kNoElement = static_cast<std::size_t>(-1);
  std::size_t element = 0;
  std::size_t origin_element = kNoElement;
  int origin_line = 0;
};

// A link's mass with the links hanging off it outside the chain, and their centre of mass in its
// frame.
struct UrdfMass {
  double mass_kg = 0.0;
  Vector3 centre_m = Vector3::Zero();
};

// The joints from the base link to the tip link, in order (fixed ones included).
struct UrdfChain {
  std::string source;
  std::string robot_name;
  std::string base_link, tip_link;
  int tip_line = 0;  // of the tip's <link> element
  std::vector<UrdfJoint> joints;
  std::vector<UrdfMass> masses;  // of each joint's child link (see the top)
  // "FILE:LINE: what" for what the chain's joints were read as and a user may not expect (limits
  // 0 and 0: none); model::load_model prints them to standard error.
  std::vector<std::string> warnings;

  int movable_count() const;
};

// The farthest an <origin> may put a frame from its parent (m): ten kilometres, beyond any
// robot, and near enough that the model's round trip stays exact to 1e-11 m (fuzz.urdf found a
// 1e101 m link).
inline constexpr double kMaxOriginM = 1e4;

// The largest link mass read (kg): beyond any robot's link.
inline constexpr double kMaxMassKg = 1e6;

// How many chains the "which chain?" refusal lists.
inline constexpr std::size_t kMaxListedChains = 20;

// Throws InputError ("FILE:LINE: what") for everything the top lists as refused.
UrdfChain parse_urdf_chain(const std::string& text, const std::string& source, const UrdfChainEnds& ends = {});

// base_link_T_(child link of joint k) for every joint of the chain at the movable joints'
// values q (q.size() == movable_count()).
std::vector<Transform> urdf_link_poses(const UrdfChain& chain, std::span<const double> q);

// The chain as a model (see the top). Throws InputError ("FILE:LINE:", the tip link's line) for
// a chain without movable joints or with more than core::kMaxJoints.
RobotModel model_from_urdf(const UrdfChain& chain);

// True when `path` names a URDF file (extension .urdf, any case).
bool is_urdf_path(const std::string& path);

}  // namespace kincal::model
