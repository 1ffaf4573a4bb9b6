// `kincal session`: a calibration session (host/session/session.hpp) from the command line.
//
//   kincal session --model FILE [--rig platform|stereo|camera] [--plan FILE | --sweeps N [--home Q] | --poses N]
//                  [--validation N | --validation-plan FILE]
//                  [--robot sim|manual | --robot-cmd 'CMD {q}'] [--can IF [--fd] [--squares N]
//                   [--platform-camera FILE]]
//                  [--left SRC... --right SRC... --stereo FILE [--colour-table FILE] [--pixel-sigma PX]]
//                  [--board B --mount hand|world [--camera FILE --source SRC...] [--hand-eye FILE]]
//                  [--discover --joints N --home Q [--prismatic J,...] [--sweep-deg D] [--sweep-m M]
//                   [--discovered FILE]]
//                  [--journal FILE] [--resume] [--out FILE] [--report FILE] [--dataset FILE] [--seed S]
//
// The simulated robot (the default) comes with its simulated rig: the model file with hidden
// errors, the platform's firmware in-process on a loopback bus or the stereo pair. A real robot
// (--robot manual or --robot-cmd) visits only the poses of plan files (--plan, --validation-plan),
// never random ones, and is measured by the sensor platform on a SocketCAN interface (--can,
// required) looking at a strip of --squares calibration squares (--platform-camera: its camera's
// calibration with the intrinsics' covariance, whose share each pose's covariance then includes,
// host/session/sensor.hpp), or, with --rig stereo, by a
// calibrated stereo pair watching the beacon (host/session/stereo_sensor.hpp): frames from
// host/capture (--left, --right: cameras, videos or recorded images, one pair per pose), the
// pair from `kincal camera stereo` (--stereo; the device frame is the left camera's), the beacon
// by its colour class (--colour-table) or as the brightest blob; or, with --rig camera (issue
// #26), by a camera and a printed board (--board), the camera on the flange (--mount hand: the
// device frame is the board's) or fixed (--mount world: the device frame is the camera's), each
// view a full pose with its 6x6 covariance (host/session/board_sensor.hpp): frames from
// host/capture (--source, one per pose as --left), the camera from `kincal camera calibrate`
// (--camera); the base registration and the mount (hand-eye) are identified with the arm. The
// simulated robot's camera rig renders the views of its hidden-truth arm (random poses near
// --home, where the camera sees the board head-on).
// A discovery session (--discover, stereo rig) needs no model: it sweeps each of the --joints
// joints in turn from --home over --sweep-deg (or --sweep-m for the --prismatic joints, those the
// controller reads in metres) with --sweeps readings, discovers the arm from the sweeps
// (host/identify/discover.hpp, as `kincal discover`; --discovered writes it) and identifies it
// fully starting there (--out). With the simulated robot, --model is the arm the simulator hides.
// Exit status 0, or 1 with a message naming what failed (and, for a stopped session, the pose and
// how to resume).
#include "host/cli/session_command.hpp"

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <map>
#include <memory>
#include <numbers>
#include <random>
#include <sstream>

#include <Eigen/Core>
#include <opencv2/core/eigen.hpp>

#include "firmware/core/camera_model.hpp"
#include "host/camera/board.hpp"
#include "host/camera/calibration_file.hpp"
#include "host/can/socketcan.hpp"
#include "host/capture/frame_source.hpp"
#include "host/capture/stereo_source.hpp"
#include "host/cli/colour_table.hpp"
#include "host/cli/model_option.hpp"
#include "host/cli/number_options.hpp"
#include "host/demo/simulated_rig.hpp"
#include "host/files/input_file.hpp"
#include "host/files/output_file.hpp"
#include "host/identify/discover.hpp"
#include "host/identify/plausibility.hpp"
#include "host/model/isometry.hpp"
#include "host/model/model_file.hpp"
#include "host/model/number_text.hpp"
#include "host/report/report.hpp"
#include "host/session/board_sensor.hpp"
#include "host/session/online_correction.hpp"
#include "host/session/session.hpp"
#include "host/session/session_report.hpp"
#include "host/session/stereo_sensor.hpp"
#include "shared/crc32.hpp"

