#include "host/correct/prediction_spread.hpp"

#include <cmath>

namespace kincal::correct {

std::optional<ParameterCovariance> record_covariance(const model::RobotModel& calibrated) {
  if (!calibrated.calibration) return std::nullopt;
  ParameterCovariance out;
  std::vector<double> variance;
  for (const model::ParameterReport& p : calibrated.calibration->parameters) {
    if (!(p.stddev > 0.0)) continue;
    out.ids.push_back(model::parse_parameter_name(p.name, calibrated.joint_count()));
    variance.push_back(p.stddev * p.stddev);
  }
  if (out.ids.empty()) return std::nullopt;
  out.covariance =
      Eigen::Map<const Eigen::VectorXd>(variance.data(), static_cast<Eigen::Index>(variance.size())).asDiagonal();
  return out;
}

PoseSpread predicted_spread(const model::RobotModel& model, const ParameterCovariance& covariance,
                            std::span<const double> q, bool with_base) {
  std::vector<core::ParameterId> ids;
  std::vector<Eigen::Index> columns;
  for (std::size_t k = 0; k < covariance.ids.size(); ++k) {
    const int kind = static_cast<int>(covariance.ids[k].kind), base_x = static_cast<int>(core::ParameterKind::base_x);
    if (!with_base && kind >= base_x && kind < base_x + 6) continue;
    ids.push_back(covariance.ids[k]);
    columns.push_back(static_cast<Eigen::Index>(k));
  }
  PoseSpread out;
  if (ids.empty()) return out;
  const Eigen::MatrixXd e = model::parameter_jacobian(model, q, ids);
  const Eigen::MatrixXd c = covariance.covariance(columns, columns);
  const Eigen::Matrix<double, 6, 6> pose = e * c * e.transpose();
  out.position_m = std::sqrt(std::max(0.0, pose.topLeftCorner<3, 3>().trace()));
  out.orientation_rad = std::sqrt(std::max(0.0, pose.bottomRightCorner<3, 3>().trace()));
  return out;
}

}  // namespace kincal::correct
