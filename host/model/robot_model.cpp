#include "host/model/robot_model.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

namespace kincal::model {

namespace {

double& variable_parameter(core::LinkParameters<double>& p, core::JointType type) {
  return type == core::JointType::revolute ? p.theta_rad : p.d_m;
}
double variable_parameter(const core::LinkParameters<double>& p, core::JointType type) {
  return type == core::JointType::revolute ? p.theta_rad : p.d_m;
}

core::ParameterSet to_set(std::span<const core::ParameterId> ids) {
  if (ids.size() > static_cast<std::size_t>(core::kMaxErrorParameters))
    throw std::invalid_argument("more parameters than core::kMaxErrorParameters");
  core::ParameterSet set;
  set.count = static_cast<int>(ids.size());
  std::copy(ids.begin(), ids.end(), set.ids.begin());
  return set;
}

struct KindName {
  core::ParameterKind kind;
  const char* name;
};
constexpr KindName kLinkNames[] = {{core::ParameterKind::link_theta, "theta"},
                                   {core::ParameterKind::link_alpha, "alpha"},
                                   {core::ParameterKind::link_beta, "beta"},
                                   {core::ParameterKind::link_d, "d"},
                                   {core::ParameterKind::link_a, "a"}};
constexpr const char* kMotionNames[] = {"base_x", "base_y", "base_z", "base_rx", "base_ry", "base_rz",
                                        "tool_x", "tool_y", "tool_z", "tool_rx", "tool_ry", "tool_rz"};

}  // namespace

core::ChainModel<double> to_chain(const RobotModel& model) {
  core::ChainModel<double> chain;
  chain.joint_count = model.joint_count();
  for (std::size_t i = 0; i < model.joints.size() && i < static_cast<std::size_t>(core::kMaxJoints); ++i) {
    const Joint& j = model.joints[i];
    core::Link<double>& link = chain.links[i];
    link.convention = j.convention;
    link.joint = j.type;
    link.parameters = j.parameters;
    variable_parameter(link.parameters, j.type) += j.offset;
  }
  chain.base_T_frame0 = model.base_T_frame0;
  chain.flange_T_tool = model.flange_T_tool;
  return chain;
}

RobotModel from_chain(const RobotModel& like, const core::ChainModel<double>& chain) {
  RobotModel out = like;
  for (std::size_t i = 0; i < out.joints.size(); ++i) {
    Joint& j = out.joints[i];
    const core::Link<double>& link = chain.links[i];
    const double nominal = variable_parameter(j.parameters, j.type);
    j.convention = link.convention;
    j.parameters = link.parameters;
    variable_parameter(j.parameters, j.type) = nominal;
    j.offset = variable_parameter(link.parameters, j.type) - nominal;
  }
  out.base_T_frame0 = chain.base_T_frame0;
  out.flange_T_tool = chain.flange_T_tool;
  return out;
}

core::JointVector<double> joint_vector(std::span<const double> q) {
  core::JointVector<double> v = core::JointVector<double>::Zero();
  for (std::size_t i = 0; i < q.size() && i < static_cast<std::size_t>(core::kMaxJoints); ++i)
    v(static_cast<Eigen::Index>(i)) = q[i];
  return v;
}

Transform forward_kinematics(const RobotModel& model, std::span<const double> q) {
  return core::forward_kinematics(to_chain(model), joint_vector(q));
}

ChainAtJoints chain_at_joints(const RobotModel& model, std::span<const double> q) {
  ChainAtJoints at;
  core::prepare_chain(to_chain(model), at.chain);
  at.q = joint_vector(q);
  core::joint_trig(at.chain, at.q, at.trig);
  core::forward_kinematics(at.chain, at.q, at.trig, at.frames);
  return at;
}

Eigen::MatrixXd joint_jacobian(const RobotModel& model, std::span<const double> q) {
  const ChainAtJoints at = chain_at_joints(model, q);
  core::JointJacobian<double> j;
  core::joint_jacobian(at.chain, at.frames, j);
  return j.leftCols(model.joint_count());
}

std::string parameter_name(core::ParameterId id) {
  const int kind = static_cast<int>(id.kind);
  if (kind >= static_cast<int>(core::ParameterKind::base_x))
    return kMotionNames[kind - static_cast<int>(core::ParameterKind::base_x)];
  for (const KindName& k : kLinkNames)
    if (k.kind == id.kind) return std::string(k.name) + std::to_string(id.link + 1);
  return "?";
}

core::ParameterId parse_parameter_name(const std::string& name, int joint_count) {
  for (int k = 0; k < 12; ++k)
    if (name == kMotionNames[k])
      return {static_cast<core::ParameterKind>(static_cast<int>(core::ParameterKind::base_x) + k), 0};
  for (const KindName& k : kLinkNames) {
    const std::string prefix = k.name;
    if (name.size() <= prefix.size() || name.compare(0, prefix.size(), prefix) != 0) continue;
    int joint = 0;
    const char* first = name.data() + prefix.size();
    const char* last = name.data() + name.size();
    const auto [end, ec] = std::from_chars(first, last, joint);
    if (ec != std::errc() || end != last) continue;
    if (joint < 1 || joint > joint_count)
      throw InputError("parameter '" + name + "': joint " + std::to_string(joint) + " does not exist (the model has " +
                       std::to_string(joint_count) + " joints)");
    return {k.kind, static_cast<std::uint8_t>(joint - 1)};
  }
  throw InputError("unknown parameter name '" + name +
                   "' (expected d<i>, theta<i>, a<i>, alpha<i>, beta<i>, base_x..base_rz or tool_x..tool_rz)");
}

std::vector<core::ParameterId> all_parameters(const RobotModel& model) {
  std::vector<core::ParameterId> ids;
  for (int i = 0; i < model.joint_count(); ++i) {
    const auto link = static_cast<std::uint8_t>(i);
    ids.push_back({core::ParameterKind::link_theta, link});
    ids.push_back({core::ParameterKind::link_d, link});
    ids.push_back({core::ParameterKind::link_a, link});
    ids.push_back({core::ParameterKind::link_alpha, link});
    if (model.joints[static_cast<std::size_t>(i)].convention == core::LinkConvention::doty)
      ids.push_back({core::ParameterKind::link_beta, link});
  }
  const int tool_count = model.tool == ToolKind::point ? 3 : 6;
  for (int k = 0; k < 6; ++k)
    ids.push_back({static_cast<core::ParameterKind>(static_cast<int>(core::ParameterKind::base_x) + k), 0});
  for (int k = 0; k < tool_count; ++k)
    ids.push_back({static_cast<core::ParameterKind>(static_cast<int>(core::ParameterKind::tool_x) + k), 0});
  return ids;
}

Eigen::MatrixXd parameter_jacobian(const RobotModel& model, std::span<const double> q,
                                   std::span<const core::ParameterId> ids) {
  const core::ParameterSet set = to_set(ids);
  const ChainAtJoints at = chain_at_joints(model, q);
  core::ErrorMatrix<double> e = core::ErrorMatrix<double>::Zero();
  if (core::parameter_jacobian(at.chain, at.q, at.trig, at.frames, set, e) != core::ErrorModelStatus::ok)
    throw std::invalid_argument("parameter_jacobian: a parameter names a joint the model does not have");
  return e.leftCols(set.count);
}

RobotModel apply_parameter_errors(const RobotModel& model, std::span<const core::ParameterId> ids,
                                  const Eigen::VectorXd& errors) {
  const core::ParameterSet set = to_set(ids);
  core::ErrorVector<double> e = core::ErrorVector<double>::Zero();
  e.head(set.count) = errors.head(set.count);
  core::ChainModel<double> actual;
  if (core::apply_parameter_errors(to_chain(model), set, e, actual) != core::ErrorModelStatus::ok)
    throw std::invalid_argument("apply_parameter_errors: a parameter names a joint the model does not have");
  return from_chain(model, actual);
}

Matrix3 rotation_from_rpy(const Vector3& rpy) {
  return (Eigen::AngleAxisd(rpy.z(), Vector3::UnitZ()) * Eigen::AngleAxisd(rpy.y(), Vector3::UnitY()) *
          Eigen::AngleAxisd(rpy.x(), Vector3::UnitX()))
      .toRotationMatrix();
}

Vector3 rpy_from_rotation(const Matrix3& r) {
  // R = Rz(y) Ry(p) Rx(r): r20 = -sin p, r21 = cos p sin r, r22 = cos p cos r, r10 = sin y cos p.
  const double pitch = std::atan2(-r(2, 0), std::hypot(r(0, 0), r(1, 0)));
  if (std::hypot(r(0, 0), r(1, 0)) < 1e-12) {  // gimbal lock: put everything into yaw
    const double yaw = std::atan2(-r(0, 1), r(1, 1));
    return {0.0, pitch, yaw};
  }
  return {std::atan2(r(2, 1), r(2, 2)), pitch, std::atan2(r(1, 0), r(0, 0))};
}

}  // namespace kincal::model
