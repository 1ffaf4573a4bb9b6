// The readings a calibration covered (host/model/reading_coverage.hpp): recorded from the data,
// written and read back with the model, and the readings beyond them named -- a joint that never
// moved as a warning, the rest as one note.
#include "host/model/reading_coverage.hpp"

#include <doctest/doctest.h>

#include "host/model/model_file.hpp"

namespace model = kincal::model;

namespace {

constexpr const char* kTwoJoints = R"(name: two
joints:
  - {name: shoulder, type: revolute, convention: dh, d: 0.3, theta: 0, a: 0.5, alpha: 0}
  - {name: lift, type: prismatic, convention: dh, d: 0, theta: 0, a: 0.2, alpha: 0}
tool:
  point: [0, 0, 0.1]
)";

model::RobotModel two_joints() { return model::parse_model(kTwoJoints, "two.yaml"); }

std::string model_error(const std::string& calibration) {
  try {
    (void)model::parse_model(std::string(kTwoJoints) + calibration, "two.yaml");
  } catch (const model::InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("reading ranges: recorded from the data, written with the model and read back bit for bit") {
  model::Dataset data;
  data.joint_count = 2;
  for (const double q : {0.25, -0.5, 1.0 / 3.0}) {
    model::Measurement m;
    m.q = {q, 0.1};
    data.rows.push_back(m);
  }
  const auto ranges = model::reading_ranges(data);
  REQUIRE(ranges.size() == 2);
  CHECK(ranges[0] == std::array<double, 2>{-0.5, 1.0 / 3.0});
  CHECK(ranges[1] == std::array<double, 2>{0.1, 0.1});

  model::RobotModel m = two_joints();
  m.calibration = model::CalibrationRecord{};
  m.calibration->reading_ranges = ranges;
  const model::RobotModel again = model::parse_model(model::write_model(m), "again.yaml");
  REQUIRE(again.calibration);
  CHECK(again.calibration->reading_ranges == ranges);

  CHECK(model_error("calibration: {reading_ranges: [[0, 1]]}\n").find("one [lowest, highest] per joint (2)") !=
        std::string::npos);
  CHECK(model_error("calibration: {reading_ranges: [[0, 1], [2, 1]]}\n").find("lowest is above its highest") !=
        std::string::npos);
  CHECK(model_error("calibration: {reading_ranges: [[0, 1], [1]]}\n").find("must be [lowest, highest]") !=
        std::string::npos);
  CHECK(model_error("calibration: {reading_ranges: [[0, 1], [0, .nan]]}\n").find("is not a number") !=
        std::string::npos);
}

TEST_CASE("readings beyond the calibrated ranges: a still joint warned per joint, the rest in one note") {
  model::RobotModel m = two_joints();
  CHECK(model::readings_outside_calibration(m, {{5.0, 5.0}}, "rows").empty());  // no record: nothing to say
  m.calibration = model::CalibrationRecord{};
  m.calibration->reading_ranges = {{-1.0, 1.0}, {0.1, 0.1}};
  CHECK(model::readings_outside_calibration(m, {{0.5, 0.1}, {1.0, 0.1 + 1e-6}}, "rows").empty());
  const auto findings = model::readings_outside_calibration(m, {{1.5, 0.1}, {0.0, 0.15}, {-1.2, 0.1}}, "targets");
  REQUIRE(findings.size() == 2);
  CHECK(findings[0].still);
  CHECK(findings[0].text ==
        "1 of 3 targets move joint 2 (lift) from 100.0 mm, the one reading it had in the calibration data (it never "
        "moved), by up to 50.0 mm: there the model's error includes that joint's axis, which the data could not "
        "calibrate, and the prediction's spread does not count it");
  CHECK(!findings[1].still);
  CHECK(findings[1].text ==
        "2 of 3 targets lie outside the readings the calibration data covered, where the model is extrapolated: "
        "joint 1 (shoulder) by up to 28.6 deg (-57.3 to 57.3 deg covered)");
}
