// Joint readings that put a model's tool at a goal pose or point: the damped Newton
// (Levenberg-Marquardt) solve behind `kincal correct` (issue #24), for Cartesian targets and for
// joint targets where the platform's first-order step is not enough, and among the readings that
// reach the goal the one nearest a reference (issue #42).
//
// Problem: min over readings q within [lower, upper] of |W^1/2 e(q)|^2, with
//   e(q) = [p_goal - p(q); log(R_goal R(q)^T)]   (rotation rows only when `orientation`)
//   W    = diag(1, 1, 1, L^2, L^2, L^2),  L = rotation_weight_m,
// p, R the model's forward_kinematics (its joint map, deflection and base included), in the frame
// forward_kinematics returns. Joint changes are measured in units u = S^-1 dq, S = diag(1 rad for a
// revolute joint, prismatic_m_per_rad for a prismatic one), so that a lift's metres and a turn's
// radians weigh as the caller's joint-change limits do. Step: du = (Js^T W Js + lambda^2 I)^-1
// Js^T W e over the joints that are free, Js = joint_jacobian(model, q) S; lambda starts at
// initial_damping, shrinks by 3 after a step that lowers the cost and grows by 10 after one that
// does not (the step is then not taken): near a singularity lambda bounds the step, away from one
// the solve is Gauss-Newton. A joint at a limit whose descent direction points out of its range is
// held there for the step (active set); every step is clamped into the limits; a seed outside them
// starts clamped.
//
// Nearest the reference (the seed unless given): where the arm has more joints than the goal has
// rows (a 7-joint arm, a point goal), the goal is reached by a set of readings, and the damped steps keep only each
// step's own change small -- over several steps turns can build up that cancel at the tool (tens of degrees on a
// 7-joint arm). Once reached, the solve walks along that set toward the reference: a step r projected onto the null
// space of W^1/2 Js (singular values below 1e-9 of the largest count as zero), r = S^-1 (reference - q), then the
// damped steps back onto the goal; the walk is kept while it reaches the goal nearer the reference (the step halved up
// to 5 times otherwise), at most max_nearest_steps times. It ends at readings whose change from the reference is
// orthogonal to the set (locally the nearest, in the units above); a goal that needs a large change still gets it. A
// goal with as many rows as the arm has joints has isolated solutions: no walk.
//
// Termination and outcome (Solution::outcome):
//   reached        position residual <= tolerance_m and (with orientation) rotation <= tolerance_rad;
//   out_of_reach   not reached, and the goal is farther from frame 0's origin than any tool point
//                  can be (sum of the links' |a| + |d|, prismatic travel, the tool's offset);
//   joint_limit    not reached, and a joint is held at a limit that the descent pushes against;
//   out_of_reach   also: not reached where the joints can no longer move the tool toward the goal
//                  (|Js^T W e| below stall_cosine times |W^1/2 Js|_2 |W^1/2 e|: a stationary point
//                  off the goal, where J is singular in the residual's direction) with the goal
//                  farther from frame 0's origin than the tool: the arm stretched toward it;
//   singularity    such a stationary point otherwise (folded, or a wrist singular for the goal);
//   not_converged  max_iterations used, or lambda above 1e8 (no step lowers the cost), none of the
//                  above.
// Only `reached` is a result to use; the others carry the best readings found and their residual.
// A local solve: it keeps the seed's configuration (elbow, wrist branch) and can stop in a local
// minimum that is not the goal (reported as not reached, never as reached).
// Cost per iteration: one forward kinematics and one Jacobian (each O(n) frames), an n x n solve;
// typically 2 to 5 iterations from a seed within a few millimetres, and for a redundant goal a few
// walk steps (an n x n SVD and 1 to 3 iterations each). Throws std::invalid_argument when the seed's
// or a given reference's size is not the model's joint count. Thread-safe (no shared state).
#pragma once

#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "host/model/robot_model.hpp"

namespace kincal::correct {

struct SolveOptions {
  double rotation_weight_m = 0.5;  // L: a radian weighs as L metres
  double tolerance_m = 1e-7;
  double tolerance_rad = 1e-7;
  int max_iterations = 60;
  double initial_damping = 1e-3;  // weighted metres
  double stall_cosine = 1e-2;
  // S's prismatic entry (see the top): the metres of a prismatic joint's travel that weigh as one
  // radian of a revolute joint's turn. Default: `kincal correct`'s default limits, 5 mm : 5 deg.
  double prismatic_m_per_rad = 5e-3 / (5.0 * std::numbers::pi / 180.0);
  int max_nearest_steps = 30;  // walk steps toward the reference once the goal is reached
};

// joint_change_limit is the target corrector's (target_correction.hpp), never solve_pose's: the
// target was reached only by moving a joint more than the caller allows.
enum class Outcome { reached, joint_limit, out_of_reach, singularity, not_converged, joint_change_limit };

// "reached", "joint-limit", "out-of-reach", "singularity", "not-converged", "joint-change-limit"
// (as files and messages write it).
const char* outcome_name(Outcome outcome);

struct Solution {
  std::vector<double> q;
  Outcome outcome = Outcome::not_converged;
  double residual_m = 0.0;    // |p_goal - p(q)|
  double residual_rad = 0.0;  // angle of R_goal R(q)^T (0 without orientation)
  int iterations = 0;
};

// `reference` empty: the seed (as given, before clamping).
Solution solve_pose(const model::RobotModel& model, const model::Transform& goal, bool orientation,
                    std::span<const double> seed, const SolveOptions& options = {},
                    std::span<const double> reference = {});

// The goal followed from the reference: the goal moved in `steps` equal steps from the tool's pose
// at the reference readings (clamped into the limits; position along the line, rotation about one
// axis) to `goal`, each solved from the readings of the step before, then the goal itself as
// solve_pose does (walk, outcome). A local solve ends on the branch its start leads to: started
// from readings just past a stretched elbow (the controller's readings for a target next to the
// stretch), it reaches the mirrored elbow, degrees from the reference (the zoo's draw 5,
// kr16_2/tracker-6dof/coupled/100: joint 3 6.75 deg where the true arm needs 0.12); steps of a
// fraction of the correction from the reference itself keep the branch the reference is on. A goal
// past any tool point's reach (the out_of_reach bound above) is solved directly. Cost: up to
// `steps` times 10 iterations more than a solve's.
Solution solve_pose_along(const model::RobotModel& model, const model::Transform& goal, bool orientation,
                          std::span<const double> reference, const SolveOptions& options = {}, int steps = 20);

// The twist e(q) of the top comment (6 rows; the rotation rows exact, not first-order).
Eigen::Matrix<double, 6, 1> pose_residual(const model::Transform& goal, const model::Transform& at);

}  // namespace kincal::correct
