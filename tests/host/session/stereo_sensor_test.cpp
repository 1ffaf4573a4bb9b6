// host/session/stereo_sensor: the stereo beacon sensor on frames the simulator renders through a
// calibrated pair with lens distortion, against the beacon's true position (issue #14).
#include <doctest.h>

#include <cmath>
#include <numbers>
#include <random>

#include "host/session/stereo_sensor.hpp"
#include "host/sim/beacon.hpp"

using namespace kincal;

namespace {

// The rendered pair (sim/beacon.hpp) as the sensor's calibrated pair, in the left camera's frame.
session::StereoSetup setup_of(const sim::StereoRigSpec& spec) {
  session::StereoSetup setup;
  setup.pair = sim::stereo_pair_of(spec);
  setup.left_size_px = setup.right_size_px = cv::Size(spec.camera.width_px, spec.camera.height_px);
  setup.pixel_sigma_px = 0.05;
  return setup;
}

// Device (right camera, y up) to the left camera's OpenCV frame.
model::Vector3 in_left(const sim::StereoRigSpec& spec, const model::Vector3& device) {
  return {-device.x() + spec.baseline_m, -device.y(), device.z()};
}

}  // namespace

TEST_CASE("stereo sensor: a distorted pair's rendered beacon triangulates to its true position") {
  for (const double k1 : {0.0, -0.2}) {
    CAPTURE(k1);
    sim::StereoRigSpec spec;
    spec.camera.distortion = {k1, 0.02, 0, 0, 0};
    sim::BeaconSpec beacon;
    beacon.radius_m = 0.03;
    sim::ImagingConditions conditions;
    model::Vector3 where = model::Vector3::Zero();
    session::StereoBeaconSensor sensor(
        [&](int pose) {
          conditions.seed = static_cast<std::uint64_t>(pose) + 1;
          const sim::StereoFrame f = sim::render_beacon(spec, beacon, where, conditions);
          return session::StereoFrames{f.left, f.right, 0.0, "left", "right"};
        },
        setup_of(spec));
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> x(-1.2, 1.0), y(-0.9, 0.9), z(3.5, 5.0);
    constexpr int kPoses = 30;
    model::Vector3 mean_error = model::Vector3::Zero();
    double mean_z_sigma = 0, chi2 = 0;
    for (int i = 0; i < kPoses; ++i) {
      where = model::Vector3(x(rng), y(rng), z(rng));
      const session::Observation o = sensor.measure(i, model::Transform{});
      const model::Vector3 error = o.position - in_left(spec, where);
      mean_error += error / kPoses;
      mean_z_sigma += std::sqrt((*o.covariance)(2, 2)) / kPoses;
      chi2 += error.dot(o.covariance->ldlt().solve(error)) / kPoses;
    }
    MESSAGE("k1 " << k1 << ": mean error " << mean_error.transpose() * 1e3 << " mm, mean z sigma " << mean_z_sigma * 1e3
                  << " mm, mean chi2 (3 dof) " << chi2);
    // Unbiased: the mean depth error within 3 standard errors; errors of the size the covariance says.
    CHECK(std::abs(mean_error.z()) < 3 * mean_z_sigma * std::sqrt(chi2 / 3) / std::sqrt(double{kPoses}));
    CHECK(chi2 < 3 * 3);
  }
}

TEST_CASE("stereo sensor: a frame of another size than the calibration's names the pose and the camera") {
  sim::StereoRigSpec spec;
  session::StereoBeaconSensor sensor(
      [](int) {
        return session::StereoFrames{cv::Mat(480, 640, CV_8UC1, cv::Scalar(40)), cv::Mat(240, 320, CV_8UC1), 0.0,
                                     "l.png", "r.png"};
      },
      setup_of(spec));
  CHECK_THROWS_WITH(sensor.measure(4, model::Transform{}), doctest::Contains("pose 4, left camera (l.png): no beacon"));
  session::StereoBeaconSensor sized(
      [](int) {
        return session::StereoFrames{cv::Mat(480, 640, CV_8UC3), cv::Mat(240, 320, CV_8UC1), 0.0, "l.png", "r.png"};
      },
      [&] {
        session::StereoSetup s = setup_of(spec);
        s.left_size_px = cv::Size(320, 240);
        return s;
      }());
  CHECK_THROWS_WITH(sized.measure(5, model::Transform{}),
                    doctest::Contains("pose 5, left camera (l.png): the frame is 640x480 px, the stereo calibration's "
                                      "320x240 px"));
}

