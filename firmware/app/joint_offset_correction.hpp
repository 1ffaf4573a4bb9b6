// The correction step this build applies: the identified joint zero offsets.
//
// What: corrected_i = q_i - error_i.theta_rad for the arm's joint_count joints (the others pass
// through), where error.theta is the identified deviation of joint i's zero (true = nominal +
// error): commanding q - error makes the real joint stand where the nominal model puts q.
// Joint zero offsets are the largest kinematic errors of most arms; the full first-order
// correction (the Jacobian of all identified deviations) replaces this step when the geometry
// module lands, behind the same CorrectionStep concept (firmware/app/ports.hpp).
// Cost: 6 float subtractions and conversions. Memory: none. Thread/ISR safety: pure.
// Failure modes: kNoParameters when joint_count is 0; results saturate at the +-8 rad range.
#pragma once

#include "firmware/app/ports.hpp"

namespace kincal::app {

class JointOffsetCorrection {
 public:
  CorrectStatus correct(const shared::CorrectionParameters& parameters, const JointRaw& in, JointRaw& out);
};

static_assert(CorrectionStep<JointOffsetCorrection>);

}  // namespace kincal::app
