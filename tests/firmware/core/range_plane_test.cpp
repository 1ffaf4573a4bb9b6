// range_plane.hpp against a double-precision reference: exact planes recovered within the
// stated bound for both range models, least squares equal to a double normal-equation fit,
// Doty's planarity condition as the flatness residual, and every status.
#include "firmware/core/range_plane.hpp"

#include <doctest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <numbers>

#include "tests/firmware/core/random_source.hpp"

using namespace kincal::core;

namespace {

struct PlaneD {
  Eigen::Vector3d normal;  // unit, n_z > 0
  double distance_m;
};

// Exact readings of a plane by a layout, in double.
std::array<double, 4> exact_readings(const RangeSensorLayout& layout, const PlaneD& plane) {
  std::array<double, 4> r{};
  for (std::size_t i = 0; i < 4; ++i) {
    const Eigen::Vector3d s(static_cast<double>(layout.position_m[i].x()),
                            static_cast<double>(layout.position_m[i].y()), static_cast<double>(layout.origin_z_m));
    const double gap = plane.distance_m - plane.normal.dot(s);
    r[i] = layout.model == RangeModel::along_beam ? gap / plane.normal.z() : gap;
  }
  return r;
}

std::array<float, 4> to_float(const std::array<double, 4>& r) {
  return {static_cast<float>(r[0]), static_cast<float>(r[1]), static_cast<float>(r[2]), static_cast<float>(r[3])};
}

PlaneD random_plane(kincal::test::RandomSource& random, double max_tilt_rad, double min_m, double max_m) {
  const Eigen::Matrix3d tilt = random.rotation_up_to(max_tilt_rad);
  return {tilt * Eigen::Vector3d::UnitZ(), random.uniform(min_m, max_m)};
}

double angle_between(const Vector3<float>& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ad = a.cast<double>();
  return std::atan2(ad.cross(b).norm(), ad.dot(b));
}

// Least squares in double, straight from the definition: minimize sum (z_i - c0 - cx x_i - cy y_i)^2.
Eigen::Vector3d reference_fit(const RangeSensorLayout& layout, const Eigen::Vector4d& values) {
  Eigen::Matrix<double, 4, 3> a;
  for (int i = 0; i < 4; ++i) {
    const auto& p = layout.position_m[static_cast<std::size_t>(i)];
    a.row(i) << 1.0, static_cast<double>(p.x()), static_cast<double>(p.y());
  }
  return (a.transpose() * a).ldlt().solve(a.transpose() * values);
}

}  // namespace

TEST_CASE("exact planes come back within the stated bound, both range models, four and three sensors") {
  kincal::test::RandomSource random(0x9A7E);
  for (const RangeModel model : {RangeModel::along_beam, RangeModel::perpendicular}) {
    double worst_normal_ratio = 0.0, worst_distance_ratio = 0.0;
    for (int trial = 0; trial < 2000; ++trial) {
      const double spacing = random.uniform(0.05, 0.3);
      RangeSensorLayout layout = plus_pattern_layout(static_cast<float>(spacing), model);
      layout.origin_z_m = static_cast<float>(random.uniform(-0.02, 0.02));
      layout.max_range_m = 3.0f;
      RangePlaneModel prepared;
      REQUIRE(prepare_range_plane(layout, prepared) == PlaneStatus::ok);
      const PlaneD truth = random_plane(random, 40.0 * std::numbers::pi / 180.0, 0.3, 1.5);
      const auto exact = exact_readings(layout, truth);
      double max_range = 0.0;
      for (double r : exact) max_range = std::fmax(max_range, r);
      if (*std::min_element(exact.begin(), exact.end()) < 0.05 || max_range > 2.0) continue;
      std::array<float, 4> readings = to_float(exact);
      const int left_out = trial % 5;  // 4: all four sensors
      if (left_out < 4) readings[static_cast<std::size_t>(left_out)] = NAN;
      CalibrationPlane plane;
      REQUIRE(fit_range_plane(prepared, readings, plane) == PlaneStatus::ok);
      CHECK(plane.sensors_used == (left_out < 4 ? (0xF & ~(1 << left_out)) : 0xF));
      worst_normal_ratio =
          std::fmax(worst_normal_ratio, angle_between(plane.normal, truth.normal) / (max_range / spacing));
      worst_distance_ratio =
          std::fmax(worst_distance_ratio, std::fabs(static_cast<double>(plane.distance_m) - truth.distance_m) /
                                              (max_range * (1.0 + max_range / spacing)));
      if (left_out == 4) CHECK(static_cast<double>(plane.flatness_residual_m) <= 4e-7 * max_range);
    }
    CHECK(worst_normal_ratio <= static_cast<double>(kPlaneNormalErrorPerRange));
    CHECK(worst_distance_ratio <= static_cast<double>(kPlaneDistanceErrorPerRange));
    MESSAGE("range plane model ", static_cast<int>(model), ": normal error / (range/spacing) ", worst_normal_ratio,
            ", distance error / (range (1 + range/spacing)) ", worst_distance_ratio);
  }
}

