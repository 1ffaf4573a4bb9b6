// How well the calibrated model knows where a corrected target puts the tool (issue #24): the
// parameters' covariance propagated to the tool pose at the corrected readings,
//   C_pose = E C_par E^T,   E = parameter_jacobian(model, q, ids)   (6 x parameters, twists)
// reported as the RMS length of the position error, sqrt(trace of its 3 x 3 block), and the same
// for the rotation vector. What it leaves out: the model error no parameter explains (identify's
// s_p, s_o; about 0.45 mm on a real UR10) and the controller's repeatability.
//
// Where the covariance comes from: a model file carries each identified parameter's 1-sigma
// standard deviation (calibration: parameters: stddev), not their correlations, so
// record_covariance() gives the diagonal covariance. A calibration's parameters are correlated,
// so this is a rough scale, not the spread (on the UR10 tracker example it says 0.4-0.5 mm);
// identify::IdentifyResult::covariance has the whole matrix, and library callers that hold one
// pass it. Base parameters move the device frame, not
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
  Eigen::MatrixXd covariance;  // SI, ids.size() square
};

// The diagonal covariance of the model's calibration record; nullopt without a record or when
// no parameter has a standard deviation above 0. Throws model::InputError for a parameter name
// the model does not have.
std::optional<ParameterCovariance> record_covariance(const model::RobotModel& calibrated);

struct PoseSpread {
  double position_m = 0.0;
  double orientation_rad = 0.0;
};

PoseSpread predicted_spread(const model::RobotModel& model, const ParameterCovariance& covariance,
                            std::span<const double> q, bool with_base);

}  // namespace kincal::correct
