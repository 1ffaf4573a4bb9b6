#include "host/model/model_file.hpp"

#include "host/files/input_file.hpp"
#include "host/files/output_file.hpp"
#include "host/model/number_text.hpp"
#include "host/model/yaml_text.hpp"

#include <yaml-cpp/yaml.h>

#include <charconv>
#include <cmath>
#include <initializer_list>
#include <iostream>
#include <limits>
#include <numbers>
#include <set>
#include <sstream>

#include <Eigen/SVD>

namespace kincal::model {

namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const YAML::Node& node, const std::string& what) const {
    const YAML::Mark mark = node.Mark();
    std::ostringstream out;
    out << source_;
    if (!mark.is_null()) out << ':' << mark.line + 1 << ':' << mark.column + 1;
    out << ": " << what;
    throw InputError(out.str());
  }

  void only_keys(const YAML::Node& map, const std::string& what, std::initializer_list<const char*> keys) const {
    if (!map.IsMap()) fail(map, what + " must be a mapping");
    for (const auto& entry : map) {
      const std::string key = entry.first.as<std::string>();
      bool known = false;
      for (const char* k : keys) known = known || key == k;
      if (!known) {
        std::string list;
        for (const char* k : keys) list += std::string(list.empty() ? "" : ", ") + k;
        fail(entry.first, "unknown key '" + files::excerpt(key) + "' in " + what + " (expected " + list + ")");
      }
    }
  }

  double number(const YAML::Node& node, const std::string& what) const {
    if (!node.IsScalar()) fail(node, what + " must be a number");
    const std::string text = node.Scalar();
    double value = 0.0;
    const char* first = text.data();
    const char* last = text.data() + text.size();
    if (first != last && *first == '+') ++first;
    const auto [end, ec] = std::from_chars(first, last, value);
    if (ec != std::errc() || end != last) fail(node, what + ": '" + files::excerpt(text) + "' is not a number");
    if (!std::isfinite(value)) fail(node, what + " must be finite");
    return value;
  }

  // An angle in rad, within `turns` turns either way. In a file whose angles are radians, one
  // beyond that is most likely degrees (alpha: 90), which the message says.
  double angle(const YAML::Node& node, const std::string& what, AngleUnit unit, double turns = 1.0) const {
    const double v = number(node, what);
    const double rad = unit == AngleUnit::deg ? v / kDegPerRad : v;
    if (std::abs(rad) > turns * 2.0 * std::numbers::pi + 1e-9) {
      const std::string within = turns == 1.0 ? "a turn" : shortest_number_text(turns) + " turns";
      if (unit == AngleUnit::rad)
        fail(node, what + ": " + files::excerpt(node.Scalar()) + " rad is more than " + within +
                       ": are the file's angles degrees? then say 'angles: deg' at its top (without it, angles "
                       "are radians)");
      fail(node, what + ": " + files::excerpt(node.Scalar()) + " deg is more than " + within);
    }
    return rad;
  }

  // A number within [lowest, highest], the range's reason in the message.
  double bounded(const YAML::Node& node, const std::string& what, double lowest, double highest,
                 const std::string& why) const {
    const double v = number(node, what);
    if (v < lowest || v > highest)
      fail(node, what + ": " + files::excerpt(node.Scalar()) + " is outside [" + shortest_number_text(lowest) + ", " +
                     shortest_number_text(highest) + "] " + why);
    return v;
  }

  // A length in m, at most `limit` either way.
  double length(const YAML::Node& node, const std::string& what, double limit = kMaxLength_m) const {
    return bounded(node, what, -limit, limit, "(m: is it in millimetres?)");
  }

  Vector3 vector3(const YAML::Node& node, const std::string& what, double limit = kMaxLength_m) const {
    if (!node.IsSequence() || node.size() != 3) fail(node, what + " must be a list of 3 numbers");
    return Vector3(length(node[0], what, limit), length(node[1], what, limit), length(node[2], what, limit));
  }

  Vector3 angles3(const YAML::Node& node, const std::string& what, AngleUnit unit) const {
    if (!node.IsSequence() || node.size() != 3) fail(node, what + " must be a list of 3 numbers");
    return Vector3(angle(node[0], what, unit), angle(node[1], what, unit), angle(node[2], what, unit));
  }

  double mass(const YAML::Node& node, const std::string& what) const {
    const double v = number(node, what);
    if (v < 0.0) fail(node, what + " must not be negative (kg)");
    if (v > kMaxMass_kg)
      fail(node, what + ": " + files::excerpt(node.Scalar()) + " kg is more than " + shortest_number_text(kMaxMass_kg) +
                     " kg, more than any arm's link or payload (grams?)");
    return v;
  }

  std::string text(const YAML::Node& node, const std::string& what) const {
    if (!node.IsScalar()) fail(node, what + " must be a string");
    // yaml-cpp reads escapes ("\xE9") as bytes that it would write back as U+FFFD: a name that is
    // not UTF-8 would not survive being written (found by fuzz.model_input).
    if (files::first_invalid_utf8(node.Scalar()) != std::string::npos) fail(node, what + " is not UTF-8 text");
    return node.Scalar();
  }

  // A name of the robot, a joint or a link: it names a URDF's elements (`kincal urdf` wrote
  // "wa\x01ist" into a file lxml refuses; tinyxml2 and urdfdom took it).
  std::string name(const YAML::Node& node, const std::string& what) const {
    const std::string t = text(node, what);
    if (const std::size_t i = files::first_control_character(t); i != std::string::npos)
      fail(node,
           what + ": " + files::control_character_text(t, i) + ": a name is printable text (it names URDF elements)");
    return t;
  }

  // translation + rpy or quaternion (both optional: identity).
  Transform transform(const YAML::Node& node, const std::string& what, AngleUnit unit, double limit) const {
    Transform t;
    if (node["translation"]) t.translation = vector3(node["translation"], what + " translation", limit);
    if (node["rpy"] && node["quaternion"]) fail(node, what + ": give rpy or quaternion, not both");
    if (node["rpy"]) t.rotation = rotation_from_rpy(angles3(node["rpy"], what + " rpy", unit));
    if (node["quaternion"]) {
      const YAML::Node& qn = node["quaternion"];
      if (!qn.IsSequence() || qn.size() != 4) fail(qn, what + " quaternion must be a list of 4 numbers [w, x, y, z]");
      Eigen::Quaterniond q(number(qn[0], what), number(qn[1], what), number(qn[2], what), number(qn[3], what));
      const double norm = q.norm();
      if (std::abs(norm - 1.0) > 1e-6)
        fail(qn, what + " quaternion is not a unit quaternion (norm " + std::to_string(norm) + ")");
      t.rotation = q.normalized().toRotationMatrix();
    }
    return t;
  }

 private:
  std::string source_;
};

