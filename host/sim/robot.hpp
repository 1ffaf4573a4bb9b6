// A simulated robot (issue #6): the true robot is the nominal model with hidden errors in every
// kinematic parameter, drawn once from a seed; the calibration session commands joint readings
// and the simulator answers with the true tool pose. Also the random draws the identification
// tests and benchmarks share (perturbed models, configurations within the joint limits).
//
// The truth is parameterized as identify() works (identify::reparameterize_for_identification:
// Doty's parameters at nearly parallel axes, modified DH otherwise), every parameter of it
// (model::all_parameters: links, joint offsets, base and tool) off by a Gaussian error of the
// ErrorScale's sigma. Its forward kinematics equals the nominal's to within those errors.
//
// Cost: perturbed() is one reparameterization (microseconds); tool_pose() one forward kinematics.
// Errors: std::invalid_argument naming what is wrong: a joint vector of the wrong length, a
// non-finite reading, a reading outside the joint's limits; model::InputError from the model
// code for a model the identification cannot reparameterize.
#pragma once

#include <cstdint>
#include <numbers>
#include <random>
#include <span>
#include <vector>

#include "host/model/robot_model.hpp"

namespace kincal::sim {

// Standard deviations of the hidden errors.
struct ErrorScale {
  double length_m = 1e-3;
  double angle_rad = 0.1 * std::numbers::pi / 180.0;
  double base_length_m = 5e-3;
  double base_angle_rad = 0.5 * std::numbers::pi / 180.0;
};

// Whether a parameter is an angle (rad) rather than a length (m).
bool is_angle(core::ParameterKind kind);

// A true robot drawn around `nominal` (see the header comment).
model::RobotModel perturbed(const model::RobotModel& nominal, std::mt19937_64& rng, const ErrorScale& scale = {});

// Joint readings uniform within each joint's limits ([-pi, pi] where a limit is infinite).
std::vector<double> random_configuration(const model::RobotModel& model, std::mt19937_64& rng);
std::vector<std::vector<double>> random_configurations(const model::RobotModel& model, int count, std::mt19937_64& rng);

class SimulatedRobot {
 public:
  SimulatedRobot(model::RobotModel nominal, std::uint64_t seed, const ErrorScale& scale = {});

  const model::RobotModel& nominal() const { return nominal_; }
  // The hidden truth: for tests and for judging a calibration, never for the session's solver.
  const model::RobotModel& truth() const { return truth_; }

  // device_T_tool of the true robot at joint readings q (checked against the nominal limits).
  model::Transform tool_pose(std::span<const double> q) const;

 private:
  model::RobotModel nominal_;
  model::RobotModel truth_;
};

}  // namespace kincal::sim
