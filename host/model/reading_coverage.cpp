#include "host/model/reading_coverage.hpp"

#include <algorithm>
#include <iomanip>
#include <numbers>
#include <sstream>

namespace kincal::model {

std::vector<std::array<double, 2>> reading_ranges(const Dataset& data) {
  std::vector<std::array<double, 2>> out(static_cast<std::size_t>(data.joint_count), {0.0, 0.0});
  for (std::size_t j = 0; j < out.size() && !data.rows.empty(); ++j) {
    const auto [low, high] = std::ranges::minmax_element(data.rows, {}, [j](const Measurement& m) { return m.q[j]; });
    out[j] = {low->q[j], high->q[j]};
  }
  return out;
}

std::vector<CoverageFinding> readings_outside_calibration(const RobotModel& model,
                                                          const std::vector<std::vector<double>>& readings,
                                                          const std::string& what) {
  std::vector<CoverageFinding> out;
  if (!model.calibration || model.calibration->reading_ranges.size() != model.joints.size()) return out;
  std::ostringstream outside;  // the joints moved beyond their range, on one line
  outside << std::fixed << std::setprecision(1);
  std::vector<bool> beyond(readings.size(), false);
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const auto [low, high] = model.calibration->reading_ranges[j];
    int count = 0;
    double largest = 0.0;
    for (std::size_t i = 0; i < readings.size(); ++i) {
      const double excess = std::max(low - readings[i][j], readings[i][j] - high);
      if (excess <= kSameReading) continue;
      ++count;
      largest = std::max(largest, excess);
      if (low != high) beyond[i] = true;
    }
    if (count == 0) continue;
    const bool revolute = model.joints[j].type == core::JointType::revolute;
    const double unit = revolute ? 180.0 / std::numbers::pi : 1e3;
    const char* symbol = revolute ? " deg" : " mm";
    const std::string joint = "joint " + std::to_string(j + 1) + " (" + model.joints[j].name + ")";
    if (low == high) {
      std::ostringstream text;
      text << std::fixed << std::setprecision(1) << count << " of " << readings.size() << ' ' << what << " move "
           << joint << " from " << low * unit << symbol
           << ", the one reading it had in the calibration data (it never moved), by up to " << largest * unit << symbol
           << ": there the model's error includes that joint's axis, which the data could not calibrate, and the "
              "prediction's spread does not count it";
      out.push_back({true, text.str()});
    } else {
      outside << (outside.tellp() > 0 ? "; " : "") << joint << " by up to " << largest * unit << symbol << " ("
              << low * unit << " to " << high * unit << symbol << " covered)";
    }
  }
  const auto extrapolated = std::count(beyond.begin(), beyond.end(), true);
  if (extrapolated > 0)
    out.push_back({false, std::to_string(extrapolated) + " of " + std::to_string(readings.size()) + ' ' + what +
                              " lie outside the readings the calibration data covered, where the model is "
                              "extrapolated: " +
                              outside.str()});
  return out;
}

}  // namespace kincal::model
