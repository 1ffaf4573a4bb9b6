#include "host/camera/uncertainty.hpp"

#include <array>
#include <cmath>
#include <limits>
#include <string>

#include <Eigen/Dense>
#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "host/camera/intrinsics.hpp"

namespace kincal::camera {

namespace {

using Matrix9d = Eigen::Matrix<double, 9, 9>;

// Which of fx fy cx cy k1 k2 p1 p2 k3 the solver moved under `flags`.
std::array<bool, 9> free_parameters(int flags) {
  constexpr int kUnmodelled =
      cv::CALIB_FIX_ASPECT_RATIO | cv::CALIB_RATIONAL_MODEL | cv::CALIB_THIN_PRISM_MODEL | cv::CALIB_TILTED_MODEL;
  if ((flags & kUnmodelled) != 0) {
    throw CalibrationError(
        "intrinsics covariance: CALIB_FIX_ASPECT_RATIO and the rational, thin-prism and tilted models are not "
        "modelled");
  }
  const auto is_free = [&](int flag) { return (flags & flag) == 0; };
  const bool focal = is_free(cv::CALIB_FIX_FOCAL_LENGTH), centre = is_free(cv::CALIB_FIX_PRINCIPAL_POINT);
  const bool tangential = is_free(cv::CALIB_ZERO_TANGENT_DIST);
  return {focal,
          focal,
          centre,
          centre,
          is_free(cv::CALIB_FIX_K1),
          is_free(cv::CALIB_FIX_K2),
          tangential,
          tangential,
          is_free(cv::CALIB_FIX_K3)};
}

// projectPoints of `points` at the pose with its Jacobian: columns rotation (3), translation (3),
// fx fy cx cy (4), k1 k2 p1 p2 k3 (5), two rows per point.
cv::Mat project_with_jacobian(const CameraModel& camera, cv::InputArray points, cv::Vec3d r, cv::Vec3d t,
                              std::vector<cv::Point2d>& projected) {
  cv::Mat jacobian;
  cv::projectPoints(points, r, t, cv::Mat(camera.camera_matrix), camera.distortion_mat(), projected, jacobian);
  return jacobian;
}

}  // namespace

std::vector<cv::Point3d> rays_of(const CameraModel& camera, const std::vector<cv::Point2d>& pixels_px) {
  std::vector<cv::Point2d> normalised;
  cv::undistortPoints(pixels_px, normalised, cv::Mat(camera.camera_matrix), camera.distortion_mat(), cv::noArray(),
                      cv::noArray(), cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 200, 1e-12));
  std::vector<cv::Point3d> rays;
  for (const cv::Point2d& n : normalised) rays.emplace_back(n.x, n.y, 1.0);
  return rays;
}

std::vector<cv::Point2d> reproject(const CameraModel& from, const CameraModel& to,
                                   const std::vector<cv::Point2d>& pixels_px) {
  if (pixels_px.empty()) return {};
  std::vector<cv::Point2d> projected;
  cv::projectPoints(rays_of(from, pixels_px), cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), cv::Mat(to.camera_matrix),
                    to.distortion_mat(), projected);
  return projected;
}

