// How the platform reads the correction parameter block (shared::CorrectionParameters) as a
// kinematic chain for firmware/core's correction: written once, templated on the scalar, so the
// host computes its double-precision reference of the correction from the very same reading
// (host/can/scenario.cpp) and the firmware its float correction (kinematic_correction.hpp).
//
// The reading (format version 2 of the block, shared/parameters.hpp):
//   joints 0..joint_count-1   each with its type (revolute: the streamed joint value adds to theta,
//                             in rad; prismatic: to d, in m, same 2^-16 LSB) and link convention
//                             (standard DH, modified DH, Doty's; link_model.hpp);
//   nominal                   the values the robot controller's own model uses;
//   error                     identified deviations, true = nominal + error (error_model.hpp's
//                             link parameters: d, theta, a, alpha, and beta for Doty's links);
//   beta on a DH link         must be 0 (nominal and error): DH has no pitch parameter, and a
//                             block that sets one describes a chain this reading cannot represent;
//   tool_offset               the nominal flange_T_tool: translation x y z (m) and rotation vector
//                             rx ry rz (axis * angle, rad; rotation_vector.hpp);
//   tool_error                its identified error: error_model.hpp's tool_x..tool_rz, a small
//                             motion along and about the tool frame's own axes;
//   base                      base_T_frame0 is the identity, with no error.
//   joint map (format 3)      correction_joint_maps(): the coupling rows (a joint without its
//                             flag: its own reading), nominal scale and compliance, identified =
//                             nominal + error, for two core::JointMap; masses, centres of mass,
//                             payload and gravity as a core::MassModel (joint_map.hpp). Whether the
//                             map is usable (scales > 0, coupling invertible) is for
//                             core::prepare_joint_map to judge; a coupling coefficient on a joint
//                             at or beyond joint_count is kBadCoupling.
// Statuses: kNoJoints (joint_count 0 or above core::kMaxJoints), kPitchSet (a beta on a DH link).
// Outputs are written only on kOk. Cost: O(joints), no trigonometry but the tool's rotation
// (one sin_cos); no heap; stack a few hundred bytes (the outputs are the caller's).
#pragma once

#include <cstdint>

#include "firmware/app/rotation_vector.hpp"
#include "firmware/core/error_model.hpp"
#include "firmware/core/joint_map.hpp"
#include "firmware/core/link_model.hpp"
#include "shared/parameters.hpp"

