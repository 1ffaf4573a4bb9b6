// The identification problem every method shares: a starting model, a vector of parameter
// changes delta over named parameters, the measurements, their weights, and the whitened
// residuals with their exact Jacobian.
//
// Parameterization: model(delta) = model::apply_parameter_errors(start, ids, delta): link
// parameters add; the base and tool motions compose as base_T_frame0 * [exp(r_b), t_b] and
// flange_T_tool * [exp(r_t), t_t]. The core's error model gives the twist of the tool pose for a
// small motion of the *current* frames; jacobian() turns it into d/d(delta) exactly (translation
// columns through exp(r)^T, rotation columns through the right Jacobian of SO(3)), so the
// Jacobian is exact at any delta, not only at zero (tests/host/identify check it against
// central differences).
//
// Joint-map parameters (scale<i>, compliance<i>, coupling<i>_<i-1>; model/robot_model.hpp) add to the model's
// fields; a model with a joint map is evaluated through model::evaluate_chain and its columns
// come from model::parameter_jacobian (exact but for the gravity deflection's dependence on
// the geometry, taken by central differences, about 1e-12 of a column). A model without one takes
// the plain chain's path, unchanged.
//
// Residuals of one measurement (whitened, so each is N(0, 1) for a correct model): L e with
//   e = [p_measured - p_model; log(R_measured R_model^T)]   (the orientation rows when used)
// and L^T L = V^-1, V the row's covariance over e: the position's (3 x 3), or the full pose's
// (6 x 6: position and rotation error, the rotation error a rotation vector on the left,
// R_measured = exp([d]x) R_true, in the device frame as the dataset states it; the orientation
// residual is that d). A row's V need not be block-diagonal: a board pose seen from a camera
// 0.6 m away has its position error tied to its rotation error by the lever arm.
#pragma once

#include <span>
#include <vector>

#include <Eigen/Core>

#include "host/model/dataset.hpp"
#include "host/model/robot_model.hpp"

namespace kincal::identify {

using model::RobotModel;
using model::Transform;
using ParameterIds = std::vector<core::ParameterId>;

class Parameterization {
 public:
  Parameterization(const RobotModel& start, ParameterIds ids);

  const RobotModel& start() const { return start_; }
  const ParameterIds& ids() const { return ids_; }
  int size() const { return static_cast<int>(ids_.size()); }

  // Moves the evaluation point (cheap if delta is unchanged).
  void set(std::span<const double> delta);
  RobotModel model() const;  // at the current delta

  // The tool pose at readings q, and optionally d(pose twist)/d(delta): 6 x size().
  Transform pose(std::span<const double> q, Eigen::MatrixXd* jacobian) const;

 private:
  // The columns of ids_ from those of the augmented set, motion columns made d/d(delta).
  template <class Columns>
  void motion_corrected(const Columns& e, Eigen::MatrixXd& jacobian) const;

