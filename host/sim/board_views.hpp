// A camera and a printed board on a simulated arm (issue #26): the rig's nominal geometry, joint
// readings at which the camera sees the whole board, and the views the true arm gives there.
//
// Mounts and frames (what `kincal board-poses` measures):
//   hand   the camera on the flange (flange_T_camera), the board fixed in the cell. The device
//          frame is the board's: device_T_tool = board_T_camera.
//   world  the board on the flange (flange_T_board, its face turned away from the flange), the
//          camera fixed in the cell. The device frame is the camera's: device_T_tool =
//          camera_T_board.
// board_rig() builds the rig's nominal model from an arm's: its base becomes device_T_base (the
// fixed part placed so that at `home` the camera looks at the board's centre head-on from
// distance_m, the board's z pointing away from the camera as OpenCV's object points do) and its
// tool (a frame) the carried part's mount: hand, the camera 60 mm off the flange axis and 40 mm
// out, looking along the flange's z; world, the board's centre on the flange axis 20 mm out.
// A SimulatedRobot on that nominal (robot.hpp) draws the hidden truth of all of it: the arm's
// geometry, the fixed part's place (the base) and the mount (the tool).
//
// Views: board_view_plan() draws readings uniformly within spread_rad of home (and within the
// joint limits) and keeps those at which the nominal rig sees every point of `outline_m` (board
// frame: the board's outer corners) at least margin_px inside the image, from 0.3 m to 1.2 m,
// the board's normal at most max_tilt_rad from the line of sight (the true arm differs by
// millimetres: the margin keeps its views whole). render_board_view() renders the true arm's view
// at q (render.hpp). camera_T_board() turns a device_T_tool of either mount into the camera's
// view of the board.
// Errors: std::invalid_argument naming what is wrong: a home of the wrong length or outside the
// limits, a distance or spread that is not positive, an empty outline, a plan that finds fewer
// than `count` views in 200 draws per view (the home does not see the board, or the spread is
// too wide).
// Cost: one forward kinematics and a few projections per draw; one render_plane per view.
#pragma once

#include <random>
#include <span>
#include <vector>

#include <Eigen/Geometry>
#include <opencv2/core.hpp>

#include "host/model/robot_model.hpp"
#include "host/sim/render.hpp"
#include "host/sim/robot.hpp"

namespace kincal::sim {

enum class BoardMount { hand, world };

struct BoardRig {
  BoardMount mount = BoardMount::hand;
  model::RobotModel nominal;  // base = device_T_base, tool = the carried part's mount (a frame)
  std::vector<double> home;
};

// outline_centre_m: the board's centre in its frame (the point the camera looks at at home).
BoardRig board_rig(const model::RobotModel& arm, BoardMount mount, std::span<const double> home, double distance_m,
                   const Eigen::Vector3d& board_centre_m);

Eigen::Isometry3d camera_T_board(BoardMount mount, const model::Transform& device_T_tool);

struct ViewPlanOptions {
  double spread_rad = 0.35;
  double margin_px = 30;
  double max_tilt_rad = 50 * 3.14159265358979323846 / 180;
};

std::vector<std::vector<double>> board_view_plan(const BoardRig& rig, const CameraSpec& camera,
                                                 const std::vector<Eigen::Vector3d>& outline_m, int count,
                                                 std::mt19937_64& rng, const ViewPlanOptions& options = {});

cv::Mat render_board_view(const SimulatedRobot& robot, BoardMount mount, std::span<const double> q,
                          const CameraSpec& camera, const PlanarTarget& board, const ImagingConditions& conditions);

}  // namespace kincal::sim
