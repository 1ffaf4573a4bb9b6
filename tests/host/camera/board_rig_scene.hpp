// The board rig the issue #26 tests and benchmark share: a UR5 (host/model/robots/ur5.yaml)
// with the test camera (camera_scenes.hpp) and the 9 x 6 chessboard of 30 mm squares (a 0.3 m
// board), at a home where the camera sees the board's centre head-on from 0.6 m
// (sim::board_rig), and the rendering conditions of its views.
#pragma once

#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "host/camera/board.hpp"
#include "host/sim/board_views.hpp"
#include "host/sim/render.hpp"

namespace kincal::camera::scenes {

sim::BoardRig board_rig(const Board& board, sim::BoardMount mount);
// The board's centre and the corners of its printed area (the white border included), board frame.
Eigen::Vector3d board_centre(const Board& board);
std::vector<Eigen::Vector3d> board_outline(const Board& board);
// 2x supersampling, the renderer's default noise; `seed` varies the noise.
sim::ImagingConditions board_rig_conditions(std::uint64_t seed);

}  // namespace kincal::camera::scenes