// Readings must map one to one onto the chain's variables (the correction inverts the map).
void check_coupling(const Reader& r, const YAML::Node& joints, const RobotModel& model) {
  const auto n = static_cast<Eigen::Index>(model.joints.size());
  Eigen::MatrixXd c = Eigen::MatrixXd::Identity(n, n);
  bool coupled = false;
  for (Eigen::Index i = 0; i < n; ++i) {
    const std::vector<double>& row = model.joints[static_cast<std::size_t>(i)].coupling;
    if (row.empty()) continue;
    coupled = true;
    for (Eigen::Index k = 0; k < n; ++k) c(i, k) = row[static_cast<std::size_t>(k)];
  }
  if (!coupled) return;
  const Eigen::VectorXd s = c.jacobiSvd().singularValues();
  if (!(s(n - 1) > 1e-9 * s(0)))
    r.fail(joints, "the joints' coupling rows are linearly dependent: two joints would follow the same readings");
}

// Joint names name a joint in messages, parameters and URDF: two joints of one name (a name
// given twice, or a given name equal to another joint's default j<i>) are refused naming both.
void check_names(const Reader& r, const YAML::Node& joints, const RobotModel& model) {
  for (std::size_t i = 0; i < model.joints.size(); ++i)
    for (std::size_t k = 0; k < i; ++k) {
      if (model.joints[i].name != model.joints[k].name) continue;
      const YAML::Node first = joints[k]["name"] ? joints[k]["name"] : joints[k];
      const YAML::Node second = joints[i]["name"] ? joints[i]["name"] : joints[i];
      r.fail(second, "joint " + std::to_string(i + 1) + "'s name '" + files::excerpt(model.joints[i].name) +
                         "' is joint " + std::to_string(k + 1) + "'s name too (line " +
                         std::to_string(first.Mark().line + 1) + "): joint names must differ");
    }
}

