#include "tests/host/camera/camera_scenes.hpp"

#include <cmath>

#include <opencv2/calib3d.hpp>
#include <opencv2/core/eigen.hpp>

namespace kincal::camera::scenes {

namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

sim::CameraSpec test_camera() {
  sim::CameraSpec c;
  c.width_px = 640;
  c.height_px = 480;
  c.fx_px = 610;
  c.fy_px = 606;
  c.cx_px = 324.5;
  c.cy_px = 236.0;
  c.distortion = {-0.21, 0.09, 0.0008, -0.0005, 0.0};
  return c;
}

const char* chessboard_text() { return "chessboard:9x6:0.03"; }
const char* charuco_text() { return "charuco:7x5:0.04:0.03:DICT_4X4_50"; }
const char* aprilgrid_text() { return "aprilgrid:6x5:0.04:0.3"; }

std::vector<Eigen::Isometry3d> board_views(const camera::Board& board, int n) {
  // The board's centre, where its corners are.
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e9), hi = Eigen::Vector3d::Constant(-1e9);
  for (int id = 0; id < board.corner_count(); ++id) {
    const cv::Point3f p = board.corner_m(id);
    const Eigen::Vector3d corner(p.x, p.y, p.z);
    lo = lo.cwiseMin(corner);
    hi = hi.cwiseMax(corner);
  }
  const Eigen::Vector3d centre = 0.5 * (lo + hi), half = 0.5 * (hi - lo);
  std::vector<Eigen::Isometry3d> views;
  for (int i = 0; i < n; ++i) {
    const double phase = 2 * kPi * i / n;
    const double tilt = (15.0 + 20.0 * ((i * 7) % n) / n) * kPi / 180;
    const double distance = 0.5 + 0.25 * ((i * 3) % n) / n;
    // The camera sits on the board's -z side looking at an aim point that wanders over the
    // board, so that the board wanders over the image.
    const Eigen::Vector3d aim =
        centre + Eigen::Vector3d(0.55 * half.x() * std::cos(3 * phase), 0.55 * half.y() * std::sin(2 * phase), 0);
    const Eigen::Vector3d dir(std::sin(tilt) * std::cos(phase), std::sin(tilt) * std::sin(phase), -std::cos(tilt));
    const Eigen::Vector3d position = aim + distance * dir;
    const Eigen::Vector3d z = (aim - position).normalized();
    Eigen::Vector3d x = (Eigen::Vector3d::UnitX() - z * z.x()).normalized();
    const double roll = 15.0 * kPi / 180 * std::sin(5 * phase);
    x = Eigen::AngleAxisd(roll, z) * x;
    const Eigen::Vector3d y = z.cross(x);
    Eigen::Isometry3d board_T_camera = Eigen::Isometry3d::Identity();
    board_T_camera.linear().col(0) = x;
    board_T_camera.linear().col(1) = y;
    board_T_camera.linear().col(2) = z;
    board_T_camera.translation() = position;
    views.push_back(board_T_camera.inverse());
  }
  return views;
}

sim::CameraSpec scaled(sim::CameraSpec spec, int scale) {
  spec.width_px *= scale;
  spec.height_px *= scale;
  spec.fx_px *= scale;
  spec.fy_px *= scale;
  spec.cx_px = (spec.cx_px + 0.5) * scale - 0.5;
  spec.cy_px = (spec.cy_px + 0.5) * scale - 0.5;
  return spec;
}

sim::PlanarTarget target_of(const camera::Board& board) {
  if (board.kind == camera::BoardKind::kChessboard) return sim::chessboard(board.cols, board.rows, board.square_m);
  if (board.kind == camera::BoardKind::kAprilGrid) {
    // The board's origin is the upper left corner of texel (gap, gap), whose centre sim::texture
    // puts at gap texels from its own origin.
    constexpr int kPxPerBit = 10;
    const double metres_per_px = board.square_m / (10 * kPxPerBit);
    const double shift_m = (camera::aprilgrid_gap_px(board, kPxPerBit) - 0.5) * metres_per_px;
    const sim::PlanarTarget sheet = sim::texture(camera::draw_aprilgrid(board, kPxPerBit), metres_per_px);
    return sim::PlanarTarget{
        [sheet, shift_m](double x_m, double y_m) { return sheet.reflectance(x_m + shift_m, y_m + shift_m); }};
  }
  constexpr int kPxPerSquare = 100;
  return sim::texture(camera::draw_charuco(board, kPxPerSquare), board.square_m / kPxPerSquare);
}

