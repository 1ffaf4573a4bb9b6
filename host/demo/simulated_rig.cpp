#include "host/demo/simulated_rig.hpp"

#include <cmath>
#include <functional>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>

#include <Eigen/Eigenvalues>

#include "host/camera/board.hpp"
#include "host/can/loopback.hpp"
#include "host/model/isometry.hpp"
#include "host/session/board_sensor.hpp"
#include "host/session/stereo_sensor.hpp"
#include "host/sim/beacon.hpp"
#include "host/sim/board_views.hpp"
#include "host/sim/parameter_blocks.hpp"
#include "host/sim/rangers.hpp"
#include "host/sim/render.hpp"
#include "host/sim/robot.hpp"
#include "host/sim/simulated_platform.hpp"
#include "host/sim/strip.hpp"

namespace kincal::session {

namespace {

using model::isometry;
using model::transform;

// The noise of pose `index`: the same whatever happened before (a resumed session sees what an
// uninterrupted one would).
std::uint64_t pose_seed(std::uint64_t seed, int index) {
  constexpr std::uint64_t kGolden = 0x9E3779B97F4A7C15u, kMix = 0xBF58476D1CE4E5B9u;
  return seed * kGolden + static_cast<std::uint64_t>(index) * kMix + 1u;
}

// `count` random readings within the joint limits that `rig` observes, in bounded draws.
std::vector<std::vector<double>> observable_draws(const SimulatedRig& rig, int count, std::mt19937_64& rng) {
  const long attempts = 1000 + 1000L * count;
  std::vector<std::vector<double>> poses;
  for (long i = 0; i < attempts && static_cast<int>(poses.size()) < count; ++i) {
    std::vector<double> q = sim::random_configuration(rig.nominal(), rng);
    if (rig.observable(q)) poses.push_back(std::move(q));
  }
  if (static_cast<int>(poses.size()) < count)
    throw model::InputError(std::to_string(poses.size()) + " of " + std::to_string(attempts) +
                            " random configurations of " + rig.nominal().name +
                            " within its joint limits are in view of the simulated rig, " + std::to_string(count) +
                            " needed: the rig cannot see this robot's workspace");
  return poses;
}

// Goes exactly where it is told, then lets the world show what is there.
class SimulatedDriver : public RobotDriver {
 public:
  explicit SimulatedDriver(std::function<void(int, const std::vector<double>&)> moved) : moved_(std::move(moved)) {}
  std::vector<double> move_to(int index, const std::vector<double>& target) override {
    moved_(index, target);
    return target;
  }
  std::string name() const override { return "simulated"; }

 private:
  std::function<void(int, const std::vector<double>&)> moved_;
};

// A rig whose sensor is on the host (no platform on a bus): the simulated driver and the sensor.
class HostSensorRig : public SimulatedRig {
 public:
  RobotDriver& driver() override { return *driver_; }
  Sensor& sensor() override { return *sensor_; }
  can::PlatformClient* platform() override { return nullptr; }
  bool fd() const override { return false; }

 protected:
  std::unique_ptr<Sensor> sensor_;
  std::unique_ptr<SimulatedDriver> driver_;
};

// ---- Doty's ARID with the sensor platform ----------------------------------------------------

constexpr double kStandOffM = 0.3;    // camera to strip at the rail's nearest reading
constexpr double kRailTravelM = 0.1;  // the rail moves the camera along its axis: keep within the rangers
constexpr int kSquares = 16;

class PlatformRig : public SimulatedRig {
 public:
  PlatformRig(const model::RobotModel& file, const RigOptions& options)
      : options_(options),
        nominal_(place(file)),
        robot_(nominal_, options.seed, {}, sim::typical_imperfections(sim::reach_m(nominal_))) {
    camera_.distortion = {-0.05, 0.01, 0, 0, 0};
    if (!options.candump_log.empty()) bus_.log_to(options.candump_log);
    platform_ = std::make_unique<sim::SimulatedPlatform>(bus_, options.fd, camera_.width_px, camera_.height_px, view_);
    can::LoopbackOptions lo;
    lo.fd = options.fd;
    transport_ = std::make_unique<can::LoopbackTransport>(bus_.attach(), lo);
    client_ = std::make_unique<can::PlatformClient>(*transport_);
    upload(shared::ParameterBlock::kIntrinsics, sim::to_intrinsics(camera_));
    upload(shared::ParameterBlock::kGeometry, sim::platform_geometry(strip_, rangers_));
    sensor_ = std::make_unique<PlatformPoseSensor>(*client_, strip_square_poses(strip_.squares));
    driver_ = std::make_unique<SimulatedDriver>([this](int index, const std::vector<double>& q) { show(index, q); });
  }

