#include "host/camera/hand_eye_uncertainty.hpp"

#include <cmath>
#include <cstddef>
#include <exception>
#include <numbers>
#include <sstream>

#include <Eigen/Geometry>

namespace kincal::camera {

HandEyeSpread hand_eye_jackknife(const std::vector<HandEyeView>& views, const CameraModel& camera,
                                 const HandEyeOptions& options, const HandEyeCalibration& full) {
  HandEyeSpread out;
  std::vector<Eigen::Vector3d> positions, rotations;
  for (std::size_t k = 0; k < views.size() && k < full.views.size(); ++k) {
    if (!full.views[k].used) continue;
    std::vector<HandEyeView> rest = views;
    rest.erase(rest.begin() + static_cast<std::ptrdiff_t>(k));
    try {
      const Eigen::Isometry3d x = calibrate_hand_eye(rest, camera, options).gripper_T_camera;
      const Eigen::AngleAxisd turn(full.gripper_T_camera.linear().transpose() * x.linear());
      positions.push_back(x.translation());
      rotations.push_back(turn.angle() * turn.axis());
    } catch (const std::exception&) {
      ++out.refused;
    }
  }
  out.counted = static_cast<int>(positions.size());
  if (out.counted < 3) return out;
  const double n = out.counted;
  const auto spread = [n](const std::vector<Eigen::Vector3d>& v) {
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const Eigen::Vector3d& x : v) mean += x / n;
    Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
    for (const Eigen::Vector3d& x : v) c += (x - mean) * (x - mean).transpose();
    return Eigen::Matrix3d((n - 1) / n * c);
  };
  out.position_covariance_m2 = spread(positions);
  out.rotation_covariance_rad2 = spread(rotations);
  return out;
}

std::string describe(const HandEyeSpread& spread) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(2);
  out << "gripper_T_camera uncertainty (jackknife over " << spread.counted << " views";
  if (spread.refused > 0) out << "; " << spread.refused << " leave-one-out solve(s) refused";
  if (spread.counted < 3) {
    out << "): none, fewer than 3 solutions\n";
    return out.str();
  }
  out << "): position sigma";
  for (int i = 0; i < 3; ++i) out << ' ' << std::sqrt(spread.position_covariance_m2(i, i)) * 1e3;
  out << " mm, rotation sigma";
  out.precision(3);
  for (int i = 0; i < 3; ++i) out << ' ' << std::sqrt(spread.rotation_covariance_rad2(i, i)) * 180 / std::numbers::pi;
  out << " deg\n";
  return out.str();
}

}  // namespace kincal::camera
