#include "host/identify/plan_constraints.hpp"

#include <charconv>
#include <cmath>
#include <numbers>
#include <set>
#include <sstream>

#include <yaml-cpp/yaml.h>

#include "host/files/input_file.hpp"
#include "host/model/number_text.hpp"
#include "host/model/yaml_text.hpp"

namespace kincal::identify {

namespace {

using model::InputError;
using model::Vector3;

// Values of one constraints file, each failure naming the key and where it stands.
struct Values {
  const std::string& source;

  [[noreturn]] void fail(const YAML::Node& node, const std::string& key, const std::string& what) const {
    const YAML::Mark mark = node.Mark();
    std::string where = source;
    if (!mark.is_null()) where += ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1);
    throw InputError(where + ": " + key + ": " + what);
  }

  void keys(const YAML::Node& map, const std::string& key, std::initializer_list<const char*> allowed) const {
    if (!map.IsMap()) fail(map, key.empty() ? "the file" : key, "expected a mapping");
    for (const auto& entry : map) {
      name_key(entry.first, key.empty() ? "the file" : key);
      const std::string name = entry.first.Scalar();
      bool known = false;
      std::string list;
      for (const char* k : allowed) {
        known = known || name == k;
        list += std::string(list.empty() ? "" : ", ") + k;
      }
      if (!known)
        fail(entry.first, key.empty() ? files::excerpt(name) : key + "." + files::excerpt(name),
             "unknown key (expected " + list + ")");
    }
  }

  // A key of a mapping that is not a name (a list, a mapping or null: "? [a, b]").
  void name_key(const YAML::Node& node, const std::string& key) const {
    if (!node.IsScalar()) fail(node, key, "a key must be a name, not a list, a mapping or null");
  }

  double number(const YAML::Node& node, const std::string& key) const {
    if (!node.IsScalar()) fail(node, key, "expected a number");
    const std::string& text = node.Scalar();
    const char* first = text.data() + (!text.empty() && text[0] == '+' ? 1 : 0);
    double v = 0.0;
    const auto [end, ec] = std::from_chars(first, text.data() + text.size(), v);
    if (ec != std::errc() || end != text.data() + text.size() || text.empty())
      fail(node, key, "'" + files::excerpt(text) + "' is not a number");
    if (!std::isfinite(v)) fail(node, key, "not finite");
    return v;
  }

  std::vector<double> list(const YAML::Node& node, const std::string& key, std::size_t size) const {
    if (!node.IsSequence() || node.size() != size)
      fail(node, key, "expected a list of " + std::to_string(size) + " numbers");
    std::vector<double> out;
    for (std::size_t i = 0; i < size; ++i) out.push_back(number(node[i], key));
    return out;
  }

  Vector3 vector3(const YAML::Node& map, const std::string& parent, const char* name) const {
    const YAML::Node node = map[name];
    const std::string key = parent + "." + name;
    if (!node) fail(map, key, "missing");
    const std::vector<double> v = list(node, key, 3);
    return Vector3(v[0], v[1], v[2]);
  }

