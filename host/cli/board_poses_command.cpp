#include "host/cli/board_poses_command.hpp"

#include <cmath>
#include <iostream>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "host/camera/board.hpp"
#include "host/camera/board_pose.hpp"
#include "host/camera/calibration_file.hpp"
#include "host/camera/intrinsics.hpp"
#include "host/cli/board_frames.hpp"
#include "host/cli/number_options.hpp"
#include "host/files/input_limits.hpp"
#include "host/files/output_file.hpp"
#include "host/model/dataset.hpp"

namespace kincal::cli {

namespace {

struct BoardPosesArgs {
  std::string camera, board, mount = "hand", joints, out;
  std::vector<std::string> images;
  int min_corners = camera::BoardPoseOptions{}.min_corners;
};

std::string fixed(double v, int precision) {
  std::ostringstream o;
  o.setf(std::ios::fixed);
  o.precision(precision);
  o << v;
  return o.str();
}

int run_board_poses(const BoardPosesArgs& a) {
  std::vector<files::NamedPath> inputs{{"--camera", a.camera}, {"--joints", a.joints}};
  for (const std::string& p : a.images) inputs.push_back({"--images", p});
  files::refuse_overwriting({{"-o", a.out}}, inputs);
  const camera::Board board = camera::parse_board(a.board);
  const camera::CameraModel cam = camera::load_camera(a.camera);
  const std::optional<camera::IntrinsicsCovariance> intrinsics = camera::load_camera_uncertainty(a.camera);
  const std::vector<std::vector<double>> joints = model::read_joints(a.joints);

  const std::vector<camera::BoardDetection> detections = detect_in_frames(board, a.images, a.min_corners);
  if (detections.size() != joints.size())
    throw camera::CalibrationError(a.joints + ": " + std::to_string(joints.size()) + " joint rows but " +
                                   std::to_string(detections.size()) + " images");
  camera::refuse_wrong_board(detections);

  const bool hand = a.mount == "hand";
  camera::BoardPoseOptions options;
  options.min_corners = a.min_corners;
  model::Dataset data;
  data.source = a.out;
  data.joint_count = joints.empty() ? 0 : static_cast<int>(joints[0].size());
  data.has_orientation = true;
  data.noise = model::NoiseColumns::covariance;
  data.has_pose_covariance = true;
  std::cout << "camera " << a.camera << (intrinsics ? " (with its intrinsics' covariance)" : " (no covariance)")
            << ", board " << board.text() << ", mount " << a.mount << "\n";
  for (std::size_t i = 0; i < detections.size(); ++i) {
    const camera::BoardPose p = camera::board_pose(detections[i], cam, intrinsics, options);
    if (!p.refusal.empty()) {
      std::cout << p.view << ": refused: " << p.refusal << "\n";
      continue;
    }
    const auto [device_T_tool, c] = camera::pose_measurement(p, hand);
    data.rows.push_back(model::pose_row(joints[i], device_T_tool, c, static_cast<int>(i) + 1));
    std::cout << p.view << ": " << p.corners << " corners, RMS " << fixed(p.rms_px, 3) << " px, sigma "
              << fixed(p.corner_sigma_px, 3) << " px, tilt " << fixed(p.tilt_rad * 180 / std::numbers::pi, 1)
              << " deg, position sigma " << fixed(std::sqrt(c.topLeftCorner<3, 3>().trace()) * 1e3, 3)
              << " mm, rotation sigma "
              << fixed(std::sqrt(c.bottomRightCorner<3, 3>().trace()) * 180 / std::numbers::pi, 4) << " deg\n";
  }
  if (data.rows.empty())
    throw camera::CalibrationError("no usable view of " + std::to_string(detections.size()) +
                                   camera::seen_board_hint(detections));
  std::ostringstream text;
  model::write_dataset(text, data);
  files::write_file_atomically(a.out, text.str());
  std::cout << "wrote " << a.out << " (" << data.rows.size() << " of " << detections.size() << " views)\n";
  return 0;
}

}  // namespace

void add_board_poses_command(CLI::App& app, int& status) {
  auto a = std::make_shared<BoardPosesArgs>();
  CLI::App* cmd = app.add_subcommand(
      "board-poses", "Pose measurements from board views and joint readings (a camera and a printed board)");
  cmd->add_option("--camera", a->camera, "the camera's calibration (OpenCV or ROS YAML)")->required();
  cmd->add_option("--board", a->board, camera::kBoardForms)->required();
  cmd->add_option("--mount", a->mount, "hand: the camera on the flange; world: the board on the flange")
      ->check(CLI::IsMember({"hand", "world"}))
      ->required();
  cmd->add_option(
         "--images", a->images,
         std::string("the views, one per joints row (files, a directory or a video; ") + files::kImageLimitText + ")")
      ->required();
  cmd->add_option("--joints", a->joints, "joint readings of the views (CSV q1..qN)")->required();
  cmd->add_option("-o,--out", a->out, "dataset to write (CSV)")->required();
  cmd->add_option("--min-corners", a->min_corners, camera::kMinCornersHelp)
      ->check(whole_in(camera::kMinViewCorners, camera::kMaxViewCorners))
      ->capture_default_str();
  cmd->callback([a, &status] {
    try {
      status = run_board_poses(*a);
    } catch (const std::exception& e) {
      std::cerr << "kincal board-poses: " << e.what() << "\n";
      status = 1;
    }
  });
}

}  // namespace kincal::cli