TEST_CASE("four readings off a plane: the fit is the least-squares plane, the residual Doty's 7-24 defect") {
  kincal::test::RandomSource random(0xF1A7);
  for (int trial = 0; trial < 500; ++trial) {
    RangeSensorLayout layout =
        plus_pattern_layout(static_cast<float>(random.uniform(0.05, 0.2)), RangeModel::along_beam);
    layout.flatness_tolerance_m = 0.003f;
    RangePlaneModel prepared;
    REQUIRE(prepare_range_plane(layout, prepared) == PlaneStatus::ok);
    const PlaneD truth = random_plane(random, 0.5, 0.3, 1.0);
    auto exact = exact_readings(layout, truth);
    for (double& r : exact) r += random.uniform(-0.004, 0.004);
    const auto readings = to_float(exact);
    // Doty's condition for the + pattern: opposite pairs have equal sums; the least-squares
    // residual of each sensor is a quarter of the difference.
    const double defect = std::fabs(static_cast<double>(readings[0]) - static_cast<double>(readings[1]) +
                                    static_cast<double>(readings[2]) - static_cast<double>(readings[3])) /
                          4.0;
    CalibrationPlane plane;
    const PlaneStatus status = fit_range_plane(prepared, readings, plane);
    CHECK(std::fabs(static_cast<double>(plane.flatness_residual_m) - defect) <= 1e-6);
    if (defect > 0.003 + 1e-6) CHECK(status == PlaneStatus::not_flat);
    if (defect < 0.003 - 1e-6) CHECK(status == PlaneStatus::ok);
    Eigen::Vector4d values;
    for (int i = 0; i < 4; ++i) values(i) = static_cast<double>(readings[static_cast<std::size_t>(i)]);
    const Eigen::Vector3d c = reference_fit(layout, values);
    const Eigen::Vector3d n = Eigen::Vector3d(-c(1), -c(2), 1.0).normalized();
    CHECK(angle_between(plane.normal, n) <= 2e-6);
    CHECK(std::fabs(static_cast<double>(plane.distance_m) - c(0) * n.z()) <= 1e-6);
  }
}

TEST_CASE("missing and out-of-limit readings, planes behind the camera, bad layouts") {
  RangeSensorLayout layout = plus_pattern_layout(0.1f, RangeModel::along_beam);
  RangePlaneModel prepared;
  REQUIRE(prepare_range_plane(layout, prepared) == PlaneStatus::ok);
  CalibrationPlane plane;
  CHECK(fit_range_plane(prepared, {0.5f, NAN, 0.5f, NAN}, plane) == PlaneStatus::range_missing);
  CHECK(fit_range_plane(prepared, {0.5f, 9.0f, 0.5f, INFINITY}, plane) == PlaneStatus::range_out_of_limits);
  CHECK(fit_range_plane(prepared, {0.5f, 0.001f, 0.5f, 0.5f}, plane) == PlaneStatus::ok);  // three-point
  CHECK(plane.sensors_used == 0xD);
  CHECK(fit_range_plane(prepared, {0.5f, 0.5f, 0.5f, 0.5f}, plane) == PlaneStatus::ok);
  CHECK(plane.normal.isApprox(Vector3<float>(0, 0, 1)));
  CHECK(plane.distance_m == doctest::Approx(0.5));

  layout.allow_three_point = false;
  REQUIRE(prepare_range_plane(layout, prepared) == PlaneStatus::ok);
  CHECK(fit_range_plane(prepared, {0.5f, 0.001f, 0.5f, 0.5f}, plane) == PlaneStatus::range_out_of_limits);
  CHECK(fit_range_plane(prepared, {0.5f, 0.5f, NAN, 0.5f}, plane) == PlaneStatus::range_missing);

  layout = plus_pattern_layout(0.1f, RangeModel::along_beam);
  layout.origin_z_m = -0.2f;  // rangers mounted behind the projection centre
  REQUIRE(prepare_range_plane(layout, prepared) == PlaneStatus::ok);
  CHECK(fit_range_plane(prepared, {0.1f, 0.1f, 0.1f, 0.1f}, plane) == PlaneStatus::plane_not_facing);

  layout = plus_pattern_layout(0.1f, RangeModel::perpendicular);
  REQUIRE(prepare_range_plane(layout, prepared) == PlaneStatus::ok);
  // Differences across a pair larger than the spacing: no unit normal fits.
  CHECK(fit_range_plane(prepared, {0.1f, 0.3f, 0.3f, 0.1f}, plane) == PlaneStatus::plane_not_facing);

  layout = plus_pattern_layout(0.1f, RangeModel::along_beam);
  layout.position_m[1] = Vector2<float>(0.0f, 0.0f);  // sensors 0, 1, 2 on the x axis
  CHECK(prepare_range_plane(layout, prepared) == PlaneStatus::bad_layout);
  layout = plus_pattern_layout(0.1f, RangeModel::along_beam);
  layout.max_range_m = layout.min_range_m;
  CHECK(prepare_range_plane(layout, prepared) == PlaneStatus::bad_layout);
}
