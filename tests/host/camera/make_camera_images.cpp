// Writes the files the `kincal camera` CLI tests read, into DIR:
//   views/view_NN.png      12 rendered chessboard views of the test camera (also the hand-eye
//                          images and the stereo left images)
//   right/right_NN.png     the first 8 of them seen by the stereo rig's right camera
//   poses.csv              base_T_gripper for each view (q1,x,y,z,qw,qx,qy,qz; q1 a dummy joint)
//   poses_swapped.csv      the same poses inverted (gripper_T_base), a convention mix-up
//   poses_rotvec.csv       the same poses as a controller gives them: x,y,z,rx,ry,rz (rotation
//                          vector), no joint columns
//   poses_4x4.txt          the same poses as 4x4 matrices, row-major, 16 numbers a line
//   blank.png              an image without a board;  not_an_image.png  text, not an image
//   aprilgrid/april_NN.png 12 rendered views of the 6 x 5 AprilGrid (issue #22)
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "tests/host/camera/camera_scenes.hpp"

namespace {

std::string numbered(const std::string& stem, std::size_t i) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "_%02zu.png", i);
  return stem + buf;
}

void write_poses(const std::string& path, const std::vector<Eigen::Isometry3d>& poses) {
  std::ofstream out(path);
  out.precision(17);
  out << "q1,x,y,z,qw,qx,qy,qz\n";
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const Eigen::Quaterniond q(poses[i].rotation());
    const Eigen::Vector3d t = poses[i].translation();
    out << 0.1 * static_cast<double>(i) << ',' << t.x() << ',' << t.y() << ',' << t.z() << ',' << q.w() << ',' << q.x()
        << ',' << q.y() << ',' << q.z() << '\n';
  }
}

void write_controller_poses(const std::string& rotvec_path, const std::string& matrix_path,
                            const std::vector<Eigen::Isometry3d>& poses) {
  std::ofstream rotvec(rotvec_path), matrices(matrix_path);
  rotvec.precision(17);
  matrices.precision(17);
  rotvec << "x,y,z,rx,ry,rz\n";
  for (const Eigen::Isometry3d& p : poses) {
    const Eigen::AngleAxisd a(p.rotation());
    const Eigen::Vector3d r = a.angle() * a.axis(), t = p.translation();
    rotvec << t.x() << ',' << t.y() << ',' << t.z() << ',' << r.x() << ',' << r.y() << ',' << r.z() << '\n';
    for (int i = 0; i < 16; ++i) matrices << p.matrix()(i / 4, i % 4) << (i < 15 ? ' ' : '\n');
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::cerr << "usage: make_camera_images DIR\n";
    return 2;
  }
  namespace fs = std::filesystem;
  using namespace kincal;
  const fs::path dir = argv[1];
  fs::create_directories(dir / "views");
  fs::create_directories(dir / "right");
  const camera::Board board = camera::parse_board(camera::scenes::chessboard_text());
  const sim::PlanarTarget target = camera::scenes::target_of(board);
  const std::vector<Eigen::Isometry3d> views = camera::scenes::board_views(board, 12);
  sim::CameraSpec right_camera = camera::scenes::test_camera();
  right_camera.fx_px = 598;
  right_camera.fy_px = 597;
  for (std::size_t i = 0; i < views.size(); ++i) {
    cv::imwrite((dir / "views" / numbered("view", i)).string(),
                camera::scenes::render(camera::scenes::test_camera(), views[i], target, i));
    if (i < 8) {
      cv::imwrite(
          (dir / "right" / numbered("right", i)).string(),
          camera::scenes::render(right_camera, camera::scenes::left_T_right().inverse() * views[i], target, 100 + i));
    }
  }
  const std::vector<Eigen::Isometry3d> poses = camera::scenes::gripper_poses(views);
  write_poses((dir / "poses.csv").string(), poses);
  std::vector<Eigen::Isometry3d> swapped;
  for (const Eigen::Isometry3d& p : poses) swapped.push_back(p.inverse());
  write_poses((dir / "poses_swapped.csv").string(), swapped);
  write_controller_poses((dir / "poses_rotvec.csv").string(), (dir / "poses_4x4.txt").string(), poses);
  cv::imwrite((dir / "blank.png").string(), cv::Mat(480, 640, CV_8UC1, cv::Scalar(150)));
  fs::create_directories(dir / "aprilgrid");
  const camera::Board april = camera::parse_board(camera::scenes::aprilgrid_text());
  const sim::PlanarTarget april_target = camera::scenes::target_of(april);
  const std::vector<Eigen::Isometry3d> april_views = camera::scenes::board_views(april, 12);
  for (std::size_t i = 0; i < april_views.size(); ++i) {
    cv::imwrite((dir / "aprilgrid" / numbered("april", i)).string(),
                camera::scenes::render(camera::scenes::test_camera(), april_views[i], april_target, 200 + i));
  }
  std::ofstream(dir / "not_an_image.png") << "plain text, not a PNG\n";
  return 0;
}
