// Robot model files (YAML, yaml-cpp): what people read and write, and what `kincal identify`
// writes back with the calibrated geometry.
//
//   name: stanford-rrp
//   angles: deg                  # angles in this file are degrees (default: rad); lengths are m
//   base:                        # frame 0 of the chain in the measuring device's frame
//     translation: [0, 0, 0]     # m
//     rpy: [0, 0, 0]             # roll, pitch, yaw (R = Rz(yaw) Ry(pitch) Rx(roll)), or
//                                # quaternion: [w, x, y, z]
//   joints:
//     - name: waist              # optional (default j<i>)
//       type: revolute           # revolute | prismatic
//       convention: dh           # dh (standard DH) | mdh (modified DH, Craig) | doty (Doty/Hayati, beta)
//       d: 1.27                  # link_model.hpp says what each parameter does in each convention
//       theta: 0
//       a: 0
//       alpha: 90
//       beta: 0                  # doty only
//       offset: 0                # joint offset: added to the reading (optional, default 0)
//       limits: [-170, 170]      # reading limits (optional)
//       coupling: [0, 1, 1]      # optional: this joint's variable is this combination of the
//                                # readings (here J2 + J3); one coefficient per joint
//       scale: 1                 # optional: reading factor (gear ratio), identified when given
//       compliance: 0            # optional: rad/(N m) (m/N prismatic), SI whatever 'angles' says;
//                                # deflection = compliance * gravity torque, identified when given
//       mass: 25                 # optional, kg: the link this joint moves, for the gravity torque
//       centre_of_mass: [0.3, 0, 0]   # optional, m, in frame i (the frame at the end of link i)
//   tool:
//     point: [0, 0, 0.1]         # a tool point in the flange frame, or a frame:
//                                # translation: [...] and rpy: [...] (or quaternion). The tool is
//                                # the measured point or frame (a reflector, a marker, a board)
//   flange:                      # optional: the flange in frame n (robot_model.hpp; default frame n)
//     link: tool0                # its URDF link, for messages
//     translation: [0, 0, 0]     # and rpy or quaternion
//   tcp:                         # optional: the controller's TCP in the flange frame, what
//     translation: [0, 0, 0.2]   # `correct` aims; never identified (default: the tool)
//   gravity: [0, 0, -9.80665]    # optional, m/s^2 in frame 0 (this default)
//   payload:                     # optional: what the flange carries, for the gravity torque
//     mass: 10                   # kg
//     centre_of_mass: [0, 0, 0.1]   # m, flange frame
//
// robot_model.hpp says how scale, coupling and compliance act. A model without them reads and
// writes exactly as before (gravity is written only with a compliance or when not the default).
//   calibration: ...             # written by `kincal identify`; read back as a record: its
//                                # reading_ranges (per joint [lowest, highest] in the data, SI)
//                                # let correct and predict name readings it was not calibrated at
//   priors:                      # optional: identify's prior sigma of a parameter's deviation from
//     a5: 0.0005                 # this model (identify/prior.hpp): lengths m, angles in the file's
//     theta5: 0.2                # unit, scale<i> a ratio; names as identify prints them. Not
//                                # written back (a calibrated model's deviations start anew);
//                                # `identify` refuses one no candidate model has (tool_rx of a point tool)
//
// Reading is strict: unknown keys, a key given twice in one mapping or a second YAML document
// (yaml_text.hpp), missing parameters, wrong types, an unknown convention or
// joint type, more than core::kMaxJoints joints, non-finite numbers, lower >= upper (equal limits
// leave a joint no motion), a coupling list of the wrong length or coupling rows that are
// linearly dependent, a scale that is not positive, a negative mass or compliance, two joints
// of one name (a given name may not be another joint's default j<i> either; both named), two
// priors for one parameter, text that is not UTF-8, a control character in a name (the robot's, a
// joint's, the flange link's: XML takes none): InputError with "FILE:LINE:COLUMN: what"
// (quoted values cut to 80 bytes). Every number is held to its physical range (the constants
// below), where it is read:
//   d, a, a prismatic joint's offset and limits, centres of mass, the tool   |x| <= kMaxLength_m
//   base translation (the robot in the measuring device's frame)            |x| <= kMaxBaseDistance_m
//   theta, alpha, beta, a revolute joint's offset, rpy angles, angle priors  within one turn
//   a revolute joint's limits                                                within kMaxLimitTurns
//   scale                                             [kMinScale, kMaxScale] (and positive)
//   coupling coefficients                              |c| <= kMaxCoupling
//   mass, payload mass                                 [0, kMaxMass_kg]
//   compliance                                         [0, kMaxCompliance] rad/(N m) or m/N, and
//        only where the joint carries a mass (its link, a later link or a payload has one: else
//        gravity loads it with nothing and the compliance cannot act)
//   gravity                                            |g| <= kMaxGravity_mps2
//   calibration (a record): measurements a whole count; rms, validation rms, stddev >= 0; each
//        parameter named once; reading_ranges one [lowest, highest] per joint, lowest <= highest;
//        correlations one row per parameter after the first, row k of k entries in [-1, 1]
//        (whether they form a covariance is judged where one is built: correct's
//        record_covariance); model_error_m in [0, kMaxLength_m], model_error_rad in [0, pi]
// A file without 'angles:' is in radians: an angle beyond its range there is refused with the
// advice to say 'angles: deg' (alpha: 90 is a degree file missing its key). Everything
// `kincal identify` and `discover` write is inside these ranges. The file
// is read through files::read_text() (files/input_file.hpp): a regular file of at most
// files::kModelFile.max_bytes (a URDF: files::kUrdfFile.max_bytes), UTF-8 (a byte-order mark is
// accepted), LF or CRLF. Writing keeps the file's angle unit and prints numbers in their
// shortest exact form, so a model written in radians reads back bit for bit.
#pragma once

