// How a calibration session moves the robot (issue #6): one interface, three drivers.
//
//   simulated  (host/demo, over host/sim) the simulated robot goes where it is told; what the platform sees
//              follows from its true (hidden) model.
//   manual     the operator jogs the robot to the pose shown and confirms with Enter, or types
//              the readings the robot's pendant shows if they differ from the target.
//   command    a command the user supplies is run once per pose, e.g.
//              `--robot-cmd 'mymove {q}'`: {q} becomes the target joint values, space-separated,
//              in SI units (rad, m) with 9 significant digits; the command runs under /bin/sh
//              and must exit 0 once the robot stands still at the pose. If its standard output
//              holds exactly as many numbers as the robot has joints, they are the readings;
//              otherwise the target is the reading.
//
// move_to() returns the joint readings at which the measurement is taken: the dataset records
// readings, not targets, because the robot may settle elsewhere. Errors throw SessionError naming
// the pose and what failed (command exit status, operator abort, wrong number of readings).
// Thread safety: one session thread.
#pragma once

#include <iosfwd>
#include <string>
#include <vector>

#include "host/session/session_error.hpp"

namespace kincal::session {

class RobotDriver {
 public:
  virtual ~RobotDriver() = default;
  // Moves to `target` (pose number `index` of the plan) and returns the readings there.
  virtual std::vector<double> move_to(int index, const std::vector<double>& target) = 0;
  virtual std::string name() const = 0;
};

class ManualRobotDriver : public RobotDriver {
 public:
  // `prompt` shows the target and instructions; `answers` gives Enter, readings or "q" to stop.
  ManualRobotDriver(std::istream& answers, std::ostream& prompt) : answers_(answers), prompt_(prompt) {}
  std::vector<double> move_to(int index, const std::vector<double>& target) override;
  std::string name() const override { return "manual"; }

 private:
  std::istream& answers_;
  std::ostream& prompt_;
};

class CommandRobotDriver : public RobotDriver {
 public:
  // Throws SessionError if the template has no {q}.
  explicit CommandRobotDriver(std::string command_template);
  std::vector<double> move_to(int index, const std::vector<double>& target) override;
  std::string name() const override { return "command '" + template_ + "'"; }

 private:
  std::string template_;
};

// The command line for `target` ({q} replaced); exported for tests.
std::string expand_robot_command(const std::string& command_template, const std::vector<double>& target);

// The numbers in `text` if it holds exactly `count` of them (whitespace or comma separated),
// else an empty vector.
std::vector<double> parse_readings(const std::string& text, std::size_t count);

}  // namespace kincal::session
