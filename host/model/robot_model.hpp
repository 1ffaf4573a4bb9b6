// A serial robot's kinematic model on the host: the firmware core's chain (link_model.hpp, one
// definition of every link transform) plus what a person needs around it -- names, joint
// offsets and limits, whether the tool is a point or a frame -- and the named parameters the
// identification works on.
//
// Frames (rigid_transform.hpp conventions):
//   device    the measuring device's frame (tracker, stereo pair); measurements are in it.
//   frame 0   the chain's first frame; base_T_frame0 places it in the device frame (so the
//             "base" transform is the device-to-robot registration, identified with the rest).
//   frame n   after the last link: the core chain's "flange" (core::ChainModel::flange_T_tool
//             is from there).
//   tool      the measured point or frame: what the data measure (a tracker's reflector, a mocap
//             marker, a camera's board): flange_T_tool places it in frame n, and the tool_*
//             parameters identify it. Often 50-150 mm off the flange, known to a few mm at best.
//   flange    the frame a tool is mounted on and the controller gives its TCP from: a URDF's
//             tip link (--tip-link), named by flange_link; frame_n_T_flange places it in frame n
//             (identity for a model file without 'flange:'). Nominal: never identified.
//   tcp       the controller's tool centre point, flange_T_tcp in the flange frame: what
//             `correct` aims. Never identified and never folded into the chain; a model without
//             one (a model file without 'tcp:') has its measured point as its TCP.
// Nothing converts one into another silently: tool_at_tcp() below is the one place the TCP
// takes the measured point's place, and flange_T_measured() the one that reads the measured
// point from the flange.
//
// Joint readings: q_i as the controller reports it (rad or m). The chain's variable is
// q_i + offset_i, added to theta (revolute) or d (prismatic). The offset is where calibrated
// zero-reference errors go; theta/d keep the nominal geometry, so both are visible in the file.
//
// Non-geometric joint map (all optional; a model without them evaluates exactly as the plain
// chain, bit for bit). From readings r to the chain's variables v:
//   u_k = scale_k r_k                        gear-ratio error of reading k (scale absent: 1)
//   v_i = sum_k coupling_ik u_k + offset_i   coupling absent: v_i = u_i + offset_i (Fanuc's elbow
//                                            is J2 + J3: coupling [0, 1, 1, 0, 0, 0] on joint 3)
//   v_i += compliance_i * G_i(v)             gravity deflection: G_i the generalized force that
//                                            gravity puts on joint i (N m, or N for a prismatic
//                                            joint) at v, from the link masses and the payload
// G_i = sum over bodies b that joint i moves (links i..n, the payload) of m_b g . dc_b/dv_i, with
// c_b each body's centre of mass, g the gravity vector given in frame 0: the first-order model
// of a joint that gives way in proportion to the static torque it holds (heavy arms' shoulder
// and elbow sag). A joint with a scale or a compliance in its model has that parameter
// identified (names scale<i>, compliance<i>); the masses, centres of mass and gravity are inputs
// unless identify_mass or identify_gravity_direction (below) say otherwise.
// A joint with identify_coupling has its share of its upstream neighbour's reading identified
// (coupling<i>_<i-1>, added to coupling_i,i-1; an absent row counts as the identity row): the
// one coupling a transmission makes -- a joint's drive passes through the joint before it
// (Fanuc's elbow J2 + J3 with a ratio off, a wrist whose shafts run through J4 and J5). Only
// between two revolute joints (a share of a reading of the same kind, dimensionless); the other
// coefficients stay inputs.
// A joint with identify_mass (the geometry+sag candidate, for a model without masses) has its
// link's mass and centre of mass identified too (mass<i> kg, com_x<i> com_y<i> com_z<i> m in
// frame i). Only compliance x first moment reaches the measurements, so they come with a gauge:
// the caller holds one of them fixed (identify/sag.hpp fixes the compliance of the joint that
// sags most). A mass is never negative (identify/problem.hpp's bounds).
// A joint with identify_centre (the geometry+gravity candidate, for a model whose links have
// masses) has its link's centre of mass identified with the given mass (com_x<i> .. com_z<i>,
// drawn toward the given centre by a prior): a calibrated theta turns the link's mass with it
// where the truth may have turned only the next axis about this one -- kinematics cannot tell a
// joint's zero from that -- and a URDF's centre is a CAD estimate (the zoo's KR 210 with 300
// 6-DoF tracker rows: 1.32x the oracle's held-out error with the centres given, 0.96x drawn
// toward them: identify/prior_scale.hpp's given centres).
// A model with identify_gravity_direction (the candidates with a compliance) has the direction of
// gravity in frame 0 identified too (gravity_rx, gravity_ry: turns of the gravity vector about
// frame 0's x and y axes): frame 0 is where the registration puts the arm, and an arm standing
// off level, or a first joint tilted against its base, loads its joints as gravity really
// points, not as frame 0's -z (the zoo's service arms: 6.8x the oracle without it).
//
// Everything is double, SI (m, rad). Functions here do not throw unless they say so.
#pragma once

