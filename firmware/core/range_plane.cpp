#include "firmware/core/range_plane.hpp"

#include <algorithm>
#include <cmath>

namespace kincal::core {

namespace {

// The preparation runs once per configuration, with plain float arrays: double arithmetic
// (software on the M4F) and Eigen's out-of-line kernels at -Os would cost several hundred bytes
// of stack, and the stored matrices are float anyway.
using Row = std::array<float, 3>;
using Matrix33 = std::array<Row, 3>;

float determinant(const Matrix33& m) {
  return m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
         m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
}

// Inverse by cofactors; the caller has checked that the determinant is not zero.
Matrix33 inverse(const Matrix33& m, float det) {
  Matrix33 r{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j < 3; ++j) {
      const auto i1 = static_cast<std::size_t>((j + 1) % 3), i2 = static_cast<std::size_t>((j + 2) % 3);
      const auto j1 = static_cast<std::size_t>((i + 1) % 3), j2 = static_cast<std::size_t>((i + 2) % 3);
      r[static_cast<std::size_t>(i)][static_cast<std::size_t>(j)] =
          (m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]) / det;
    }
  }
  return r;
}

using Design = std::array<Row, kRangeSensorCount>;
using FitMatrix = Eigen::Matrix<float, 3, kRangeSensorCount>;

// The exact fit through the sensors other than `left_out`; returns the determinant of their
// rows (zero: collinear, `fit` not written). Not inlined: its frame is not the caller's.
[[gnu::noinline]] float three_point_matrix(const Design& a, std::size_t left_out, FitMatrix& fit) {
  Matrix33 sub{};
  std::size_t row = 0;
  for (std::size_t i = 0; i < kRangeSensorCount; ++i) {
    if (i != left_out) sub[row++] = a[i];
  }
  const float det = determinant(sub);
  if (det == 0.0f) return det;
  const Matrix33 inv = inverse(sub, det);
  fit.setZero();
  std::size_t column = 0;
  for (std::size_t i = 0; i < kRangeSensorCount; ++i) {
    if (i == left_out) continue;
    for (std::size_t r = 0; r < 3; ++r) fit(static_cast<int>(r), static_cast<int>(i)) = inv[r][column];
    ++column;
  }
  return det;
}

// Least squares over all sensors: (A^T A)^-1 A^T.
[[gnu::noinline]] void least_squares_matrix(const Design& a, FitMatrix& fit) {
  Matrix33 normal{};
  for (std::size_t r = 0; r < 3; ++r)
    for (std::size_t c = 0; c < 3; ++c)
      for (std::size_t i = 0; i < kRangeSensorCount; ++i) normal[r][c] += a[i][r] * a[i][c];
  const Matrix33 normal_inverse = inverse(normal, determinant(normal));
  for (std::size_t r = 0; r < 3; ++r) {
    for (std::size_t i = 0; i < kRangeSensorCount; ++i) {
      float sum = 0.0f;
      for (std::size_t c = 0; c < 3; ++c) sum += normal_inverse[r][c] * a[i][c];
      fit(static_cast<int>(r), static_cast<int>(i)) = sum;
    }
  }
}

}  // namespace

RangeSensorLayout plus_pattern_layout(float spacing_m, RangeModel model) noexcept {
  RangeSensorLayout layout;
  const float h = 0.5f * spacing_m;
  layout.position_m = {Vector2<float>(h, 0.0f), Vector2<float>(0.0f, h), Vector2<float>(-h, 0.0f),
                       Vector2<float>(0.0f, -h)};
  layout.model = model;
  return layout;
}

