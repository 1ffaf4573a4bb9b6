#include "firmware/app/joint_offset_correction.hpp"

#include "shared/protocol.hpp"

namespace kincal::app {

CorrectStatus JointOffsetCorrection::correct(const shared::CorrectionParameters& parameters, const JointRaw& in,
                                             JointRaw& out) {
  if (parameters.joint_count == 0) return CorrectStatus::kNoParameters;
  for (std::size_t j = 0; j < shared::kJoints; ++j) {
    if (j >= parameters.joint_count) {
      out[j] = in[j];
      continue;
    }
    const float q_rad = shared::joint_angle_rad<float>(in[j]);
    out[j] = shared::quantize_joint_angle(q_rad - parameters.joints[j].error.theta_rad);
  }
  return CorrectStatus::kOk;
}

}  // namespace kincal::app
