#include "firmware/core/planar_pose.hpp"

#include <cmath>

#include "firmware/core/pose_from_points.hpp"

namespace kincal::core {

namespace {

// Symmetric positive definite systems of size N in packed lower-triangular storage (row-major:
// element (i, j), j <= i, at i (i + 1) / 2 + j), factored in place by Cholesky. Plain loops: the
// same order of operations on every target, and nothing Eigen could send to a GEMM kernel.
constexpr int packed_index(int i, int j) { return i * (i + 1) / 2 + j; }

template <int N>
using Vector = std::array<float, static_cast<std::size_t>(N)>;
template <int N>
using Packed = std::array<float, static_cast<std::size_t>(N*(N + 1) / 2)>;

template <int N>
float& at(Packed<N>& a, int i, int j) {
  return a[static_cast<std::size_t>(packed_index(i, j))];
}
template <int N>
float at(const Packed<N>& a, int i, int j) {
  return a[static_cast<std::size_t>(packed_index(i, j))];
}

// A = L L^T in place. False when a pivot is not above kMinRelativePivot times its diagonal entry
// (singular in float) or not finite.
constexpr float kMinRelativePivot = 1.0e-7f;

template <int N>
[[gnu::noinline]] bool cholesky(Packed<N>& a) {
  for (int j = 0; j < N; ++j) {
    const float diagonal = at<N>(a, j, j);
    float d = diagonal;
    for (int k = 0; k < j; ++k) d -= at<N>(a, j, k) * at<N>(a, j, k);
    if (!(d > kMinRelativePivot * diagonal) || !std::isfinite(d)) return false;
    const float l = std::sqrt(d);
    at<N>(a, j, j) = l;
    for (int i = j + 1; i < N; ++i) {
      float s = at<N>(a, i, j);
      for (int k = 0; k < j; ++k) s -= at<N>(a, i, k) * at<N>(a, j, k);
      at<N>(a, i, j) = s / l;
    }
  }
  return true;
}

// Solves L L^T x = b in place (b becomes x).
template <int N>
[[gnu::noinline]] void cholesky_solve(const Packed<N>& l, Vector<N>& b) {
  for (int i = 0; i < N; ++i) {
    float s = b[static_cast<std::size_t>(i)];
    for (int k = 0; k < i; ++k) s -= at<N>(l, i, k) * b[static_cast<std::size_t>(k)];
    b[static_cast<std::size_t>(i)] = s / at<N>(l, i, i);
  }
  for (int i = N - 1; i >= 0; --i) {
    float s = b[static_cast<std::size_t>(i)];
    for (int k = i + 1; k < N; ++k) s -= at<N>(l, k, i) * b[static_cast<std::size_t>(k)];
    b[static_cast<std::size_t>(i)] = s / at<N>(l, i, i);
  }
}

// Adds w w^T to the packed matrix and w e to the gradient.
template <int N>
[[gnu::noinline]] void accumulate(Packed<N>& normal, Vector<N>& gradient, const Vector<N>& w, float e) {
  for (int i = 0; i < N; ++i) {
    const float wi = w[static_cast<std::size_t>(i)];
    for (int j = 0; j <= i; ++j) at<N>(normal, i, j) += wi * w[static_cast<std::size_t>(j)];
    gradient[static_cast<std::size_t>(i)] += wi * e;
  }
}

float dot3(const Vector3<float>& a, const Vector3<float>& b) { return a.x() * b.x() + a.y() * b.y() + a.z() * b.z(); }

Vector3<float> cross3(const Vector3<float>& a, const Vector3<float>& b) {
  return Vector3<float>(a.y() * b.z() - a.z() * b.y(), a.z() * b.x() - a.x() * b.z(), a.x() * b.y() - a.y() * b.x());
}

float norm3(const Vector3<float>& a) { return std::sqrt(dot3(a, a)); }

// p = R (x, y, 0) + t
Vector3<float> target_to_camera(const RigidTransform<float>& pose, const Vector2<float>& target_m) {
  const Matrix3<float>& r = pose.rotation;
  return Vector3<float>(r(0, 0) * target_m.x() + r(0, 1) * target_m.y() + pose.translation.x(),
                        r(1, 0) * target_m.x() + r(1, 1) * target_m.y() + pose.translation.y(),
                        r(2, 0) * target_m.x() + r(2, 1) * target_m.y() + pose.translation.z());
}

// The rotation with columns r1, r2 nearest (symmetrically) to the given ones, and r3 = r1 x r2.
// False if they are (nearly) parallel or zero.
bool rotation_from_two_columns(const Vector3<float>& c1, const Vector3<float>& c2, Matrix3<float>& rotation) {
  const float n1 = norm3(c1), n2 = norm3(c2);
  if (!(n1 > 0.0f && n2 > 0.0f)) return false;
  const Vector3<float> a = c1 / n1, b = c2 / n2;
  const Vector3<float> sum = a + b, difference = a - b;
  const float ns = norm3(sum), nd = norm3(difference);
  if (!(ns > 1.0e-3f && nd > 1.0e-3f)) return false;
  // a + b and a - b are orthogonal for unit a, b; their bisectors are the nearest orthonormal pair.
  const Vector3<float> u = sum / ns, w = difference / nd;
  constexpr float kInvSqrt2 = 0.70710678118654752f;
  const Vector3<float> r1 = (u + w) * kInvSqrt2, r2 = (u - w) * kInvSqrt2;
  rotation.col(0) = r1;
  rotation.col(1) = r2;
  rotation.col(2) = cross3(r1, r2);
  return true;
}

Matrix3<float> rotation_from_small_vector(const Vector3<float>& phi) {
  // The unit quaternion (1, phi / 2) normalized: a proper rotation, exp([phi]x) to second order.
  const float x = 0.5f * phi.x(), y = 0.5f * phi.y(), z = 0.5f * phi.z();
  const float inv = 1.0f / std::sqrt(1.0f + x * x + y * y + z * z);
  const float w = inv, qx = x * inv, qy = y * inv, qz = z * inv;
  Matrix3<float> r;
  r << 1.0f - 2.0f * (qy * qy + qz * qz), 2.0f * (qx * qy - w * qz), 2.0f * (qx * qz + w * qy),  //
      2.0f * (qx * qy + w * qz), 1.0f - 2.0f * (qx * qx + qz * qz), 2.0f * (qy * qz - w * qx),   //
      2.0f * (qx * qz - w * qy), 2.0f * (qy * qz + w * qx), 1.0f - 2.0f * (qx * qx + qy * qy);
  return r;
}

Matrix3<float> multiply3(const Matrix3<float>& a, const Matrix3<float>& b) {
  Matrix3<float> c;
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j) c(i, j) = a(i, 0) * b(0, j) + a(i, 1) * b(1, j) + a(i, 2) * b(2, j);
  return c;
}

bool finite_pose(const RigidTransform<float>& pose) {
  return pose.rotation.allFinite() && pose.translation.allFinite();
}

// ---- start: homography of the normalized points (n >= 4) -------------------------------------

[[gnu::noinline]] PlanarPoseStatus homography_start(std::span<const PlanarCorrespondence> points,
                                                    PlanarPoseWorkspace& ws, RigidTransform<float>& pose) {
  const std::size_t n = points.size();
  const float inv_n = 1.0f / static_cast<float>(n);
  // Hartley normalization: centroids at the origin, RMS distance sqrt(2).
  float sx = 0.0f, sy = 0.0f, ix = 0.0f, iy = 0.0f;
  for (std::size_t i = 0; i < n; ++i) {
    sx += points[i].target_m.x();
    sy += points[i].target_m.y();
    ix += ws.normalized_xy[i].x();
    iy += ws.normalized_xy[i].y();
  }
  sx *= inv_n;
  sy *= inv_n;
  ix *= inv_n;
  iy *= inv_n;
  float s2 = 0.0f, i2 = 0.0f;
  for (std::size_t i = 0; i < n; ++i) {
    const float dx = points[i].target_m.x() - sx, dy = points[i].target_m.y() - sy;
    const float ex = ws.normalized_xy[i].x() - ix, ey = ws.normalized_xy[i].y() - iy;
    s2 += dx * dx + dy * dy;
    i2 += ex * ex + ey * ey;
  }
  if (!(s2 > 0.0f && i2 > 0.0f)) return PlanarPoseStatus::degenerate_geometry;
  const float ks = std::sqrt(2.0f / (s2 * inv_n)), ki = std::sqrt(2.0f / (i2 * inv_n));

  // DLT with h33 = 1: rows [X Y 1 0 0 0 -xX -xY] h = x and [0 0 0 X Y 1 -yX -yY] h = y.
  Packed<8>& normal = ws.homography_normal;
  Vector<8>& rhs = ws.homography_rhs;
  normal.fill(0.0f);
  rhs.fill(0.0f);
  for (std::size_t i = 0; i < n; ++i) {
    const float X = (points[i].target_m.x() - sx) * ks, Y = (points[i].target_m.y() - sy) * ks;
    const float x = (ws.normalized_xy[i].x() - ix) * ki, y = (ws.normalized_xy[i].y() - iy) * ki;
    accumulate<8>(normal, rhs, {X, Y, 1.0f, 0.0f, 0.0f, 0.0f, -x * X, -x * Y}, x);
    accumulate<8>(normal, rhs, {0.0f, 0.0f, 0.0f, X, Y, 1.0f, -y * X, -y * Y}, y);
  }
  if (!cholesky<8>(normal)) return PlanarPoseStatus::degenerate_geometry;
  cholesky_solve<8>(normal, rhs);
  // H = Ti^-1 Hn Ts with Ts = [ks 0 -ks sx; 0 ks -ks sy; 0 0 1], Ti^-1 = [1/ki 0 ix; 0 1/ki iy; 0 0 1],
  // written out column by column (h33 of Hn is 1).
  const auto hn = [&rhs](int r, int c) { return r == 2 && c == 2 ? 1.0f : rhs[static_cast<std::size_t>(3 * r + c)]; };
  const float inv_ki = 1.0f / ki;
  std::array<Vector3<float>, 3> columns;  // H's columns h1, h2, h3
  for (int c = 0; c < 3; ++c) {
    Vector3<float> m;  // column c of Hn Ts
    for (int r = 0; r < 3; ++r) m(r) = c < 2 ? ks * hn(r, c) : hn(r, 2) - ks * sx * hn(r, 0) - ks * sy * hn(r, 1);
    columns[static_cast<std::size_t>(c)] = Vector3<float>(m(0) * inv_ki + ix * m(2), m(1) * inv_ki + iy * m(2), m(2));
  }
  const Vector3<float>& h1 = columns[0];
  const Vector3<float>& h2 = columns[1];
  const Vector3<float>& h3 = columns[2];
  if (!h1.allFinite() || !h2.allFinite() || !h3.allFinite()) return PlanarPoseStatus::degenerate_geometry;

  // H ~ [r1 r2 t]: the scale from the two rotation columns, the sign from the depth of the
  // target points' centroid (third row of H at it).
  const float scale_norm = 0.5f * (norm3(h1) + norm3(h2));
  if (!(scale_norm > 0.0f)) return PlanarPoseStatus::degenerate_geometry;
  const float depth = h1.z() * sx + h2.z() * sy + h3.z();
  const float lambda = (depth > 0.0f ? 1.0f : -1.0f) / scale_norm;
  if (!rotation_from_two_columns(h1 * lambda, h2 * lambda, pose.rotation)) return PlanarPoseStatus::degenerate_geometry;
  pose.translation = h3 * lambda;
  return PlanarPoseStatus::ok;
}

// ---- start: three rays on the prior plane (n = 3) ----------------------------------------------

[[gnu::noinline]] PlanarPoseStatus prior_plane_start(std::span<const PlanarCorrespondence> points,
                                                     const CalibrationPlane& plane, PlanarPoseWorkspace& ws,
                                                     RigidTransform<float>& pose) {
  const std::size_t n = points.size();  // 3
  for (std::size_t i = 0; i < n; ++i) {
    if (point_on_plane(plane, ws.normalized_xy[i], ws.scratch3[n + i]) != CameraStatus::ok)
      return PlanarPoseStatus::bad_prior;
    ws.scratch3[i] = Vector3<float>(points[i].target_m.x(), points[i].target_m.y(), 0.0f);
  }
  PoseFit fit;
  const PoseStatus status =
      pose_from_points(std::span<const Vector3<float>>(ws.scratch3.data(), n),
                       std::span<const Vector3<float>>(ws.scratch3.data() + n, n), PoseOptions{}, fit);
  if (status != PoseStatus::ok) return PlanarPoseStatus::degenerate_geometry;
  pose = fit.camera_T_square;
  return PlanarPoseStatus::ok;
}

// ---- the prior --------------------------------------------------------------------------------

using planar_pose_detail::WhitenedPrior;

bool prepare_prior(const PlanePrior& prior, WhitenedPrior& w) {
  const CalibrationPlane& p = prior.plane;
  if (!p.normal.allFinite() || !std::isfinite(p.distance_m) || !prior.covariance.allFinite()) return false;
  if (!(p.normal.z() > kMinRayPlaneCosine) || !(p.distance_m > 0.0f)) return false;
  w.slope_form =
      Vector3<float>(p.distance_m / p.normal.z(), -p.normal.x() / p.normal.z(), -p.normal.y() / p.normal.z());
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j <= i; ++j) {
      if (prior.covariance(i, j) != prior.covariance(j, i)) return false;
      at<3>(w.chol, i, j) = prior.covariance(i, j);
    }
  }
  return cholesky<3>(w.chol) && w.slope_form.allFinite();
}

