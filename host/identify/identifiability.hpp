// Which parameters a dataset can identify: rank of the identification Jacobian by its singular
// values, and a choice of identifiable parameters, naming the ones held fixed and why.
//
// The columns of the whitened Jacobian (one per candidate parameter) are scaled to unit length,
// which makes the analysis independent of units (m vs rad). Candidates are taken in the order
// given -- the caller's order of preference -- and a candidate is kept when the part of its
// column outside the span of those already kept is longer than `tolerance` (the sine of its
// angle to that span; 1e-6 by default: exact dependencies, such as a base rotation about axis 1
// and theta1, come out near 1e-12, while a poorly excited but identifiable parameter stays far
// above, and its large standard deviation says the rest). A dependent parameter is named with
// the kept parameters it is a combination of.
#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

#include "host/identify/problem.hpp"

namespace kincal::identify {

struct HeldFixed {
  core::ParameterId id;
  std::string reason;
};

struct Identifiability {
  ParameterIds identified;            // in candidate order
  std::vector<HeldFixed> held_fixed;  // dependent or without effect on the measurements
  int rank = 0;                       // numerical rank of the scaled Jacobian (SVD)
  double condition = 0.0;             // of the scaled Jacobian of the identified parameters
  Eigen::VectorXd singular_values;    // of the scaled Jacobian of all candidates
};

Identifiability analyze_identifiability(const Eigen::MatrixXd& jacobian, const ParameterIds& candidates,
                                        double tolerance = 1e-6);

}  // namespace kincal::identify
