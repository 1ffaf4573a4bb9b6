#include "host/camera/board_pose.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <vector>

#include <opencv2/calib3d.hpp>

namespace kincal::camera {

namespace {

Eigen::Matrix3d skew(const Eigen::Vector3d& v) {
  Eigen::Matrix3d s;
  s << 0, -v.z(), v.y(), v.z(), 0, -v.x(), -v.y(), v.x(), 0;
  return s;
}

// exp(r + dr) = exp(J_l(r) dr) exp(r) to first order: the left Jacobian of SO(3).
Eigen::Matrix3d left_jacobian(const Eigen::Vector3d& r) {
  const double t = r.norm();
  const Eigen::Matrix3d s = skew(r);
  if (t < 1e-8) return Eigen::Matrix3d::Identity() + 0.5 * s;
  return Eigen::Matrix3d::Identity() + (1 - std::cos(t)) / (t * t) * s + (t - std::sin(t)) / (t * t * t) * s * s;
}

std::string number(double v) {
  std::ostringstream o;
  o.precision(3);
  o << v;
  return o.str();
}

}  // namespace

BoardPose board_pose(const BoardDetection& detection, const CameraModel& camera,
                     const std::optional<IntrinsicsCovariance>& intrinsics, const BoardPoseOptions& options) {
  BoardPose pose;
  pose.view = detection.view;
  if (!detection.found) {
    pose.refusal = detection.reason;
    return pose;
  }
  if (detection.image_size != camera.image_size)
    throw CalibrationError(detection.view + ": the image is " + std::to_string(detection.image_size.width) + "x" +
                           std::to_string(detection.image_size.height) + ", the camera's " +
                           std::to_string(camera.image_size.width) + "x" + std::to_string(camera.image_size.height) +
                           " (another camera or resolution)");
  if (detection.board_m.size() != detection.image_px.size())
    throw CalibrationError(detection.view + ": corners without their board coordinates");
  const int n = static_cast<int>(detection.image_px.size());
  pose.corners = n;
  if (n < options.min_corners) {
    pose.refusal = "too few corners (" + std::to_string(n) + ", at least " + std::to_string(options.min_corners) + ")";
    return pose;
  }

  const cv::Mat k(camera.camera_matrix);
  const cv::Mat dist = camera.distortion_mat();
  cv::Mat rvec, tvec;
  cv::solvePnP(detection.board_m, detection.image_px, k, dist, rvec, tvec, false, cv::SOLVEPNP_ITERATIVE);
  cv::solvePnPRefineLM(detection.board_m, detection.image_px, k, dist, rvec, tvec,
                       cv::TermCriteria(cv::TermCriteria::COUNT + cv::TermCriteria::EPS, 100, 1e-12));

  std::vector<cv::Point2d> projected;
  cv::Mat jacobian;  // 2N x 15: rvec, tvec, fx, fy, cx, cy, k1 k2 p1 p2 k3
  std::vector<cv::Point3d> board_m(detection.board_m.begin(), detection.board_m.end());
  cv::projectPoints(board_m, rvec, tvec, k, dist, projected, jacobian);
  double ssr = 0;
  for (std::size_t i = 0; i < projected.size(); ++i) {
    const double dx = projected[i].x - static_cast<double>(detection.image_px[i].x);
    const double dy = projected[i].y - static_cast<double>(detection.image_px[i].y);
    ssr += dx * dx + dy * dy;
  }
  pose.rms_px = std::sqrt(ssr / n);
  pose.corner_sigma_px = std::sqrt(ssr / (2 * n - 6));

  const Eigen::Vector3d r(rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2));
  const Eigen::Vector3d t(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  pose.camera_T_board = Eigen::Isometry3d::Identity();
  if (r.norm() > 0) pose.camera_T_board.linear() = Eigen::AngleAxisd(r.norm(), r.normalized()).toRotationMatrix();
  pose.camera_T_board.translation() = t;

  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const cv::Point3d& p : board_m) centre += Eigen::Vector3d(p.x, p.y, p.z);
  centre = pose.camera_T_board * (centre / static_cast<double>(n));
  const Eigen::Vector3d normal = pose.camera_T_board.linear().col(2);
  pose.tilt_rad = std::acos(std::min(1.0, std::abs(normal.dot(centre.normalized()))));

  const double gate =
      std::max(options.outlier_floor_px, intrinsics ? options.outlier_over_sigma * intrinsics->corner_sigma_px : 0.0);
  if (pose.rms_px > gate) {
    pose.refusal = "an outlier: reprojection RMS " + number(pose.rms_px) + " px above " + number(gate) + " px";
    return pose;
  }
  if (pose.tilt_rad > options.max_tilt_rad) {
    pose.refusal = "the board nearly edge-on: its normal " + number(pose.tilt_rad * 180 / std::numbers::pi) +
                   " deg from the line of sight (at most " + number(options.max_tilt_rad * 180 / std::numbers::pi) +
                   ")";
    return pose;
  }

  Eigen::MatrixXd j(2 * n, 15);
  for (int row = 0; row < 2 * n; ++row)
    for (int col = 0; col < 15; ++col) j(row, col) = jacobian.at<double>(row, col);
  const Eigen::MatrixXd jp = j.leftCols(6);
  const Eigen::Matrix<double, 6, 6> information = jp.transpose() * jp;
  const Eigen::Matrix<double, 6, 6> inverse = information.inverse();
  // (rvec, tvec) -> (position, rotation error d).
  Eigen::Matrix<double, 6, 6> m = Eigen::Matrix<double, 6, 6>::Zero();
  m.block<3, 3>(0, 3).setIdentity();
  m.block<3, 3>(3, 0) = left_jacobian(r);
  Eigen::Matrix<double, 6, 6> covariance = pose.corner_sigma_px * pose.corner_sigma_px * inverse;
  if (intrinsics) {
    Eigen::Matrix<double, 9, 9> c;
    for (int a = 0; a < 9; ++a)
      for (int b = 0; b < 9; ++b) c(a, b) = intrinsics->covariance(a, b);
    const Eigen::Matrix<double, 6, 9> g = -inverse * jp.transpose() * j.rightCols(9);
    covariance += g * c * g.transpose();
  }
  pose.covariance = m * covariance * m.transpose();
  pose.covariance = 0.5 * (pose.covariance + pose.covariance.transpose()).eval();
  return pose;
}

PoseCovariance inverse_pose_covariance(const Eigen::Isometry3d& camera_T_board, const PoseCovariance& covariance) {
  // T^-1 = (R^T, -R^T t). With R' = exp(d) R and t' = t + e: R'^T = exp(-R^T d) R^T and
  // -R'^T t' = -R^T t - R^T e - R^T [t]x d to first order.
  const Eigen::Matrix3d rt = camera_T_board.linear().transpose();
  Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Zero();
  a.block<3, 3>(0, 0) = -rt;
  a.block<3, 3>(0, 3) = -rt * skew(camera_T_board.translation());
  a.block<3, 3>(3, 3) = -rt;
  return a * covariance * a.transpose();
}

PoseMeasurement pose_measurement(const BoardPose& pose, bool camera_on_hand) {
  if (!camera_on_hand) return {pose.camera_T_board, pose.covariance};
  return {pose.camera_T_board.inverse(), inverse_pose_covariance(pose.camera_T_board, pose.covariance)};
}

}  // namespace kincal::camera