PlaneStatus prepare_range_plane(const RangeSensorLayout& layout, RangePlaneModel& model) noexcept {
  if (!(layout.min_range_m >= 0.0f && layout.max_range_m > layout.min_range_m && layout.flatness_tolerance_m > 0.0f &&
        std::isfinite(layout.origin_z_m))) {
    return PlaneStatus::bad_layout;
  }
  // Design matrix rows (1, x_i, y_i): the plane's value at sensor i is row_i . (c0, cx, cy).
  Design a{};
  float extent2 = 0.0f;
  for (std::size_t i = 0; i < kRangeSensorCount; ++i) {
    const float x = layout.position_m[i].x(), y = layout.position_m[i].y();
    if (!std::isfinite(x) || !std::isfinite(y)) return PlaneStatus::bad_layout;
    a[i] = {1.0f, x, y};
    extent2 = std::max(extent2, x * x + y * y);
  }
  if (!(extent2 > 0.0f)) return PlaneStatus::bad_layout;

  model.model = layout.model;
  model.origin_z_m = layout.origin_z_m;
  model.min_range_m = layout.min_range_m;
  model.max_range_m = layout.max_range_m;
  model.flatness_tolerance_m = layout.flatness_tolerance_m;
  model.allow_three_point = layout.allow_three_point;

  std::array<float, kRangeSensorCount> null_vector{};
  float null_norm2 = 0.0f;
  for (std::size_t k = 0; k < kRangeSensorCount; ++k) {
    // Every three sensors must span a triangle: |det| is twice its area; compared with the
    // square of the layout's extent so that the test does not depend on units.
    const float det = three_point_matrix(a, k, model.three_point[k]);
    if (!(std::fabs(det) > 1e-6f * extent2)) return PlaneStatus::bad_layout;
    // Cofactor expansion: the vector orthogonal to the three columns of the design matrix.
    null_vector[k] = (k % 2 == 0 ? 1.0f : -1.0f) * det;
    null_norm2 += det * det;
  }
  least_squares_matrix(a, model.least_squares);
  const float null_norm = std::sqrt(null_norm2);
  for (std::size_t i = 0; i < kRangeSensorCount; ++i)
    model.null_vector(static_cast<int>(i)) = null_vector[i] / null_norm;
  return PlaneStatus::ok;
}

PlaneStatus fit_range_plane(const RangePlaneModel& model, const std::array<float, kRangeSensorCount>& range_m,
                            CalibrationPlane& plane) noexcept {
  Eigen::Matrix<float, kRangeSensorCount, 1> values;
  int bad_count = 0;
  int bad_sensor = 0;
  PlaneStatus bad_status = PlaneStatus::ok;
  for (int i = 0; i < kRangeSensorCount; ++i) {
    const float r = range_m[static_cast<std::size_t>(i)];
    PlaneStatus s = PlaneStatus::ok;
    if (!std::isfinite(r)) {
      s = PlaneStatus::range_missing;
    } else if (r < model.min_range_m || r > model.max_range_m) {
      s = PlaneStatus::range_out_of_limits;
    }
    if (s != PlaneStatus::ok) {
      if (bad_count == 0) bad_status = s;
      bad_sensor = i;
      ++bad_count;
      values(i) = 0.0f;
    } else {
      values(i) = model.model == RangeModel::along_beam ? model.origin_z_m + r : r;
    }
  }
  if (bad_count > 1 || (bad_count == 1 && !model.allow_three_point)) return bad_status;

  const Eigen::Matrix<float, 3, kRangeSensorCount>& fit =
      bad_count == 0 ? model.least_squares : model.three_point[static_cast<std::size_t>(bad_sensor)];
  const Vector3<float> c = fit.lazyProduct(values);

  CalibrationPlane result;
  if (model.model == RangeModel::along_beam) {
    // z = c0 + cx x + cy y  <=>  (-cx, -cy, 1) . p = c0
    const float k = std::sqrt(1.0f + c(1) * c(1) + c(2) * c(2));
    result.normal = Vector3<float>(-c(1), -c(2), 1.0f) / k;
    result.distance_m = c(0) / k;
  } else {
    // h = (rho - n_z z0) - n_x x - n_y y
    const float in_plane = c(1) * c(1) + c(2) * c(2);
    if (!(in_plane < 1.0f)) return PlaneStatus::plane_not_facing;
    const float nz = std::sqrt(1.0f - in_plane);
    result.normal = Vector3<float>(-c(1), -c(2), nz);
    result.distance_m = c(0) + nz * model.origin_z_m;
  }
  if (!(result.distance_m > 0.0f)) return PlaneStatus::plane_not_facing;

  result.sensors_used = static_cast<std::uint8_t>(bad_count == 0 ? 0xFu : (0xFu & ~(1u << bad_sensor)));
  if (bad_count == 0) {
    // Summed in a fixed order, not by Eigen's dot(): a 4-float dot is one SSE packet natively,
    // reduced as (0 + 2) + (1 + 3), against (0 + 1) + (2 + 3) on the M4 -- not the same bits.
    float along_null = 0.0f;
    for (int i = 0; i < kRangeSensorCount; ++i) along_null += model.null_vector(i) * values(i);
    result.flatness_residual_m = model.null_vector.cwiseAbs().maxCoeff() * std::fabs(along_null);
    if (!(result.flatness_residual_m <= model.flatness_tolerance_m)) {
      plane = result;
      return PlaneStatus::not_flat;
    }
  }
  plane = result;
  return PlaneStatus::ok;
}

