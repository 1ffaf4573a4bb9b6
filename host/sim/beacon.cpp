#include "host/sim/beacon.hpp"

#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

namespace kincal::sim {

StereoFrame render_beacon(const StereoRigSpec& rig, const BeaconSpec& beacon, const Eigen::Vector3d& beacon_device_m,
                          const ImagingConditions& conditions) {
  const auto fail = [](const std::string& what) { throw std::invalid_argument("render_beacon: " + what); };
  if (!(rig.baseline_m > 0) || !std::isfinite(rig.baseline_m)) fail("StereoRigSpec.baseline_m must be positive");
  if (!(beacon.radius_m > 0) || !std::isfinite(beacon.radius_m)) fail("BeaconSpec.radius_m must be positive");
  if (!(beacon.beacon >= 0 && beacon.beacon <= 1)) fail("BeaconSpec.beacon outside [0, 1]");
  if (!(beacon.background >= 0 && beacon.background <= 1)) fail("BeaconSpec.background outside [0, 1]");
  if (!beacon_device_m.allFinite() || !(beacon_device_m.z() > beacon.radius_m)) {
    fail("beacon_device_m must be finite and in front of the cameras (Z > radius)");
  }
  // Device (right camera, Y up) to the right camera's OpenCV frame: half a turn about Z.
  const Eigen::Vector3d right_cv(-beacon_device_m.x(), -beacon_device_m.y(), beacon_device_m.z());
  const Eigen::Vector3d left_cv = right_cv + Eigen::Vector3d(rig.baseline_m, 0, 0);
  const double r2 = beacon.radius_m * beacon.radius_m;
  const PlanarTarget disc{[r2, inside = beacon.beacon, outside = beacon.background](double x, double y) {
    return x * x + y * y <= r2 ? inside : outside;
  }};
  StereoFrame frame;
  const Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  const Eigen::Isometry3d right_T_disc = facing_camera(right_cv, 0, 0);
  const Eigen::Isometry3d left_T_disc = facing_camera(left_cv, 0, 0);
  frame.right = render_plane(rig.camera, right_T_disc, disc, conditions);
  ImagingConditions left_conditions = conditions;
  left_conditions.seed = conditions.seed ^ 0x5EEDF00D1EF7CA3EULL;
  frame.left = render_plane(rig.camera, left_T_disc, disc, left_conditions);
  frame.right_px = project_points(rig.camera, right_T_disc, std::span(&centre, 1))[0];
  frame.left_px = project_points(rig.camera, left_T_disc, std::span(&centre, 1))[0];
  return frame;
}

StereoFrame render_colour_beacon(const StereoRigSpec& rig, double radius_m, const Eigen::Vector3d& beacon_device_m,
                                 const ImagingConditions& conditions, bool lit) {
  BeaconSpec red, green_blue;
  red.radius_m = green_blue.radius_m = radius_m;
  red.background = green_blue.background = 0.3;
  red.beacon = lit ? 0.95 : red.background;
  green_blue.beacon = lit ? 0.08 : green_blue.background;
  const StereoFrame r = render_beacon(rig, red, beacon_device_m, conditions);
  ImagingConditions other = conditions;
  other.seed = conditions.seed * 7919 + 17;
  const StereoFrame gb = render_beacon(rig, green_blue, beacon_device_m, other);
  StereoFrame out;
  cv::merge(std::vector<cv::Mat>{gb.left, gb.left, r.left}, out.left);
  cv::merge(std::vector<cv::Mat>{gb.right, gb.right, r.right}, out.right);
  out.left_px = r.left_px;
  out.right_px = r.right_px;
  return out;
}

core::StereoPair stereo_pair_of(const StereoRigSpec& rig) {
  core::CameraIntrinsics camera;
  camera.fx_px = static_cast<float>(rig.camera.fx_px);
  camera.fy_px = static_cast<float>(rig.camera.fy_px);
  camera.cx_px = static_cast<float>(rig.camera.cx_px);
  camera.cy_px = static_cast<float>(rig.camera.cy_px);
  camera.distortion.k1 = static_cast<float>(rig.camera.distortion[0]);
  camera.distortion.k2 = static_cast<float>(rig.camera.distortion[1]);
  camera.distortion.p1 = static_cast<float>(rig.camera.distortion[2]);
  camera.distortion.p2 = static_cast<float>(rig.camera.distortion[3]);
  camera.distortion.k3 = static_cast<float>(rig.camera.distortion[4]);
  core::StereoPair pair;
  pair.left = pair.right = camera;
  pair.left_T_right.translation = core::Vector3<float>(static_cast<float>(rig.baseline_m), 0, 0);
  return pair;
}

}  // namespace kincal::sim
