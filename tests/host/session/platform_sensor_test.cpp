// The platform pose sensor (host/session/sensor.hpp) against a scripted platform: the report's
// pose covariance (protocol 2.0) reaches the Observation, turned into the strip frame of the
// square the pose was placed on; the note names that square and how many squares the pose used
// (protocol 3.0).
#include <doctest.h>

#include <Eigen/Eigenvalues>
#include <cmath>
#include <deque>
#include <numbers>

#include "host/session/sensor.hpp"
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

}  // namespace

TEST_CASE("platform pose sensor: the report's covariance becomes the observation's, in the strip frame") {
  // Two squares; the second turned a quarter turn about z, so the covariance must turn with it.
  model::Transform square0, square1;
  square1.translation = model::Vector3(0.1016, 0.0, 0.0);
  square1.rotation = Eigen::AngleAxisd(std::numbers::pi / 2, model::Vector3::UnitZ()).toRotationMatrix();
  ScriptedPlatform platform;
  can::PlatformClient client(platform);
  session::PlatformPoseSensor sensor(client, {square0, square1});
  CHECK(sensor.gives_covariance());

  // square_T_camera: the camera 0.25 m above the square, looking down at it.
  shared::MeasurementReport r;
  r.sequence = 1;  // the client's first trigger
  r.sections = shared::section::kPose;
  r.pose_squares = 2;  // protocol 3.0: the pose used the reference square and one neighbour
  const model::Vector3 t(0.01, -0.02, 0.25);
  for (std::size_t k = 0; k < 3; ++k)
    r.translation_raw[k] = static_cast<std::int32_t>(std::lround(t(static_cast<int>(k)) / shared::kTranslationLsbM));
  r.rotation_raw = {static_cast<std::int32_t>(std::lround(std::numbers::pi / shared::kRotationLsbRad)), 0, 0};
  // sigma_x 0.1 mm, sigma_y 0.2 mm, sigma_z 0.5 mm, x and y correlated by 0.5; the rotation's 1 mrad.
  std::array<float, 36> c{};
  const double sigma[6] = {1e-4, 2e-4, 5e-4, 1e-3, 1e-3, 1e-3};
  for (std::size_t i = 0; i < 6; ++i) c[i * 6 + i] = static_cast<float>(sigma[i] * sigma[i]);
  c[1] = c[6] = static_cast<float>(0.5 * sigma[0] * sigma[1]);
  shared::set_pose_covariance(c, r);
  platform.reports.push_back(r);

  // The nominal prediction puts the camera over the second square.
  model::Transform square_T_camera;
  square_T_camera.translation = t;
  square_T_camera.rotation = Eigen::AngleAxisd(std::numbers::pi, model::Vector3::UnitX()).toRotationMatrix();
  model::Transform predicted = square1 * square_T_camera;
  const session::Observation o = sensor.measure(0, predicted);
  CHECK(o.note.find("square 2 (pose over 2 squares)") != std::string::npos);
  REQUIRE(o.covariance.has_value());
  model::Matrix3 square_c;
  square_c << 1e-8, 1e-8, 0, 1e-8, 4e-8, 0, 0, 0, 25e-8;
  const model::Matrix3 expected = square1.rotation * square_c * square1.rotation.transpose();
  // In the strip frame the second square's x is the strip's y: sigma_y(strip) = 0.1 mm.
  CHECK(expected(1, 1) == doctest::Approx(1e-8));
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      CHECK((*o.covariance)(i, j) == doctest::Approx(expected(i, j)).epsilon(0.025).scale(1e-10));
  // Exactly symmetric and positive definite (the journal and the dataset refuse anything else).
  CHECK(*o.covariance == o.covariance->transpose());
  CHECK(Eigen::SelfAdjointEigenSolver<model::Matrix3>(*o.covariance).eigenvalues().minCoeff() > 0);
}
