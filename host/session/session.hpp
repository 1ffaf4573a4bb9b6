// A calibration session (issue #6): visit every pose of the plan with a robot driver, measure
// with a sensor, append each measurement to the journal the moment it arrives, then identify the
// model and judge it on validation poses measured the same way.
//
// Durability: the journal (journal.hpp) is fsync'd after every record, so a session killed at
// any moment and started again with resume = true skips the poses already recorded and gives
// the same dataset, in plan order, as an uninterrupted run: nothing lost, nothing twice. The
// journal's header holds the session's identity (model, plan, options); resuming a journal of
// another session is refused.
//
// Fail fast: the first failure of the driver or the sensor (no platform on the bus, a frame
// without the target, a surface that is not flat) stops the session with a SessionError naming
// the pose; what was measured before it stays in the journal for --resume.
//
// Validation: poses the identification never sees; their errors under the nominal and the
// identified model are the before/after accuracy the report shows.
#pragma once

#include <iosfwd>
#include <map>
#include <string>
#include <vector>

#include "host/identify/identify.hpp"
#include "host/model/dataset.hpp"
#include "host/session/pose_plan.hpp"
#include "host/session/robot_driver.hpp"
#include "host/session/sensor.hpp"

namespace kincal::session {

struct SessionPlan {
  Configurations calibration;  // poses for the identification
  Configurations validation;   // poses to judge it on
  int total() const { return static_cast<int>(calibration.size() + validation.size()); }
};

struct SessionOptions {
  std::string journal_path;
  bool resume = false;
  // What makes two sessions the same one (model, plan, options): KEY -> VALUE items of the
  // journal's header (journal.hpp: keys of [A-Za-z0-9_.-]), each named when it differs on resume.
  std::map<std::string, std::string> identity;
  bool progress_terminal = false;  // redraw the progress line in place
};

struct SessionData {
  model::Dataset calibration, validation;
  int resumed = 0;  // poses restored from the journal instead of measured
};

// Measures every pose of the plan not yet in the journal; returns all of them, in plan order.
// Throws SessionError (driver, sensor, journal) or model::InputError (the journal's identity).
SessionData run_session(const model::RobotModel& nominal, const SessionPlan& plan, RobotDriver& driver, Sensor& sensor,
                        const SessionOptions& options, std::ostream& log);

struct Calibration {
  identify::IdentifyResult result;
  identify::AccuracyStats before, after;  // nominal and identified model on the validation poses
};

// Identifies the model from the session's data and judges it on the validation poses.
Calibration calibrate(const model::RobotModel& nominal, const SessionData& data,
                      const identify::IdentifyOptions& options);

}  // namespace kincal::session
