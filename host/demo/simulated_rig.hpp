// Simulated rigs for sessions and the demo (issue #6): a robot with hidden true errors, the world
// the simulator renders around it (host/sim) and the sensor that watches it, ready for
// run_session() with nothing real attached.
//
//   platform  Doty's ARID set-up: the sensor platform (camera + four rangers in a +) on the tool,
//             looking along the joint axes at the calibration strip 0.3 m away. The real
//             firmware (firmware/app) runs in-process (sim::SimulatedPlatform) on a loopback bus
//             and sees the rendered frame and the simulated ranges of the pose the robot stands
//             at; the host talks to it through PlatformClient as it would over SocketCAN,
//             uploads the camera intrinsics and the platform geometry first, and measures
//             square_T_camera through the protocol. The nominal model is the file's chain and
//             tool, placed in the strip's frame so the camera looks at the strip.
//   stereo    Kapucu & Baysec's rig: a beacon on the tool, a fixed parallel stereo pair (f = 1 cm,
//             11 x 13 um cells, 640 x 480, baseline 12.6 cm) 4.54 m away; the frames go through
//             the firmware core's labeler and triangulation on the host. The device frame is the
//             right camera's; the nominal model is the file's (host/model/robots/stanford_rrp.yaml).
//   camera    a camera and a printed board (issue #26): a VGA camera (640 x 480, f = 600 px, barrel
//             distortion) on the flange seeing a board fixed in the cell (camera_on_hand), or fixed
//             and seeing the board the flange carries; the board a chessboard (default 9 x 6 inner
//             corners of 30 mm squares, a 0.3 m sheet). sim::board_rig places the fixed part so
//             that at `home` the camera sees the board's centre head-on from 0.6 m; the nominal
//             model is the file's arm with that registration as its base and the mount as its tool
//             (sim/board_views.hpp: the device frame is the board's for hand, the camera's for
//             world). The views are rendered (sim::render_board_view) and measured by
//             BoardPoseSensor (host/session/board_sensor.hpp) with the camera's true intrinsics;
//             random poses are drawn near home (sim::board_view_plan: the whole board in view).
//             Its truth has geometric errors only (no sag or repeatability): what is left after
//             the calibration is the camera's.
//
// The truth: the nominal model with every parameter off by a Gaussian error (1 mm, 0.1 deg; base
// 5 mm, 0.5 deg), drawn from the seed. The robot goes exactly where it is told (its readings are
// its targets); everything a sensor sees is rendered for the pose index from the seed, so a
// session killed and resumed measures each pose exactly as an uninterrupted one would.
//
// Errors: model::InputError (a model the rig cannot use: e.g. a platform rig whose camera would
// not face a plane, a camera rig's home outside the joint limits or a board that is not a
// chessboard), SessionError (the platform refusing its parameters).
#pragma once

#include <cstdint>
#include <memory>
#include <random>
#include <string>
#include <vector>

#include "host/can/platform_client.hpp"
#include "host/model/robot_model.hpp"
#include "host/session/robot_driver.hpp"
#include "host/session/sensor.hpp"

namespace kincal::session {

enum class RigKind { platform, stereo, camera };

struct RigOptions {
  std::uint64_t seed = 1;
  bool fd = false;               // platform rig: CAN FD on the loopback bus
  std::string candump_log;       // platform rig: log every frame of the bus here (candump -L)
  double measurement_scale = 1;  // multiplies the simulated image and range noise
  // Camera rig: the printed board (camera::parse_board's text), the mount, and the home at which
  // the camera sees the board's centre head-on (empty: the middle of each joint's limits).
  std::string board = "chessboard:9x6:0.03";
  bool camera_on_hand = true;
  std::vector<double> home;
};

class SimulatedRig {
 public:
  virtual ~SimulatedRig() = default;
  virtual const model::RobotModel& nominal() const = 0;  // the controller's model
  virtual const model::RobotModel& truth() const = 0;
  virtual RobotDriver& driver() = 0;
  virtual Sensor& sensor() = 0;
  // The platform, for uploading the correction (platform rig); nullptr for the stereo rig.
  virtual can::PlatformClient* platform() = 0;
  virtual bool fd() const = 0;
  // Whether the sensor sees its target at joint readings q, by the nominal model with a margin
  // for the errors: plans keep to such poses.
  virtual bool observable(const std::vector<double>& q) const = 0;
  // `count` random joint readings the sensor can measure at: within the joint limits and
  // observable() (platform, stereo), or near the camera rig's home. Throws model::InputError
  // when bounded draws do not find them (the rig cannot see the robot's workspace).
  virtual std::vector<std::vector<double>> random_poses(int count, std::mt19937_64& rng) const = 0;
  virtual std::string description() const = 0;
};

// The poses of a strip's squares (sim::strip_T_square: 4-inch squares in a row, the layout real
// strips are printed from), as PlatformPoseSensor takes them.
std::vector<model::Transform> strip_square_poses(int squares);

std::unique_ptr<SimulatedRig> make_simulated_rig(RigKind kind, const model::RobotModel& model,
                                                 const RigOptions& options);

}  // namespace kincal::session
