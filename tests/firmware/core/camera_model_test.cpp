// camera_model.hpp against an independent double-precision implementation of OpenCV's model:
// projection, undistortion (exact point recovered within 1e-6 normalized), its pixel
// Jacobian, ray-plane intersection, and the refusals.
#include "firmware/core/camera_model.hpp"

#include <doctest.h>

#include <Eigen/Dense>
#include <cmath>

#include "tests/firmware/core/random_source.hpp"

using namespace kincal::core;

namespace {

struct CameraD {
  double fx, fy, cx, cy, k1, k2, p1, p2, k3;
};

// OpenCV's projectPoints for one point, written out in double.
Eigen::Vector2d distort_d(const CameraD& c, const Eigen::Vector2d& xy) {
  const double x = xy.x(), y = xy.y(), r2 = x * x + y * y;
  const double radial = 1 + c.k1 * r2 + c.k2 * r2 * r2 + c.k3 * r2 * r2 * r2;
  return {x * radial + 2 * c.p1 * x * y + c.p2 * (r2 + 2 * x * x),
          y * radial + c.p1 * (r2 + 2 * y * y) + 2 * c.p2 * x * y};
}

Eigen::Vector2d pixel_d(const CameraD& c, const Eigen::Vector2d& xy) {
  const Eigen::Vector2d d = distort_d(c, xy);
  return {c.fx * d.x() + c.cx, c.fy * d.y() + c.cy};
}

CameraIntrinsics to_float(const CameraD& c, float max_radius) {
  CameraIntrinsics f;
  f.fx_px = static_cast<float>(c.fx);
  f.fy_px = static_cast<float>(c.fy);
  f.cx_px = static_cast<float>(c.cx);
  f.cy_px = static_cast<float>(c.cy);
  f.distortion = {static_cast<float>(c.k1), static_cast<float>(c.k2), static_cast<float>(c.p1),
                  static_cast<float>(c.p2), static_cast<float>(c.k3)};
  f.max_normalized_radius = max_radius;
  return f;
}

// Rounds the double camera to what the float one holds, so that the reference and the code
// under test describe the same lens.
CameraD rounded(const CameraD& c) {
  const CameraIntrinsics f = to_float(c, 1.0f);
  return {
      static_cast<double>(f.fx_px),         static_cast<double>(f.fy_px),         static_cast<double>(f.cx_px),
      static_cast<double>(f.cy_px),         static_cast<double>(f.distortion.k1), static_cast<double>(f.distortion.k2),
      static_cast<double>(f.distortion.p1), static_cast<double>(f.distortion.p2), static_cast<double>(f.distortion.k3)};
}

// A lens whose distortion is invertible out to normalized radius 0.9 (|d(r radial)/dr| > 0.15).
CameraD random_camera(kincal::test::RandomSource& random) {
  const double f = random.uniform(300, 2000);
  return rounded({f, f * random.uniform(0.95, 1.05), random.uniform(200, 1000), random.uniform(200, 800),
                  random.uniform(-0.25, 0.25), random.uniform(-0.05, 0.1), random.uniform(-0.002, 0.002),
                  random.uniform(-0.002, 0.002), random.uniform(-0.02, 0.02)});
}

Eigen::Vector2d random_normalized(kincal::test::RandomSource& random, double max_radius) {
  for (;;) {
    const Eigen::Vector2d xy(random.uniform(-max_radius, max_radius), random.uniform(-max_radius, max_radius));
    if (xy.norm() <= max_radius) return xy;
  }
}

}  // namespace

TEST_CASE("project_point matches OpenCV's model in double") {
  kincal::test::RandomSource random(0xCA11);
  double worst_px = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const CameraD c = random_camera(random);
    const Eigen::Vector2d xy = random_normalized(random, 0.9);
    const double z = random.uniform(0.1, 5.0);
    const Eigen::Vector3d p(xy.x() * z, xy.y() * z, z);
    Vector2<float> pixel;
    REQUIRE(project_point(to_float(c, 1.2f), p.cast<float>(), pixel) == CameraStatus::ok);
    worst_px = std::fmax(worst_px, (pixel.cast<double>() - pixel_d(c, p.head<2>() / p.z())).norm() / c.fx);
  }
  CHECK(worst_px <= 4e-7);  // pixel error / fx: a few float roundings of the normalized point
  MESSAGE("project_point worst pixel error / fx ", worst_px);
  Vector2<float> pixel;
  CHECK(project_point(CameraIntrinsics{}, Vector3<float>(0, 0, -1), pixel) == CameraStatus::behind_camera);
  CHECK(project_point(CameraIntrinsics{}, Vector3<float>(3, 0, 1), pixel) == CameraStatus::outside_model_domain);
}

