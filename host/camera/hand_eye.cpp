#include "host/camera/hand_eye.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>
#include <optional>
#include <sstream>
#include <utility>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

#include "host/camera/hand_eye_refinement.hpp"
#include "host/camera/number_text.hpp"

namespace kincal::camera {

namespace {

using Eigen::Isometry3d;
using Eigen::Matrix3d;
using Eigen::Vector3d;

constexpr double kDeg = 180.0 / std::numbers::pi;
constexpr int kMaxShiftTested = 3;
constexpr double kScaleWarning = 0.03;  // step 7: a board scale this far from 1 is warned of  // step 7: poses shifted
                                        // by up to this many rows against the images

struct Residual {
  double rotation_rms_rad = 0, translation_rms_m = 0;
  std::vector<double> pose_rotation_rms_rad, pose_translation_rms_m;  // over the pairs holding pose i
};

// RMS over all pairs i < j of (A X)^-1 (X B), A = H_i^-1 H_j, B = C_i C_j^-1 (from H_i X C_i =
// base_T_target for every i), and per pose over the pairs holding it.
Residual ax_xb(const std::vector<Isometry3d>& base_T_gripper, const std::vector<Isometry3d>& camera_T_target,
               const Isometry3d& gripper_T_camera) {
  const std::size_t n = base_T_gripper.size();
  std::vector<double> rot2(n, 0.0), trans2(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j) {
      const Isometry3d a = base_T_gripper[i].inverse() * base_T_gripper[j];
      const Isometry3d b = camera_T_target[i] * camera_T_target[j].inverse();
      const Isometry3d e = (a * gripper_T_camera).inverse() * (gripper_T_camera * b);
      const double angle = Eigen::AngleAxisd(e.rotation()).angle();
      for (std::size_t k : {i, j}) {
        rot2[k] += angle * angle;
        trans2[k] += e.translation().squaredNorm();
      }
    }
  }
  // Each pair is counted at both of its poses: the sums over poses hold every pair twice.
  Residual r;
  double rot2_all = 0, trans2_all = 0;
  for (std::size_t i = 0; i < n; ++i) {
    rot2_all += rot2[i];
    trans2_all += trans2[i];
    r.pose_rotation_rms_rad.push_back(std::sqrt(rot2[i] / static_cast<double>(n - 1)));
    r.pose_translation_rms_m.push_back(std::sqrt(trans2[i] / static_cast<double>(n - 1)));
  }
  const double pairs = static_cast<double>(n * (n - 1));  // twice the number of pairs
  r.rotation_rms_rad = std::sqrt(rot2_all / pairs);
  r.translation_rms_m = std::sqrt(trans2_all / pairs);
  return r;
}

// The factor k on the board's lengths (so on the camera's translations B) that fits the robot's
// motions best with X's rotation, and the AX = XB translation RMS it leaves: linear least squares
// over all pairs i < j in t_X and k of (R_A - I) t_X - k R_X t_B = -t_A (the translation of
// (A X)^-1 (X B) with B's scaled by k). The rotation part does not depend on the board's size, so
// a board given at the wrong size (a square measured wrong) leaves the rotations fitting and the
// translations off by k - 1 of the camera's motion.
struct BoardScale {
  double factor = 1.0;
  double translation_rms_m = 0.0;
};
BoardScale fit_board_scale(const std::vector<Isometry3d>& base_T_gripper,
                           const std::vector<Isometry3d>& camera_T_target, const Matrix3d& gripper_R_camera) {
  const std::size_t n = base_T_gripper.size(), pairs = n * (n - 1) / 2;
  Eigen::MatrixXd m(3 * pairs, 4);
  Eigen::VectorXd rhs(3 * pairs);
  Eigen::Index row = 0;
  for (std::size_t i = 0; i < n; ++i) {
    for (std::size_t j = i + 1; j < n; ++j, row += 3) {
      const Isometry3d a = base_T_gripper[i].inverse() * base_T_gripper[j];
      const Isometry3d b = camera_T_target[i] * camera_T_target[j].inverse();
      m.block<3, 3>(row, 0) = a.linear() - Matrix3d::Identity();
      m.block<3, 1>(row, 3) = -gripper_R_camera * b.translation();
      rhs.segment<3>(row) = -a.translation();
    }
  }
  const Eigen::Vector4d x = m.colPivHouseholderQr().solve(rhs);
  return {x(3), std::sqrt((m * x - rhs).squaredNorm() / static_cast<double>(pairs))};
}

HandEyeEstimate estimate(const char* method, const Isometry3d& gripper_T_camera,
                         const std::vector<Isometry3d>& base_T_gripper,
                         const std::vector<Isometry3d>& camera_T_target) {
  const Residual r = ax_xb(base_T_gripper, camera_T_target, gripper_T_camera);
  return {method, gripper_T_camera, r.rotation_rms_rad, r.translation_rms_m};
}

Isometry3d isometry(const cv::Mat& r, const cv::Mat& t) {
  Matrix3d rotation;
  Vector3d translation;
  cv::cv2eigen(r, rotation);
  cv::cv2eigen(t, translation);
  Isometry3d m = Isometry3d::Identity();
  m.linear() = rotation;
  m.translation() = translation;
  return m;
}

void split(const Isometry3d& m, cv::Mat& r, cv::Mat& t) {
  const Matrix3d rotation = m.rotation();
  const Vector3d translation = m.translation();
  cv::eigen2cv(rotation, r);
  cv::eigen2cv(translation, t);
}

// OpenCV's solvers throw cv::Exception on motions they cannot use (a rotation matrix that does not
// normalize, a singular system): its text names OpenCV's source line, not the input.
CalibrationError solve_failed(const char* function, const cv::Exception& e) {
  return CalibrationError(std::string("hand-eye calibration: OpenCV's ") + function + " failed on the robot poses (" +
                          e.err +
                          "): their motions do not fit one rigid mount -- poses of another run, or "
                          "rotations in another unit or convention?");
}

Isometry3d solve_hand_eye(const std::vector<Isometry3d>& base_T_gripper, const std::vector<Isometry3d>& camera_T_target,
                          cv::HandEyeCalibrationMethod method) {
  std::vector<cv::Mat> r_g2b(base_T_gripper.size()), t_g2b(base_T_gripper.size());
  std::vector<cv::Mat> r_t2c(camera_T_target.size()), t_t2c(camera_T_target.size());
  for (std::size_t i = 0; i < base_T_gripper.size(); ++i) {
    split(base_T_gripper[i], r_g2b[i], t_g2b[i]);
    split(camera_T_target[i], r_t2c[i], t_t2c[i]);
  }
  cv::Mat r, t;
  try {
    cv::calibrateHandEye(r_g2b, t_g2b, r_t2c, t_t2c, r, t, method);
  } catch (const cv::Exception& e) {
    throw solve_failed("calibrateHandEye", e);
  }
  return isometry(r, t);
}

Isometry3d solve_robot_world(const std::vector<Isometry3d>& base_T_gripper,
                             const std::vector<Isometry3d>& camera_T_target,
                             cv::RobotWorldHandEyeCalibrationMethod method) {
  // OpenCV's world is the board: world2cam = camera_T_target, base2gripper = gripper_T_base;
  // it returns base2world = target_T_base and gripper2cam = camera_T_gripper.
  std::vector<cv::Mat> r_w2c(camera_T_target.size()), t_w2c(camera_T_target.size());
  std::vector<cv::Mat> r_b2g(base_T_gripper.size()), t_b2g(base_T_gripper.size());
  for (std::size_t i = 0; i < base_T_gripper.size(); ++i) {
    split(camera_T_target[i], r_w2c[i], t_w2c[i]);
    split(base_T_gripper[i].inverse(), r_b2g[i], t_b2g[i]);
  }
  cv::Mat r_b2w, t_b2w, r_g2c, t_g2c;
  try {
    cv::calibrateRobotWorldHandEye(r_w2c, t_w2c, r_b2g, t_b2g, r_b2w, t_b2w, r_g2c, t_g2c, method);
  } catch (const cv::Exception& e) {
    throw solve_failed("calibrateRobotWorldHandEye", e);
  }
  return isometry(r_g2c, t_g2c).inverse();
}

// The squared reprojection error (px^2) summed over one view's corners at camera_T_target.
double reprojection_ssr(const BoardDetection& detection, const CameraModel& camera, const Isometry3d& camera_T_target) {
  cv::Mat r, rvec, tvec;
  split(camera_T_target, r, tvec);
  cv::Rodrigues(r, rvec);
  std::vector<cv::Point2f> projected;
  cv::projectPoints(detection.board_m, rvec, tvec, cv::Mat(camera.camera_matrix), camera.distortion_mat(), projected);
  double sum2 = 0;
  for (std::size_t k = 0; k < projected.size(); ++k) {
    const cv::Point2f e = projected[k] - detection.image_px[k];
    sum2 += static_cast<double>(e.dot(e));
  }
  return sum2;
}

// Where a hand-eye and board pose put the board in view i: X^-1 H_i^-1 W.
Isometry3d chained_camera_T_target(const Isometry3d& base_T_gripper, const Isometry3d& gripper_T_camera,
                                   const Isometry3d& base_T_target) {
  return gripper_T_camera.inverse() * base_T_gripper.inverse() * base_T_target;
}

// RMS (px) of the corners' reprojection for a hand-eye and board pose, by cv::projectPoints.
double reprojection_rms(const std::vector<const BoardDetection*>& detections,
                        const std::vector<Isometry3d>& base_T_gripper, const CameraModel& camera,
                        const Isometry3d& gripper_T_camera, const Isometry3d& base_T_target) {
  double sum2 = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < detections.size(); ++i) {
    sum2 += reprojection_ssr(*detections[i], camera,
                             chained_camera_T_target(base_T_gripper[i], gripper_T_camera, base_T_target));
    n += detections[i]->board_m.size();
  }
  return std::sqrt(sum2 / static_cast<double>(n));
}

