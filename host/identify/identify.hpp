// Offline identification of a robot's kinematic parameters from measurements (issue #7):
// what `kincal identify` runs.
//
// Methods (IdentifyOptions::method):
//   full          nonlinear weighted least squares (Ceres Solver, Levenberg-Marquardt, dense QR)
//                 over every identifiable parameter of base, links and tool, started from the
//                 nominal model or from cpa, with the noise model and outlier handling below.
//   first-order   Doty's linear error model (his 3-12, eps = E psi) for N joints: one weighted
//                 least-squares step of the same Jacobian at the nominal model, no iteration.
//   cpa           circle-point analysis (cpa.hpp): single-joint sweeps -> axes -> DH/Doty table.
//
// Noise model (full and first-order): the error of row i is N(0, V_i) with
//   position     V_i = C_i + s_p^2 I   C_i the row's covariance (or --sigma^2 I, or 0)
//   orientation  V_i = (s_given^2 + s_o^2) I   (rotation vector)
// or, for a row with the full pose covariance C_i (6 x 6, model/dataset.hpp: a board pose, whose
// position error is tied to its rotation error by the lever arm), V_i = C_i + diag(s_p^2 I, s_o^2 I)
// over [position; rotation], whitened by its Cholesky factor (problem.hpp).
// s_p and s_o are the model error: what the robot does that the model cannot (repeatability,
// elasticity, gears). A laser tracker measures to 0.01 mm while a real arm leaves about 0.4 mm
// unexplained, so the instrument's covariance alone would call every row an outlier. s_p, s_o
// are estimated by REML: solve with the current V, linearize, and solve the REML equations
// r^T V^-1 V_k V^-1 r = tr(V_k P), P = V^-1 - V^-1 J (J^T V^-1 J)^-1 J^T V^-1 (the hat-matrix
// correction for the degrees of freedom the fit uses) by Fisher scoring, then solve again until
// s_p and s_o change by less than 0.1 %. Every standard deviation, the parameter covariance and
// the prediction covariance carry them. With model_error = false they are estimated only where
// nothing else gives the noise (rows without covariance and no --sigma; orientation without
// --orientation-sigma), as pure noise levels.
//
// Outliers (full, robust = true): each row's studentized residual t_i = r_i^T (I - H_ii)^-1 r_i
// (whitened by V, H the hat matrix: leverage-aware, chi-square with 3 or 6 degrees of freedom
// for a good row) is judged against a robust scale c = median(t) / (the chi-square median), at
// least 0.1 (a given sigma above the actual noise must not turn rounding into outliers); a
// row is rejected when t_i / c exceeds the chi-square quantile at 1 - outlier_probability / N
// (Bonferroni over the N rows). The median makes this the deleted-residual test to first order.
// Nothing is rejected with fewer than 5 equations per identified parameter (a small set, or sweeps:
// a row there cannot be told from the model error; rejecting cost held out on the simulated sagging
// sweep set). At most max_rejected_fraction of the rows are rejected, in up to eight rounds with the fit and
// V redone between them, each round only the rows within a factor 2 of the largest residual (a
// blunder pulls its neighbours' residuals until it is out); each rejection is reported with its residual, its
// statistic and how far removing it moves the predicted tool over the data (Rejection).
// The rejection gate (rejection_gate = true, issue #23): a row the test rejects may be a blunder or
// only the model's error where few rows see a direction (a sweep's end, a small set); residuals
// cannot tell them apart (the rejected rows do lower the others' leave-one-out errors, yet cost
// held out on the real UR10 set). So when rows were rejected, cross-validation decides, with
// model selection's folds (model_selection.hpp: cross_validate) trained with the rejection rule
// and without it, each held-out row's position error counted whether rejected or not. The
// rejections stand only when they lower the 5-fold position errors by at least 2 standard errors
// of the rows' paired differences (paired t <= -2: a difference within the folds' own noise is a tie,
// and a tie means no rejection) and do not raise the out-of-range fold's RMS (when there is one:
// rejection must not cost beyond the data's range either). Otherwise the result is the fit
// without rejection, and the undone rejections are reported. A blunder in a held-out fold costs
// both variants alike, so the difference is what rejecting does to the other rows: three 1 mm
// blunders in 80 rows give t = -7.2, the real UR10 rows' model error -0.8 (100 and 300 rows), a
// sagging arm's sweep ends -0.4 to +0.3 (tests, realdata_ur10_bench). Cost, only when the
// test rejected rows: the K + 1 solves of the folds without the rule, and the K + 1 with it unless
// the caller has them (model selection's, which `kincal identify` passes on); the fit without
// rejection is the one the test had before its first round (300 UR10 rows with model selection's
// folds: 0.92 s against 0.27 s without the gate, Release, loaded machine; 2.9 s when each solve
// was made here).
// When the folds cannot be identified (too few rows) the gate cannot judge: the rejections stand,
// with a note.
//
// Priors (full and first-order; prior.hpp): each identified parameter's deviation from the
// nominal has a Gaussian prior, whatever the start (from cpa, the nominal expressed in the start's
// parameters by a fit of its tool poses at the data's configurations is the prior's centre); the solve is the maximum a
// posteriori estimate and the covariance the inverse of the posterior information J^T J + diag(1 / sigma^2) (over the
// parameters not on a physical bound: at_bound). The noise
// model's REML counts the prior rows as observations of known variance (from the second noise pass on, once the
// data have chosen the priors' widths: identify.cpp says why); the outlier test judges each row against the
// data alone (the leverage of the data's own fit: a sweep's end that alone sees a direction keeps it). Exact
// dependencies (identifiability.hpp) are still held fixed: the data cannot split them, so the
// prior alone would. Each parameter's prior share of its posterior information is reported, and
// a change beyond 3 prior sigmas is flagged in the report.
// The widths of the priors' classes (link lengths, link angles, registration, measured point,
// non-geometric, link masses, mass centres) are the data's (prior_scale.hpp, issue #41): each
// noise pass, after the REML of s_p and s_o, the evidence chooses each class's scale of its
// default widths at the solution, and the next solve uses them, until the noise and the widths
// both settle; the report says what each class got and why. Parameters whose prior the user
// named keep it.
//
// Physical bounds (problem.hpp, issue #41): a compliance never goes negative (a Ceres lower
// bound; the first-order step projected), so every model identify writes loads in predict,
// correct, export and urdf.
//
// Every method reports: the identifiable parameters and those held fixed with the reason
// (identifiability.hpp: rank of the whitened Jacobian at the start), each identified
// parameter's change and 1-sigma standard deviation (from the inverse Fisher information,
// (J^T J)^-1 of the whitened Jacobian at the solution), residual statistics and the rejected
// measurements.
//
// Base registration before solving (full and first-order, unless the base is fixed or exact
// parameters are requested): when the model's tool points are more than 5 cm RMS from the data
// (the base a placeholder for the device-to-robot registration), the rigid motion that best maps
// them onto the measurements (Umeyama) is composed into the start's base, with a note.
//
// The measured point before deciding (full and first-order; measured_point.hpp): the start's
// registration and tool are fitted at its geometry first, so that what the data identify is decided
// where the data were measured (a reflector off the last axis sees that axis' tilt), and the tool's
// prior is about that estimate.
//
// Reparameterization before solving: standard-DH links whose consecutive axes are within
// parallel_tolerance_rad of parallel become Doty links (beta = 0: the same transform exactly),
// and a chain of modified-DH links with such a pair is rewritten as DH/Doty from its axes
// (model/axes.hpp), checked to give the same tool poses within 1e-9 m. Without this the DH
// common normal of a nearly parallel pair runs away (d of metres for a tilt of milliradians).
//
// Errors (InputError, message says what and where): joint count of data and model differ; no
// measurements; fewer equations than identifiable parameters;
// a requested parameter the data cannot identify (with the parameters it is not separable
// from); an unknown parameter name; cpa without single-joint sweeps.
#pragma once