namespace kincal::app {

enum class [[nodiscard]] ChainStatus : std::uint8_t{kOk, kNoJoints, kPitchSet, kBadCoupling};

template <class S>
ChainStatus correction_chain(const shared::CorrectionParameters& block, core::ChainModel<S>& nominal,
                             core::ParameterSet& parameters, core::ErrorVector<S>& errors) noexcept {
  if (block.joint_count == 0 || block.joint_count > core::kMaxJoints || block.joint_count > shared::kJoints)
    return ChainStatus::kNoJoints;
  for (std::size_t j = 0; j < block.joint_count; ++j) {
    const shared::JointModel& joint = block.joints[j];
    if (joint.convention != shared::LinkKind::kDoty && (joint.nominal.beta_rad != 0.0f || joint.error.beta_rad != 0.0f))
      return ChainStatus::kPitchSet;
  }
  nominal.joint_count = block.joint_count;  // links beyond it are not read
  nominal.base_T_frame0 = core::RigidTransform<S>{};
  for (std::size_t j = 0; j < block.joint_count; ++j) {
    const shared::JointModel& joint = block.joints[j];
    const shared::DhValues& v = joint.nominal;
    core::Link<S>& link = nominal.links[j];
    link.convention = joint.convention == shared::LinkKind::kStandardDh   ? core::LinkConvention::standard_dh
                      : joint.convention == shared::LinkKind::kModifiedDh ? core::LinkConvention::modified_dh
                                                                          : core::LinkConvention::doty;
    link.joint = joint.type == shared::JointKind::kPrismatic ? core::JointType::prismatic : core::JointType::revolute;
    link.parameters = {S(v.d_m), S(v.theta_rad), S(v.a_m), S(v.alpha_rad), S(v.beta_rad)};
  }
  const auto& t = block.tool_offset;
  nominal.flange_T_tool.translation = core::Vector3<S>(S(t[0]), S(t[1]), S(t[2]));
  nominal.flange_T_tool.rotation = rotation_from_vector(core::Vector3<S>(S(t[3]), S(t[4]), S(t[5])));

  parameters = core::full_parameter_set(nominal, false, true);
  errors.setZero();
  for (int i = 0; i < parameters.count; ++i) {
    const core::ParameterId id = parameters.ids[static_cast<std::size_t>(i)];
    const shared::DhValues& e = block.joints[id.link].error;
    const auto& tool = block.tool_error;
    float value = 0.0f;
    switch (id.kind) {
      case core::ParameterKind::link_d:
        value = e.d_m;
        break;
      case core::ParameterKind::link_theta:
        value = e.theta_rad;
        break;
      case core::ParameterKind::link_a:
        value = e.a_m;
        break;
      case core::ParameterKind::link_alpha:
        value = e.alpha_rad;
        break;
      case core::ParameterKind::link_beta:
        value = e.beta_rad;
        break;
      case core::ParameterKind::tool_x:
        value = tool[0];
        break;
      case core::ParameterKind::tool_y:
        value = tool[1];
        break;
      case core::ParameterKind::tool_z:
        value = tool[2];
        break;
      case core::ParameterKind::tool_rx:
        value = tool[3];
        break;
      case core::ParameterKind::tool_ry:
        value = tool[4];
        break;
      case core::ParameterKind::tool_rz:
        value = tool[5];
        break;
      default:
        break;  // base motions: not in the block, and not asked of full_parameter_set
    }
    errors(i) = S(value);
  }
  return ChainStatus::kOk;
}

template <class S>
ChainStatus correction_joint_maps(const shared::CorrectionParameters& block, core::JointMap<S>& nominal,
                                  core::JointMap<S>& identified, core::MassModel<S>& masses) noexcept {
  if (block.joint_count == 0 || block.joint_count > core::kMaxJoints || block.joint_count > shared::kJoints)
    return ChainStatus::kNoJoints;
  const int n = block.joint_count;
  for (int i = 0; i < n; ++i) {
    const shared::JointMapValues& m = block.joint_maps[static_cast<std::size_t>(i)];
    for (std::size_t k = static_cast<std::size_t>(n); m.coupled && k < shared::kJoints; ++k)
      if (m.coupling[k] != 0.0f) return ChainStatus::kBadCoupling;
  }
  nominal = core::JointMap<S>{};
  nominal.joint_count = n;
  masses = core::MassModel<S>{};
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const shared::JointMapValues& m = block.joint_maps[k];
    if (m.coupled)
      for (int c = 0; c < n; ++c) nominal.coupling(i, c) = S(m.coupling[static_cast<std::size_t>(c)]);
    nominal.scale(i) = S(m.scale);
    nominal.compliance(i) = S(m.compliance);
    masses.link_mass_kg[k] = S(m.mass_kg);
    for (std::size_t r = 0; r < 3; ++r) masses.link_centre_of_mass_m[k][r] = S(m.centre_of_mass_m[r]);
  }
  identified = nominal;
  for (int i = 0; i < n; ++i) {
    const shared::JointMapValues& m = block.joint_maps[static_cast<std::size_t>(i)];
    identified.scale(i) = S(m.scale) + S(m.scale_error);
    identified.compliance(i) = S(m.compliance) + S(m.compliance_error);
  }
  masses.payload_mass_kg = S(block.payload_mass_kg);
  for (std::size_t r = 0; r < 3; ++r) {
    masses.payload_centre_of_mass_m[r] = S(block.payload_centre_of_mass_m[r]);
    masses.gravity_mps2[r] = S(block.gravity_mps2[r]);
  }
  return ChainStatus::kOk;
}

}  // namespace kincal::app