// The mean of base_T_gripper_i * X * camera_T_target_i (chordal mean of the rotations).
Isometry3d mean_target(const std::vector<Isometry3d>& base_T_gripper, const std::vector<Isometry3d>& camera_T_target,
                       const Isometry3d& gripper_T_camera) {
  Eigen::Vector4d q_sum = Eigen::Vector4d::Zero();
  Vector3d t_sum = Vector3d::Zero();
  Eigen::Quaterniond first;
  for (std::size_t i = 0; i < base_T_gripper.size(); ++i) {
    const Isometry3d m = base_T_gripper[i] * gripper_T_camera * camera_T_target[i];
    Eigen::Quaterniond q(m.rotation());
    if (i == 0) first = q;
    if (q.dot(first) < 0) q.coeffs() *= -1.0;
    q_sum += q.coeffs();
    t_sum += m.translation();
  }
  Isometry3d mean = Isometry3d::Identity();
  mean.linear() = Eigen::Quaterniond(q_sum.normalized()).toRotationMatrix();
  mean.translation() = t_sum / static_cast<double>(base_T_gripper.size());
  return mean;
}

// The AX = XB rotation residual (Park's solution) with image i paired with pose i + shift, over
// the pairs both lists hold; nullopt when fewer than `min_poses` remain or OpenCV cannot solve.
std::optional<double> shifted_rotation_rms(const std::vector<Isometry3d>& base_T_gripper,
                                           const std::vector<Isometry3d>& camera_T_target, int shift, int min_poses) {
  std::vector<Isometry3d> poses, boards;
  for (std::size_t i = 0; i < camera_T_target.size(); ++i) {
    const std::ptrdiff_t p = static_cast<std::ptrdiff_t>(i) + shift;
    if (p < 0 || p >= static_cast<std::ptrdiff_t>(base_T_gripper.size())) continue;
    poses.push_back(base_T_gripper[static_cast<std::size_t>(p)]);
    boards.push_back(camera_T_target[i]);
  }
  if (static_cast<int>(poses.size()) < std::max(3, min_poses)) return std::nullopt;
  try {
    return ax_xb(poses, boards, solve_hand_eye(poses, boards, cv::CALIB_HAND_EYE_PARK)).rotation_rms_rad;
  } catch (const CalibrationError&) {
    return std::nullopt;
  }
}