  RobotModel start_;
  core::ChainModel<double> start_chain_;
  ParameterIds ids_;
  core::ParameterSet augmented_;  // the links of ids_, then all 12 base/tool motions
  ParameterIds joint_map_ids_;    // the augmented set's tail: the joint-map parameters of ids_
  std::vector<int> link_column_;  // ids_[k] -> column of the augmented set (links, joint map), -1 for motions
  bool plain_ = true;             // no joint map: the core's chain alone
  RobotModel current_;            // start_ with the joint-map deltas (its fields, not its geometry)
  core::ChainModel<double> current_chain_;
  std::vector<double> delta_;
  core::PreparedChain<double> prepared_;
  Eigen::Matrix3d base_exp_t_, base_jr_, tool_exp_t_, tool_jr_;
  bool ready_ = false;
};

// Right Jacobian of SO(3) and its inverse: exp(r + d) = exp(r) exp(Jr(r) d) to first order.
Eigen::Matrix3d so3_right_jacobian(const Eigen::Vector3d& r);
Eigen::Matrix3d so3_right_jacobian_inverse(const Eigen::Vector3d& r);
// The rotation vector of R (angle <= pi).
Eigen::Vector3d so3_log(const Eigen::Matrix3d& r);
// The small motion (t, r) of frame b from frame a, as the base and tool parameters compose:
// b = a * [exp(r), t], so t is in a's axes.
Eigen::Matrix<double, 6, 1> small_motion(const Transform& a, const Transform& b);

// The physical bounds of the parameters (issue #41: every file identify writes is one every
// command accepts): the lowest and highest change of each of p's parameters, -/+infinity for none.
// A joint's compliance must not be negative (model files refuse it: a joint yields with its
// load), so a compliance<i> change is at least minus the start's value; likewise an identified
// mass<i> (model/robot_model.hpp's identify_mass) never goes negative, and an identified centre of
// mass stays within the arm's size (the sum of its links' lengths at zero and the tool's offset
// from the last frame): a link whose mass goes to 0 with its first moment kept would otherwise
// carry its centre off to kilometres. Each joint-map parameter also keeps to the model file's own
// range (model_file.hpp: a compliance at most kMaxCompliance, a mass kMaxMass_kg, a scale within
// [kMinScale, kMaxScale], a coupling within kMaxCoupling): a Kinova Gen3's first joint, its axis
// 7 urad off vertical in its URDF, took a compliance of 1.86 rad/(N m) that predict then refused.
// The solve keeps to them (Ceres bounds; the first-order step is clamped to them).
// `negative_masses`: an identified mass may go below 0, down to -kMaxMass_kg -- the sag's first
// solve of its masses, where only their sums along a run of revolute joints reach the loads and a
// mass the data cannot tell from its neighbours' is held at the start's (sag.hpp's spread).
struct PhysicalBounds {
  Eigen::VectorXd lower, upper;
};
PhysicalBounds physical_bounds(const Parameterization& p, bool negative_masses);
// Of each change in `delta`: on its lower or upper bound (to a part in 1e9 of the bound; the
// solve clamps to them exactly).
std::vector<bool> on_bound(const PhysicalBounds& b, std::span<const double> delta);

using Matrix6 = model::Matrix6;

// The whitening of every row: residuals per row (3: position; 6: position and orientation) and
// per measurement L, whose top-left size x size block is the inverse of the Cholesky factor of
// the row's covariance (lower triangular; L^T L = V^-1). Rows of a dataset share the size.
struct Weights {
  int size = 3;
  std::vector<Matrix6> factor;
};

// The instrument's covariance of every row over (x, y, z, rx, ry, rz) (model/dataset.hpp): the
// row's pose covariance where it has one; else its position covariance (or sigma_m^2 I) and
// orientation_sigma_rad^2 I, uncorrelated. A row's own covariance wins over the given sigmas.
std::vector<Matrix6> instrument_covariances(const model::Dataset& data, double sigma_m, double orientation_sigma_rad);

// Weights whitening covariances' top-left size x size blocks, each first increased by
// diag(position2 I, orientation2 I) (the model-error components identify estimates).
// Throws std::invalid_argument when one is not positive definite.
Weights covariance_weights(const std::vector<Matrix6>& covariance, int size, double position2 = 0.0,
                           double orientation2 = 0.0);

// Identity weights (unwhitened residuals: metres and radians) for `rows` measurements.
Weights unit_weights(std::size_t rows, int size);

// Weights of the instrument alone: orientation rows when the data has orientations and
// orientation_sigma_rad > 0 (rows with a pose covariance are weighted by it).
Weights make_weights(const model::Dataset& data, double sigma_m, double orientation_sigma_rad);

// Whitened residual of row i at the current point, and optionally its Jacobian (size x P).
void row_residual(const Parameterization& p, const model::Measurement& m, const Matrix6& factor, int size,
                  double* residual, Eigen::MatrixXd* jacobian);

// All rows stacked: residual (rows * size) and Jacobian (rows * size x P).
void stacked(const Parameterization& p, const model::Dataset& data, const Weights& w, const std::vector<int>& rows,
             Eigen::VectorXd& residual, Eigen::MatrixXd* jacobian);

}  // namespace kincal::identify
