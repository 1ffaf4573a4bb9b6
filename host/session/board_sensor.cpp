#include "host/session/board_sensor.hpp"

#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <utility>

namespace kincal::session {

BoardPoseSensor::BoardPoseSensor(std::function<BoardFrame(int)> grab, BoardSetup setup)
    : grab_(std::move(grab)), setup_(std::move(setup)) {}

std::string BoardPoseSensor::name() const {
  return std::string("camera and printed board (") + (setup_.camera_on_hand ? "eye-in-hand" : "eye-to-hand") + ")";
}

Observation BoardPoseSensor::measure(int index, const model::Transform&) {
  const BoardFrame frame = grab_(index);
  const std::string where =
      "pose " + std::to_string(index) + (frame.origin.empty() ? "" : " (" + frame.origin + ")") + ": ";
  if (frame.image.empty()) throw SessionError(where + "no frame");
  if (frame.image.depth() != CV_8U || (frame.image.channels() != 1 && frame.image.channels() != 3))
    throw SessionError(where + "not an 8-bit grey or colour frame");
  camera::BoardPose pose;
  try {
    const camera::BoardDetection detection =
        camera::detect_board(setup_.board, frame.image, frame.origin, setup_.options.min_corners);
    pose = camera::board_pose(detection, setup_.camera, setup_.intrinsics, setup_.options);
  } catch (const std::exception& e) {  // a frame of another size, or one the detector cannot take
    throw SessionError(where + e.what());
  }
  if (!pose.refusal.empty()) throw SessionError(where + "the board's view is refused: " + pose.refusal);

  const camera::PoseMeasurement m = camera::pose_measurement(pose, setup_.camera_on_hand);
  Observation o;
  o.position = m.device_T_tool.translation();
  o.orientation = Eigen::Quaterniond(m.device_T_tool.linear()).normalized();
  const model::Matrix6 covariance = (m.covariance + m.covariance.transpose()) / 2;  // exactly symmetric
  o.pose_covariance = covariance;
  o.covariance = model::Matrix3(covariance.topLeftCorner<3, 3>());
  o.timestamp_s = frame.timestamp_s;
  char note[128];
  std::snprintf(note, sizeof note, "%d corners, RMS %.3f px, position sigma %.3f mm", pose.corners, pose.rms_px,
                std::sqrt(covariance.topLeftCorner<3, 3>().trace()) * 1e3);
  o.note = note;
  return o;
}

}  // namespace kincal::session