// Step 7 (see the header): the refusals for poses that cannot belong to the images, and the
// warnings, with their likely cause, for poses and images that fit less well than a good set.
std::vector<std::string> assess_consistency(const HandEyeCalibration& result,
                                            const std::vector<Isometry3d>& base_T_gripper,
                                            const std::vector<Isometry3d>& camera_T_target, const CameraModel& camera,
                                            const std::vector<const BoardDetection*>& detections,
                                            const Matrix3d& gripper_R_camera, const HandEyeOptions& options) {
  const std::string residuals = "AX = XB residual " + fixed(result.rotation_rms_rad * kDeg, 2) + " degrees / " +
                                fixed(result.translation_rms_m * 1e3, 1) + " mm RMS, reprojection " +
                                fixed(result.rms_after_px, 2) + " px RMS";
  const std::string exact_residuals = "AX = XB residual " + fixed(result.exact_rotation_rms_rad * kDeg, 2) +
                                      " degrees / " + fixed(result.exact_translation_rms_m * 1e3, 1) +
                                      " mm RMS with the poses held exact";
  const std::string mistake = "hand-eye calibration: the robot poses and the images do not belong together: ";
  for (int shift = -kMaxShiftTested; shift <= kMaxShiftTested; ++shift) {
    if (shift == 0 || result.exact_rotation_rms_rad <= 0.5 / kDeg) continue;
    const std::optional<double> shifted =
        shifted_rotation_rms(base_T_gripper, camera_T_target, shift, options.min_poses);
    if (shifted && *shifted * options.convention_ratio < result.exact_rotation_rms_rad) {
      throw CalibrationError(mistake + exact_residuals + "; each image fits the pose " +
                             std::to_string(std::abs(shift)) + (std::abs(shift) == 1 ? " row " : " rows ") +
                             (shift > 0 ? "after" : "before") + " its own (AX = XB rotation residual " +
                             fixed(*shifted * kDeg, 2) +
                             " degrees): a poses file of another run, rows out of order, or images missing");
    }
  }
  if (result.exact_rotation_rms_rad > options.refuse_rotation_rms_rad) {
    throw CalibrationError(mistake + exact_residuals + " (rotations beyond " +
                           fixed(options.refuse_rotation_rms_rad * kDeg, 1) +
                           " degrees, which no intrinsics or board size explain): a poses file of another run, rows "
                           "out of order, or another camera");
  }
  std::vector<std::string> warnings;
  if (result.rotation_rms_rad > options.max_rotation_rms_rad ||
      result.translation_rms_m > options.max_translation_rms_m || result.rms_after_px > options.max_reprojection_rms_px)
    warnings.push_back("the robot poses and the images fit less well than a good set: " + residuals +
                       " (a good set: " + fixed(options.max_rotation_rms_rad * kDeg, 2) + " degrees / " +
                       fixed(options.max_translation_rms_m * 1e3, 1) + " mm, " +
                       fixed(options.max_reprojection_rms_px, 2) +
                       " px); the result is as uncertain as its sigma and the methods' spread say");
  // A board of another size, or a camera whose focal length is off, scales the board's motion.
  const BoardScale scale = fit_board_scale(base_T_gripper, camera_T_target, gripper_R_camera);
  if (std::abs(scale.factor - 1.0) > kScaleWarning && scale.translation_rms_m < 0.7 * result.translation_rms_m) {
    const cv::Matx33d& k = camera.camera_matrix;
    const double square_m =
        detections.front()->board_m.size() > 1
            ? static_cast<double>(cv::norm(detections.front()->board_m[1] - detections.front()->board_m[0]))
            : 0.0;
    warnings.push_back(
        "the views fit the robot's motions with the board's lengths " + fixed(scale.factor, 3) +
        " times those given (AX = XB translation " + fixed(scale.translation_rms_m * 1e3, 1) + " mm RMS against " +
        fixed(result.translation_rms_m * 1e3, 1) +
        " mm): either the camera's focal length is off (the data suggest fx " + fixed(k(0, 0) * scale.factor, 1) +
        ", fy " + fixed(k(1, 1) * scale.factor, 1) + " px for the " + fixed(k(0, 0), 1) + ", " + fixed(k(1, 1), 1) +
        " given: factory intrinsics are often 10 % off; calibrate the camera with `kincal camera calibrate`) or the "
        "board's square size is (the data suggest " +
        fixed(square_m * scale.factor * 1e3, 2) + " mm for the " + fixed(square_m * 1e3, 2) + " mm given)");
  }
  return warnings;
}

