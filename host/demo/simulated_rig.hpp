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
//
// The truth: the nominal model with every parameter off by a Gaussian error (1 mm, 0.1 deg; base
// 5 mm, 0.5 deg), drawn from the seed. The robot goes exactly where it is told (its readings are
// its targets); everything a sensor sees is rendered for the pose index from the seed, so a
// session killed and resumed measures each pose exactly as an uninterrupted one would.
//
// Errors: model::InputError (a model the rig cannot use: e.g. a platform rig whose camera would
// not face a plane), SessionError (the platform refusing its parameters).
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "host/can/platform_client.hpp"
#include "host/model/robot_model.hpp"
#include "host/session/robot_driver.hpp"
#include "host/session/sensor.hpp"

namespace kincal::session {

enum class RigKind { platform, stereo };

struct RigOptions {
  std::uint64_t seed = 1;
  bool fd = false;               // platform rig: CAN FD on the loopback bus
  std::string candump_log;       // platform rig: log every frame of the bus here (candump -L)
  double measurement_scale = 1;  // multiplies the simulated image and range noise
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
  virtual std::string description() const = 0;
};

// The poses of a strip's squares (sim::strip_T_square: 4-inch squares in a row, the layout real
// strips are printed from), as PlatformPoseSensor takes them.
std::vector<model::Transform> strip_square_poses(int squares);

std::unique_ptr<SimulatedRig> make_simulated_rig(RigKind kind, const model::RobotModel& model,
                                                 const RigOptions& options);

}  // namespace kincal::session
