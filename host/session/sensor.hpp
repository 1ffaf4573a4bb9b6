// What a calibration session measures with (issue #6): the tool's position (and orientation) in
// the measuring device's frame, one observation per pose, or a SessionError that stops the
// session at once (fail fast: a missing sensor, a blob-less frame or a non-flat surface at the
// first pose, not a wasted run).
//
//   PlatformPoseSensor   Doty's ARID platform over CAN: the platform's camera and four rangers
//                        measure square_T_camera on board; the strip layout places the square
//                        in the strip (device) frame: strip_T_camera = strip_T_square[k] *
//                        square_T_camera. Which square k the platform measured against is the
//                        one that puts the camera nearest the nominal prediction (squares are 4
//                        inches apart, far more than any kinematic error), so the platform may
//                        pick any square in view (protocol 3.0: its pose may rest on that
//                        reference square's neighbours too; the report says how many squares,
//                        the observation's note shows it). The observation is a full pose, with
//                        the position's covariance from the report's (protocol 2.0: the platform's
//                        fused pose covariance; its translation block turned into the strip
//                        frame), so identification weights each row by it, and the full 6x6
//                        pose covariance (issue #26: position and rotation, in the dataset's
//                        convention and the strip frame), which the journal and the dataset
//                        carry.
//   StereoBeaconSensor   Kapucu & Baysec's rig: stereo_sensor.hpp.
//   BoardPoseSensor      a camera and a printed board: board_sensor.hpp.
//
// Thread safety: one session thread. Cost: one CAN round trip.
#pragma once

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Geometry>

#include "host/can/platform_client.hpp"
#include "host/model/dataset.hpp"
#include "host/model/robot_model.hpp"
#include "host/session/session_error.hpp"

namespace kincal::session {

struct Observation {
  model::Vector3 position = model::Vector3::Zero();  // device frame, m
  std::optional<Eigen::Quaterniond> orientation;     // device_R_tool
  std::optional<model::Matrix3> covariance;          // of position, m^2
  // Of (x, y, z, rx, ry, rz): the position error (m) and the rotation error (rad, a rotation
  // vector on the left, in the device frame), as the dataset's 6x6 columns (dataset.hpp); its
  // position block is `covariance`.
  std::optional<model::Matrix6> pose_covariance;
  std::uint32_t sequence = 0;  // the platform's trigger sequence, if any
  double timestamp_s = 0;      // when the sensor saw it (sensor clock)
  std::string note;            // e.g. "square 3 (pose over 2 squares), 6 fiducials"
};

class Sensor {
 public:
  virtual ~Sensor() = default;
  // One observation at pose `index`; `predicted` is the nominal model's device_T_tool there.
  virtual Observation measure(int index, const model::Transform& predicted) = 0;
  virtual std::string name() const = 0;
  // What every observation carries (the journal's layout is fixed when it is created).
  virtual bool gives_orientation() const = 0;
  virtual bool gives_covariance() const = 0;
  // Every observation carries pose_covariance (a sensor that measures the full pose's 6x6).
  virtual bool gives_pose_covariance() const { return false; }
};

class PlatformPoseSensor : public Sensor {
 public:
  // strip_T_square: every calibration square's pose in the strip frame. Puts the platform in
  // measuring mode (and clears its error flags); throws SessionError if it does not answer.
  PlatformPoseSensor(can::PlatformClient& client, std::vector<model::Transform> strip_T_square);
  Observation measure(int index, const model::Transform& predicted) override;
  std::string name() const override { return "sensor platform over CAN"; }
  bool gives_orientation() const override { return true; }
  bool gives_covariance() const override { return true; }
  bool gives_pose_covariance() const override { return true; }

  // The square k for which strip_T_square[k] * square_T_camera is nearest `predicted`.
  int measured_square(const model::Transform& square_T_camera, const model::Transform& predicted) const;

 private:
  can::PlatformClient& client_;
  std::vector<model::Transform> strip_T_square_;
};

}  // namespace kincal::session