  const model::RobotModel& nominal() const override { return nominal_; }
  const model::RobotModel& truth() const override { return robot_.truth(); }
  RobotDriver& driver() override { return *driver_; }
  Sensor& sensor() override { return *sensor_; }
  can::PlatformClient* platform() override { return client_.get(); }
  bool fd() const override { return options_.fd; }
  std::string description() const override {
    return "Doty's ARID (" + nominal_.name + ") with the camera-and-ranger platform over a strip of " +
           std::to_string(strip_.squares) + " calibration squares; the firmware in the loop on a loopback bus";
  }

  bool observable(const std::vector<double>& q) const override {
    const model::Transform strip_T_camera = model::forward_kinematics(nominal_, q);
    const model::Vector3 axis = strip_T_camera.rotation.col(2);
    if (axis.z() > -0.9) return false;  // not looking at the strip
    const double t = -strip_T_camera.translation.z() / axis.z();
    if (t < 0.2 || t > 0.6) return false;
    const model::Vector3 hit = strip_T_camera.translation + t * axis;
    const double half = strip_.square_m / 2;
    return hit.x() > half && hit.x() < (strip_.squares - 1.5) * strip_.square_m && std::abs(hit.y()) < half * 0.6;
  }
  std::vector<std::vector<double>> random_poses(int count, std::mt19937_64& rng) const override {
    return observable_draws(*this, count, rng);
  }

 private:
  // The file's chain and camera, placed so that the camera looks along the joint axes at the
  // strip kStandOffM away, the strip along the band the camera sweeps (the principal direction
  // of the camera's positions over random poses); the rail limited to kRailTravelM.
  static model::RobotModel place(model::RobotModel m) {
    for (model::Joint& j : m.joints)
      if (j.type == core::JointType::prismatic) j.upper = std::min(j.upper, j.lower + kRailTravelM);
    m.base_T_frame0 = model::Transform{};
    std::mt19937_64 rng(12345);
    std::vector<model::Vector3> p;
    for (int i = 0; i < 2000; ++i)
      p.push_back(model::forward_kinematics(m, sim::random_configuration(m, rng)).translation);
    model::Vector3 centre = model::Vector3::Zero();
    double nearest_z = std::numeric_limits<double>::infinity();
    for (const auto& v : p) {
      centre += v / static_cast<double>(p.size());
      nearest_z = std::min(nearest_z, v.z());
    }
    Eigen::Matrix2d scatter = Eigen::Matrix2d::Zero();
    for (const auto& v : p) scatter += (v - centre).head<2>() * (v - centre).head<2>().transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix2d> eigen(scatter);
    const Eigen::Vector2d u = eigen.eigenvectors().col(1);
    // The strip frame in frame 0: x along u, z toward the camera (which looks along +z0).
    model::Transform frame0_T_strip;
    frame0_T_strip.rotation.col(0) = model::Vector3(u.x(), u.y(), 0);
    frame0_T_strip.rotation.col(2) = model::Vector3(0, 0, -1);
    frame0_T_strip.rotation.col(1) = frame0_T_strip.rotation.col(2).cross(frame0_T_strip.rotation.col(0));
    const double half_length = (kSquares - 1) * sim::kInch_m * 4 / 2;
    frame0_T_strip.translation = centre - half_length * frame0_T_strip.rotation.col(0);
    frame0_T_strip.translation.z() = nearest_z + kStandOffM + kRailTravelM;
    m.base_T_frame0 = frame0_T_strip.inverse();
    return m;
  }

