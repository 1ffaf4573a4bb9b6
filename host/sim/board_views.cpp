#include "host/sim/board_views.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "host/model/isometry.hpp"

namespace kincal::sim {

namespace {

using model::isometry;
using model::transform;

Eigen::Isometry3d pose(const Eigen::Matrix3d& rotation, const Eigen::Vector3d& translation) {
  Eigen::Isometry3d i = Eigen::Isometry3d::Identity();
  i.linear() = rotation;
  i.translation() = translation;
  return i;
}

}  // namespace

BoardRig board_rig(const model::RobotModel& arm, BoardMount mount, std::span<const double> home, double distance_m,
                   const Eigen::Vector3d& board_centre_m) {
  if (static_cast<int>(home.size()) != arm.joint_count())
    throw std::invalid_argument("board_rig: home has " + std::to_string(home.size()) + " readings, the arm " +
                                std::to_string(arm.joint_count()) + " joints");
  if (!(distance_m > 0)) throw std::invalid_argument("board_rig: distance_m must be positive");
  for (std::size_t j = 0; j < home.size(); ++j)
    if (!(home[j] >= arm.joints[j].lower && home[j] <= arm.joints[j].upper))
      throw std::invalid_argument("board_rig: home reading q" + std::to_string(j + 1) + " outside the joint's limits");
  // At home the camera looks at the board's centre head-on: camera_T_board's rotation the identity.
  const Eigen::Isometry3d camera_T_board0 =
      pose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0, distance_m) - board_centre_m);
  const Eigen::Isometry3d base_T_flange = isometry(model::forward_kinematics(arm, home)) *
                                          isometry(arm.flange_T_tool).inverse();  // the arm's own tool removed
  BoardRig rig;
  rig.mount = mount;
  rig.home.assign(home.begin(), home.end());
  rig.nominal = arm;
  rig.nominal.tool = model::ToolKind::frame;
  Eigen::Isometry3d mount_pose, device_T_base;
  if (mount == BoardMount::hand) {
    mount_pose = pose(Eigen::Matrix3d::Identity(), Eigen::Vector3d(0, 0.06, 0.04));  // flange_T_camera
    const Eigen::Isometry3d base_T_board = base_T_flange * mount_pose * camera_T_board0;
    device_T_base = base_T_board.inverse();
  } else {
    // flange_T_board: the board's face away from the flange (its z into the flange), its centre on the axis.
    const Eigen::Matrix3d turned = Eigen::AngleAxisd(std::numbers::pi, Eigen::Vector3d::UnitX()).toRotationMatrix();
    mount_pose = pose(turned, Eigen::Vector3d(0, 0, 0.02) - turned * board_centre_m);
    const Eigen::Isometry3d base_T_camera = base_T_flange * mount_pose * camera_T_board0.inverse();
    device_T_base = base_T_camera.inverse();
  }
  rig.nominal.flange_T_tool = transform(mount_pose);
  rig.nominal.base_T_frame0 = transform(device_T_base) * arm.base_T_frame0;
  return rig;
}

Eigen::Isometry3d camera_T_board(BoardMount mount, const model::Transform& device_T_tool) {
  return mount == BoardMount::hand ? isometry(device_T_tool).inverse() : isometry(device_T_tool);
}

std::vector<std::vector<double>> board_view_plan(const BoardRig& rig, const CameraSpec& camera,
                                                 const std::vector<Eigen::Vector3d>& outline_m, int count,
                                                 std::mt19937_64& rng, const ViewPlanOptions& options) {
  if (outline_m.empty()) throw std::invalid_argument("board_view_plan: the board's outline is empty");
  if (!(options.spread_rad > 0)) throw std::invalid_argument("board_view_plan: spread_rad must be positive");
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  for (const Eigen::Vector3d& p : outline_m) centre += p;
  centre /= static_cast<double>(outline_m.size());
  std::vector<std::vector<double>> plan;
  const int draws = 200 * count;
  for (int draw = 0; draw < draws && static_cast<int>(plan.size()) < count; ++draw) {
    std::vector<double> q = rig.home;
    for (std::size_t j = 0; j < q.size(); ++j) {
      const model::Joint& joint = rig.nominal.joints[j];
      std::uniform_real_distribution<double> step(std::max(joint.lower, q[j] - options.spread_rad),
                                                  std::min(joint.upper, q[j] + options.spread_rad));
      q[j] = step(rng);
    }
    const Eigen::Isometry3d view = camera_T_board(rig.mount, model::forward_kinematics(rig.nominal, q));
    const Eigen::Vector3d seen = view * centre;
    const double distance = seen.norm();
    if (distance < 0.3 || distance > 1.2 || seen.z() <= 0) continue;
    const double tilt = std::acos(std::min(1.0, std::abs(view.linear().col(2).dot(seen / distance))));
    if (tilt > options.max_tilt_rad) continue;
    bool inside = true;
    for (const Eigen::Vector3d& p : outline_m) inside = inside && (view * p).z() > 0;
    if (!inside) continue;
    for (const cv::Point2d& px : project_points(camera, view, outline_m))
      inside = inside && px.x >= options.margin_px && px.y >= options.margin_px &&
               px.x <= camera.width_px - 1 - options.margin_px && px.y <= camera.height_px - 1 - options.margin_px;
    if (inside) plan.push_back(q);
  }
  if (static_cast<int>(plan.size()) < count)
    throw std::invalid_argument("board_view_plan: " + std::to_string(plan.size()) + " views found of " +
                                std::to_string(count) + " in " + std::to_string(draws) +
                                " draws (the home does not see the board, or the spread is too wide)");
  return plan;
}

cv::Mat render_board_view(const SimulatedRobot& robot, BoardMount mount, std::span<const double> q,
                          const CameraSpec& camera, const PlanarTarget& board, const ImagingConditions& conditions) {
  return render_plane(camera, camera_T_board(mount, robot.tool_pose(q)), board, conditions);
}

}  // namespace kincal::sim