  Vector3 direction(const YAML::Node& map, const std::string& parent, const char* name) const {
    // stableNorm: norm() squares, so [1e300, 0, 1] made inf and normalized() a zero direction
    // that every point meets, and [1e-200, 0, 0] 0.
    const Vector3 v = vector3(map, parent, name);
    if (!(v.stableNorm() > 0.0)) fail(map[name], parent + "." + name, "a zero vector has no direction");
    return v.stableNormalized();
  }
};

int joint_of(const model::RobotModel& model, const std::string& name) {
  for (int j = 0; j < model.joint_count(); ++j)
    if (model.joints[static_cast<std::size_t>(j)].name == name || name == "q" + std::to_string(j + 1)) return j;
  return -1;
}

std::string point_text(const Vector3& v) {
  return "(" + model::shortest_number_text(v.x()) + ", " + model::shortest_number_text(v.y()) + ", " +
         model::shortest_number_text(v.z()) + ")";
}

PlanConstraints read_root(const YAML::Node& root, const Values& r, const model::RobotModel& model) {
  PlanConstraints c;
  if (!root || root.IsNull())
    throw InputError(r.source + ": no constraints (expected workspace, floor, joints or sight)");
  r.keys(root, "", {"angles", "workspace", "floor", "joints", "sight"});
  double angle_scale = 1.0;
  if (const YAML::Node a = root["angles"]) {
    if (!a.IsScalar() || (a.Scalar() != "deg" && a.Scalar() != "rad")) r.fail(a, "angles", "expected deg or rad");
    angle_scale = a.Scalar() == "deg" ? std::numbers::pi / 180.0 : 1.0;
  }
  if (const YAML::Node w = root["workspace"]) {
    r.keys(w, "workspace", {"min", "max"});
    WorkspaceBox box{r.vector3(w, "workspace", "min"), r.vector3(w, "workspace", "max")};
    if (!(box.min_m.array() < box.max_m.array()).all())
      r.fail(w["max"], "workspace", "min must be below max on every axis");
    c.workspace = box;
  }
  if (const YAML::Node f = root["floor"]) {
    r.keys(f, "floor", {"point", "normal"});
    c.floor = FloorPlane{r.vector3(f, "floor", "point"), r.direction(f, "floor", "normal")};
  }
  if (const YAML::Node j = root["joints"]) {
    if (!j.IsMap()) r.fail(j, "joints", "expected a mapping of joint names (or q1..qN) to [lower, upper]");
    std::set<int> named;
    for (const auto& entry : j) {
      r.name_key(entry.first, "joints");
      const std::string name = entry.first.Scalar();
      const std::string key = "joints." + files::excerpt(name);
      const int joint = joint_of(model, name);
      if (joint < 0) r.fail(entry.first, key, "the model '" + model.name + "' has no such joint");
      if (!named.insert(joint).second) r.fail(entry.first, key, "the joint is named twice");
      const model::Joint& mj = model.joints[static_cast<std::size_t>(joint)];
      const double scale = mj.type == core::JointType::revolute ? angle_scale : 1.0;
      const std::vector<double> range = r.list(entry.second, key, 2);
      const JointRange jr{joint, range[0] * scale, range[1] * scale};
      if (!(jr.lower < jr.upper)) r.fail(entry.second, key, "the lower end must be below the upper end");
      if (jr.lower < mj.lower || jr.upper > mj.upper)
        r.fail(entry.second, key,
               "the range leaves the joint's limits [" + model::shortest_number_text(mj.lower) + ", " +
                   model::shortest_number_text(mj.upper) + "] (rad or m)");
      c.joint_ranges.push_back(jr);
    }
  }
  if (const YAML::Node s = root["sight"]) {
    r.keys(s, "sight", {"apex", "axis", "half_angle"});
    SightCone cone{r.vector3(s, "sight", "apex"), r.direction(s, "sight", "axis"), 0.0};
    if (!s["half_angle"]) r.fail(s, "sight.half_angle", "missing");
    cone.half_angle_rad = r.number(s["half_angle"], "sight.half_angle") * angle_scale;
    if (!(cone.half_angle_rad > 0.0 && cone.half_angle_rad < std::numbers::pi))
      r.fail(s["half_angle"], "sight.half_angle", "expected more than 0 and less than 180 deg (pi rad)");
    c.sight = cone;
  }
  if (!c.workspace && !c.floor && c.joint_ranges.empty() && !c.sight)
    r.fail(root, "the file", "no constraints (expected workspace, floor, joints or sight)");
  return c;
}

}  // namespace

const char* constraint_name(Constraint c) {
  switch (c) {
    case Constraint::joint_limits:
      return "joint limits";
    case Constraint::joint_ranges:
      return "joint ranges";
    case Constraint::workspace:
      return "workspace";
    case Constraint::floor:
      return "floor";
    case Constraint::sight:
      return "sight";
  }
  return "";
}

std::string describe(Constraint c, const PlanConstraints& k, const model::RobotModel& model) {
  switch (c) {
    case Constraint::joint_limits:
      return "joint limits: the model's (" + std::to_string(model.joint_count()) + " joints)";
    case Constraint::joint_ranges: {
      std::string text = "joint ranges:";
      for (const JointRange& r : k.joint_ranges)
        text += " " + model.joints[static_cast<std::size_t>(r.joint)].name + " [" +
                model::shortest_number_text(r.lower) + ", " + model::shortest_number_text(r.upper) + "]";
      return text;
    }
    case Constraint::workspace:
      return "workspace: tool point in the box " + point_text(k.workspace->min_m) + " to " +
             point_text(k.workspace->max_m) + " m";
    case Constraint::floor:
      return "floor: tool point and frame origins on the side of " + point_text(k.floor->normal) +
             " of the plane through " + point_text(k.floor->point_m) + " m";
    case Constraint::sight:
      return "sight: tool point within " +
             model::shortest_number_text(k.sight->half_angle_rad * 180.0 / std::numbers::pi) + " deg of the axis " +
             point_text(k.sight->axis) + " from " + point_text(k.sight->apex_m) + " m";
  }
  return {};
}

