// host/session: robot drivers, progress, plans, the correction block read back by the firmware's
// reading of it, and a whole session against a scripted driver and sensor (journal, resume,
// fail fast).
#include <doctest.h>

#include <algorithm>
#include <filesystem>
#include <numbers>
#include <random>
#include <sstream>

#include "firmware/app/correction_chain.hpp"
#include "firmware/app/kinematic_correction.hpp"
#include "host/correct/correction_block.hpp"
#include "host/model/model_file.hpp"
#include "host/session/online_correction.hpp"
#include "host/session/pose_plan.hpp"
#include "host/session/progress.hpp"
#include "host/session/robot_driver.hpp"
#include "host/session/session.hpp"

using namespace kincal;

namespace {

model::RobotModel robot(const char* file) { return model::load_model(std::string(KINCAL_ROBOTS_DIR) + "/" + file); }

std::string temp_path(const std::string& name) {
  return (std::filesystem::temp_directory_path() / ("kincal-session-test-" + name)).string();
}

// Sees the tool of `truth` exactly, and fails at a chosen pose.
class TruthSensor : public session::Sensor {
 public:
  explicit TruthSensor(model::RobotModel truth) : truth_(std::move(truth)) {}
  session::Observation measure(int index, const model::Transform&) override {
    if (index == fail_at) throw session::SessionError("pose " + std::to_string(index) + ": no target in view");
    ++measured;
    session::Observation o;
    const model::Transform t = model::forward_kinematics(truth_, readings);
    o.position = t.translation;
    o.orientation = Eigen::Quaterniond(t.rotation);
    o.sequence = static_cast<std::uint32_t>(index);
    return o;
  }
  std::string name() const override { return "truth"; }
  bool gives_orientation() const override { return true; }
  bool gives_covariance() const override { return false; }
  std::vector<double> readings;
  int fail_at = -1;
  int measured = 0;

 private:
  model::RobotModel truth_;
};

// Goes where it is told and tells the sensor.
class ExactDriver : public session::RobotDriver {
 public:
  explicit ExactDriver(TruthSensor& sensor) : sensor_(sensor) {}
  std::vector<double> move_to(int, const std::vector<double>& target) override {
    sensor_.readings = target;
    return target;
  }
  std::string name() const override { return "exact"; }

 private:
  TruthSensor& sensor_;
};

}  // namespace

TEST_CASE("robot command: {q} expands to the joint values; its output may give the readings") {
  CHECK(session::expand_robot_command("move {q} now", {0.5, -1e-3, 2}) == "move 0.5 -0.001 2 now");
  CHECK(session::parse_readings("0.1 0.2, 0.3\n", 3) == std::vector<double>{0.1, 0.2, 0.3});
  CHECK(session::parse_readings("0.1 0.2", 3).empty());
  CHECK(session::parse_readings("moved", 1).empty());
  CHECK_THROWS_WITH_AS(session::CommandRobotDriver("move"), doctest::Contains("{q}"), session::SessionError);

  session::CommandRobotDriver echo("echo 1 2 {q} >/dev/null; echo 0.25 0.5");
  CHECK(echo.move_to(3, {0.2, 0.4}) == std::vector<double>{0.25, 0.5});
  session::CommandRobotDriver quiet("true {q}");
  CHECK(quiet.move_to(3, {0.2, 0.4}) == std::vector<double>{0.2, 0.4});
  session::CommandRobotDriver failing("exit 3 {q}");
  CHECK_THROWS_WITH_AS(failing.move_to(7, {0.2}),
                       doctest::Contains("pose 7: robot command 'exit 3 0.2' exited with status 3"),
                       session::SessionError);
}

