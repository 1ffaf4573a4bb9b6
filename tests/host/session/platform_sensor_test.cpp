// The platform pose sensor (host/session/sensor.hpp) against a scripted platform: the report's
// pose covariance (protocol 2.0) reaches the Observation, turned into the strip frame of the
// square the pose was placed on; the note names that square and how many squares the pose used
// (protocol 3.0); the full 6x6 (issue #26) reaches a session's dataset row; the platform camera's
// share (issue #22) joins it where its intrinsics move the pose.
#include <doctest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <deque>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <sstream>

#include "host/camera/calibration_file.hpp"
#include "host/session/sensor.hpp"
#include "host/session/session.hpp"
#include "shared/measurement_report.hpp"

using namespace kincal;

namespace {

// Answers every measurement trigger with the next scripted report; ignores what else is sent.
class ScriptedPlatform : public can::Transport {
 public:
  void send_frame(const shared::CanFrame&) override {}
  void send_message(std::span<const std::uint8_t>) override {}
  bool receive(can::Received& out, std::chrono::milliseconds) override {
    if (reports.empty()) return false;
    std::array<std::uint8_t, shared::kMaxReportBytes> bytes{};
    const std::size_t n = shared::encode(reports.front(), bytes);
    reports.pop_front();
    out.kind = can::Received::Kind::kMessage;
    out.message.assign(bytes.begin(), bytes.begin() + static_cast<std::ptrdiff_t>(n));
    return true;
  }
  std::string name() const override { return "scripted platform"; }
  std::deque<shared::MeasurementReport> reports;
};

// The camera 0.25 m above the square (square_T_camera), looking down at it; its pose covariance
// (square frame, the report's convention): sigma_x 0.1 mm, sigma_y 0.2 mm, sigma_z 0.5 mm, x and
// y correlated by 0.5; the rotation's 1 mrad, its error about x correlated with x by 0.6.
const model::Vector3 kT(0.01, -0.02, 0.25);
constexpr double kSigma[6] = {1e-4, 2e-4, 5e-4, 1e-3, 1e-3, 1e-3};

model::Matrix6 square_covariance() {
  model::Matrix6 c = model::Matrix6::Zero();
  for (int i = 0; i < 6; ++i) c(i, i) = kSigma[i] * kSigma[i];
  c(0, 1) = c(1, 0) = 0.5 * kSigma[0] * kSigma[1];
  c(0, 3) = c(3, 0) = 0.6 * kSigma[0] * kSigma[3];
  return c;
}

shared::MeasurementReport pose_report(std::uint8_t sequence) {
  shared::MeasurementReport r;
  r.sequence = sequence;  // the client's triggers count from 1
  r.sections = shared::section::kPose;
  r.pose_squares = 2;  // protocol 3.0: the pose used the reference square and one neighbour
  for (std::size_t k = 0; k < 3; ++k)
    r.translation_raw[k] = static_cast<std::int32_t>(std::lround(kT(static_cast<int>(k)) / shared::kTranslationLsbM));
  r.rotation_raw = {static_cast<std::int32_t>(std::lround(std::numbers::pi / shared::kRotationLsbRad)), 0, 0};
  std::array<float, 36> c{};
  const model::Matrix6 square = square_covariance();
  for (std::size_t i = 0; i < 36; ++i)
    c[i] = static_cast<float>(square(static_cast<int>(i / 6), static_cast<int>(i % 6)));
  shared::set_pose_covariance(c, r);
  return r;
}

// Two squares; the second turned a quarter turn about z, so the covariance must turn with it.
std::vector<model::Transform> two_squares() {
  model::Transform square0, square1;
  square1.translation = model::Vector3(0.1016, 0.0, 0.0);
  square1.rotation = Eigen::AngleAxisd(std::numbers::pi / 2, model::Vector3::UnitZ()).toRotationMatrix();
  return {square0, square1};
}

// The nominal prediction: the camera over the second square.
model::Transform over_second_square() {
  model::Transform square_T_camera;
  square_T_camera.translation = kT;
  square_T_camera.rotation = Eigen::AngleAxisd(std::numbers::pi, model::Vector3::UnitX()).toRotationMatrix();
  return two_squares()[1] * square_T_camera;
}

// The 6x6 in the strip frame: position and rotation turned (the dataset's errors, the
// measurement's on the truth, are both the report's negated: the cross block is the same).
model::Matrix6 expected_strip_covariance() {
  model::Matrix6 turn = model::Matrix6::Zero();
  turn.topLeftCorner<3, 3>() = two_squares()[1].rotation;
  turn.bottomRightCorner<3, 3>() = two_squares()[1].rotation;
  return turn * square_covariance() * turn.transpose();
}

void check_pose_covariance(const model::Matrix6& c) {
  const model::Matrix6 expected = expected_strip_covariance();
  for (int i = 0; i < 6; ++i)
    for (int j = 0; j < 6; ++j) CHECK(c(i, j) == doctest::Approx(expected(i, j)).epsilon(0.025).scale(1e-8));
  CHECK(c == c.transpose());
  CHECK(Eigen::SelfAdjointEigenSolver<model::Matrix6>(c).eigenvalues().minCoeff() > 0);
}

// A pinhole camera (640x480, f = 800 px, no distortion) with the intrinsics' covariance given.
session::PlatformCamera pinhole(const Eigen::Matrix<double, 9, 9>& covariance) {
  session::PlatformCamera c{core::CameraIntrinsics{}, covariance, 0.0254 / 4};
  c.camera.fx_px = c.camera.fy_px = 800;
  c.camera.cx_px = 320;
  c.camera.cy_px = 240;
  return c;
}

// The pose covariance the sensor gives for pose_report's pose over the second square, with the
// camera or without.
model::Matrix6 measured_covariance(const std::optional<session::PlatformCamera>& camera) {
  ScriptedPlatform platform;
  can::PlatformClient client(platform);
  session::PlatformPoseSensor sensor(client, two_squares(), camera);
  platform.reports.push_back(pose_report(1));
  const session::Observation o = sensor.measure(0, over_second_square());
  REQUIRE(o.pose_covariance.has_value());
  CHECK(*o.pose_covariance == o.pose_covariance->transpose());
  CHECK(o.pose_covariance->topLeftCorner<3, 3>() == *o.covariance);
  return *o.pose_covariance;
}

// Goes where it is told (one joint that moves nothing).
class StillDriver : public session::RobotDriver {
 public:
  std::vector<double> move_to(int, const std::vector<double>& target) override { return target; }
  std::string name() const override { return "still"; }
};

}  // namespace

