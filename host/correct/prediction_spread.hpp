// How well the calibrated model knows where a corrected target puts the tool (issue #24): the
// parameters' covariance propagated to the tool pose at the corrected readings, plus the model
// error no parameter explains (identify's s_p, s_o per axis),
//   C_pose = E C_par E^T + diag(s_p^2 I, s_o^2 I),   E = parameter_jacobian(model, q, ids)
// reported as the RMS length of the position error, sqrt(trace of its 3 x 3 block), and the same
// for the rotation vector. What it leaves out: the controller's repeatability.
//
// Where the covariance comes from: a model file carries each identified parameter's 1-sigma
// standard deviation and their correlations (calibration: parameters, correlations), and the model
// error where identify could tell it from the instrument's noise (model_error_m, model_error_rad);
// record_covariance() builds the whole covariance from them. A record without correlations (written
// before they were) gives the diagonal one: a rough scale, not the spread -- a calibration's
// parameters are correlated, and on the zoo's torso_lift_6r/camera-board/service/40 the diagonal
// said 0.7 mm where the model predicts to 0.06. Base parameters move the device frame, not
// the arm: with_base = false leaves them out (targets in the robot's base frame, joint targets).
#pragma once

#include <optional>
#include <span>
#include <vector>

#include <Eigen/Core>

#include "host/model/robot_model.hpp"

namespace kincal::correct {

struct ParameterCovariance {
  std::vector<core::ParameterId> ids;
  Eigen::MatrixXd covariance;    // SI, ids.size() square
  double model_error_m = 0.0;    // s_p, per axis
  double model_error_rad = 0.0;  // s_o, per axis of the rotation vector
};

// The covariance of the model's calibration record (see the top); nullopt without a record or
// when no parameter has a standard deviation above 0 and no model error is recorded. Throws
// model::InputError for a parameter name the model does not have, or correlations that are not
// one row per parameter after the first or not a covariance's (not positive semi-definite).
std::optional<ParameterCovariance> record_covariance(const model::RobotModel& calibrated);

struct PoseSpread {
  double position_m = 0.0;
  double orientation_rad = 0.0;
};

PoseSpread predicted_spread(const model::RobotModel& model, const ParameterCovariance& covariance,
                            std::span<const double> q, bool with_base);

}  // namespace kincal::correct
