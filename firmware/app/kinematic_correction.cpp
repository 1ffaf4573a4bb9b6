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

PrepareStatus prepare_block(const shared::CorrectionParameters& block, PreparedCorrection& out) noexcept {
  if (correction_chain(block, out.nominal, out.parameter_ids, out.errors) != ChainStatus::kOk)
    return PrepareStatus::kNotAChain;
  if (core::prepare_correction(out.nominal, out.parameter_ids, out.errors, core::CorrectionOptions{}, out.model) !=
      core::CorrectionStatus::ok)
    return PrepareStatus::kModelRefused;
  core::JointMapModel& map = out.joint_map;
  if (correction_joint_maps(block, map.nominal, map.identified, map.masses) != ChainStatus::kOk ||
      core::prepare_joint_map(out.model, map.nominal, map.identified, map.masses, out.workspace, map) !=
          core::CorrectionStatus::ok)
    return PrepareStatus::kJointMapRefused;
  return PrepareStatus::kOk;
}

void KinematicCorrection::load(const shared::CorrectionParameters& parameters) noexcept {
  loaded_block_ = parameters;
  loaded_ = true;
  usable_ = prepare_block(parameters, prepared_) == PrepareStatus::kOk;
}

CorrectStatus KinematicCorrection::correct(const shared::CorrectionParameters& parameters, const JointRaw& in,
                                           JointRaw& out) noexcept {
  if (parameters.joint_count == 0) return CorrectStatus::kNoParameters;
  if (!loaded_ || !same_block(parameters, loaded_block_)) load(parameters);
  if (!usable_) return CorrectStatus::kNoParameters;
  PreparedCorrection& p = prepared_;
  const int n = p.model.nominal.joint_count;
  core::JointVector<float> q = core::JointVector<float>::Zero();
  for (int i = 0; i < n; ++i) q(i) = shared::joint_angle_rad<float>(in[static_cast<std::size_t>(i)]);
  if (core::correct_joint_readings(p.model, p.joint_map, p.workspace, q, p.correction, corrected_) !=
      core::CorrectionStatus::ok)
    return CorrectStatus::kNotCorrectable;
  out = in;
  for (int i = 0; i < n; ++i) out[static_cast<std::size_t>(i)] = shared::quantize_joint_angle(corrected_(i));
  return CorrectStatus::kOk;
}

}  // namespace kincal::app
