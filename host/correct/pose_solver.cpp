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

Solution solve_pose(const model::RobotModel& model, const model::Transform& goal, bool orientation,
                    std::span<const double> seed, const SolveOptions& o) {
  const int n = model.joint_count();
  if (static_cast<int>(seed.size()) != n)
    throw std::invalid_argument("solve_pose: the seed has " + std::to_string(seed.size()) +
                                " readings for a model of " + std::to_string(n) + " joints");
  const auto lower = [&](int i) { return model.joints[static_cast<std::size_t>(i)].lower; };
  const auto upper = [&](int i) { return model.joints[static_cast<std::size_t>(i)].upper; };
  Solution s;
  s.q.assign(seed.begin(), seed.end());
  for (int i = 0; i < n; ++i)
    s.q[static_cast<std::size_t>(i)] = std::clamp(s.q[static_cast<std::size_t>(i)], lower(i), upper(i));
  const double w = o.rotation_weight_m;
  const Eigen::Index rows = orientation ? 6 : 3;
  Evaluation at = evaluate(model, goal, orientation, s.q, w);
  double lambda = o.initial_damping;
  Eigen::MatrixXd jw;
  Eigen::VectorXd ew, gradient;
  std::vector<bool> held(static_cast<std::size_t>(n), false);
  const auto weighted_system = [&] {
    jw = model::joint_jacobian(model, s.q).topRows(rows);
    ew = at.e.head(rows);
    if (orientation) {
      jw.bottomRows(3) *= w;
      ew.tail(3) *= w;
    }
    gradient = jw.transpose() * ew;  // the descent direction of the cost (up to a factor 2)
    for (int i = 0; i < n; ++i) {
      const double qi = s.q[static_cast<std::size_t>(i)], g = gradient(i);
      held[static_cast<std::size_t>(i)] = (qi <= lower(i) && g < 0.0) || (qi >= upper(i) && g > 0.0);
    }
  };
  weighted_system();
  while (!reached(at, o) && s.iterations < o.max_iterations && lambda < 1e8) {
    ++s.iterations;
    Eigen::MatrixXd a = jw.transpose() * jw;
    Eigen::VectorXd b = gradient;
    for (int i = 0; i < n; ++i) {
      if (!held[static_cast<std::size_t>(i)]) continue;
      a.row(i).setZero();
      a.col(i).setZero();
      b(i) = 0.0;
    }
    a.diagonal().array() += lambda * lambda;
    const Eigen::VectorXd step = a.ldlt().solve(b);
    std::vector<double> trial = s.q;
    for (int i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      trial[k] = std::clamp(trial[k] + step(i), lower(i), upper(i));
    }
    const Evaluation next = evaluate(model, goal, orientation, trial, w);
    if (next.cost < at.cost) {
      s.q = std::move(trial);
      at = next;
      lambda = std::max(lambda / 3.0, 1e-12);
      weighted_system();
    } else {
      lambda *= 10.0;
    }
  }
  s.residual_m = at.e.head<3>().norm();
  s.residual_rad = at.e.tail<3>().norm();
  if (reached(at, o)) {
    s.outcome = Outcome::reached;
    return s;
  }
  if ((model.base_T_frame0.inverse() * goal).translation.norm() > reach_bound(model)) {
    s.outcome = Outcome::out_of_reach;
    return s;
  }
  if (std::find(held.begin(), held.end(), true) != held.end()) {
    s.outcome = Outcome::joint_limit;
    return s;
  }
  // How much of the residual the joints can still move along, first order: |J^T W e| against
  // its largest possible value |W^1/2 J| |W^1/2 e|. Near 0: a stationary point off the goal.
  const double largest = Eigen::JacobiSVD<Eigen::MatrixXd>(jw).singularValues()(0);
  if (largest * ew.norm() <= 0.0 || gradient.norm() < o.stall_cosine * largest * ew.norm()) {
    const model::Vector3 origin = model.base_T_frame0.translation;
    const double tool_distance = (model::forward_kinematics(model, s.q).translation - origin).norm();
    s.outcome = (goal.translation - origin).norm() > tool_distance ? Outcome::out_of_reach : Outcome::singularity;
    return s;
  }
  s.outcome = Outcome::not_converged;
  return s;
}

}  // namespace kincal::correct