// Step 6's start values of the noise scales (hand_eye_refinement.hpp): the corners' sigma from the
// views' own board poses, SSR / (2 m - 6 n); the poses' per axis from the AX = ZB loop closures
// W^-1 H_i X C_i at the start (RMS angle and shift over sqrt 3); zero when the poses are held exact.
ChainNoise start_noise(const std::vector<const BoardDetection*>& detections,
                       const std::vector<Isometry3d>& base_T_gripper, const std::vector<Isometry3d>& camera_T_target,
                       const CameraModel& camera, const Isometry3d& gripper_T_camera, const Isometry3d& base_T_target,
                       bool correct_poses) {
  double ssr = 0, rows = 0, angle2 = 0, shift2 = 0;
  for (std::size_t i = 0; i < detections.size(); ++i) {
    ssr += reprojection_ssr(*detections[i], camera, camera_T_target[i]);
    rows += 2.0 * static_cast<double>(detections[i]->board_m.size()) - 6.0;
    const Isometry3d loop = base_T_target.inverse() * base_T_gripper[i] * gripper_T_camera * camera_T_target[i];
    angle2 += std::pow(Eigen::AngleAxisd(loop.rotation()).angle(), 2);
    shift2 += loop.translation().squaredNorm();
  }
  ChainNoise noise;
  noise.corner_px = rows > 0 ? std::sqrt(ssr / rows) : 1.0;
  if (correct_poses) {
    const double per_axis = 3.0 * static_cast<double>(detections.size());
    noise.pose_rotation_rad = std::sqrt(angle2 / per_axis);
    noise.pose_translation_m = std::sqrt(shift2 / per_axis);
  }
  return noise;
}

}  // namespace

