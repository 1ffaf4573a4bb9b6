#include "firmware/app/kinematic_correction.hpp"

#include "firmware/app/correction_chain.hpp"
#include "shared/protocol.hpp"

namespace kincal::app {

namespace {

bool same_values(const shared::DhValues& a, const shared::DhValues& b) {
  return a.a_m == b.a_m && a.alpha_rad == b.alpha_rad && a.d_m == b.d_m && a.theta_rad == b.theta_rad &&
         a.beta_rad == b.beta_rad;
}

// Field by field: the struct has padding, so its bytes cannot be compared.
bool same_block(const shared::CorrectionParameters& a, const shared::CorrectionParameters& b) {
  if (a.joint_count != b.joint_count || a.tool_offset != b.tool_offset || a.tool_error != b.tool_error) return false;
  for (std::size_t j = 0; j < shared::kJoints; ++j) {
    const shared::JointModel &x = a.joints[j], &y = b.joints[j];
    if (x.type != y.type || x.convention != y.convention || !same_values(x.nominal, y.nominal) ||
        !same_values(x.error, y.error))
      return false;
    const shared::JointMapValues &u = a.joint_maps[j], &w = b.joint_maps[j];
    if (u.coupled != w.coupled || u.coupling != w.coupling || u.scale != w.scale || u.scale_error != w.scale_error ||
        u.compliance != w.compliance || u.compliance_error != w.compliance_error || u.mass_kg != w.mass_kg ||
        u.centre_of_mass_m != w.centre_of_mass_m)
      return false;
  }
  return a.payload_mass_kg == b.payload_mass_kg && a.payload_centre_of_mass_m == b.payload_centre_of_mass_m &&
         a.gravity_mps2 == b.gravity_mps2;
}

}  // namespace

void KinematicCorrection::load(const shared::CorrectionParameters& parameters) noexcept {
  loaded_block_ = parameters;
  loaded_ = true;
  usable_ = correction_chain(parameters, nominal_, parameter_ids_, errors_) == ChainStatus::kOk &&
            core::prepare_correction(nominal_, parameter_ids_, errors_, core::CorrectionOptions{}, model_) ==
                core::CorrectionStatus::ok &&
            correction_joint_maps(parameters, joint_map_.nominal, joint_map_.identified, joint_map_.masses) ==
                ChainStatus::kOk &&
            core::prepare_joint_map(model_, joint_map_.nominal, joint_map_.identified, joint_map_.masses, workspace_,
                                    joint_map_) == core::CorrectionStatus::ok;
}

CorrectStatus KinematicCorrection::correct(const shared::CorrectionParameters& parameters, const JointRaw& in,
                                           JointRaw& out) noexcept {
  if (parameters.joint_count == 0) return CorrectStatus::kNoParameters;
  if (!loaded_ || !same_block(parameters, loaded_block_)) load(parameters);
  if (!usable_) return CorrectStatus::kNoParameters;
  const int n = model_.nominal.joint_count;
  core::JointVector<float> q = core::JointVector<float>::Zero();
  for (int i = 0; i < n; ++i) q(i) = shared::joint_angle_rad<float>(in[static_cast<std::size_t>(i)]);
  if (core::correct_joint_readings(model_, joint_map_, workspace_, q, correction_, corrected_) !=
      core::CorrectionStatus::ok)
    return CorrectStatus::kNotCorrectable;
  out = in;
  for (int i = 0; i < n; ++i) out[static_cast<std::size_t>(i)] = shared::quantize_joint_angle(corrected_(i));
  return CorrectStatus::kOk;
}

}  // namespace kincal::app