  template <class Block>
  void upload(shared::ParameterBlock id, const Block& block) {
    std::array<std::uint8_t, shared::kMaxBlockBytes> image{};
    const std::size_t n = shared::encode_block(block, image);
    try {
      client_->upload(id, std::span<const std::uint8_t>(image.data(), n));
    } catch (const can::PlatformError& e) {
      throw SessionError(std::string("simulated platform: loading its parameters: ") + e.what());
    }
  }

  void show(int index, const std::vector<double>& q) {
    // The true pose on this visit (sag and repeatability included), without the limit check of
    // tool_pose(): a corrected target may lie a hair beyond a limit.
    const Eigen::Isometry3d camera_T_strip =
        isometry(robot_.visit_pose(q, static_cast<std::uint64_t>(index)).inverse());
    sim::ImagingConditions conditions;
    conditions.seed = pose_seed(options_.seed, index);
    conditions.read_noise_dn *= options_.measurement_scale;
    sim::RangerSpec rangers = rangers_;
    rangers.sigma_m *= options_.measurement_scale;
    std::mt19937_64 rng(conditions.seed);
    view_.set(sim::render_plane(camera_, camera_T_strip, target_, conditions),
              sim::simulate_ranges(rangers, camera_T_strip, rng));
  }

  RigOptions options_;
  model::RobotModel nominal_;
  sim::SimulatedRobot robot_;
  sim::CameraSpec camera_;
  sim::StripSpec strip_{kSquares};
  sim::RangerSpec rangers_;
  sim::PlanarTarget target_ = sim::strip_target(strip_);
  sim::SimulatedView view_;
  can::LoopbackBus bus_;
  std::unique_ptr<sim::SimulatedPlatform> platform_;
  std::unique_ptr<can::LoopbackTransport> transport_;
  std::unique_ptr<can::PlatformClient> client_;
  std::unique_ptr<PlatformPoseSensor> sensor_;
  std::unique_ptr<SimulatedDriver> driver_;
};

// ---- Kapucu & Baysec's stereo rig ------------------------------------------------------------

// Centroid noise the stereo sensor's covariance assumes (px): measured on this rig's rendered
// beacon (tests/host/session: the spread of the centroid over noise seeds).
constexpr double kBeaconCentroidSigmaPx = 0.05;

class StereoRig : public HostSensorRig {
 public:
  StereoRig(const model::RobotModel& file, const RigOptions& options)
      : options_(options), robot_(file, options.seed, {}, sim::typical_imperfections(sim::reach_m(file))) {
    beacon_.radius_m = 0.015;
    // The rendered pair as a calibrated one: both cameras as rendered (sim::stereo_pair_of), the
    // right camera one baseline along the left camera's x.
    StereoSetup setup;
    setup.pair = sim::stereo_pair_of(spec_);
    setup.left_size_px = setup.right_size_px = cv::Size(spec_.camera.width_px, spec_.camera.height_px);
    // Their camera frame has y up: the right camera's OpenCV frame turned half a turn about z.
    model::Transform device_T_right;
    device_T_right.rotation = Eigen::AngleAxisd(std::numbers::pi, model::Vector3::UnitZ()).toRotationMatrix();
    model::Transform right_T_left;
    right_T_left.translation = model::Vector3(-spec_.baseline_m, 0, 0);
    setup.device_T_left = device_T_right * right_T_left;
    setup.pixel_sigma_px = kBeaconCentroidSigmaPx * options.measurement_scale;
    sensor_ = std::make_unique<StereoBeaconSensor>([this](int) { return frames_; }, std::move(setup));
    driver_ = std::make_unique<SimulatedDriver>([this](int index, const std::vector<double>& q) { show(index, q); });
  }

  const model::RobotModel& nominal() const override { return robot_.nominal(); }
  const model::RobotModel& truth() const override { return robot_.truth(); }
  std::string description() const override {
    return "Kapucu & Baysec's rig (" + robot_.nominal().name +
           "): a beacon on the tool, a parallel stereo pair 4.54 m away, baseline 12.6 cm";
  }