TEST_CASE("stereo sensor: with the calibration's covariance, the triangulated point's covariance covers its error") {
  // Each trial: the pair's true calibration (k1 -0.1), an estimate of it off by an error drawn
  // from the calibration's covariance C (a fixed, correlated 24 x 24: sigmas of 0.5 px for fx fy,
  // 0.1 px for cx cy, 0.005 / 0.02 / 0.05 for k1 k2 k3, 2e-4 for p1 p2, 0.05 mrad and 0.5 mm for
  // right_T_left: the calibration error dominates the pixels' at 3.5-5 m; the rows of the two
  // cameras stay within the triangulation's 2 px), a point projected by the truth
  // with 0.03 px of pixel noise, triangulated by the estimate. chi^2 (3 dof) of the error under
  // triangulation_covariance: inside the 95 % bound in 95 % of trials with the calibration's
  // share, far fewer without it.
  sim::StereoRigSpec spec;
  spec.camera.distortion = {-0.1, 0, 0, 0, 0};
  const core::StereoPair truth = sim::stereo_pair_of(spec);
  std::mt19937_64 rng(11);
  std::normal_distribution<double> normal;
  Eigen::Matrix<double, 24, 1> sigma;
  const Eigen::Matrix<double, 9, 1> camera_sigma =
      (Eigen::Matrix<double, 9, 1>() << 0.5, 0.5, 0.1, 0.1, 0.005, 0.02, 2e-4, 2e-4, 0.05).finished();
  sigma << camera_sigma, camera_sigma, 5e-5, 5e-5, 5e-5, 5e-4, 5e-4, 5e-4;
  Eigen::Matrix<double, 24, 24> mix;
  for (int i = 0; i < 24; ++i)
    for (int j = 0; j < 24; ++j) mix(i, j) = normal(rng);
  const Eigen::Matrix<double, 24, 24> correlation =
      0.5 * (mix * mix.transpose() / 24 + Eigen::Matrix<double, 24, 24>::Identity());
  const Eigen::Matrix<double, 24, 24> unit = correlation.diagonal().cwiseInverse().cwiseSqrt().asDiagonal();
  const session::CalibrationCovariance c = sigma.asDiagonal() * unit * correlation * unit * sigma.asDiagonal();
  const session::CalibrationDirections directions = session::calibration_directions(c);
  const Eigen::Matrix<double, 24, 24> draw = c.llt().matrixL();
  constexpr double kPixelSigmaPx = 0.03, kChi2Bound95 = 7.815;
  constexpr int kTrials = 1000;
  std::uniform_real_distribution<double> x(-1.0, 0.9), y(-0.7, 0.7), z(3.5, 5.0);
  int inside = 0, inside_without = 0;
  double chi2_mean = 0;
  for (int trial = 0; trial < kTrials; ++trial) {
    Eigen::Matrix<double, 24, 1> error;
    for (int k = 0; k < 24; ++k) error(k) = normal(rng);
    const core::StereoPair estimate = session::perturbed(truth, draw * error);
    const core::Vector3<float> point(static_cast<float>(x(rng)), static_cast<float>(y(rng)),
                                     static_cast<float>(z(rng)));
    core::Vector2<float> left, right;
    REQUIRE(core::project_point(truth.left, point, left) == core::CameraStatus::ok);
    REQUIRE(core::project_point(truth.right, truth.left_T_right.inverse() * point, right) == core::CameraStatus::ok);
    for (core::Vector2<float>* px : {&left, &right})
      for (int k = 0; k < 2; ++k) (*px)(k) += static_cast<float>(kPixelSigmaPx * normal(rng));
    core::StereoPoint found;
    REQUIRE(core::triangulate_pair(estimate, left, right, static_cast<float>(kPixelSigmaPx), found) ==
            core::StereoStatus::ok);
    const model::Vector3 e = (found.point_left_m - point).cast<double>();
    const model::Matrix3 with = session::triangulation_covariance(estimate, left, right, kPixelSigmaPx, directions, "");
    const model::Matrix3 without = session::triangulation_covariance(estimate, left, right, kPixelSigmaPx, {}, "");
    const double chi2 = e.dot(with.ldlt().solve(e));
    chi2_mean += chi2 / kTrials;
    inside += chi2 < kChi2Bound95;
    inside_without += e.dot(without.ldlt().solve(e)) < kChi2Bound95;
  }
  const double coverage = double(inside) / kTrials, coverage_without = double(inside_without) / kTrials;
  MESSAGE("95 % coverage " << coverage << " (without the calibration's share " << coverage_without
                           << "), mean chi2 (3 dof) " << chi2_mean);
  CHECK(coverage > 0.92);
  CHECK(coverage < 0.98);
  CHECK(coverage_without < 0.5);
}

TEST_CASE("stereo sensor: a calibration covariance that is not one is refused") {
  session::CalibrationCovariance c = session::CalibrationCovariance::Identity();
  c(3, 3) = -1;
  CHECK_THROWS_WITH_AS(session::calibration_directions(c), doctest::Contains("negative eigenvalue"),
                       session::SessionError);
  c = session::CalibrationCovariance::Identity();
  c(0, 5) = 0.5;
  CHECK_THROWS_WITH_AS(session::calibration_directions(c), doctest::Contains("symmetric"), session::SessionError);
}
