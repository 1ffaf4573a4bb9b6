// The correction step the platform applies to every streamed joint target: firmware/core's
// online correction (correction.hpp) with the calibrated chain of the correction block.
//
// What: the robot controller computes joint targets q_nom with its nominal model, expecting the
// tool at FK_nominal(q_nom). The real arm follows the calibrated model (nominal + identified
// errors), so it would put the tool at FK_calibrated(q_nom). correct() returns the target q_corr
// with FK_calibrated(q_corr) = FK_nominal(q_nom) to the correction's order, each FK through its
// model's joint map (coupling, scale, gravity compliance: core::correct_joint_readings): core's damped
// first-order step plus one chord refinement (CorrectionOptions defaults: rotation weight 0.5 m,
// damping 1e-3, at most 0.05 rad (or m) of correction per joint). How the block becomes the two
// chains: correction_chain.hpp (each joint's type and convention, tool offset and its error).
// Joints at and beyond joint_count pass through unchanged. The result is quantized to the
// protocol's 2^-16 rad, rounded to nearest (shared::quantize_joint_angle, saturating).
//
// Loading: the block is read into a CorrectionModel the first time correct() sees it and again
// whenever its contents differ from the copy the model was built from (a field-by-field compare,
// ~60 float compares per call), so an uploaded block takes effect on the next joint target.
// Statuses: kNoParameters when joint_count is 0 or the block cannot be read as a chain
// (correction_chain.hpp: a beta on a DH link, or prepare_correction refuses it); kNotCorrectable when a
// joint value is beyond core::kSinCosMaxArgumentRad or the correction would move a joint by more
// than 0.05 rad (a singular configuration or parameters far off): `out` is then not written.
// Cost (M4F, 6 joints): about 4.8k instructions per target (correction_m4_instructions), 8.3k
// with coupling, scale and compliance (correction_joint_map_m4_instructions), plus preparing the
// model when the block changed (two chains' trigonometry, the coupling's inverse). Memory: the
// model, joint map, workspace and a copy of the block inside the object (5,728 bytes on the M4): construct it
// statically, not on a small stack. Thread/ISR safety: main loop only (one workspace).
#pragma once

#include <cstdint>

#include "firmware/app/ports.hpp"
#include "firmware/core/correction.hpp"

namespace kincal::app {

// A correction block read as two chains (correction_chain.hpp) and prepared for
// core::correct_joint_readings(model, joint_map, workspace, q, correction, out): the one reading of
// a block the platform and the host's copy of its step (host/correct/platform_step.hpp) share.
struct PreparedCorrection {
  core::ChainModel<float> nominal{};
  core::ParameterSet parameter_ids{};
  core::ErrorVector<float> errors{};
  core::CorrectionModel model{};
  core::CorrectionWorkspace workspace{};
  core::Correction correction{};
  core::JointMapModel joint_map{};  // read from the block in place, then prepared
};

// Which step refused the block: kNotAChain (correction_chain: no joints, or a beta on a DH link),
// kModelRefused (core::prepare_correction), kJointMapRefused (correction_joint_maps or
// core::prepare_joint_map: a coupling beyond the joints, a scale not above 0, a singular coupling).
// `out` is only usable on kOk.
enum class [[nodiscard]] PrepareStatus : std::uint8_t{kOk, kNotAChain, kModelRefused, kJointMapRefused};
PrepareStatus prepare_block(const shared::CorrectionParameters& block, PreparedCorrection& out) noexcept;

class KinematicCorrection {
 public:
  CorrectStatus correct(const shared::CorrectionParameters& parameters, const JointRaw& in, JointRaw& out) noexcept;

 private:
  void load(const shared::CorrectionParameters& parameters) noexcept;

  bool loaded_ = false;  // loaded_block_ is the block the model was built from
  bool usable_ = false;  // ... and it gave a model
  shared::CorrectionParameters loaded_block_{};
  PreparedCorrection prepared_{};
  core::JointVector<float> corrected_ = core::JointVector<float>::Zero();
};

static_assert(CorrectionStep<KinematicCorrection>);

}  // namespace kincal::app