  bool observable(const std::vector<double>& q) const override {
    const model::Vector3 p = model::forward_kinematics(robot_.nominal(), q).translation;
    if (p.z() < 1.0) return false;
    const double margin = 30;
    for (const double x_offset : {0.0, spec_.baseline_m}) {  // right camera, then left
      // Device frame (y up) to the camera's pixels.
      const double u = spec_.camera.cx_px - spec_.camera.fx_px * (p.x() - x_offset) / p.z();
      const double v = spec_.camera.cy_px - spec_.camera.fy_px * p.y() / p.z();
      if (u < margin || v < margin || u > spec_.camera.width_px - 1 - margin || v > spec_.camera.height_px - 1 - margin)
        return false;
    }
    return true;
  }
  std::vector<std::vector<double>> random_poses(int count, std::mt19937_64& rng) const override {
    return observable_draws(*this, count, rng);
  }

 private:
  void show(int index, const std::vector<double>& q) {
    sim::ImagingConditions conditions;
    conditions.seed = pose_seed(options_.seed, index);
    conditions.read_noise_dn *= options_.measurement_scale;
    const model::Vector3 beacon = robot_.visit_pose(q, static_cast<std::uint64_t>(index)).translation;
    if (!(beacon.z() > beacon_.radius_m)) {
      throw SessionError("pose " + std::to_string(index) + ": the beacon is " + std::to_string(beacon.z()) +
                         " m along the stereo pair's axis, behind or at the cameras: this rig cannot see " +
                         robot_.nominal().name + " there (give --home or a --plan with poses in front of it)");
    }
    const sim::StereoFrame f = sim::render_beacon(spec_, beacon_, beacon, conditions);
    frames_ = {f.left, f.right, 0.0, "rendered left", "rendered right"};
  }

  RigOptions options_;
  sim::SimulatedRobot robot_;
  sim::StereoRigSpec spec_;
  sim::BeaconSpec beacon_;
  StereoFrames frames_;
};

// ---- A camera and a printed board -----------------------------------------------------------

constexpr double kBoardDistanceM = 0.6;  // camera to board's centre at home
constexpr double kViewMarginPx = 30;     // the board's outline this far inside the image

// The VGA camera the rig renders with and measures through (its true intrinsics): the
// renderer's 640 x 480, f = 600 px, with barrel distortion.
sim::CameraSpec vga_camera() {
  sim::CameraSpec c;
  c.distortion = {-0.21, 0.09, 0.0, 0.0, 0.0};
  return c;
}

camera::CameraModel camera_model(const sim::CameraSpec& s) {
  camera::CameraModel m;
  m.image_size = cv::Size(s.width_px, s.height_px);
  m.camera_matrix = cv::Matx33d(s.fx_px, 0, s.cx_px, 0, s.fy_px, s.cy_px, 0, 0, 1);
  m.distortion = s.distortion;
  return m;
}

// A chessboard: the one kind the rig renders.
camera::Board parse_chessboard(const std::string& text) {
  camera::Board board;
  try {
    board = camera::parse_board(text);
  } catch (const std::invalid_argument& e) {
    throw model::InputError(std::string("camera rig: ") + e.what());
  }
  if (board.kind != camera::BoardKind::kChessboard)
    throw model::InputError("camera rig: the simulated camera rig renders chessboards only, not '" + text + "'");
  return board;
}

// The printed area's extent in the board frame: inner corners from 0 to (cols - 1) squares, the
// outer squares and the white border two more on each side.
std::vector<Eigen::Vector3d> board_outline(const camera::Board& b) {
  const double s = b.square_m, x0 = -2 * s, y0 = -2 * s, x1 = (b.cols + 1) * s, y1 = (b.rows + 1) * s;
  return {{x0, y0, 0}, {x1, y0, 0}, {x1, y1, 0}, {x0, y1, 0}};
}

sim::BoardRig place_board_rig(const model::RobotModel& arm, const camera::Board& board, const RigOptions& options) {
  std::vector<double> home = options.home;
  if (home.empty())
    for (const model::Joint& j : arm.joints)
      home.push_back(std::isfinite(j.lower) && std::isfinite(j.upper) ? (j.lower + j.upper) / 2 : 0.0);
  const Eigen::Vector3d centre(0.5 * (board.cols - 1) * board.square_m, 0.5 * (board.rows - 1) * board.square_m, 0);
  try {
    return sim::board_rig(arm, options.camera_on_hand ? sim::BoardMount::hand : sim::BoardMount::world, home,
                          kBoardDistanceM, centre);
  } catch (const std::invalid_argument& e) {
    throw model::InputError(std::string("camera rig (") + arm.name + "): " + e.what());
  }
}

class CameraRig : public HostSensorRig {
 public:
  CameraRig(const model::RobotModel& file, const RigOptions& options)
      : options_(options),
        board_(parse_chessboard(options.board)),
        outline_(board_outline(board_)),
        target_(sim::chessboard(board_.cols, board_.rows, board_.square_m)),
        rig_(place_board_rig(file, board_, options)),
        robot_(rig_.nominal, options.seed) {
    BoardSetup setup;
    setup.board = board_;
    setup.camera = camera_model(camera_);
    setup.camera_on_hand = options.camera_on_hand;
    sensor_ = std::make_unique<BoardPoseSensor>([this](int) { return frame_; }, std::move(setup));
    driver_ = std::make_unique<SimulatedDriver>([this](int index, const std::vector<double>& q) { show(index, q); });
  }