IntrinsicsCovariance intrinsics_covariance(const CameraModel& camera, const std::vector<SolvedView>& views, int flags) {
  const std::array<bool, 9> free = free_parameters(flags);
  Matrix9d schur = Matrix9d::Zero();
  double ssr = 0;
  IntrinsicsCovariance out;
  for (const SolvedView& v : views) {
    if (v.board_m->size() != v.image_px->size())
      throw CalibrationError("intrinsics covariance: a view's board and image corners differ in number");
    std::vector<cv::Point2d> projected;
    const std::vector<cv::Point3d> board_m(v.board_m->begin(), v.board_m->end());  // double in, double out
    const cv::Mat jacobian_cv = project_with_jacobian(camera, board_m, v.camera_r_board, v.camera_t_board_m, projected);
    Eigen::MatrixXd jacobian;
    cv::cv2eigen(jacobian_cv, jacobian);
    const Eigen::MatrixXd pose = jacobian.leftCols(6);
    Eigen::MatrixXd intrinsics = jacobian.middleCols(6, 9);
    for (int p = 0; p < 9; ++p) {
      if (!free[static_cast<std::size_t>(p)]) intrinsics.col(p).setZero();
    }
    const Eigen::Matrix<double, 9, 6> cross = intrinsics.transpose() * pose;
    const Eigen::Matrix<double, 6, 6> pose_block = pose.transpose() * pose;
    schur += intrinsics.transpose() * intrinsics - cross * pose_block.ldlt().solve(cross.transpose());
    for (std::size_t i = 0; i < projected.size(); ++i) {
      const double dx = projected[i].x - static_cast<double>((*v.image_px)[i].x);
      const double dy = projected[i].y - static_cast<double>((*v.image_px)[i].y);
      ssr += dx * dx + dy * dy;
    }
    out.corners += static_cast<int>(projected.size());
  }
  int free_count = 0;
  for (bool f : free) free_count += f ? 1 : 0;
  out.parameters = free_count + 6 * static_cast<int>(views.size());
  const int dof = 2 * out.corners - out.parameters;
  if (dof <= 0) {
    throw CalibrationError("intrinsics covariance: " + std::to_string(2 * out.corners) + " residuals for " +
                           std::to_string(out.parameters) + " parameters");
  }
  out.corner_sigma_px = std::sqrt(ssr / dof);
  // Invert over the free parameters, their columns scaled to unit norm (fx and k3 differ by 1e6).
  std::vector<int> index;
  for (int p = 0; p < 9; ++p) {
    if (free[static_cast<std::size_t>(p)]) index.push_back(p);
  }
  const Eigen::Index m = static_cast<Eigen::Index>(index.size());
  Eigen::MatrixXd s(m, m);
  for (Eigen::Index i = 0; i < m; ++i)
    for (Eigen::Index j = 0; j < m; ++j)
      s(i, j) = schur(index[static_cast<std::size_t>(i)], index[static_cast<std::size_t>(j)]);
  const Eigen::VectorXd scale = s.diagonal().cwiseMax(std::numeric_limits<double>::min()).cwiseSqrt().cwiseInverse();
  const Eigen::MatrixXd scaled = scale.asDiagonal() * s * scale.asDiagonal();
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(scaled);
  const double largest = eigen.eigenvalues().maxCoeff(), smallest = eigen.eigenvalues().minCoeff();
  if (!(smallest > largest * 1e-14)) {
    throw CalibrationError("intrinsics covariance: the views do not determine the intrinsics (J^T J singular)");
  }
  const Eigen::MatrixXd inverse =
      scale.asDiagonal() *
      (eigen.eigenvectors() * eigen.eigenvalues().cwiseInverse().asDiagonal() * eigen.eigenvectors().transpose()) *
      scale.asDiagonal();
  const double sigma2 = out.corner_sigma_px * out.corner_sigma_px;
  for (Eigen::Index i = 0; i < m; ++i)
    for (Eigen::Index j = 0; j < m; ++j)
      out.covariance(index[static_cast<std::size_t>(i)], index[static_cast<std::size_t>(j)]) = sigma2 * inverse(i, j);
  return out;
}

cv::Matx22d projection_covariance(const CameraModel& camera, const IntrinsicsCovariance& covariance,
                                  cv::Point2d pixel_px) {
  std::vector<cv::Point2d> projected;
  const cv::Mat jacobian =
      project_with_jacobian(camera, rays_of(camera, {pixel_px}), cv::Vec3d(0, 0, 0), cv::Vec3d(0, 0, 0), projected);
  if (!(cv::norm(projected[0] - pixel_px) <= 1e-3)) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    return {nan, nan, nan, nan};
  }
  const cv::Matx<double, 2, 9> j(jacobian(cv::Rect(6, 0, 9, 2)).clone());
  return j * covariance.covariance * j.t();
}

