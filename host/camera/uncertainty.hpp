// How well a calibrated camera is known (issue #22): the intrinsics' covariance and, from it, the
// uncertainty of the projection at every pixel of the image -- where more views would help.
//
// Covariance (the method behind OpenCV's stdDeviationsIntrinsics and mrcal's projection
// uncertainty): J = d(residuals) / d(intrinsics, view poses) at the solution, one 2 x (9 + 6 V)
// block row per corner (cv::projectPoints' Jacobian). The view poses are nuisance parameters and
// are marginalised, not held fixed: cov(intrinsics) = sigma^2 S^-1 with S = A - sum_v B_v C_v^-1
// B_v^T, the Schur complement of the poses in J^T J (A the intrinsics block, B_v the intrinsics x
// pose-v block, C_v pose v's block) -- the intrinsics block of (J^T J)^-1.
// The corner noise is estimated from the residuals: sigma^2 = SSR / (2 N - n), N corners, n the
// free intrinsics plus 6 per view. (OpenCV 4.6's calibrateCamera divides by N - n, the number of
// corners, not of residuals: its standard deviations are sqrt((2N - n) / (N - n)) times these,
// 1.46 on OpenCV's 13 sample views; tests/host/camera/camera_real_test.cpp checks that the rest
// agrees to 1e-5: OpenCV inverts the whole J^T J, the same marginalisation.) The estimate
// assumes independent corner errors of one sigma in x and y and a lens that the model can
// follow; residuals from a lens the model cannot follow inflate sigma.
//
// Parameter order everywhere: fx fy cx cy (px) k1 k2 p1 p2 k3 (OpenCV's). Parameters held fixed
// by cv::CALIB_FIX_K1, _K2, _K3, CALIB_ZERO_TANGENT_DIST, CALIB_FIX_PRINCIPAL_POINT or
// CALIB_FIX_FOCAL_LENGTH have zero rows and columns.
//
// Projection uncertainty at a pixel: the pixel is unprojected by the solved model to its ray in
// the camera frame (cv::undistortPoints, iterated to 1e-12); that ray is projected again with the
// intrinsics varying by their covariance: cov(q) = J_q cov(intrinsics) J_q^T (2 x 2, px^2), J_q
// = d project / d intrinsics at the fixed ray. The ray's distance does not matter (a point fixed
// in the camera frame projects by its direction only), and projection is linear in the
// distortion coefficients at a fixed ray, so the first order is close to exact. This is the
// uncertainty of the camera on its own, its frame fixed by the intrinsics; a use that also
// re-estimates the camera's pose (hand-eye, a board pose) absorbs part of it (mrcal's argument).
//
// Errors (CalibrationError): fewer residuals than parameters; a view whose board and image
// corners differ in number; cv::CALIB_FIX_ASPECT_RATIO, CALIB_RATIONAL_MODEL, CALIB_THIN_PRISM_MODEL or
// CALIB_TILTED_MODEL in `flags` (not modelled here); J^T J singular after scaling its columns
// (condition above 1e14: the views do not determine the intrinsics).
// Cost: one projectPoints with Jacobian and a 6 x 6 solve per view, one 9 x 9 eigen-solve; one
// undistortPoints and one projectPoints per pixel for the projection covariance.
#pragma once

#include <vector>

#include <opencv2/core.hpp>