TEST_CASE("pixel_to_normalized recovers the exact ray within 1e-6 and its pixel Jacobian") {
  kincal::test::RandomSource random(0x0D15);
  double worst = 0.0, worst_jacobian = 0.0;
  for (int i = 0; i < 3000; ++i) {
    const CameraD c = random_camera(random);
    const Eigen::Vector2d xy = random_normalized(random, 0.9);
    const Eigen::Vector2d pixel = pixel_d(c, xy);
    NormalizedPoint n;
    REQUIRE(pixel_to_normalized(to_float(c, 1.2f), pixel.cast<float>(), n) == CameraStatus::ok);
    worst = std::fmax(worst, (n.xy.cast<double>() - xy).cwiseAbs().maxCoeff());
    // d(xy)/d(pixel) times a central difference of the forward model must give the identity.
    const double h = 1e-6;
    Eigen::Matrix2d dpixel_dxy;
    for (int k = 0; k < 2; ++k) {
      const Eigen::Vector2d step = Eigen::Vector2d::Unit(k) * h;
      dpixel_dxy.col(k) = (pixel_d(c, xy + step) - pixel_d(c, xy - step)) / (2 * h);
    }
    const Eigen::Matrix2d product = n.xy_per_px.cast<double>() * dpixel_dxy;
    worst_jacobian = std::fmax(worst_jacobian, (product - Eigen::Matrix2d::Identity()).cwiseAbs().maxCoeff());
  }
  CHECK(worst <= 1e-6);
  CHECK(worst_jacobian <= 1e-5);
  MESSAGE("pixel_to_normalized worst error ", worst, ", Jacobian ", worst_jacobian);
}

TEST_CASE("a typical calibrated webcam undistorts over its whole image") {
  // Magnitudes typical of calibrateCamera on a 640x480 webcam (strong barrel distortion).
  const CameraD c = rounded({612.3, 611.8, 319.6, 241.2, -0.412, 0.215, 0.0011, -0.0007, -0.061});
  const CameraIntrinsics f = to_float(c, 1.0f);
  double worst = 0.0;
  for (int v = 0; v <= 480; v += 16) {
    for (int u = 0; u <= 640; u += 16) {
      NormalizedPoint n;
      REQUIRE(pixel_to_normalized(f, Vector2<float>(static_cast<float>(u), static_cast<float>(v)), n) ==
              CameraStatus::ok);
      const Eigen::Vector2d back = pixel_d(c, n.xy.cast<double>());
      worst = std::fmax(worst, (back - Eigen::Vector2d(u, v)).norm());
    }
  }
  CHECK(worst <= 2e-3);  // pixels
}

TEST_CASE("pixels the distortion model cannot invert are refused") {
  // k1 = -1: r radial = r - r^3 folds at r = 0.577, where it reaches 0.385; nothing maps beyond.
  CameraIntrinsics f;
  f.distortion.k1 = -1.0f;
  f.max_normalized_radius = 2.0f;
  NormalizedPoint n;
  CHECK(pixel_to_normalized(f, Vector2<float>(0.3f, 0.0f), n) == CameraStatus::ok);
  CHECK(n.xy.x() < 0.577f);
  const CameraStatus beyond = pixel_to_normalized(f, Vector2<float>(0.5f, 0.1f), n);
  CHECK((beyond == CameraStatus::outside_model_domain || beyond == CameraStatus::not_converged));
  f.max_normalized_radius = 0.2f;
  CHECK(pixel_to_normalized(f, Vector2<float>(0.3f, 0.0f), n) == CameraStatus::outside_model_domain);
  f.fx_px = 0.0f;
  CHECK(pixel_to_normalized(f, Vector2<float>(0.3f, 0.0f), n) == CameraStatus::bad_intrinsics);
}

TEST_CASE("pixels to points on the calibration plane, against double geometry") {
  kincal::test::RandomSource random(0x7E57);
  double worst_rel = 0.0;
  for (int i = 0; i < 2000; ++i) {
    const CameraD c = random_camera(random);
    const Eigen::Vector3d n = random.rotation_up_to(0.6) * Eigen::Vector3d::UnitZ();
    const double rho = random.uniform(0.2, 1.5);
    const Eigen::Vector2d xy = random_normalized(random, 0.8);
    const Eigen::Vector3d ray(xy.x(), xy.y(), 1.0);
    if (n.dot(ray) < 0.2 * ray.norm()) continue;
    const Eigen::Vector3d truth = ray * (rho / n.dot(ray));
    CalibrationPlane plane;
    plane.normal = n.cast<float>();
    plane.distance_m = static_cast<float>(rho);
    Vector3<float> point;
    REQUIRE(pixel_to_plane_point(to_float(c, 1.2f), plane, pixel_d(c, xy).cast<float>(), point) == CameraStatus::ok);
    const double cosine = n.dot(ray) / ray.norm();
    // Undistortion error (2e-6 normalized) plus float rounding, amplified by the incidence.
    worst_rel = std::fmax(worst_rel, (point.cast<double>() - truth).norm() / truth.norm() * cosine);
  }
  CHECK(worst_rel <= 1e-6);
  MESSAGE("pixel_to_plane_point worst relative error x cos(incidence) ", worst_rel);

  CalibrationPlane plane;
  plane.normal = Vector3<float>(1, 0, 0);  // contains the optical axis
  plane.distance_m = 0.5f;
  Vector3<float> point;
  CHECK(point_on_plane(plane, Vector2<float>(0, 0), point) == CameraStatus::ray_misses_plane);
  CHECK(point_on_plane(plane, Vector2<float>(-1, 0), point) == CameraStatus::ray_misses_plane);
  CHECK(point_on_plane(plane, Vector2<float>(1, 0), point) == CameraStatus::ok);
  CHECK(point.isApprox(Vector3<float>(0.5f, 0, 0.5f)));
}
