// A 7-joint arm's URDF measured by a laser tracker whose reflector is no link of it (issue #42):
// the case users meet first. Shared by the tests (measured_point_test.cpp) and the data maker of
// the command tests (make_reflector_data.cpp).
//
// The arm: an iiwa-like chain base_link -> link7 (axes z, y, z, y, z, y, z), then fixed joints
// beyond the last movable one -- link7 -> flange (126 mm out), flange -> hand (turned -45 deg about
// z, the case whose yaw a calibration once dropped), hand -> tcp (100 mm out) and hand -> finger
// (off the chain) -- with meshes, so that "byte for byte" has something to keep. The reflector sits
// 57 mm off the last axis and 85 mm along it from the flange (102 mm away): known to nobody.
// The true arm: every link parameter off by up to 0.5 mm and 0.1 deg (a cobot), registered in the
// tracker's frame 2 m away. Rows: random readings within 80 % of the limits, positions with
// 0.02 mm of tracker noise per axis.
#pragma once

#include <cstdint>
#include <random>
#include <string>
#include <vector>

#include "host/model/dataset.hpp"
#include "host/model/robot_model.hpp"
#include "host/model/urdf_chain.hpp"

namespace kincal::test {

inline std::string reflector_arm_urdf() {
  std::string joints;
  const char* axes[7] = {"0 0 1", "0 1 0", "0 0 1", "0 1 0", "0 0 1", "0 1 0", "0 0 1"};
  const char* origins[7] = {"0 0 0.34", "0 0 0", "0 0 0.2", "0 0 0.2", "0 0 0.2", "0 0 0.19", "0 0 0"};
  const char* limits[7] = {"2.9", "2.0", "2.9", "2.0", "2.9", "2.0", "3.0"};
  for (int i = 0; i < 7; ++i) {
    const std::string parent = i == 0 ? "base_link" : "link" + std::to_string(i);
    joints += "  <joint name=\"j" + std::to_string(i + 1) + "\" type=\"revolute\">\n    <parent link=\"" + parent +
              "\"/>\n    <child link=\"link" + std::to_string(i + 1) + "\"/>\n    <origin xyz=\"" + origins[i] +
              "\" rpy=\"0 0 0\"/>\n    <axis xyz=\"" + axes[i] + "\"/>\n    <limit lower=\"-" + limits[i] +
              "\" upper=\"" + limits[i] + "\" effort=\"100\" velocity=\"1\"/>\n  </joint>\n";
  }
  std::string links = "  <link name=\"base_link\"/>\n";
  for (int i = 1; i <= 7; ++i)
    links += "  <link name=\"link" + std::to_string(i) +
             "\">\n    <visual><geometry><mesh filename=\"package://arm7/meshes/link" + std::to_string(i) +
             ".stl\"/></geometry></visual>\n  </link>\n";
  return "<?xml version=\"1.0\"?>\n<!-- a 7-joint arm, its flange, a hand turned -45 deg and its TCP -->\n"
         "<robot name=\"arm7\">\n" +
         links +
         "  <link name=\"flange\"/>\n"
         "  <link name=\"hand\">\n    <visual><origin xyz=\"0 0 0.03\"/><geometry><mesh "
         "filename=\"package://arm7/meshes/hand.stl\"/></geometry></visual>\n  </link>\n"
         "  <link name=\"tcp\"/>\n  <link name=\"finger\"/>\n" +
         joints +
         "  <joint name=\"flange_joint\" type=\"fixed\">\n    <parent link=\"link7\"/>\n    <child link=\"flange\"/>\n"
         "    <origin xyz=\"0 0 0.126\" rpy=\"0 0 0\"/>\n  </joint>\n"
         "  <joint name=\"hand_joint\" type=\"fixed\">\n    <parent link=\"flange\"/>\n    <child link=\"hand\"/>\n"
         "    <origin xyz=\"0 0 0.02\" rpy=\"0 0 -0.7853981633974483\"/>\n  </joint>\n"
         "  <joint name=\"tcp_joint\" type=\"fixed\">\n    <parent link=\"hand\"/>\n    <child link=\"tcp\"/>\n"
         "    <origin xyz=\"0 0 0.1\" rpy=\"0 0 0\"/>\n  </joint>\n"
         "  <joint name=\"finger_joint\" type=\"fixed\">\n    <parent link=\"hand\"/>\n    <child link=\"finger\"/>\n"
         "    <origin xyz=\"0.03 0 0.06\" rpy=\"0 0 0\"/>\n  </joint>\n"
         "</robot>\n";
}

// The reflector in the flange's frame (m).
inline model::Vector3 reflector_in_flange() { return {0.057, 0.0, 0.085}; }

// The nominal model of the chain base_link -> flange.
inline model::RobotModel reflector_arm_nominal() {
  return model::model_from_urdf(model::parse_urdf_chain(reflector_arm_urdf(), "arm7.urdf", {"", "flange"}));
}

// The true arm: link parameters perturbed, the reflector on the flange, registered in the tracker.
inline model::RobotModel reflector_arm_truth(std::uint64_t seed) {
  const model::RobotModel nominal = reflector_arm_nominal();
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  std::vector<core::ParameterId> ids;
  std::vector<double> errors;
  for (const core::ParameterId& id : model::all_parameters(nominal)) {
    if (model::is_motion_parameter(id.kind)) continue;
    const bool angle = id.kind == core::ParameterKind::link_theta || id.kind == core::ParameterKind::link_alpha ||
                       id.kind == core::ParameterKind::link_beta;
    ids.push_back(id);
    errors.push_back((angle ? 0.1 * 3.141592653589793 / 180.0 : 0.5e-3) * u(rng));
  }
  model::RobotModel truth = model::apply_parameter_errors(
      nominal, ids, Eigen::Map<const Eigen::VectorXd>(errors.data(), static_cast<Eigen::Index>(errors.size())));
  model::Transform reflector;
  reflector.translation = reflector_in_flange();
  truth.flange_T_tool = nominal.frame_n_T_flange * reflector;
  truth.tool = model::ToolKind::point;
  model::Transform tracker_T_base;
  tracker_T_base.translation = model::Vector3(2.0, -1.0, 0.3);
  tracker_T_base.rotation = model::rotation_from_rpy(model::Vector3(0.0, 0.0, 1.2));
  truth.base_T_frame0 = tracker_T_base * truth.base_T_frame0;
  return truth;
}

// `count` rows of the tracker measuring `truth`'s reflector, 0.02 mm noise per axis.
inline model::Dataset reflector_rows(const model::RobotModel& truth, int count, std::uint64_t seed,
                                     const std::string& source) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 2e-5);
  model::Dataset data;
  data.source = source;
  data.joint_count = truth.joint_count();
  for (int r = 0; r < count; ++r) {
    model::Measurement m;
    for (const model::Joint& j : truth.joints)
      m.q.push_back(std::uniform_real_distribution<double>(0.8 * j.lower, 0.8 * j.upper)(rng));
    m.position = model::forward_kinematics(truth, m.q).translation + model::Vector3(noise(rng), noise(rng), noise(rng));
    m.line = r + 2;
    data.rows.push_back(m);
  }
  return data;
}

}  // namespace kincal::test