ProjectionSigmaGrid projection_sigma_grid(const CameraModel& camera, const IntrinsicsCovariance& covariance, int cols,
                                          int rows) {
  ProjectionSigmaGrid g;
  for (int c = 0; c < cols; ++c) g.x_px.push_back((c + 0.5) * camera.image_size.width / cols - 0.5);
  for (int r = 0; r < rows; ++r) g.y_px.push_back((r + 0.5) * camera.image_size.height / rows - 0.5);
  g.sigma_px.create(rows, cols, CV_64F);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const cv::Matx22d q = projection_covariance(
          camera, covariance, {g.x_px[static_cast<std::size_t>(c)], g.y_px[static_cast<std::size_t>(r)]});
      // The larger eigenvalue of a symmetric 2 x 2.
      const double mean = 0.5 * (q(0, 0) + q(1, 1)), half = 0.5 * (q(0, 0) - q(1, 1));
      g.sigma_px.at<double>(r, c) = std::sqrt(mean + std::sqrt(half * half + q(0, 1) * q(0, 1)));
    }
  }
  return g;
}

StereoPoseCovariance stereo_pose_covariance(const CameraModel& left, const CameraModel& right,
                                            const cv::Matx33d& right_R_left, const cv::Vec3d& right_t_left_m,
                                            const std::vector<StereoView>& views,
                                            const IntrinsicsCovariance* left_intrinsics,
                                            const IntrinsicsCovariance* right_intrinsics) {
  if (views.size() < 3) throw CalibrationError("stereo pose covariance: fewer than 3 pairs");
  if ((left_intrinsics == nullptr) != (right_intrinsics == nullptr))
    throw CalibrationError("stereo pose covariance: give both cameras' intrinsics covariances or neither");
  using Matrix6d = Eigen::Matrix<double, 6, 6>;
  using Matrix6x18 = Eigen::Matrix<double, 6, 18>;
  cv::Vec3d rig_r;
  cv::Rodrigues(right_R_left, rig_r);
  Matrix6d schur = Matrix6d::Zero();      // the rig pose's block, board poses marginalised
  Matrix6x18 cross = Matrix6x18::Zero();  // its rows of J^T J_intrinsics, likewise
  double ssr = 0;
  int corners = 0;
  for (const StereoView& v : views) {
    if (v.board_m->size() != v.left_px->size() || v.board_m->size() != v.right_px->size())
      throw CalibrationError("stereo pose covariance: a pair's board and image corners differ in number");
    cv::Vec3d board_r, board_t;
    cv::solvePnP(*v.board_m, *v.left_px, cv::Mat(left.camera_matrix), left.distortion_mat(), board_r, board_t);
    cv::Mat r3, t3, dr3dr1, dr3dt1, dr3dr2, dr3dt2, dt3dr1, dt3dt1, dt3dr2, dt3dt2;
    cv::composeRT(board_r, board_t, rig_r, right_t_left_m, r3, t3, dr3dr1, dr3dt1, dr3dr2, dr3dt2, dt3dr1, dt3dt1,
                  dt3dr2, dt3dt2);
    const std::vector<cv::Point3d> board_m(v.board_m->begin(), v.board_m->end());
    std::vector<cv::Point2d> left_proj, right_proj;
    Eigen::MatrixXd jl, jr;
    cv::cv2eigen(project_with_jacobian(left, board_m, board_r, board_t, left_proj), jl);
    cv::cv2eigen(project_with_jacobian(right, board_m, cv::Vec3d(r3), cv::Vec3d(t3), right_proj), jr);
    // d(r3, t3) / d(board pose) and / d(rig pose), 6 x 6 each.
    Eigen::Matrix3d a, b, c, d, e, f, g, h;
    cv::cv2eigen(dr3dr1, a), cv::cv2eigen(dr3dt1, b), cv::cv2eigen(dt3dr1, c), cv::cv2eigen(dt3dt1, d);
    cv::cv2eigen(dr3dr2, e), cv::cv2eigen(dr3dt2, f), cv::cv2eigen(dt3dr2, g), cv::cv2eigen(dt3dt2, h);
    Matrix6d d_board, d_rig;
    d_board << a, b, c, d;
    d_rig << e, f, g, h;
    const Eigen::Index n = static_cast<Eigen::Index>(board_m.size());
    // Rows: the left image's residuals, then the right's. Columns: rig pose, board pose, intrinsics.
    Eigen::MatrixXd rig = Eigen::MatrixXd::Zero(4 * n, 6), board(4 * n, 6),
                    intrinsics = Eigen::MatrixXd::Zero(4 * n, 18);
    board.topRows(2 * n) = jl.leftCols(6);
    board.bottomRows(2 * n) = jr.leftCols(6) * d_board;
    rig.bottomRows(2 * n) = jr.leftCols(6) * d_rig;
    intrinsics.topLeftCorner(2 * n, 9) = jl.middleCols(6, 9);
    intrinsics.bottomRightCorner(2 * n, 9) = jr.middleCols(6, 9);
    const Matrix6d board_block = board.transpose() * board;
    const Eigen::LDLT<Matrix6d> board_solve(board_block);
    const Matrix6d rig_board = rig.transpose() * board;
    schur += rig.transpose() * rig - rig_board * board_solve.solve(rig_board.transpose());
    cross += rig.transpose() * intrinsics - rig_board * board_solve.solve(board.transpose() * intrinsics);
    for (std::size_t i = 0; i < board_m.size(); ++i) {
      const cv::Point2d l = left_proj[i] - cv::Point2d((*v.left_px)[i]);
      const cv::Point2d r = right_proj[i] - cv::Point2d((*v.right_px)[i]);
      ssr += l.dot(l) + r.dot(r);
    }
    corners += static_cast<int>(n);
  }
  const int dof = 4 * corners - 6 - 6 * static_cast<int>(views.size());
  if (dof <= 0) throw CalibrationError("stereo pose covariance: fewer residuals than parameters");
  StereoPoseCovariance out;
  out.corner_sigma_px = std::sqrt(ssr / dof);
  const Eigen::SelfAdjointEigenSolver<Matrix6d> eigen(schur);
  if (!(eigen.eigenvalues().minCoeff() > eigen.eigenvalues().maxCoeff() * 1e-14))
    throw CalibrationError("stereo pose covariance: the pairs do not determine right_T_left (J^T J singular)");
  const Matrix6d inverse =
      eigen.eigenvectors() * eigen.eigenvalues().cwiseInverse().asDiagonal() * eigen.eigenvectors().transpose();
  Matrix6d covariance = out.corner_sigma_px * out.corner_sigma_px * inverse;
  if (left_intrinsics != nullptr) {
    Eigen::Matrix<double, 18, 18> intrinsics_covariance = Eigen::Matrix<double, 18, 18>::Zero();
    Eigen::Matrix<double, 9, 9> l, r;
    cv::cv2eigen(left_intrinsics->covariance, l);
    cv::cv2eigen(right_intrinsics->covariance, r);
    intrinsics_covariance.topLeftCorner<9, 9>() = l;
    intrinsics_covariance.bottomRightCorner<9, 9>() = r;
    const Matrix6x18 sensitivity = -inverse * cross;
    covariance += sensitivity * intrinsics_covariance * sensitivity.transpose();
    covariance = 0.5 * (covariance + covariance.transpose());
    Eigen::Matrix<double, 24, 24> joint;
    joint.topLeftCorner<18, 18>() = intrinsics_covariance;
    joint.bottomLeftCorner<6, 18>() = sensitivity * intrinsics_covariance;
    joint.topRightCorner<18, 6>() = joint.bottomLeftCorner<6, 18>().transpose();
    joint.bottomRightCorner<6, 6>() = covariance;
    cv::eigen2cv(Eigen::MatrixXd(joint), out.calibration_covariance);
  }
  covariance = 0.5 * (covariance + covariance.transpose());
  cv::eigen2cv(covariance, out.covariance);
  return out;
}

}  // namespace kincal::camera