const char* convention_name(PoseConvention c) {
  return c == PoseConvention::kGripperToBase ? "gripper2base" : "base2gripper";
}

HandEyeCalibration calibrate_hand_eye(const std::vector<HandEyeView>& views, const CameraModel& camera,
                                      const HandEyeOptions& options) {
  std::vector<BoardDetection> given;
  for (const HandEyeView& v : views) given.push_back(v.detection);
  refuse_wrong_board(given);
  HandEyeCalibration result;
  std::vector<Isometry3d> base_T_gripper, camera_T_target;
  std::vector<const BoardDetection*> detections;
  std::vector<std::size_t> used;  // indices into result.views
  const cv::Mat k(camera.camera_matrix), distortion = camera.distortion_mat();
  for (const HandEyeView& v : views) {
    HandEyeViewReport report;
    report.view = v.view;
    cv::Mat rvec, tvec;
    if (!v.detection.found) {
      report.rejection = v.detection.reason;
    } else if (v.detection.image_size != camera.image_size) {
      report.rejection = "image size differs from the camera's calibration";
    } else if (!cv::solvePnP(v.detection.board_m, v.detection.image_px, k, distortion, rvec, tvec)) {
      report.rejection = "the board's pose was not found (solvePnP failed)";
    } else {
      cv::Mat r;
      cv::Rodrigues(rvec, r);
      report.used = true;
      report.camera_T_target = isometry(r, tvec);
      camera_T_target.push_back(report.camera_T_target);
      base_T_gripper.push_back(options.convention == PoseConvention::kGripperToBase ? v.robot_pose
                                                                                    : v.robot_pose.inverse());
      detections.push_back(&v.detection);
      used.push_back(result.views.size());
    }
    result.views.push_back(std::move(report));
  }
  result.poses_used = static_cast<int>(base_T_gripper.size());
  if (result.poses_used < std::max(3, options.min_poses)) {
    std::string message = "hand-eye calibration: " + std::to_string(result.poses_used) + " usable poses of " +
                          std::to_string(views.size()) + ", at least " +
                          std::to_string(std::max(3, options.min_poses)) + " needed";
    for (const HandEyeViewReport& r : result.views) {
      if (!r.used) message += "\n  " + r.view + ": " + r.rejection;
    }
    throw CalibrationError(message + seen_board_hint(given));
  }

  // Rotation diversity of the gripper's relative motions.
  std::vector<Vector3d> large_axes;
  for (std::size_t i = 0; i < base_T_gripper.size(); ++i) {
    for (std::size_t j = i + 1; j < base_T_gripper.size(); ++j) {
      const Eigen::AngleAxisd motion((base_T_gripper[i].inverse() * base_T_gripper[j]).rotation());
      result.largest_rotation_rad = std::max(result.largest_rotation_rad, motion.angle());
      if (motion.angle() >= options.min_rotation_rad) large_axes.push_back(motion.axis());
    }
  }
  if (result.largest_rotation_rad < options.min_rotation_rad) {
    throw CalibrationError("hand-eye calibration: the largest rotation between two poses is " +
                           fixed(result.largest_rotation_rad * kDeg, 1) + " degrees; at least " +
                           fixed(options.min_rotation_rad * kDeg, 1) +
                           " degrees about two non-parallel axes is needed: rotate the gripper more between poses");
  }
  for (std::size_t i = 0; i < large_axes.size(); ++i) {
    for (std::size_t j = i + 1; j < large_axes.size(); ++j) {
      const double angle = std::acos(std::min(1.0, std::abs(large_axes[i].dot(large_axes[j]))));
      result.largest_axis_angle_rad = std::max(result.largest_axis_angle_rad, angle);
    }
  }
  if (result.largest_axis_angle_rad < options.min_axis_angle_rad) {
    throw CalibrationError(
        "hand-eye calibration: the rotations between poses are about nearly parallel axes "
        "(largest angle between two axes " +
        fixed(result.largest_axis_angle_rad * kDeg, 1) + " degrees, at least " +
        fixed(options.min_axis_angle_rad * kDeg, 1) + " degrees needed): rotate the gripper about a second axis");
  }

  // Convention: solve both readings of the robot poses and compare their residuals.
  std::vector<Isometry3d> other(base_T_gripper.size());
  std::transform(base_T_gripper.begin(), base_T_gripper.end(), other.begin(),
                 [](const Isometry3d& m) { return m.inverse(); });
  const double given_rms =
      ax_xb(base_T_gripper, camera_T_target, solve_hand_eye(base_T_gripper, camera_T_target, cv::CALIB_HAND_EYE_PARK))
          .rotation_rms_rad;
  result.other_convention_rotation_rms_rad =
      ax_xb(other, camera_T_target, solve_hand_eye(other, camera_T_target, cv::CALIB_HAND_EYE_PARK)).rotation_rms_rad;
  if (given_rms > 0.5 / kDeg && result.other_convention_rotation_rms_rad * options.convention_ratio < given_rms) {
    const PoseConvention fits = options.convention == PoseConvention::kGripperToBase ? PoseConvention::kBaseToGripper
                                                                                     : PoseConvention::kGripperToBase;
    throw CalibrationError(std::string("hand-eye calibration: the robot poses fit as ") + convention_name(fits) +
                           (fits == PoseConvention::kGripperToBase ? " (base_T_gripper)" : " (gripper_T_base)") +
                           ", not as " + convention_name(options.convention) + " as given: AX = XB rotation residual " +
                           fixed(result.other_convention_rotation_rms_rad * kDeg, 3) + " degrees against " +
                           fixed(given_rms * kDeg, 3) + " degrees; invert the poses or give the other convention");
  }

  const std::array<std::pair<const char*, cv::HandEyeCalibrationMethod>, 5> methods = {{
      {"tsai", cv::CALIB_HAND_EYE_TSAI},
      {"park", cv::CALIB_HAND_EYE_PARK},
      {"horaud", cv::CALIB_HAND_EYE_HORAUD},
      {"andreff", cv::CALIB_HAND_EYE_ANDREFF},
      {"daniilidis", cv::CALIB_HAND_EYE_DANIILIDIS},
  }};
  for (const auto& [name, method] : methods) {
    result.methods.push_back(
        estimate(name, solve_hand_eye(base_T_gripper, camera_T_target, method), base_T_gripper, camera_T_target));
  }
  const std::array<std::pair<const char*, cv::RobotWorldHandEyeCalibrationMethod>, 2> robot_world = {{
      {"shah", cv::CALIB_ROBOT_WORLD_HAND_EYE_SHAH},
      {"li", cv::CALIB_ROBOT_WORLD_HAND_EYE_LI},
  }};
  for (const auto& [name, method] : robot_world) {
    result.robot_world.push_back(
        estimate(name, solve_robot_world(base_T_gripper, camera_T_target, method), base_T_gripper, camera_T_target));
  }

  // Refinement from the AX = XB estimate with the smallest rotation residual.
  const HandEyeEstimate& start =
      *std::min_element(result.methods.begin(), result.methods.end(),
                        [](const auto& a, const auto& b) { return a.rotation_rms_rad < b.rotation_rms_rad; });
  result.start_method = start.method;
  const Isometry3d target0 = mean_target(base_T_gripper, camera_T_target, start.gripper_T_camera);
  result.rms_before_px = reprojection_rms(detections, base_T_gripper, camera, start.gripper_T_camera, target0);
  const ChainRefinement refined_chain =
      refine_chain(detections, base_T_gripper, camera, start.gripper_T_camera, target0,
                   start_noise(detections, base_T_gripper, camera_T_target, camera, start.gripper_T_camera, target0,
                               options.correct_poses),
                   options.correct_poses);
  result.gripper_T_camera = refined_chain.gripper_T_camera;
  result.base_T_target = refined_chain.base_T_target;
  result.noise = refined_chain.sigma;
  result.noise_rounds = refined_chain.rounds;
  result.rotation_sigma_rad = refined_chain.rotation_sigma_rad;
  result.translation_sigma_m = refined_chain.translation_sigma_m;
  result.rms_after_px =
      reprojection_rms(detections, base_T_gripper, camera, result.gripper_T_camera, result.base_T_target);
  const Residual refined = ax_xb(base_T_gripper, camera_T_target, result.gripper_T_camera);
  result.rotation_rms_rad = refined.rotation_rms_rad;
  result.translation_rms_m = refined.translation_rms_m;
  const Residual exact = options.correct_poses
                             ? ax_xb(base_T_gripper, camera_T_target,
                                     refine_chain(detections, base_T_gripper, camera, start.gripper_T_camera, target0,
                                                  refined_chain.sigma, false)
                                         .gripper_T_camera)
                             : refined;
  result.exact_rotation_rms_rad = exact.rotation_rms_rad;
  result.exact_translation_rms_m = exact.translation_rms_m;
  for (std::size_t i = 0; i < used.size(); ++i) {
    HandEyeViewReport& v = result.views[used[i]];
    const double corners = static_cast<double>(detections[i]->board_m.size());
    v.refined_camera_T_target =
        chained_camera_T_target(base_T_gripper[i], result.gripper_T_camera, result.base_T_target);
    v.board_rms_px = std::sqrt(reprojection_ssr(*detections[i], camera, camera_T_target[i]) / corners);
    v.refined_rms_px = std::sqrt(reprojection_ssr(*detections[i], camera, v.refined_camera_T_target) / corners);
    v.pair_rotation_rms_rad = refined.pose_rotation_rms_rad[i];
    v.pair_translation_rms_m = refined.pose_translation_rms_m[i];
    const Isometry3d loop =
        result.base_T_target.inverse() * base_T_gripper[i] * result.gripper_T_camera * camera_T_target[i];
    v.loop_rotation_rad = Eigen::AngleAxisd(loop.rotation()).angle();
    v.loop_translation_m = loop.translation().norm();
  }
  for (const HandEyeEstimate& e : result.methods)
    result.methods_spread_m = std::max(
        result.methods_spread_m, (e.gripper_T_camera.translation() - result.gripper_T_camera.translation()).norm());
  result.warnings = assess_consistency(result, base_T_gripper, camera_T_target, camera, detections,
                                       start.gripper_T_camera.linear(), options);
  return result;
}