// A compliance deflects its joint by the gravity load of the bodies the joint moves (its link,
// the links after it, the payload): with no mass on any of them the load is zero in every pose
// and the compliance can do nothing.
void check_loaded_compliances(const Reader& r, const YAML::Node& joints, const RobotModel& model) {
  double carried_kg = model.payload.mass_kg;
  for (std::size_t i = model.joints.size(); i-- > 0;) {
    carried_kg += model.joints[i].mass_kg;
    if (model.joints[i].compliance && carried_kg == 0.0)
      r.fail(joints[i]["compliance"],
             "joint " + std::to_string(i + 1) + " compliance: neither the links this joint moves nor a payload " +
                 "have a mass, so gravity loads it with nothing and the compliance cannot act (give their " +
                 "'mass:' and 'centre_of_mass:', or a 'payload:')");
  }
}

CalibrationRecord read_calibration(const Reader& r, const YAML::Node& node, int joint_count) {
  r.only_keys(node, "calibration",
              {"method", "data", "measurements", "rms_residual_m", "validation_rms_m", "held_fixed", "parameters",
               "reading_ranges", "correlations", "model_error_m", "model_error_rad"});
  CalibrationRecord c;
  if (node["method"]) c.method = r.text(node["method"], "calibration method");
  if (node["data"]) c.data = r.text(node["data"], "calibration data");
  if (node["measurements"]) {
    const double count =
        r.bounded(node["measurements"], "measurements", 0.0, std::numeric_limits<int>::max(), "(a count of rows)");
    if (count != std::floor(count)) r.fail(node["measurements"], "measurements must be a whole number");
    c.measurements = static_cast<int>(count);
  }
  if (node["rms_residual_m"])
    c.rms_residual_m =
        r.bounded(node["rms_residual_m"], "rms_residual_m", 0.0, std::numeric_limits<double>::max(), "(an RMS)");
  if (node["validation_rms_m"])
    c.validation_rms_m =
        r.bounded(node["validation_rms_m"], "validation_rms_m", 0.0, std::numeric_limits<double>::max(), "(an RMS)");
  if (node["held_fixed"]) {
    if (!node["held_fixed"].IsSequence()) r.fail(node["held_fixed"], "held_fixed must be a list");
    for (const auto& n : node["held_fixed"]) c.held_fixed.push_back(r.text(n, "held_fixed entry"));
  }
  if (const YAML::Node& ranges = node["reading_ranges"]) {
    if (!ranges.IsSequence() || static_cast<int>(ranges.size()) != joint_count)
      r.fail(ranges,
             "reading_ranges must be a list of one [lowest, highest] per joint (" + std::to_string(joint_count) + ")");
    for (const auto& n : ranges) {
      if (!n.IsSequence() || n.size() != 2) r.fail(n, "a reading range must be [lowest, highest]");
      const std::array<double, 2> range{r.number(n[0], "lowest reading"), r.number(n[1], "highest reading")};
      if (range[0] > range[1]) r.fail(n, "a reading range's lowest is above its highest");
      c.reading_ranges.push_back(range);
    }
  }
  if (node["parameters"]) {
    if (!node["parameters"].IsSequence()) r.fail(node["parameters"], "calibration parameters must be a list");
    std::set<std::string> names;
    for (const auto& n : node["parameters"]) {
      r.only_keys(n, "calibration parameter", {"name", "change", "stddev"});
      ParameterReport p;
      p.name = r.text(n["name"], "parameter name");
      if (!names.insert(p.name).second)
        r.fail(n["name"], "calibration parameter '" + files::excerpt(p.name) + "' named twice");
      if (n["change"]) p.value = r.number(n["change"], "change");
      if (n["stddev"])
        p.stddev = r.bounded(n["stddev"], "stddev", 0.0, std::numeric_limits<double>::max(), "(a standard deviation)");
      c.parameters.push_back(p);
    }
  }
  if (const YAML::Node& rows = node["correlations"]) {
    const std::size_t n = c.parameters.size();
    if (!rows.IsSequence() || rows.size() + 1 != std::max<std::size_t>(n, 1))
      r.fail(rows, "correlations must be a list of one row per parameter after the first (" +
                       std::to_string(n > 0 ? n - 1 : 0) + ")");
    for (std::size_t k = 0; k < rows.size(); ++k) {
      const YAML::Node& row = rows[k];
      if (!row.IsSequence() || row.size() != k + 1)
        r.fail(row, "correlations row " + std::to_string(k + 1) + " must list " + std::to_string(k + 1) +
                        " correlations (parameter " + std::to_string(k + 2) + "'s with each before it)");
      std::vector<double> values;
      for (const auto& v : row) values.push_back(r.bounded(v, "correlation", -1.0, 1.0, "(a correlation)"));
      c.correlations.push_back(std::move(values));
    }
  }
  if (node["model_error_m"])
    c.model_error_m = r.bounded(node["model_error_m"], "model_error_m", 0.0, kMaxLength_m, "(a model error)");
  if (node["model_error_rad"])
    c.model_error_rad = r.bounded(node["model_error_rad"], "model_error_rad", 0.0, std::numbers::pi, "(a model error)");
  return c;
}