  const model::RobotModel& nominal() const override { return rig_.nominal; }
  const model::RobotModel& truth() const override { return robot_.truth(); }
  std::string description() const override {
    return std::string("a camera and a printed board (") + rig_.nominal.name + "): a VGA camera " +
           (options_.camera_on_hand ? "on the flange, the board fixed in the cell"
                                    : "fixed in the cell, the board on the flange") +
           ", board " + board_.text() + " seen from about 0.6 m";
  }

  // The whole printed board in view, margin included, by the nominal rig.
  bool observable(const std::vector<double>& q) const override {
    const Eigen::Isometry3d view = sim::camera_T_board(rig_.mount, model::forward_kinematics(rig_.nominal, q));
    for (const Eigen::Vector3d& p : outline_)
      if ((view * p).z() <= 0) return false;
    for (const cv::Point2d& px : sim::project_points(camera_, view, outline_))
      if (px.x < kViewMarginPx || px.y < kViewMarginPx || px.x > camera_.width_px - 1 - kViewMarginPx ||
          px.y > camera_.height_px - 1 - kViewMarginPx)
        return false;
    return true;
  }
  std::vector<std::vector<double>> random_poses(int count, std::mt19937_64& rng) const override {
    sim::ViewPlanOptions plan;
    plan.margin_px = kViewMarginPx;
    try {
      return sim::board_view_plan(rig_, camera_, outline_, count, rng, plan);
    } catch (const std::invalid_argument& e) {
      throw model::InputError(std::string("camera rig (") + rig_.nominal.name + "): " + e.what());
    }
  }

 private:
  void show(int index, const std::vector<double>& q) {
    sim::ImagingConditions conditions;
    conditions.supersampling = 2;
    conditions.seed = pose_seed(options_.seed, index);
    conditions.read_noise_dn *= options_.measurement_scale;
    frame_ = {sim::render_board_view(robot_, rig_.mount, q, camera_, target_, conditions), 0.0,
              "rendered view " + std::to_string(index)};
  }

  RigOptions options_;
  sim::CameraSpec camera_ = vga_camera();
  camera::Board board_;
  std::vector<Eigen::Vector3d> outline_;
  sim::PlanarTarget target_;
  sim::BoardRig rig_;
  sim::SimulatedRobot robot_;
  BoardFrame frame_;
};

}  // namespace

std::vector<model::Transform> strip_square_poses(int squares) {
  sim::StripSpec strip;
  strip.squares = squares;
  std::vector<model::Transform> poses;
  for (int k = 0; k < strip.squares; ++k) poses.push_back(transform(sim::strip_T_square(strip, k)));
  return poses;
}

std::unique_ptr<SimulatedRig> make_simulated_rig(RigKind kind, const model::RobotModel& model,
                                                 const RigOptions& options) {
  if (kind == RigKind::platform) return std::make_unique<PlatformRig>(model, options);
  if (kind == RigKind::camera) return std::make_unique<CameraRig>(model, options);
  return std::make_unique<StereoRig>(model, options);
}

}  // namespace kincal::session