namespace kincal::camera {

struct CameraModel;  // host/camera/intrinsics.hpp

inline constexpr const char* kIntrinsicsOrder = "fx fy cx cy k1 k2 p1 p2 k3";

struct IntrinsicsCovariance {
  cv::Matx<double, 9, 9> covariance = cv::Matx<double, 9, 9>::zeros();  // kIntrinsicsOrder; px^2, px, 1
  double corner_sigma_px = 0;                                           // sqrt(SSR / (2 N - n))
  int corners = 0;                                                      // N
  int parameters = 0;                                                   // n
};

// One view's corners as the solver used them, with the solved pose.
struct SolvedView {
  const std::vector<cv::Point3f>* board_m;   // board frame
  const std::vector<cv::Point2f>* image_px;  // detected corners
  cv::Vec3d camera_r_board, camera_t_board_m;
};

IntrinsicsCovariance intrinsics_covariance(const CameraModel& camera, const std::vector<SolvedView>& views, int flags);

// The covariance of a stereo pair's right_T_left (right_r_left, the rotation vector in rad, then
// right_t_left in m: x_right = R x_left + t), from the stereo solve's Jacobian as the intrinsics'
// is from theirs: each pair's residuals in both cameras, d/d(right_T_left, left_T_board of each
// pair) by cv::projectPoints and cv::composeRT, the board poses marginalised (Schur complement),
// sigma^2 = SSR / (4 N - 6 - 6 P) over the N corners of P pairs in both images. The cameras'
// intrinsics are held as the solve held them (cv::CALIB_FIX_INTRINSIC); when their covariances
// are given (both or neither), their effect on the solution is added to first order:
// d(right_T_left)/d(intrinsics) = -S^-1 (the pose rows of J^T J_intrinsics, poses marginalised),
// cov += G diag(cov_left, cov_right) G^T. Approximation, stated: each board pose is the left
// camera's own cv::solvePnP, not the joint optimum (they differ by far less than the pose's
// uncertainty; the Jacobian hardly changes).
// Errors (CalibrationError): fewer than 3 pairs, a pair whose lists differ in length, or J^T J
// singular (the pairs do not determine the pose).
// With the intrinsics' covariances given, calibration_covariance is the joint covariance of the
// whole pair (24 x 24, order kStereoCalibrationOrder: the left camera's intrinsics, the right's,
// then right_r_left and right_t_left): diag(cov_left, cov_right) for the intrinsics, G times it
// for their cross block with the pose, and `covariance` for the pose. Triangulation needs all of
// it: an intrinsics error and the pose error it causes partly cancel in a triangulated point.
inline constexpr const char* kStereoCalibrationOrder =
    "left fx fy cx cy k1 k2 p1 p2 k3, right fx fy cx cy k1 k2 p1 p2 k3, rx ry rz tx ty tz";
struct StereoPoseCovariance {
  cv::Matx66d covariance = cv::Matx66d::zeros();  // right_r_left (rad), right_t_left (m)
  double corner_sigma_px = 0;
  cv::Mat calibration_covariance;  // 24 x 24 CV_64F (see above), or empty without the intrinsics'
};
struct StereoView {
  const std::vector<cv::Point3f>* board_m;
  const std::vector<cv::Point2f>*left_px, *right_px;  // the same corners in both images
};
StereoPoseCovariance stereo_pose_covariance(const CameraModel& left, const CameraModel& right,
                                            const cv::Matx33d& right_R_left, const cv::Vec3d& right_t_left_m,
                                            const std::vector<StereoView>& views,
                                            const IntrinsicsCovariance* left_intrinsics = nullptr,
                                            const IntrinsicsCovariance* right_intrinsics = nullptr);

// The 2 x 2 covariance (px^2) of the projection of the ray seen at `pixel_px`; NaN entries when
// the model does not invert there (its round trip misses the pixel by more than 1e-3 px: a
// distortion that folds beyond where the corners were).
cv::Matx22d projection_covariance(const CameraModel& camera, const IntrinsicsCovariance& covariance,
                                  cv::Point2d pixel_px);

// The camera-frame points (x, y, 1) of the rays `camera` sees at `pixels_px` (cv::undistortPoints
// iterated to 1e-12).
std::vector<cv::Point3d> rays_of(const CameraModel& camera, const std::vector<cv::Point2d>& pixels_px);

// Where `to` projects the rays that `from` sees at `pixels_px` (cv::undistortPoints iterated to
// 1e-12, then cv::projectPoints): two lens models compared pixel by pixel, e.g. an estimate
// against the truth, whose difference projection_covariance predicts.
std::vector<cv::Point2d> reproject(const CameraModel& from, const CameraModel& to,
                                   const std::vector<cv::Point2d>& pixels_px);

// The worst-axis standard deviation (px, sqrt of the larger eigenvalue of the projection
// covariance) on a cols x rows grid of pixels over the whole image: x_px[c] = (c + 0.5) W / cols
// - 0.5, y_px[r] likewise (cell centres); sigma_px is rows x cols (CV_64F), NaN where the model
// does not invert.
struct ProjectionSigmaGrid {
  std::vector<double> x_px, y_px;
  cv::Mat sigma_px;
};
ProjectionSigmaGrid projection_sigma_grid(const CameraModel& camera, const IntrinsicsCovariance& covariance, int cols,
                                          int rows);

}  // namespace kincal::camera