#include <array>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "firmware/core/error_model.hpp"
#include "firmware/core/link_model.hpp"
#include "firmware/core/rigid_transform.hpp"

namespace kincal::model {

using Transform = core::RigidTransform<double>;
using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;

// Bad model or bad data: the message names the file, the line and what is wrong.
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Throws InputError("source:line: what"), the form every reader's message takes.
[[noreturn]] inline void fail_at(const std::string& source, int line, const std::string& what) {
  throw InputError(source + ":" + std::to_string(line) + ": " + what);
}

struct Joint {
  std::string name;
  core::JointType type = core::JointType::revolute;
  core::LinkConvention convention = core::LinkConvention::standard_dh;
  core::LinkParameters<double> parameters{};  // theta and d without the offset
  double offset = 0.0;                        // rad (revolute) or m (prismatic)
  double lower = -std::numeric_limits<double>::infinity();
  double upper = std::numeric_limits<double>::infinity();
  // The joint map (see the top): empty coupling = the joint's own reading; otherwise one
  // coefficient per reading.
  std::vector<double> coupling;
  bool identify_coupling = false;              // coupling<i>_<i-1> identified (see the top)
  std::optional<double> scale;                 // dimensionless; present: identified
  std::optional<double> compliance;            // rad/(N m) or m/N; present: identified
  double mass_kg = 0.0;                        // of the link this joint moves
  bool identify_mass = false;                  // mass<i>, com_*<i> identified (see the top); not in files
  bool identify_centre = false;                // com_*<i> identified, the mass given (see the top); not in files
  Vector3 centre_of_mass_m = Vector3::Zero();  // in frame i, the frame at the end of link i
};

// What the last link carries, for the gravity deflection: its mass and centre of mass in the
// flange frame.
struct Payload {
  double mass_kg = 0.0;
  Vector3 centre_of_mass_m = Vector3::Zero();
};

inline constexpr double kStandardGravity_mps2 = 9.80665;

enum class ToolKind { point, frame };
enum class AngleUnit { rad, deg };

// One identified parameter as the identification reports it (written to the output file).
struct ParameterReport {
  std::string name;
  double value = 0.0;   // its change from the starting model, in SI units
  double stddev = 0.0;  // 1-sigma, SI units
};

// What `kincal identify` records about how a model was obtained; free text plus numbers.
struct CalibrationRecord {
  std::string method;
  std::string data;
  int measurements = 0;
  double rms_residual_m = 0.0;
  std::vector<ParameterReport> parameters;
  std::vector<std::string> held_fixed;
  std::optional<double> validation_rms_m;
  // Per joint, the lowest and highest reading in the data (SI); empty: not recorded. Equal: the
  // joint never moved, and the model holds at that reading (reading_coverage.hpp).
  std::vector<std::array<double, 2>> reading_ranges;
  // The parameters' correlations, the strict lower triangle in the order of `parameters`: row k
  // holds parameter k+2's correlations with parameters 1..k+1 (empty: not recorded). With the
  // stddevs they give the covariance that correct's predicted spread propagates.
  std::vector<std::vector<double>> correlations;
  // The model error identify told apart from a known instrument noise (s_p per axis, s_o per
  // axis of the rotation vector): what a prediction misses beyond its parameters' spread.
  std::optional<double> model_error_m, model_error_rad;

  // Removes parameter k, or appends one uncorrelated with the others, keeping the correlations'
  // rows (where recorded) one per parameter after the first.
  void erase_parameter(std::size_t k);
  void add_parameter(const ParameterReport& p);
};

struct RobotModel {
  std::string name;
  std::vector<Joint> joints;
  Transform base_T_frame0{};
  Transform flange_T_tool{};  // frame n -> the measured point or frame (see the top)
  ToolKind tool = ToolKind::point;
  std::string flange_link;                 // the flange's link name; "" : frame n is the flange
  Transform frame_n_T_flange{};            // the flange in frame n (nominal)
  std::optional<Transform> flange_T_tcp;   // the controller's TCP; absent: the measured point
  AngleUnit file_angles = AngleUnit::rad;  // how the file wrote angles; writing keeps it
  std::optional<CalibrationRecord> calibration;
  Vector3 gravity_mps2{0.0, 0.0, -kStandardGravity_mps2};  // in frame 0
  bool identify_gravity_direction = false;                 // gravity_rx, gravity_ry (see the top); not in files
  Payload payload;

