// A camera and a printed board (issue #26): the peers' everyday rig. One camera sees one board;
// one of them rides on the robot's flange, the other stands fixed in the cell:
//   hand   (eye-in-hand) the camera on the flange, the board fixed: the device frame is the
//          board's, the observation board_T_camera (the tool is the camera);
//   world  (eye-to-hand) the camera fixed, the board on the flange: the device frame is the
//          camera's OpenCV frame (x right, y down, z forward), the observation camera_T_board.
// One code path for real cameras (frames from host/capture, the camera file from `kincal camera
// calibrate`) and for the simulator (host/demo renders the views of its hidden-truth arm).
//
// Per pose: grab(pose) gives the frame; camera::detect_board finds the board's corners (refined,
// the whole board or nothing), camera::board_pose solves camera_T_board through the camera's full
// lens model and gives its 6x6 covariance (from the view's own residuals, plus the intrinsics'
// share when the camera file has their covariance), and camera::pose_measurement turns it into
// the mount's device_T_tool. The observation is the full pose: position, orientation
// (device_R_tool), the position's covariance and the full 6x6 pose covariance of (x, y, z, rx, ry,
// rz) in the device frame, the rotation error a rotation vector on the left (the dataset's
// convention, host/model/dataset.hpp), which the journal and the dataset carry.
//
// A pose fails (SessionError naming the pose and the frame's origin, e.g. the image file) when
// the frame is missing or not an 8-bit image, or camera::board_pose refuses the view: the board
// not found (missing, half out of view, another board), too few corners, a reprojection outlier,
// the board nearly edge-on, a frame of another size than the camera file's (see board_pose.hpp
// for the thresholds, BoardSetup::options).
//
// Thread safety: one session thread. Cost: one board detection (tens of ms for VGA) and one pose
// solve (under a millisecond) per pose.
#pragma once

#include <functional>
#include <optional>
#include <string>

#include <opencv2/core.hpp>

#include "host/camera/board.hpp"
#include "host/camera/board_pose.hpp"
#include "host/camera/intrinsics.hpp"
#include "host/camera/uncertainty.hpp"
#include "host/session/sensor.hpp"

namespace kincal::session {

struct BoardFrame {
  cv::Mat image;  // 8-bit grey or BGR
  double timestamp_s = 0;
  std::string origin;  // where the frame came from (file, "camera 0 frame 12")
};

struct BoardSetup {
  camera::Board board;
  camera::CameraModel camera;                              // intrinsics, distortion, image size
  std::optional<camera::IntrinsicsCovariance> intrinsics;  // none: the residuals' share only
  bool camera_on_hand = true;                              // hand; false: world
  camera::BoardPoseOptions options;                        // the refusals' thresholds
};

class BoardPoseSensor : public Sensor {
 public:
  // grab(pose) returns the frame of that pose (the session asks for each pose once, in plan
  // order; a resumed session starts later).
  BoardPoseSensor(std::function<BoardFrame(int pose)> grab, BoardSetup setup);
  Observation measure(int index, const model::Transform& predicted) override;
  std::string name() const override;
  bool gives_orientation() const override { return true; }
  bool gives_covariance() const override { return true; }
  bool gives_pose_covariance() const override { return true; }

 private:
  std::function<BoardFrame(int)> grab_;
  BoardSetup setup_;
};

}  // namespace kincal::session
