// Writes a recorded board-rig session of the simulated arm (host/sim/board_views.hpp) into DIR,
// for the `kincal board-poses` -> `kincal identify` tests (issue #26):
//   nominal.yaml      the rig's nominal model (UR5, base = device registration, tool = the mount)
//   camera.yaml       the test camera (ROS camera_info, the true intrinsics, no covariance)
//   views/view_NN.png the true arm's views at the training readings;  joints.csv  their readings
//   held_out.csv      the true device_T_tool at held-out readings (q, x, y, z, qw..qz)
//   robot_poses.csv   base_T_flange at the training readings as the controller reports them (the
//                     nominal kinematics): x,y,z,qw,qx,qy,qz, for `kincal camera hand-eye`
//   true_hand_eye.yaml the true arm's tool and device registration as `identify --hand-eye` writes
//   hostile/          three views, the board missing (a blank view) and the board half out of
//                     view; hostile_joints.csv their readings
// Usage: make_board_rig_views DIR hand|world [TRAINING HELD_OUT SEED]
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <random>
#include <sstream>
#include <string>

#include <opencv2/imgcodecs.hpp>

#include "host/camera/calibration_file.hpp"
#include "host/model/dataset.hpp"
#include "host/model/isometry.hpp"
#include "host/model/model_file.hpp"
#include "host/model/number_text.hpp"
#include "host/sim/board_views.hpp"
#include "host/sim/robot.hpp"
#include "tests/host/camera/board_rig_scene.hpp"
#include "tests/host/camera/camera_scenes.hpp"

namespace fs = std::filesystem;
using namespace kincal;
namespace scenes = kincal::camera::scenes;

namespace {

std::string numbered(const std::string& stem, std::size_t i) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "_%02zu.png", i);
  return stem + buf;
}

void write_joints(const std::string& path, const std::vector<std::vector<double>>& rows) {
  std::ofstream out(path);
  for (std::size_t j = 1; j <= rows.at(0).size(); ++j) out << (j > 1 ? "," : "") << 'q' << j;
  out << '\n';
  for (const std::vector<double>& q : rows) {
    for (std::size_t j = 0; j < q.size(); ++j) out << (j > 0 ? "," : "") << model::shortest_number_text(q[j]);
    out << '\n';
  }
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3 && argc != 6) {
    std::cerr << "usage: make_board_rig_views DIR hand|world [TRAINING HELD_OUT SEED]\n";
    return 2;
  }
  const fs::path dir = argv[1];
  const sim::BoardMount mount = std::string(argv[2]) == "world" ? sim::BoardMount::world : sim::BoardMount::hand;
  const int training = argc == 6 ? std::stoi(argv[3]) : 24;
  const int held_out = argc == 6 ? std::stoi(argv[4]) : 8;
  const std::uint64_t seed = argc == 6 ? std::stoull(argv[5]) : 26;
  fs::create_directories(dir / "views");
  fs::create_directories(dir / "hostile");

  const camera::Board board = camera::parse_board(scenes::chessboard_text());
  const sim::CameraSpec spec = scenes::test_camera();
  const sim::BoardRig rig = scenes::board_rig(board, mount);
  std::mt19937_64 rng(seed);
  const std::vector<std::vector<double>> plan =
      sim::board_view_plan(rig, spec, scenes::board_outline(board), training + held_out, rng);
  const sim::SimulatedRobot robot(rig.nominal, seed);
  const sim::PlanarTarget target = scenes::target_of(board);

  model::save_model(rig.nominal, (dir / "nominal.yaml").string());
  camera::save_camera_ros((dir / "camera.yaml").string(), scenes::model_of(spec), "board_rig_camera");
  const std::vector<std::vector<double>> train(plan.begin(), plan.begin() + training);
  for (std::size_t i = 0; i < train.size(); ++i)
    cv::imwrite((dir / "views" / numbered("view", i)).string(),
                sim::render_board_view(robot, mount, train[i], spec, target, scenes::board_rig_conditions(i + 1)));
  write_joints((dir / "joints.csv").string(), train);
  {
    std::ofstream poses(dir / "robot_poses.csv");
    poses << "x,y,z,qw,qx,qy,qz\n";
    const Eigen::Isometry3d frame0_T_device = model::isometry(rig.nominal.base_T_frame0).inverse();
    const Eigen::Isometry3d tool_T_flange = model::isometry(rig.nominal.flange_T_tool).inverse();
    for (const std::vector<double>& q : train) {
      const Eigen::Isometry3d base_T_flange =
          frame0_T_device * model::isometry(model::forward_kinematics(rig.nominal, q)) * tool_T_flange;
      const Eigen::Quaterniond r(base_T_flange.linear());
      const Eigen::Vector3d t = base_T_flange.translation();
      const double row[] = {t.x(), t.y(), t.z(), r.w(), r.x(), r.y(), r.z()};
      for (std::size_t k = 0; k < 7; ++k) poses << (k > 0 ? "," : "") << model::shortest_number_text(row[k]);
      poses << '\n';
    }
  }
  std::ofstream(dir / "true_hand_eye.yaml")
      << camera::rig_hand_eye_text(mount == sim::BoardMount::hand, model::isometry(robot.truth().flange_T_tool),
                                   model::isometry(robot.truth().base_T_frame0).inverse());

  model::Dataset truth;
  truth.joint_count = rig.nominal.joint_count();
  truth.has_orientation = true;
  for (std::size_t i = static_cast<std::size_t>(training); i < plan.size(); ++i) {
    const model::Transform t = robot.tool_pose(plan[i]);
    model::Measurement m;
    m.q = plan[i];
    m.position = t.translation;
    m.orientation = Eigen::Quaterniond(t.rotation).normalized();
    truth.rows.push_back(m);
  }
  std::ostringstream text;
  model::write_dataset(text, truth);
  std::ofstream(dir / "held_out.csv") << text.str();

  // Hostile: three good views, a view without the board, a view with the board half out of it.
  std::vector<std::vector<double>> hostile(train.begin(), train.begin() + 3);
  for (std::size_t i = 0; i < hostile.size(); ++i)
    fs::copy_file(dir / "views" / numbered("view", i), dir / "hostile" / numbered("view", i),
                  fs::copy_options::overwrite_existing);
  hostile.push_back(train[3]);
  cv::imwrite(
      (dir / "hostile" / numbered("view", 3)).string(),
      sim::render_plane(spec, Eigen::Isometry3d::Identity(), sim::PlanarTarget{[](double, double) { return 0.5; }},
                        scenes::board_rig_conditions(100)));
  hostile.push_back(train[4]);
  Eigen::Isometry3d half = sim::camera_T_board(mount, robot.tool_pose(train[4]));
  const Eigen::Vector3d centre = half * scenes::board_centre(board);
  half.pretranslate(Eigen::Vector3d(-centre.x() + centre.z() * (spec.width_px / 2.0) / spec.fx_px, 0, 0));
  cv::imwrite((dir / "hostile" / numbered("view", 4)).string(),
              sim::render_plane(spec, half, target, scenes::board_rig_conditions(101)));
  write_joints((dir / "hostile_joints.csv").string(), hostile);
  std::cout << "wrote " << training << " views, " << held_out << " held-out poses and 5 hostile views to "
            << dir.string() << "\n";
  return 0;
}