// L^-1 v by forward substitution.
std::array<float, 3> whiten(const Packed<3>& l, const std::array<float, 3>& v) {
  std::array<float, 3> out{};
  for (int i = 0; i < 3; ++i) {
    float s = v[static_cast<std::size_t>(i)];
    for (int k = 0; k < i; ++k) s -= at<3>(l, i, k) * out[static_cast<std::size_t>(k)];
    out[static_cast<std::size_t>(i)] = s / at<3>(l, i, i);
  }
  return out;
}

// The prior's three whitened residuals L^-1 (pose's slope form - prior's) and their Jacobian
// rows with respect to (dt_c, dphi) (the centroid perturbation below). False if the pose's plane
// is seen edge-on (|m_z| <= kMinRayPlaneCosine).
struct WhitenedRows {
  std::array<float, 3> residual{};
  std::array<Vector<6>, 3> jacobian{};
};

bool prior_rows(const WhitenedPrior& prior, const RigidTransform<float>& pose, const Vector3<float>& centre,
                WhitenedRows& out) {
  // The pose's plane: m = R e3, d = m . t; slope form (d / m_z, -m_x / m_z, -m_y / m_z).
  const Vector3<float> m = pose.rotation.col(2);
  if (!(std::fabs(m.z()) > kMinRayPlaneCosine)) return false;
  const float inv_mz = 1.0f / m.z();
  const float plane_d = dot3(m, pose.translation);
  const std::array<float, 3> difference = {plane_d * inv_mz - prior.slope_form.x(),
                                           -m.x() * inv_mz - prior.slope_form.y(),
                                           -m.y() * inv_mz - prior.slope_form.z()};
  // Rows d(c0, slope_x, slope_y)/d(dt_c, dphi): dm = dphi x m; dd = m . dt_c + (m x c) . dphi.
  const float inv_mz2 = inv_mz * inv_mz;
  const Vector3<float> m_cross_c = cross3(m, centre);
  const Vector3<float> dmz(m.y(), -m.x(), 0.0f);  // d m_z / d dphi
  std::array<Vector<6>, 3> rows{};
  for (int k = 0; k < 3; ++k) {
    rows[0][static_cast<std::size_t>(k)] = m(k) * inv_mz;
    rows[0][static_cast<std::size_t>(3 + k)] = m_cross_c(k) * inv_mz - plane_d * dmz(k) * inv_mz2;
  }
  const Vector3<float> dsx(m.x() * m.y(), -(m.z() * m.z() + m.x() * m.x()), m.z() * m.y());
  const Vector3<float> dsy(m.z() * m.z() + m.y() * m.y(), -m.y() * m.x(), -m.z() * m.x());
  for (int k = 0; k < 3; ++k) {
    rows[1][static_cast<std::size_t>(3 + k)] = dsx(k) * inv_mz2;
    rows[2][static_cast<std::size_t>(3 + k)] = dsy(k) * inv_mz2;
  }
  out.residual = whiten(prior.chol, difference);
  for (std::size_t c = 0; c < 6; ++c) {
    const std::array<float, 3> column = whiten(prior.chol, {rows[0][c], rows[1][c], rows[2][c]});
    for (std::size_t r = 0; r < 3; ++r) out.jacobian[r][c] = column[r];
  }
  return true;
}

