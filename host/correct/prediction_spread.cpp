#include "host/correct/prediction_spread.hpp"

#include <cmath>

#include <Eigen/Eigenvalues>

namespace kincal::correct {

namespace {

// The record's correlation matrix (unit diagonal, in the order of its parameters), checked: rows
// one per parameter after the first, every name the model's own (the file's reader takes each
// once, so n is bounded by the model's parameters before the n x n matrix is built), positive
// semi-definite.
Eigen::MatrixXd recorded_correlation(const model::RobotModel& calibrated) {
  const model::CalibrationRecord& record = *calibrated.calibration;
  const std::size_t n = record.parameters.size();
  bool shaped = record.correlations.size() + 1 == n;
  for (std::size_t k = 0; shaped && k < record.correlations.size(); ++k)
    shaped = record.correlations[k].size() == k + 1;
  if (!shaped) throw model::InputError("calibration: correlations are not one row per parameter after the first");
  for (const model::ParameterReport& p : record.parameters)
    (void)model::parse_parameter_name(p.name, calibrated.joint_count());
  Eigen::MatrixXd correlation = Eigen::MatrixXd::Identity(static_cast<Eigen::Index>(n), static_cast<Eigen::Index>(n));
  for (std::size_t k = 0; k + 1 < n; ++k)
    for (std::size_t l = 0; l <= k; ++l) {
      const auto i = static_cast<Eigen::Index>(k + 1), j = static_cast<Eigen::Index>(l);
      correlation(i, j) = correlation(j, i) = record.correlations[k][l];
    }
  if (Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(correlation).eigenvalues().minCoeff() < -1e-9)
    throw model::InputError("calibration: correlations are not those of a covariance (not positive semi-definite)");
  return correlation;
}

}  // namespace

std::optional<ParameterCovariance> record_covariance(const model::RobotModel& calibrated) {
  if (!calibrated.calibration) return std::nullopt;
  const model::CalibrationRecord& record = *calibrated.calibration;
  const bool correlated = !record.correlations.empty();
  const Eigen::MatrixXd correlation = correlated ? recorded_correlation(calibrated) : Eigen::MatrixXd();
  ParameterCovariance out;
  std::vector<Eigen::Index> kept;
  std::vector<double> sd;
  for (std::size_t k = 0; k < record.parameters.size(); ++k) {
    const model::ParameterReport& p = record.parameters[k];
    if (!(p.stddev > 0.0)) continue;
    out.ids.push_back(model::parse_parameter_name(p.name, calibrated.joint_count()));
    kept.push_back(static_cast<Eigen::Index>(k));
    sd.push_back(p.stddev);
  }
  out.model_error_m = record.model_error_m.value_or(0.0);
  out.model_error_rad = record.model_error_rad.value_or(0.0);
  if (out.ids.empty() && out.model_error_m == 0.0 && out.model_error_rad == 0.0) return std::nullopt;
  const auto m = static_cast<Eigen::Index>(sd.size());
  const Eigen::VectorXd s = Eigen::Map<const Eigen::VectorXd>(sd.data(), m);
  // Without recorded correlations, the diagonal (see the header).
  const Eigen::MatrixXd r = correlated ? Eigen::MatrixXd(correlation(kept, kept)) : Eigen::MatrixXd::Identity(m, m);
  out.covariance = s.asDiagonal() * r * s.asDiagonal();
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
  Eigen::Matrix<double, 6, 6> pose = Eigen::Matrix<double, 6, 6>::Zero();
  if (!ids.empty()) {
    const Eigen::MatrixXd e = model::parameter_jacobian(model, q, ids);
    pose = e * covariance.covariance(columns, columns) * e.transpose();
  }
  const double p2 = covariance.model_error_m * covariance.model_error_m;
  const double o2 = covariance.model_error_rad * covariance.model_error_rad;
  PoseSpread out;
  out.position_m = std::sqrt(std::max(0.0, pose.topLeftCorner<3, 3>().trace()) + 3.0 * p2);
  out.orientation_rad = std::sqrt(std::max(0.0, pose.bottomRightCorner<3, 3>().trace()) + 3.0 * o2);
  return out;
}

}  // namespace kincal::correct
