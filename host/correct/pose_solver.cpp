#include "host/correct/pose_solver.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <Eigen/Cholesky>
#include <Eigen/Geometry>
#include <Eigen/SVD>

namespace kincal::correct {

namespace {

struct Evaluation {
  Eigen::Matrix<double, 6, 1> e;
  double cost = 0.0;
};

Evaluation evaluate(const model::RobotModel& model, const model::Transform& goal, bool orientation,
                    const std::vector<double>& q, double weight) {
  Evaluation out;
  out.e = pose_residual(goal, model::forward_kinematics(model, q));
  if (!orientation) out.e.tail<3>().setZero();
  out.cost = out.e.head<3>().squaredNorm() + weight * weight * out.e.tail<3>().squaredNorm();
  return out;
}

bool reached(const Evaluation& at, const SolveOptions& o) {
  return at.e.head<3>().norm() <= o.tolerance_m && at.e.tail<3>().norm() <= o.tolerance_rad;
}

// No tool point of the arm is farther than this from frame 0's origin: each link translates by d
// along one axis and a along another (Doty's beta only turns), the tool by its offset; a
// prismatic joint's d by its variable within the limits (no bound without limits).
double reach_bound(const model::RobotModel& model) {
  double reach = model.flange_T_tool.translation.norm();
  for (const model::Joint& j : model.joints) {
    double d = std::abs(j.parameters.d_m + (j.type == core::JointType::prismatic ? j.offset : 0.0));
    if (j.type == core::JointType::prismatic) d += std::max(std::abs(j.lower), std::abs(j.upper));
    reach += d + std::abs(j.parameters.a_m);
  }
  return reach;
}

// The goal farther from frame 0's origin than reach_bound: out of reach whatever the readings.
bool beyond_reach(const model::RobotModel& model, const model::Transform& goal) {
  return (model.base_T_frame0.inverse() * goal).translation.norm() > reach_bound(model);
}

}  // namespace

const char* outcome_name(Outcome outcome) {
  switch (outcome) {
    case Outcome::reached:
      return "reached";
    case Outcome::joint_limit:
      return "joint-limit";
    case Outcome::out_of_reach:
      return "out-of-reach";
    case Outcome::singularity:
      return "singularity";
    case Outcome::joint_change_limit:
      return "joint-change-limit";
    case Outcome::not_converged:
      break;
  }
  return "not-converged";
}

Eigen::Matrix<double, 6, 1> pose_residual(const model::Transform& goal, const model::Transform& at) {
  Eigen::Matrix<double, 6, 1> e;
  e.head<3>() = goal.translation - at.translation;
  const Eigen::AngleAxisd r(Eigen::Matrix3d(goal.rotation * at.rotation.transpose()));
  e.tail<3>() = r.angle() * r.axis();
  return e;
}

namespace {

// One solve's fixed data: the goal, the weights and the joints' units (S of the header).
struct Problem {
  const model::RobotModel& model;
  const model::Transform& goal;
  bool orientation;
  const SolveOptions& o;
  Eigen::VectorXd scale;  // S's diagonal
  Eigen::Index rows() const { return orientation ? 6 : 3; }
  double lower(Eigen::Index i) const { return model.joints[static_cast<std::size_t>(i)].lower; }
  double upper(Eigen::Index i) const { return model.joints[static_cast<std::size_t>(i)].upper; }
};

// Where the solve stands: readings, residual and the weighted system at them.
struct State {
  std::vector<double> q;
  Evaluation at;
  Eigen::MatrixXd jw;            // W^1/2 J S
  Eigen::VectorXd ew, gradient;  // W^1/2 e, and Js^T W e (the cost's descent direction, up to 2)
  std::vector<bool> held;        // at a limit the descent pushes against
};

void linearize(const Problem& p, State& s) {
  const Eigen::Index n = p.scale.size();
  s.jw = model::joint_jacobian(p.model, s.q).topRows(p.rows()) * p.scale.asDiagonal();
  s.ew = s.at.e.head(p.rows());
  if (p.orientation) {
    s.jw.bottomRows(3) *= p.o.rotation_weight_m;
    s.ew.tail(3) *= p.o.rotation_weight_m;
  }
  s.gradient = s.jw.transpose() * s.ew;
  s.held.assign(static_cast<std::size_t>(n), false);
  for (Eigen::Index i = 0; i < n; ++i) {
    const double qi = s.q[static_cast<std::size_t>(i)], g = s.gradient(i);
    s.held[static_cast<std::size_t>(i)] = (qi <= p.lower(i) && g < 0.0) || (qi >= p.upper(i) && g > 0.0);
  }
}

// q + S du, clamped into the limits.
std::vector<double> moved(const Problem& p, const std::vector<double>& q, const Eigen::VectorXd& du) {
  std::vector<double> out = q;
  for (Eigen::Index i = 0; i < du.size(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    out[k] = std::clamp(out[k] + p.scale(i) * du(i), p.lower(i), p.upper(i));
  }
  return out;
}

// The damped steps of the header from s until reached, `budget` iterations or lambda above 1e8;
// counts the iterations into `iterations`.
void descend(const Problem& p, State& s, int budget, int& iterations) {
  double lambda = p.o.initial_damping;
  linearize(p, s);
  for (int k = 0; k < budget && !reached(s.at, p.o) && lambda < 1e8; ++k) {
    ++iterations;
    Eigen::MatrixXd a = s.jw.transpose() * s.jw;
    Eigen::VectorXd b = s.gradient;
    for (Eigen::Index i = 0; i < b.size(); ++i) {
      if (!s.held[static_cast<std::size_t>(i)]) continue;
      a.row(i).setZero();
      a.col(i).setZero();
      b(i) = 0.0;
    }
    a.diagonal().array() += lambda * lambda;
    std::vector<double> trial = moved(p, s.q, a.ldlt().solve(b));
    const Evaluation next = evaluate(p.model, p.goal, p.orientation, trial, p.o.rotation_weight_m);
    if (next.cost < s.at.cost) {
      s.q = std::move(trial);
      s.at = next;
      lambda = std::max(lambda / 3.0, 1e-12);
      linearize(p, s);
    } else {
      lambda *= 10.0;
    }
  }
}

// |S^-1 (q - reference)|.
double distance(const Problem& p, const std::vector<double>& q, std::span<const double> reference) {
  double sum = 0.0;
  for (Eigen::Index i = 0; i < p.scale.size(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    sum += std::pow((q[k] - reference[k]) / p.scale(i), 2);
  }
  return std::sqrt(sum);
}

// The walk of the header toward the reference from a reached s.
void approach(const Problem& p, State& s, std::span<const double> reference, int& iterations) {
  const Eigen::Index n = p.scale.size();
  for (int step = 0; step < p.o.max_nearest_steps; ++step) {
    linearize(p, s);
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(s.jw, Eigen::ComputeFullV);
    const Eigen::VectorXd& sigma = svd.singularValues();
    Eigen::Index rank = 0;
    while (rank < sigma.size() && sigma(rank) > 1e-9 * sigma(0)) ++rank;
    if (rank == n) return;  // no readings near these reach the goal but these
    Eigen::VectorXd r(n);
    for (Eigen::Index i = 0; i < n; ++i)
      r(i) = (reference[static_cast<std::size_t>(i)] - s.q[static_cast<std::size_t>(i)]) / p.scale(i);
    const Eigen::MatrixXd null = svd.matrixV().rightCols(n - rank);
    Eigen::VectorXd du = null * (null.transpose() * r);
    const double before = distance(p, s.q, reference);
    bool kept = false;
    for (int half = 0; half <= 5 && !kept; ++half, du *= 0.5) {
      if (du.norm() <= 1e-12 * std::max(1.0, before)) return;
      State trial;
      trial.q = moved(p, s.q, du);
      trial.at = evaluate(p.model, p.goal, p.orientation, trial.q, p.o.rotation_weight_m);
      descend(p, trial, p.o.max_iterations, iterations);
      if (!reached(trial.at, p.o) || distance(p, trial.q, reference) >= before) continue;
      s = std::move(trial);
      kept = true;
    }
    if (!kept) return;
  }
}

// The outcome of a solve that did not reach the goal (header).
Outcome not_reached(const Problem& p, const State& s) {
  if (beyond_reach(p.model, p.goal)) return Outcome::out_of_reach;
  if (std::find(s.held.begin(), s.held.end(), true) != s.held.end()) return Outcome::joint_limit;
  // How much of the residual the joints can still move along, first order: |Js^T W e| against
  // its largest possible value |W^1/2 Js| |W^1/2 e|. Near 0: a stationary point off the goal.
  const double largest = Eigen::JacobiSVD<Eigen::MatrixXd>(s.jw).singularValues()(0);
  if (largest * s.ew.norm() <= 0.0 || s.gradient.norm() < p.o.stall_cosine * largest * s.ew.norm()) {
    const model::Vector3 origin = p.model.base_T_frame0.translation;
    const double tool_distance = (model::forward_kinematics(p.model, s.q).translation - origin).norm();
    return (p.goal.translation - origin).norm() > tool_distance ? Outcome::out_of_reach : Outcome::singularity;
  }
  return Outcome::not_converged;
}

// Readings clamped into the limits: where a solve starts.
std::vector<double> clamped(const Problem& p, std::span<const double> q) {
  return moved(p, std::vector<double>(q.begin(), q.end()), Eigen::VectorXd::Zero(p.scale.size()));
}

// One solve's setup: the sizes checked, and S.
Problem problem(const model::RobotModel& model, const model::Transform& goal, bool orientation,
                std::span<const double> seed, const SolveOptions& o, std::span<const double> reference) {
  const int n = model.joint_count();
  if (static_cast<int>(seed.size()) != n || (!reference.empty() && static_cast<int>(reference.size()) != n))
    throw std::invalid_argument("solve_pose: the seed has " + std::to_string(seed.size()) + " readings" +
                                (reference.empty() ? "" : ", the reference " + std::to_string(reference.size())) +
                                ", for a model of " + std::to_string(n) + " joints");
  Problem p{model, goal, orientation, o, Eigen::VectorXd::Ones(n)};
  for (int i = 0; i < n; ++i)
    if (model.joints[static_cast<std::size_t>(i)].type == core::JointType::prismatic)
      p.scale(i) = o.prismatic_m_per_rad;
  return p;
}

// The goal's solve from s (its readings within the limits), the walk toward the reference and the
// outcome (header).
Solution finish(const Problem& p, State& s, std::span<const double> reference, int iterations) {
  Solution out;
  out.iterations = iterations;
  s.at = evaluate(p.model, p.goal, p.orientation, s.q, p.o.rotation_weight_m);
  descend(p, s, p.o.max_iterations, out.iterations);
  // A goal with as many rows as joints has isolated solutions (but exactly at a singularity): no
  // walk (its SVD would cost as much as the solve).
  if (reached(s.at, p.o) && p.rows() < p.scale.size()) approach(p, s, reference, out.iterations);
  out.q = s.q;
  out.residual_m = s.at.e.head<3>().norm();
  out.residual_rad = s.at.e.tail<3>().norm();
  out.outcome = reached(s.at, p.o) ? Outcome::reached : not_reached(p, s);
  return out;
}

}  // namespace

Solution solve_pose(const model::RobotModel& model, const model::Transform& goal, bool orientation,
                    std::span<const double> seed, const SolveOptions& o, std::span<const double> reference) {
  const Problem p = problem(model, goal, orientation, seed, o, reference);
  State s;
  s.q = clamped(p, seed);
  return finish(p, s, reference.empty() ? seed : reference, 0);
}

Solution solve_pose_along(const model::RobotModel& model, const model::Transform& goal, bool orientation,
                          std::span<const double> reference, const SolveOptions& o, int steps) {
  const Problem p = problem(model, goal, orientation, reference, o, {});
  State s;
  s.q = clamped(p, reference);
  const model::Transform start = model::forward_kinematics(model, s.q);
  const Eigen::AngleAxisd turn(Eigen::Matrix3d(goal.rotation * start.rotation.transpose()));
  int iterations = 0;
  // No way to follow to a goal past any tool point's reach; a step's solve needs only a few
  // iterations (the next one starts where it stopped).
  const bool beyond = beyond_reach(model, goal);
  for (int k = 1; k < steps && !beyond; ++k) {
    const double f = static_cast<double>(k) / steps;
    model::Transform on_path;
    on_path.translation = start.translation + f * (goal.translation - start.translation);
    on_path.rotation = Eigen::AngleAxisd(f * turn.angle(), turn.axis()).toRotationMatrix() * start.rotation;
    const Problem step{model, on_path, orientation, o, p.scale};
    s.at = evaluate(model, on_path, orientation, s.q, o.rotation_weight_m);
    descend(step, s, std::min(o.max_iterations, 10), iterations);
  }
  return finish(p, s, reference, iterations);
}

}  // namespace kincal::correct
