#include "host/identify/plan.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <random>

#include <Eigen/Cholesky>

#include "host/identify/identify.hpp"
#include "host/identify/model_selection.hpp"
#include "host/identify/prior.hpp"

namespace kincal::identify {

namespace {

using model::InputError;

struct PoolCandidate {
  std::vector<double> q;
  Eigen::MatrixXd j;  // scaled, whitened rows (3 or 6) x P
  Eigen::MatrixXd v;  // the covariance of its rows' model error, whitened (rows x rows)
};

double log_det(const Eigen::MatrixXd& m) {
  Eigen::LLT<Eigen::MatrixXd> llt(m);
  if (llt.info() != Eigen::Success) return -1e300;
  return 2.0 * llt.matrixL().toDenseMatrix().diagonal().array().log().sum();
}

// O1 from the information matrix of `rows` Jacobian rows.
double o1(const Eigen::MatrixXd& info, double rows) {
  return std::exp(0.5 * log_det(info) / static_cast<double>(info.rows())) / std::sqrt(rows);
}

// tr(a b) of symmetric matrices.
double trace_product(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return a.cwiseProduct(b).sum(); }

// A plan's information M = L + sum J^T J (identify's weights, L the priors') and the covariance
// of its score, N = L + sum J^T V J (the rows' model error as the joints make it): the estimate's
// covariance is M^-1 N M^-1 (a sandwich: identify weighs every row alike, the joints do not err
// alike).
struct PlanMatrices {
  Eigen::MatrixXd info, noise;
  void add(const PoolCandidate& c, double sign) {
    info += sign * c.j.transpose() * c.j;
    noise += sign * c.j.transpose() * c.v * c.j;
  }
};

// The prediction criterion: tr(A M^-1 N M^-1), the mean over the pool of the predicted position
// variance (A the pool's mean of P^T P, P a candidate's position rows), per unit position sigma.
double mean_variance(const Eigen::MatrixXd& info, const Eigen::MatrixXd& noise, const Eigen::MatrixXd& moment) {
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(info);
  const Eigen::MatrixXd inverse = ldlt.solve(Eigen::MatrixXd::Identity(info.rows(), info.cols()));
  return trace_product(moment, inverse * noise * inverse);
}

// The ridge that keeps a plan without one configuration positive definite.
constexpr double kRidge = 1e-9;

// What exchanging one planned configuration for candidate c makes of the criterion, from the
// plan without it (R, N_R: `reduced`, R with the ridge); larger is better.
//   D-optimal (moment null): log det(R + J^T J) - log det(R) = log det(I + J R^-1 J^T).
//   prediction: minus tr(A E N' E), E = (R + J^T J)^-1 = B - U S^-1 U^T (Woodbury: B = R^-1,
//     U = B J^T, S = I + J U), N' = N_R + J^T V J, expanded so that a candidate costs O(P^2 rows):
//       tr(B A B N') - 2 tr(S^-1 U^T A B N' U) + tr(S^-1 U^T A U S^-1 U^T N' U)
//     with U^T A B J^T = U^T A U and J U = S - I; or by factorizing R + J^T J when R is too
//     ill-conditioned for those differences (a plan with fewer rows than parameters without the
//     leaving configuration).
class ExchangeGain {
 public:
  ExchangeGain(const PlanMatrices& reduced, const Eigen::MatrixXd* moment)
      : reduced_(reduced), ldlt_(reduced.info), moment_(moment) {
    if (moment_ == nullptr) return;
    direct_ = !(ldlt_.rcond() > 1e-6);
    if (direct_) return;
    const Eigen::MatrixXd& a = *moment_;
    inverse_ = ldlt_.solve(Eigen::MatrixXd::Identity(a.rows(), a.cols()));
    bab_ = inverse_ * a * inverse_;
    abn_ = a * inverse_ * reduced_.noise;
    base_ = trace_product(bab_, reduced_.noise);
  }
  double operator()(const PoolCandidate& c) const {
    const Eigen::MatrixXd identity = Eigen::MatrixXd::Identity(c.j.rows(), c.j.rows());
    if (moment_ == nullptr) return log_det(identity + c.j * ldlt_.solve(c.j.transpose()));
    if (direct_) {
      PlanMatrices after = reduced_;
      after.add(c, 1.0);
      return -mean_variance(after.info, after.noise, *moment_);
    }
    const Eigen::MatrixXd u = inverse_ * c.j.transpose();
    const Eigen::MatrixXd ju = c.j * u;
    const Eigen::LDLT<Eigen::MatrixXd> s(identity + ju);
    const Eigen::MatrixXd uau = u.transpose() * *moment_ * u;
    const Eigen::MatrixXd unu = u.transpose() * reduced_.noise * u + ju.transpose() * c.v * ju;
    const double first = base_ + trace_product(c.v, c.j * bab_ * c.j.transpose());
    const double second = s.solve(u.transpose() * abn_ * u + uau * c.v * ju).trace();
    const double third = (s.solve(uau) * s.solve(unu)).trace();
    return -(first - 2.0 * second + third);
  }
  // The criterion's improvement from gain `from` to gain `to` as a ratio above 1: of O1
  // (D-optimal, P parameters) or of the predicted position rms (prediction).
  double ratio(double from, double to) const {
    if (moment_ == nullptr) return std::exp((to - from) * 0.5 / static_cast<double>(reduced_.info.rows()));
    return std::sqrt(from / to);
  }