namespace kincal::cli {

namespace {

struct SessionArgs {
  ModelOption model;
  std::string rig = "platform", plan, validation_plan, home, robot = "sim", robot_cmd, can, journal = "session.journal";
  std::string out, report, dataset;
  std::vector<std::string> left, right;  // real stereo pair: frame sources
  std::string stereo, colour_table;
  std::vector<std::string> source;  // real camera rig: frame source
  std::string camera, board = "chessboard:9x6:0.03", mount = "hand", hand_eye;
  std::string platform_camera;  // real platform: its camera's calibration with the intrinsics' covariance
  double pixel_sigma_px = 0.1, pair_tolerance_s = 0.5;
  // Discovery of an unknown arm: its joint count, the joints read in metres, the sweeps' spans.
  bool discover = false;
  int joints = 0;
  std::vector<int> prismatic;
  double sweep_deg = 60, sweep_m = 0.2;
  std::string discovered;
  int sweeps = 0, poses = 40, validation = 20, squares = 8;
  bool fd = false, resume = false, accept_implausible = false;
  std::uint64_t seed = 1;
};

constexpr double kDegree = std::numbers::pi / 180;

std::vector<double> parse_home(const std::string& text, const model::RobotModel& m) {
  const std::vector<double> q = session::parse_readings(text, static_cast<std::size_t>(m.joint_count()));
  if (q.empty())
    throw model::InputError("--home '" + text + "': not " + std::to_string(m.joint_count()) + " joint readings");
  return q;
}

// The arm a discovery session plans its sweeps for: --joints joints, revolute but for --prismatic,
// each limited to its sweep (--sweep-deg or --sweep-m, centred on --home). Nothing else of it is
// known, nor used: the session measures with it, the discovery finds the arm from the data.
model::RobotModel unknown_arm(const SessionArgs& a) {
  model::RobotModel m;
  m.name = "unknown arm";
  for (int j = 1; j <= a.joints; ++j) {
    model::Joint joint;
    joint.name = "joint" + std::to_string(j);
    for (const int p : a.prismatic) {
      if (p < 1 || p > a.joints)
        throw model::InputError("--prismatic " + std::to_string(p) + ": the arm has joints 1 to " +
                                std::to_string(a.joints));
      if (p == j) joint.type = core::JointType::prismatic;
    }
    m.joints.push_back(joint);
  }
  const std::vector<double> home = parse_home(a.home, m);
  for (std::size_t j = 0; j < m.joints.size(); ++j) {
    const double half = m.joints[j].type == core::JointType::prismatic ? a.sweep_m / 2 : a.sweep_deg * kDegree / 2;
    m.joints[j].lower = home[j] - half;
    m.joints[j].upper = home[j] + half;
  }
  return m;
}

// What a session's identity holds of an input: the CRC-32 of what the session uses, not the path
// it came by, so that `--model ./m.yaml` resumes a session of `--model m.yaml` and an edited file
// is another session (a journal took 7 poses measured with one model and 8 with another).
std::string crc_text(std::string_view bytes) {
  char hex[16];
  std::snprintf(hex, sizeof hex, "%08x", static_cast<unsigned>(shared::crc32_text(bytes)));
  return std::string("crc32:") + hex;
}
std::string file_crc(const std::string& path, const files::InputKind& kind) {
  return path.empty() ? std::string("none") : crc_text(files::read_text(path, kind));
}
std::string plan_crc(const session::SessionPlan& plan) {
  std::string text;
  for (const session::Configurations* part : {&plan.calibration, &plan.validation}) {
    for (const std::vector<double>& q : *part) {
      for (double v : q) text += model::shortest_number_text(v) + ',';
      text += '\n';
    }
    text += "--\n";
  }
  return crc_text(text);
}

// The middle of each joint's limits (0 without limits): the sweeps' default home.
std::vector<double> mid_range(const model::RobotModel& m) {
  std::vector<double> q;
  for (const model::Joint& j : m.joints)
    q.push_back(std::isfinite(j.lower) && std::isfinite(j.upper) ? (j.lower + j.upper) / 2 : 0.0);
  return q;
}

// `count` random configurations the simulated rig can measure (SimulatedRig::random_poses: bounded
// draws, so a robot whose workspace the rig cannot see fails with the numbers instead of drawing
// forever).
std::vector<std::vector<double>> random_observable(const session::SimulatedRig& rig, int count, std::mt19937_64& rng,
                                                   const char* what) {
  try {
    return rig.random_poses(count, rng);
  } catch (const model::InputError& e) {
    throw model::InputError(std::string(what) + ": " + e.what() +
                            " (give --plan/--validation-plan with poses it can see, or fewer poses)");
  }
}

// A plan file read against the rig's model. A simulated rig may narrow joint limits (the ARID rig
// keeps its rail within 0.1 m so that the camera stays over the strip): a plan made from the
// model file then fails, and the error says which limits the rig narrowed and why.
std::vector<std::vector<double>> read_plan_for(const model::RobotModel& file, const model::RobotModel& nominal,
                                               const std::string& path) {
  try {
    return session::read_plan(nominal, path);
  } catch (const model::InputError& e) {
    std::string narrowed;
    for (std::size_t j = 0; j < nominal.joints.size() && j < file.joints.size(); ++j) {
      const model::Joint &rig = nominal.joints[j], &given = file.joints[j];
      if (rig.lower != given.lower || rig.upper != given.upper) {
        std::ostringstream text;
        text << (narrowed.empty() ? "" : ", ") << rig.name << " [" << rig.lower << ", " << rig.upper << "] instead of ["
             << given.lower << ", " << given.upper << "]";
        narrowed += text.str();
      }
    }
    if (narrowed.empty()) throw;
    throw model::InputError(std::string(e.what()) + "\n  the simulated rig narrows its model's limits (SI units) to " +
                            narrowed +
                            " so that the sensor sees the target; make the plan within these limits, or "
                            "leave --plan out to let the rig draw poses it can see");
  }
}

// The frames of a real stereo pair (host/capture), one pair per pose. Recorded sources (image
// sequences, videos) hold one pair per pose of the plan, in plan order: pose i is pair i, so a
// resumed session skips the pairs of the poses already measured, and a frame without a partner
// in time is an error (it would shift every later pose). A live camera gives the pair taken
// after kLiveStalePairs more pairs, so that frames queued during the move are not used.
class CapturedStereo {
 public:
  static constexpr int kLiveStalePairs = 4;  // --help says so

