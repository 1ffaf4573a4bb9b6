// What a real robot may visit (`kincal plan --constraints FILE`, issue #23): the configurations a
// calibration plan may hold, beyond the model's joint limits. The plan draws and filters its
// candidates within them (plan.hpp), so no planned configuration violates one.
//
// The file (YAML, yaml-cpp), every key optional; positions in frame 0 of the model (the robot's
// base: a URDF's base link), m:
//
//   angles: deg               # the unit of revolute joint ranges and of half_angle (default rad)
//   workspace:                # the tool point inside this axis-aligned box
//     min: [-1.2, -1.2, 0.05]
//     max: [1.2, 1.2, 1.5]
//   floor:                    # the tool point and the origin of every frame 1..N on the normal's
//     point: [0, 0, 0]        # side of this plane (on it counts): the table the robot stands on
//     normal: [0, 0, 1]       # need not be unit length; not zero
//   joints:                   # sub-ranges of the readings, by joint name or q1..qN
//     shoulder_lift_joint: [-180, 0]
//   sight:                    # line of sight: the tool point inside the cone of this apex (the
//     apex: [0.4, -3.2, 0.2]  # measuring device), axis (from the apex, any length, not zero)
//     axis: [0, 1, 0]         # and half angle (0 < half_angle < 180 deg)
//     half_angle: 30
//
// The frame origins are the model's link frames (DH frames of a DH model, the joint frames of a
// URDF), which stand for the links' bodies only as well as the frames lie on them: a floor a few
// centimetres above the table leaves the links' thickness room.
//
// Refused (model::InputError "FILE:LINE:COLUMN: what", naming the key): YAML syntax, a file
// without any constraint (empty, or only `angles`), an unknown key, a key given twice in one
// mapping, a second YAML document (model/yaml_text.hpp), a key that is not a name (a list, a
// mapping or null), a value that is not a number
// or a list of the right length, non-finite numbers, a box whose min is not below its max on
// every axis, a zero normal or axis (any other length is normalized without overflow: [1e300,
// 0, 1] is the x axis), a half angle outside (0, 180) deg, a joint the model does not
// have or named twice, a range whose lower end is not below its upper end or that lies outside
// the joint's limits. Read through files::read_text() (kSettingsFile: a regular file of at most
// 16 MiB, UTF-8).
#pragma once

#include <array>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include "host/model/robot_model.hpp"

namespace kincal::identify {

struct WorkspaceBox {
  model::Vector3 min_m = model::Vector3::Zero();
  model::Vector3 max_m = model::Vector3::Zero();
};

struct FloorPlane {
  model::Vector3 point_m = model::Vector3::Zero();
  model::Vector3 normal = model::Vector3::UnitZ();  // unit, towards the allowed side
};

struct JointRange {
  int joint = 0;  // 0-based
  double lower = 0.0, upper = 0.0;
};

struct SightCone {
  model::Vector3 apex_m = model::Vector3::Zero();
  model::Vector3 axis = model::Vector3::UnitZ();  // unit
  double half_angle_rad = 0.0;
};

struct PlanConstraints {
  std::optional<WorkspaceBox> workspace;
  std::optional<FloorPlane> floor;
  std::vector<JointRange> joint_ranges;
  std::optional<SightCone> sight;
};

// The constraints a candidate configuration is held to, the model's joint limits first.
enum class Constraint { joint_limits, joint_ranges, workspace, floor, sight };
inline constexpr std::array<Constraint, 5> kConstraints{Constraint::joint_limits, Constraint::joint_ranges,
                                                        Constraint::workspace, Constraint::floor, Constraint::sight};

// "joint limits", "joint ranges", "workspace", "floor", "sight": the name the printout uses.
const char* constraint_name(Constraint c);

// One line for the printout: the constraint and its values ("floor: tool point and frame origins
// on the side of (0, 0, 1) of the plane through (0, 0, 0) m").
std::string describe(Constraint c, const PlanConstraints& constraints, const model::RobotModel& model);

// The constraints that readings q violate, as a bit set (bit static_cast<int>(Constraint)).
// q.size() == model.joint_count().
unsigned violated_constraints(const model::RobotModel& model, const PlanConstraints& constraints,
                              std::span<const double> q);

PlanConstraints read_plan_constraints(const std::string& path, const model::RobotModel& model);
PlanConstraints parse_plan_constraints(const std::string& text, const std::string& source,
                                       const model::RobotModel& model);

// The same constraints given as command-line options (`kincal plan --workspace ...`): each value
// as the user typed it, read and checked exactly as the file's keys (the same units, `angles`
// included); errors "the command line: KEY: what". At least one constraint must be given.
struct ConstraintOptions {
  std::string angles;                                                    // "deg" or "rad" (empty: rad)
  std::vector<std::string> workspace;                                    // min x, y, z, max x, y, z
  std::vector<std::string> floor;                                        // point x, y, z, normal x, y, z
  std::vector<std::pair<std::string, std::vector<std::string>>> joints;  // name (or qN): lower, upper
  std::vector<std::string> sight;                                        // apex x, y, z, axis x, y, z, half angle
};
PlanConstraints plan_constraints_from_options(const ConstraintOptions& options, const model::RobotModel& model);

// A file's constraints and the command line's together. A workspace, floor or sight given by
// both, or a joint ranged by both, is refused (InputError naming it and the file): neither
// silently wins.
PlanConstraints combine_plan_constraints(const PlanConstraints& file, const std::string& file_name,
                                         const PlanConstraints& options);

}  // namespace kincal::identify
