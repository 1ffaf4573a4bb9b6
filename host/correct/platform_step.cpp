#include "host/correct/platform_step.hpp"

#include "firmware/app/correction_chain.hpp"
#include "firmware/core/correction.hpp"
#include "host/session/online_correction.hpp"

namespace kincal::correct {

struct PlatformStep::Model {
  core::ChainModel<float> nominal{};
  core::ParameterSet ids{};
  core::ErrorVector<float> errors{};
  core::CorrectionModel model{};
  core::CorrectionWorkspace workspace{};
  core::JointMapModel map{};
  core::Correction correction{};
  int joints = 0;
};

PlatformStep::PlatformStep(const model::RobotModel& controller, const model::RobotModel& calibrated)
    : m_(std::make_unique<Model>()) {
  const shared::CorrectionParameters block = session::correction_block(controller, calibrated);
  if (app::correction_chain(block, m_->nominal, m_->ids, m_->errors) != app::ChainStatus::kOk)
    throw model::InputError("the correction block is not a chain the platform can read (a beta on a DH link)");
  if (core::prepare_correction(m_->nominal, m_->ids, m_->errors, core::CorrectionOptions{}, m_->model) !=
      core::CorrectionStatus::ok)
    throw model::InputError("the platform refuses the correction model");
  if (app::correction_joint_maps(block, m_->map.nominal, m_->map.identified, m_->map.masses) != app::ChainStatus::kOk ||
      core::prepare_joint_map(m_->model, m_->map.nominal, m_->map.identified, m_->map.masses, m_->workspace, m_->map) !=
          core::CorrectionStatus::ok)
    throw model::InputError("the platform refuses the joint map (a scale not above 0, a singular coupling)");
  m_->joints = controller.joint_count();
}

PlatformStep::~PlatformStep() = default;

std::optional<std::vector<double>> PlatformStep::correct(std::span<const double> readings) {
  core::JointVector<float> q = core::JointVector<float>::Zero(), corrected = q;
  for (int i = 0; i < m_->joints; ++i) q(i) = static_cast<float>(readings[static_cast<std::size_t>(i)]);
  if (core::correct_joint_readings(m_->model, m_->map, m_->workspace, q, m_->correction, corrected) !=
      core::CorrectionStatus::ok)
    return std::nullopt;
  std::vector<double> out(static_cast<std::size_t>(m_->joints));
  for (int i = 0; i < m_->joints; ++i) out[static_cast<std::size_t>(i)] = static_cast<double>(corrected(i));
  return out;
}

}  // namespace kincal::correct
