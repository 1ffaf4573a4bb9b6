#include "host/correct/platform_step.hpp"

#include "firmware/app/kinematic_correction.hpp"
#include "host/correct/correction_block.hpp"

namespace kincal::correct {

struct PlatformStep::Model {
  app::PreparedCorrection prepared{};
  int joints = 0;
};

PlatformStep::PlatformStep(const model::RobotModel& controller, const model::RobotModel& calibrated)
    : m_(std::make_unique<Model>()) {
  switch (app::prepare_block(correction_block(controller, calibrated), m_->prepared)) {
    case app::PrepareStatus::kOk:
      break;
    case app::PrepareStatus::kNotAChain:
      throw model::InputError("the correction block is not a chain the platform can read (a beta on a DH link)");
    case app::PrepareStatus::kModelRefused:
      throw model::InputError("the platform refuses the correction model");
    case app::PrepareStatus::kJointMapRefused:
      throw model::InputError("the platform refuses the joint map (a scale not above 0, a singular coupling)");
  }
  m_->joints = controller.joint_count();
}

PlatformStep::~PlatformStep() = default;

std::optional<std::vector<double>> PlatformStep::correct(std::span<const double> readings) {
  core::JointVector<float> q = core::JointVector<float>::Zero(), corrected = q;
  for (int i = 0; i < m_->joints; ++i) q(i) = static_cast<float>(readings[static_cast<std::size_t>(i)]);
  app::PreparedCorrection& p = m_->prepared;
  if (core::correct_joint_readings(p.model, p.joint_map, p.workspace, q, p.correction, corrected) !=
      core::CorrectionStatus::ok)
    return std::nullopt;
  std::vector<double> out(static_cast<std::size_t>(m_->joints));
  for (int i = 0; i < m_->joints; ++i) out[static_cast<std::size_t>(i)] = static_cast<double>(corrected(i));
  return out;
}

}  // namespace kincal::correct
