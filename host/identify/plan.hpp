// Calibration planning (`kincal plan`): N joint configurations within the limits from which
// identification predicts the tool best (or, d_optimal, that make the identification Jacobian
// well conditioned), compared with random configurations.
//
// Candidates: options.candidates when given (configurations the user knows the robot reaches and
// the device sees, `plan --candidates`), else a pool drawn uniformly within the joint limits and
// options.constraints' joint ranges. Either way a candidate that violates a constraint
// (plan_constraints.hpp, the model's joint limits included) is left out before the exchange, so
// no planned configuration violates one; the plan holds N distinct candidates (a candidate given
// twice, the same joint values, is refused: InputError naming both by candidate_names). A random pool
// draws up to 100 x pool configurations to find `pool` that pass. Fewer passing candidates than
// N: InputError naming each constraint that no candidate meets, or the rejections of each.
// Which constraints bind the plan: a constraint is active when a candidate that violates it alone
// would improve the criterion if exchanged into the final plan (relaxing it would change the plan);
// its rejections and the largest such gain are reported (PlanResult::constraints). Joint ranges
// of a random pool shape the draws and reject none.
//
// Criterion (PlanOptions::criterion). What a calibration is for is the tool's position over the
// workspace, so the default, `prediction`, is I-optimal (Bayesian) design: the plan minimizes the
// mean over the pool (the candidates: where the robot will work and be measured) of the predicted
// position variance of identify's estimate, tr(P_k C P_k^T), P_k a candidate's position rows and
// C = (M + L)^-1 (N + L) (M + L)^-1 the covariance of the MAP estimate: M = sum J^T J the plan's
// information as identify weighs its rows (every position row by 1 / s_p, every rotation row by
// 1 / s_o), N = sum J^T V J the covariance of its score, L the priors' information
// (options.prior against options.model_error_m). The noise model V is the joints': each revolute
// joint errs by an independent angle of the same spread at every configuration (gears,
// elasticity: what identify's model error is), so a candidate's rows err as K K^T, K the joint
// Jacobian's revolute columns, and s_p, s_o are that error's mean spreads over the pool. On the
// real UR10 the geometric fit's residuals grow with |K_p|^2 as this says (0.37 mm RMS over the
// candidates' smallest eighth of it, 0.55 mm over the largest), and s_p / s_o is 0.62 m this way,
// 0.50 m as identify fits it; a plan weighing every row alike chose the rows the model explains
// worst (0.57 to 0.62 mm RMS under the fit of all candidates, against 0.44 for all of them). No
// revolute joint: every row alike. `d_optimal` maximizes Borm and Menq's
// O1 = (s_1 s_2 ... s_P)^(1/P) / sqrt(m), the geometric mean of the singular values of the
// identification Jacobian (m rows, weighted as above, the priors not counted), which shrinks the
// parameters' confidence ellipsoid (volume O1^-P) whatever the parameters do to the tool. Both
// use the identifiable parameters (chosen as `kincal identify` chooses them), each column scaled
// by its RMS over the pool. When the model's links have masses and it declares no compliance
// (options.gravity, the prediction criterion), the parameters are those of identify's
// geometry+gravity candidate (a gravity compliance on each joint gravity loads, gravity's
// direction; model_selection.hpp) where the plan's equations are as many as those parameters
// (else the geometry's), which model selection chooses on real arms: on the shared UR10 (30 of
// 995 candidates, seeds 1..5) a plan made for it predicts 0.416 to 0.424 mm held out with that
// model, one made for the geometry alone 0.431 to 0.458, and with the geometry alone 0.463 to
// 0.469 against 0.465 to 0.477. D-optimal plans stay with the geometry: O1 weighs the compliances
// like any parameter, whatever they do to the tool, and its plans for them predicted worse (0.4785
// mm held out with the defaults, seeds 1..5, against 0.4520 made for the geometry).
// Method: Fedorov exchange over the pool, starting from a random set of distinct candidates:
// first D-optimal (the rank-3, or 6, determinant update), then, for `prediction`, from that plan
// under the prediction criterion (its Woodbury update, plan.cpp), each until no exchange improves
// the criterion by more than 1e-9 relative (at most 20 sweeps each). The exchange finds a local
// optimum: plans from different seeds differ (on the real UR10, 30 of 995 candidates: the
// criterion within 0.5 %, the held-out RMS 0.465 to 0.477 mm). Candidates: drawn uniformly
// within the limits (revolute joints without limits: [-pi, pi]; prismatic joints need limits)
// or given.
//
// Cost: a sweep visits each of the N planned configurations and tries candidates for it: the
// whole pool while N x pool <= kExchangeBudget, else a random kExchangeBudget / N of them (at
// least 64), so a sweep costs O(kExchangeBudget) determinant updates plus N P^3 factorizations
// instead of growing with N x pool (`plan -n 1000` took 32 s, `-n 100000` did not finish).
// options.progress, when set, hears after each sweep (and every tenth of a long sweep).
//
// Also reported, whatever the criterion: O1 and the predicted position RMS over the pool
// (sqrt of the prediction criterion: the Cramer-Rao bound of the tool point per unit position
// sigma, a ratio between plans is unit-free), planned vs random.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "host/identify/identifiability.hpp"
#include "host/identify/plan_constraints.hpp"
#include "host/identify/prior.hpp"
#include "host/model/robot_model.hpp"

