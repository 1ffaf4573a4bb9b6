// Readings a calibrated model was not calibrated at: the joint readings its data covered (the
// calibration record's reading_ranges) against those a command is about to use -- correct's
// solutions, predict's rows. A joint that never moved in the data was calibrated at that one
// reading: elsewhere the model's error includes its axis, which the data could not show, and the
// record's standard deviations (zero for what was held) do not count it.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "host/model/dataset.hpp"
#include "host/model/robot_model.hpp"

namespace kincal::model {

// Per joint, the lowest and highest reading of the rows (SI); [0, 0] without rows. Requires rows
// with data.joint_count readings.
std::vector<std::array<double, 2>> reading_ranges(const Dataset& data);

// What `readings` take beyond the recorded ranges by more than kSameReading: a warning per joint
// that never moved in the data, and one note (extrapolated) for the other joints together.
// `what` names the readings ("targets", "rows"). Empty when the model records no ranges.
struct CoverageFinding {
  bool still = false;  // the joint never moved in the calibration data
  std::string text;
};
std::vector<CoverageFinding> readings_outside_calibration(const RobotModel& model,
                                                          const std::vector<std::vector<double>>& readings,
                                                          const std::string& what);

}  // namespace kincal::model
