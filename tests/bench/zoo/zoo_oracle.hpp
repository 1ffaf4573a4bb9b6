// The zoo's oracle (issue #41): the truth's own structure (the parameters the error class changed,
// the registration and the measured point or frame) fitted by plain least squares -- Ceres'
// Levenberg-Marquardt with numeric derivatives of the zoo's forward kinematics, no prior, each row
// weighted by the instrument's true noise -- from the nominal chain, to convergence; the masses and
// the compliances of joints gravity barely loads are given (Truth::compliance_known). What the best
// fit of the right model reaches on the same rows; kincal's defaults are judged against it.
#pragma once

#include <random>
#include <vector>

#include "zoo_world.hpp"

namespace zoo {

struct OracleFit {
  Truth estimate;  // the fitted structure, in the truth's form (its noise copied from the truth)
  int iterations = 0;
  bool converged = false;
};

// Starts from the nominal chain, the measured point/frame as known to a few millimetres (the truth's
// moved 5 mm, turned 1 deg) and the rigid registration of the nominal points to the measured ones.
// geometry_only: the joints' origins and zeros alone, without the truth's scale, coupling or
// compliance -- what a URDF can carry, to tell kincal's defaults from the limits of its model.
OracleFit fit_oracle(const Chain& chain, const Truth& truth, const std::vector<Row>& train, std::mt19937& rng,
                     bool geometry_only = false);

}  // namespace zoo
