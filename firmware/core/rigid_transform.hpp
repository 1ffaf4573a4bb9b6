// Rigid transforms and small pose differences, templated on the scalar: float on the MCU,
// double and ceres::Jet on the host, one definition.
//
// Conventions (written once, used by every geometry module):
//   a_T_b         maps coordinates in frame b to frame a: p_a = a_T_b * p_b; so products read
//                 right: base_T_tool = base_T_flange * flange_T_tool.
//   rotation      a proper 3x3 rotation matrix (columns are b's axes in a); translation is b's
//                 origin in a. Stored as 12 scalars, no homogeneous row.
//   twist         a small pose difference as a 6-vector [dp; dphi], in the frame it is
//                 expressed in: dp a displacement of the point of interest (metres), dphi a
//                 rotation vector (radians) such that R_moved = (I + [dphi]x) R to first order.
//                 This is the order of Pinocchio's motion vectors (linear first).
//   skew(v)       the cross-product matrix: skew(v) * w = v x w.
//
// Everything here is inline, cannot fail and does not allocate. Cost on the M4F: a product of
// two transforms is 36 multiplies and 30 adds; inverse() 9 multiplies and 6 adds.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "firmware/core/mul_add.hpp"

namespace kincal::core {

template <class S>
using Vector2 = Eigen::Matrix<S, 2, 1>;
template <class S>
using Vector3 = Eigen::Matrix<S, 3, 1>;
template <class S>
using Matrix3 = Eigen::Matrix<S, 3, 3>;
template <class S>
using Twist = Eigen::Matrix<S, 6, 1>;

template <class S>
struct RigidTransform {
  Matrix3<S> rotation = Matrix3<S>::Identity();
  Vector3<S> translation = Vector3<S>::Zero();

  static RigidTransform identity() noexcept { return {}; }

  // a_T_c = a_T_b * b_T_c
  friend RigidTransform operator*(const RigidTransform& a_T_b, const RigidTransform& b_T_c) noexcept {
    RigidTransform a_T_c;
    compose(a_T_b, b_T_c, a_T_c);
    return a_T_c;
  }

  // a_T_c = a_T_b * b_T_c written in place, without a temporary. a_T_c may be a_T_b itself (each
  // row of the result needs only the same row of a_T_b), never b_T_c. Written out entry by entry:
  // Eigen's expression templates do not unroll at -Os, and this is the inner loop of forward
  // kinematics.
  friend void compose(const RigidTransform& a_T_b, const RigidTransform& b_T_c, RigidTransform& a_T_c) noexcept {
    // All of b_T_c in locals first: the stores below could alias it as far as the compiler knows.
    const Matrix3<S>& b = b_T_c.rotation;
    const S b00 = b(0, 0), b01 = b(0, 1), b02 = b(0, 2), b10 = b(1, 0), b11 = b(1, 1), b12 = b(1, 2), b20 = b(2, 0),
            b21 = b(2, 1), b22 = b(2, 2);
    const S t0 = b_T_c.translation(0), t1 = b_T_c.translation(1), t2 = b_T_c.translation(2);
    for (int i = 0; i < 3; ++i) {
      const S a0 = a_T_b.rotation(i, 0), a1 = a_T_b.rotation(i, 1), a2 = a_T_b.rotation(i, 2);
      const S ta = a_T_b.translation(i);
      // (a0 b0j + a1 b1j) + a2 b2j: for double the same sums as written plainly.
      a_T_c.rotation(i, 0) = mul_add(a2, b20, mul_add(a1, b10, a0 * b00));
      a_T_c.rotation(i, 1) = mul_add(a2, b21, mul_add(a1, b11, a0 * b01));
      a_T_c.rotation(i, 2) = mul_add(a2, b22, mul_add(a1, b12, a0 * b02));
      a_T_c.translation(i) = mul_add(a2, t2, mul_add(a1, t1, a0 * t0)) + ta;
    }
  }

  // p_a = a_T_b * p_b
  Vector3<S> operator*(const Vector3<S>& p_b) const noexcept {
    Vector3<S> p_a = rotation.lazyProduct(p_b);
    p_a += translation;
    return p_a;
  }

  // b_T_a from a_T_b; exact for a proper rotation (uses the transpose).
  RigidTransform inverse() const noexcept {
    RigidTransform b_T_a;
    b_T_a.rotation = rotation.transpose();
    b_T_a.translation.noalias() = -(b_T_a.rotation.lazyProduct(translation));
    return b_T_a;
  }
};

template <class S>
Matrix3<S> skew(const Vector3<S>& v) noexcept {
  Matrix3<S> m;
  m << S(0), -v.z(), v.y(), v.z(), S(0), -v.x(), -v.y(), v.x(), S(0);
  return m;
}

// The rotation vector phi with R_to = exp([phi]x) R_from, both in the same outer frame, for
// small differences: returns v * (1 + |v|^2 / 6) with v the axial part of R_to R_from^T, whose
// relative error is below 1e-5 for angles up to 0.1 rad (the correction's operating range).
template <class S>
Vector3<S> small_rotation_difference(const Matrix3<S>& to, const Matrix3<S>& from) noexcept {
  // Only the antisymmetric part of delta = to from^T is needed: delta(i, j) = to.row(i) . from.row(j).
  const auto delta = [&](int i, int j) { return to.row(i).dot(from.row(j)); };
  Vector3<S> v(delta(2, 1) - delta(1, 2), delta(0, 2) - delta(2, 0), delta(1, 0) - delta(0, 1));
  v *= S(0.5);
  return v * (S(1) + v.squaredNorm() / S(6));
}

// Twist [dp; dphi] in frame a that moves a_T_from onto a_T_to (to first order in dphi): the
// translation difference of the origins and small_rotation_difference of the rotations.
template <class S>
Twist<S> small_pose_difference(const RigidTransform<S>& a_T_to, const RigidTransform<S>& a_T_from) noexcept {
  Twist<S> twist;
  twist.template head<3>() = a_T_to.translation - a_T_from.translation;
  twist.template tail<3>() = small_rotation_difference(a_T_to.rotation, a_T_from.rotation);
  return twist;
}

}  // namespace kincal::core
