// The shared real UR10 laser-tracker export (../shared/realdata/ur10-laser-tracker, see its
// README) read through kincal import's reader, as a user would name its columns; and a fixed split
// of its rows into training candidates and a held-out set, for the tests and the benchmark.
#pragma once

#include <algorithm>
#include <random>
#include <string>
#include <vector>

#include "host/model/measurement_import.hpp"

namespace kincal::realdata {

inline model::ImportOptions ur10_import_options() {
  model::ImportOptions o;
  o.joints = {"shoulder_pan_joint", "shoulder_lift_joint", "elbow_joint",
              "wrist_1_joint",      "wrist_2_joint",       "wrist_3_joint"};
  o.joint_units = {model::JointUnit::rad};
  o.position = {"measurement_x", "measurement_y", "measurement_z"};
  o.position_unit = model::LengthUnit::mm;
  o.position_std = {"measurement_std_x", "measurement_std_y", "measurement_std_z"};
  o.angles = {"measurement_rx", "measurement_ry", "measurement_rz"};
  o.convention = model::parse_euler_convention("intrinsic-xyz");
  o.angle_unit = model::AngleUnit::deg;
  o.angle_std = {"measurement_std_rx", "measurement_std_ry", "measurement_std_rz"};
  return o;
}

// realdata_dir: the folder holding ur10-laser-tracker/.
inline model::ImportResult import_ur10(const std::string& realdata_dir) {
  return model::import_measurements_file(realdata_dir + "/ur10-laser-tracker/measurements_joint_configurations.csv",
                                         ur10_import_options());
}

// The rows in a fixed pseudo-random order (seed 2021): the last `held_out` are the held-out set,
// the first n of the rest a training set of n rows.
struct Split {
  std::vector<int> train_order;
  std::vector<int> held_out;
};

inline Split split_rows(int rows, int held_out) {
  std::vector<int> order(static_cast<std::size_t>(rows));
  for (int i = 0; i < rows; ++i) order[static_cast<std::size_t>(i)] = i;
  std::mt19937_64 rng(2021);
  std::shuffle(order.begin(), order.end(), rng);
  Split s;
  s.train_order.assign(order.begin(), order.end() - held_out);
  s.held_out.assign(order.end() - held_out, order.end());
  return s;
}

// The dataset of the given rows.
inline model::Dataset subset(const model::Dataset& d, const std::vector<int>& rows) {
  model::Dataset out = d;
  out.rows.clear();
  for (int r : rows) out.rows.push_back(d.rows[static_cast<std::size_t>(r)]);
  return out;
}

}  // namespace kincal::realdata
