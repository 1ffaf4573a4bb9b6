#include "host/session/online_correction.hpp"

#include <cmath>
#include <ostream>

#include "host/correct/correction_block.hpp"

namespace kincal::session {

CorrectionCheck verify_online_correction(can::PlatformClient& client, bool fd, const Calibration& calibration,
                                         const SessionData& data, RobotDriver& driver, Sensor& sensor,
                                         std::ostream& log) {
  const identify::IdentifyResult& r = calibration.result;
  const shared::CorrectionParameters block = correct::correction_block(r.start, r.model);
  std::array<std::uint8_t, shared::kCorrectionBytes> image{};
  if (shared::encode_block(block, image) != image.size()) throw SessionError("correction block: encoding failed");
  CorrectionCheck check;
  try {
    client.set_mode(false, false);  // the platform takes parameters only when idle
    check.storage_sequence = client.upload(shared::ParameterBlock::kCorrection, image);
    const std::vector<std::uint8_t> back = client.download(shared::ParameterBlock::kCorrection);
    if (!std::equal(back.begin(), back.end(), image.begin(), image.end()))
      throw SessionError("the platform's copy of the correction parameters differs from the upload");
    client.set_mode(true, true);
  } catch (const can::PlatformError& e) {
    throw SessionError(std::string("uploading the correction parameters: ") + e.what());
  }
  log << "correction parameters uploaded (" << image.size() << " bytes, stored as copy " << check.storage_sequence
      << ") and read back identical\n";

  // The goal of each target: the controller's chain and tool, placed with the identified base.
  model::RobotModel goal_model = r.start;
  goal_model.base_T_frame0 = r.model.base_T_frame0;
  const model::RobotModel& nominal = r.start;
  std::vector<double> before, after;
  for (std::size_t i = 0; i < data.validation.rows.size(); ++i) {
    const model::Measurement& m = data.validation.rows[i];
    std::array<std::int32_t, shared::kJoints> raw{};
    for (std::size_t j = 0; j < m.q.size(); ++j) raw[j] = shared::quantize_joint_angle(m.q[j]);
    std::array<std::int32_t, shared::kJoints> corrected_raw{};
    try {
      corrected_raw = client.correct(raw, fd);
    } catch (const can::PlatformError& e) {
      throw SessionError("validation pose " + std::to_string(i) + ": the platform did not correct it: " + e.what());
    }
    std::vector<double> corrected(m.q.size());
    for (std::size_t j = 0; j < m.q.size(); ++j)
      corrected[j] = std::ldexp(static_cast<double>(corrected_raw[j]), -shared::kJointAngleFractionBits);
    const int index = static_cast<int>(data.calibration.rows.size() + i);
    const std::vector<double> readings = driver.move_to(index, corrected);
    const Observation o = sensor.measure(index, model::forward_kinematics(nominal, readings));
    const model::Vector3 goal = model::forward_kinematics(goal_model, m.q).translation;
    before.push_back((m.position - goal).norm());
    after.push_back((o.position - goal).norm());
  }
  check.before = identify::error_stats(before);
  check.after = identify::error_stats(after);
  return check;
}

}  // namespace kincal::session