// ---- Gauss-Newton ------------------------------------------------------------------------------

// The perturbation used inside (better conditioned than the origin's): about the camera-frame
// centroid c of the target points, p' = c + dt_c + exp([dphi]x) (p - c). Converted to the
// header's origin convention for the covariance at the end.
using planar_pose_detail::Linearization;

[[gnu::noinline]] PlanarPoseStatus linearize(const CameraIntrinsics& camera,
                                             std::span<const PlanarCorrespondence> points,
                                             const PlanarPoseWorkspace& ws, const WhitenedPrior* prior, float inv_sigma,
                                             const RigidTransform<float>& pose, const Vector3<float>& centre,
                                             Linearization& lin) {
  lin = Linearization{};
  const float max_r2 = camera.max_normalized_radius * camera.max_normalized_radius;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Vector3<float> p = target_to_camera(pose, points[i].target_m);
    if (!(p.z() > 0.0f)) return PlanarPoseStatus::behind_camera;
    const float inv_z = 1.0f / p.z();
    const float x = p.x() * inv_z, y = p.y() * inv_z;
    if (!(x * x + y * y <= max_r2)) return PlanarPoseStatus::outside_model_domain;
    const Vector2<float> d = distort_normalized(camera.distortion, Vector2<float>(x, y));
    const Eigen::Matrix<float, 2, 2> jd = distortion_jacobian(camera.distortion, x, y);
    const float u = camera.fx_px * d.x() + camera.cx_px, v = camera.fy_px * d.y() + camera.cy_px;
    const Vector3<float> lever = p - centre;
    const float f[2] = {camera.fx_px, camera.fy_px};
    const float residual[2] = {(u - ws.pixel_px[i].x()) * inv_sigma, (v - ws.pixel_px[i].y()) * inv_sigma};
    for (int r = 0; r < 2; ++r) {
      // d(pixel_r)/dp = f_r * jd.row(r) * [1/z 0 -x/z; 0 1/z -y/z], whitened.
      const float a0 = f[r] * jd(r, 0) * inv_sigma, a1 = f[r] * jd(r, 1) * inv_sigma;
      const Vector3<float> b(a0 * inv_z, a1 * inv_z, -(a0 * x + a1 * y) * inv_z);
      const Vector3<float> rot = cross3(lever, b);  // d/d(dphi) of b . (dphi x lever)
      accumulate<6>(lin.normal, lin.gradient, {b.x(), b.y(), b.z(), rot.x(), rot.y(), rot.z()}, residual[r]);
      lin.image_sum2 += residual[r] * residual[r];
    }
  }
  if (prior == nullptr) return PlanarPoseStatus::ok;
  WhitenedRows rows;
  if (!prior_rows(*prior, pose, centre, rows)) return PlanarPoseStatus::degenerate_geometry;
  for (std::size_t r = 0; r < 3; ++r) {
    accumulate<6>(lin.normal, lin.gradient, rows.jacobian[r], rows.residual[r]);
    lin.prior_sum2 += rows.residual[r] * rows.residual[r];
  }
  return PlanarPoseStatus::ok;
}