PlaneStatus range_plane_covariance(const RangePlaneModel& model, const CalibrationPlane& plane, float range_sigma_m,
                                   Matrix3<float>& covariance) noexcept {
  if (!(range_sigma_m > 0.0f && std::isfinite(range_sigma_m))) return PlaneStatus::bad_layout;
  int used = 0, missing = 0;
  for (int i = 0; i < kRangeSensorCount; ++i) {
    if ((plane.sensors_used & (1u << i)) != 0) {
      ++used;
    } else {
      missing = i;
    }
  }
  if (used < kRangeSensorCount - 1) return PlaneStatus::range_missing;
  if (!(plane.normal.z() > 0.0f)) return PlaneStatus::plane_not_facing;
  const Eigen::Matrix<float, 3, kRangeSensorCount>& fit =
      used == kRangeSensorCount ? model.least_squares : model.three_point[static_cast<std::size_t>(missing)];
  // sigma^2 F F^T of the fitted coefficients, summed in a fixed order.
  Matrix3<float> c;
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) {
      float sum = 0.0f;
      for (int i = 0; i < kRangeSensorCount; ++i) sum += fit(r, i) * fit(k, i);
      c(r, k) = range_sigma_m * range_sigma_m * sum;
    }
  }
  if (model.model == RangeModel::along_beam) {
    covariance = c;  // the coefficients are (c0, slope_x, slope_y) already
    return PlaneStatus::ok;
  }
  // Perpendicular: the coefficients are (a0, q_x, q_y) = (distance - n_z z0, -n_x, -n_y) with
  // n_z = sqrt(1 - q_x^2 - q_y^2); c0 = a0 / n_z + z0, slope = q / n_z. J = d(c0, slope)/d(a0, q).
  const float nz = plane.normal.z(), qx = -plane.normal.x(), qy = -plane.normal.y();
  const float a0 = plane.distance_m - nz * model.origin_z_m;
  const float inv_nz = 1.0f / nz, inv_nz3 = inv_nz * inv_nz * inv_nz;
  Matrix3<float> j;
  j << inv_nz, a0 * qx * inv_nz3, a0 * qy * inv_nz3,        //
      0.0f, inv_nz + qx * qx * inv_nz3, qx * qy * inv_nz3,  //
      0.0f, qx * qy * inv_nz3, inv_nz + qy * qy * inv_nz3;
  for (int r = 0; r < 3; ++r) {
    for (int k = 0; k < 3; ++k) {
      float sum = 0.0f;
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) sum += j(r, a) * c(a, b) * j(k, b);
      covariance(r, k) = sum;
    }
  }
  return PlaneStatus::ok;
}

}  // namespace kincal::core
