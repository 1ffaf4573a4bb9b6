// host/sim: the strip's squares through the firmware's FID, the beacon's images, the rangers
// against a hand-computed case, the simulated robot, the parameter blocks; errors.
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "firmware/core/fiducial_id.hpp"
#include "host/identify/identify.hpp"
#include "host/model/model_file.hpp"
#include "host/sim/beacon.hpp"
#include "host/sim/parameter_blocks.hpp"
#include "host/sim/rangers.hpp"
#include "host/sim/render.hpp"
#include "host/sim/robot.hpp"
#include "host/sim/strip.hpp"
#include "host/vision/image_labeling.hpp"

namespace kincal::sim {
namespace {

constexpr double kDeg = std::numbers::pi / 180;

TEST_CASE("a strip square seen tilted: the firmware's FID identifies all six fiducials where they project") {
  const StripSpec strip;
  CameraSpec camera;
  camera.distortion = {-0.1, 0.02, 0.0005, -0.0003, 0.0};
  const std::array<FiducialRect, 6> fiducials = square_fiducials(strip);
  int view = 0;
  // 0.25 m: the square spans more than 181 px, where the FID's collinearity products once
  // overflowed 32 bits (UBSan found it here).
  for (const auto& [distance_m, tilt_x, tilt_y, square] :
       {std::tuple{0.25, 0.0, 0.0, 0}, std::tuple{0.3, 25 * kDeg, -10 * kDeg, 2},
        std::tuple{0.4, -15 * kDeg, 28 * kDeg, 4}, std::tuple{0.33, 20 * kDeg, 20 * kDeg, 1}}) {
    // Square `square`'s centre in front of the camera, slightly off axis.
    const Eigen::Isometry3d camera_T_square = facing_camera(Eigen::Vector3d(0.004, -0.006, distance_m), tilt_x, tilt_y);
    const Eigen::Isometry3d camera_T_strip = camera_T_square * strip_T_square(strip, square).inverse();
    ImagingConditions conditions;
    conditions.seed = static_cast<std::uint64_t>(++view);
    const cv::Mat image = render_plane(camera, camera_T_strip, strip_target(strip), conditions);
    vision::LabelOptions options;
    options.polarity = core::Polarity::kDark;
    const vision::LabelResult labels = vision::label_grey(image, options);
    REQUIRE(labels.blobs.size() <= core::kFidMaxBlobs);
    std::vector<core::FidVerdict> verdicts(labels.blobs.size());
    core::FidResult result;
    CAPTURE(view);
    REQUIRE(core::identify_fiducials(core::FidModel{}, labels.blobs, verdicts, result) == core::FidStatus::kOk);
    CHECK(result.count == 6);
    CHECK(result.orientation_from_marker);
    // Several squares are in view; the FID picks one (the first in raster order on a tie). Which
    // one: the square whose centre projects nearest to the identified centre fiducial.
    const auto centre_px = [&](int k) {
      const Eigen::Vector3d c = strip_T_square(strip, k).translation();
      return project_points(camera, camera_T_strip, std::span(&c, 1))[0];
    };
    const core::IdentifiedFiducial* p4 = nullptr;
    for (std::size_t i = 0; i < result.count; ++i) {
      if (result.fiducials[i].id == 4) p4 = &result.fiducials[i];
    }
    REQUIRE(p4 != nullptr);
    int seen = 0;
    for (int k = 1; k < strip.squares; ++k) {
      const cv::Point2d a = centre_px(k) - cv::Point2d(p4->x_px.to_double(), p4->y_px.to_double());
      const cv::Point2d b = centre_px(seen) - cv::Point2d(p4->x_px.to_double(), p4->y_px.to_double());
      if (a.dot(a) < b.dot(b)) seen = k;
    }
    const Eigen::Isometry3d camera_T_seen = camera_T_strip * strip_T_square(strip, seen);
    for (std::size_t i = 0; i < result.count; ++i) {
      const core::IdentifiedFiducial& f = result.fiducials[i];
      REQUIRE(f.id >= 1);
      REQUIRE(f.id <= 6);
      const FiducialRect& rect = fiducials[f.id - 1u];
      CHECK(rect.id == f.id);
      const Eigen::Vector3d centre(rect.centre_m.x(), rect.centre_m.y(), 0);
      const cv::Point2d truth = project_points(camera, camera_T_seen, std::span(&centre, 1))[0];
      // The centroid of a tilted square is not its centre's projection (perspective; about
      // 0.26 px at 30 degrees, README), so this checks identity and place, not accuracy.
      CAPTURE(static_cast<int>(f.id));
      CHECK(std::hypot(f.x_px.to_double() - truth.x, f.y_px.to_double() - truth.y) < 0.5);
    }
  }
}

TEST_CASE("strip geometry: fiducials as fiducial_id.hpp places them, squares in a row") {
  const StripSpec strip;
  const double s = 0.0254 / 4;
  const std::array<FiducialRect, 6> f = square_fiducials(strip);
  CHECK(f[0].centre_m.isApprox(Eigen::Vector2d(-7 * s, 7 * s)));
  CHECK(f[1].centre_m.isApprox(Eigen::Vector2d(0, 7 * s)));
  CHECK(f[2].centre_m.isApprox(Eigen::Vector2d(-7 * s, 0)));
  CHECK(f[3].centre_m.norm() == 0);
  CHECK(f[3].size_m.isApprox(Eigen::Vector2d(s, 2 * s)));
  CHECK(f[4].centre_m.isApprox(Eigen::Vector2d(7 * s, 0)));
  CHECK(f[5].centre_m.isApprox(Eigen::Vector2d(0, -7 * s)));
  const PlanarTarget t = strip_target(strip);
  CHECK(t.reflectance(0, 0) == strip.ink);
  CHECK(t.reflectance(0, 1.5 * s) == strip.paper);           // beyond the centre fiducial's end
  CHECK(t.reflectance(2 * 0.1016 + 7 * s, 0) == strip.ink);  // square 2's p5
  CHECK(t.reflectance(0, 0.06) == strip.surround);
  CHECK(strip_T_square(strip, 3).translation().isApprox(Eigen::Vector3d(3 * 0.1016, 0, 0)));
  CHECK_THROWS_WITH_AS(strip_T_square(strip, 5), doctest::Contains("index 5"), std::invalid_argument);
  StripSpec bad;
  bad.squares = 0;
  CHECK_THROWS_WITH_AS(strip_target(bad), doctest::Contains("StripSpec.squares"), std::invalid_argument);
  bad = {};
  bad.fiducial_side_m = 0.01;
  CHECK_THROWS_WITH_AS(strip_target(bad), doctest::Contains("fiducial_side_m"), std::invalid_argument);
  bad = {};
  bad.ink = 1.5;
  CHECK_THROWS_WITH_AS(strip_target(bad), doctest::Contains("StripSpec.ink"), std::invalid_argument);
}

TEST_CASE("rangers against a hand-computed plane") {
  RangerSpec spec;
  spec.spacing_m = 0.1;
  spec.sigma_m = 0;
  // A plane tilted 30 degrees about the camera's y axis, its point (0, 0, 0.5) on the optical
  // axis: z = 0.5 + tan(30 deg) x. Beams along z from (x, y, 0): range = 0.5 + tan(30 deg) x.
  Eigen::Isometry3d camera_T_plane = Eigen::Isometry3d::Identity();
  camera_T_plane.linear() = Eigen::AngleAxisd(-30 * kDeg, Eigen::Vector3d::UnitY()).toRotationMatrix();
  camera_T_plane.translation() = Eigen::Vector3d(0, 0, 0.5);
  std::mt19937_64 rng(1);
  const std::array<double, 4> r = simulate_ranges(spec, camera_T_plane, rng);
  const double t30 = std::tan(30 * kDeg);
  CHECK(r[0] == doctest::Approx(0.5 + 0.05 * t30).epsilon(1e-12));  // (+d/2, 0)
  CHECK(r[1] == doctest::Approx(0.5).epsilon(1e-12));               // (0, +d/2)
  CHECK(r[2] == doctest::Approx(0.5 - 0.05 * t30).epsilon(1e-12));  // (-d/2, 0)
  CHECK(r[3] == doctest::Approx(0.5).epsilon(1e-12));               // (0, -d/2)
  // Grazing incidence (beyond 50 degrees) and beyond the maximum range: no echo.
  camera_T_plane.linear() = Eigen::AngleAxisd(-60 * kDeg, Eigen::Vector3d::UnitY()).toRotationMatrix();
  for (double v : simulate_ranges(spec, camera_T_plane, rng)) CHECK(std::isnan(v));
  camera_T_plane.linear().setIdentity();
  camera_T_plane.translation() = Eigen::Vector3d(0, 0, 0.95);
  for (double v : simulate_ranges(spec, camera_T_plane, rng)) CHECK(std::isnan(v));
  camera_T_plane.translation() = Eigen::Vector3d(0, 0, -0.3);  // behind
  for (double v : simulate_ranges(spec, camera_T_plane, rng)) CHECK(std::isnan(v));
  // Noise: the spread of many readings is sigma.
  spec.sigma_m = 1e-3;
  camera_T_plane.translation() = Eigen::Vector3d(0, 0, 0.4);
  double sum = 0, sum_sq = 0;
  constexpr int kDraws = 2000;
  for (int i = 0; i < kDraws; ++i) {
    const double e = simulate_ranges(spec, camera_T_plane, rng)[1] - 0.4;
    sum += e;
    sum_sq += e * e;
  }
  CHECK(std::abs(sum / kDraws) < 1e-4);
  CHECK(std::sqrt(sum_sq / kDraws) == doctest::Approx(1e-3).epsilon(0.1));
  spec.spacing_m = -1;
  CHECK_THROWS_WITH_AS(ranger_beams(spec), doctest::Contains("RangerSpec.spacing_m"), std::invalid_argument);
  spec = {};
  spec.sigma_m = -1;
  CHECK_THROWS_WITH_AS(simulate_ranges(spec, camera_T_plane, rng), doctest::Contains("RangerSpec.sigma_m"),
                       std::invalid_argument);
}

TEST_CASE("parameter blocks: intrinsics in float, the geometry block's beams, fiducials and square pitch") {
  CameraSpec camera;
  camera.fx_px = 612.25;
  camera.distortion = {-0.1, 0.02, 0.001, -0.002, 0.003};
  const shared::CameraIntrinsics k = to_intrinsics(camera);
  CHECK(k.fx_px == 612.25f);
  CHECK(k.cx_px == 319.5f);
  CHECK(k.k1 == -0.1f);
  CHECK(k.p2 == -0.002f);
  CHECK(k.k3 == 0.003f);
  CHECK(k.width_px == 640);
  CHECK(k.height_px == 480);
  camera.fx_px = 0;
  CHECK_THROWS_WITH_AS(to_intrinsics(camera), doctest::Contains("fx_px"), std::invalid_argument);

  RangerSpec rangers;
  rangers.spacing_m = 0.12;
  const shared::PlatformGeometry g = platform_geometry(StripSpec{}, rangers);
  CHECK(g.fiducial_count == 6);
  CHECK(g.rangers[0].origin_m[0] == 0.06f);
  CHECK(g.rangers[1].origin_m[1] == 0.06f);
  CHECK(g.rangers[2].origin_m[0] == -0.06f);
  CHECK(g.rangers[3].origin_m[1] == -0.06f);
  for (const shared::RangerBeam& b : g.rangers) CHECK(b.direction[2] == 1.0f);
  CHECK(g.fiducial_square_m[0][0] == static_cast<float>(-7 * 0.0254 / 4));  // p1
  CHECK(g.square_pitch_m == static_cast<float>(4 * 0.0254));                // square k at (k square_m, 0, 0)
  CHECK(g.fiducial_square_m[0][1] == static_cast<float>(7 * 0.0254 / 4));
  CHECK(g.fiducial_square_m[4][0] == static_cast<float>(7 * 0.0254 / 4));  // p5
  StripSpec wide;
  wide.square_m = 2.5;  // beyond the block's square pitch
  CHECK_THROWS_WITH_AS(platform_geometry(wide, rangers), doctest::Contains("square_m"), std::invalid_argument);
}

TEST_CASE("the beacon: bright spots whose centroids are the centre's projections in both cameras") {
  const StereoRigSpec rig;
  ImagingConditions conditions;
  conditions.read_noise_dn = 0;
  conditions.shot_noise_gain = 0;
  const Eigen::Vector3d beacon_device(0.31, -0.12, 4.54);
  const StereoFrame frame = render_beacon(rig, BeaconSpec{}, beacon_device, conditions);
  // The device frame is the right camera's with Y up and X toward the left camera.
  CHECK(frame.right_px.x == doctest::Approx(319.5 - rig.camera.fx_px * 0.31 / 4.54));
  CHECK(frame.right_px.y == doctest::Approx(239.5 + rig.camera.fy_px * 0.12 / 4.54));
  CHECK(frame.left_px.x - frame.right_px.x == doctest::Approx(rig.camera.fx_px * 0.126 / 4.54));
  CHECK(frame.left_px.y == doctest::Approx(frame.right_px.y));
  vision::LabelOptions options;
  options.threshold = 100;
  for (const auto& [image, truth] : {std::pair{frame.left, frame.left_px}, std::pair{frame.right, frame.right_px}}) {
    const vision::LabelResult labels = vision::label_grey(image, options);
    REQUIRE(labels.blobs.size() == 1);
    CHECK(std::abs(labels.blobs[0].x_px.to_double() - truth.x) < 0.05);
    CHECK(std::abs(labels.blobs[0].y_px.to_double() - truth.y) < 0.05);
  }
  // With noise the two images get different noise, reproducibly.
  conditions = {};
  const StereoFrame a = render_beacon(rig, BeaconSpec{}, beacon_device, conditions);
  const StereoFrame b = render_beacon(rig, BeaconSpec{}, beacon_device, conditions);
  CHECK(cv::norm(a.left, b.left, cv::NORM_INF) == 0);
  CHECK(cv::norm(a.right, b.right, cv::NORM_INF) == 0);
  CHECK_THROWS_WITH_AS(render_beacon(rig, BeaconSpec{}, Eigen::Vector3d(0, 0, -1), conditions),
                       doctest::Contains("beacon_device_m"), std::invalid_argument);
  BeaconSpec bad;
  bad.radius_m = 0;
  CHECK_THROWS_WITH_AS(render_beacon(rig, bad, beacon_device, conditions), doctest::Contains("radius_m"),
                       std::invalid_argument);
}

TEST_CASE("the simulated robot: hidden errors of the stated size, the true pose, checked readings") {
  const model::RobotModel nominal = model::load_model(KINCAL_ROBOTS_DIR "/arid_prrr.yaml");
  const SimulatedRobot robot(nominal, 42);
  const SimulatedRobot again(nominal, 42);
  std::mt19937_64 rng(3);
  const std::vector<std::vector<double>> qs = random_configurations(nominal, 30, rng);
  // The tool's RMS offset from the reparameterized nominal robot, for errors of a given scale.
  const model::RobotModel start = identify::reparameterize_for_identification(nominal, 0.1, nullptr);
  const auto offset_rms_m = [&](const ErrorScale& scale) {
    const SimulatedRobot r(nominal, 42, scale);
    double sum_sq = 0;
    for (const auto& q : qs) {
      sum_sq += (r.tool_pose(q).translation - model::forward_kinematics(start, q).translation).squaredNorm();
    }
    return std::sqrt(sum_sq / static_cast<double>(qs.size()));
  };
  ErrorScale none;
  none.length_m = none.angle_rad = none.base_length_m = none.base_angle_rad = 0;
  CHECK(offset_rms_m(none) < 1e-12);
  ErrorScale small, twice;
  small.length_m = 1e-5;
  small.angle_rad = 1e-6;
  small.base_length_m = 2e-5;
  small.base_angle_rad = 2e-6;
  twice.length_m = 2e-5;
  twice.angle_rad = 2e-6;
  twice.base_length_m = 4e-5;
  twice.base_angle_rad = 4e-6;
  // The same seed draws the same unit errors: twice the scale, twice the offset (first order).
  CHECK(offset_rms_m(small) > 1e-5);
  CHECK(offset_rms_m(twice) / offset_rms_m(small) == doctest::Approx(2).epsilon(0.01));
  CHECK(robot.tool_pose(qs[0]).translation == again.tool_pose(qs[0]).translation);
  CHECK(robot.tool_pose(qs[0]).translation != SimulatedRobot(nominal, 43).tool_pose(qs[0]).translation);
  std::vector<double> q = random_configuration(nominal, rng);
  q.pop_back();
  CHECK_THROWS_WITH_AS(robot.tool_pose(q), doctest::Contains("joint readings"), std::invalid_argument);
  q = random_configuration(nominal, rng);
  q[0] = nominal.joints[0].upper + 1;
  CHECK_THROWS_WITH_AS(robot.tool_pose(q), doctest::Contains("joint 1"), std::invalid_argument);
}

}  // namespace
}  // namespace kincal::sim