#include <map>
#include <optional>
#include <span>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "host/identify/identifiability.hpp"
#include "host/identify/prior.hpp"
#include "host/identify/prior_scale.hpp"
#include "host/identify/problem.hpp"
#include "host/model/dataset.hpp"
#include "host/model/robot_model.hpp"

namespace kincal::identify {

enum class Method { cpa, first_order, full };
enum class Start { nominal, cpa };

struct IdentifyOptions {
  Method method = Method::full;
  Start start = Start::nominal;
  std::vector<std::string> fixed;  // parameter names, or "base" / "tool" for all six
  // Why a name in `fixed` is held when the user did not ask for it (a candidate model's structure,
  // a sag stage's gauge), as the printout says; a name without one is "fixed on request".
  std::map<std::string, std::string> fixed_because;
  std::vector<std::string> requested;  // non-empty: identify exactly these (error if not identifiable)
  double sigma_m = 0.0;                // instrument position sigma of rows without covariance; 0: none
  double orientation_sigma_rad = 0.0;  // instrument orientation sigma; 0: none
  bool model_error = true;             // estimate the model-error components s_p, s_o (see above)
  bool robust = true;                  // reject outliers (see above)
  double outlier_probability = 1e-3;   // family-wise, over the rows (chosen on the real UR10 set)
  double max_rejected_fraction = 0.05;
  bool rejection_gate = true;  // cross-validation decides whether rejections stand (see above)
  int max_iterations = 100;
  double parallel_tolerance_rad = 0.1;
  PriorOptions prior;                   // MAP with these priors (prior.hpp); prior.strength = 0: least squares
  bool estimate_measured_point = true;  // the measured point first (measured_point.hpp, issue #42)
  // An identified mass may go below 0 in the solve: the sag's first solve of its masses, whose
  // result sag.hpp spreads along the chain (problem.hpp's physical_bounds).
  bool negative_masses = false;
};

// Position (and orientation) errors of a model against measurements.
struct AccuracyStats {
  int count = 0;
  double mean_m = 0.0, rms_m = 0.0, max_m = 0.0;
  bool has_orientation = false;
  double mean_rad = 0.0, rms_rad = 0.0, max_rad = 0.0;
};

AccuracyStats accuracy(const RobotModel& model, const model::Dataset& data, const std::vector<int>& rows = {});

// The statistics of given error lengths: positions (m) and, when angles_rad is not empty, the
// orientations' angles (rad, has_orientation set). The one summary behind accuracy() and the
// session's correction checks.
AccuracyStats error_stats(std::span<const double> positions_m, std::span<const double> angles_rad = {});

struct SweepReport;  // cpa.hpp

// One rejected measurement and what rejecting it changes.
struct Rejection {
  int line = 0;
  std::string id;                 // " (id TEXT)" from the row's id column (model::id_suffix), or empty
  double residual_m = 0.0;        // position residual of the fit with it
  double statistic_ratio = 0.0;   // t_i / c over the rejection threshold (> 1)
  double tool_shift_max_m = 0.0;  // largest change of the predicted tool position over the
                                  // data's configurations when it is removed (first order)
};

// The rejection gate's decision (see above); judged only when the test rejected rows.
struct RejectionGate {
  bool judged = false;
  bool kept = false;                  // the rejections stand
  double kfold_with_m = 0.0;          // 5-fold cross-validated position RMS with the rejection rule
  double kfold_without_m = 0.0;       // and without it
  double kfold_t = 0.0;               // paired t of the rows' position-error differences (with - without)
  double out_of_range_with_m = -1.0;  // the out-of-range fold's RMS with and without; < 0: no such fold
  double out_of_range_without_m = -1.0;
  std::vector<Rejection> undone;  // the test's rejections the gate undid (kept = false)
};

struct IdentifyResult {
  RobotModel model;  // identified, with its calibration record
  RobotModel start;  // the starting model after reparameterization
  Identifiability identifiability;
  Eigen::VectorXd change;  // of identifiability.identified, SI
  Eigen::VectorXd stddev;
  Eigen::VectorXd prior_sigma;   // of change, SI; infinity where there is none (as the data scaled it)
  PriorScales prior_scales;      // the width each class of priors was given, and why (prior_scale.hpp)
  Eigen::VectorXd prior_centre;  // of change, SI: the nominal in the start's parameters (0 from the nominal)
  Eigen::VectorXd prior_share;   // of each parameter's posterior information, 0..1 (1 - data share)
  AccuracyStats residuals;       // over the measurements used
  Eigen::MatrixXd covariance;    // of change, SI (0 in the rows and columns of a parameter at_bound)
  // Of change: the parameter ended on a physical bound (problem.hpp). The bound holds it, so the
  // covariance is that of the others given it (its stddev 0): its linearized variance would
  // say nothing (a compliance pinned at kMaxCompliance had sd 1441 rad/(N m)) and would swell
  // every predicted spread that correct's "reached within the spread" trusts.
  std::vector<bool> at_bound;
  std::vector<int> outlier_lines;  // source lines of rejected measurements
  std::vector<Rejection> rejections;
  RejectionGate rejection_gate;
  double chi_square_per_dof = 0.0;
  double sigma_m = 0.0;                    // instrument sigma used for rows without covariance (0: none)
  bool all_covariance = false;             // every measurement carried its covariance
  double median_instrument_sigma_m = 0.0;  // over the rows' covariance diagonals (or sigma_m)
  double orientation_sigma_rad = 0.0;      // instrument orientation sigma used (0: none)
  bool orientation_used = false;
  bool model_error_estimated = false;        // s_p (and s_o with orientation) by REML
  double model_error_position_m = 0.0;       // s_p, per axis
  double model_error_orientation_rad = 0.0;  // s_o, per axis of the rotation vector
  double model_error_before_rejection_m = 0.0;
  int noise_passes = 0;  // solves of the noise-model iteration
  int iterations = 0;
  std::string termination;
  std::vector<std::string> notes;
  std::vector<std::string> cpa_sweeps;  // one line per sweep when cpa ran
};

// Throws model::InputError for bad input (see above).
IdentifyResult identify(const RobotModel& nominal, const model::Dataset& data, const IdentifyOptions& options);

// The joints (0-based) that never moved in the data: one reading in every row (a wrist kept facing
// the tracker, a rail or a seventh axis left still). identify() holds what only their motion shows
// and notes each; the calibrated model holds at that reading alone.
std::vector<int> still_joints(const model::Dataset& data);

struct CrossValidation;  // model_selection.hpp

// identify() with the rejection gate's cross-validation with the rejection rule given, saving its
// K + 1 solves: `with_rule` must be cross_validate(nominal, data, options) with the default
// SelectionOptions -- as model selection scored the candidate it chose
// (Selection::chosen_cross_validation, with the chosen candidate's model and options).
IdentifyResult identify(const RobotModel& nominal, const model::Dataset& data, const IdentifyOptions& options,
                        const CrossValidation& with_rule);

// The baseline a calibration is judged against: the nominal geometry with only the registration
// to the measuring device and the tool fitted (those of `calibrated`'s identified parameters that
// are base_* or tool_*), registered first as above, by the same noise model and outlier rule. What
// a user would get from the nominal model and a careful registration and tool measurement.
IdentifyResult identify_registration(const RobotModel& nominal, const model::Dataset& data,
                                     const IdentifyOptions& options, const IdentifyResult& calibrated);

// Covariance (m^2, device frame) of the error of a new measurement's position at readings q,
// less its instrument noise: the parameter covariance propagated to the tool point plus the
// model-error variance s_p^2 I. Requires a full or first-order result.
Eigen::Matrix3d prediction_covariance(const IdentifyResult& result, std::span<const double> q);

// The standard-DH -> Doty promotion and modified-DH rewrite described above (exported for tests).
RobotModel reparameterize_for_identification(const RobotModel& model, double parallel_tolerance_rad,
                                             std::vector<std::string>* notes);

// Every parameter of the model in the order identification prefers to keep them: the base's six
// motions, the tool's, then link by link (theta, d, a, alpha, beta). Where parameters cannot be
// told apart, the later ones are held fixed -- so theta1 and d1 give way to the base, and the last
// link's parameters to the tool.
// The parameters one --fix / --params entry names: "base" and "tool" stand for their six
// motions, any other entry for the parameter of that name (model::parse_parameter_name, whose
// InputError it throws).
ParameterIds parameter_entry_ids(const std::string& name, int joint_count);
ParameterIds candidate_parameters(const RobotModel& model);

// The noise model's lines of the report: the instrument's noise, the model error (mm, deg), the
// chi-square per degree of freedom, and each rejected row with what rejecting it changes.
std::string format_noise(const IdentifyResult& result);

// A human-readable report of a result (what `kincal identify` prints).
std::string format_report(const IdentifyResult& result);

}  // namespace kincal::identify
