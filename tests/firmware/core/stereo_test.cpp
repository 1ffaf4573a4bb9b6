// stereo.hpp against double precision: Kapucu & Baysec's parallel rig (and their numbers), the
// general calibrated pair with distortion and converging cameras, the depth sigma against a
// finite-difference propagation, and every refusal.
#include "firmware/core/stereo.hpp"

#include <doctest.h>

#include <Eigen/Dense>
#include <cmath>

#include "tests/firmware/core/random_source.hpp"

using namespace kincal::core;

namespace {

// Kapucu & Baysec's rig: f = 1 cm, 11 x 13 um cells, 12.6 cm baseline, 640 x 480 image.
ParallelStereoRig kapucu_rig() {
  ParallelStereoRig rig;
  rig.focal_x_px = 0.01f / 11e-6f;
  rig.focal_y_px = 0.01f / 13e-6f;
  rig.baseline_m = 0.126f;
  rig.principal_left_px = Vector2<float>(319.5f, 239.5f);
  rig.principal_right_px = Vector2<float>(319.5f, 239.5f);
  return rig;
}

struct CameraD {
  double fx, fy, cx, cy, k1, k2, p1, p2, k3;
  Eigen::Vector2d pixel(const Eigen::Vector3d& p) const {
    const double x = p.x() / p.z(), y = p.y() / p.z(), r2 = x * x + y * y;
    const double radial = 1 + k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2;
    const double xd = x * radial + 2 * p1 * x * y + p2 * (r2 + 2 * x * x);
    const double yd = y * radial + p1 * (r2 + 2 * y * y) + 2 * p2 * x * y;
    return {fx * xd + cx, fy * yd + cy};
  }
  CameraIntrinsics to_float() const {
    CameraIntrinsics c;
    c.fx_px = static_cast<float>(fx);
    c.fy_px = static_cast<float>(fy);
    c.cx_px = static_cast<float>(cx);
    c.cy_px = static_cast<float>(cy);
    c.distortion = {static_cast<float>(k1), static_cast<float>(k2), static_cast<float>(p1), static_cast<float>(p2),
                    static_cast<float>(k3)};
    c.max_normalized_radius = 1.5f;
    return c;
  }
  // The same camera as the float one holds.
  CameraD rounded() const {
    const CameraIntrinsics f = to_float();
    return {f.fx_px,         f.fy_px,         f.cx_px,         f.cy_px,        f.distortion.k1,
            f.distortion.k2, f.distortion.p1, f.distortion.p2, f.distortion.k3};
  }
};

CameraD random_camera(kincal::test::RandomSource& random) {
  const double f = random.uniform(500, 2500);
  return CameraD{f,
                 f * random.uniform(0.98, 1.02),
                 random.uniform(300, 700),
                 random.uniform(200, 500),
                 random.uniform(-0.2, 0.2),
                 random.uniform(-0.05, 0.08),
                 random.uniform(-0.001, 0.001),
                 random.uniform(-0.001, 0.001),
                 0.0}
      .rounded();
}

// Undistortion in double by Newton on the forward model (reference only).
Eigen::Vector3d ray_d(const CameraD& c, const Eigen::Vector2d& pixel) {
  Eigen::Vector2d xy((pixel.x() - c.cx) / c.fx, (pixel.y() - c.cy) / c.fy);
  const Eigen::Vector2d target = xy;
  for (int i = 0; i < 8; ++i) {  // Newton: quadratic from the distorted point
    const auto f = [&](const Eigen::Vector2d& v) {
      const Eigen::Vector2d p = c.pixel(Eigen::Vector3d(v.x(), v.y(), 1.0));
      return Eigen::Vector2d((p.x() - c.cx) / c.fx, (p.y() - c.cy) / c.fy);
    };
    Eigen::Matrix2d j;
    const double h = 1e-7;
    for (int k = 0; k < 2; ++k)
      j.col(k) = (f(xy + Eigen::Vector2d::Unit(k) * h) - f(xy - Eigen::Vector2d::Unit(k) * h)) / (2 * h);
    xy -= j.inverse() * (f(xy) - target);
  }
  return {xy.x(), xy.y(), 1.0};
}

// Midpoint triangulation in double by the 2x2 normal equations (reference only): z of the point.
Eigen::Vector3d midpoint_d(const Eigen::Vector3d& dl, const Eigen::Vector3d& dr, const Eigen::Vector3d& t) {
  Eigen::Matrix2d a;
  a << dl.dot(dl), -dl.dot(dr), dl.dot(dr), -dr.dot(dr);
  const Eigen::Vector2d su = a.inverse() * Eigen::Vector2d(dl.dot(t), dr.dot(t));
  return 0.5 * (su(0) * dl + t + su(1) * dr);
}

}  // namespace