Vector3<float> centroid_in_camera(std::span<const PlanarCorrespondence> points, const RigidTransform<float>& pose) {
  float x = 0.0f, y = 0.0f;
  for (const PlanarCorrespondence& p : points) {
    x += p.target_m.x();
    y += p.target_m.y();
  }
  const float inv_n = 1.0f / static_cast<float>(points.size());
  return target_to_camera(pose, Vector2<float>(x * inv_n, y * inv_n));
}

// One pass of at most max_iterations steps from `pose`. On ok, `lin` holds the factored normal
// matrix of the last linearization and `centre` its centroid.
[[gnu::noinline]] PlanarPoseStatus gauss_newton(const CameraIntrinsics& camera,
                                                std::span<const PlanarCorrespondence> points,
                                                const PlanarPoseWorkspace& ws, const WhitenedPrior* prior,
                                                const PlanarPoseOptions& options, RigidTransform<float>& pose,
                                                Vector3<float>& centre, Linearization& lin, std::uint8_t& iterations) {
  const float inv_sigma = 1.0f / options.pixel_sigma_px;
  for (int iteration = 0; iteration < options.max_iterations; ++iteration) {
    centre = centroid_in_camera(points, pose);
    const PlanarPoseStatus status = linearize(camera, points, ws, prior, inv_sigma, pose, centre, lin);
    if (status != PlanarPoseStatus::ok) return status;
    if (!cholesky<6>(lin.normal)) return PlanarPoseStatus::degenerate_geometry;
    std::array<float, 6> step = lin.gradient;
    cholesky_solve<6>(lin.normal, step);
    const Vector3<float> dt(-step[0], -step[1], -step[2]), dphi(-step[3], -step[4], -step[5]);
    if (!dt.allFinite() || !dphi.allFinite()) return PlanarPoseStatus::non_finite;
    // t' = c + dt_c + Q (t - c), R' = Q R
    const Matrix3<float> q = rotation_from_small_vector(dphi);
    const Vector3<float> lever = pose.translation - centre;
    Vector3<float> moved;
    for (int k = 0; k < 3; ++k) moved(k) = q(k, 0) * lever.x() + q(k, 1) * lever.y() + q(k, 2) * lever.z();
    pose.translation = centre + dt + moved;
    const Matrix3<float> rotated = multiply3(q, pose.rotation);
    if (!rotation_from_two_columns(rotated.col(0), rotated.col(1), pose.rotation)) return PlanarPoseStatus::non_finite;
    ++iterations;
    const float t_norm = norm3(pose.translation);
    if (!finite_pose(pose)) return PlanarPoseStatus::non_finite;
    if (dphi.cwiseAbs().maxCoeff() <= kPlanarPoseStepTolerance &&
        dt.cwiseAbs().maxCoeff() <= kPlanarPoseStepTolerance * t_norm) {
      return PlanarPoseStatus::ok;
    }
  }
  return PlanarPoseStatus::not_converged;
}