  CapturedStereo(const SessionArgs& a, int poses) {
    std::unique_ptr<capture::FrameSource> left = capture::open_source(a.left);
    std::unique_ptr<capture::FrameSource> right = capture::open_source(a.right);
    live_ = dynamic_cast<capture::CameraSource*>(left.get()) || dynamic_cast<capture::CameraSource*>(right.get());
    const auto* left_images = dynamic_cast<const capture::ImageSequenceSource*>(left.get());
    const auto* right_images = dynamic_cast<const capture::ImageSequenceSource*>(right.get());
    if (left_images && right_images) {
      const std::size_t l = left_images->files().size(), r = right_images->files().size();
      if (l != r || l != static_cast<std::size_t>(poses))
        throw model::InputError("--left has " + std::to_string(l) + " images (" + left->name() + "), --right " +
                                std::to_string(r) + " (" + right->name() + "), the plan " + std::to_string(poses) +
                                " poses (calibration and validation): recorded frames are one pair per pose, in "
                                "plan order");
    }
    source_.emplace(std::move(left), std::move(right), a.pair_tolerance_s);
  }

  session::StereoFrames grab(int pose) {
    std::optional<capture::StereoFrame> pair;
    try {
      if (live_) {
        for (int i = 0; i <= kLiveStalePairs; ++i) pair = next(pose);
      } else {
        if (taken_ > pose)
          throw session::SessionError("pose " + std::to_string(pose) + ": its frames were read already");
        while (taken_ <= pose) pair = next(pose);
      }
    } catch (const capture::CaptureError& e) {
      throw session::SessionError("pose " + std::to_string(pose) + ": " + e.what());
    }
    return {pair->left.image, pair->right.image, pair->left.timestamp_s, pair->left.origin, pair->right.origin};
  }

 private:
  capture::StereoFrame next(int pose) {
    std::optional<capture::StereoFrame> pair = source_->next();
    if (!live_ && !source_->unpaired().empty()) {
      const capture::UnpairedFrame& u = source_->unpaired().front();
      throw session::SessionError("pose " + std::to_string(pose) + ": the " +
                                  (u.side == capture::Side::kLeft ? "left" : "right") + " frame " + u.origin +
                                  " has no partner in time in the other camera's frames: recorded frames are one "
                                  "pair per pose");
    }
    if (!pair)
      throw session::SessionError("pose " + std::to_string(pose) + ": the stereo frames ended after " +
                                  std::to_string(taken_) + " pairs");
    ++taken_;
    return std::move(*pair);
  }

  std::optional<capture::StereoSource> source_;
  bool live_ = false;
  int taken_ = 0;
};

// The frames of a real camera (host/capture), one per pose: recorded sources (image sequences,
// videos) hold one frame per pose of the plan, in plan order (pose i is frame i, so a resumed
// session skips the frames of the poses already measured); a live camera gives the frame taken
// after kLiveStaleFrames more, so that frames queued during the move are not used.
class CapturedFrames {
 public:
  static constexpr int kLiveStaleFrames = 4;  // --help says so

  CapturedFrames(const std::vector<std::string>& sources, int poses) : source_(capture::open_source(sources)) {
    live_ = dynamic_cast<capture::CameraSource*>(source_.get()) != nullptr;
    const auto* images = dynamic_cast<const capture::ImageSequenceSource*>(source_.get());
    if (images && images->files().size() != static_cast<std::size_t>(poses))
      throw model::InputError("--source has " + std::to_string(images->files().size()) + " images (" + source_->name() +
                              "), the plan " + std::to_string(poses) +
                              " poses (calibration and validation): recorded frames are one per pose, in plan order");
  }