unsigned violated_constraints(const model::RobotModel& model, const PlanConstraints& k, std::span<const double> q) {
  unsigned violated = 0;
  const auto mark = [&](Constraint c) { violated |= 1u << static_cast<unsigned>(c); };
  for (std::size_t j = 0; j < q.size(); ++j) {
    const model::Joint& joint = model.joints[j];
    if (q[j] < joint.lower || q[j] > joint.upper) mark(Constraint::joint_limits);
  }
  for (const JointRange& r : k.joint_ranges) {
    const double v = q[static_cast<std::size_t>(r.joint)];
    if (v < r.lower || v > r.upper) mark(Constraint::joint_ranges);
  }
  if (!k.workspace && !k.floor && !k.sight) return violated;
  // Positions in frame 0: the chain's frames are in the device frame.
  const model::ChainAtJoints at = model::chain_at_joints(model, q);
  const model::Transform frame0_T_device = model.base_T_frame0.inverse();
  const auto in_frame0 = [&](const model::Transform& device_T_x) -> Vector3 {
    return (frame0_T_device * device_T_x).translation;
  };
  const Vector3 tool = in_frame0(at.frames.base_T_tool);
  if (k.workspace &&
      !((tool.array() >= k.workspace->min_m.array()).all() && (tool.array() <= k.workspace->max_m.array()).all()))
    mark(Constraint::workspace);
  if (k.floor) {
    const auto above = [&](const Vector3& p) { return k.floor->normal.dot(p - k.floor->point_m) >= 0.0; };
    bool all_above = above(tool);
    for (int i = 1; i <= model.joint_count(); ++i)
      all_above = all_above && above(in_frame0(at.frames.base_T_frame[static_cast<std::size_t>(i)]));
    if (!all_above) mark(Constraint::floor);
  }
  if (k.sight) {
    const Vector3 ray = tool - k.sight->apex_m;
    const double angle = std::atan2(ray.cross(k.sight->axis).norm(), ray.dot(k.sight->axis));
    if (!(angle <= k.sight->half_angle_rad)) mark(Constraint::sight);
  }
  return violated;
}

PlanConstraints parse_plan_constraints(const std::string& text, const std::string& source,
                                       const model::RobotModel& model) {
  const Values r{source};
  return model::read_yaml_text(text, source, [&](const YAML::Node& root) { return read_root(root, r, model); });
}

PlanConstraints read_plan_constraints(const std::string& path, const model::RobotModel& model) {
  return parse_plan_constraints(files::read_text_or_throw<InputError>(path, files::kSettingsFile), path, model);
}

PlanConstraints plan_constraints_from_options(const ConstraintOptions& o, const model::RobotModel& model) {
  // The document the file would hold; nodes built here carry no position, so errors name the key.
  const auto three_and_rest = [](YAML::Node node, const char* first, const char* second,
                                 const std::vector<std::string>& values) {
    node[first] = YAML::Node(YAML::NodeType::Sequence);
    node[second] = YAML::Node(YAML::NodeType::Sequence);
    for (std::size_t i = 0; i < values.size(); ++i) node[i < 3 ? first : second].push_back(values[i]);
  };
  if (o.workspace.empty() && o.floor.empty() && o.joints.empty() && o.sight.empty())
    throw InputError("the command line: no constraint (expected --workspace, --floor, --joint-range or --sight)");
  YAML::Node root(YAML::NodeType::Map);
  if (!o.angles.empty()) root["angles"] = o.angles;
  if (!o.workspace.empty()) three_and_rest(root["workspace"], "min", "max", o.workspace);
  if (!o.floor.empty()) three_and_rest(root["floor"], "point", "normal", o.floor);
  std::set<std::string> ranged;  // a map keeps one value a key: the second would silently win
  for (const auto& [name, range] : o.joints) {
    if (!ranged.insert(name).second)
      throw InputError("the command line: joints." + files::excerpt(name) + ": the joint is named twice");
    root["joints"][name] = range;
  }
  if (!o.sight.empty()) {
    if (o.sight.size() != 7)
      throw InputError("the command line: sight: expected 7 numbers (apex x, y, z, axis x, y, z, half angle), got " +
                       std::to_string(o.sight.size()));
    three_and_rest(root["sight"], "apex", "axis", {o.sight.begin(), o.sight.end() - 1});
    root["sight"]["half_angle"] = o.sight.back();
  }
  return read_root(root, Values{"the command line"}, model);
}

PlanConstraints combine_plan_constraints(const PlanConstraints& file, const std::string& file_name,
                                         const PlanConstraints& options) {
  const auto refuse_both = [&](bool both, const std::string& what) {
    if (both) throw InputError("the command line and " + file_name + " both give " + what + ": give it in one place");
  };
  PlanConstraints c = file;
  refuse_both(file.workspace && options.workspace, "a workspace");
  refuse_both(file.floor && options.floor, "a floor");
  refuse_both(file.sight && options.sight, "a sight cone");
  if (options.workspace) c.workspace = options.workspace;
  if (options.floor) c.floor = options.floor;
  if (options.sight) c.sight = options.sight;
  for (const JointRange& r : options.joint_ranges) {
    for (const JointRange& f : file.joint_ranges)
      refuse_both(f.joint == r.joint, "a range of q" + std::to_string(r.joint + 1));
    c.joint_ranges.push_back(r);
  }
  return c;
}

}  // namespace kincal::identify