TEST_CASE("platform pose sensor: the report's covariance becomes the observation's, in the strip frame") {
  ScriptedPlatform platform;
  can::PlatformClient client(platform);
  session::PlatformPoseSensor sensor(client, two_squares());
  CHECK(sensor.gives_covariance());
  CHECK(sensor.gives_pose_covariance());
  platform.reports.push_back(pose_report(1));

  const session::Observation o = sensor.measure(0, over_second_square());
  CHECK(o.note.find("square 2 (pose over 2 squares)") != std::string::npos);
  REQUIRE(o.covariance.has_value());
  model::Matrix3 square_c;
  square_c << 1e-8, 1e-8, 0, 1e-8, 4e-8, 0, 0, 0, 25e-8;
  const model::Matrix3 expected = two_squares()[1].rotation * square_c * two_squares()[1].rotation.transpose();
  // In the strip frame the second square's x is the strip's y: sigma_y(strip) = 0.1 mm.
  CHECK(expected(1, 1) == doctest::Approx(1e-8));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      CHECK((*o.covariance)(i, j) == doctest::Approx(expected(i, j)).epsilon(0.025).scale(1e-10));
  // Exactly symmetric and positive definite (the journal and the dataset refuse anything else).
  CHECK(*o.covariance == o.covariance->transpose());
  CHECK(Eigen::SelfAdjointEigenSolver<model::Matrix3>(*o.covariance).eigenvalues().minCoeff() > 0);

  // The full 6x6 (issue #26): position and rotation turned into the strip frame; its position
  // block is the covariance.
  REQUIRE(o.pose_covariance.has_value());
  check_pose_covariance(*o.pose_covariance);
  CHECK(o.pose_covariance->topLeftCorner<3, 3>() == *o.covariance);
}

TEST_CASE("platform pose sensor: a session's dataset row holds the report's 6x6 pose covariance") {
  ScriptedPlatform platform;
  can::PlatformClient client(platform);
  session::PlatformPoseSensor sensor(client, two_squares());
  platform.reports.push_back(pose_report(1));
  // One revolute joint of zero length at reading 0: the nominal tool is where the base puts it.
  model::RobotModel nominal;
  nominal.name = "still";
  nominal.joints.emplace_back();
  nominal.base_T_frame0 = over_second_square();
  session::SessionPlan plan;
  plan.calibration = {{0.0}};
  session::SessionOptions options;
  options.journal_path = (std::filesystem::temp_directory_path() / "kincal-platform-pose-covariance.journal").string();
  options.identity = {{"session", "test"}};
  std::filesystem::remove(options.journal_path);
  StillDriver driver;
  std::ostringstream log;
  const session::SessionData data = session::run_session(nominal, plan, driver, sensor, options, log);
  CHECK(data.calibration.has_pose_covariance);
  REQUIRE(data.calibration.rows.size() == 1);
  REQUIRE(data.calibration.rows[0].pose_covariance.has_value());
  check_pose_covariance(*data.calibration.rows[0].pose_covariance);

  // Through the dataset file and back: the 15 columns beyond the position block.
  std::ostringstream csv;
  model::write_dataset(csv, data.calibration);
  CHECK(csv.str().find(",cxrx,") != std::string::npos);
  std::istringstream in(csv.str());
  const model::Dataset back = model::parse_dataset(in, "csv");
  REQUIRE(back.rows.size() == 1);
  REQUIRE(back.rows[0].pose_covariance.has_value());
  CHECK(*back.rows[0].pose_covariance == *data.calibration.rows[0].pose_covariance);
  std::filesystem::remove(options.journal_path);
}

