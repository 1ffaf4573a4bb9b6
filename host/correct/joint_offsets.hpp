// Mastering (joint-zero) offsets from a calibration (issue #24): what a controller that keeps its
// nominal kinematics can still take, and how much of the calibration they carry.
//
// offset_i = (theta_i + offset_i)_calibrated - (theta_i + offset_i)_nominal for a revolute joint
// (rad), the same with d for a prismatic one (m): the calibrated arm at reading r_i is where the
// nominal model puts it at r_i + offset_i. A controller that takes zero offsets as "joint angle =
// encoder angle + offset" takes them as they are; one that subtracts them takes their negatives.
// Everything else the calibration found -- link lengths and twists, Doty's beta, gear scales,
// compliance, the tool -- the offsets do not carry.
//
// How much they carry: three arms, each with the calibrated model's base registration and tool
// (a controller takes a TCP; the registration belongs to the measuring device): the nominal arm,
// the nominal arm with the offsets, the calibrated arm. On measured rows (a dataset: ideally rows
// that were not used to calibrate) their position errors; without measurements, each arm's tool
// against the calibrated arm's over random readings within the joint limits (what the
// calibration predicts, not what was measured).
// Throws model::InputError when the joint counts or a joint's type or link convention differ (the
// nominal from a calibration record always matches).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "host/model/dataset.hpp"
#include "host/model/robot_model.hpp"

namespace kincal::correct {

std::vector<double> joint_offsets(const model::RobotModel& nominal, const model::RobotModel& calibrated);

// The offsets that bring the nominal arm closest to the calibrated one: least squares of the tool
// points over `samples` random readings within the limits (Gauss-Newton from joint_offsets(), at
// most 8 steps), with a prior that holds each offset at its zero change with the weight of 10 mm
// of tool displacement per radian (or metre) at every reading: a joint whose turn hardly moves
// the tool point (a wrist turning a probe on its axis) keeps its zero change. Where the calibration also changed link
// lengths and twists, the zero changes alone can leave the arm worse than nominal (they compensate the other changes
// inside the calibrated model); these take what offsets can carry.
std::vector<double> fitted_joint_offsets(const model::RobotModel& nominal, const model::RobotModel& calibrated,
                                         int samples, std::uint64_t seed);

// The nominal arm with `offsets` added to its joint offsets, and the calibrated base and tool.
model::RobotModel offsets_only_model(const model::RobotModel& nominal, const model::RobotModel& calibrated,
                                     const std::vector<double>& offsets);

struct ArmErrors {
  double rms_m = 0.0, max_m = 0.0;
};
struct OffsetShare {
  int rows = 0;  // measured rows, or random readings
  ArmErrors nominal, offsets_only, calibrated;
  // 1 - offsets_only.rms / nominal.rms against the calibrated arm's own error: the part of the
  // calibration's improvement the offsets give, (nominal - offsets) / (nominal - calibrated) in RMS.
  double carried = 0.0;
};

// On measured rows (throws model::InputError when the dataset's joint count is not the model's).
OffsetShare offset_share(const model::RobotModel& nominal, const model::RobotModel& calibrated,
                         const std::vector<double>& offsets, const model::Dataset& data);
// Predicted: `samples` random readings (uniform within the limits, +-pi where a revolute joint has
// none, +-0.5 m for a prismatic one), seeded; calibrated errors are 0 by definition.
OffsetShare offset_share(const model::RobotModel& nominal, const model::RobotModel& calibrated,
                         const std::vector<double>& offsets, int samples, std::uint64_t seed);

// The file: '#' lines saying what the offsets are and their sign, then "joint,name,type,offset"
// rows (offset in rad or m, shortest exact decimal).
std::string write_joint_offsets(const model::RobotModel& calibrated, const std::vector<double>& offsets);

}  // namespace kincal::correct
