// model::Transform (the core's rigid transform in double) to and from Eigen::Isometry3d, for the
// host code that meets OpenCV and Eigen's geometry (board rigs, simulated rigs, camera files); and
// the rotation nearest a 3x3 matrix, which averages rotations.
#pragma once

#include <Eigen/Geometry>
#include <Eigen/SVD>

#include "host/model/robot_model.hpp"

namespace kincal::model {

inline Eigen::Isometry3d isometry(const Transform& t) {
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.linear() = t.rotation;
  out.translation() = t.translation;
  return out;
}

inline Transform transform(const Eigen::Isometry3d& t) {
  Transform out;
  out.rotation = t.linear();
  out.translation = t.translation();
  return out;
}

// The rotation nearest `m` in the Frobenius norm (its orthogonal polar factor, the determinant's sign
// chosen): of a sum of rotations, their chordal mean.
inline Eigen::Matrix3d nearest_rotation(const Eigen::Matrix3d& m) {
  const Eigen::JacobiSVD<Eigen::Matrix3d> svd(m, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Eigen::Matrix3d u = svd.matrixU();
  if ((u * svd.matrixV().transpose()).determinant() < 0) u.col(2) *= -1.0;
  return u * svd.matrixV().transpose();
}

}  // namespace kincal::model