// The `priors:` mapping: parameter name -> sigma (SI lengths; angles in the file's unit).
std::vector<std::pair<std::string, double>> read_priors(const Reader& r, const YAML::Node& node, int joint_count,
                                                        AngleUnit unit) {
  if (!node.IsMap()) r.fail(node, "priors must be a mapping of parameter names to sigmas");
  std::vector<std::pair<std::string, double>> out;
  std::vector<std::pair<core::ParameterId, YAML::Node>> seen;
  for (const auto& entry : node) {
    const std::string name = r.text(entry.first, "a prior's parameter name");
    core::ParameterId id{};
    try {
      id = parse_parameter_name(name, joint_count);
    } catch (const InputError& e) {
      r.fail(entry.first, std::string("priors: ") + e.what());
    }
    for (const auto& [other, key] : seen)
      if (other.kind == id.kind && other.link == id.link)
        r.fail(entry.first, "priors: '" + files::excerpt(name) + "' names the parameter that '" +
                                files::excerpt(key.Scalar()) + "' (line " + std::to_string(key.Mark().line + 1) +
                                ") names: give one prior per parameter");
    seen.emplace_back(id, entry.first);
    const bool angle = is_angle_parameter(id.kind);
    const double sigma =
        angle ? r.angle(entry.second, "priors: " + name, unit) : r.number(entry.second, "priors: " + name);
    // A sigma beyond the parameter's own range says nothing the range does not.
    const double largest = angle                         ? 2.0 * std::numbers::pi
                           : id.kind == kJointScale      ? kMaxScale
                           : id.kind == kJointCompliance ? kMaxCompliance
                           : id.kind == kJointCoupling   ? kMaxCoupling
                                                         : kMaxLength_m;
    if (sigma > largest)
      r.fail(entry.second, "priors: " + name + ": " + shortest_number_text(sigma) + " is more than " +
                               shortest_number_text(largest) + ", the parameter's own range (m, rad, or SI)");
    if (!(sigma > 0.0)) r.fail(entry.second, "priors: " + name + " must be positive (a standard deviation)");
    if (sigma < kMinPriorSigma)
      r.fail(entry.second, "priors: " + name + ": " + shortest_number_text(sigma) + " (m or rad) is below " +
                               shortest_number_text(kMinPriorSigma) +
                               ", too small for the solve; hold the parameter with identify --fix instead");
    out.emplace_back(name, sigma);
  }
  return out;
}

