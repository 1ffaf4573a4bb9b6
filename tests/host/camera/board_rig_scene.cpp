#include "tests/host/camera/board_rig_scene.hpp"

#include <string>

#include "host/model/model_file.hpp"

namespace kincal::camera::scenes {

sim::BoardRig board_rig(const Board& board, sim::BoardMount mount) {
  const model::RobotModel arm = model::load_model(std::string(KINCAL_ROBOTS_DIR) + "/ur5.yaml");
  const std::vector<double> home{0.3, -1.3, 1.5, -1.4, 1.2, 0.4};
  return sim::board_rig(arm, mount, home, 0.6, board_centre(board));
}

Eigen::Vector3d board_centre(const Board& board) {
  return Eigen::Vector3d(0.5 * (board.cols - 1) * board.square_m, 0.5 * (board.rows - 1) * board.square_m, 0);
}

std::vector<Eigen::Vector3d> board_outline(const Board& board) {
  // Inner corners span 0..(cols - 1) squares; the outer squares and the white border add two.
  const double s = board.square_m, x0 = -2 * s, y0 = -2 * s, x1 = (board.cols + 1) * s, y1 = (board.rows + 1) * s;
  return {{x0, y0, 0}, {x1, y0, 0}, {x1, y1, 0}, {x0, y1, 0}};
}

sim::ImagingConditions board_rig_conditions(std::uint64_t seed) {
  sim::ImagingConditions c;
  c.supersampling = 2;
  c.seed = seed;
  return c;
}

}  // namespace kincal::camera::scenes