std::string describe(const HandEyeCalibration& c) {
  std::ostringstream out;
  out << "poses used: " << c.poses_used << " of " << c.views.size() << "\n";
  out << "largest rotation between poses: " << fixed(c.largest_rotation_rad * kDeg, 1)
      << " degrees; largest angle between rotation axes: " << fixed(c.largest_axis_angle_rad * kDeg, 1) << " degrees\n";
  out << "method, AX = XB rotation RMS (degrees), translation RMS (mm), gripper_t_camera (m):\n";
  const auto line = [&out](const HandEyeEstimate& e) {
    const Vector3d t = e.gripper_T_camera.translation();
    out << "  " << e.method << ": " << fixed(e.rotation_rms_rad * kDeg, 4) << ", "
        << fixed(e.translation_rms_m * 1e3, 3) << ", " << fixed(t.x(), 5) << " " << fixed(t.y(), 5) << " "
        << fixed(t.z(), 5) << "\n";
  };
  for (const HandEyeEstimate& e : c.methods) line(e);
  for (const HandEyeEstimate& e : c.robot_world) line(e);
  line({"refined", c.gripper_T_camera, c.rotation_rms_rad, c.translation_rms_m});
  out << "refinement from " << c.start_method << ": reprojection RMS " << fixed(c.rms_before_px, 4) << " px before, "
      << fixed(c.rms_after_px, 4) << " px after\n";
  out << "noise scales from the data (" << c.noise_rounds << " rounds): corners " << fixed(c.noise.corner_px, 3)
      << " px; poses ";
  if (c.noise.pose_rotation_rad > 0)
    out << fixed(c.noise.pose_rotation_rad * kDeg, 4) << " degrees, " << fixed(c.noise.pose_translation_m * 1e3, 3)
        << " mm per axis\n";
  else
    out << "held exact\n";
  out << "gripper_t_camera sigma (from the residuals) x y z: " << fixed(c.translation_sigma_m[0] * 1e3, 2) << " "
      << fixed(c.translation_sigma_m[1] * 1e3, 2) << " " << fixed(c.translation_sigma_m[2] * 1e3, 2)
      << " mm; rotation about x y z: " << fixed(c.rotation_sigma_rad[0] * kDeg, 3) << " "
      << fixed(c.rotation_sigma_rad[1] * kDeg, 3) << " " << fixed(c.rotation_sigma_rad[2] * kDeg, 3)
      << " degrees; the AX = XB methods lie within " << fixed(c.methods_spread_m * 1e3, 2) << " mm of the refined\n";
  for (const HandEyeViewReport& v : c.views) {
    if (!v.used) out << "view " << v.view << ": rejected: " << v.rejection << "\n";
  }
  return out.str();
}

}  // namespace kincal::camera