RobotModel read_model(const YAML::Node& root, const Reader& r) {
  if (!root || root.IsNull()) r.fail(root, "empty model file");
  r.only_keys(
      root, "the model",
      {"name", "angles", "base", "joints", "tool", "flange", "tcp", "gravity", "payload", "calibration", "priors"});
  RobotModel model;
  model.name = root["name"] ? r.name(root["name"], "name") : "robot";
  if (root["angles"]) {
    const std::string unit = r.text(root["angles"], "angles");
    if (unit == "deg" || unit == "degrees") {
      model.file_angles = AngleUnit::deg;
    } else if (unit != "rad" && unit != "radians") {
      r.fail(root["angles"], "angles: unknown unit '" + files::excerpt(unit) + "' (expected rad or deg)");
    }
  }
  const AngleUnit unit = model.file_angles;
  if (root["base"]) {
    r.only_keys(root["base"], "base", {"translation", "rpy", "quaternion"});
    model.base_T_frame0 = r.transform(root["base"], "base", unit, kMaxBaseDistance_m);
  }
  const YAML::Node joints = root["joints"];
  if (!joints) r.fail(root, "the model has no 'joints' list");
  if (!joints.IsSequence() || joints.size() == 0) r.fail(joints, "joints must be a non-empty list");
  if (joints.size() > static_cast<std::size_t>(core::kMaxJoints))
    r.fail(joints, "the model has " + std::to_string(joints.size()) + " joints; at most " +
                       std::to_string(core::kMaxJoints) + " are supported");
  int index = 0;
  for (const auto& jn : joints) {
    ++index;
    const std::string what = "joint " + std::to_string(index);
    r.only_keys(jn, what,
                {"name", "type", "convention", "d", "theta", "a", "alpha", "beta", "offset", "limits", "coupling",
                 "scale", "compliance", "mass", "centre_of_mass"});
    Joint j;
    j.name = jn["name"] ? r.name(jn["name"], what + " name") : "j" + std::to_string(index);
    if (!jn["type"]) r.fail(jn, what + ": missing 'type' (revolute or prismatic)");
    const std::string type = r.text(jn["type"], what + " type");
    if (type == "revolute") {
      j.type = core::JointType::revolute;
    } else if (type == "prismatic") {
      j.type = core::JointType::prismatic;
    } else {
      r.fail(jn["type"], what + ": unknown joint type '" + files::excerpt(type) + "' (expected revolute or prismatic)");
    }
    if (!jn["convention"]) r.fail(jn, what + ": missing 'convention' (dh, mdh or doty)");
    const std::string convention = r.text(jn["convention"], what + " convention");
    if (convention == "dh") {
      j.convention = core::LinkConvention::standard_dh;
    } else if (convention == "mdh") {
      j.convention = core::LinkConvention::modified_dh;
    } else if (convention == "doty") {
      j.convention = core::LinkConvention::doty;
    } else {
      r.fail(jn["convention"],
             what + ": unknown convention '" + files::excerpt(convention) + "' (expected dh, mdh or doty)");
    }
    for (const char* key : {"d", "theta", "a", "alpha"})
      if (!jn[key]) r.fail(jn, what + ": missing parameter '" + key + "'");
    if (jn["beta"] && j.convention != core::LinkConvention::doty)
      r.fail(jn["beta"], what + ": beta belongs to the doty convention only");
    j.parameters.d_m = r.length(jn["d"], what + " d");
    j.parameters.a_m = r.length(jn["a"], what + " a");
    j.parameters.theta_rad = r.angle(jn["theta"], what + " theta", unit);
    j.parameters.alpha_rad = r.angle(jn["alpha"], what + " alpha", unit);
    if (jn["beta"]) j.parameters.beta_rad = r.angle(jn["beta"], what + " beta", unit);
    const bool revolute = j.type == core::JointType::revolute;
    if (jn["offset"])
      j.offset = revolute ? r.angle(jn["offset"], what + " offset", unit) : r.length(jn["offset"], what + " offset");
    if (jn["limits"]) {
      const YAML::Node& l = jn["limits"];
      if (!l.IsSequence() || l.size() != 2) r.fail(l, what + ": limits must be [lower, upper]");
      j.lower =
          revolute ? r.angle(l[0], what + " lower limit", unit, kMaxLimitTurns) : r.length(l[0], what + " lower limit");
      j.upper =
          revolute ? r.angle(l[1], what + " upper limit", unit, kMaxLimitTurns) : r.length(l[1], what + " upper limit");
      if (!(j.lower < j.upper))
        r.fail(l, what + ": lower limit must be below the upper limit (equal limits leave the joint no motion)");
    }
    if (jn["coupling"]) {
      const YAML::Node& c = jn["coupling"];
      if (!c.IsSequence() || c.size() != joints.size())
        r.fail(c, what + ": coupling must be a list of " + std::to_string(joints.size()) +
                      " coefficients, one per joint reading");
      for (const auto& k : c)
        j.coupling.push_back(r.bounded(k, what + " coupling", -kMaxCoupling, kMaxCoupling,
                                       "(a reading's share in this joint's motion)"));
    }
    if (jn["scale"]) {
      j.scale = r.number(jn["scale"], what + " scale");
      if (!(*j.scale > 0.0)) r.fail(jn["scale"], what + ": scale must be positive");
      (void)r.bounded(jn["scale"], what + " scale", kMinScale, kMaxScale,
                      "(a gear-ratio error near 1: a factor like 57.3 or 1000 is a unit, not a scale)");
    }
    if (jn["compliance"]) {
      j.compliance = r.number(jn["compliance"], what + " compliance");
      if (*j.compliance < 0.0)
        r.fail(jn["compliance"], what +
                                     ": compliance must not be negative (a joint yields with its load, "
                                     "rad/(N m) or m/N)");
      (void)r.bounded(jn["compliance"], what + " compliance", 0.0, kMaxCompliance,
                      revolute ? "(rad/(N m): 1 N m would turn the joint by a radian)"
                               : "(m/N: 1 N would move the joint by a metre)");
    }
    if (jn["mass"]) j.mass_kg = r.mass(jn["mass"], what + " mass");
    if (jn["centre_of_mass"]) j.centre_of_mass_m = r.vector3(jn["centre_of_mass"], what + " centre_of_mass");
    model.joints.push_back(j);
  }
  check_coupling(r, joints, model);
  check_names(r, joints, model);
  if (root["tool"]) {
    const YAML::Node& t = root["tool"];
    r.only_keys(t, "tool", {"point", "translation", "rpy", "quaternion"});
    if (t["point"]) {
      if (t["translation"] || t["rpy"] || t["quaternion"])
        r.fail(t, "tool: give either point or a frame (translation with rpy or quaternion), not both");
      model.tool = ToolKind::point;
      model.flange_T_tool.translation = r.vector3(t["point"], "tool point");
    } else {
      model.tool = ToolKind::frame;
      model.flange_T_tool = r.transform(t, "tool", unit, kMaxLength_m);
    }
  }
  if (root["flange"]) {  // robot_model.hpp: the flange in frame n, and the TCP from it
    r.only_keys(root["flange"], "flange", {"link", "translation", "rpy", "quaternion"});
    if (root["flange"]["link"]) model.flange_link = r.name(root["flange"]["link"], "flange link");
    model.frame_n_T_flange = r.transform(root["flange"], "flange", unit, kMaxLength_m);
  }
  if (root["tcp"]) {
    r.only_keys(root["tcp"], "tcp", {"translation", "rpy", "quaternion"});
    model.flange_T_tcp = r.transform(root["tcp"], "tcp", unit, kMaxLength_m);
  }
  if (root["gravity"]) {
    model.gravity_mps2 = r.vector3(root["gravity"], "gravity", std::numeric_limits<double>::max());
    if (model.gravity_mps2.norm() > kMaxGravity_mps2)
      r.fail(root["gravity"], "gravity: " + shortest_number_text(model.gravity_mps2.norm()) + " m/s^2 is more than " +
                                  shortest_number_text(kMaxGravity_mps2) +
                                  " m/s^2 (twice the standard gravity; is it in mm/s^2?)");
  }
  if (root["payload"]) {
    const YAML::Node& p = root["payload"];
    r.only_keys(p, "payload", {"mass", "centre_of_mass"});
    if (p["mass"]) model.payload.mass_kg = r.mass(p["mass"], "payload mass");
    if (p["centre_of_mass"]) model.payload.centre_of_mass_m = r.vector3(p["centre_of_mass"], "payload centre_of_mass");
  }
  check_loaded_compliances(r, joints, model);
  if (root["calibration"]) model.calibration = read_calibration(r, root["calibration"], model.joint_count());
  if (root["priors"])
    (void)read_priors(r, root["priors"], model.joint_count(), unit);  // checked here, used by identify
  return model;
}

