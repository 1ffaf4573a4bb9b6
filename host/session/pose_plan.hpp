// The poses a calibration session visits (issue #6): a plan file (`kincal plan`'s output, or any
// joints file: host/model/dataset.hpp's read_joints), or Kapucu & Baysec's single-joint sweeps.
//
// Sweeps: for each joint in turn, `readings_per_joint` values evenly spaced over `span_fraction`
// of its range (its limits; revolute joints without limits: 2 pi), centred on the home reading
// and shifted to stay within the limits; the other joints stay at home. circle_point_analysis
// (host/identify/cpa.hpp) finds them again as runs in which exactly one joint moves.
//
// Errors: model::InputError naming what is wrong (home outside the limits, fewer than 4 readings
// per joint -- a circle needs them --, a fraction outside (0, 1], a prismatic joint without
// limits, a plan whose joint count is not the model's).
#pragma once

#include <string>
#include <vector>

#include "host/model/robot_model.hpp"

namespace kincal::session {

using Configurations = std::vector<std::vector<double>>;

Configurations single_joint_sweeps(const model::RobotModel& model, const std::vector<double>& home,
                                   int readings_per_joint, double span_fraction);

// A plan file, checked against the model (joint count, limits).
Configurations read_plan(const model::RobotModel& model, const std::string& path);

}  // namespace kincal::session