  session::BoardFrame grab(int pose) {
    const std::string at = "pose " + std::to_string(pose) + ": ";
    std::optional<capture::Frame> frame;
    try {
      if (live_) {
        for (int i = 0; i <= kLiveStaleFrames; ++i) frame = source_->next();
      } else {
        if (taken_ > pose) throw session::SessionError(at + "its frame was read already");
        while (taken_ <= pose) {
          frame = source_->next();
          if (!frame)
            throw session::SessionError(at + "the frames of " + source_->name() + " ended after " +
                                        std::to_string(taken_));
          ++taken_;
        }
      }
    } catch (const capture::CaptureError& e) {
      throw session::SessionError(at + e.what());
    }
    return {frame->image, frame->timestamp_s, frame->origin};
  }

 private:
  std::unique_ptr<capture::FrameSource> source_;
  bool live_ = false;
  int taken_ = 0;
};

// The calibrated pair of `kincal camera stereo` as the sensor takes it; the device frame is the
// left camera's.
session::StereoSetup stereo_setup(const SessionArgs& a) {
  const camera::StereoCalibration c = camera::load_stereo(a.stereo);
  session::StereoSetup setup;
  setup.pair.left = core::camera_from_block(camera::to_platform(c.left));
  setup.pair.right = core::camera_from_block(camera::to_platform(c.right));
  // x_right = R x_left + t: the right camera's pose in the left frame is the inverse.
  core::RigidTransform<float> right_T_left;
  for (int i = 0; i < 3; ++i) {
    right_T_left.translation(i) = static_cast<float>(c.right_t_left_m[i]);
    for (int j = 0; j < 3; ++j) right_T_left.rotation(i, j) = static_cast<float>(c.right_R_left(i, j));
  }
  setup.pair.left_T_right = right_T_left.inverse();
  setup.left_size_px = c.left.image_size;
  setup.right_size_px = c.right.image_size;
  setup.pixel_sigma_px = a.pixel_sigma_px;
  if (c.pose_uncertainty && !c.pose_uncertainty->calibration_covariance.empty()) {
    session::CalibrationCovariance covariance;
    cv::cv2eigen(c.pose_uncertainty->calibration_covariance, covariance);
    setup.calibration_covariance = covariance;
  }
  if (!a.colour_table.empty()) setup.colour = read_colour_table(a.colour_table);
  return setup;
}

int run(const SessionArgs& a) {
  files::refuse_overwriting({{"--out", a.out},
                             {"--report", a.report},
                             {"--dataset", a.dataset},
                             {"--discovered", a.discovered},
                             {"--hand-eye", a.hand_eye}},
                            {{"--journal", a.journal},
                             {"--model", a.model.path},
                             {"--plan", a.plan},
                             {"--validation-plan", a.validation_plan},
                             {"--stereo", a.stereo},
                             {"--colour-table", a.colour_table},
                             {"--camera", a.camera},
                             {"--platform-camera", a.platform_camera}});
  const bool simulated = a.robot == "sim" && a.robot_cmd.empty();
  const bool platform = a.rig == "platform", stereo = a.rig == "stereo", camera_rig = a.rig == "camera";
  if (!a.hand_eye.empty() && !camera_rig) throw model::InputError("--hand-eye: the camera rig's (--rig camera)");
  if (!a.platform_camera.empty() && (!platform || simulated))
    throw model::InputError(
        "--platform-camera: the camera of a real sensor platform (--rig platform with --can IF); the simulated "
        "platform's camera is exact");
  if (a.discover) {
    if (!stereo)
      throw model::InputError(
          "--discover: a discovery session watches a beacon: add --rig stereo (the platform "
          "needs the arm's model to know which square it sees)");
    if (a.joints < 1 || a.home.empty()) throw model::InputError("--discover needs --joints N and --home Q");
    if (!a.plan.empty()) throw model::InputError("--discover plans its own single-joint sweeps: leave --plan out");
    if (simulated && a.model.path.empty())
      throw model::InputError("--discover with the simulated robot: --model gives the arm the simulator hides");
  } else if (a.model.path.empty()) {
    throw model::InputError("--model is required (or --discover --joints N --home Q for an unknown arm)");
  }
  const std::optional<model::RobotModel> unknown = a.discover ? std::optional(unknown_arm(a)) : std::nullopt;
  const model::RobotModel file = a.model.path.empty() ? *unknown : a.model.load();
  if (unknown && unknown->joint_count() != file.joint_count())
    throw model::InputError("--joints " + std::to_string(a.joints) + ": the simulated robot (" + a.model.path +
                            ") has " + std::to_string(file.joint_count()));
  const bool real_stereo = !a.left.empty() || !a.right.empty() || !a.stereo.empty();
  if (real_stereo) {
    if (!stereo) throw model::InputError("--left/--right/--stereo: cameras of a stereo rig: add --rig stereo");
    if (simulated)
      throw model::InputError(
          "--left/--right/--stereo: real cameras watch a real robot: give --robot manual or --robot-cmd CMD (the "
          "simulated robot brings its own rendered cameras)");
    if (a.left.empty() || a.right.empty() || a.stereo.empty())
      throw model::InputError("a real stereo pair needs all of --left SRC, --right SRC and --stereo FILE");
    if (!a.can.empty()) throw model::InputError("--can: the stereo rig has no platform on a CAN bus");
  }
  const bool real_camera = !a.source.empty() || !a.camera.empty();
  if (real_camera) {
    if (!camera_rig)
      throw model::InputError("--camera/--source: the camera of a camera-and-board rig: add --rig camera");
    if (simulated)
      throw model::InputError(
          "--camera/--source: a real camera watches a real robot: give --robot manual or --robot-cmd CMD (the "
          "simulated robot brings its own rendered camera)");
    if (a.source.empty() || a.camera.empty())
      throw model::InputError("a real camera rig needs both --camera FILE and --source SRC");
  }
  if (camera_rig && !a.can.empty()) throw model::InputError("--can: the camera rig has no platform on a CAN bus");

  std::unique_ptr<session::SimulatedRig> rig;
  std::unique_ptr<can::Transport> transport;
  std::unique_ptr<can::PlatformClient> client;
  std::unique_ptr<session::RobotDriver> driver;
  std::unique_ptr<session::Sensor> sensor;
  if (simulated) {
    if (!a.can.empty())
      throw model::InputError(
          "--can: the simulated robot brings its own simulated platform; use --robot manual or "
          "--robot-cmd with a real platform");
    session::RigOptions o;
    o.seed = a.seed;
    o.fd = a.fd;
    o.board = a.board;
    o.camera_on_hand = a.mount == "hand";
    if (camera_rig && !a.home.empty()) o.home = parse_home(a.home, file);
    rig = session::make_simulated_rig(platform ? session::RigKind::platform
                                      : stereo ? session::RigKind::stereo
                                               : session::RigKind::camera,
                                      file, o);
  } else {
    if (camera_rig && !real_camera)
      throw model::InputError(
          "--rig camera with a real robot: give its camera (--camera FILE from `kincal camera calibrate`, --source "
          "SRC, --board B, --mount hand|world)");
    if (stereo && !real_stereo)
      throw model::InputError(
          "--rig stereo with a real robot: give its cameras (--left SRC --right SRC --stereo FILE from `kincal "
          "camera stereo`, and --colour-table FILE for a coloured beacon)");
    if (platform && a.can.empty())
      throw model::InputError("a real robot is measured by the platform: --can IF is required");
    if (a.plan.empty()) throw model::InputError("a real robot visits only planned poses: --plan FILE is required");
    if (platform) {
      std::optional<session::PlatformCamera> platform_camera;
      if (!a.platform_camera.empty()) platform_camera = session::load_platform_camera(a.platform_camera);
      transport = std::make_unique<can::SocketCanTransport>(a.can, can::SocketCanOptions{a.fd, true, {}});
      client = std::make_unique<can::PlatformClient>(*transport);
      sensor = std::make_unique<session::PlatformPoseSensor>(*client, session::strip_square_poses(a.squares),
                                                             std::move(platform_camera));
    }
    if (!a.robot_cmd.empty())
      driver = std::make_unique<session::CommandRobotDriver>(a.robot_cmd);
    else
      driver = std::make_unique<session::ManualRobotDriver>(std::cin, std::cerr);
  }
  const model::RobotModel& nominal = rig ? rig->nominal() : file;
  session::RobotDriver& robot = rig ? rig->driver() : *driver;

  session::SessionPlan plan;
  std::mt19937_64 rng(a.seed);
  if (unknown) {
    plan.calibration =
        session::single_joint_sweeps(*unknown, parse_home(a.home, *unknown), a.sweeps > 0 ? a.sweeps : 10, 1.0);
  } else if (!a.plan.empty()) {
    plan.calibration = read_plan_for(file, nominal, a.plan);
  } else if (a.sweeps > 0 || stereo) {
    const std::vector<double> home = a.home.empty() ? mid_range(nominal) : parse_home(a.home, nominal);
    plan.calibration = session::single_joint_sweeps(nominal, home, a.sweeps > 0 ? a.sweeps : 10, 0.4);
  } else {
    plan.calibration = random_observable(*rig, a.poses, rng, "--poses");
  }
  if (!a.validation_plan.empty() && unknown && a.model.path.empty()) {
    // An unknown arm's limits are only its sweeps: its validation poses lie anywhere.
    model::RobotModel unlimited = *unknown;
    for (model::Joint& j : unlimited.joints) j.lower = -(j.upper = std::numeric_limits<double>::infinity());
    plan.validation = session::read_plan(unlimited, a.validation_plan);
  } else if (!a.validation_plan.empty()) {
    plan.validation = read_plan_for(file, nominal, a.validation_plan);
  } else if (rig) {
    plan.validation = random_observable(*rig, a.validation, rng, "--validation");
  }

  std::unique_ptr<CapturedStereo> captured;
  if (real_stereo) {
    session::StereoSetup setup = stereo_setup(a);
    captured = std::make_unique<CapturedStereo>(a, plan.total());
    sensor = std::make_unique<session::StereoBeaconSensor>(
        [&frames = *captured](int pose) { return frames.grab(pose); }, std::move(setup));
  }
  std::unique_ptr<CapturedFrames> frames;
  if (real_camera) {
    session::BoardSetup setup;
    setup.board = camera::parse_board(a.board);
    setup.camera = camera::load_camera(a.camera);
    setup.intrinsics = camera::load_camera_uncertainty(a.camera);
    setup.camera_on_hand = a.mount == "hand";
    frames = std::make_unique<CapturedFrames>(a.source, plan.total());
    sensor = std::make_unique<session::BoardPoseSensor>([&captured = *frames](int pose) { return captured.grab(pose); },
                                                        std::move(setup));
  }
  session::Sensor& measure = rig ? rig->sensor() : *sensor;

  session::SessionOptions options;
  options.journal_path = a.journal;
  options.resume = a.resume;
  options.progress_terminal = ::isatty(STDERR_FILENO) != 0;
  std::map<std::string, std::string>& identity = options.identity;
  identity = {{"model", a.model.path.empty() ? std::string("none") : crc_text(model::write_model(file))},
              {"rig", a.rig},
              {"robot", simulated ? "sim" : "real"},
              {"seed", std::to_string(a.seed)},
              {"plan", plan_crc(plan)},
              {"sweeps", std::to_string(a.sweeps)},
              {"home", a.home}};
  if (real_stereo) {
    identity["stereo"] = file_crc(a.stereo, files::kSettingsFile);
    identity["colour-table"] = file_crc(a.colour_table, files::kColourTableFile);
  }
  if (!a.platform_camera.empty()) identity["platform-camera"] = file_crc(a.platform_camera, files::kSettingsFile);
  if (camera_rig) {
    identity["board"] = a.board;
    identity["mount"] = a.mount;
    identity["camera"] = file_crc(a.camera, files::kSettingsFile);
  }
  if (unknown) {
    std::string prismatic;
    for (const int p : a.prismatic) prismatic += std::to_string(p) + ' ';
    identity["discover"] = "joints=" + std::to_string(a.joints) +
                           " sweep-deg=" + model::shortest_number_text(a.sweep_deg) +
                           " sweep-m=" + model::shortest_number_text(a.sweep_m) + " prismatic=" + prismatic;
  }
  const session::SessionData data =
      session::run_session(unknown ? *unknown : nominal, plan, robot, measure, options, std::cerr);
  if (!a.dataset.empty()) {
    std::ostringstream csv;
    model::Dataset all = data.calibration;
    all.rows.insert(all.rows.end(), data.validation.rows.begin(), data.validation.rows.end());
    model::write_dataset(csv, all);
    files::write_file_atomically(a.dataset, csv.str());
  }

  // A discovery session starts the identification from the discovered model; a session with a
  // model from that model (the stereo rig: from circle-point analysis of its sweeps).
  identify::IdentifyOptions io;
  model::RobotModel start = nominal;
  if (unknown) {
    identify::DiscoverOptions discover;
    discover.name = "discovered";
    const identify::DiscoverResult found = identify::discover(data.calibration, discover);
    std::cout << "discovered from the sweeps:\n" << identify::format_discovery(found);
    if (!a.discovered.empty()) {
      model::save_model(found.model, a.discovered);
      std::cout << "discovered model: " << a.discovered << "\n";
    }
    start = found.model;
  } else {
    if (!a.accept_implausible) identify::require_plausible(nominal, data.calibration, "--accept-implausible");
    if (stereo) io.start = identify::Start::cpa;
  }
  const session::Calibration calibration = session::calibrate(start, data, io);
  std::cout << identify::format_report(calibration.result);
  if (!data.validation.rows.empty())
    std::cout << "validation (" << data.validation.rows.size() << " poses): " << (unknown ? "discovered" : "nominal")
              << " RMS " << calibration.before.rms_m * 1e3 << " mm, identified RMS " << calibration.after.rms_m * 1e3
              << " mm\n";
  if (!a.out.empty()) model::save_model(calibration.result.model, a.out);
  if (!a.hand_eye.empty()) {
    const model::RobotModel& m = calibration.result.model;
    files::write_file_atomically(a.hand_eye,
                                 camera::rig_hand_eye_text(a.mount == "hand", model::isometry(m.flange_T_tool),
                                                           model::isometry(m.base_T_frame0).inverse()));
    std::cout << "wrote " << a.hand_eye << " (the hand-eye, mount " << a.mount << ", identified with the arm)\n";
  }

  std::optional<session::CorrectionCheck> check;
  can::PlatformClient* platform_client = rig ? rig->platform() : client.get();
  if (platform && platform_client && !data.validation.rows.empty()) {
    check = session::verify_online_correction(*platform_client, a.fd, calibration, data, robot, measure, std::cout);
    std::cout << "online correction on the validation targets: RMS " << check->before.rms_m * 1e3 << " mm -> "
              << check->after.rms_m * 1e3 << " mm\n";
  }
  if (!a.report.empty()) {
    session::RunDescription d;
    d.title = "Calibration session: " + file.name;
    d.robot = file.name;
    d.method = !stereo   ? "full nonlinear least squares"
               : unknown ? "discovery from single-joint sweeps (no model), then full least squares"
                         : "circle-point analysis, then full least squares";
    d.data = a.journal;
    d.simulated = simulated;
    report::Report r;
    r.title = "kincal session";
    r.runs.push_back(session::report_run(d, start, data, calibration,
                                         rig ? std::optional<model::RobotModel>(rig->truth()) : std::nullopt, nullptr));
    report::write_html(r, a.report);
    std::cout << "wrote " << a.report << "\n";
  }
  return 0;
}

}  // namespace

void add_session_command(CLI::App& app, int& status) {
  auto a = std::make_shared<SessionArgs>();
  auto* cmd = app.add_subcommand("session", "Run a calibration session: move, measure, journal, identify, upload");
  add_model_option(*cmd, a->model, "robot model (with --discover: the arm the simulated robot hides)", false);
  cmd->add_option("--rig", a->rig,
                  "platform (camera + rangers over CAN), stereo (beacon and stereo pair) or camera (a camera and a "
                  "printed board)")
      ->check(CLI::IsMember({"platform", "stereo", "camera"}))
      ->capture_default_str();
  auto* plan = cmd->add_option("--plan", a->plan, "calibration poses (joints CSV, e.g. from `kincal plan`)");
  auto* sweeps =
      cmd->add_option("--sweeps", a->sweeps,
                      "single-joint sweeps with this many readings per joint (default 10 on the stereo rig and with "
                      "--discover)")
          ->check(whole_in(4, 1000))
          ->excludes(plan);
  auto* poses = cmd->add_option("--poses", a->poses, "random calibration poses in view (simulated robot, platform rig)")
                    ->check(whole_in(1, 10000))
                    ->capture_default_str()
                    ->excludes(plan)
                    ->excludes(sweeps);
  cmd->add_option("--home", a->home, "home readings of the sweeps, comma-separated (rad, m)");
  auto* validation = cmd->add_option("--validation", a->validation, "random validation poses (simulated robot)")
                         ->check(whole_in(0, 10000))
                         ->capture_default_str();
  cmd->add_option("--validation-plan", a->validation_plan, "validation poses (joints CSV)")->excludes(validation);
  auto* robot = cmd->add_option("--robot", a->robot, "sim or manual")
                    ->check(CLI::IsMember({"sim", "manual"}))
                    ->capture_default_str();
  cmd->add_option("--robot-cmd", a->robot_cmd,
                  "command that moves the robot; {q} = the joint values (not with --robot)")
      ->excludes(robot);
  cmd->add_option("--left", a->left,
                  "real stereo rig: the left camera's frames: a V4L2 device (0, /dev/video0), a video, a "
                  "directory of images or image files (a quoted pattern like 'left/*.png' is expanded); recorded "
                  "frames are one per pose of --plan then --validation-plan, in order; a live camera's pair is taken "
                  "after 4 more, so that frames queued during the move are not used")
      ->expected(1, -1);
  cmd->add_option("--right", a->right, "real stereo rig: the right camera's frames, as --left")->expected(1, -1);
  auto* stereo =
      cmd->add_option("--stereo", a->stereo,
                      "real stereo rig: the calibrated pair (`kincal camera stereo`); positions are measured in the "
                      "left camera's frame (x right, y down, z forward): the model's base is placed in it");
  cmd->add_option("--colour-table", a->colour_table,
                  "real stereo rig: the beacon's colour class (`kincal colour-table`); without it the beacon is the "
                  "brightest blob")
      ->needs(stereo);
  cmd->add_option("--pixel-sigma", a->pixel_sigma_px,
                  "real stereo rig: centroid noise (px) the measurements' covariance assumes; the identification "
                  "estimates any excess as model error")
      ->check(finite_positive())
      ->capture_default_str()
      ->needs(stereo);
  cmd->add_option("--pair-tolerance", a->pair_tolerance_s,
                  "real stereo rig: largest time difference of a left and right frame (s); image sequences are "
                  "stamped 1 s apart")
      ->check(finite_non_negative())
      ->capture_default_str()
      ->needs(stereo);
  cmd->add_option("--board", a->board,
                  std::string("camera rig: the printed board, ") + camera::kBoardForms +
                      " (the simulated rig renders chessboards)")
      ->capture_default_str();
  cmd->add_option("--mount", a->mount,
                  "camera rig: hand, the camera on the flange and the board fixed (positions in the board's frame); "
                  "world, the camera fixed and the board on the flange (positions in the camera's frame)")
      ->check(CLI::IsMember({"hand", "world"}))
      ->capture_default_str();
  cmd->add_option("--camera", a->camera, "real camera rig: the camera's calibration (`kincal camera calibrate`)");
  cmd->add_option("--hand-eye", a->hand_eye,
                  "camera rig: also write the identified mount and board or camera place as `kincal camera hand-eye` "
                  "does (OpenCV YAML)");
  cmd->add_option("--source", a->source,
                  "real camera rig: the camera's frames, as --left: a V4L2 device, a video, a directory of images or "
                  "image files, one per pose of --plan then --validation-plan; a live camera's frame is taken after "
                  "4 more")
      ->expected(1, -1);
  auto* discover = cmd->add_flag(
      "--discover", a->discover,
      "discovery session (stereo rig): sweep each joint of an unknown arm from --home, discover its model "
      "(`kincal discover`), then identify it fully from there");
  poses->excludes(discover);
  // The discovery's own options mean nothing in another session.
  cmd->add_option("--joints", a->joints, "discovery: the arm's joint count")->check(whole_in(1, 16))->needs(discover);
  cmd->add_option("--prismatic", a->prismatic, "discovery: joints (1-based) the controller moves in metres")
      ->delimiter(',')
      ->needs(discover);
  cmd->add_option("--sweep-deg", a->sweep_deg, "discovery: span of each revolute joint's sweep (deg)")
      ->check(finite_in(1, 720))
      ->capture_default_str()
      ->needs(discover);
  cmd->add_option("--sweep-m", a->sweep_m, "discovery: span of each prismatic joint's sweep (m)")
      ->check(finite_in(1e-3, 10))
      ->capture_default_str()
      ->needs(discover);
  cmd->add_option("--discovered", a->discovered, "discovery: write the discovered model here (YAML)")->needs(discover);
  cmd->add_option("--platform-camera", a->platform_camera,
                  "real platform: its camera's calibration with intrinsics_covariance (`kincal camera calibrate`); "
                  "each pose's covariance then includes the camera's share");
  auto* can = cmd->add_option("--can", a->can, "SocketCAN interface of a real platform (e.g. can0, vcan0)");
  cmd->add_flag("--fd", a->fd, "CAN FD");
  cmd->add_option("--squares", a->squares, "calibration squares on the strip (real platform)")
      ->check(whole_in(1, 64))
      ->capture_default_str()
      ->needs(can);
  cmd->add_option("--journal", a->journal, "the session's measurement journal")->capture_default_str();
  cmd->add_flag("--resume", a->resume, "continue the journal of a stopped session");
  cmd->add_option("--out", a->out, "write the identified model here (YAML)");
  cmd->add_option("--report", a->report, "write the HTML report here");
  cmd->add_option("--dataset", a->dataset, "write the measurements here (dataset CSV)");
  cmd->add_flag("--accept-implausible", a->accept_implausible,
                "identify even when the measurements look wrong for the model (units, quaternion order)");
  cmd->add_option("--seed", a->seed, "seed of the simulated robot's hidden errors and noise")->capture_default_str();
  cmd->callback([a, &status] {
    try {
      status = run(*a);
    } catch (const std::exception& e) {
      std::cerr << "\nkincal session: " << e.what() << "\n";
      if (dynamic_cast<const session::SessionError*>(&e))
        std::cerr << "kincal session: the journal " << a->journal
                  << " keeps every measurement so far; run again with --resume to continue\n";
      status = 1;
    }
  });
}

}  // namespace kincal::cli
