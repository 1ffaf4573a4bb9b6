// Offline identification of a robot's kinematic parameters from measurements (issue #7):
// what `kincal identify` runs.
//
// Methods (IdentifyOptions::method):
//   full          nonlinear weighted least squares (Ceres Solver, Levenberg-Marquardt, dense QR)
//                 over every identifiable parameter of base, links and tool, started from the
//                 nominal model or from cpa; residuals whitened by each measurement's covariance;
//                 Huber loss at the 99.9 % chi-square radius; measurements beyond the (1 - p)
//                 chi-square quantile (p = outlier_probability) rejected and the fit repeated;
//                 unknown noise levels estimated from the residuals (robustly first, by the
//                 median, then by the residual sum of squares over the degrees of freedom).
//   first-order   Doty's linear error model (his 3-12, eps = E psi) for N joints: one weighted
//                 least-squares step of the same Jacobian at the nominal model, no iteration.
//   cpa           circle-point analysis (cpa.hpp): single-joint sweeps -> axes -> DH/Doty table.
//
// Every method reports: the identifiable parameters and those held fixed with the reason
// (identifiability.hpp: rank of the whitened Jacobian at the start), each identified
// parameter's change and 1-sigma standard deviation (from the inverse Fisher information,
// (J^T J)^-1 of the whitened Jacobian at the solution), residual statistics and the rejected
// measurements.
//
// Reparameterization before solving: standard-DH links whose consecutive axes are within
// parallel_tolerance_rad of parallel become Doty links (beta = 0: the same transform exactly),
// and a chain of modified-DH links with such a pair is rewritten as DH/Doty from its axes
// (model/axes.hpp), checked to give the same tool poses within 1e-9 m. Without this the DH
// common normal of a nearly parallel pair runs away (d of metres for a tilt of milliradians).
//
// Errors (InputError, message says what and where): joint count of data and model differ; no
// measurements; a joint never moved in the data; fewer equations than identifiable parameters;
// a requested parameter the data cannot identify (with the parameters it is not separable
// from); an unknown parameter name; cpa without single-joint sweeps.
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "host/identify/identifiability.hpp"
#include "host/identify/problem.hpp"
#include "host/model/dataset.hpp"
#include "host/model/robot_model.hpp"

namespace kincal::identify {

enum class Method { cpa, first_order, full };
enum class Start { nominal, cpa };

struct IdentifyOptions {
  Method method = Method::full;
  Start start = Start::nominal;
  std::vector<std::string> fixed;      // parameter names, or "base" / "tool" for all six
  std::vector<std::string> requested;  // non-empty: identify exactly these (error if not identifiable)
  double sigma_m = 0.0;                // position sigma for rows without covariance; 0: estimate
  double orientation_sigma_rad = 0.0;  // 0: estimate (pose data with a tool frame)
  bool robust = true;
  double outlier_probability = 1e-4;
  int max_iterations = 100;
  double parallel_tolerance_rad = 0.1;
};

// Position (and orientation) errors of a model against measurements.
struct AccuracyStats {
  int count = 0;
  double mean_m = 0.0, rms_m = 0.0, max_m = 0.0;
  bool has_orientation = false;
  double mean_rad = 0.0, rms_rad = 0.0, max_rad = 0.0;
};

AccuracyStats accuracy(const RobotModel& model, const model::Dataset& data, const std::vector<int>& rows = {});

struct SweepReport;  // cpa.hpp

struct IdentifyResult {
  RobotModel model;  // identified, with its calibration record
  RobotModel start;  // the starting model after reparameterization
  Identifiability identifiability;
  Eigen::VectorXd change;  // of identifiability.identified, SI
  Eigen::VectorXd stddev;
  AccuracyStats residuals;         // over the measurements used
  std::vector<int> outlier_lines;  // source lines of rejected measurements
  double chi_square_per_dof = 0.0;
  double sigma_m = 0.0;  // used for rows without covariance
  bool sigma_estimated = false;
  bool all_covariance = false;  // every measurement carried its covariance
  bool orientation_estimated = false;
  double orientation_sigma_rad = 0.0;
  bool orientation_used = false;
  int iterations = 0;
  std::string termination;
  std::vector<std::string> notes;
  std::vector<std::string> cpa_sweeps;  // one line per sweep when cpa ran
};

// Throws model::InputError for bad input (see above).
IdentifyResult identify(const RobotModel& nominal, const model::Dataset& data, const IdentifyOptions& options);

// The standard-DH -> Doty promotion and modified-DH rewrite described above (exported for tests).
RobotModel reparameterize_for_identification(const RobotModel& model, double parallel_tolerance_rad,
                                             std::vector<std::string>* notes);

// Every parameter of the model in the order identification prefers to keep them: the base's six
// motions, the tool's, then link by link (theta, d, a, alpha, beta). Where parameters cannot be
// told apart, the later ones are held fixed -- so theta1 and d1 give way to the base, and the last
// link's parameters to the tool.
ParameterIds candidate_parameters(const RobotModel& model);

// A human-readable report of a result (what `kincal identify` prints).
std::string format_report(const IdentifyResult& result);

}  // namespace kincal::identify
