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
// A real robot is more than a perturbed chain (Imperfections, all off by default): its links and
// payload have mass and its joints give way under the gravity torque (the model's compliance,
// robot_model.hpp, in the truth), its controller may report coupled joints (the truth keeps the
// nominal's coupling), and it does not return exactly to where it was: each visit draws its own
// joint-angle error and tool jitter, from the seed and the visit's number (so a resumed session
// sees the same robot).
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
  double scale_sigma = 2e-4;  // the joint scales a model declares (gear-ratio error)
};

// What the truth has beyond the perturbed geometry (see the header comment). Zero: nothing.
struct Imperfections {
  double link_mass_kg_per_m = 0.0;       // links without a mass: this per metre between their frame
                                         // origins (at zero readings), centred between them
  double payload_kg = 0.0;               // at the tool point, when the model has no payload
  double compliance_rad_per_Nm = 0.0;    // added to every revolute joint's compliance (joints
                                         // whose axis is along gravity feel no torque)
  double joint_repeatability_rad = 0.0;  // per visit and joint, Gaussian (prismatic: m)
  double position_jitter_m = 0.0;        // per visit and axis, Gaussian, at the tool
};

// Imperfections of a real arm of a given reach: sag and repeatability about as laser-tracker
// data show them (tenths of a millimetre on a 2 m arm, a few hundredths on a desk robot).
Imperfections typical_imperfections(double reach_m);

// An arm's reach for that: the sum of its links' |a| and |d| and of the tool's offset (m).
double reach_m(const model::RobotModel& model);

// A true robot drawn around `nominal` (see the header comment). Scales get a Gaussian error of
// scale_sigma; compliances keep the nominal's value.
model::RobotModel perturbed(const model::RobotModel& nominal, std::mt19937_64& rng, const ErrorScale& scale = {});

// `truth` with the masses, payload and compliance of `imperfections` (no randomness).
model::RobotModel with_imperfections(const model::RobotModel& truth, const Imperfections& imperfections);

// Joint readings uniform within each joint's limits ([-pi, pi] where a limit is infinite).
std::vector<double> random_configuration(const model::RobotModel& model, std::mt19937_64& rng);
std::vector<std::vector<double>> random_configurations(const model::RobotModel& model, int count, std::mt19937_64& rng);

class SimulatedRobot {
 public:
  SimulatedRobot(model::RobotModel nominal, std::uint64_t seed, const ErrorScale& scale = {},
                 const Imperfections& imperfections = {});

  const model::RobotModel& nominal() const { return nominal_; }
  // The hidden truth: for tests and for judging a calibration, never for the session's solver.
  const model::RobotModel& truth() const { return truth_; }

  // device_T_tool of the true robot at joint readings q (checked against the nominal limits),
  // without the repeatability error.
  model::Transform tool_pose(std::span<const double> q) const;

  // The same on visit number `visit`, with that visit's repeatability error, and without the
  // limit check (a corrected target may lie a hair beyond a limit).
  model::Transform visit_pose(std::span<const double> q, std::uint64_t visit) const;

  const Imperfections& imperfections() const { return imperfections_; }

 private:
  model::RobotModel nominal_;
  model::RobotModel truth_;
  Imperfections imperfections_;
  std::uint64_t seed_;
};

}  // namespace kincal::sim
