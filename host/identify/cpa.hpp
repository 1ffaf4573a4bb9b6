// Circle-point analysis (after Kapucu & Baysec, done with the statistics they left out):
// single-joint sweeps in the data -> one 3-D circle (revolute) or line (prismatic) per joint ->
// joint axes -> a DH/Doty model (model/axes.hpp). The same sweep fits serve `kincal discover`
// (discover.hpp), which has no model and takes each joint's type from the test below.
//
// Sweeps: maximal runs of consecutive rows in which exactly one joint's reading changes (by more
// than still_tolerance), with at least 4 rows. With several sweeps of a joint the longest is used
// (noted). Steps may be uneven, larger than half a turn, and a sweep may span several turns:
// every fit uses the joint readings q_k as the known angles (stroke), never the order of the arc.
//
// Per sweep, with each point whitened by its covariance (or by sigma_m, or by 1: the scale is
// always estimated from the data, the covariance gives only its shape):
//   screen    the general model p = c + v q + a cos q + b sin q (12 parameters, linear) holds
//             for both joint types. Points are judged by their studentized deleted residual
//             under it (leverage included; F(3, dof - 3), Bonferroni over the sweep): the worst
//             is dropped while its family-wise p-value is below outlier_probability, at most
//             max_rejected_fraction of the sweep. Needs 6 points; smaller sweeps are not screened.
//   type      two tests against the general model, exact F tests for Gaussian noise:
//             p_line   H0 prismatic: the points are affine in q (p = c + v q);
//             p_circle H0 revolute: the points lie on a circle at angle q (7 parameters; nonlinear,
//                      so the F distribution holds to first order).
//             With too few points for an F test (dof 0) and a known noise level (covariance on
//             every row, or sigma_m) the drop in whitened residual is taken as chi-square. The
//             verdict is revolute when only the line is rejected at `significance`, prismatic
//             when only the circle is. When both fit (a short sweep) a third test decides:
//             p_unit_speed, H0 "a line at unit speed" (a prismatic joint moves 1 m per metre of
//             reading, a revolute one r per radian): prismatic unless it is rejected. When neither
//             fits, the smaller Akaike criterion (circle 7 parameters, unit line 5). Such verdicts
//             are marked inconclusive.
//   fit       revolute: p_k = c + r R [cos q_k, sin q_k, 0]^T (linear start, then Ceres on centre,
//             rotation, radius); the axis is R's z through c, signed so positive q turns
//             counter-clockwise about it. prismatic: p_k = c + u q_k, |u| = 1 (metres of travel
//             per metre of reading). Weighted least squares on the screened points.
//   spread    the fit's covariance (Gauss-Newton, scaled by the residual variance over its dof)
//             gives the axis direction's and position's standard deviations and the radius's.
// Axes measured with earlier joints away from zero are carried back to all-zero readings by the
// inverse joint motions about/along the axes already found (product of exponentials), and the
// tool point (frame) at zero readings is the mean of every sweep point carried back the same way.
//
// A joint type that disagrees with the model file is never a refusal: cpa fits the declared type
// and notes the evidence (both p-values).
#pragma once

#include <optional>
#include <span>
#include <string>
#include <vector>

#include "host/identify/problem.hpp"
#include "host/model/axes.hpp"
#include "host/model/dataset.hpp"

namespace kincal::identify {

struct Sweep {
  int joint = 0;          // 0-based
  std::vector<int> rows;  // indices into the dataset, in file order
};

// A joint whose reading changes by no more than still_tolerance (rad or m) counts as still.
std::vector<Sweep> find_sweeps(const model::Dataset& data, double still_tolerance = 0.0);

struct CpaOptions {
  double sigma_m = 0.0;                // for rows without covariance (shape only: the scale is estimated)
  double outlier_probability = 1e-3;   // family-wise per sweep
  double max_rejected_fraction = 0.2;  // of a sweep's points
  double significance = 0.01;          // of the joint-type tests
  double parallel_tolerance_rad = 0.1;
  double still_tolerance = 0.0;
};

struct TypeTest {
  bool tested = false;        // false: too few points and unknown noise; the verdict is by fit only
  double p_line = 1.0;        // of "affine in q" (prismatic)
  double p_circle = 1.0;      // of "on a circle at angle q" (revolute)
  double p_unit_speed = 1.0;  // of "on a line at 1 m per unit of reading" (prismatic, scale known)
  int residual_dof = 0;       // of the general model
  core::JointType verdict = core::JointType::revolute;
  bool conclusive = false;  // exactly one of the two hypotheses rejected
};

struct SweepFit {
  int joint = 0;
  core::JointType type = core::JointType::revolute;  // fitted (declared, or the verdict)
  bool curved = false;                               // type == revolute
  double p_value = 1.0;                              // test.p_line
  TypeTest test;
  bool contradicts_model = false;  // cpa: the declared type's hypothesis rejected
  model::AxisLine axis;            // as measured (device frame, the sweep's other readings)
  double radius_m = 0.0;           // revolute
  // 1-sigma spreads: angle of the direction, position of the line normal to it, radius.
  double direction_stddev_rad = 0.0, position_stddev_m = 0.0, radius_stddev_m = 0.0;
  // The axis's covariance in the basis (position along n1, n2; direction along n1, n2), where
  // n1, n2 are the columns of normal_basis, both normal to the direction.
  Eigen::Matrix4d axis_covariance = Eigen::Matrix4d::Zero();
  Eigen::Matrix<double, 3, 2> normal_basis = Eigen::Matrix<double, 3, 2>::Zero();
  double noise_scale = 1.0;         // residual RMS in whitened units (1: the stated covariance holds)
  double rms_m = 0.0;               // of the fit's residuals
  double q_min = 0.0, q_max = 0.0;  // readings swept (range of mobility observed)
  int first_line = 0, last_line = 0;
  int used = 0;
  std::vector<int> rejected_lines;
};

// Every joint's sweep fitted (declared[j], or the test's verdict where it is empty), the axes
// carried back to all-zero readings and the tool at zero readings.
struct SweepAnalysis {
  std::vector<SweepFit> fits;                       // one per joint
  std::vector<std::vector<double>> sweep_readings;  // the other joints' readings during each sweep
  std::vector<model::AxisLine> zero_axes;
  model::Transform tool_home;  // device_T_tool at all-zero readings (rotation: identity without orientations)
  std::vector<std::string> notes;
};

// Throws model::InputError naming the joint without a sweep, or whose sweep's measured points (and
// orientations, when used) move by less than 1 um (1 urad): such a sweep shows no axis; and naming
// the tolerance when options.still_tolerance is at or above every step of a joint that moves (it
// leaves the joint still in every row).
SweepAnalysis analyse_sweeps(const model::Dataset& data, std::span<const std::optional<core::JointType>> declared,
                             bool use_orientation, const CpaOptions& options);

// Axes measured during sweeps (measured[j] with the readings sweep_readings[j]) carried back to
// all-zero readings.
std::vector<model::AxisLine> axes_at_zero(std::span<const model::AxisLine> measured,
                                          std::span<const std::vector<double>> sweep_readings);

struct CpaResult {
  RobotModel model;
  std::vector<SweepFit> fits;  // one per joint
  std::vector<std::string> notes;
};

// Throws model::InputError (no sweep of a joint, joint count).
CpaResult circle_point_analysis(const RobotModel& nominal, const model::Dataset& data, const CpaOptions& options);

// One line about a sweep fit for printouts: type, p-values, points, radius, spreads, rejections.
std::string describe(const SweepFit& fit);

}  // namespace kincal::identify
