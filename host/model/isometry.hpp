// model::Transform (the core's rigid transform in double) to and from Eigen::Isometry3d, for the
// host code that meets OpenCV and Eigen's geometry (board rigs, simulated rigs, camera files).
#pragma once

#include <Eigen/Geometry>

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

}  // namespace kincal::model
