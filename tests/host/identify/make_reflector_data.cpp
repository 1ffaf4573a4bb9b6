// Files for the command tests of issue #42 (tests/host/identify/CMakeLists.txt): the 7-joint
// arm's URDF, 150 tracker rows to calibrate with, 100 held out, and 20 joint targets (the held-out
// rows' readings). make_reflector_data OUTPUT_DIR
#include <filesystem>
#include <fstream>
#include <iostream>

#include "reflector_arm.hpp"

int main(int argc, char** argv) {
  using namespace kincal;
  if (argc != 2) {
    std::cerr << "usage: make_reflector_data OUTPUT_DIR\n";
    return 2;
  }
  const std::string out = argv[1];
  std::error_code error;
  std::filesystem::create_directories(out, error);
  const model::RobotModel truth = test::reflector_arm_truth(7);
  const model::Dataset held_out = test::reflector_rows(truth, 100, 12, "held_out.csv");
  std::ofstream urdf(out + "/arm7.urdf"), train(out + "/train.csv"), held(out + "/held_out.csv"),
      targets(out + "/targets.csv");
  urdf << test::reflector_arm_urdf();
  model::write_dataset(train, test::reflector_rows(truth, 150, 11, "train.csv"));
  model::write_dataset(held, held_out);
  targets << "q1,q2,q3,q4,q5,q6,q7\n";
  for (std::size_t r = 0; r < 20; ++r)
    for (std::size_t j = 0; j < 7; ++j) targets << held_out.rows[r].q[j] << (j + 1 < 7 ? ',' : '\n');
  if (!urdf || !train || !held || !targets) {
    std::cerr << "make_reflector_data: cannot write into " << out << '\n';
    return 1;
  }
  return 0;
}
