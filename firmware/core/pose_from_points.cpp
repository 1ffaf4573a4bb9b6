#include "firmware/core/pose_from_points.hpp"

#include <array>
#include <cmath>
#include <limits>

namespace kincal::core {

namespace {

using Matrix4 = std::array<std::array<float, 4>, 4>;

// Sum of the principal 2x2 minors of a symmetric 3x3 matrix: lambda1 l2 + l1 l3 + l2 l3.
float second_invariant(const Matrix3<float>& c) {
  return c(0, 0) * c(1, 1) - c(0, 1) * c(0, 1) + c(0, 0) * c(2, 2) - c(0, 2) * c(0, 2) + c(1, 1) * c(2, 2) -
         c(1, 2) * c(1, 2);
}

bool spread_enough(const Matrix3<float>& scatter, float min_ratio) {
  const float trace = scatter.trace();
  return trace > 0.0f && second_invariant(scatter) >= min_ratio * trace * trace;
}

// One Jacobi rotation zeroing a[p][q] of the symmetric matrix a, accumulated into v's columns.
void jacobi_rotate(Matrix4& a, Matrix4& v, int p, int q) {
  const auto up = static_cast<std::size_t>(p), uq = static_cast<std::size_t>(q);
  const float apq = a[up][uq];
  const float theta = (a[uq][uq] - a[up][up]) / (2.0f * apq);
  // t = tan of the rotation angle, the smaller root of t^2 + 2 t theta - 1 = 0.
  const float abs_theta = std::fabs(theta);
  float t = abs_theta > 1.0e6f ? 0.5f / abs_theta : 1.0f / (abs_theta + std::sqrt(theta * theta + 1.0f));
  if (theta < 0.0f) t = -t;
  const float c = 1.0f / std::sqrt(t * t + 1.0f);
  const float s = t * c;
  const float tau = s / (1.0f + c);
  a[up][up] -= t * apq;
  a[uq][uq] += t * apq;
  a[up][uq] = 0.0f;
  a[uq][up] = 0.0f;
  for (std::size_t r = 0; r < 4; ++r) {
    if (r != up && r != uq) {
      const float g = a[r][up], h = a[r][uq];
      a[r][up] = a[up][r] = g - s * (h + g * tau);
      a[r][uq] = a[uq][r] = h + s * (g - h * tau);
    }
    const float g = v[r][up], h = v[r][uq];
    v[r][up] = g - s * (h + g * tau);
    v[r][uq] = h + s * (g - h * tau);
  }
}

// Eigen-decomposition of a symmetric 4x4 matrix by cyclic Jacobi sweeps (at most
// kHornMaxSweeps): on return a is diagonal (the eigenvalues) and v's columns the eigenvectors.
void jacobi_eigen(Matrix4& a, Matrix4& v) {
  for (std::size_t i = 0; i < 4; ++i)
    for (std::size_t j = 0; j < 4; ++j) v[i][j] = i == j ? 1.0f : 0.0f;
  for (int sweep = 0; sweep < kHornMaxSweeps; ++sweep) {
    float off = 0.0f;
    for (int p = 0; p < 3; ++p)
      for (int q = p + 1; q < 4; ++q) off += std::fabs(a[static_cast<std::size_t>(p)][static_cast<std::size_t>(q)]);
    if (off == 0.0f) return;
    for (int p = 0; p < 3; ++p) {
      for (int q = p + 1; q < 4; ++q) {
        const auto up = static_cast<std::size_t>(p), uq = static_cast<std::size_t>(q);
        const float apq = a[up][uq];
        if (apq == 0.0f) continue;
        // An element too small to change either diagonal entry in float is zero for good.
        const float g = 100.0f * std::fabs(apq);
        if (sweep > 2 && std::fabs(a[up][up]) + g == std::fabs(a[up][up]) &&
            std::fabs(a[uq][uq]) + g == std::fabs(a[uq][uq])) {
          a[up][uq] = a[uq][up] = 0.0f;
          continue;
        }
        jacobi_rotate(a, v, p, q);
      }
    }
  }
}

Matrix3<float> rotation_from_quaternion(float w, float x, float y, float z) {
  Matrix3<float> r;
  r << w * w + x * x - y * y - z * z, 2.0f * (x * y - w * z), 2.0f * (x * z + w * y),  //
      2.0f * (x * y + w * z), w * w - x * x + y * y - z * z, 2.0f * (y * z - w * x),   //
      2.0f * (x * z - w * y), 2.0f * (y * z + w * x), w * w - x * x - y * y + z * z;
  return r;
}

// Centroids, cross-covariance s' c'^T and the scatter of each point set about its centroid.
// The helpers below are not inlined so that their frames do not add up in pose_from_points'.
struct Moments {
  Vector3<float> square_mean, camera_mean;
  Matrix3<float> cross, square_scatter, camera_scatter;
};

[[gnu::noinline]] bool accumulate_moments(std::span<const Vector3<float>> square,
                                          std::span<const Vector3<float>> camera, Moments& m) {
  const std::size_t n = square.size();
  m.square_mean.setZero();
  m.camera_mean.setZero();
  for (std::size_t i = 0; i < n; ++i) {
    if (!square[i].allFinite() || !camera[i].allFinite()) return false;
    m.square_mean += square[i];
    m.camera_mean += camera[i];
  }
  const float inv_n = 1.0f / static_cast<float>(n);
  m.square_mean *= inv_n;
  m.camera_mean *= inv_n;
  m.cross.setZero();
  m.square_scatter.setZero();
  m.camera_scatter.setZero();
  for (std::size_t i = 0; i < n; ++i) {
    const Vector3<float> s = square[i] - m.square_mean;
    const Vector3<float> c = camera[i] - m.camera_mean;
    for (int r = 0; r < 3; ++r) {
      for (int k = 0; k < 3; ++k) {
        m.cross(r, k) += s(r) * c(k);
        m.square_scatter(r, k) += s(r) * s(k);
        m.camera_scatter(r, k) += c(r) * c(k);
      }
    }
  }
  return true;
}

// Horn's unit quaternion (w, x, y, z) from the cross-covariance m; false if the top eigenvalue
// is not separated from the next by min_gap (relative).
[[gnu::noinline]] bool horn_quaternion(const Matrix3<float>& m, float min_gap, std::array<float, 4>& q) {
  Matrix4 horn{};
  horn[0] = {m(0, 0) + m(1, 1) + m(2, 2), m(1, 2) - m(2, 1), m(2, 0) - m(0, 2), m(0, 1) - m(1, 0)};
  horn[1] = {horn[0][1], m(0, 0) - m(1, 1) - m(2, 2), m(0, 1) + m(1, 0), m(2, 0) + m(0, 2)};
  horn[2] = {horn[0][2], horn[1][2], -m(0, 0) + m(1, 1) - m(2, 2), m(1, 2) + m(2, 1)};
  horn[3] = {horn[0][3], horn[1][3], horn[2][3], -m(0, 0) - m(1, 1) + m(2, 2)};
  Matrix4 vectors;
  jacobi_eigen(horn, vectors);

  std::size_t best = 0;
  for (std::size_t k = 1; k < 4; ++k)
    if (horn[k][k] > horn[best][best]) best = k;
  float second = -std::numeric_limits<float>::infinity();
  for (std::size_t k = 0; k < 4; ++k)
    if (k != best && horn[k][k] > second) second = horn[k][k];
  const float top = horn[best][best];
  if (!(top - second > min_gap * std::fabs(top))) return false;
  const float norm = std::sqrt(vectors[0][best] * vectors[0][best] + vectors[1][best] * vectors[1][best] +
                               vectors[2][best] * vectors[2][best] + vectors[3][best] * vectors[3][best]);
  for (std::size_t i = 0; i < 4; ++i) q[i] = vectors[i][best] / norm;
  return true;
}

}  // namespace

PoseStatus pose_from_points(std::span<const Vector3<float>> square_points_m,
                            std::span<const Vector3<float>> camera_points_m, const PoseOptions& options,
                            PoseFit& fit) noexcept {
  if (square_points_m.size() != camera_points_m.size()) return PoseStatus::size_mismatch;
  if (square_points_m.size() < static_cast<std::size_t>(kMinPosePoints)) return PoseStatus::too_few_points;
  if (square_points_m.size() > static_cast<std::size_t>(kMaxPosePoints)) return PoseStatus::too_many_points;
  const std::size_t n = square_points_m.size();

  Moments m;
  if (!accumulate_moments(square_points_m, camera_points_m, m)) return PoseStatus::non_finite;
  if (!spread_enough(m.square_scatter, options.min_spread_ratio) ||
      !spread_enough(m.camera_scatter, options.min_spread_ratio)) {
    return PoseStatus::collinear_points;
  }
  // Horn's matrix from the cross-covariance scaled by 1/trace of the square scatter, so that
  // its entries are O(1) whatever the units.
  std::array<float, 4> q{};
  if (!horn_quaternion(m.cross / m.square_scatter.trace(), options.min_eigen_gap, q)) {
    return PoseStatus::ambiguous_rotation;
  }

  fit.camera_T_square.rotation = rotation_from_quaternion(q[0], q[1], q[2], q[3]);
  fit.camera_T_square.translation = m.camera_mean - fit.camera_T_square.rotation * m.square_mean;
  float sum2 = 0.0f;
  for (std::size_t i = 0; i < n; ++i)
    sum2 += (fit.camera_T_square * square_points_m[i] - camera_points_m[i]).squaredNorm();
  fit.residual_rms_m = std::sqrt(sum2 / static_cast<float>(n));
  fit.point_count = static_cast<int>(n);
  return PoseStatus::ok;
}

}  // namespace kincal::core
