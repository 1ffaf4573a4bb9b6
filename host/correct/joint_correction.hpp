// Joint targets corrected on the PC (issue #24): readings r that a controller computed with its
// nominal model become readings r* at which the calibrated arm puts its tool where the nominal
// model promised, frame 0 to tool:  FK_calibrated(r*) = FK_controller(r)  (both without the base
// registration, which belongs to the measuring device, not to the arm -- as the platform's online
// correction, host/session/online_correction.hpp).
//
// One correction, two places. When the two models can be read as the platform's correction block
// (correct::correction_block, correction_block.hpp: same joints and link conventions, at most
// shared::kJoints joints; identify's starting model and its result always can), correct() first
// runs the very step the platform runs on every streamed target -- firmware/core's
// correct_joint_readings (damped first-order step plus one chord refinement, float, through the joint map;
// platform_step.hpp) -- so the PC and the platform give the same readings to within float rounding. Where that step
// leaves more than accept_m / accept_rad at the tool (measured in double on the host models), or refuses (a step above
// 0.05 rad), correct() goes on with the damped Newton solve of pose_solver.hpp on the calibrated model, from the
// platform's readings (or from r), to the readings nearest r that reach the goal. Without a block (models the block
// cannot carry) the Newton solve does it all; platform_step() says which.
//
// Costs: the platform step a few microseconds, each Newton iteration one FK and one Jacobian.
// Not thread-safe: correct() uses the object's float workspace (one object per thread).
#pragma once

#include <memory>
#include <span>
#include <string>

#include "host/correct/platform_step.hpp"
#include "host/correct/pose_solver.hpp"
#include "host/model/robot_model.hpp"

namespace kincal::correct {

struct JointCorrectionOptions {
  SolveOptions solve;
  double accept_m = 1e-5;     // the platform step's result is kept when it leaves at most this ...
  double accept_rad = 1e-5;   // ... and this at the tool; else the Newton solve refines it
  bool platform_step = true;  // false: the Newton solve alone
  // false: only the tool point is corrected (the tool's orientation left free; the Newton solve
  // moves the joints the least it can). For a point tool, or a tool frame whose identified rotation
  // is a measuring convention rather than the arm's (see JointCorrector's constructor).
  bool orientation = true;
};

struct JointCorrection {
  Solution solution;                // the corrected readings, residual and outcome (frame 0 to tool)
  model::Transform goal;            // FK_controller(r) without the base registration
  bool platform_step_used = false;  // the platform's step ran and gave a result
  bool refined = false;             // the Newton solve ran after it (or instead of it)
};

class JointCorrector {
 public:
  // Throws model::InputError when the joint counts differ.
  JointCorrector(const model::RobotModel& controller, const model::RobotModel& calibrated,
                 const JointCorrectionOptions& options = {});
  ~JointCorrector();
  JointCorrector(const JointCorrector&) = delete;
  JointCorrector& operator=(const JointCorrector&) = delete;

  // Throws std::invalid_argument when readings.size() is not the joint count, and model::InputError
  // when `orientation` is set and the two tools' rotations differ by more than 0.05 rad (the
  // platform's largest step): such a rotation is usually the measuring device's convention for the
  // tool frame (a tracker's probe frame turned 90 degrees about its axis), and following it would
  // turn the wrist; the message says so and names the way out (orientation = false, or a nominal
  // model with the calibrated tool).
  JointCorrection correct(std::span<const double> readings);

  // Whether the platform's step is in use, and if not why not (empty when it is).
  bool platform_step() const;
  const std::string& platform_note() const;

  // The calibrated model without its base registration: where correct()'s readings are evaluated.
  const model::RobotModel& calibrated_arm() const;

 private:
  model::RobotModel controller_, calibrated_;
  JointCorrectionOptions options_;
  double tool_turn_rad_ = 0.0;  // the angle between the two tools' rotations
  std::unique_ptr<PlatformStep> platform_;
  std::string note_;
};

// The model a calibration started from, rebuilt from the calibrated model's record (each
// identified parameter's change undone: link values and the joint map's scales and compliances
// subtracted, the base's and tool's small motions inverted exactly). Its conventions are the
// calibrated model's. Throws model::InputError when the model has no calibration record or the
// record names a parameter the model does not have.
model::RobotModel nominal_from_record(const model::RobotModel& calibrated);

}  // namespace kincal::correct
