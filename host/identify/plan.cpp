#include "host/identify/plan.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <numbers>
#include <random>

#include <Eigen/Cholesky>

#include "host/identify/identify.hpp"

namespace kincal::identify {

namespace {

using model::InputError;

struct Candidate {
  std::vector<double> q;
  Eigen::MatrixXd j;  // scaled rows (3 or 6) x P
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

double prediction_rms(const Eigen::MatrixXd& info, const std::vector<Candidate>& pool, int rows) {
  const Eigen::LDLT<Eigen::MatrixXd> ldlt(info);
  double sum = 0.0;
  for (const Candidate& c : pool) {
    const Eigen::MatrixXd p = c.j.topRows(3);
    sum += (p * ldlt.solve(p.transpose())).trace();
  }
  (void)rows;
  return std::sqrt(sum / static_cast<double>(pool.size()));
}

// det(reduced + J^T J) / det(reduced) = det(I + J reduced^-1 J^T): what exchanging J into a plan
// whose information without the leaving configuration is `reduced` multiplies its determinant by.
double exchange_gain(const Eigen::LDLT<Eigen::MatrixXd>& reduced, const Eigen::MatrixXd& j) {
  return (Eigen::MatrixXd::Identity(j.rows(), j.rows()) + j * reduced.solve(j.transpose())).determinant();
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
  std::vector<Candidate> pool, rejected;
  std::vector<unsigned> rejected_mask;
  std::vector<std::size_t> pool_source;  // index into options.candidates
  int considered = 0;
  const auto consider = [&](std::vector<double> q, std::size_t source) {
    ++considered;
    const unsigned mask = violated_constraints(m, limits, q);
    for (std::size_t c = 0; c < kConstraints.size(); ++c) rejected_by[c] += ((mask >> c) & 1u) != 0 ? 1 : 0;
    if (mask == 0) {
      pool.push_back({std::move(q), {}});
      pool_source.push_back(source);
    } else if (!options.candidates.empty() || rejected.size() < static_cast<std::size_t>(options.pool)) {
      rejected.push_back({std::move(q), {}});
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
  // Pool and identifiable parameters.
  const RobotModel start = reparameterize_for_identification(m, 0.1, nullptr);
  const ParameterIds candidates = candidate_parameters(start);
  Eigen::MatrixXd all(static_cast<Eigen::Index>(pool.size()) * rows, static_cast<Eigen::Index>(candidates.size()));
  for (std::size_t k = 0; k < pool.size(); ++k)
    all.middleRows(static_cast<Eigen::Index>(k) * rows, rows) =
        model::parameter_jacobian(start, pool[k].q, candidates).topRows(rows);
  const Identifiability ident = analyze_identifiability(all, candidates);
  result.identified = ident.identified;
  result.held_fixed = ident.held_fixed;
  const auto p = static_cast<Eigen::Index>(ident.identified.size());
  if (options.count * rows < p)
    throw InputError("plan: " + std::to_string(options.count) + " configurations give " +
                     std::to_string(options.count * rows) + " equations for " + std::to_string(p) +
                     " identifiable parameters; ask for at least " + std::to_string((p + rows - 1) / rows + 1));
  // Columns of the identified parameters, scaled by their RMS over the pool.
  std::vector<Eigen::Index> columns;
  for (const core::ParameterId& id : ident.identified)
    for (std::size_t c = 0; c < candidates.size(); ++c)
      if (candidates[c].kind == id.kind && candidates[c].link == id.link)
        columns.push_back(static_cast<Eigen::Index>(c));
  Eigen::VectorXd scale(p);
  for (Eigen::Index c = 0; c < p; ++c)
    scale(c) = all.col(columns[static_cast<std::size_t>(c)]).norm() / std::sqrt(static_cast<double>(pool.size()));
  for (std::size_t k = 0; k < pool.size(); ++k) {
    pool[k].j.resize(rows, p);
    for (Eigen::Index c = 0; c < p; ++c)
      pool[k].j.col(c) =
          all.block(static_cast<Eigen::Index>(k) * rows, columns[static_cast<std::size_t>(c)], rows, 1) / scale(c);
  }
  for (Candidate& r : rejected) {
    const Eigen::MatrixXd j = model::parameter_jacobian(start, r.q, candidates).topRows(rows);
    r.j.resize(rows, p);
    for (Eigen::Index c = 0; c < p; ++c) r.j.col(c) = j.col(columns[static_cast<std::size_t>(c)]) / scale(c);
  }
  const auto information = [&](const std::vector<std::size_t>& set) {
    Eigen::MatrixXd info = Eigen::MatrixXd::Zero(p, p);
    for (std::size_t k : set) info += pool[k].j.transpose() * pool[k].j;
    return info;
  };
  const double m_rows = static_cast<double>(options.count * rows);
  // Random plans for comparison.
  double random_sum = 0.0, random_pred = 0.0;
  for (int s = 0; s < options.random_sets; ++s) {
    std::vector<std::size_t> set;
    for (int k = 0; k < options.count; ++k)
      set.push_back(std::uniform_int_distribution<std::size_t>(0, pool.size() - 1)(rng));
    const Eigen::MatrixXd info = information(set);
    // A singular plan (repeated configurations of a small pool) predicts nothing: its LDLT solve
    // is garbage and its rms NaN. It is left out of the comparison.
    if (Eigen::LLT<Eigen::MatrixXd>(info).info() != Eigen::Success) continue;
    const double index = o1(info, m_rows);
    ++result.random_full_rank;
    random_sum += index;
    result.random_index_best = std::max(result.random_index_best, index);
    random_pred += prediction_rms(info, pool, options.count);
  }
  const double none = std::numeric_limits<double>::quiet_NaN();
  result.random_index_mean = result.random_full_rank > 0 ? random_sum / result.random_full_rank : none;
  result.random_prediction_rms = result.random_full_rank > 0 ? random_pred / result.random_full_rank : none;
  // Fedorov exchange from a random start of distinct candidates (a drawn pool is in random order;
  // given candidates are sampled).
  std::vector<std::size_t> set(pool.size());
  for (std::size_t k = 0; k < set.size(); ++k) set[k] = k;
  if (!options.candidates.empty()) std::shuffle(set.begin(), set.end(), rng);
  set.resize(static_cast<std::size_t>(options.count));
  std::vector<bool> in_set(pool.size(), false);
  for (std::size_t k : set) in_set[k] = true;
  Eigen::MatrixXd info = information(set);
  const Eigen::MatrixXd ridge = Eigen::MatrixXd::Identity(p, p) * 1e-9;
  const std::size_t tried = std::min(pool.size(), std::max<std::size_t>(64, kExchangeBudget / set.size()));
  std::vector<std::size_t> candidates_tried(tried);
  for (int sweep = 0; sweep < 20; ++sweep) {
    bool improved = false;
    for (std::size_t i = 0; i < set.size(); ++i) {
      if (options.progress && set.size() >= 1000 && i % (set.size() / 10) == 0)
        options.progress(sweep + 1, i, set.size());
      for (std::size_t t = 0; t < tried; ++t)
        candidates_tried[t] =
            tried == pool.size() ? t : std::uniform_int_distribution<std::size_t>(0, pool.size() - 1)(rng);
      const Eigen::MatrixXd reduced = info - pool[set[i]].j.transpose() * pool[set[i]].j + ridge;
      const Eigen::LDLT<Eigen::MatrixXd> ldlt(reduced);
      const auto gain = [&](std::size_t c) { return exchange_gain(ldlt, pool[c].j); };
      const double current = gain(set[i]);
      double best = current;
      std::size_t best_c = set[i];
      for (const std::size_t c : candidates_tried) {
        if (in_set[c]) continue;
        const double g = gain(c);
        if (g > best) {
          best = g;
          best_c = c;
        }
      }
      if (best > current * (1.0 + 1e-9)) {
        info = reduced - ridge + pool[best_c].j.transpose() * pool[best_c].j;
        in_set[set[i]] = false;
        in_set[best_c] = true;
        set[i] = best_c;
        improved = true;
      }
    }
    if (options.progress) options.progress(sweep + 1, set.size(), set.size());
    if (!improved) break;
  }
  result.index = o1(info, m_rows);
  result.prediction_rms = prediction_rms(info, pool, options.count);
  for (std::size_t k : set) {
    result.configurations.push_back(pool[k].q);
    if (!options.candidates.empty()) result.chosen.push_back(pool_source[k]);
  }
  // Active constraints: would a candidate rejected by one constraint alone enter the plan?
  for (std::size_t i = 0; i < set.size(); ++i) {
    const Eigen::MatrixXd reduced = info - pool[set[i]].j.transpose() * pool[set[i]].j + ridge;
    const Eigen::LDLT<Eigen::MatrixXd> ldlt(reduced);
    const double current = exchange_gain(ldlt, pool[set[i]].j);
    for (ConstraintOutcome& o : result.constraints) {
      const unsigned alone = 1u << static_cast<unsigned>(o.constraint);
      for (std::size_t r = 0; r < rejected.size(); ++r) {
        if (rejected_mask[r] != alone) continue;
        const double ratio = std::pow(exchange_gain(ldlt, rejected[r].j) / current, 0.5 / static_cast<double>(p));
        if (ratio > 1.0 + 1e-9) o.active = true;
        o.index_gain = std::max(o.index_gain, ratio);
      }
    }
  }
  return result;
}

}  // namespace kincal::identify