TEST_CASE("manual driver: Enter confirms the target, typed readings replace it, q stops") {
  std::istringstream answers("\n0.11 0.22\nq\n");
  std::ostringstream prompt;
  session::ManualRobotDriver manual(answers, prompt);
  CHECK(manual.move_to(0, {0.1, 0.2}) == std::vector<double>{0.1, 0.2});
  CHECK(manual.move_to(1, {0.1, 0.2}) == std::vector<double>{0.11, 0.22});
  CHECK_THROWS_WITH_AS(manual.move_to(2, {0.1, 0.2}), doctest::Contains("stopped by the operator"),
                       session::SessionError);
  CHECK(prompt.str().find("pose 1") != std::string::npos);
}

TEST_CASE("progress: an ETA from the steps of this run, a line per tenth off a terminal") {
  CHECK(session::Progress::format_duration(61) == "1:01");
  CHECK(session::Progress::format_duration(3725) == "1:02:05");
  std::ostringstream out;
  session::Progress p(out, false, "measuring", 20, 5);
  for (int i = 0; i < 15; ++i) p.step();
  p.finish();
  const std::string text = out.str();
  CHECK(text.find("resuming with 5 of 20") != std::string::npos);
  CHECK(text.find("20/20") != std::string::npos);
  CHECK(std::count(text.begin(), text.end(), '\n') <= 10);
}

TEST_CASE("sweeps: one joint at a time, within the limits, errors named") {
  const model::RobotModel m = robot("stanford_rrp.yaml");
  const std::vector<double> home = {0.0, 100 * std::numbers::pi / 180, 0.9};
  const session::Configurations s = session::single_joint_sweeps(m, home, 10, 0.4);
  REQUIRE(s.size() == 30);
  for (std::size_t i = 0; i < s.size(); ++i)
    for (std::size_t j = 0; j < 3; ++j) {
      CHECK(s[i][j] >= m.joints[j].lower - 1e-12);
      CHECK(s[i][j] <= m.joints[j].upper + 1e-12);
      if (j != i / 10) CHECK(s[i][j] == home[j]);
    }
  CHECK_THROWS_WITH_AS(session::single_joint_sweeps(m, home, 3, 0.4), doctest::Contains("at least 4"),
                       model::InputError);
  CHECK_THROWS_WITH_AS(session::single_joint_sweeps(m, {0, 0, 0.9}, 10, 0.4), doctest::Contains("outside its limits"),
                       model::InputError);
}

TEST_CASE("correction block: the firmware reads back the chains the host identified") {
  const model::RobotModel start = robot("puma560.yaml");
  model::RobotModel identified = start;
  identified.joints[1].parameters.a_m += 1e-3;
  identified.joints[2].offset += 2e-3;
  identified.flange_T_tool.translation.x() += 5e-4;
  const shared::CorrectionParameters block = correct::correction_block(start, identified);
  core::ChainModel<double> nominal;
  core::ParameterSet ids;
  core::ErrorVector<double> errors;
  REQUIRE(app::correction_chain(block, nominal, ids, errors) == app::ChainStatus::kOk);
  core::ChainModel<double> calibrated;
  REQUIRE(core::apply_parameter_errors(nominal, ids, errors, calibrated) == core::ErrorModelStatus::ok);
  const std::vector<double> q = {0.1, -0.4, 0.3, 0.2, -0.5, 0.7};
  core::RigidTransform<double> want = model::forward_kinematics(identified, q), got;
  // The block leaves out the base: compare in the robot's own frame.
  want = start.base_T_frame0.inverse() * want;
  got = core::forward_kinematics(calibrated, model::joint_vector(q));
  CHECK((got.translation - want.translation).norm() < 1e-6);
  CHECK((got.rotation - want.rotation).norm() < 1e-6);
}

