// The pose of a planar target (the calibration square, the strip) from its image points through
// the full lens model, fused with the ranger plane as a prior: the camera measures, the rangers
// only help where the image cannot (issue #13).
//
// Why: the pose from the ranger plane alone (range_plane.hpp + pose_from_points.hpp) tilts with
// the rangers' noise (0.5 mm over 10 cm: about 7 mrad), while the camera locates fiducials to
// about 0.07 px. Here the image points decide the pose; the plane enters as three extra whitened
// residuals, so with few points (three) the plane fixes what the image cannot, and with four or
// more well-spread points the image dominates and a tilted plane cannot drag the pose.
//
// Frames and units (rigid_transform.hpp conventions):
//   target frame   points on its z = 0 plane: PlanarCorrespondence::target_m = (x, y) there.
//   camera frame   OpenCV's (x right, y down, z forward), metres; pixels as camera_model.hpp.
//   camera_T_target  maps target coordinates to the camera frame (the target frame in the
//                  camera frame); its rotation's third column is the target's z axis.
//   covariance     6x6, of the twist [dt; dphi] in the CAMERA frame (linear first, as Twist):
//                  the true pose is  R = exp([dphi]x) R_est,  t = t_est + dt  (t = the target
//                  origin). It is the inverse of the Gauss-Newton normal matrix of the whitened
//                  residuals at the last linearization point: it trusts options.pixel_sigma_px
//                  and the prior's covariance as given (no a-posteriori rescaling).
//
// Method (all bounded; no heap; float only; sqrtf the only libm call):
//   1. start   n >= 4 points: homography of the undistorted normalized points (Hartley-
//              normalized DLT, h33 = 1, 8x8 normal equations by Cholesky), decomposed into
//              [r1 r2 t], r1 and r2 made orthonormal symmetrically, r3 = r1 x r2, the sign
//              chosen so that the target lies in front of the camera.
//              n = 3 with a prior: the rays meet the prior plane (camera_model.hpp) and the
//              three points give the rigid fit (pose_from_points.hpp).
//   2. refine  at most options.max_iterations Gauss-Newton steps on the reprojection error in
//              pixels through the full distortion model (analytic Jacobian), divided by
//              pixel_sigma_px, plus the prior's three whitened residuals; update
//              t += dt, R = q(dphi) R (q: unit quaternion (1, dphi/2) normalized), R kept
//              orthonormal. Converged when |dphi|_inf <= kPlanarPoseStepTolerance and
//              |dt|_inf <= kPlanarPoseStepTolerance * |t|.
//   2a. gate   n >= 4 with a prior: step 2 runs on the image alone first; the prior joins (step 2
//              again, from there) only if its disagreement with that pose is plausible under both
//              covariances (options.prior_gate_chi2); otherwise the pose is the image's and
//              out.prior_rejected says so. n = 3 needs the prior and always uses it.
//   3. fiducial centres (options.perspective_passes = 1): the blob centroid of a fiducial is the
//              centroid of its IMAGE, not the image of its centre (up to 0.26 px at 30 degrees
//              tilt here). With the refined pose, each correspondence with a non-zero
//              fiducial_half_size_m has fiducial_centroid_bias_px subtracted from its pixel, and
//              step 2 runs once more from the refined pose (iterations add up).
//
// The prior: the ranger plane in the SLOPE form the along-beam fit computes exactly,
//   z = c0 + slope_x x + slope_y y   (camera frame; c0 in metres, slopes dimensionless),
// i.e. c0 = distance_m / n_z, slope_x = -n_x / n_z, slope_y = -n_y / n_z for CalibrationPlane's
// normal n and distance. The same three numbers of the pose's plane (z axis m = R e3, origin t):
// slope = -(m_x, m_y) / m_z, c0 = m.t / m_z -- independent of the normal's sign. The residual is
// L^-1 (pose's - prior's) with L L^T = covariance. range_plane_covariance (range_plane.hpp) gives
// that covariance from the rangers' noise.
//
// Statuses (`out` is written on ok; otherwise `out.status` and nothing else is meaningful, and
// `out` may hold partial values):
//   too_few_points        n < 4 without a prior, n < 3 with one
//   too_many_points       n > kPlanarPoseMaxPoints
//   non_finite            a pixel or target coordinate is NaN or infinite, or the solution became
//                         non-finite
//   bad_intrinsics        fx, fy not positive and finite, or non-finite coefficients
//   outside_model_domain  a pixel could not be undistorted (camera_model.hpp's statuses
//                         outside_model_domain / not_converged), or a point of the pose leaves the
//                         distortion model's domain
//   collinear_points      the target points lie on a line (I2/trace^2 of their 2x2 scatter below
//                         options.min_spread_ratio): the rotation about that line is free
//   degenerate_geometry   the homography or the Gauss-Newton normal matrix is singular in float
//                         (e.g. the plane seen edge-on, coincident image points)
//   behind_camera         a target point of the result (or of the start) has camera z <= 0
//   not_converged         no convergence within max_iterations (per pass)
//   bad_prior             the prior's plane or covariance is not finite, its normal does not face
//                         the camera (n_z <= kMinRayPlaneCosine) or its distance is not positive,
//                         or the covariance is not positive definite; also n = 3 when the rays
//                         miss the prior plane
//
// Cost (M4F, -O3, measured by tests/bench/geometry_m4_bench.cpp: six fiducials with the ranger
// prior, 0.07 px noise): planar_pose_m4_instructions 65,650 with the default perspective pass
// (7.3 Gauss-Newton steps in all: image-only, fused, fused again after the bias correction),
// planar_pose_no_bias_pass_m4_instructions 36,201 without it (5.2 steps); i.e. 0.39 / 0.22 ms at
// 168 MHz. A step is about 120 flops per point plus a 6x6 Cholesky; the start undistorts each
// pixel (camera_model.hpp). fiducial_centroid_bias_px: 4 kFiducialEdgeSegments + 1 projections.
// Stack: the per-point data and the solver's state live in the caller's PlanarPoseWorkspace; the
// call itself needs 824 bytes on the M4 at -O3 (deepest path, toolchain/check_stack.py; the core's
// budget is 896 for it, m4.kincal_core.stack); fiducial_centroid_bias_px 128 bytes.
// Numerics: the same bits natively and on the Cortex-M4 (sums in fixed order, explicit fma only;
// tests/firmware/core/geometry_digest.cpp). No state; reentrant as long as each caller has its
// own workspace.
#pragma once

