// The plausibility gate before any solve (issue #16): a dataset in the wrong units or the wrong
// quaternion order is still made of finite numbers, and a least-squares solve "converges" on it
// into an absurd model. These checks compare the data with the nominal model in ways that do
// not depend on the unknown registration (base_T_frame0) or tool (flange_T_tool):
//
//   joints        readings against the model's limits (1 % of the range tolerance); revolute
//                 readings beyond +-4 pi without limits. Likely cause named when the readings /
//                 (180/pi) (degrees given as radians) or / 1000 (mm given as m) would fit and the
//                 largest is more than twice the range's largest magnitude.
//   positions     the distance between consecutive rows, measured over predicted, median over
//                 the pairs the model moves by more than 1 cm: outside [0.7, 1.4] is implausible
//                 (1000: millimetres given as metres; 100, 39.4 and 3.28 within 15 %: centimetres,
//                 inches, feet). A rigid registration keeps distances.
//   orientations  the rotation between consecutive rows, measured M against predicted P, must be
//                 M = B P B^T for one registration rotation B: B is fitted (Kabsch on the rotation
//                 vectors of the pairs turning 5..150 degrees); above a median misfit of 10
//                 degrees the quaternions read as x,y,z,w, inverted (the JPL convention) or both
//                 are tried and named when they fit (4 x better); above 30 degrees the data are
//                 implausible though none fits (a model a few degrees off in every angle misses by
//                 up to about 16).
//                 (Unit norm is checked by the dataset reader.)
//   far points    a measured point farther from the median point than twice the model's own
//                 spread plus 0.5 m (a typing error), or more than 1 km from the device (1e308):
//                 the first is named by its line.
//   exact fit     the nominal model reproduces every point within 1e-9 m and the data carry no
//                 noise (no sigma/covariance columns, no --sigma): no noise level or uncertainty
//                 can be estimated from it (data made by `kincal predict`?).
//   mirror, joint conventions, logs out of step, a moved instrument   data_mistakes.hpp: fits, not scales.
//
// Cost: one forward kinematics per row. Finds nothing on data too short to compare (< 3 pairs).
#pragma once

#include <string>
#include <vector>

#include "host/model/dataset.hpp"
#include "host/model/robot_model.hpp"

namespace kincal::identify {

struct PlausibilityOptions {
  bool noise_given = false;  // the user stated the instrument noise (--sigma)
};

// What looks wrong, one sentence each with the numbers and the likely cause; empty: plausible.
std::vector<std::string> implausibilities(const model::RobotModel& nominal, const model::Dataset& data,
                                          const PlausibilityOptions& options = {});

// The `joints` check above on joint readings alone (a dataset's, or `correct`'s targets): one
// finding per joint with readings outside its limits; unit_mistake when they all fit divided by
// 57.3 (degrees) or 1000 (millimetres) and reach more than twice the range.
struct JointFinding {
  std::string text;
  bool unit_mistake = false;
};
std::vector<JointFinding> joint_readings_outside(const model::RobotModel& model,
                                                 const std::vector<std::vector<double>>& readings);

// Without a model (import without --model): the measured points' median distance from their
// median point above kMaxSpread_m (50 m; the largest arms reach 4 m, so a 1 m workspace in
// millimetres read as metres).
inline constexpr double kMaxSpread_m = 50.0;
std::vector<std::string> implausibilities(const model::Dataset& data);

// Throws model::InputError "FILE: implausible data: ..." listing every finding and naming
// `override_flag` (e.g. "--accept-implausible") to proceed deliberately.
void require_plausible(const model::RobotModel& nominal, const model::Dataset& data, const std::string& override_flag,
                       const PlausibilityOptions& options = {});

}  // namespace kincal::identify