TEST_CASE("parallel rig: Kapucu & Baysec's geometry, against the closed form in double") {
  const ParallelStereoRig rig = kapucu_rig();
  kincal::test::RandomSource random(0x57E0);
  double worst = 0.0;
  for (int i = 0; i < 3000; ++i) {
    const Eigen::Vector3d p(random.uniform(-1.5, 1.5), random.uniform(-1.0, 1.0), random.uniform(1.0, 8.0));
    const double fx = static_cast<double>(rig.focal_x_px), fy = static_cast<double>(rig.focal_y_px);
    const double b = static_cast<double>(rig.baseline_m), c = 319.5, r = 239.5;
    const Vector2<float> left(static_cast<float>(fx * p.x() / p.z() + c), static_cast<float>(fy * p.y() / p.z() + r));
    const Vector2<float> right(static_cast<float>(fx * (p.x() - b) / p.z() + c), left.y());
    StereoPoint point;
    REQUIRE(triangulate_parallel(rig, left, right, 0.5f, point) == StereoStatus::ok);
    // Reference: the closed form in double on the same float pixels.
    const double d = static_cast<double>(left.x()) - static_cast<double>(right.x());
    const double z = fx * b / d;
    const Eigen::Vector3d ref((static_cast<double>(left.x()) - c) * z / fx,
                              (static_cast<double>(left.y()) - r) * z / fy, z);
    // Float pixel columns near 600 carry 3e-5 px of rounding once centred: relative to the
    // disparity that is the floor; the bound scales with it.
    const double columns =
        std::fmax(std::fabs(static_cast<double>(left.x()) - c), std::fabs(static_cast<double>(right.x()) - c));
    worst = std::fmax(worst, (point.point_left_m.cast<double>() - ref).norm() / (z * (1.0 + columns / d)));
  }
  CHECK(worst <= 3e-7);
  MESSAGE("parallel rig worst relative error / (1 + max|u - cx| / d) ", worst);

  // Their numbers: at 4.54 m one pixel of disparity is about 18 cm of depth.
  const float disparity = rig.focal_x_px * rig.baseline_m / 4.54f;
  StereoPoint point;
  REQUIRE(triangulate_parallel(rig, Vector2<float>(330.0f + disparity, 240.0f), Vector2<float>(330.0f, 240.0f),
                               1.0f / std::sqrt(2.0f), point) == StereoStatus::ok);
  CHECK(point.point_left_m.z() == doctest::Approx(4.54).epsilon(1e-5));
  CHECK(point.depth_sigma_m == doctest::Approx(4.54 * 4.54 / (909.0909 * 0.126)).epsilon(1e-4));
  CHECK(point.depth_sigma_m > 0.17f);
  CHECK(point.depth_sigma_m < 0.19f);
}

TEST_CASE("parallel rig refusals") {
  const ParallelStereoRig rig = kapucu_rig();
  StereoPoint point;
  CHECK(triangulate_parallel(rig, {300.0f, 200.0f}, {300.0f, 200.0f}, 0.5f, point) == StereoStatus::zero_disparity);
  CHECK(triangulate_parallel(rig, {300.0f, 200.0f}, {310.0f, 200.0f}, 0.5f, point) == StereoStatus::behind_camera);
  CHECK(triangulate_parallel(rig, {310.0f, 200.0f}, {300.0f, 205.0f}, 0.5f, point) == StereoStatus::rows_mismatch);
  ParallelStereoRig bad = rig;
  bad.baseline_m = 0.0f;
  CHECK(triangulate_parallel(bad, {310.0f, 200.0f}, {300.0f, 200.0f}, 0.5f, point) == StereoStatus::bad_rig);
  CHECK(triangulate_parallel(rig, {NAN, 200.0f}, {300.0f, 200.0f}, 0.5f, point) == StereoStatus::bad_rig);
}