// Angles converted to degrees: 15 significant digits, so 30 deg does not come out as
// 29.999999999999996 (the conversion's rounding); radians keep the exact shortest form.
std::string angle_text(double v, double scale) {
  if (scale == 1.0) return shortest_number_text(v);
  v *= scale;
  if (v == 0.0) v = 0.0;
  char buffer[64];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, v, std::chars_format::general, 15);
  return ec == std::errc() ? std::string(buffer, end) : std::string("nan");
}

void emit_vector(YAML::Emitter& out, const Vector3& v, double scale = 1.0) {
  out << YAML::Flow << YAML::BeginSeq;
  for (int i = 0; i < 3; ++i) out << angle_text(v(i), scale);
  out << YAML::EndSeq;
}

void emit_transform(YAML::Emitter& out, const Transform& t, double angle_scale) {
  out << YAML::BeginMap;
  out << YAML::Key << "translation" << YAML::Value;
  emit_vector(out, t.translation);
  out << YAML::Key << "rpy" << YAML::Value;
  emit_vector(out, rpy_from_rotation(t.rotation), angle_scale);
  out << YAML::EndMap;
}

}  // namespace

RobotModel parse_model(const std::string& text, const std::string& source) {
  const Reader r(source);
  return read_yaml_text(text, source, [&](const YAML::Node& root) { return read_model(root, r); });
}