#include <string>
#include <utility>
#include <vector>

#include "host/model/robot_model.hpp"
#include "host/model/urdf_chain.hpp"

namespace kincal::model {

// The physical ranges above. Lengths: the largest arms reach a few metres and gantry axes tens,
// so 100 m refuses millimetres written as metres of any link over 0.1 m while leaving room;
// the base is the robot's place in a tracker's or a room's frame, hence 1 km.
inline constexpr double kMaxLength_m = 100.0;
inline constexpr double kMaxBaseDistance_m = 1000.0;
// A joint that reads more than eight turns either way is continuous: leave its limits out. Its
// DH angles and offset are within one turn (a larger one is degrees in a radian file).
inline constexpr double kMaxLimitTurns = 8.0;
// A scale is a gear-ratio error, a few percent at worst: a factor of 2 either way is a wrong
// transmission, and 57.3 (deg/rad) or 1000 (mm/m) a unit, which no identification repairs.
inline constexpr double kMinScale = 0.5;
inline constexpr double kMaxScale = 2.0;
// A coupling coefficient is one reading's share in a joint's motion (Fanuc's elbow: 1; a
// SCARA's screw: its lead over 2 pi, m/rad): ten is beyond any transmission between joints.
inline constexpr double kMaxCoupling = 10.0;
// 100 t: no arm's link or payload comes near it (1e300 kg, or grams taken for kilograms of a
// heavy link, are refused).
inline constexpr double kMaxMass_kg = 1e5;
// rad/(N m) or m/N: at 1, a newton-metre (100 g at 1 m) turns a joint by a radian, or a newton
// moves it by a metre: no joint that holds its pose.
inline constexpr double kMaxCompliance = 1.0;
// Twice the standard gravity (a gravity vector in mm/s^2 is refused).
inline constexpr double kMaxGravity_mps2 = 2.0 * kStandardGravity_mps2;

// Throws InputError (file missing, YAML syntax, schema). A path ending in .urdf is read as a
// URDF: the chain between `ends` (urdf_chain.hpp); `ends` is for URDF files only.
RobotModel load_model(const std::string& path, const UrdfChainEnds& ends = {});
// `source` names the text in messages.
RobotModel parse_model(const std::string& text, const std::string& source);
// The smallest prior sigma kincal takes (m, rad, or SI for a scale or compliance), from a model
// file's priors or `identify --prior`: the solve squares its weight 1/sigma, and a sigma of
// 1e-163 m made every standard deviation NaN and the written model unreadable. A parameter held
// at its value is `identify --fix`'s.
inline constexpr double kMinPriorSigma = 1e-12;

// The `priors:` of a YAML model file (name, sigma in SI), in file order; empty without. Throws
// InputError as load_model, and for an unknown parameter name or a sigma that is not positive
// or is below kMinPriorSigma.
std::vector<std::pair<std::string, double>> load_model_priors(const std::string& path);

std::string write_model(const RobotModel& model);
// Writes whole or not at all (host/files/output_file.hpp); throws InputError when the file
// cannot be written.
void save_model(const RobotModel& model, const std::string& path);

}  // namespace kincal::model
