// The camera's pose relative to the calibration square, from identified fiducials.
//
// Doty (7-33..7-35) takes the square's axes as normalized differences of measured fiducial
// points and stacks them into a matrix; with measurement noise that matrix is not a rotation
// (its columns are not orthogonal), and every later step inherits the error. Here the pose is
// the least-squares rigid fit: camera_T_square minimizing sum |camera_T_square * s_i - c_i|^2
// over n >= 3 pairs (square-frame point s_i, known from the square's layout; camera-frame
// point c_i, measured by camera_model.hpp). The rotation comes from Horn's closed form (1987):
// the unit quaternion is the eigenvector of the largest eigenvalue of a symmetric 4x4 matrix
// built from the cross-covariance. The eigenvector is found by cyclic Jacobi rotations:
// unconditionally convergent for symmetric matrices, quadratically so at the end, at most
// kHornMaxSweeps sweeps of 6 rotations -- a bounded loop, float only, no SVD.
// The result is a proper rotation (det = +1, orthonormal to float rounding) by construction.
//
// Statuses (`fit` is written only on ok):
//   too_few_points / too_many_points   n < 3 or n > kMaxPosePoints
//   size_mismatch                      the two spans differ in length (a programming error)
//   non_finite                         a coordinate is NaN or infinite
//   collinear_points                   the square points, or the measured points, lie on a line
//                                      (or coincide): the rotation about that line is free.
//                                      Test: with C the scatter matrix of the centred points,
//                                      I2(C) / trace(C)^2 < min_spread_ratio, where I2 is the sum
//                                      of the principal 2x2 minors (~ lambda1 lambda2).
//   ambiguous_rotation                 the top two eigenvalues of Horn's matrix are within
//                                      min_eigen_gap (relative): no unique best rotation (the
//                                      measured points do not resemble the square's).
//
// Error bound (tests/firmware/core/pose_from_points_test.cpp, random poses, 4-inch squares at
// 0.2..1.5 m, exact points and up to 0.5 mm of noise, against a double-precision SVD (Kabsch)
// fit of the same float inputs): rotation within kPoseRotationErrorRad of that optimum, translation
// within kPoseTranslationErrorPerM per metre of distance (measured 3.9e-7 rad and 1.9e-7 per m);
// the rotation is orthonormal within 5e-7; the RMS within 2e-7 m of the optimum's.
//
// Cost (M4F, 5 points, -O3): 4,859 instructions measured (tests/bench/geometry_m4_bench.cpp,
// pose_from_points_m4_instructions), most of it the Jacobi sweeps. Stack: m4.kincal_core.stack.
#pragma once

#include <cstdint>
#include <span>

#include "firmware/core/rigid_transform.hpp"

namespace kincal::core {

inline constexpr int kMinPosePoints = 3;
inline constexpr int kMaxPosePoints = 64;
inline constexpr int kHornMaxSweeps = 10;
inline constexpr float kPoseRotationErrorRad = 1.0e-6f;
inline constexpr float kPoseTranslationErrorPerM = 5.0e-7f;

enum class [[nodiscard]] PoseStatus : std::uint8_t{
    ok, too_few_points, too_many_points, size_mismatch, non_finite, collinear_points, ambiguous_rotation,
};

struct PoseOptions {
  float min_spread_ratio = 1.0e-4f;  // I2 / trace^2 of the scatter; 1/4 for a square's corners
  float min_eigen_gap = 1.0e-4f;     // (lambda1 - lambda2) / |lambda1| of Horn's matrix
};

struct PoseFit {
  RigidTransform<float> camera_T_square;
  float residual_rms_m = 0.0f;  // sqrt(mean |camera_T_square * s_i - c_i|^2): the fit's quality
  int point_count = 0;
};

PoseStatus pose_from_points(std::span<const Vector3<float>> square_points_m,
                            std::span<const Vector3<float>> camera_points_m, const PoseOptions& options,
                            PoseFit& fit) noexcept;

}  // namespace kincal::core
