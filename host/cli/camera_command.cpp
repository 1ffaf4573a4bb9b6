#include "host/cli/camera_command.hpp"

#include <algorithm>
#include <cstdint>
#include <iostream>
#include <optional>
#include <string>
#include <vector>

#include "host/camera/board.hpp"
#include "host/camera/calibration_file.hpp"
#include "host/camera/hand_eye.hpp"
#include "host/camera/hand_eye_uncertainty.hpp"
#include "host/camera/intrinsics.hpp"
#include "host/camera/robot_poses.hpp"
#include "host/camera/stereo.hpp"
#include "host/capture/frame_source.hpp"
#include "host/capture/stereo_source.hpp"
#include "host/cli/board_frames.hpp"
#include "host/cli/camera_report.hpp"
#include "host/cli/number_options.hpp"
#include "host/files/input_limits.hpp"
#include "host/files/output_file.hpp"

namespace kincal::cli {

namespace {

struct CameraArgs {
  std::string board, out, report, left_camera, right_camera, camera, poses, convention = "gripper2base";
  std::string format = "opencv", camera_name = "camera", rotation;
  std::vector<std::string> images, left, right;
  bool refine_intrinsics = false, timed_poses = false;
  double tolerance_s = 0.5, max_pose_gap_s = camera::kMaxPoseGap_s;
  int min_corners = 6;
};

// Refuses an output over any input (host/files/output_file.hpp) before any work.
void refuse_overwriting_inputs(const CameraArgs& a) {
  std::vector<files::NamedPath> inputs{{"--camera", a.camera},
                                       {"--poses", a.poses},
                                       {"--left-camera", a.left_camera},
                                       {"--right-camera", a.right_camera}};
  for (const std::string& p : a.images) inputs.push_back({"image", p});
  for (const std::string& p : a.left) inputs.push_back({"--left", p});
  for (const std::string& p : a.right) inputs.push_back({"--right", p});
  files::refuse_overwriting({{"-o", a.out}, {"--report", a.report}}, inputs);
}

int run_calibrate(const CameraArgs& a) {
  const camera::Board board = camera::parse_board(a.board);
  const std::vector<camera::BoardDetection> detections = detect_in_frames(board, a.images, a.min_corners);
  const camera::IntrinsicCalibration c = camera::calibrate_intrinsics(detections);
  std::cout << camera::describe(c);
  if (a.format == "ros")
    camera::save_camera_ros(a.out, c.camera, a.camera_name, c.views, c.uncertainty);
  else
    camera::save_camera(a.out, c, board.text());
  std::cout << "wrote " << a.out << "\n";
  if (!a.report.empty()) {
    report::write_camera_report(camera_report(c, detections), a.report);
    std::cout << "wrote " << a.report << "\n";
  }
  return 0;
}

int run_stereo(const CameraArgs& a) {
  const camera::Board board = camera::parse_board(a.board);
  capture::StereoSource frames(capture::open_source(a.left), capture::open_source(a.right), a.tolerance_s);
  BoardFrames pairs(board, a.min_corners);  // left, right, left, right, ...
  while (std::optional<capture::StereoFrame> p = frames.next()) {
    pairs.add(std::move(p->left));
    pairs.add(std::move(p->right));
  }
  std::vector<camera::BoardDetection> left, right;
  for (camera::BoardDetection& d : pairs.finish()) (left.size() == right.size() ? left : right).push_back(std::move(d));
  for (const capture::UnpairedFrame& u : frames.unpaired()) {
    std::cout << "unpaired " << (u.side == capture::Side::kLeft ? "left" : "right") << " frame: " << u.origin << " ("
              << u.timestamp_s << " s)\n";
  }
  // Each camera with its intrinsics' covariance: from its file (none in files without it) or
  // calibrated here.
  // With --report, the camera's report is made here, where its calibration is at hand.
  struct Camera {
    camera::CameraModel model;
    std::optional<camera::IntrinsicsCovariance> uncertainty;
    report::CameraReport report;
  };
  const auto camera_for = [&](const std::string& file, const std::vector<camera::BoardDetection>& views,
                              const char* side) {
    if (!file.empty()) {
      Camera from_file{camera::load_camera(file), camera::load_camera_uncertainty(file), {}};
      if (!a.report.empty()) from_file.report = lens_report(from_file.model, from_file.uncertainty, file);
      return from_file;
    }
    const camera::IntrinsicCalibration c = camera::calibrate_intrinsics(views);
    std::cout << side << " camera: reprojection RMS " << c.rms_px << " px over " << c.views_used << " views\n";
    for (const std::string& w : c.warnings) std::cout << side << " camera warning: " << w << "\n";
    return Camera{c.camera, c.uncertainty, a.report.empty() ? report::CameraReport{} : camera_report(c, views)};
  };
  const Camera left_camera = camera_for(a.left_camera, left, "left");
  const Camera right_camera = camera_for(a.right_camera, right, "right");
  camera::StereoOptions options;
  options.refine_intrinsics = a.refine_intrinsics;
  if (left_camera.uncertainty && right_camera.uncertainty) {
    options.left_intrinsics = &*left_camera.uncertainty;
    options.right_intrinsics = &*right_camera.uncertainty;
  } else if (!a.refine_intrinsics) {
    std::cout << "no uncertainty: the " << (left_camera.uncertainty ? "right" : "left")
              << " camera's file has no intrinsics_covariance\n";
  }
  const camera::StereoCalibration s =
      camera::calibrate_stereo(left, right, left_camera.model, right_camera.model, options);
  std::cout << camera::describe(s);
  camera::save_stereo(a.out, s);
  std::cout << "wrote " << a.out << "\n";
  if (!a.report.empty()) {
    report::write_camera_page(stereo_report(s, options, left_camera.report, right_camera.report), a.report);
    std::cout << "wrote " << a.report << "\n";
  }
  return 0;
}

// --timed-poses: each image's pose interpolated at the time its name gives
// (host/camera/robot_poses.hpp); an image without a pose around its time is left out, saying why.
std::vector<camera::HandEyeView> timed_views(const CameraArgs& a, const std::vector<camera::RobotPose>& poses,
                                             const std::vector<camera::BoardDetection>& detections) {
  std::vector<camera::HandEyeView> views;
  for (const camera::BoardDetection& d : detections) {
    const std::optional<std::int64_t> t_ns = camera::image_time_ns(d.view);
    if (!t_ns)
      throw camera::CalibrationError(d.view + ": with --timed-poses an image's name is its time, in ns (" +
                                     "1606153907495166540.jpg) or s (1606153907.495166540.png)");
    const camera::PoseAtTime p = camera::pose_at_time(poses, *t_ns, a.max_pose_gap_s);
    if (!p.pose) {
      std::cout << d.view << ": left out, no pose at its time: " << p.refusal << "\n";
      continue;
    }
    views.push_back(
        {d.view + " (" + a.poses + ":" + std::to_string(p.line_before) + "-" + std::to_string(p.line_after) + ")",
         *p.pose, d});
  }
  std::cout << views.size() << " of " << detections.size() << " images with a pose interpolated at their time\n";
  return views;
}

int run_hand_eye(const CameraArgs& a) {
  const camera::Board board = camera::parse_board(a.board);
  const camera::CameraModel cam = camera::load_camera(a.camera);
  const camera::RotationColumns rotation =
      a.rotation.empty() ? camera::RotationColumns::kUnnamed : camera::rotation_columns(a.rotation);
  const std::vector<camera::RobotPose> poses =
      a.timed_poses ? camera::read_timed_poses(a.poses, rotation) : camera::read_robot_poses(a.poses, rotation);
  const std::vector<camera::BoardDetection> detections = detect_in_frames(board, a.images, a.min_corners);
  if (!a.timed_poses && detections.size() != poses.size()) {
    throw camera::CalibrationError(a.poses + ": " + std::to_string(poses.size()) + " poses but " +
                                   std::to_string(detections.size()) + " images" +
                                   (poses.front().time_ns ? " (the poses have times: --timed-poses?)" : ""));
  }
  std::vector<camera::HandEyeView> views;
  if (a.timed_poses) views = timed_views(a, poses, detections);
  for (std::size_t i = 0; !a.timed_poses && i < detections.size(); ++i) {
    views.push_back({detections[i].view + " (" + a.poses + ":" + std::to_string(poses[i].line) + ")", poses[i].pose,
                     detections[i]});
  }
  camera::HandEyeOptions options;
  options.convention =
      a.convention == "base2gripper" ? camera::PoseConvention::kBaseToGripper : camera::PoseConvention::kGripperToBase;
  const camera::HandEyeCalibration h = camera::calibrate_hand_eye(views, cam, options);
  std::cout << camera::describe(h);
  std::cout << camera::describe(camera::hand_eye_jackknife(views, cam, options, h));
  // Poor data give the answer (exit 0) and what is wrong with them on standard error.
  for (const std::string& w : h.warnings) std::cerr << "kincal camera hand-eye: warning: " << w << "\n";
  camera::save_hand_eye(a.out, h);
  std::cout << "wrote " << a.out << "\n";
  if (!a.report.empty()) {
    report::write_camera_page(hand_eye_report(h, views, cam), a.report);
    std::cout << "wrote " << a.report << "\n";
  }
  return 0;
}

// Runs a command, turning every error into a message on stderr and exit status 1.
template <typename F>
void guarded(const char* name, int& status, const CameraArgs& a, F&& run) {
  try {
    refuse_overwriting_inputs(a);
    status = run();
  } catch (const std::exception& e) {
    std::cerr << "kincal camera " << name << ": " << e.what() << "\n";
    status = 1;
  }
}

void add_common(CLI::App* cmd, CameraArgs& a) {
  cmd->add_option("--board", a.board, camera::kBoardForms)->required();
  cmd->add_option("-o,--out", a.out, "output file (OpenCV YAML)")->required();
  cmd->add_option("--min-corners", a.min_corners, camera::kMinCornersHelp)
      ->check(whole_in(camera::kMinViewCorners, camera::kMaxViewCorners))
      ->capture_default_str();
}

}  // namespace

void add_camera_command(CLI::App& app, int& status) {
  auto args = std::make_shared<CameraArgs>();
  CLI::App* camera = app.add_subcommand("camera", "Camera calibration: intrinsic, stereo, hand-eye");
  camera->require_subcommand(1);

  CLI::App* calibrate = camera->add_subcommand("calibrate", "Intrinsic calibration from images of a board");
  add_common(calibrate, *args);
  calibrate
      ->add_option("images", args->images,
                   std::string("image files, a directory or a video (") + files::kImageLimitText + ")")
      ->required();
  calibrate->add_option("--format", args->format, "opencv (OpenCV YAML, the default) or ros (ROS camera_info YAML)")
      ->check(CLI::IsMember({"opencv", "ros"}));
  auto* camera_name =
      calibrate->add_option("--camera-name", args->camera_name, "camera_name of a ROS file (--format ros)")
          ->capture_default_str();
  calibrate->add_option("--report", args->report,
                        "HTML report: residuals, coverage, distortion and projection uncertainty over the image");
  calibrate->callback([args, &status, camera_name] {
    if (camera_name->count() > 0 && args->format != "ros")  // an OpenCV file has no camera name
      throw CLI::ValidationError("--camera-name", "--camera-name is a ROS file's: it needs --format ros");
    guarded("calibrate", status, *args, [&] { return run_calibrate(*args); });
  });

  CLI::App* stereo = camera->add_subcommand("stereo", "Stereo calibration from image pairs of a board");
  add_common(stereo, *args);
  stereo
      ->add_option("--left", args->left,
                   std::string("left images, directory or video (") + files::kImageLimitText + ")")
      ->required();
  stereo
      ->add_option("--right", args->right,
                   std::string("right images, directory or video (") + files::kImageLimitText + ")")
      ->required();
  stereo->add_option("--left-camera", args->left_camera, "left camera (YAML; default: calibrate from the images)");
  stereo->add_option("--right-camera", args->right_camera, "right camera (YAML; default: calibrate from the images)");
  stereo->add_flag("--refine-intrinsics", args->refine_intrinsics, "refine both cameras jointly with the pose");
  stereo->add_option("--tolerance", args->tolerance_s, "largest time difference of a pair (s)")
      ->check(finite_non_negative())
      ->capture_default_str();
  stereo->add_option("--report", args->report,
                     "HTML report: every pair's residuals, epipolar error and pose against the calibrated one, each "
                     "camera's residuals, coverage, distortion and projection uncertainty");
  stereo->callback([args, &status] { guarded("stereo", status, *args, [&] { return run_stereo(*args); }); });

  CLI::App* hand_eye = camera->add_subcommand("hand-eye", "Hand-eye calibration of a camera on the gripper");
  add_common(hand_eye, *args);
  hand_eye->add_option("--camera", args->camera, "the camera's calibration (YAML)")->required();
  hand_eye
      ->add_option("--poses", args->poses,
                   "robot poses, one per image: CSV x,y,z,qw,qx,qy,qz or x,y,z,rx,ry,rz (other columns ignored), "
                   "or 4x4 matrices row-major; with --timed-poses a timed stream, e.g. a motion capture's")
      ->required();
  hand_eye
      ->add_option("--rotation", args->rotation,
                   "what rx,ry,rz are: rotvec (rotation vector, rad), rpy or rpy-deg (R = Rz Ry Rx, fixed axes)")
      ->check(CLI::IsMember({"rotvec", "rpy", "rpy-deg"}));
  hand_eye
      ->add_option(
          "--images", args->images,
          std::string("images, in the order of the poses (files or a directory; ") + files::kImageLimitText + ")")
      ->required();
  hand_eye->add_flag("--timed-poses", args->timed_poses,
                     "the poses are a timed stream, as a motion capture records them (a time column: 'timestamp "
                     "[ns]', time_ns, time_s, ...): each image's pose is interpolated at the time its file name gives "
                     "(ns, as 1606153907495166540.jpg); the body's pose is the gripper's");
  hand_eye
      ->add_option("--max-pose-gap", args->max_pose_gap_s,
                   "with --timed-poses: the longest time between the two poses around an image (s)")
      ->check(finite_non_negative())
      ->capture_default_str();
  hand_eye->add_option("--convention", args->convention, "what the poses are: base_T_gripper or gripper_T_base")
      ->check(CLI::IsMember({"gripper2base", "base2gripper"}))
      ->capture_default_str();
  hand_eye->add_option("--report", args->report,
                       "HTML report: every pose's AX = XB and AX = ZB residuals and reprojection RMS, the views left "
                       "out, the corners' residuals at the refined result");
  hand_eye->callback([args, &status] { guarded("hand-eye", status, *args, [&] { return run_hand_eye(*args); }); });
}

}  // namespace kincal::cli