RobotModel load_model(const std::string& path, const UrdfChainEnds& ends) {
  if (is_urdf_path(path)) {
    const UrdfChain chain = parse_urdf_chain(files::read_text_or_throw<InputError>(path, files::kUrdfFile), path, ends);
    for (const std::string& w : chain.warnings) std::cerr << "kincal: warning: " << w << '\n';  // urdf_chain.hpp
    return model_from_urdf(chain);
  }
  if (!ends.base_link.empty() || !ends.tip_link.empty())
    throw InputError(path + ": --base-link and --tip-link are for URDF models (*.urdf)");
  return parse_model(files::read_text_or_throw<InputError>(path, files::kModelFile), path);
}

std::vector<std::pair<std::string, double>> load_model_priors(const std::string& path) {
  const std::string text = files::read_text_or_throw<InputError>(path, files::kModelFile);  // read once
  const RobotModel model = parse_model(text, path);  // the whole file checked, priors included
  return read_yaml_text(text, path, [&](const YAML::Node& root) {
    if (!root["priors"]) return std::vector<std::pair<std::string, double>>{};
    return read_priors(Reader(path), root["priors"], model.joint_count(), model.file_angles);
  });
}

std::string write_model(const RobotModel& model) {
  const bool deg = model.file_angles == AngleUnit::deg;
  const double a = deg ? kDegPerRad : 1.0;
  YAML::Emitter out;
  out << YAML::BeginMap;
  out << YAML::Key << "name" << YAML::Value << model.name;
  out << YAML::Key << "angles" << YAML::Value << (deg ? "deg" : "rad");
  out << YAML::Key << "base" << YAML::Value;
  emit_transform(out, model.base_T_frame0, a);
  out << YAML::Key << "joints" << YAML::Value << YAML::BeginSeq;
  for (const Joint& j : model.joints) {
    const bool revolute = j.type == core::JointType::revolute;
    out << YAML::BeginMap;
    out << YAML::Key << "name" << YAML::Value << j.name;
    out << YAML::Key << "type" << YAML::Value << (revolute ? "revolute" : "prismatic");
    const char* convention = j.convention == core::LinkConvention::standard_dh   ? "dh"
                             : j.convention == core::LinkConvention::modified_dh ? "mdh"
                                                                                 : "doty";
    out << YAML::Key << "convention" << YAML::Value << convention;
    out << YAML::Key << "d" << YAML::Value << shortest_number_text(j.parameters.d_m);
    out << YAML::Key << "theta" << YAML::Value << angle_text(j.parameters.theta_rad, a);
    out << YAML::Key << "a" << YAML::Value << shortest_number_text(j.parameters.a_m);
    out << YAML::Key << "alpha" << YAML::Value << angle_text(j.parameters.alpha_rad, a);
    if (j.convention == core::LinkConvention::doty)
      out << YAML::Key << "beta" << YAML::Value << angle_text(j.parameters.beta_rad, a);
    out << YAML::Key << "offset" << YAML::Value << angle_text(j.offset, revolute ? a : 1.0);
    if (std::isfinite(j.lower) && std::isfinite(j.upper)) {
      const double s = revolute ? a : 1.0;
      out << YAML::Key << "limits" << YAML::Value << YAML::Flow << YAML::BeginSeq << angle_text(j.lower, s)
          << angle_text(j.upper, s) << YAML::EndSeq;
    }
    if (!j.coupling.empty()) {
      out << YAML::Key << "coupling" << YAML::Value << YAML::Flow << YAML::BeginSeq;
      for (const double c : j.coupling) out << shortest_number_text(c);
      out << YAML::EndSeq;
    }
    if (j.scale) out << YAML::Key << "scale" << YAML::Value << shortest_number_text(*j.scale);
    if (j.compliance) out << YAML::Key << "compliance" << YAML::Value << shortest_number_text(*j.compliance);
    if (j.mass_kg != 0.0) out << YAML::Key << "mass" << YAML::Value << shortest_number_text(j.mass_kg);
    if (!j.centre_of_mass_m.isZero(0.0)) {
      out << YAML::Key << "centre_of_mass" << YAML::Value;
      emit_vector(out, j.centre_of_mass_m);
    }
    out << YAML::EndMap;
  }
  out << YAML::EndSeq;
  out << YAML::Key << "tool" << YAML::Value;
  if (model.tool == ToolKind::point) {
    out << YAML::BeginMap << YAML::Key << "point" << YAML::Value;
    emit_vector(out, model.flange_T_tool.translation);
    out << YAML::EndMap;
  } else {
    emit_transform(out, model.flange_T_tool, a);
  }
  if (!model.flange_link.empty() || !model.frame_n_T_flange.translation.isZero(0.0) ||
      !model.frame_n_T_flange.rotation.isIdentity(0.0)) {
    out << YAML::Key << "flange" << YAML::Value << YAML::BeginMap;
    if (!model.flange_link.empty()) out << YAML::Key << "link" << YAML::Value << model.flange_link;
    out << YAML::Key << "translation" << YAML::Value;
    emit_vector(out, model.frame_n_T_flange.translation);
    out << YAML::Key << "rpy" << YAML::Value;
    emit_vector(out, rpy_from_rotation(model.frame_n_T_flange.rotation), a);
    out << YAML::EndMap;
  }
  if (model.flange_T_tcp) {
    out << YAML::Key << "tcp" << YAML::Value;
    emit_transform(out, *model.flange_T_tcp, a);
  }
  if (has_compliance(model) || model.gravity_mps2 != RobotModel{}.gravity_mps2) {
    out << YAML::Key << "gravity" << YAML::Value;
    emit_vector(out, model.gravity_mps2);
  }
  if (model.payload.mass_kg != 0.0 || !model.payload.centre_of_mass_m.isZero(0.0)) {
    out << YAML::Key << "payload" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "mass" << YAML::Value << shortest_number_text(model.payload.mass_kg);
    out << YAML::Key << "centre_of_mass" << YAML::Value;
    emit_vector(out, model.payload.centre_of_mass_m);
    out << YAML::EndMap;
  }
  if (model.calibration) {
    const CalibrationRecord& c = *model.calibration;
    out << YAML::Key << "calibration" << YAML::Value << YAML::BeginMap;
    out << YAML::Key << "method" << YAML::Value << c.method;
    out << YAML::Key << "data" << YAML::Value << c.data;
    out << YAML::Key << "measurements" << YAML::Value << c.measurements;
    out << YAML::Key << "rms_residual_m" << YAML::Value << shortest_number_text(c.rms_residual_m);
    if (c.validation_rms_m)
      out << YAML::Key << "validation_rms_m" << YAML::Value << shortest_number_text(*c.validation_rms_m);
    out << YAML::Key << "held_fixed" << YAML::Value << YAML::Flow << YAML::BeginSeq;
    for (const std::string& name : c.held_fixed) out << name;
    out << YAML::EndSeq;
    if (!c.reading_ranges.empty()) {
      out << YAML::Key << "reading_ranges" << YAML::Value << YAML::Flow << YAML::BeginSeq;
      for (const auto& [low, high] : c.reading_ranges)
        out << YAML::BeginSeq << shortest_number_text(low) << shortest_number_text(high) << YAML::EndSeq;
      out << YAML::EndSeq;
    }
    out << YAML::Key << "parameters" << YAML::Value << YAML::BeginSeq;
    for (const ParameterReport& p : c.parameters) {
      out << YAML::Flow << YAML::BeginMap << YAML::Key << "name" << YAML::Value << p.name;
      out << YAML::Key << "change" << YAML::Value << shortest_number_text(p.value);
      out << YAML::Key << "stddev" << YAML::Value << shortest_number_text(p.stddev) << YAML::EndMap;
    }
    out << YAML::EndSeq;
    if (!c.correlations.empty()) {
      out << YAML::Key << "correlations" << YAML::Value << YAML::BeginSeq;
      for (const std::vector<double>& row : c.correlations) {
        out << YAML::Flow << YAML::BeginSeq;
        for (const double v : row) out << shortest_number_text(v);
        out << YAML::EndSeq;
      }
      out << YAML::EndSeq;
    }
    if (c.model_error_m) out << YAML::Key << "model_error_m" << YAML::Value << shortest_number_text(*c.model_error_m);
    if (c.model_error_rad)
      out << YAML::Key << "model_error_rad" << YAML::Value << shortest_number_text(*c.model_error_rad);
    out << YAML::EndMap;
  }
  out << YAML::EndMap;
  std::string text =
      "# kincal robot model: SI units (m; angles as 'angles' says). Frames: base = frame 0 in the\n"
      "# measuring device's frame; tool in the flange frame. calibration: changes and stddevs in SI "
      "(m, rad).\n";
  text += out.c_str();
  text += "\n";
  return text;
}

void save_model(const RobotModel& model, const std::string& path) {
  try {
    files::write_file_atomically(path, write_model(model));
  } catch (const files::OutputError& e) {
    throw InputError(e.what());
  }
}

}  // namespace kincal::model