cv::Mat render(const sim::CameraSpec& camera, const Eigen::Isometry3d& camera_T_board, const sim::PlanarTarget& target,
               std::uint64_t seed) {
  sim::ImagingConditions conditions;
  conditions.supersampling = 2;
  conditions.seed = seed;
  return sim::render_plane(camera, camera_T_board, target, conditions);
}

CameraModel model_of(const sim::CameraSpec& s) {
  CameraModel m;
  m.image_size = cv::Size(s.width_px, s.height_px);
  m.camera_matrix = cv::Matx33d(s.fx_px, 0, s.cx_px, 0, s.fy_px, s.cy_px, 0, 0, 1);
  m.distortion = s.distortion;
  return m;
}

BoardDetection projected(const camera::Board& board, const CameraModel& camera, const Eigen::Isometry3d& camera_T_board,
                         const std::string& view, cv::RNG& rng, double sigma_px) {
  BoardDetection d;
  d.view = view;
  d.image_size = camera.image_size;
  d.found = true;
  std::vector<cv::Point3f> all;
  for (int id = 0; id < board.corner_count(); ++id) all.push_back(board.corner_m(id));
  cv::Mat r, rvec, tvec;
  const Eigen::Matrix3d rotation = camera_T_board.rotation();
  cv::eigen2cv(rotation, r);
  cv::Rodrigues(r, rvec);
  tvec = (cv::Mat_<double>(3, 1) << camera_T_board.translation().x(), camera_T_board.translation().y(),
          camera_T_board.translation().z());
  std::vector<cv::Point2f> px;
  cv::projectPoints(all, rvec, tvec, cv::Mat(camera.camera_matrix), camera.distortion_mat(), px);
  for (std::size_t i = 0; i < px.size(); ++i) {
    d.ids.push_back(static_cast<int>(i));
    d.board_m.push_back(all[i]);
    d.image_px.emplace_back(px[i].x + static_cast<float>(rng.gaussian(sigma_px)),
                            px[i].y + static_cast<float>(rng.gaussian(sigma_px)));
  }
  return d;
}

Eigen::Isometry3d left_T_right() {
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  m.linear() = Eigen::AngleAxisd(-3.0 * kPi / 180, Eigen::Vector3d::UnitY()).toRotationMatrix();
  m.translation() = Eigen::Vector3d(0.12, 0.0, 0.0);
  return m;
}

Eigen::Isometry3d gripper_T_camera() {
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  m.linear() = (Eigen::AngleAxisd(0.2, Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(-0.1, Eigen::Vector3d::UnitX()))
                   .toRotationMatrix();
  m.translation() = Eigen::Vector3d(0.03, -0.05, 0.09);
  return m;
}

Eigen::Isometry3d base_T_target() {
  Eigen::Isometry3d m = Eigen::Isometry3d::Identity();
  m.linear() = Eigen::AngleAxisd(kPi, Eigen::Vector3d::UnitX()).toRotationMatrix();  // board face up
  m.translation() = Eigen::Vector3d(0.6, -0.1, 0.02);
  return m;
}

std::vector<Eigen::Isometry3d> gripper_poses(const std::vector<Eigen::Isometry3d>& camera_T_board) {
  std::vector<Eigen::Isometry3d> poses;
  for (const Eigen::Isometry3d& c : camera_T_board) {
    poses.push_back(base_T_target() * c.inverse() * gripper_T_camera().inverse());
  }
  return poses;
}

}  // namespace kincal::camera::scenes