 private:
  PlanMatrices reduced_;
  Eigen::LDLT<Eigen::MatrixXd> ldlt_;
  const Eigen::MatrixXd* moment_;
  bool direct_ = false;
  Eigen::MatrixXd inverse_, bab_, abn_;  // B, B A B, A B N_R
  double base_ = 0.0;                    // tr(B A B N_R)
};

// The plan without candidate c, with the ridge.
PlanMatrices without(const PlanMatrices& plan, const PoolCandidate& c) {
  PlanMatrices reduced = plan;
  reduced.add(c, -1.0);
  reduced.info += Eigen::MatrixXd::Identity(plan.info.rows(), plan.info.cols()) * kRidge;
  return reduced;
}

// Fedorov exchange of `set`'s configurations for pool candidates under the criterion (moment null:
// D-optimal), sweep by sweep until no exchange improves it by more than 1e-9 relative (at most 20
// sweeps); `plan` holds the set's matrices, kept up to date. A sweep tries for each configuration
// the whole pool while N x pool <= kExchangeBudget, else a random kExchangeBudget / N of it.
void exchange(const std::vector<PoolCandidate>& pool, const Eigen::MatrixXd* moment, const PlanOptions& options,
              int first_sweep, std::mt19937_64& rng, std::vector<std::size_t>& set, PlanMatrices& plan) {
  std::vector<bool> in_set(pool.size(), false);
  for (std::size_t k : set) in_set[k] = true;
  const std::size_t tried = std::min(pool.size(), std::max<std::size_t>(64, kExchangeBudget / set.size()));
  std::vector<std::size_t> candidates_tried(tried);
  for (int sweep = first_sweep; sweep < first_sweep + 20; ++sweep) {
    bool improved = false;
    for (std::size_t i = 0; i < set.size(); ++i) {
      if (options.progress && set.size() >= 1000 && i % (set.size() / 10) == 0)
        options.progress(sweep + 1, i, set.size());
      for (std::size_t t = 0; t < tried; ++t)
        candidates_tried[t] =
            tried == pool.size() ? t : std::uniform_int_distribution<std::size_t>(0, pool.size() - 1)(rng);
      const PlanMatrices reduced = without(plan, pool[set[i]]);
      const ExchangeGain gain(reduced, moment);
      const double current = gain(pool[set[i]]);
      double best = current;
      std::size_t best_c = set[i];
      for (const std::size_t c : candidates_tried) {
        if (in_set[c]) continue;
        const double g = gain(pool[c]);
        if (g > best) {
          best = g;
          best_c = c;
        }
      }
      if (best - current > 1e-9 * std::max(1.0, std::abs(current))) {
        plan.add(pool[set[i]], -1.0);
        plan.add(pool[best_c], 1.0);
        in_set[set[i]] = false;
        in_set[best_c] = true;
        set[i] = best_c;
        improved = true;
      }
    }
    if (options.progress) options.progress(sweep + 1, set.size(), set.size());
    if (!improved) break;
  }
}

// The model error's shape (plan.hpp): a candidate's rows err as K K^T, K its joint Jacobian's
// revolute columns (rows x joints); empty without a revolute joint.
Eigen::MatrixXd joint_error(const model::RobotModel& m, const std::vector<double>& q, int rows) {
  const Eigen::MatrixXd j = model::joint_jacobian(m, q);
  Eigen::MatrixXd k = Eigen::MatrixXd::Zero(rows, j.cols());
  bool revolute = false;
  for (std::size_t i = 0; i < m.joints.size(); ++i) {
    if (m.joints[i].type != core::JointType::revolute) continue;
    k.col(static_cast<Eigen::Index>(i)) = j.col(static_cast<Eigen::Index>(i)).head(rows);
    revolute = true;
  }
  return revolute ? k : Eigen::MatrixXd();
}

// The rows' weights identify would give them, 1 / s_p and 1 / s_o: the pool's mean spreads of
// the joints' error per axis (ones without a revolute joint).
Eigen::VectorXd row_weights(const model::RobotModel& m, const std::vector<PoolCandidate>& pool, int rows) {
  Eigen::VectorXd sum = Eigen::VectorXd::Zero(rows);
  for (const PoolCandidate& c : pool) {
    const Eigen::MatrixXd k = joint_error(m, c.q, rows);
    if (k.size() == 0) return Eigen::VectorXd::Ones(rows);
    sum += k.rowwise().squaredNorm();
  }
  Eigen::VectorXd w(rows);
  for (int b = 0; b < rows; b += 3)
    w.segment(b, 3).setConstant(std::sqrt(3.0 * static_cast<double>(pool.size()) / sum.segment(b, 3).sum()));
  return w;
}

// A candidate's rows weighted by w, and its whitened model-error covariance (identity without a
// revolute joint: every row alike).
void whiten(const model::RobotModel& m, const Eigen::VectorXd& w, PoolCandidate& c) {
  c.j = w.asDiagonal() * c.j;
  const Eigen::MatrixXd k = joint_error(m, c.q, static_cast<int>(w.size()));
  if (k.size() == 0) {
    c.v = Eigen::MatrixXd::Identity(w.size(), w.size());
    return;
  }
  const Eigen::MatrixXd wk = w.asDiagonal() * k;
  c.v = wk * wk.transpose();
}

}  // namespace

PlanResult plan_configurations(const model::RobotModel& m, const PlanOptions& options) {
  const int n = m.joint_count();
  std::vector<double> lower(static_cast<std::size_t>(n)), upper(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const model::Joint& j = m.joints[static_cast<std::size_t>(i)];
    const bool finite = std::isfinite(j.lower) && std::isfinite(j.upper);
    if (!finite && j.type == core::JointType::prismatic)
      throw InputError("plan: joint " + std::to_string(i + 1) + " (" + j.name + ") is prismatic and has no limits");
    lower[static_cast<std::size_t>(i)] = finite ? j.lower : -std::numbers::pi;
    upper[static_cast<std::size_t>(i)] = finite ? j.upper : std::numbers::pi;
  }
  const int rows = options.orientation ? 6 : 3;
  if (options.orientation && m.tool != model::ToolKind::frame)
    throw InputError("plan: pose measurements need a tool frame in the model");
  std::mt19937_64 rng(options.seed);
  const PlanConstraints& limits = options.constraints;
  for (const JointRange& r : limits.joint_ranges) {
    lower[static_cast<std::size_t>(r.joint)] = std::max(lower[static_cast<std::size_t>(r.joint)], r.lower);
    upper[static_cast<std::size_t>(r.joint)] = std::min(upper[static_cast<std::size_t>(r.joint)], r.upper);
  }
  const auto random_q = [&] {
    std::vector<double> q(static_cast<std::size_t>(n));
    for (std::size_t i = 0; i < q.size(); ++i) q[i] = std::uniform_real_distribution<double>(lower[i], upper[i])(rng);
    return q;
  };
  // Candidates: the given ones or random draws, split into those meeting every constraint (the
  // pool) and those rejected (kept, a random pool's up to `pool` of them, for the active test).
  std::array<int, kConstraints.size()> rejected_by{};
  std::vector<PoolCandidate> pool, rejected;
  std::vector<unsigned> rejected_mask;
  std::vector<std::size_t> pool_source;  // index into options.candidates
  int considered = 0;
  const auto consider = [&](std::vector<double> q, std::size_t source) {
    ++considered;
    const unsigned mask = violated_constraints(m, limits, q);
    for (std::size_t c = 0; c < kConstraints.size(); ++c) rejected_by[c] += ((mask >> c) & 1u) != 0 ? 1 : 0;
    if (mask == 0) {
      pool.push_back({std::move(q), {}, {}});
      pool_source.push_back(source);
    } else if (!options.candidates.empty() || rejected.size() < static_cast<std::size_t>(options.pool)) {
      rejected.push_back({std::move(q), {}, {}});
      rejected_mask.push_back(mask);
    }
  };
  const std::size_t held = options.candidates.empty()
                               ? static_cast<std::size_t>(std::max({options.pool, options.count, 0}))
                               : options.candidates.size();
  if (held > kMaxCandidates)
    throw InputError("plan: " + std::to_string(held) + " candidate configurations, more than the " +
                     std::to_string(kMaxCandidates) + " a plan holds");
  if (!options.candidates.empty()) {
    const auto name = [&](std::size_t k) {
      return k < options.candidate_names.size() ? options.candidate_names[k] : "candidate " + std::to_string(k + 1);
    };
    std::map<std::vector<double>, std::size_t> first;
    for (std::size_t k = 0; k < options.candidates.size(); ++k) {
      if (options.candidates[k].size() != static_cast<std::size_t>(n))
        throw InputError("plan: " + name(k) + " has " + std::to_string(options.candidates[k].size()) +
                         " joint values, the model " + std::to_string(n));
      if (const auto [at, inserted] = first.emplace(options.candidates[k], k); !inserted)
        throw InputError("plan: " + name(k) + " is the same configuration as " + name(at->second) +
                         " (a plan holds distinct configurations)");
      consider(options.candidates[k], k);
    }
  } else {
    const auto wanted = static_cast<std::size_t>(std::max(options.pool, options.count));
    for (int draw = 0; pool.size() < wanted && draw < 100 * options.pool; ++draw) consider(random_q(), 0);
  }
  PlanResult result;
  result.considered = considered;
  result.feasible = static_cast<int>(pool.size());
  const auto applies = [&](Constraint c) {
    switch (c) {
      case Constraint::joint_limits:
        return true;
      case Constraint::joint_ranges:
        return !limits.joint_ranges.empty();
      case Constraint::workspace:
        return limits.workspace.has_value();
      case Constraint::floor:
        return limits.floor.has_value();
      case Constraint::sight:
        return limits.sight.has_value();
    }
    return false;
  };
  for (const Constraint c : kConstraints)
    if (applies(c)) result.constraints.push_back({c, rejected_by[static_cast<std::size_t>(c)], false, 1.0});
  if (pool.size() < static_cast<std::size_t>(options.count)) {
    std::string alone, counts;
    for (const ConstraintOutcome& o : result.constraints) {
      if (o.rejected == considered) alone += "; no candidate meets " + describe(o.constraint, limits, m);
      counts += std::string(counts.empty() ? "" : ", ") + constraint_name(o.constraint) + " rejects " +
                std::to_string(o.rejected);
    }
    throw InputError("plan: " + std::to_string(pool.size()) + " of " + std::to_string(considered) +
                     " candidate configurations meet the constraints, " + std::to_string(options.count) +
                     " are asked for" + (alone.empty() ? " (" + counts + ")" : alone));
  }
  // Pool and identifiable parameters: the geometry+gravity candidate's when the model has masses
  // and the plan's equations carry them (plan.hpp), else the geometry's.
  struct Parameters {
    RobotModel start;
    ParameterIds candidates;
    Eigen::MatrixXd all;  // the pool's Jacobian rows
    Identifiability ident;
  };
  const auto identifiable = [&](const RobotModel& planned) {
    Parameters out{reparameterize_for_identification(planned, 0.1, nullptr), {}, {}, {}};
    out.candidates = candidate_parameters(out.start);
    out.all.resize(static_cast<Eigen::Index>(pool.size()) * rows, static_cast<Eigen::Index>(out.candidates.size()));
    for (std::size_t k = 0; k < pool.size(); ++k)
      out.all.middleRows(static_cast<Eigen::Index>(k) * rows, rows) =
          model::parameter_jacobian(out.start, pool[k].q, out.candidates).topRows(rows);
    out.ident = analyze_identifiability(out.all, out.candidates);
    return out;
  };
  const bool for_gravity = options.gravity && options.criterion == PlanCriterion::prediction;
  const std::optional<RobotModel> with_gravity = for_gravity ? gravity_model(m) : std::nullopt;
  Parameters planned = identifiable(with_gravity ? *with_gravity : m);
  result.gravity = with_gravity && options.count * rows >= static_cast<int>(planned.ident.identified.size());
  if (with_gravity && !result.gravity) {
    result.gravity_needs = (static_cast<int>(planned.ident.identified.size()) + rows - 1) / rows;
    planned = identifiable(m);
  }
  const auto& [start, candidates, all, ident] = planned;
  result.identified = ident.identified;
  result.held_fixed = ident.held_fixed;
  const auto p = static_cast<Eigen::Index>(ident.identified.size());
  if (options.count * rows < p)
    throw InputError("plan: " + std::to_string(options.count) + " configurations give " +
                     std::to_string(options.count * rows) + " equations for " + std::to_string(p) +
                     " identifiable parameters; ask for at least " + std::to_string((p + rows - 1) / rows + 1));
  // Columns of the identified parameters, scaled by their RMS over the pool; rows weighted as
  // identify weighs them and the model error's shape at each candidate (plan.hpp).
  result.criterion = options.criterion;
  std::vector<Eigen::Index> columns;
  for (const core::ParameterId& id : ident.identified)
    for (std::size_t c = 0; c < candidates.size(); ++c)
      if (candidates[c].kind == id.kind && candidates[c].link == id.link)
        columns.push_back(static_cast<Eigen::Index>(c));
  Eigen::VectorXd scale(p);
  for (Eigen::Index c = 0; c < p; ++c)
    scale(c) = all.col(columns[static_cast<std::size_t>(c)]).norm() / std::sqrt(static_cast<double>(pool.size()));
  const auto scaled = [&](const Eigen::MatrixXd& j) {
    Eigen::MatrixXd out(rows, p);
    for (Eigen::Index c = 0; c < p; ++c) out.col(c) = j.col(columns[static_cast<std::size_t>(c)]) / scale(c);
    return out;
  };
  const Eigen::VectorXd w = row_weights(m, pool, rows);
  if (rows == 6) result.lever_m = w(3) / w(0);
  for (std::size_t k = 0; k < pool.size(); ++k) {
    pool[k].j = scaled(all.middleRows(static_cast<Eigen::Index>(k) * rows, rows));
    whiten(m, w, pool[k]);
  }
  for (PoolCandidate& r : rejected) {
    r.j = scaled(model::parameter_jacobian(start, r.q, candidates).topRows(rows));
    whiten(m, w, r);
  }
  // The pool's mean of P^T P: what the prediction criterion averages over.
  Eigen::MatrixXd moment = Eigen::MatrixXd::Zero(p, p);
  for (const PoolCandidate& c : pool) moment += c.j.topRows(3).transpose() * c.j.topRows(3);
  moment /= static_cast<double>(pool.size());
  // identify's priors (options.prior) in the plan's units, where a row's noise is
  // the joints' error over its weight: 1 / (sigma * scale)^2 times sigma_j^2, the joints' error
  // spread that makes options.model_error_m at the tool. The MAP estimate's error has covariance
  // (M + L)^-1 (N + L) (M + L)^-1 (the prior's own spread is L^-1), so L joins both matrices.
  const Eigen::VectorXd sigmas =
      prior_sigmas(options.prior, ident.identified, n, "plan", {}, given_centres(start)) *
      (options.prior.strength > 0.0 ? 1.0 / options.prior.strength : std::numeric_limits<double>::infinity());
  const double joint_sigma = options.model_error_m * w(0);
  Eigen::MatrixXd prior = Eigen::MatrixXd::Zero(p, p);
  for (Eigen::Index c = 0; c < p; ++c)
    if (std::isfinite(sigmas(c))) prior(c, c) = std::pow(joint_sigma / (sigmas(c) * scale(c)), 2);
  const auto matrices = [&](const std::vector<std::size_t>& set) {
    PlanMatrices plan{prior, prior};
    for (std::size_t k : set) plan.add(pool[k], 1.0);
    return plan;
  };
  const double m_rows = static_cast<double>(options.count * rows);
  // Random plans for comparison.
  double random_sum = 0.0, random_pred = 0.0;
  for (int s = 0; s < options.random_sets; ++s) {
    std::vector<std::size_t> set;
    for (int k = 0; k < options.count; ++k)
      set.push_back(std::uniform_int_distribution<std::size_t>(0, pool.size() - 1)(rng));
    const PlanMatrices plan = matrices(set);
    // A singular plan (repeated configurations of a small pool) predicts nothing: its LDLT solve
    // is garbage and its rms NaN. It is left out of the comparison.
    if (Eigen::LLT<Eigen::MatrixXd>(plan.info).info() != Eigen::Success) continue;
    const double index = o1(plan.info - prior, m_rows);
    ++result.random_full_rank;
    random_sum += index;
    result.random_index_best = std::max(result.random_index_best, index);
    random_pred += std::sqrt(mean_variance(plan.info, plan.noise, moment));
  }
  const double none = std::numeric_limits<double>::quiet_NaN();
  result.random_index_mean = result.random_full_rank > 0 ? random_sum / result.random_full_rank : none;
  result.random_prediction_rms = result.random_full_rank > 0 ? random_pred / result.random_full_rank : none;
  // D-optimal exchange from a random start of distinct candidates (a drawn pool is in random
  // order; given candidates are sampled), then the prediction criterion's exchange from that plan.
  std::vector<std::size_t> set(pool.size());
  for (std::size_t k = 0; k < set.size(); ++k) set[k] = k;
  if (!options.candidates.empty()) std::shuffle(set.begin(), set.end(), rng);
  set.resize(static_cast<std::size_t>(options.count));
  PlanMatrices plan = matrices(set);
  exchange(pool, nullptr, options, 0, rng, set, plan);
  const Eigen::MatrixXd* criterion = options.criterion == PlanCriterion::prediction ? &moment : nullptr;
  if (criterion != nullptr) exchange(pool, criterion, options, 20, rng, set, plan);
  result.index = o1(plan.info - prior, m_rows);
  result.prediction_rms = std::sqrt(mean_variance(plan.info, plan.noise, moment));
  for (std::size_t k : set) {
    result.configurations.push_back(pool[k].q);
    if (!options.candidates.empty()) result.chosen.push_back(pool_source[k]);
  }
  // Active constraints: would a candidate rejected by one constraint alone enter the plan?
  for (std::size_t i = 0; i < set.size(); ++i) {
    const ExchangeGain gain(without(plan, pool[set[i]]), criterion);
    const double current = gain(pool[set[i]]);
    for (ConstraintOutcome& o : result.constraints) {
      const unsigned alone = 1u << static_cast<unsigned>(o.constraint);
      for (std::size_t r = 0; r < rejected.size(); ++r) {
        if (rejected_mask[r] != alone) continue;
        const double ratio = gain.ratio(current, gain(rejected[r]));
        if (ratio > 1.0 + 1e-9) o.active = true;
        o.index_gain = std::max(o.index_gain, ratio);
      }
    }
  }
  return result;
}

}  // namespace kincal::identify
