// The simulated board rig (issue #26, host/sim/board_views.hpp): the nominal rig's geometry at
// home, the plan's views whole in the image, and the true arm's rendered views measured by
// board_pose within their covariance, for both mounts.
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "host/camera/board_pose.hpp"
#include "host/sim/board_views.hpp"
#include "host/sim/robot.hpp"
#include "tests/host/camera/board_rig_scene.hpp"
#include "tests/host/camera/camera_scenes.hpp"

using namespace kincal;
using namespace kincal::camera;

TEST_CASE(
    "board rig: at home the camera sees the board's centre head-on from 0.6 m; rendered views within the covariance") {
  const Board board = parse_board(scenes::chessboard_text());
  const sim::CameraSpec spec = scenes::test_camera();
  const CameraModel camera = scenes::model_of(spec);
  const sim::PlanarTarget target = scenes::target_of(board);
  for (const sim::BoardMount mount : {sim::BoardMount::hand, sim::BoardMount::world}) {
    INFO((mount == sim::BoardMount::hand ? "hand" : "world"));
    const sim::BoardRig rig = scenes::board_rig(board, mount);
    const Eigen::Isometry3d home = sim::camera_T_board(mount, model::forward_kinematics(rig.nominal, rig.home));
    CHECK((home * scenes::board_centre(board) - Eigen::Vector3d(0, 0, 0.6)).norm() < 1e-9);
    CHECK(home.linear().isApprox(Eigen::Matrix3d::Identity(), 1e-9));

    std::mt19937_64 rng(7);
    const std::vector<std::vector<double>> plan = sim::board_view_plan(rig, spec, scenes::board_outline(board), 3, rng);
    REQUIRE(plan.size() == 3);
    const sim::SimulatedRobot robot(rig.nominal, 11);
    for (std::size_t i = 0; i < plan.size(); ++i) {
      const Eigen::Isometry3d truth = sim::camera_T_board(mount, robot.tool_pose(plan[i]));
      const BoardDetection d = detect_board(
          board, sim::render_board_view(robot, mount, plan[i], spec, target, scenes::board_rig_conditions(i + 1)),
          "view " + std::to_string(i));
      const BoardPose p = board_pose(d, camera, std::nullopt);
      INFO(p.view, " ", p.refusal);
      REQUIRE(p.refusal.empty());
      Eigen::Matrix<double, 6, 1> e;
      e.head<3>() = p.camera_T_board.translation() - truth.translation();
      const Eigen::AngleAxisd r(p.camera_T_board.linear() * truth.linear().transpose());
      e.tail<3>() = r.angle() * r.axis();
      CHECK(e.dot(p.covariance.ldlt().solve(e)) < 22.46);  // chi-square, 6 dof, 99.9 %
    }
  }
}

TEST_CASE("board rig: a home that does not see the board finds no plan, named") {
  const Board board = parse_board(scenes::chessboard_text());
  sim::BoardRig rig = scenes::board_rig(board, sim::BoardMount::hand);
  rig.home[1] += 1.5;  // the shoulder turned away
  std::mt19937_64 rng(1);
  sim::ViewPlanOptions narrow;
  narrow.spread_rad = 0.01;
  CHECK_THROWS_WITH_AS(sim::board_view_plan(rig, scenes::test_camera(), scenes::board_outline(board), 2, rng, narrow),
                       "board_view_plan: 0 views found of 2 in 400 draws (the home does not see the board, or the "
                       "spread is too wide)",
                       std::invalid_argument);
}