namespace kincal::identify {

enum class PlanCriterion { prediction, d_optimal };

struct PlanOptions {
  int count = 30;            // configurations to propose
  int pool = 1000;           // candidate configurations
  int random_sets = 50;      // random plans to compare with
  bool orientation = false;  // pose measurements (the tool must be a frame)
  PlanCriterion criterion = PlanCriterion::prediction;
  bool gravity = true;  // prediction: plan for the geometry+gravity candidate when it exists (above)
  // The priors identify will put on the parameters (prior.hpp; default: its default widths) and
  // the model error expected per position axis (m) that they weigh against.
  PriorOptions prior;
  double model_error_m = 0.25e-3;
  std::uint64_t seed = 1;
  std::vector<std::vector<double>> candidates;  // non-empty: choose from these (pool unused)
  // How messages name candidates[k] (`plan --candidates`: "FILE:LINE"); empty: "candidate k+1".
  std::vector<std::string> candidate_names;
  PlanConstraints constraints;
  // (sweep from 1, configurations visited in this sweep, N): progress of the exchange.
  std::function<void(int, std::size_t, std::size_t)> progress;
};

inline constexpr std::size_t kExchangeBudget = 200000;

// The most candidates a plan holds, given or drawn (`--pool`, the rows of `--candidates`): each
// keeps its Jacobian rows, about 4 kB, so 10^6 of them took 3.7 GB and three minutes (Release),
// 10^5 0.6 GB and 23 s; more is refused (InputError) before any is evaluated.
inline constexpr std::size_t kMaxCandidates = 100000;

// One constraint's effect on the plan.
struct ConstraintOutcome {
  Constraint constraint = Constraint::joint_limits;
  int rejected = 0;     // candidates that violate it (whatever else they violate)
  bool active = false;  // a candidate rejected by it alone would improve the plan
  // The best such exchange's improvement (1: none): the ratio of O1 (d_optimal) or of the
  // predicted position rms (prediction, old over new).
  double index_gain = 1.0;
};

struct PlanResult {
  std::vector<std::vector<double>> configurations;
  std::vector<std::size_t> chosen;             // with options.candidates: their indices, in plan order
  int considered = 0;                          // candidates given or drawn
  int feasible = 0;                            // of them, those meeting every constraint (the exchange's pool)
  std::vector<ConstraintOutcome> constraints;  // the model's joint limits and those given
  bool gravity = false;                        // planned for the geometry+gravity candidate's parameters
  // The geometry+gravity candidate exists but its parameters outnumber the plan's equations: the
  // configurations it would need (0: not left out).
  int gravity_needs = 0;
  ParameterIds identified;
  std::vector<HeldFixed> held_fixed;
  PlanCriterion criterion = PlanCriterion::prediction;
  double lever_m = 0.0;  // the orientation rows' weight used (m/rad; 0: positions only)
  double index = 0.0;    // O1 of the plan
  // Over the random plans of the same size (random_sets drawn) whose information matrix is
  // positive definite: a plan that cannot identify every parameter has no prediction rms. NaN
  // when none of them is (a small pool drawn with repetition); random_full_rank counts them.
  double random_index_mean = 0.0;
  double random_index_best = 0.0;
  double prediction_rms = 0.0;         // per unit position sigma, RMS over the pool
  double random_prediction_rms = 0.0;  // mean over the random plans (as random_index_mean)
  int random_full_rank = 0;
};

// Throws model::InputError (prismatic joint without limits, count too small for the parameters,
// fewer feasible candidates than count, a candidate with the wrong number of joints).
PlanResult plan_configurations(const model::RobotModel& model, const PlanOptions& options);

}  // namespace kincal::identify
