#include "host/correct/joint_correction.hpp"

#include <numbers>

#include <Eigen/Geometry>

namespace kincal::correct {

namespace {

model::RobotModel without_base(model::RobotModel m) {
  m.base_T_frame0 = model::Transform{};
  return m;
}

}  // namespace

JointCorrector::JointCorrector(const model::RobotModel& controller, const model::RobotModel& calibrated,
                               const JointCorrectionOptions& options)
    : controller_(without_base(controller)), calibrated_(without_base(calibrated)), options_(options) {
  if (controller.joint_count() != calibrated.joint_count())
    throw model::InputError("the nominal model has " + std::to_string(controller.joint_count()) +
                            " joints, the calibrated one " + std::to_string(calibrated.joint_count()));
  tool_turn_rad_ = Eigen::AngleAxisd(Eigen::Matrix3d(controller.flange_T_tool.rotation.transpose() *
                                                     calibrated.flange_T_tool.rotation))
                       .angle();
  if (!options.platform_step) {
    note_ = "the platform's step is switched off";
    return;
  }
  try {
    platform_ = std::make_unique<PlatformStep>(controller_, calibrated_);
  } catch (const model::InputError& e) {
    note_ = e.what();
  }
}

JointCorrector::~JointCorrector() = default;

bool JointCorrector::platform_step() const { return platform_ != nullptr; }
const std::string& JointCorrector::platform_note() const { return note_; }
const model::RobotModel& JointCorrector::calibrated_arm() const { return calibrated_; }

JointCorrection JointCorrector::correct(std::span<const double> readings) {
  const int n = controller_.joint_count();
  if (static_cast<int>(readings.size()) != n)
    throw std::invalid_argument("JointCorrector::correct: " + std::to_string(readings.size()) +
                                " readings for a model of " + std::to_string(n) + " joints");
  if (options_.orientation && tool_turn_rad_ > 0.05)
    throw model::InputError("the calibrated tool frame is turned " +
                            std::to_string(tool_turn_rad_ * 180 / std::numbers::pi) +
                            " deg from the nominal's: correcting the orientation would turn the wrist to follow it "
                            "(usually the measuring device's convention for the tool frame, not an error of the "
                            "arm); correct the tool point alone (--position-only), or give a --nominal with the "
                            "calibrated tool");
  JointCorrection out;
  out.goal = model::forward_kinematics(controller_, readings);
  std::vector<double> start(readings.begin(), readings.end());
  if (platform_) {
    if (std::optional<std::vector<double>> corrected = platform_->correct(readings)) {
      out.platform_step_used = true;
      start = std::move(*corrected);
      Eigen::Matrix<double, 6, 1> e = pose_residual(out.goal, model::forward_kinematics(calibrated_, start));
      if (!options_.orientation) e.tail<3>().setZero();
      if (e.head<3>().norm() <= options_.accept_m && e.tail<3>().norm() <= options_.accept_rad) {
        out.solution.q = std::move(start);
        out.solution.outcome = Outcome::reached;
        out.solution.residual_m = e.head<3>().norm();
        out.solution.residual_rad = e.tail<3>().norm();
        return out;
      }
    }
  }
  out.refined = true;
  out.solution = solve_pose(calibrated_, out.goal, options_.orientation, start, options_.solve, readings);
  return out;
}

model::RobotModel nominal_from_record(const model::RobotModel& calibrated) {
  if (!calibrated.calibration)
    throw model::InputError("the model '" + calibrated.name +
                            "' has no calibration record to take the nominal from (give --nominal)");
  const int n = calibrated.joint_count();
  std::vector<core::ParameterId> ids;
  std::vector<double> undo;
  Eigen::Matrix<double, 6, 1> base = Eigen::Matrix<double, 6, 1>::Zero(), tool = base;
  for (const model::ParameterReport& p : calibrated.calibration->parameters) {
    const core::ParameterId id = model::parse_parameter_name(p.name, n);
    if (!model::is_motion_parameter(id.kind)) {
      ids.push_back(id);
      undo.push_back(-p.value);
      continue;
    }
    const int k = static_cast<int>(id.kind) - static_cast<int>(core::ParameterKind::base_x);
    (k < 6 ? base : tool)(k % 6) = p.value;
  }
  model::RobotModel nominal = model::apply_parameter_errors(
      calibrated, ids, Eigen::Map<const Eigen::VectorXd>(undo.data(), static_cast<Eigen::Index>(undo.size())));
  // The base and tool errors compose as frame * [exp(r), t]: undone by the inverse motion.
  const auto inverse_motion = [](const Eigen::Matrix<double, 6, 1>& t) {
    model::Transform m;
    const double angle = t.tail<3>().norm();
    if (angle > 0.0) m.rotation = Eigen::AngleAxisd(angle, t.tail<3>() / angle).toRotationMatrix();
    m.translation = t.head<3>();
    return m.inverse();
  };
  nominal.base_T_frame0 = calibrated.base_T_frame0 * inverse_motion(base);
  nominal.flange_T_tool = calibrated.flange_T_tool * inverse_motion(tool);
  nominal.calibration.reset();
  return nominal;
}

}  // namespace kincal::correct