// The chi^2 (3 degrees of freedom) of the disagreement between the image-only pose's plane and the
// prior: e^T S^-1 e with e the whitened prior residual and S = I + G N^-1 G^T its covariance
// (G the whitened rows, N the image-only normal matrix, factored in lin). False if not computable.
[[gnu::noinline]] bool innovation_chi2(const WhitenedPrior& prior, const RigidTransform<float>& pose,
                                       const Vector3<float>& centre, const Linearization& lin, float& chi2) {
  WhitenedRows rows;
  if (!prior_rows(prior, pose, centre, rows)) return false;
  std::array<Vector<6>, 3> solved = rows.jacobian;
  for (Vector<6>& v : solved) cholesky_solve<6>(lin.normal, v);
  Packed<3> s{};
  for (int i = 0; i < 3; ++i) {
    for (int j = 0; j <= i; ++j) {
      float sum = i == j ? 1.0f : 0.0f;
      for (std::size_t k = 0; k < 6; ++k)
        sum += rows.jacobian[static_cast<std::size_t>(i)][k] * solved[static_cast<std::size_t>(j)][k];
      at<3>(s, i, j) = sum;
    }
  }
  if (!cholesky<3>(s)) return false;
  const std::array<float, 3> w = whiten(s, rows.residual);
  chi2 = w[0] * w[0] + w[1] * w[1] + w[2] * w[2];
  return std::isfinite(chi2);
}

