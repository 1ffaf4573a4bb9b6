// Calibration planning (`kincal plan`): N joint configurations within the limits that make the
// identification Jacobian well conditioned, compared with random configurations.
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
// would raise the index if exchanged into the final plan (relaxing it would change the plan);
// its rejections and the largest such gain are reported (PlanResult::constraints). Joint ranges
// of a random pool shape the draws and reject none.
//
// Index: Borm and Menq's O1 = (s_1 s_2 ... s_P)^(1/P) / sqrt(m), the geometric mean of the
// singular values of the identification Jacobian (m rows) of the identifiable parameters
// (chosen as `kincal identify` chooses them), with each parameter's column scaled by its RMS
// over a pool of random configurations so that metres and radians weigh alike. Maximizing it
// is D-optimal design: the volume of the parameters' confidence ellipsoid shrinks as
// O1^-P. Method: Fedorov exchange over a candidate pool drawn uniformly within the limits
// (revolute joints without limits: [-pi, pi]; prismatic joints need limits), starting from
// a random set, with the rank-3 (6 with orientation) determinant update, until no exchange
// improves the index by more than 1e-9 relative (at most 20 sweeps).
//
// Cost: a sweep visits each of the N planned configurations and tries candidates for it: the
// whole pool while N x pool <= kExchangeBudget, else a random kExchangeBudget / N of them (at
// least 64), so a sweep costs O(kExchangeBudget) determinant updates plus N P^3 factorizations
// instead of growing with N x pool (`plan -n 1000` took 32 s, `-n 100000` did not finish).
// options.progress, when set, hears after each sweep (and every tenth of a long sweep).
//
// Also reported: the mean predicted position RMS over the pool (the Cramer-Rao bound of the
// tool point for sigma = 1, a ratio between plans is unit-free), planned vs random.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "host/identify/identifiability.hpp"
#include "host/identify/plan_constraints.hpp"
#include "host/model/robot_model.hpp"

namespace kincal::identify {

struct PlanOptions {
  int count = 30;            // configurations to propose
  int pool = 1000;           // candidate configurations
  int random_sets = 50;      // random plans to compare with
  bool orientation = false;  // pose measurements (the tool must be a frame)
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
  int rejected = 0;         // candidates that violate it (whatever else they violate)
  bool active = false;      // a candidate rejected by it alone would improve the plan
  double index_gain = 1.0;  // the best such exchange's O1 ratio (1: none)
};

struct PlanResult {
  std::vector<std::vector<double>> configurations;
  std::vector<std::size_t> chosen;             // with options.candidates: their indices, in plan order
  int considered = 0;                          // candidates given or drawn
  int feasible = 0;                            // of them, those meeting every constraint (the exchange's pool)
  std::vector<ConstraintOutcome> constraints;  // the model's joint limits and those given
  ParameterIds identified;
  std::vector<HeldFixed> held_fixed;
  double index = 0.0;  // O1 of the plan
  // Over the random plans of the same size (random_sets drawn) whose information matrix is
  // positive definite: a plan that cannot identify every parameter has no prediction rms. NaN
  // when none of them is (a small pool drawn with repetition); random_full_rank counts them.
  double random_index_mean = 0.0;
  double random_index_best = 0.0;
  double prediction_rms = 0.0;         // per unit sigma, mean over the pool
  double random_prediction_rms = 0.0;  // mean over the random plans (as random_index_mean)
  int random_full_rank = 0;
};

// Throws model::InputError (prismatic joint without limits, count too small for the parameters,
// fewer feasible candidates than count, a candidate with the wrong number of joints).
PlanResult plan_configurations(const model::RobotModel& model, const PlanOptions& options);

}  // namespace kincal::identify