TEST_CASE("correction block with the joint map: the platform's correction puts the identified arm on the goal") {
  // The controller reports the elbow relative to the shoulder (Fanuc-style coupling, in both
  // models); the identified model adds geometry errors, gear scales and gravity compliance.
  model::RobotModel start = robot("puma560.yaml");
  start.joints[2].coupling = {0, 1, 1, 0, 0, 0};
  const double mass_kg[6] = {0, 17.4, 4.8, 0.82, 0.34, 0.09};
  for (std::size_t j = 0; j < 6; ++j) start.joints[j].mass_kg = mass_kg[j];
  start.joints[1].centre_of_mass_m = {-0.3638, 0.006, 0.2275};
  start.joints[2].centre_of_mass_m = {-0.0203, -0.0141, 0.070};
  start.payload.mass_kg = 3.0;
  start.payload.centre_of_mass_m = {0, 0, 0.1};
  start.joints[1].compliance = 0.0;  // declared, so identified; the controller's value is 0
  start.joints[2].compliance = 0.0;
  model::RobotModel identified = start;
  identified.joints[1].parameters.a_m += 1e-3;
  identified.joints[2].offset += 2e-3;
  identified.joints[0].scale = 1.0 + 4e-4;
  identified.joints[1].scale = 1.0 - 3e-4;
  identified.joints[2].scale = 1.0 + 5e-4;
  identified.joints[1].compliance = 2e-5;
  identified.joints[2].compliance = 3e-5;
  // As identification writes it: the links' given masses stay on their bodies (a1 moved the frame).
  model::carry_centres_of_mass(identified, model::to_chain(start), model::to_chain(identified));
  const shared::CorrectionParameters block = correct::correction_block(start, identified);
  CHECK(block.joint_maps[2].coupled);
  CHECK(block.joint_maps[1].compliance_error == doctest::Approx(2e-5));
  shared::CorrectionParameters geometry_only = block;
  for (shared::JointMapValues& m : geometry_only.joint_maps) m.scale_error = m.compliance_error = 0.0f;

  static app::KinematicCorrection platform;
  std::mt19937_64 rng(11);
  double worst_before_m = 0, worst_after_m = 0, worst_without_map_m = 0;
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> q = {0.1, -0.4, 0.3, 0.2, -0.5, 0.7};
    for (double& v : q) v += std::uniform_real_distribution<double>(-0.3, 0.3)(rng);
    q[2] -= q[1];  // the reading of the coupled elbow
    app::JointRaw raw{}, corrected_raw{}, without_raw{};
    for (std::size_t j = 0; j < 6; ++j) raw[j] = shared::quantize_joint_angle(q[j]);
    REQUIRE(platform.correct(block, raw, corrected_raw) == app::CorrectStatus::kOk);
    REQUIRE(platform.correct(geometry_only, raw, without_raw) == app::CorrectStatus::kOk);
    std::vector<double> readings(6), corrected(6), without(6);
    for (std::size_t j = 0; j < 6; ++j) {
      readings[j] = shared::joint_angle_rad<double>(raw[j]);
      corrected[j] = shared::joint_angle_rad<double>(corrected_raw[j]);
      without[j] = shared::joint_angle_rad<double>(without_raw[j]);
    }
    // host/model's forward kinematics with the full joint map is the arm's truth here.
    const model::Vector3 goal = model::forward_kinematics(start, readings).translation;
    worst_before_m =
        std::max(worst_before_m, (model::forward_kinematics(identified, readings).translation - goal).norm());
    worst_after_m =
        std::max(worst_after_m, (model::forward_kinematics(identified, corrected).translation - goal).norm());
    worst_without_map_m =
        std::max(worst_without_map_m, (model::forward_kinematics(identified, without).translation - goal).norm());
  }
  MESSAGE("tool position error: " << worst_before_m * 1e3 << " mm uncorrected, " << worst_after_m * 1e6
                                  << " um corrected, " << worst_without_map_m * 1e6
                                  << " um when the identified joint map is left out");
  CHECK(worst_before_m > 5e-4);
  CHECK(worst_after_m < 30e-6);  // quantization (2^-16 rad) and the correction's third-order rest
  CHECK(worst_without_map_m > 10 * worst_after_m);

  // The block carries one coupling row (the controller's): an identified coupling is refused.
  // Masses: one set, the controller's, unless its model has no compliance (then the identified
  // ones act alone); this controller declares compliances, so differing masses are refused.
  model::RobotModel other = identified;
  other.joints[2].coupling.clear();
  CHECK_THROWS_WITH_AS(correct::correction_block(start, other), doctest::Contains("coupling row differs"),
                       model::InputError);
  other = identified;
  other.joints[3].mass_kg += 1.0;
  model::RobotModel sagging = start;
  sagging.joints[1].compliance = 1e-5;
  CHECK_THROWS_WITH_AS(correct::correction_block(sagging, other), doctest::Contains("mass differs"), model::InputError);
  const shared::CorrectionParameters identified_masses = correct::correction_block(start, other);
  CHECK(identified_masses.joint_maps[3].mass_kg == doctest::Approx(other.joints[3].mass_kg));
  // An identified direction of gravity likewise: carried when the controller's model does not sag.
  other = identified;
  other.gravity_mps2 = Eigen::AngleAxisd(0.01, model::Vector3::UnitX()) * other.gravity_mps2;
  CHECK_THROWS_WITH_AS(correct::correction_block(sagging, other), doctest::Contains("gravity's direction differs"),
                       model::InputError);
  const shared::CorrectionParameters identified_gravity = correct::correction_block(start, other);
  CHECK(identified_gravity.gravity_mps2[1] == doctest::Approx(other.gravity_mps2.y()));
  CHECK(identified_gravity.gravity_mps2[1] != 0.0f);
  other = identified;
  other.payload.mass_kg = 1.0;
  CHECK_THROWS_WITH_AS(correct::correction_block(start, other), doctest::Contains("differ in payload"),
                       model::InputError);
}