#include <array>
#include <cstdint>
#include <span>

#include "firmware/core/camera_model.hpp"
#include "firmware/core/range_plane.hpp"
#include "firmware/core/rigid_transform.hpp"

namespace kincal::core {

// Capacity: up to 4 squares x 6 fiducials in one frame, with room to spare.
inline constexpr int kPlanarPoseMaxPoints = 32;
inline constexpr float kPlanarPoseStepTolerance = 2.0e-6f;  // rad, and relative to |t|
// Each fiducial rectangle edge is cut into this many segments, each end projected through the
// full lens model (the image of a straight edge is curved only by distortion).
inline constexpr int kFiducialEdgeSegments = 4;

enum class [[nodiscard]] PlanarPoseStatus : std::uint8_t{
    ok,
    too_few_points,
    too_many_points,
    non_finite,
    bad_intrinsics,
    outside_model_domain,
    collinear_points,
    degenerate_geometry,
    behind_camera,
    not_converged,
    bad_prior,
};

// One image point of a known target point. fiducial_half_size_m: half the fiducial rectangle's
// sides along the target's x and y (the square's p4 is s/2 x s, the others s/2 x s/2); zero for a
// point feature (no perspective-bias correction for it).
struct PlanarCorrespondence {
  // Zero by default (Eigen's own default leaves a vector uninitialized; a zero half size means
  // "no perspective correction" for that point).
  Vector2<float> pixel_px = Vector2<float>::Zero();
  Vector2<float> target_m = Vector2<float>::Zero();
  Vector2<float> fiducial_half_size_m = Vector2<float>::Zero();
};

// The ranger plane with its covariance, of (c0_m, slope_x, slope_y) in that order (see above).
struct PlanePrior {
  CalibrationPlane plane{};
  Matrix3<float> covariance = Matrix3<float>::Zero();
};

struct PlanarPoseOptions {
  float pixel_sigma_px = 0.1f;          // standard deviation of each image coordinate
  std::uint8_t max_iterations = 10;     // Gauss-Newton steps per pass
  std::uint8_t perspective_passes = 1;  // 0: blob centroids used as they are; 1: see step 3
  float min_spread_ratio = 1.0e-3f;     // collinearity test of the target points
  // n >= 4 with a prior: the prior joins only if the chi^2 (3 degrees of freedom) of its
  // disagreement with the image-only pose, under both covariances, is at most this (16.27: 0.1%
  // of consistent priors refused). Infinity: always fuse.
  float prior_gate_chi2 = 16.27f;
};

struct PlanarPose {
  PlanarPoseStatus status = PlanarPoseStatus::not_converged;
  RigidTransform<float> camera_T_target{};
  Eigen::Matrix<float, 6, 6> covariance = Eigen::Matrix<float, 6, 6>::Zero();  // [dt; dphi], camera frame
  float reprojection_rms_px = 0.0f;  // sqrt(mean over 2n coordinates of residual^2), corrected pixels
  float prior_mahalanobis = 0.0f;    // |L^-1 (pose's plane - prior's)| at the result; 0 unless prior_used
  std::uint8_t iterations = 0;       // Gauss-Newton steps taken, all passes
  std::uint8_t point_count = 0;
  bool prior_used = false;
  // n >= 4 with a prior: the gate's chi^2 (see prior_gate_chi2), and whether it refused the prior
  // (then the pose is the image's alone, prior_used is false and the status is still ok).
  float prior_innovation_chi2 = 0.0f;
  bool prior_rejected = false;
};

// The solver's state between its steps (part of the workspace, so that it is not on the stack;
// callers neither read nor write it).
namespace planar_pose_detail {
struct Linearization {
  std::array<float, 21> normal{};  // packed lower triangle of the 6x6 normal matrix, or its factor
  std::array<float, 6> gradient{};
  float image_sum2 = 0.0f;  // sum of squared whitened image residuals
  float prior_sum2 = 0.0f;
};
struct WhitenedPrior {
  Vector3<float> slope_form = Vector3<float>::Zero();  // (c0, slope_x, slope_y) measured
  std::array<float, 6> chol{};                         // packed factor L of the covariance
};
}  // namespace planar_pose_detail

// Caller-owned scratch memory (about 1.2 KiB): keep it out of the stack (a member, a static).
struct PlanarPoseWorkspace {
  std::array<Vector2<float>, kPlanarPoseMaxPoints> normalized_xy{};  // undistorted pixels
  std::array<Vector2<float>, kPlanarPoseMaxPoints> pixel_px{};       // pixels after bias correction
  std::array<Vector3<float>, kPlanarPoseMaxPoints> scratch3{};       // three-point start
  planar_pose_detail::Linearization linearization{};
  planar_pose_detail::WhitenedPrior prior{};
  std::array<float, 36> homography_normal{};  // packed 8x8 of the DLT
  std::array<float, 8> homography_rhs{};
};

// The pose; returns out.status. prior may be null (image only). Never traps on bad data.
PlanarPoseStatus planar_pose(const CameraIntrinsics& camera, std::span<const PlanarCorrespondence> points,
                             const PlanePrior* prior, const PlanarPoseOptions& options, PlanarPoseWorkspace& workspace,
                             PlanarPose& out) noexcept;

// The perspective bias of a fiducial rectangle's blob centroid: (area centroid of its image) -
// (image of its centre), in pixels, through the full lens model at the pose camera_T_target. The
// rectangle is centre_target_m +- half_size_m on the target's z = 0 plane. The image is the
// polygon of its projected edge points (kFiducialEdgeSegments per edge): exact for a pinhole
// (straight edges stay straight), within 0.002 px of the true curved outline for the ARID lens
// (tests/firmware/core/planar_pose_test.cpp against a brute-force sampled centroid in double).
// Returns false (bias untouched) if a corner is behind the camera, leaves the model's domain, the
// intrinsics are bad, or the image has no area.
bool fiducial_centroid_bias_px(const CameraIntrinsics& camera, const RigidTransform<float>& camera_T_target,
                               const Vector2<float>& centre_target_m, const Vector2<float>& half_size_m,
                               Vector2<float>& bias_px) noexcept;

}  // namespace kincal::core