// Covariance of [dt; dphi] at the target origin from the factored normal matrix at the centroid:
// dt_origin = dt_c + dphi x (t - c), so cov = T N^-1 T^T with T = [I -[a]x; 0 I], a = t - c.
[[gnu::noinline]] void covariance_at_origin(const Linearization& lin, const Vector3<float>& lever,
                                            Eigen::Matrix<float, 6, 6>& covariance) {
  for (int c = 0; c < 6; ++c) {
    Vector<6> e{};
    e[static_cast<std::size_t>(c)] = 1.0f;
    cholesky_solve<6>(lin.normal, e);
    for (int r = 0; r < 6; ++r) covariance(r, c) = e[static_cast<std::size_t>(r)];
  }
  // In place: T's rows k < 3 add sum_j (-[a]x)(k, j) times row 3 + j (rows 3..5 stay), then the
  // same on the columns for T^T (columns 3..5 stay).
  const float neg_skew[3][3] = {
      {0.0f, lever.z(), -lever.y()}, {-lever.z(), 0.0f, lever.x()}, {lever.y(), -lever.x(), 0.0f}};
  for (int k = 0; k < 3; ++k)
    for (int c = 0; c < 6; ++c)
      for (int j = 0; j < 3; ++j) covariance(k, c) += neg_skew[k][j] * covariance(3 + j, c);
  for (int k = 0; k < 3; ++k)
    for (int r = 0; r < 6; ++r)
      for (int j = 0; j < 3; ++j) covariance(r, k) += covariance(r, 3 + j) * neg_skew[k][j];
}

PlanarPoseStatus finish(PlanarPose& out, PlanarPoseStatus status) {
  out.status = status;
  return status;
}

}  // namespace

