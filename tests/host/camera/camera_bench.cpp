// Accuracy of the camera calibrations on rendered images with known truth (issue #6): one
// FIGURE line per number. Hand-eye: the error of every method against the true gripper_T_camera,
// so the methods can be compared, and of the reprojection refinement. AprilGrid (issue #22): the
// detected corners against their true projections, at VGA and in the same scenes at 4K.
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include "host/camera/hand_eye.hpp"
#include "host/camera/intrinsics.hpp"
#include "host/camera/stereo.hpp"
#include "tests/host/camera/camera_scenes.hpp"

namespace {

using namespace kincal;
using namespace kincal::camera;

constexpr double kDeg = 180.0 / 3.14159265358979323846;

std::vector<BoardDetection> detect_rendered(const Board& board, const sim::CameraSpec& spec,
                                            const std::vector<Eigen::Isometry3d>& views, std::uint64_t seed) {
  const sim::PlanarTarget target = scenes::target_of(board);
  std::vector<BoardDetection> out;
  for (std::size_t i = 0; i < views.size(); ++i) {
    out.push_back(detect_board(board, scenes::render(spec, views[i], target, seed + i), "v" + std::to_string(i)));
  }
  return out;
}

void figure(const std::string& name, double value, const char* unit) {
  std::printf("FIGURE %s %.6g %s\n", name.c_str(), value, unit);
}

void hand_eye_figures(const std::string& name, const Eigen::Isometry3d& estimate) {
  const Eigen::Isometry3d truth = scenes::gripper_T_camera();
  figure("hand_eye_translation_error_mm_" + name, 1e3 * (estimate.translation() - truth.translation()).norm(), "mm");
  figure("hand_eye_rotation_error_deg_" + name,
         kDeg * Eigen::AngleAxisd(estimate.rotation().transpose() * truth.rotation()).angle(), "deg");
}

// AprilGrid corners of rendered views against their true projections: RMS (px) and the fraction
// of the board's tags found.
void aprilgrid_figures(const std::string& suffix, const sim::CameraSpec& spec, int views) {
  const Board board = parse_board(scenes::aprilgrid_text());
  const std::vector<Eigen::Isometry3d> poses = scenes::board_views(board, views);
  const std::vector<BoardDetection> found = detect_rendered(board, spec, poses, 300);
  double sum_sq = 0;
  std::size_t corners = 0;
  for (std::size_t v = 0; v < found.size(); ++v) {
    cv::RNG no_noise(1);
    const BoardDetection truth = scenes::projected(board, scenes::model_of(spec), poses[v], "truth", no_noise, 0.0);
    for (std::size_t i = 0; i < found[v].ids.size(); ++i) {
      const cv::Point2f e = found[v].image_px[i] - truth.image_px[static_cast<std::size_t>(found[v].ids[i])];
      sum_sq += static_cast<double>(e.dot(e));
      ++corners;
    }
  }
  figure("aprilgrid_corner_rms_px_" + suffix, std::sqrt(sum_sq / static_cast<double>(corners)), "px");
  figure("aprilgrid_tags_found_fraction_" + suffix,
         static_cast<double>(corners) / static_cast<double>(board.corner_count() * views), "fraction");
}

}  // namespace

int main() {
  aprilgrid_figures("vga", scenes::test_camera(), 8);
  aprilgrid_figures("4k", scenes::scaled(scenes::test_camera(), 6), 2);

  const Board board = parse_board(scenes::chessboard_text());
  const sim::CameraSpec spec = scenes::test_camera();
  const std::vector<Eigen::Isometry3d> views = scenes::board_views(board, 20);
  const std::vector<BoardDetection> left = detect_rendered(board, spec, views, 1);

  const IntrinsicCalibration c = calibrate_intrinsics(left);
  figure("intrinsic_fx_relative_error", std::abs(c.camera.camera_matrix(0, 0) / spec.fx_px - 1), "ratio");
  figure("intrinsic_principal_point_error_px",
         std::hypot(c.camera.camera_matrix(0, 2) - spec.cx_px, c.camera.camera_matrix(1, 2) - spec.cy_px), "px");
  figure("intrinsic_k1_error", std::abs(c.camera.distortion[0] - spec.distortion[0]), "1");
  figure("intrinsic_rms_px", c.rms_px, "px");

  std::vector<Eigen::Isometry3d> right_views;
  for (const Eigen::Isometry3d& v : views) right_views.push_back(scenes::left_T_right().inverse() * v);
  const std::vector<BoardDetection> right = detect_rendered(board, spec, right_views, 1000);
  const StereoCalibration s = calibrate_stereo(left, right, c.camera, calibrate_intrinsics(right).camera);
  figure("stereo_baseline_relative_error", std::abs(s.baseline_m / scenes::left_T_right().translation().norm() - 1),
         "ratio");

  std::vector<HandEyeView> hand_eye;
  const std::vector<Eigen::Isometry3d> poses = scenes::gripper_poses(views);
  for (std::size_t i = 0; i < views.size(); ++i) hand_eye.push_back({left[i].view, poses[i], left[i]});
  const HandEyeCalibration h = calibrate_hand_eye(hand_eye, c.camera);
  for (const HandEyeEstimate& e : h.methods) hand_eye_figures(e.method, e.gripper_T_camera);
  for (const HandEyeEstimate& e : h.robot_world) hand_eye_figures(e.method, e.gripper_T_camera);
  hand_eye_figures("refined", h.gripper_T_camera);
  figure("hand_eye_reprojection_rms_before_px", h.rms_before_px, "px");
  figure("hand_eye_reprojection_rms_after_px", h.rms_after_px, "px");
  return 0;
}
