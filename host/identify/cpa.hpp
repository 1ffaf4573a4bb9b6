// Circle-point analysis (after Kapucu & Baysec, done with the statistics they left out):
// single-joint sweeps in the data -> one 3-D circle (revolute) or line (prismatic) per joint ->
// joint axes -> a DH/Doty model (model/axes.hpp).
//
// Sweeps: maximal runs of consecutive rows in which exactly one joint's reading changes, with
// at least 4 rows (the test below needs 3 m - 9 > 0). With several sweeps of a joint the longest
// is used (noted).
//
// Per sweep, with the readings q_k of the moving joint (the commanded increments):
//   classify  fit p = c + v q and p = c + v q + w q^2 by weighted least squares; the joint
//             moves on a curve if the quadratic term is significant: chi-square test of the
//             drop in whitened residual (3 dof) when every point has a covariance, F test
//             (3, 3m - 9) otherwise; significance 1e-3. A result that contradicts the model's
//             joint type is an error (the message gives the p-value).
//   revolute  p_k = c + r R [cos q_k, sin q_k, 0]^T over all points: linear weighted least
//             squares of p = c + a cos q + b sin q for a start, then Ceres (automatic
//             derivatives) on the constrained model -- centre c, rotation R (angle-axis), radius
//             r -- with each point whitened by its covariance and a Huber loss. The axis is
//             R's z through c, signed so positive q turns counter-clockwise about it.
//   prismatic p_k = c + u q_k, |u| = 1 (metres of travel per metre of reading), the same way.
//   outliers  points whose whitened squared residual exceeds the chi-square(3) quantile
//             1 - outlier_probability are dropped and the sweep refitted, until none is (at
//             most 5 rounds; a sweep must keep 4 points). Without covariances the noise is the
//             residual RMS (median-based while rejecting), so rejection is scale-free.
// Axes measured with earlier joints away from zero are carried back to all-zero readings by
// the inverse joint motions about/along the axes already found (product of exponentials), and
// the tool point (frame) at zero readings is the mean of every sweep point carried back the same
// way. chain_from_axes() then writes the model (Doty where consecutive axes are nearly parallel).
#pragma once

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

std::vector<Sweep> find_sweeps(const model::Dataset& data);

struct CpaOptions {
  double sigma_m = 0.0;  // for rows without covariance; 0: estimate per sweep
  double outlier_probability = 1e-3;
  double significance = 1e-3;
  double parallel_tolerance_rad = 0.1;
};

struct SweepFit {
  int joint = 0;
  bool curved = false;    // the classification
  double p_value = 1.0;   // of "no curvature"
  model::AxisLine axis;   // as measured, device frame
  double radius_m = 0.0;  // revolute
  int used = 0;
  std::vector<int> rejected_lines;
  double rms_m = 0.0;  // of the fit's residuals
};

struct CpaResult {
  RobotModel model;
  std::vector<SweepFit> fits;  // one per joint
  std::vector<std::string> notes;
};

// Throws model::InputError (no sweep of a joint, a sweep that contradicts the joint type).
CpaResult circle_point_analysis(const RobotModel& nominal, const model::Dataset& data, const CpaOptions& options);

}  // namespace kincal::identify