PlanarPoseStatus planar_pose(const CameraIntrinsics& camera, std::span<const PlanarCorrespondence> points,
                             const PlanePrior* prior, const PlanarPoseOptions& options, PlanarPoseWorkspace& workspace,
                             PlanarPose& out) noexcept {
  // Field by field: a PlanarPose temporary would be 0.2 KiB of stack.
  out.status = PlanarPoseStatus::not_converged;
  out.camera_T_target = RigidTransform<float>{};
  out.covariance.setZero();
  out.reprojection_rms_px = 0.0f;
  out.prior_mahalanobis = 0.0f;
  out.iterations = 0;
  out.point_count = 0;
  out.prior_used = false;
  out.prior_innovation_chi2 = 0.0f;
  out.prior_rejected = false;
  const std::size_t n = points.size();
  if (n > static_cast<std::size_t>(kPlanarPoseMaxPoints)) return finish(out, PlanarPoseStatus::too_many_points);
  if (n < (prior != nullptr ? 3u : 4u)) return finish(out, PlanarPoseStatus::too_few_points);
  if (!(options.pixel_sigma_px > 0.0f && std::isfinite(options.pixel_sigma_px))) {
    return finish(out, PlanarPoseStatus::non_finite);
  }
  WhitenedPrior& whitened = workspace.prior;
  if (prior != nullptr && !prepare_prior(*prior, whitened)) return finish(out, PlanarPoseStatus::bad_prior);
  const WhitenedPrior* used_prior = prior != nullptr ? &whitened : nullptr;

  // Undistort every pixel; check the target points' spread.
  float mx = 0.0f, my = 0.0f;
  for (std::size_t i = 0; i < n; ++i) {
    if (!points[i].pixel_px.allFinite() || !points[i].target_m.allFinite() ||
        !points[i].fiducial_half_size_m.allFinite()) {
      return finish(out, PlanarPoseStatus::non_finite);
    }
    NormalizedPoint normalized;
    const CameraStatus status = pixel_to_normalized(camera, points[i].pixel_px, normalized);
    if (status == CameraStatus::bad_intrinsics) return finish(out, PlanarPoseStatus::bad_intrinsics);
    if (status != CameraStatus::ok) return finish(out, PlanarPoseStatus::outside_model_domain);
    workspace.normalized_xy[i] = normalized.xy;
    workspace.pixel_px[i] = points[i].pixel_px;
    mx += points[i].target_m.x();
    my += points[i].target_m.y();
  }
  mx /= static_cast<float>(n);
  my /= static_cast<float>(n);
  float sxx = 0.0f, syy = 0.0f, sxy = 0.0f;
  for (std::size_t i = 0; i < n; ++i) {
    const float dx = points[i].target_m.x() - mx, dy = points[i].target_m.y() - my;
    sxx += dx * dx;
    syy += dy * dy;
    sxy += dx * dy;
  }
  const float trace = sxx + syy;
  if (!(trace > 0.0f) || !(sxx * syy - sxy * sxy >= options.min_spread_ratio * trace * trace)) {
    return finish(out, PlanarPoseStatus::collinear_points);
  }

  RigidTransform<float> pose;
  PlanarPoseStatus status =
      n >= 4 ? homography_start(points, workspace, pose) : prior_plane_start(points, prior->plane, workspace, pose);
  if (status != PlanarPoseStatus::ok) return finish(out, status);
  if (!finite_pose(pose)) return finish(out, PlanarPoseStatus::non_finite);

  Linearization& lin = workspace.linearization;
  Vector3<float> centre;
  bool image_only_done = false;
  if (used_prior != nullptr && n >= 4) {
    // The image alone first; the prior joins only if it agrees (a flat but tilted plane, or the
    // rangers on something else, would otherwise pull the pose).
    status = gauss_newton(camera, points, workspace, nullptr, options, pose, centre, lin, out.iterations);
    if (status != PlanarPoseStatus::ok) return finish(out, status);
    if (!innovation_chi2(whitened, pose, centre, lin, out.prior_innovation_chi2)) {
      return finish(out, PlanarPoseStatus::degenerate_geometry);
    }
    if (!(out.prior_innovation_chi2 <= options.prior_gate_chi2)) {
      used_prior = nullptr;
      out.prior_rejected = true;
    }
    image_only_done = true;
  }
  if (!image_only_done || used_prior != nullptr) {
    status = gauss_newton(camera, points, workspace, used_prior, options, pose, centre, lin, out.iterations);
  }
  for (int pass = 0; pass < options.perspective_passes && status == PlanarPoseStatus::ok; ++pass) {
    for (std::size_t i = 0; i < n; ++i) {
      if (points[i].fiducial_half_size_m.x() == 0.0f && points[i].fiducial_half_size_m.y() == 0.0f) continue;
      Vector2<float> bias;
      if (!fiducial_centroid_bias_px(camera, pose, points[i].target_m, points[i].fiducial_half_size_m, bias)) {
        return finish(out, PlanarPoseStatus::outside_model_domain);
      }
      workspace.pixel_px[i] = points[i].pixel_px - bias;
    }
    status = gauss_newton(camera, points, workspace, used_prior, options, pose, centre, lin, out.iterations);
  }
  if (status != PlanarPoseStatus::ok) return finish(out, status);
  // Every point in front of the camera at the result, not only at the last linearization.
  for (std::size_t i = 0; i < n; ++i) {
    if (!(target_to_camera(pose, points[i].target_m).z() > 0.0f)) return finish(out, PlanarPoseStatus::behind_camera);
  }

  out.camera_T_target = pose;
  covariance_at_origin(lin, pose.translation - centre, out.covariance);
  if (!out.covariance.allFinite()) return finish(out, PlanarPoseStatus::non_finite);
  out.reprojection_rms_px = options.pixel_sigma_px * std::sqrt(lin.image_sum2 / static_cast<float>(2 * n));
  out.prior_mahalanobis = std::sqrt(lin.prior_sum2);
  out.point_count = static_cast<std::uint8_t>(n);
  out.prior_used = used_prior != nullptr;
  return finish(out, PlanarPoseStatus::ok);
}