TEST_CASE("session: measures every pose once, resumes after a failure, identifies the truth") {
  const model::RobotModel nominal = robot("puma560.yaml");
  model::RobotModel truth = nominal;
  truth.joints[1].parameters.a_m += 2e-3;
  truth.joints[3].offset += 1e-3;
  session::SessionPlan plan;
  std::mt19937_64 rng(5);
  for (int i = 0; i < 30; ++i) {
    std::vector<double> q;
    for (std::size_t j = 0; j < 6; ++j) q.push_back(std::uniform_real_distribution<double>(-1.5, 1.5)(rng));
    (i < 24 ? plan.calibration : plan.validation).push_back(q);
  }
  TruthSensor sensor(truth);
  ExactDriver driver(sensor);
  session::SessionOptions options;
  options.journal_path = temp_path("journal");
  options.identity = {{"session", "test"}};
  std::filesystem::remove(options.journal_path);
  std::ostringstream log;

  sensor.fail_at = 10;
  CHECK_THROWS_WITH_AS(session::run_session(nominal, plan, driver, sensor, options, log), doctest::Contains("pose 10"),
                       session::SessionError);
  CHECK(sensor.measured == 10);
  CHECK_THROWS_WITH_AS(session::run_session(nominal, plan, driver, sensor, options, log),
                       doctest::Contains("already exists"), session::SessionError);
  sensor.fail_at = -1;
  options.resume = true;
  const session::SessionData data = session::run_session(nominal, plan, driver, sensor, options, log);
  CHECK(sensor.measured == 30);
  CHECK(data.resumed == 10);
  CHECK(data.calibration.rows.size() == 24);
  CHECK(data.validation.rows.size() == 6);

  options.identity = {{"session", "another"}};
  CHECK_THROWS_AS(session::run_session(nominal, plan, driver, sensor, options, log), model::InputError);

  identify::IdentifyOptions io;
  io.sigma_m = 1e-5;
  io.orientation_sigma_rad = 1e-5;
  const session::Calibration c = session::calibrate(nominal, data, io);
  CHECK(c.before.rms_m > 1e-3);
  CHECK(c.after.rms_m < 1e-6);
  std::filesystem::remove(options.journal_path);
}