TEST_CASE("general pair: converging cameras with distortion, against double geometry and sigma") {
  kincal::test::RandomSource random(0x9A12);
  double worst_point = 0.0, worst_sigma = 0.0;
  int solved = 0;
  for (int trial = 0; trial < 600; ++trial) {
    const CameraD left = random_camera(random), right = random_camera(random);
    const double baseline = random.uniform(0.1, 0.6);
    // Right camera: along +x, toed in toward the scene by up to 15 degrees, slightly rolled.
    const Eigen::Matrix3d toe = (Eigen::AngleAxisd(-random.uniform(0.0, 0.26), Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(random.uniform(-0.05, 0.05), Eigen::Vector3d::UnitZ()))
                                    .toRotationMatrix();
    const Eigen::Vector3d t(baseline, random.uniform(-0.02, 0.02), random.uniform(-0.02, 0.02));
    StereoPair pair;
    pair.left = left.to_float();
    pair.right = right.to_float();
    pair.left_T_right.rotation = toe.cast<float>();
    pair.left_T_right.translation = t.cast<float>();
    const Eigen::Matrix3d rotation = pair.left_T_right.rotation.cast<double>();
    const Eigen::Vector3d translation = pair.left_T_right.translation.cast<double>();

    const double z = random.uniform(0.5, 5.0);
    const Eigen::Vector3d p(random.uniform(-0.3, 0.3) * z + 0.5 * baseline, random.uniform(-0.25, 0.25) * z, z);
    const Eigen::Vector3d p_right = rotation.transpose() * (p - translation);
    if (p_right.z() < 0.3 || std::fabs(p_right.x() / p_right.z()) > 0.6 || std::fabs(p_right.y() / p_right.z()) > 0.6)
      continue;
    const Eigen::Vector2d left_px = left.pixel(p), right_px = right.pixel(p_right);
    StereoPoint point;
    REQUIRE(triangulate_pair(pair, left_px.cast<float>(), right_px.cast<float>(), 0.3f, point) == StereoStatus::ok);
    ++solved;
    worst_point = std::fmax(worst_point, (point.point_left_m.cast<double>() - p).norm() / (z * z / baseline + z));

    // Depth sigma: finite differences of the double pipeline (undistort, midpoint) per pixel axis.
    const auto depth = [&](const Eigen::Vector2d& lp, const Eigen::Vector2d& rp) {
      return midpoint_d(ray_d(left, lp), rotation * ray_d(right, rp), translation).z();
    };
    double variance = 0.0;
    const double h = 1e-3;
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector2d e = Eigen::Vector2d::Unit(k) * h;
      const double dl = (depth(left_px + e, right_px) - depth(left_px - e, right_px)) / (2 * h);
      const double dr = (depth(left_px, right_px + e) - depth(left_px, right_px - e)) / (2 * h);
      variance += dl * dl + dr * dr;
    }
    const double sigma_ref = 0.3 * std::sqrt(variance);
    worst_sigma = std::fmax(worst_sigma, std::fabs(static_cast<double>(point.depth_sigma_m) - sigma_ref) / sigma_ref);
  }
  CHECK(solved > 400);
  CHECK(worst_point <= static_cast<double>(kStereoPointErrorPerM2));
  CHECK(worst_sigma <= 1e-4);
  MESSAGE("general pair worst point error / (Z^2/b + Z) ", worst_point, ", depth sigma relative ", worst_sigma,
          " over ", solved, " points");
}

TEST_CASE("general pair reduces to the parallel rig; refusals") {
  const ParallelStereoRig rig = kapucu_rig();
  StereoPair pair;
  pair.left.fx_px = pair.right.fx_px = rig.focal_x_px;
  pair.left.fy_px = pair.right.fy_px = rig.focal_y_px;
  pair.left.cx_px = pair.right.cx_px = 319.5f;
  pair.left.cy_px = pair.right.cy_px = 239.5f;
  pair.left_T_right.translation = Vector3<float>(rig.baseline_m, 0.0f, 0.0f);
  StereoPoint general, parallel;
  const Vector2<float> left(402.25f, 180.5f), right(377.0f, 180.5f);
  REQUIRE(triangulate_pair(pair, left, right, 0.5f, general) == StereoStatus::ok);
  REQUIRE(triangulate_parallel(rig, left, right, 0.5f, parallel) == StereoStatus::ok);
  CHECK((general.point_left_m - parallel.point_left_m).norm() <= 2e-6f * parallel.point_left_m.norm());
  CHECK(general.depth_sigma_m == doctest::Approx(parallel.depth_sigma_m).epsilon(1e-3));

  StereoPoint point;
  CHECK(triangulate_pair(pair, {300.0f, 200.0f}, {300.0f, 200.0f}, 0.5f, point) == StereoStatus::zero_disparity);
  CHECK(triangulate_pair(pair, {300.0f, 200.0f}, {310.0f, 200.0f}, 0.5f, point) == StereoStatus::behind_camera);
  CHECK(triangulate_pair(pair, {310.0f, 200.0f}, {300.0f, 230.0f}, 0.5f, point) == StereoStatus::rays_miss);
  StereoPair folded = pair;
  folded.right.distortion.k1 = -1.0f;
  CHECK(triangulate_pair(folded, {310.0f, 200.0f}, {639.0f, 479.0f}, 0.5f, point) == StereoStatus::undistortion_failed);
  StereoPair bad = pair;
  bad.left_T_right.translation.setZero();
  CHECK(triangulate_pair(bad, {310.0f, 200.0f}, {300.0f, 200.0f}, 0.5f, point) == StereoStatus::bad_rig);
  bad = pair;
  bad.right.fx_px = -1.0f;
  CHECK(triangulate_pair(bad, {310.0f, 200.0f}, {300.0f, 200.0f}, 0.5f, point) == StereoStatus::bad_rig);
}