  int joint_count() const { return static_cast<int>(joints.size()); }
};

// The measured point or frame from the flange: frame_n_T_flange^-1 * flange_T_tool -- what a
// user reads as "the reflector is 102 mm from the flange".
Transform flange_T_measured(const RobotModel& model);

// The model with its tool at the TCP (flange_T_tool = frame_n_T_flange * flange_T_tcp, a frame);
// a model without a TCP as it is. What `correct` aims and what a controller computes with.
RobotModel tool_at_tcp(const RobotModel& model);

// How messages name the flange: "link 'tool0'" or "frame n (the last joint's frame)".
std::string flange_name(const RobotModel& model);

// Whether readings go through scale or coupling, and whether any joint has a compliance.
bool has_joint_map(const RobotModel& model);
bool has_compliance(const RobotModel& model);

// The core chain with offsets folded into theta/d. Requires joint_count() <= core::kMaxJoints
// (load_model checks it).
core::ChainModel<double> to_chain(const RobotModel& model);

// The inverse: a copy of `like` whose geometry is `chain`. theta (revolute) and d (prismatic)
// keep `like`'s value; the difference goes into the joint offset.
RobotModel from_chain(const RobotModel& like, const core::ChainModel<double>& chain);

core::JointVector<double> joint_vector(std::span<const double> q);

// The core's chain of a model evaluated at joint readings q, with the inputs its frames were
// computed from: what the Jacobians below and the joint axes (axes.hpp) start from. q holds the
// chain's variables (through the joint map, deflection included), coupled the same before the
// deflection.
struct ChainAtJoints {
  core::PreparedChain<double> chain;
  core::JointVector<double> q;
  core::JointVector<double> coupled;
  std::array<core::SinCos<double>, core::kMaxJoints> trig{};
  core::ChainFrames<double> frames;
};
ChainAtJoints chain_at_joints(const RobotModel& model, std::span<const double> q);

// device_T_tool at joint readings q (q.size() == joint_count()).
Transform forward_kinematics(const RobotModel& model, std::span<const double> q);

// d(tool pose)/d(readings) as a twist [dp; dphi] per reading, in the device frame: 6 x n.
Eigen::MatrixXd joint_jacobian(const RobotModel& model, std::span<const double> q);

// ---- Named parameters ---------------------------------------------------------------------
// Names: d1 theta1 a1 alpha1 beta1 (1-based joint), base_x base_y base_z base_rx base_ry base_rz
// (small motions of frame 0 along/about its own axes), tool_x ... tool_rz (along/about the
// tool's own axes). Their errors act as core::apply_parameter_errors says.
// scale1, compliance1, coupling3_2 ...: the joint map's parameters (errors add to them; a
// coupling's id names joint i, its reading is always i-1). Their kinds are the host's own,
// beyond the core's enumerators: the core never sees them (apply_parameter_errors and
// parameter_jacobian below handle them), and code that orders kinds asks
// is_joint_map_parameter first.
inline constexpr core::ParameterKind kJointScale{200};
inline constexpr core::ParameterKind kJointCompliance{201};
inline constexpr core::ParameterKind kJointCoupling{202};
// mass<i> (kg) and com_x<i>, com_y<i>, com_z<i> (m, frame i): joint i's link's mass and centre of
// mass, parameters of the joint map's gravity deflection (errors add to them).
inline constexpr core::ParameterKind kLinkMass{203};
inline constexpr core::ParameterKind kLinkCentreX{204};
inline constexpr core::ParameterKind kLinkCentreY{205};
inline constexpr core::ParameterKind kLinkCentreZ{206};
// gravity_rx, gravity_ry (rad): turns of the gravity vector about frame 0's x and y axes, one
// each per model (link 0).
inline constexpr core::ParameterKind kGravityRx{207};
inline constexpr core::ParameterKind kGravityRy{208};
bool is_gravity_direction_parameter(core::ParameterKind kind);
bool is_mass_parameter(core::ParameterKind kind);
bool is_joint_map_parameter(core::ParameterKind kind);
// base_* or tool_*: a small motion of frame 0 or of the tool, not a link's or the joint map's.
bool is_motion_parameter(core::ParameterKind kind);
// base_*: the registration (frame 0 in the measuring device's frame).
bool is_base_parameter(core::ParameterKind kind);
// An angle (rad, written in the file's angle unit): theta, alpha, beta, base_r*, tool_r*, gravity_r*.
bool is_angle_parameter(core::ParameterKind kind);

// How reports print a parameter: value_in_unit = SI value * per_si. Angles in deg, lengths in
// mm, scales and couplings in ppm, compliances in urad/(N m) (um/N for a prismatic joint), masses
// in kg, centres of mass in mm.
struct DisplayUnit {
  double per_si = 1.0;
  const char* name = "";
};
DisplayUnit display_unit(const RobotModel& model, core::ParameterId id);
std::string parameter_name(core::ParameterId id);
// Throws InputError naming the bad entry.
core::ParameterId parse_parameter_name(const std::string& name, int joint_count);

// Every parameter the model's conventions have: links (theta, d, a, alpha, and beta for Doty
// links), then the base's six motions, then the tool's six (three if the tool is a point), then
// the scales and compliances the model's joints declare, then the couplings they identify, then
// the masses and centres of mass they identify (identify_mass).
std::vector<core::ParameterId> all_parameters(const RobotModel& model);

// Whether joint i (0-based) can have its share of reading i - 1 identified: it and joint i - 1
// are revolute.
bool can_identify_coupling(const RobotModel& model, std::size_t i);

// The twist columns of the tool pose w.r.t. parameter errors at zero error: 6 x ids.size().
Eigen::MatrixXd parameter_jacobian(const RobotModel& model, std::span<const double> q,
                                   std::span<const core::ParameterId> ids);

// The same for a model whose geometry is `chain` (identify's Parameterization keeps its own
// chain), with the chain evaluated at readings q. Core kinds take the core's columns at the
// deflected joint values, plus -- when the model has compliance -- the change of the deflection
// with the parameter (G's derivatives in closed form, from one forward kinematics pass: a link
// parameter moves the chain beyond it rigidly, and G is linear in masses and gravity). Throws
// std::invalid_argument for a link index the chain does not have.
Eigen::MatrixXd parameter_jacobian(const RobotModel& model, const ChainAtJoints& at, std::span<const double> q,
                                   std::span<const core::ParameterId> ids);

// chain_at_joints for the joint map of `model` and the geometry `chain` (to_chain(model), or
// identify's Parameterization's own chain).
ChainAtJoints evaluate_chain(const RobotModel& model, const core::ChainModel<double>& chain, std::span<const double> q);

// G(v) of the top comment for the prepared chain at chain variables v: N m (revolute) or N.
core::JointVector<double> gravity_forces(const RobotModel& model, const core::PreparedChain<double>& chain,
                                         const core::JointVector<double>& v);

// The model with the given parameter errors applied exactly (link sums, base/tool composed,
// scale, compliance and coupling added; an absent scale counts as 1, an absent compliance as 0,
// an absent coupling row as the identity row).
RobotModel apply_parameter_errors(const RobotModel& model, std::span<const core::ParameterId> ids,
                                  const Eigen::VectorXd& errors);
// A link's mass stays on the body its joint turns when a calibration moves the next axis on that
// body: a revolute joint's centre of mass (given in frame i, at the link's far end) is carried
// from geometry `before` to `after` so that it keeps its place in the frame that turns with the
// joint -- as a URDF's <inertial>, in its link's frame, does when a joint origin after it moves.
// (Left in frame i, the zoo's service arms with a tracker and the URDF's masses came to 1.3-1.5
// times the oracle: a link's tilt of 1 deg swung a centre 1 m out by 17 mm.) apply_parameter_errors
// and identification's parameterization do it; link parameters before the motion (theta, and d of
// Doty's links) move the body and its mass alike. A mass being identified (identify_mass) is left
// in frame i: its place is a parameter of the fit, not a given.
void carry_centres_of_mass(RobotModel& model, const core::ChainModel<double>& before,
                           const core::ChainModel<double>& after);

// One joint-map parameter's error added to `model`'s fields, as apply_parameter_errors adds it.
// Throws std::invalid_argument for a joint the model does not have or a kind not of the map.
void add_joint_map_error(RobotModel& model, core::ParameterId id, double error);

// Rotation helpers for files: URDF's roll-pitch-yaw (R = Rz(yaw) Ry(pitch) Rx(roll)).
Matrix3 rotation_from_rpy(const Vector3& rpy);
Vector3 rpy_from_rotation(const Matrix3& r);

}  // namespace kincal::model
