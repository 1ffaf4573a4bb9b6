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