bool fiducial_centroid_bias_px(const CameraIntrinsics& camera, const RigidTransform<float>& camera_T_target,
                               const Vector2<float>& centre_target_m, const Vector2<float>& half_size_m,
                               Vector2<float>& bias_px) noexcept {
  Vector2<float> centre_px;
  if (project_point(camera, target_to_camera(camera_T_target, centre_target_m), centre_px) != CameraStatus::ok)
    return false;
  // The outline counter-clockwise in the target frame: corners (+,+), (-,+), (-,-), (+,-), each
  // edge cut into kFiducialEdgeSegments. Vertices relative to the projected centre (small numbers,
  // little cancellation); shoelace area and first moments of the polygon.
  constexpr float kCornerX[4] = {1.0f, -1.0f, -1.0f, 1.0f}, kCornerY[4] = {1.0f, 1.0f, -1.0f, -1.0f};
  constexpr int kVertices = 4 * kFiducialEdgeSegments;
  float area2 = 0.0f, moment_x = 0.0f, moment_y = 0.0f;
  Vector2<float> first = Vector2<float>::Zero(), previous = Vector2<float>::Zero();
  for (int k = 0; k <= kVertices; ++k) {
    Vector2<float> q;
    if (k == kVertices) {
      q = first;
    } else {
      const int edge = k / kFiducialEdgeSegments, step = k % kFiducialEdgeSegments;
      const auto e0 = static_cast<std::size_t>(edge), e1 = static_cast<std::size_t>((edge + 1) % 4);
      const float f = static_cast<float>(step) / static_cast<float>(kFiducialEdgeSegments);
      const float ux = kCornerX[e0] + f * (kCornerX[e1] - kCornerX[e0]);
      const float uy = kCornerY[e0] + f * (kCornerY[e1] - kCornerY[e0]);
      const Vector2<float> target(centre_target_m.x() + ux * half_size_m.x(),
                                  centre_target_m.y() + uy * half_size_m.y());
      Vector2<float> pixel;
      if (project_point(camera, target_to_camera(camera_T_target, target), pixel) != CameraStatus::ok) return false;
      q = pixel - centre_px;
    }
    if (k == 0) {
      first = q;
    } else {
      const float cross = previous.x() * q.y() - q.x() * previous.y();
      area2 += cross;
      moment_x += (previous.x() + q.x()) * cross;
      moment_y += (previous.y() + q.y()) * cross;
    }
    previous = q;
  }
  if (!(std::fabs(area2) > 0.0f)) return false;
  const Vector2<float> bias(moment_x / (3.0f * area2), moment_y / (3.0f * area2));
  if (!bias.allFinite()) return false;
  bias_px = bias;
  return true;
}

}  // namespace kincal::core