// The camera looks straight down at the square from 0.25 m (pose_report), so what the intrinsics
// do is known in closed form: fx and fy scaled together by (1 + e) leave every pixel where it is
// for the square at (1 + e) times the depth -- the camera's height moves by 0.25 m * e; cx moved
// by d shifts every normalized x by -d / fx, as the square moved 0.25 m * d / fx along the
// camera's x -- the square's x, the strip's y for the second square (a quarter turn about z).
TEST_CASE("platform pose sensor: the camera's intrinsics covariance adds its share where it moves the pose") {
  const model::Matrix6 without = measured_covariance(std::nullopt);
  constexpr double kSigmaPx = 2;
  const double moved_m = 0.25 * kSigmaPx / 800;  // 0.625 mm
  // The share with the intrinsics' covariance c: moved_m^2 at (k, k) within 1 %, nothing elsewhere.
  const auto check_share = [&](const Eigen::Matrix<double, 9, 9>& c, int k) {
    const model::Matrix6 share = measured_covariance(pinhole(c)) - without;
    CHECK(share(k, k) / (moved_m * moved_m) == doctest::Approx(1).epsilon(0.01));
    for (int i = 0; i < 6; ++i)
      for (int j = 0; j < 6; ++j)
        if (i != k || j != k) CHECK(std::abs(share(i, j)) < 1e-3 * moved_m * moved_m);
  };
  Eigen::Matrix<double, 9, 9> c = Eigen::Matrix<double, 9, 9>::Zero();

  SUBCASE("fx and fy fully correlated: the depth") {
    c.topLeftCorner<2, 2>().setConstant(kSigmaPx * kSigmaPx);
    check_share(c, 2);
  }
  SUBCASE("cx: the position across the strip") {
    c(2, 2) = kSigmaPx * kSigmaPx;
    check_share(c, 1);
  }
  SUBCASE("a zero covariance changes nothing, bit for bit") { CHECK(measured_covariance(pinhole(c)) == without); }
  SUBCASE("an indefinite covariance is refused") {
    c(0, 0) = 1;
    c(1, 1) = -1;
    ScriptedPlatform platform;
    can::PlatformClient client(platform);
    CHECK_THROWS_WITH_AS(session::PlatformPoseSensor(client, two_squares(), pinhole(c)),
                         "the platform camera's intrinsics covariance has a negative eigenvalue",
                         session::SessionError);
  }
}

TEST_CASE("platform pose sensor: a platform camera file without a usable intrinsics covariance is refused") {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "kincal-platform-camera";
  std::filesystem::create_directories(dir);
  camera::CameraModel model;
  model.image_size = cv::Size(640, 480);
  model.camera_matrix = cv::Matx33d(800, 0, 320, 0, 800, 240, 0, 0, 1);
  camera::IntrinsicsCovariance uncertainty;
  for (int i = 0; i < 9; ++i) uncertainty.covariance(i, i) = 0.01;
  uncertainty.corner_sigma_px = 0.1;

  const std::string with = (dir / "with.yaml").string();
  camera::save_camera_ros(with, model, "platform", {}, uncertainty);
  const session::PlatformCamera loaded = session::load_platform_camera(with);
  CHECK(loaded.camera.fx_px == 800);
  CHECK(loaded.covariance(8, 8) == 0.01);

  const std::string none = (dir / "none.yaml").string();
  camera::save_camera_ros(none, model, "platform");
  const std::string missing = none + ": key 'intrinsics_covariance' missing";
  CHECK_THROWS_WITH_AS(session::load_platform_camera(none), doctest::Contains(missing.c_str()),
                       camera::CalibrationError);

  std::stringstream text;
  text << std::ifstream(with).rdbuf();
  std::string eight = text.str();
  const std::string header = "intrinsics_covariance:\n  rows: 9\n  cols: 9";
  REQUIRE(eight.find(header) != std::string::npos);
  eight.replace(eight.find(header), header.size(), "intrinsics_covariance:\n  rows: 8\n  cols: 8");
  const std::string wrong = (dir / "eight.yaml").string();
  std::ofstream(wrong) << eight;
  const std::string not_9x9 = wrong + ": key 'intrinsics_covariance' missing or not a 9x9 matrix";
  CHECK_THROWS_WITH_AS(session::load_platform_camera(wrong), doctest::Contains(not_9x9.c_str()),
                       camera::CalibrationError);
  std::filesystem::remove_all(dir);
}
