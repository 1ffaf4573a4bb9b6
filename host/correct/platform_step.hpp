// The platform's online correction step on the host (issue #24): the correction block of two host
// models (correct::correction_block, correction_block.hpp) read by the platform's own app::prepare_block
// (firmware/app/kinematic_correction.hpp) and applied with
// core::correct_joint_readings -- the same float code the platform runs, without the protocol's
// 2^-16 rad quantization of the result. joint_correction.hpp builds on it; tests compare it with
// app::KinematicCorrection.
// Construction throws model::InputError when the block cannot be built (joint counts, types or
// conventions differ, coupling or masses differ, more joints than the protocol carries) or the
// platform would refuse it (the message says which). correct() is not thread-safe (one float
// workspace); memory about 8 KB, on the heap.
#pragma once

#include <memory>
#include <optional>
#include <span>
#include <vector>

#include "host/model/robot_model.hpp"

namespace kincal::correct {

class PlatformStep {
 public:
  PlatformStep(const model::RobotModel& controller, const model::RobotModel& calibrated);
  ~PlatformStep();
  PlatformStep(const PlatformStep&) = delete;
  PlatformStep& operator=(const PlatformStep&) = delete;

  // The corrected readings, or nullopt where the platform refuses (a correction above 0.05 rad,
  // a value beyond sin_cos's range: core::CorrectionStatus). readings.size() must be the joint count.
  std::optional<std::vector<double>> correct(std::span<const double> readings);

 private:
  struct Model;
  std::unique_ptr<Model> m_;
};

}  // namespace kincal::correct
