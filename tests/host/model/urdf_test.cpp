// URDF in and out (issue #15): URDF -> model -> URDF round trips checked against urdfdom (Debian's
// URDF parser, an implementation independent of ours), the calibrated URDF's link frames, the
// UR description's kinematics file, and the refusals.
#include <doctest/doctest.h>
#include <urdf_parser/urdf_parser.h>
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <random>
#include <regex>
#include <sstream>
#include <string_view>

#include "host/model/axes.hpp"
#include "host/model/model_file.hpp"
#include "host/model/ur_kinematics.hpp"
#include "host/model/urdf.hpp"
#include "host/model/urdf_chain.hpp"
#include "host/model/urdf_text.hpp"

namespace {

using namespace kincal::model;

std::string read_text(const std::string& path) {
  std::ifstream in(path);
  REQUIRE(in);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// For check_urdf (CMake runs it on what the tests write here).
void keep(const std::string& name, const std::string& text) {
  std::filesystem::create_directories(KINCAL_URDF_OUT_DIR);
  std::ofstream(std::string(KINCAL_URDF_OUT_DIR) + "/" + name) << text;
}

Transform from_pose(const urdf::Pose& p) {
  Transform t;
  t.translation = Vector3(p.position.x, p.position.y, p.position.z);
  t.rotation = Eigen::Quaterniond(p.rotation.w, p.rotation.x, p.rotation.y, p.rotation.z).toRotationMatrix();
  return t;
}

// base_T_tip of a URDF at the named joints' values, composed from urdfdom's parse: for each
// joint from the base down, origin then the motion about/along its axis.
struct UrdfdomChain {
  urdf::ModelInterfaceSharedPtr model;
  std::vector<urdf::JointConstSharedPtr> joints;  // base to tip

  UrdfdomChain(const std::string& text, const std::string& base, const std::string& tip)
      : model(urdf::parseURDF(text)) {
    REQUIRE(model);
    for (urdf::LinkConstSharedPtr link = model->getLink(tip); link && link->name != base; link = link->getParent()) {
      REQUIRE(link->parent_joint);
      joints.insert(joints.begin(), link->parent_joint);
    }
  }
  Transform pose(const std::vector<double>& q) const {
    Transform t;
    std::size_t k = 0;
    for (const auto& j : joints) {
      t = t * from_pose(j->parent_to_joint_origin_transform);
      const Vector3 axis(j->axis.x, j->axis.y, j->axis.z);
      Transform motion;
      if (j->type == urdf::Joint::REVOLUTE || j->type == urdf::Joint::CONTINUOUS) {
        motion.rotation = Eigen::AngleAxisd(q[k++], axis.normalized()).toRotationMatrix();
      } else if (j->type == urdf::Joint::PRISMATIC) {
        motion.translation = q[k++] * axis.normalized();
      }
      t = t * motion;
    }
    return t;
  }
};

std::vector<double> random_q(const RobotModel& m, std::mt19937& rng) {
  std::vector<double> q;
  for (const Joint& j : m.joints) {
    const double lo = std::isfinite(j.lower) ? j.lower : -3.0;
    const double hi = std::isfinite(j.upper) ? j.upper : 3.0;
    q.push_back(std::uniform_real_distribution<double>(lo, hi)(rng));
  }
  return q;
}

struct Gap {
  double position_m = 0.0;
  double rotation_rad = 0.0;
};
Gap gap(const Transform& a, const Transform& b) {
  return {(a.translation - b.translation).norm(), Eigen::AngleAxisd(a.rotation.transpose() * b.rotation).angle()};
}

// The largest gap between `device_T_base * urdf(q) * tip_T_tool` and the model's forward
// kinematics over random readings.
Gap worst_gap(const UrdfdomChain& urdf_chain, const RobotModel& m, const Transform& device_T_base, bool orientation,
              unsigned seed, const Transform& tip_T_tool = {}) {
  std::mt19937 rng(seed);
  Gap worst;
  for (int i = 0; i < 200; ++i) {
    const std::vector<double> q = random_q(m, rng);
    const Gap g = gap(device_T_base * urdf_chain.pose(q) * tip_T_tool, forward_kinematics(m, q));
    worst.position_m = std::max(worst.position_m, g.position_m);
    if (orientation) worst.rotation_rad = std::max(worst.rotation_rad, g.rotation_rad);
  }
  return worst;
}

// Every parameter of `m` off by a few millimetres / milliradians, the base by a registration.
RobotModel perturbed(const RobotModel& m, unsigned seed, double size = 2e-3) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, size);
  const std::vector<kincal::core::ParameterId> ids = all_parameters(m);
  Eigen::VectorXd errors(static_cast<Eigen::Index>(ids.size()));
  for (Eigen::Index i = 0; i < errors.size(); ++i) errors(i) = normal(rng);
  RobotModel out = apply_parameter_errors(m, ids, errors);
  Transform registration;
  registration.translation = Vector3(1.5, -3.2, 0.4);
  registration.rotation = rotation_from_rpy(Vector3(0.1, -0.2, 2.5));
  out.base_T_frame0 = registration * out.base_T_frame0;
  return out;
}

// A text write_calibrated_urdf wrote without kincal's comment and the line end that came with it.
std::string without_kincal_comment(std::string text) {
  const std::size_t begin = text.find("<!-- kincal: ");
  REQUIRE(begin != std::string::npos);
  const std::size_t end = text.find("-->", begin) + 3;
  const bool after_declaration = begin > 0 && text[begin - 1] == '\n';
  const std::size_t eol_before = !after_declaration ? 0 : begin > 1 && text[begin - 2] == '\r' ? 2 : 1;
  const std::size_t eol_after = after_declaration                   ? 0
                                : text.compare(end, 2, "\r\n") == 0 ? 2
                                : text.compare(end, 1, "\n") == 0   ? 1
                                                                    : 0;
  return text.erase(begin - eol_before, end + eol_after - (begin - eol_before));
}

// `text` without the xyz and rpy attributes of its <origin> elements: what --original keeps.
std::string without_origin_attributes(const std::string& text) {
  static const std::regex origin("<origin\\b[^>]*>");
  static const std::regex attribute("\\s*\\b(xyz|rpy)\\s*=\\s*(\"[^\"]*\"|'[^']*')");
  std::string out;
  std::size_t from = 0;
  for (std::sregex_iterator it(text.begin(), text.end(), origin), none; it != none; ++it) {
    out += text.substr(from, static_cast<std::size_t>(it->position()) - from);
    const std::string kept = std::regex_replace(it->str(), attribute, "");
    if (kept != "<origin/>") out += kept;  // one --original added to a joint without

    from = static_cast<std::size_t>(it->position() + it->length());
  }
  return out + text.substr(from);
}

// The whole loop on one URDF: its model agrees with urdfdom; the same model written back gives
// the same text with kincal's comment; a calibrated model written back into it agrees with
// urdfdom and keeps every byte but the chain's origin attributes and the comment.
void round_trip(const std::string& name, const std::string& text, const UrdfChainEnds& ends) {
  CAPTURE(name);
  const UrdfChain chain = parse_urdf_chain(text, name, ends);
  const RobotModel nominal = model_from_urdf(chain);
  const UrdfdomChain reference(text, chain.base_link, chain.tip_link);
  const Gap g = worst_gap(reference, nominal, Transform{}, true, 1);
  CHECK(g.position_m < 1e-9);
  CHECK(g.rotation_rad < 1e-9);

  // Unchanged model in: the same kinematics out, the registration is the identity.
  const CalibratedUrdf same = write_calibrated_urdf(text, name, ends, nominal);
  CHECK(same.device_T_base_link.translation.norm() < 1e-12);
  CHECK(without_kincal_comment(same.text) == text);  // every joint unchanged, every byte kept

  const Gap g_same = worst_gap(UrdfdomChain(same.text, chain.base_link, chain.tip_link), nominal, Transform{}, true, 2);
  CHECK(g_same.position_m < 1e-9);
  CHECK(g_same.rotation_rad < 1e-9);

  const RobotModel calibrated = perturbed(nominal, 3);
  const CalibratedUrdf out = write_calibrated_urdf(text, name, ends, calibrated);
  // The calibrated tool is the measured point (issue #42): no joint of the URDF takes it, a note
  // says how far it is from the tip link; the rest is compared, the tool taken as it is at q = 0.
  CHECK(out.notes.size() == 1u);
  const UrdfdomChain written(out.text, chain.base_link, chain.tip_link);
  const std::vector<double> zeros(static_cast<std::size_t>(calibrated.joint_count()), 0.0);
  const Transform tip_T_tool =
      (out.device_T_base_link * written.pose(zeros)).inverse() * forward_kinematics(calibrated, zeros);
  const Gap g_cal = worst_gap(written, calibrated, out.device_T_base_link, true, 4, tip_T_tool);
  CHECK(g_cal.position_m < 1e-9);
  CHECK(g_cal.rotation_rad < 1e-9);
  CHECK(without_origin_attributes(without_kincal_comment(out.text)) == without_origin_attributes(text));
  // Asked for, the measured point is a link of its own, and the calibrated tool is exactly there.
  const CalibratedUrdf marked = write_calibrated_urdf(text, name, ends, calibrated, "kincal_measured_point");
  CHECK(marked.notes.empty());
  const Gap g_marked = worst_gap(UrdfdomChain(marked.text, chain.base_link, "kincal_measured_point"), calibrated,
                                 marked.device_T_base_link, true, 5);
  CHECK(g_marked.position_m < 1e-9);
  CHECK(g_marked.rotation_rad < 1e-9);

  // Same names; meshes, inertias and everything off the chain kept.
  const urdf::ModelInterfaceSharedPtr before = urdf::parseURDF(text);
  const urdf::ModelInterfaceSharedPtr after = urdf::parseURDF(out.text);
  REQUIRE(after);
  CHECK(after->links_.size() == before->links_.size());
  CHECK(after->joints_.size() == before->joints_.size());
  for (const auto& [joint_name, joint] : before->joints_) {
    const urdf::JointConstSharedPtr j = after->getJoint(joint_name);
    REQUIRE(j);
    CHECK(j->type == joint->type);
    CHECK(j->axis.x == joint->axis.x);
    CHECK(j->axis.z == joint->axis.z);
    if (joint->limits) CHECK(j->limits->effort == joint->limits->effort);
  }
  for (const auto& [link_name, link] : before->links_) {
    const urdf::LinkConstSharedPtr l = after->getLink(link_name);
    REQUIRE(l);
    CHECK(l->visual_array.size() == link->visual_array.size());
    CHECK(static_cast<bool>(l->inertial) == static_cast<bool>(link->inertial));
    if (link->inertial) CHECK(l->inertial->mass == link->inertial->mass);
  }
  // Link frames stay on their bodies: perturbations of 2 mm / 2 mrad move none by more than
  // a few millimetres (no DH drift), over arms of up to a metre or two.
  const std::vector<double> zero(static_cast<std::size_t>(nominal.joint_count()), 0.0);
  const std::vector<Transform> poses_before = urdf_link_poses(chain, zero);
  const std::vector<Transform> poses_after = urdf_link_poses(parse_urdf_chain(out.text, name, ends), zero);
  for (std::size_t k = 0; k < poses_before.size(); ++k) {
    CAPTURE(chain.joints[k].name);
    CHECK(gap(poses_before[k], poses_after[k]).position_m < 0.03);
    CHECK(gap(poses_before[k], poses_after[k]).rotation_rad < 0.03);
  }
  keep(name + ".calibrated.urdf", out.text);
}

const char* const kFixedJointsUrdf = R"(<?xml version="1.0"?>
<!-- fixed joints between and after the movable ones, a rotated and shifted base link, axes along
     x, -y and a skew one, a prismatic joint, a tool frame on a branch with a sensor beside it -->
<robot name="test_arm">
  <link name="world"/>
  <link name="pedestal"><visual><geometry><box size="0.3 0.3 0.5"/></geometry></visual></link>
  <link name="l1"><inertial><mass value="3"/><inertia ixx="1" ixy="0" ixz="0" iyy="1" iyz="0" izz="1"/></inertial></link>
  <link name="l1_mount"/>
  <link name="l2"><visual><origin xyz="0.2 0 0"/><geometry><mesh filename="package://x/l2.stl"/></geometry></visual></link>
  <link name="l3"/>
  <link name="l4"/>
  <link name="flange"/>
  <link name="tool"/>
  <link name="camera"/>
  <joint name="world_pedestal" type="fixed">
    <parent link="world"/><child link="pedestal"/>
    <origin xyz="0.5 -0.2 0.3" rpy="0.3 -0.2 1.1"/>
  </joint>
  <joint name="j1" type="revolute">
    <parent link="pedestal"/><child link="l1"/>
    <origin xyz="0 0 0.25"/>
    <axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="10" velocity="1"/>
  </joint>
  <joint name="mount" type="fixed">
    <parent link="l1"/><child link="l1_mount"/>
    <origin xyz="0.05 0 0.1" rpy="0 0.4 0"/>
  </joint>
  <joint name="j2" type="continuous">
    <parent link="l1_mount"/><child link="l2"/>
    <origin xyz="0 0.1 0" rpy="1.5707963267948966 0 0"/>
    <axis xyz="1 0 0"/>
  </joint>
  <joint name="j3" type="prismatic">
    <parent link="l2"/><child link="l3"/>
    <origin xyz="0.4 0 0.02" rpy="0 0 0.3"/>
    <axis xyz="0 -1 0"/>
    <limit lower="-0.2" upper="0.3" effort="10" velocity="1"/>
  </joint>
  <joint name="j4" type="revolute">
    <parent link="l3"/><child link="l4"/>
    <origin xyz="0.1 0.05 0.3" rpy="-0.2 0.1 0.7"/>
    <axis xyz="0.6 0 0.8"/>
    <limit lower="-2" upper="2" effort="10" velocity="1"/>
  </joint>
  <joint name="l4_flange" type="fixed">
    <parent link="l4"/><child link="flange"/>
    <origin xyz="0 0 0.08" rpy="3.14159 0 0"/>
  </joint>
  <joint name="flange_tool" type="fixed">
    <parent link="flange"/><child link="tool"/>
    <origin xyz="0.01 0.02 0.15" rpy="0 0.5 0.25"/>
  </joint>
  <joint name="flange_camera" type="fixed">
    <parent link="flange"/><child link="camera"/>
    <origin xyz="0.05 0 0.02"/>
  </joint>
</robot>
)";

}  // namespace

TEST_CASE("urdf: the four robots written as URDF come back with the same kinematics") {
  for (const char* robot : {"puma560", "stanford_rrp", "arid_prrr", "ur5"}) {
    CAPTURE(robot);
    const RobotModel original = load_model(std::string(KINCAL_ROBOTS_DIR) + "/" + robot + ".yaml");
    const std::string text = write_urdf(original);
    keep(std::string(robot) + ".urdf", text);
    // The written URDF as urdfdom reads it agrees with the YAML model.
    const Gap g = worst_gap(UrdfdomChain(text, "device", "tool"), original, Transform{}, true, 5);
    CHECK(g.position_m < 1e-9);
    CHECK(g.rotation_rad < 1e-9);
    // URDF -> model: the same kinematics (the default chain is device -> tool).
    const RobotModel back = model_from_urdf(parse_urdf_chain(text, robot));
    std::mt19937 rng(6);
    for (int i = 0; i < 200; ++i) {
      const std::vector<double> q = random_q(original, rng);
      const Gap gi = gap(forward_kinematics(back, q), forward_kinematics(original, q));
      REQUIRE(gi.position_m < 1e-9);
      REQUIRE(gi.rotation_rad < 1e-9);
    }
    round_trip(robot, text, {});
  }
}

TEST_CASE("urdf: fixed joints, a rotated base link, a tool frame, a prismatic and a skew axis") {
  round_trip("fixed_joints", kFixedJointsUrdf, {"world", "tool"});
  // The default chain: world is the root; tool and camera are leaves with the same joints.
  CHECK_THROWS_WITH_AS(parse_urdf_chain(kFixedJointsUrdf, "arm.urdf"),
                       doctest::Contains("world -> camera (4 movable joints)\n  world -> tool (4 movable joints)"),
                       InputError);
  const UrdfChain chain = parse_urdf_chain(kFixedJointsUrdf, "arm.urdf", {"pedestal", "flange"});
  CHECK(chain.joints.size() == 6);
  CHECK(chain.movable_count() == 4);
}

TEST_CASE("urdf: UR10 from its description, calibrated and written back with meshes in place") {
  const std::string path = std::string(KINCAL_ROBOTS_DIR) + "/ur10.urdf";
  const std::string text = read_text(path);
  round_trip("ur10", text, {"", "tool0"});
  // The calibrated model from `kincal identify` may use other conventions than the URDF's:
  // the same FK, the same frames.
  const RobotModel nominal = load_model(path, {"", "tool0"});
  CHECK(nominal.joints[0].name == "shoulder_pan_joint");
  CHECK(nominal.joints[1].convention == kincal::core::LinkConvention::doty);  // axes 2, 3 parallel
  // A tilt of the parallel axes by 1 mrad: plain DH would move the common normals by metres.
  RobotModel tilted = nominal;
  tilted.joints[1].parameters.beta_rad += 1e-3;
  tilted.joints[2].parameters.beta_rad -= 1e-3;
  const CalibratedUrdf out = write_calibrated_urdf(text, path, {"", "tool0"}, tilted);
  const UrdfChain before = parse_urdf_chain(text, path, {"", "tool0"});
  const UrdfChain after = parse_urdf_chain(out.text, path, {"", "tool0"});
  const std::vector<double> zero(6, 0.0);
  const std::vector<Transform> a = urdf_link_poses(before, zero), b = urdf_link_poses(after, zero);
  double worst = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) worst = std::max(worst, gap(a[k], b[k]).position_m);
  CHECK(worst < 1.5e-3);  // 1 mrad over the 1.2 m arm
  CHECK(worst > 1e-4);

  // The file is the original but for one comment line after the declaration and the <origin>
  // lines of the six joints: formatting, comments and everything else kept -- the probe's fixed
  // joint tool0-tracker_probe too, though the calibrated tool (the measured point) moved.
  const auto lines = [](const std::string& t) {
    std::vector<std::string> result;
    std::istringstream stream(t);
    for (std::string l; std::getline(stream, l);) result.push_back(l);
    return result;
  };
  const CalibratedUrdf probe =
      write_calibrated_urdf(text, path, {"", "tracker_probe"}, perturbed(load_model(path, {"", "tracker_probe"}), 9));
  std::vector<std::string> in = lines(text), written = lines(probe.text);
  REQUIRE(written.size() == in.size() + 1);
  CHECK(written[1].starts_with("<!-- kincal: calibrated joint origins of the chain base_link -> tracker_probe"));
  written.erase(written.begin() + 1);
  int changed = 0;
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (in[i] == written[i]) continue;
    ++changed;
    CHECK(in[i].find("<origin") != std::string::npos);
    CHECK(written[i].find("<origin xyz=") != std::string::npos);
  }
  CHECK(changed == 6);
}

TEST_CASE("urdf: the last joint carries what hangs off the chain -- a gripper's fingers behind their own joints") {
  // A 2-joint arm to its flange; a gripper fixed to the flange with a finger behind a revolute
  // knuckle (a mimic of nothing on the chain) and a floating object beside it. Joint 2 carries
  // its link, the gripper and the finger (at the knuckle's zero), never the floating object.
  const std::string text = R"(<robot name="r">
  <link name="base"/><link name="l1"/>
  <link name="l2"><inertial><origin xyz="0.1 0 0"/><mass value="2"/></inertial></link>
  <link name="flange"/>
  <link name="gripper"><inertial><origin xyz="0 0 0.05"/><mass value="1"/></inertial></link>
  <link name="finger"><inertial><origin xyz="0 0.02 0"/><mass value="0.5"/></inertial></link>
  <link name="object"><inertial><mass value="100"/></inertial></link>
  <joint name="j1" type="revolute"><parent link="base"/><child link="l1"/><axis xyz="0 0 1"/>
    <limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="j2" type="revolute"><parent link="l1"/><child link="l2"/><origin xyz="0 0 0.3" rpy="1.5708 0 0"/>
    <axis xyz="0 0 1"/><limit lower="-3" upper="3" effort="1" velocity="1"/></joint>
  <joint name="to_flange" type="fixed"><parent link="l2"/><child link="flange"/><origin xyz="0.4 0 0"/></joint>
  <joint name="to_gripper" type="fixed"><parent link="flange"/><child link="gripper"/><origin xyz="0 0 0.01"/></joint>
  <joint name="knuckle" type="revolute"><parent link="gripper"/><child link="finger"/><origin xyz="0 0 0.1"/>
    <axis xyz="1 0 0"/><limit lower="0" upper="0.8" effort="1" velocity="1"/></joint>
  <joint name="loose" type="floating"><parent link="l2"/><child link="object"/></joint>
</robot>)";
  const UrdfChain chain = parse_urdf_chain(text, "gripper.urdf", {"", "flange"});
  REQUIRE(chain.masses.size() == 3);  // j1, j2, to_flange: each joint's child with what hangs off it
  CHECK(chain.masses[0].mass_kg == 0.0);
  CHECK(chain.masses[1].mass_kg == doctest::Approx(2.0));  // l2 alone: the floating object is not carried
  CHECK((chain.masses[1].centre_m - Vector3(0.1, 0, 0)).norm() < 1e-12);
  // The flange's: the gripper's 1 kg at (0, 0, 0.06) and the finger's 0.5 kg at (0, 0.02, 0.11).
  CHECK(chain.masses[2].mass_kg == doctest::Approx(1.5));
  const Vector3 centre = (1.0 * Vector3(0, 0, 0.06) + 0.5 * Vector3(0, 0.02, 0.11)) / 1.5;
  CHECK((chain.masses[2].centre_m - centre).norm() < 1e-12);
}

TEST_CASE("urdf: <inertial> masses deflect the UR10 under gravity as UR's DH-frame table (ur10.yaml) does") {
  RobotModel from_urdf = load_model(std::string(KINCAL_ROBOTS_DIR) + "/ur10.urdf", {"", "tool0"});
  RobotModel from_table = load_model(std::string(KINCAL_ROBOTS_DIR) + "/ur10.yaml");
  REQUIRE(from_urdf.joint_count() == 6);
  for (int j = 0; j < 6; ++j)  // base_link_inertia's 4 kg is before the first joint: it never moves
    CHECK(from_urdf.joints[static_cast<std::size_t>(j)].mass_kg ==
          doctest::Approx(from_table.joints[static_cast<std::size_t>(j)].mass_kg));
  // The flange's deflection by a compliance on every joint, the same in either description (the
  // two base frames differ by a turn about z: compare lengths).
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
  const auto deflection = [](RobotModel m, const std::vector<double>& q) {
    m.flange_T_tool = {};
    const Vector3 rigid = forward_kinematics(m, q).translation;
    for (Joint& j : m.joints) j.compliance = 1e-4;  // rad/(N m): about a centimetre at full reach
    return (forward_kinematics(m, q).translation - rigid).norm();
  };
  double largest = 0.0, worst = 0.0;
  for (int k = 0; k < 50; ++k) {
    std::vector<double> q(6);
    for (double& v : q) v = angle(rng);
    const double a = deflection(from_urdf, q), b = deflection(from_table, q);
    largest = std::max(largest, b);
    worst = std::max(worst, std::abs(a - b));
  }
  CHECK(largest > 5e-3);
  CHECK(worst < 1e-9);
  // A link's mass that is not one is refused naming the line.
  const std::string bad =
      "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"><inertial>\n<mass value=\"-2\"/></inertial></link>\n"
      "<joint name=\"j\" type=\"continuous\"><parent link=\"a\"/><child link=\"b\"/></joint></robot>";
  std::string error;
  try {
    (void)parse_urdf_chain(bad, "bad.urdf");
  } catch (const InputError& e) {
    error = e.what();
  }
  CHECK(error == "bad.urdf:4: link 'b' <mass> value -2 is not a link's mass (0 to 1e+06 kg)");
}

TEST_CASE("urdf: the tip link on the last joint: the tool's calibration is reported, not lost silently") {
  const std::string text = read_text(std::string(KINCAL_ROBOTS_DIR) + "/ur10.urdf");
  const UrdfChainEnds ends{"base_link", "wrist_3_link"};
  RobotModel m = load_model(std::string(KINCAL_ROBOTS_DIR) + "/ur10.urdf", ends);
  m.flange_T_tool.translation += Vector3(0, 0, 0.01);
  const CalibratedUrdf out = write_calibrated_urdf(text, "ur10.urdf", ends, m);
  REQUIRE(out.notes.size() == 1);
  CHECK(out.notes[0].find("10.000 mm") != std::string::npos);
  m.joints[1].compliance = 1e-6;
  const CalibratedUrdf sag = write_calibrated_urdf(text, "ur10.urdf", ends, m);
  REQUIRE(sag.notes.size() == 2);
  CHECK(sag.notes[0] ==
        "the joint map (coupling, scale, compliance) of shoulder_lift_joint is not in this file: "
        "readings go in as they are");
  CHECK(ur_kinematics(m).notes.back() == sag.notes[0]);
}

TEST_CASE("ur-kinematics: the UR10 description's defaults come back, and the file's FK is the model's") {
  const RobotModel ur10 = load_model(std::string(KINCAL_ROBOTS_DIR) + "/ur10.urdf", {"", "tool0"});
  const UrKinematics k = ur_kinematics(ur10);
  // config/ur10/default_kinematics.yaml of Universal_Robots_ROS2_Description.
  const double expected[6][3] = {{0, 0, 0.1273},         {0, 0, 0},       {-0.612, 0, 0},
                                 {-0.5723, 0, 0.163941}, {0, -0.1157, 0}, {0, 0.0922, 0}};
  for (std::size_t i = 0; i < 6; ++i) {
    CAPTURE(i);
    CHECK((k.joint_origins[i].translation - Vector3(expected[i][0], expected[i][1], expected[i][2])).norm() < 1e-9);
  }

  for (unsigned seed : {7u, 8u}) {
    const RobotModel calibrated = seed == 7 ? ur10 : perturbed(ur10, seed);
    const UrKinematics ck = ur_kinematics(calibrated);
    const std::string text = write_ur_kinematics(ck);
    keep("ur10_calibration_" + std::to_string(seed) + ".yaml", text);
    // Compose as ur_macro.xacro does: per joint translate (x, y, z), rotate fixed-axis roll,
    // pitch, yaw, then the joint's reading about z.
    const YAML::Node file = YAML::Load(text)["kinematics"];
    REQUIRE(file["hash"]);
    const kincal::core::ChainModel<double> chain = to_chain(calibrated);
    std::mt19937 rng(seed);
    for (int n = 0; n < 100; ++n) {
      const std::vector<double> q = random_q(calibrated, rng);
      Transform t = chain.base_T_frame0;
      for (std::size_t i = 0; i < 6; ++i) {
        const YAML::Node s = file[kUrKinematicsSections[i]];
        Transform origin;
        origin.translation = Vector3(s["x"].as<double>(), s["y"].as<double>(), s["z"].as<double>());
        origin.rotation = (Eigen::AngleAxisd(s["yaw"].as<double>(), Vector3::UnitZ()) *
                           Eigen::AngleAxisd(s["pitch"].as<double>(), Vector3::UnitY()) *
                           Eigen::AngleAxisd(s["roll"].as<double>(), Vector3::UnitX()))
                              .toRotationMatrix();
        Transform joint;
        joint.rotation = Eigen::AngleAxisd(q[i], Vector3::UnitZ()).toRotationMatrix();
        t = t * origin * joint;
      }
      t = t * ck.wrist_3_T_flange * chain.flange_T_tool;
      const Gap g = gap(t, forward_kinematics(calibrated, q));
      REQUIRE(g.position_m < 1e-9);
      REQUIRE(g.rotation_rad < 1e-9);
    }
  }
  CHECK_THROWS_AS(ur_kinematics(load_model(std::string(KINCAL_ROBOTS_DIR) + "/stanford_rrp.yaml")), InputError);
}

TEST_CASE("ur-kinematics: a six-revolute arm that is not a UR arm is refused, saying which axes differ") {
  CHECK_NOTHROW(ur_kinematics(load_model(std::string(KINCAL_ROBOTS_DIR) + "/ur10.yaml")));
  CHECK_NOTHROW(ur_kinematics(load_model(std::string(KINCAL_ROBOTS_DIR) + "/ur5.yaml")));
  // The PUMA 560's wrist is spherical: its axis 4 is across axis 3, where a UR arm's is parallel.
  CHECK_THROWS_WITH_AS(ur_kinematics(load_model(std::string(KINCAL_ROBOTS_DIR) + "/puma560.yaml")),
                       doctest::Contains("axes 3 and 4 are 90.0 deg apart where a UR arm's are parallel"), InputError);
  CHECK_THROWS_WITH_AS(ur_kinematics(load_model(std::string(KINCAL_ROBOTS_DIR) + "/heavy6r.yaml")),
                       doctest::Contains("is not a Universal Robots arm"), InputError);
}

TEST_CASE("urdf: bad input is refused naming the file, the line and what is wrong") {
  const auto error = [](const std::string& text, const UrdfChainEnds& ends = {}) {
    try {
      parse_urdf_chain(text, "bad.urdf", ends);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string head = "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n<link name=\"c\"/>\n";
  const std::string j1 =
      "<joint name=\"j1\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>"
      "<limit lower=\"-1\" upper=\"1\" effort=\"0\" velocity=\"0\"/></joint>\n";
  CHECK(error(head + j1 +
              "<joint name=\"j2\" type=\"revolute\"><parent link=\"b\"/><child link=\"c\"/>\n"
              "<mimic joint=\"j1\"/><limit lower=\"-1\" upper=\"1\" effort=\"0\" velocity=\"0\"/></joint></robot>") ==
        "bad.urdf:7: joint 'j2' mimics another joint: chains with mimic joints are not supported (calibrate the "
        "chain without it, or make it fixed)");
  CHECK(
      error(head + j1 + "<joint name=\"j2\" type=\"floating\"><parent link=\"b\"/><child link=\"c\"/></joint></robot>")
          .starts_with("bad.urdf:6: joint 'j2' is of type 'floating'"));
  CHECK(error(head + "<joint name=\"j1\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>\n"
                     "<origin xyz=\"0 0,5 0\"/><limit lower=\"-1\" upper=\"1\"/></joint></robot>") ==
        "bad.urdf:6: xyz '0 0,5 0' is not three finite numbers");
  CHECK(error(head + "<joint name=\"j1\" type=\"fixed\"><parent link=\"a\"/><child link=\"x\"/></joint></robot>") ==
        "bad.urdf:5: joint 'j1' names link 'x', which is not defined");
  CHECK(error(head + j1 + "<joint name=\"j2\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint></robot>",
              {"b", "a"}) == "bad.urdf:2: link 'a' is not below link 'b'");
  CHECK(error(head + "<joint name=\"j1\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/>\n"
                     "<origin xyz=\"0 2e4 0\"/></joint></robot>") ==
        "bad.urdf:6: an origin 20000 m from its parent frame: more than 10000 m is not a robot's geometry");
  CHECK(error("<robot><link name=\"a\">\n</robot>").starts_with("bad.urdf:1: XML: Error=XML_ERROR_MISMATCHED_ELEMENT"));
  // A second root is refused whichever --base-link: check_urdf refuses it ("Two root links found").
  for (const UrdfChainEnds& ends : {UrdfChainEnds{}, UrdfChainEnds{"a", "b"}, UrdfChainEnds{"a", "nope"}})
    CHECK(error(head + j1 + "</robot>", ends) ==
          "bad.urdf:4: link 'c' is the child of no joint, as is link 'a': a URDF's links form one tree (connect it "
          "with a joint, or remove it)");
  CHECK(error(head + j1 + "<joint name=\"j2\" type=\"fixed\"><parent link=\"b\"/><child link=\"c\"/></joint></robot>",
              {"a", "nope"}) == "bad.urdf:1: no link named 'nope' (--tip-link)");
  // tinyxml2 stops at an end tag that closes nothing and ignores the rest: refused.
  CHECK(error(head + j1 + "</robot>\n</robot>\n<robot name=\"other\"/>") ==
        "bad.urdf:7: an end tag that closes no element: the rest of the file would be ignored");
  CHECK(error(head + j1 +
              "<joint name=\"j2\" type=\"fixed\"><parent link=\"b\"/>\n</child link=\"c\"/></joint></robot>") ==
        "bad.urdf:7: '</' and '/>' around one tag: not XML (an end tag or an empty element?)");
  CHECK_THROWS_WITH_AS(load_model("robot.yaml", {"", "tool0"}), doctest::Contains("for URDF models"), InputError);
}

TEST_CASE("rpy: rotation -> rpy -> rotation to 1e-12, random and near +-pi/2 pitch") {
  const auto round_trip_error = [](const Matrix3& r) {
    const Vector3 rpy = rpy_from_rotation(r);
    CHECK(std::abs(rpy.y()) <= std::numbers::pi / 2);
    return (rotation_from_rpy(rpy) - r).cwiseAbs().maxCoeff();
  };
  // An SIA5D's tool0 (motoman_sia5d_support): pitch 4.4e-8 beyond -pi/2.
  CHECK(round_trip_error(rotation_from_rpy(Vector3(-1.57079637, -1.57079637, -1.57079637))) < 1e-12);
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
  double worst = 0.0;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Quaterniond q(std::normal_distribution<double>()(rng), std::normal_distribution<double>()(rng),
                               std::normal_distribution<double>()(rng), std::normal_distribution<double>()(rng));
    worst = std::max(worst, round_trip_error(q.normalized().toRotationMatrix()));
    // Pitch pi/2 - 10^-k (k = 0 .. 16) on either side, either sign, exactly +-pi/2 included.
    const double off = std::pow(10.0, -(i % 17)) * (i % 2 == 0 ? 1.0 : -1.0) * (i % 34 == 33 ? 0.0 : 1.0);
    const double pitch = (i % 4 < 2 ? 1.0 : -1.0) * (std::numbers::pi / 2 - off);
    worst = std::max(worst, round_trip_error(rotation_from_rpy(Vector3(angle(rng), pitch, angle(rng)))));
  }
  CHECK(worst < 1e-12);
}

// Hand-written spellings every XML reader takes: a byte-order mark, CRLF, single quotes, spaces
// around '=', attributes in any order, <origin></origin>, comments holding "<joint" and
// "<origin", a joint without <origin>, a limit without bounds, an rpy just past -pi/2.
const char* const kSpelledUrdf =
    "\xEF\xBB\xBF<?xml version='1.0' encoding='UTF-8'?>\r\n"
    "<!-- <joint name=\"elbow_joint\" type=\"revolute\"> in a comment -->\r\n"
    "<robot name = 'spelled'>\r\n"
    "  <link name='base_link'/>\r\n  <link name=\"upper\"/>\r\n  <link name = \"fore\" />\r\n"
    "  <link name=\"hand\"/>\r\n  <link name=\"tool0\"></link>\r\n"
    "  <joint type=\"revolute\" name = \"shoulder_joint\" >\r\n"
    "    <limit upper='3' lower = '-3' effort=\"1\" velocity=\"1\"/>\r\n"
    "    <child link=\"upper\"/><parent link=\"base_link\"/>\r\n"
    "    <axis xyz=\"0 0 1\"/>\r\n"
    "    <origin rpy = '0 0 0' xyz = '0 0 0.3'></origin>\r\n"
    "  </joint>\r\n"
    "  <joint name\t=\t\"elbow_joint\" type='revolute'><parent link='upper'/><child link='fore'/>\r\n"
    "    <!-- <origin xyz=\"9 9 9\"/> -->\r\n"
    "    <origin xyz=\"0.4 0 0\"   rpy=\"0 1.57079637 0\"/><axis xyz='0 1 0'/><limit effort='1' velocity='1'/>\r\n"
    "  </joint>\r\n"
    "  <joint name=\"wrist_joint\" type=\"continuous\"><parent link=\"fore\"/><child link=\"hand\"/>"
    "<axis xyz=\"1 0 0\"/></joint>\r\n"
    "  <joint name=\"hand-tool0\" type=\"fixed\">\r\n"
    "    <origin rpy=\"-1.57079637 -1.57079637 -1.57079637\" xyz=\"0.011 0 0\"/>\r\n"
    "    <parent link=\"hand\"/>\r\n    <child link=\"tool0\"/>\r\n"
    "  </joint>\r\n"
    "</robot>\r\n";

TEST_CASE("urdf --original: any XML spelling, the byte-order mark first, CRLF and every other byte kept") {
  const std::string text = kSpelledUrdf;
  const UrdfChain chain = parse_urdf_chain(text, "spelled.urdf");
  REQUIRE(chain.joints.size() == 4);
  CHECK(chain.tip_link == "tool0");
  CHECK(chain.joints[1].name == "elbow_joint");
  CHECK(std::isinf(chain.joints[1].lower));  // effort and velocity only: no limits, not [0, 0]
  CHECK(std::isinf(chain.joints[1].upper));
  round_trip("spelled", text, {});
  const CalibratedUrdf out = write_calibrated_urdf(text, "spelled.urdf", {}, perturbed(model_from_urdf(chain), 12));
  CHECK(out.text.starts_with("\xEF\xBB\xBF<?xml version='1.0' encoding='UTF-8'?>\r\n<!-- kincal: "));
  CHECK(out.text.find("\r\n<!-- <joint name=\"elbow_joint\" type=\"revolute\"> in a comment -->\r\n<robot name = "
                      "'spelled'>") != std::string::npos);
  CHECK(out.text.find("    <!-- <origin xyz=\"9 9 9\"/> -->\r\n") != std::string::npos);
  // Every line end is still CRLF; the joint without <origin> got one in its start tag's quotes.
  for (std::size_t p = out.text.find('\n'); p != std::string::npos; p = out.text.find('\n', p + 1))
    REQUIRE(out.text[p - 1] == '\r');
  CHECK(out.text.find("<joint name=\"wrist_joint\" type=\"continuous\"><origin xyz=\"") != std::string::npos);
  CHECK(out.text.find("<origin rpy = '") != std::string::npos);  // single quotes and spacing kept
  // The same model again: the text is the original's but for the comment.
  const RobotModel nominal = model_from_urdf(chain);
  CHECK(without_kincal_comment(write_calibrated_urdf(text, "spelled.urdf", {}, nominal).text) == text);
}

TEST_CASE("urdf: limits without bounds are no limits; equal limits are refused with file:line") {
  const std::string head =
      "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n"
      "<joint name=\"j1\" type=\"revolute\"><parent link=\"a\"/><child link=\"b\"/>\n";
  const UrdfChain free = parse_urdf_chain(head + "<limit effort=\"1\" velocity=\"2\"/></joint></robot>", "r.urdf");
  CHECK(free.joints[0].lower == -std::numeric_limits<double>::infinity());
  CHECK(free.joints[0].upper == std::numeric_limits<double>::infinity());
  const RobotModel m = model_from_urdf(free);
  CHECK(!std::isfinite(m.joints[0].lower));
  const UrdfChain half =
      parse_urdf_chain(head + "<limit upper=\"2\" effort=\"1\" velocity=\"2\"/></joint></robot>", "r.urdf");
  CHECK(half.joints[0].lower == 0.0);  // URDF's default for the one not given
  CHECK(half.joints[0].upper == 2.0);
  CHECK_THROWS_WITH_AS(
      parse_urdf_chain(head + "<limit lower=\"0.5\" upper=\"0.5\" effort=\"1\" velocity=\"2\"/></joint></robot>",
                       "r.urdf"),
      "r.urdf:5: joint 'j1': lower and upper limits are equal (0.5), so the joint cannot move: make it fixed, or "
      "give its range",
      InputError);
  using namespace std::string_literals;
  CHECK_THROWS_WITH_AS(parse_urdf_chain("<robot name=\"r\">\n<link name=\"a\"/>\0\n</robot>"s, "r.urdf"),
                       "r.urdf:2: a NUL byte: not XML text (UTF-16?)", InputError);
  CHECK_THROWS_WITH_AS(model_from_urdf(parse_urdf_chain(
                           "<robot name=\"r\">\n<link name=\"a\"/>\n<link name=\"b\"/>\n"
                           "<joint name=\"f\" type=\"fixed\"><parent link=\"a\"/><child link=\"b\"/></joint></robot>",
                           "r.urdf")),
                       "r.urdf:3: no movable joint between 'a' and 'b'", InputError);
}

TEST_CASE("urdf: 7,000 leaves are listed in well under a second, the message at most 20 of them") {
  // A 2 MB URDF: a 100-joint arm with 70 fixed leaves on each link.
  std::ostringstream u;
  u << "<robot name=\"many\">\n<link name=\"l0\"/>\n";
  for (int i = 1; i <= 100; ++i) {
    u << "<link name=\"l" << i << "\"/>\n<joint name=\"j" << i << "\" type=\"continuous\"><parent link=\"l" << i - 1
      << "\"/><child link=\"l" << i << "\"/><origin xyz=\"0 0 0.1\" rpy=\"0 0 0\"/><axis xyz=\"0 1 0\"/></joint>\n";
    for (int k = 0; k < 70; ++k)
      u << "<link name=\"leaf_" << i << "_" << k << "\"><inertial><origin xyz=\"0 0 0\"/><mass value=\"0.1\"/>"
        << "<inertia ixx=\"1e-4\" ixy=\"0\" ixz=\"0\" iyy=\"1e-4\" iyz=\"0\" izz=\"1e-4\"/></inertial></link>\n"
        << "<joint name=\"leaf_joint_" << i << "_" << k << "\" type=\"fixed\"><parent link=\"l" << i
        << "\"/><child link=\"leaf_" << i << "_" << k << "\"/><origin xyz=\"0 0 0.05\" rpy=\"0 0 0\"/></joint>\n";
  }
  u << "</robot>\n";
  const std::string text = u.str();
  CHECK(text.size() > 2'000'000);
  const auto start = std::chrono::steady_clock::now();
  std::string message;
  try {
    parse_urdf_chain(text, "many.urdf");
  } catch (const InputError& e) {
    message = e.what();
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  MESSAGE(seconds << " s");
  CHECK(seconds < 10.0);  // 2-3 s in a Debug ASan build on a loaded 2-core machine; linear in the file
  CHECK(message.find("which chain?") != std::string::npos);
  CHECK(std::count(message.begin(), message.end(), '\n') == 21);
  CHECK(message.ends_with("\n  and 6980 more"));
}

// check_urdf's verdict on a text (urdfdom-tools, the reference parser users have).
bool check_urdf_accepts(const std::string& path, const std::string& text) {
  std::filesystem::create_directories(std::filesystem::path(path).parent_path());
  std::ofstream(path, std::ios::binary) << text;
  std::FILE* pipe = ::popen((std::string(KINCAL_CHECK_URDF) + " '" + path + "' 2>&1").c_str(), "r");
  REQUIRE(pipe != nullptr);
  std::string output;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, pipe)) > 0;) output.append(buffer, n);
  const int status = ::pclose(pipe);
  CAPTURE(output);
  return status == 0 && output.find("Successfully Parsed XML") != std::string::npos;
}

TEST_CASE("urdf corpus: every chain of every real URDF reads exactly or is refused with file:line") {
  int exact = 0, refused = 0;
  std::vector<std::filesystem::path> files;
  for (const auto& entry : std::filesystem::recursive_directory_iterator(KINCAL_URDF_CORPUS_DIR))
    if (entry.path().extension() == ".urdf") files.push_back(entry.path());
  std::sort(files.begin(), files.end());
  REQUIRE(files.size() == 13);
  for (const std::filesystem::path& file : files) {
    const std::string path = file.string();
    CAPTURE(path);
    const std::string text = read_text(path);
    // The chains: root to every leaf, as urdfdom sees the tree.
    const urdf::ModelInterfaceSharedPtr reference = urdf::parseURDF(text);
    REQUIRE(reference);
    for (const auto& [leaf, link] : reference->links_) {
      if (!link->child_joints.empty()) continue;
      CAPTURE(leaf);
      const UrdfChainEnds ends{"", leaf};
      try {
        const UrdfChain chain = parse_urdf_chain(text, path, ends);
        const RobotModel model = model_from_urdf(chain);
        round_trip(file.stem().string() + "." + leaf, text, ends);
        const CalibratedUrdf out = write_calibrated_urdf(text, path, ends, perturbed(model, 13));
        CHECK(check_urdf_accepts(
            std::string(KINCAL_URDF_OUT_DIR) + "/corpus/" + file.stem().string() + "." + leaf + ".urdf", out.text));
        MESSAGE("exact: " << path << " -> " << leaf << " (" << chain.movable_count() << " movable joints)");
        ++exact;
      } catch (const InputError& e) {
        MESSAGE("refused: " << std::string(e.what()));
        CHECK(std::regex_search(e.what(), std::regex("^" + path + ":[0-9]+: ")));
        ++refused;
      }
    }
  }
  MESSAGE(exact << " chains read exactly, " << refused << " refused");
  CHECK(exact == 14);    // the arms' tool0 chains (but the IRB 5400's), mh5/sia10d/sia10f to link_t, kr210 Link1...
  CHECK(refused == 14);  // base frames (no movable joint) and chains through mimic joints
}

// Issue #44: URDFs as tools write them. `text` with every number of its <origin> elements' xyz
// and rpy values replaced by '#': what --original must keep, the white space between the numbers
// included.
std::string origin_numbers_blanked(const std::string& text) {
  std::string out = text;
  for (const XmlElementSpan& e : map_xml_text(text).elements) {
    if (e.name != "origin") continue;
    for (const XmlAttributeSpan& a : e.attributes) {
      if (a.name != "xyz" && a.name != "rpy") continue;
      for (std::size_t p = a.value_begin; p < a.value_end; ++p)
        if (std::string_view(" \t\r\n").find(text[p]) == std::string_view::npos) out[p] = '#';
    }
  }
  // Runs of '#' to one, so that a number respelled with another length compares equal.
  out.erase(std::unique(out.begin(), out.end(), [](char a, char b) { return a == '#' && b == '#'; }), out.end());
  return out;
}

std::string replace_all(std::string text, std::string_view from, std::string_view to) {
  for (std::size_t p = text.find(from); p != std::string::npos; p = text.find(from, p + to.size()))
    text.replace(p, from.size(), to);
  return text;
}

TEST_CASE("urdf --original: CRLF, mixed line ends, no final line end, a BOM, tabs: every byte kept but the origins") {
  const std::string lf = read_text(std::string(KINCAL_ROBOTS_DIR) + "/ur10.urdf");
  REQUIRE(lf.find('\r') == std::string::npos);
  REQUIRE(lf.find('\t') == std::string::npos);
  const UrdfChainEnds ends{"", "ft_frame"};
  const RobotModel calibrated = perturbed(model_from_urdf(parse_urdf_chain(lf, "ur10.urdf", ends)), 21);
  const std::string lf_out = write_calibrated_urdf(lf, "ur10.urdf", ends, calibrated).text;
  // Tabs as indentation and between the numbers of every origin; a comment holding an origin.
  std::string tabs = replace_all(replace_all(lf, "\n  ", "\n\t"), "<origin xyz=\"0 0 ", "<origin xyz=\"0\t0\t");
  tabs = replace_all(tabs, "</robot>", "\t<!-- <origin xyz=\"1 2 3\"/> -->\n</robot>");
  REQUIRE(tabs.find("xyz=\"0\t0\t") != std::string::npos);
  std::string mixed;  // CRLF on every other line
  for (std::size_t p = 0, n = 0; p < lf.size(); ++n) {
    const std::size_t end = std::min(lf.find('\n', p), lf.size());
    mixed += lf.substr(p, end - p) + (end == lf.size() ? "" : n % 2 == 0 ? "\r\n" : "\n");
    p = end + 1;
  }
  struct Variant {
    const char* name;
    std::string text;
    std::string (*undo)(const std::string&);  // the variant's output back to the LF file's
  };
  const std::string crlf = replace_all(lf, "\n", "\r\n");
  REQUIRE(crlf.ends_with("</robot>\r\n"));
  const std::vector<Variant> variants = {
      {"CRLF", crlf, [](const std::string& t) { return replace_all(t, "\r\n", "\n"); }},
      {"mixed", mixed, [](const std::string& t) { return replace_all(t, "\r\n", "\n"); }},
      {"CRLF without a final line end", crlf.substr(0, crlf.size() - 2),
       [](const std::string& t) { return replace_all(t, "\r\n", "\n") + "\n"; }},
      {"BOM and CRLF", "\xEF\xBB\xBF" + crlf,
       [](const std::string& t) { return replace_all(t.substr(3), "\r\n", "\n"); }},
      {"tabs and a comment", tabs, nullptr},
  };
  const std::vector<double> q = {0.1, -1.2, 1.4, -0.3, 0.8, 2.0};
  const RobotModel lf_back = model_from_urdf(parse_urdf_chain(lf_out, "out.urdf", ends));
  for (const Variant& v : variants) {
    CAPTURE(v.name);
    const std::string out = write_calibrated_urdf(v.text, "ur10.urdf", ends, calibrated).text;
    const std::string kept = without_kincal_comment(out);
    // Only the numbers of the origins differ, and some do.
    CHECK(origin_numbers_blanked(kept) == origin_numbers_blanked(v.text));
    CHECK(kept != v.text);
    CHECK(out.find("\r\r") == std::string::npos);
    if (v.undo != nullptr) CHECK(v.undo(out) == lf_out);  // the same numbers as from the LF file
    // The written file reads back to the calibrated kinematics whatever its spelling.
    const RobotModel back = model_from_urdf(parse_urdf_chain(out, "out.urdf", ends));
    CHECK(gap(forward_kinematics(back, q), forward_kinematics(lf_back, q)).position_m < 1e-12);
  }
  // CRLF: every line end of the output is CRLF, the comment's too; no final line end stays none.
  const std::string crlf_out = write_calibrated_urdf(crlf, "ur10.urdf", ends, calibrated).text;
  for (std::size_t p = crlf_out.find('\n'); p != std::string::npos; p = crlf_out.find('\n', p + 1))
    REQUIRE(crlf_out[p - 1] == '\r');
  CHECK(write_calibrated_urdf(variants[2].text, "ur10.urdf", ends, calibrated).text.ends_with("</robot>"));
  // The tabs between the numbers of a changed origin are kept: every tab of the input is still there
  // (kincal's comment has none). Which origins change: the movable joints' (issue #42: no fixed one).
  const std::string tabs_out = write_calibrated_urdf(tabs, "ur10.urdf", ends, calibrated).text;
  CHECK(std::count(tabs_out.begin(), tabs_out.end(), '\t') == std::count(tabs.begin(), tabs.end(), '\t'));
  CHECK(tabs_out != tabs);
}

// A three-joint arm as a CAD exporter writes it: CRLF, its banner comment, every limit 0 and 0.
std::string cad_arm(const std::string& limit_j2, const std::string& side = "") {
  return "<?xml version=\"1.0\" encoding=\"utf-8\"?>\r\n"
         "<!-- This URDF was automatically created by SolidWorks to URDF Exporter! -->\r\n"
         "<robot\r\n  name=\"cad_arm\">\r\n"
         "  <link name=\"base_link\"/>\r\n  <link name=\"l1\"/>\r\n  <link name=\"l2\"/>\r\n  <link name=\"l3\"/>\r\n"
         "  <link name=\"side\"/>\r\n"
         "  <joint name=\"j1\" type=\"revolute\">\r\n    <origin xyz=\"0 0 0.2\" rpy=\"0 0 0\"/>\r\n"
         "    <parent link=\"base_link\"/>\r\n    <child link=\"l1\"/>\r\n    <axis xyz=\"0 0 1\"/>\r\n"
         "    <limit lower=\"0\" upper=\"0\" effort=\"0\" velocity=\"0\"/>\r\n  </joint>\r\n"  // line 15
         "  <joint name=\"j2\" type=\"revolute\">\r\n    <origin xyz=\"0 0 0.3\" rpy=\"1.5708 0 0\"/>\r\n"
         "    <parent link=\"l1\"/>\r\n    <child link=\"l2\"/>\r\n    <axis xyz=\"0 0 1\"/>\r\n"
         "    " +
         limit_j2 +
         "\r\n  </joint>\r\n"  // line 22
         "  <joint name=\"j3\" type=\"prismatic\">\r\n    <origin xyz=\"0.4 0 0\" rpy=\"0 0 0\"/>\r\n"
         "    <parent link=\"l2\"/>\r\n    <child link=\"l3\"/>\r\n    <axis xyz=\"1 0 0\"/>\r\n"
         "    <limit lower=\"0.0\" upper=\"-0\" effort=\"0\" velocity=\"0\"/>\r\n  </joint>\r\n"  // line 29
         "  <joint name=\"grip\" type=\"revolute\">\r\n    <parent link=\"base_link\"/>\r\n"
         "    <child link=\"side\"/>\r\n    " +
         (side.empty() ? "<limit lower=\"0\" upper=\"0\" effort=\"0\" velocity=\"0\"/>" : side) +
         "\r\n  </joint>\r\n"
         "</robot>";
}

TEST_CASE("urdf: CAD exporters' limits 0 and 0 are no limits given, with a warning naming the joint and file:line") {
  // 0 and 0 spelled three ways: both written, upper alone (lower is URDF's 0), 0.0 and -0.
  for (const std::string& limit : {std::string("<limit lower=\"0\" upper=\"0\" effort=\"0\" velocity=\"0\"/>"),
                                   std::string("<limit upper=\"0\" effort=\"10\" velocity=\"1\"/>"),
                                   std::string("<limit effort='0' lower='-0.0' velocity='0' upper='0e0'/>")}) {
    CAPTURE(limit);
    const std::string text = cad_arm(limit);
    const UrdfChain chain = parse_urdf_chain(text, "arm.urdf", {"", "l3"});
    REQUIRE(chain.joints.size() == 3);
    for (const UrdfJoint& j : chain.joints) {
      CHECK(j.lower == -std::numeric_limits<double>::infinity());
      CHECK(j.upper == std::numeric_limits<double>::infinity());
    }
    // One warning per chain joint (none for the gripper joint off the chain), each at its <limit>.
    REQUIRE(chain.warnings.size() == 3);
    CHECK(chain.warnings[0] ==
          "arm.urdf:15: joint 'j1': limits 0 and 0 read as no limits given (as CAD exporters write them); give the "
          "joint's range if it has one");
    CHECK(chain.warnings[1].starts_with("arm.urdf:22: joint 'j2': limits 0 and 0"));
    CHECK(chain.warnings[2].starts_with("arm.urdf:29: joint 'j3': limits 0 and 0"));
    // A model whose revolute joints turn freely (continuous) and whose prismatic joint is unbounded,
    // as the rest of kincal reads a joint without limits: planning samples a turn, URDF out says
    // "continuous".
    const RobotModel m = model_from_urdf(chain);
    for (const Joint& j : m.joints) CHECK((!std::isfinite(j.lower) && !std::isfinite(j.upper)));
    const std::string written = write_urdf(m);
    CHECK(written.find("name=\"j1\" type=\"continuous\"") != std::string::npos);
    CHECK(written.find("name=\"j3\" type=\"prismatic\"") != std::string::npos);
    // --original keeps the 0/0 text as it is: it is the exporter's, and only origins are written.
    const std::string out = write_calibrated_urdf(text, "arm.urdf", {"", "l3"}, perturbed(m, 5)).text;
    CHECK(origin_numbers_blanked(without_kincal_comment(out)) == origin_numbers_blanked(text));
  }
  // A range stays a range, and no warning.
  const UrdfChain ranged = parse_urdf_chain(cad_arm("<limit lower=\"-2\" upper=\"2\" effort=\"0\" velocity=\"0\"/>"),
                                            "arm.urdf", {"", "l3"});
  CHECK(ranged.joints[1].lower == -2.0);
  CHECK(ranged.warnings.size() == 2);
  // Equal limits other than 0 and 0 still cannot move: refused on the chain.
  CHECK_THROWS_WITH_AS(
      parse_urdf_chain(cad_arm("<limit lower=\"0.5\" upper=\"0.5\" effort=\"0\" velocity=\"0\"/>"), "arm.urdf"),
      "arm.urdf:22: joint 'j2': lower and upper limits are equal (0.5), so the joint cannot move: make it fixed, or "
      "give its range",
      InputError);
}

// Whether check_urdf (urdfdom) takes a text as a URDF.
bool check_urdf_takes(const std::string& name, const std::string& text) {
  return check_urdf_accepts(std::string(KINCAL_URDF_OUT_DIR) + "/structure/" + name + ".urdf", text);
}

TEST_CASE("urdf: what every URDF tool refuses is refused with file:line; what check_urdf takes, kincal takes") {
  // A two-joint arm base -> a -> b (lines 1-4), then `extra` from line 5 on.
  const auto urdf = [](const std::string& extra) {
    return "<robot name=\"r\">\n<link name=\"base\"/><link name=\"a\"/><link name=\"b\"/>\n"
           "<joint name=\"j1\" type=\"revolute\"><parent link=\"base\"/><child link=\"a\"/><limit lower=\"-1\" "
           "upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n"
           "<joint name=\"j2\" type=\"continuous\"><parent link=\"a\"/><child link=\"b\"/></joint>\n" +
           extra + "</robot>\n";
  };
  const auto fixed = [](const std::string& name, const std::string& parent, const std::string& child) {
    return "<joint name=\"" + name + "\" type=\"fixed\"><parent link=\"" + parent + "\"/><child link=\"" + child +
           "\"/></joint>\n";
  };
  struct Case {
    const char* name;
    std::string text;
    UrdfChainEnds ends;
    std::string refusal;  // the whole message
    bool check_urdf_refuses;
  };
  const std::string cd = "<link name=\"c\"/><link name=\"d\"/>\n";  // line 5
  const std::vector<Case> cases = {
      // Cycles: off the chain (urdfdom keeps the one root and takes the rest for a tree), a joint
      // that is its own link's parent, a cycle with a branch below it, a cycle through the root.
      {"cycle of two off the chain",
       urdf(cd + fixed("x1", "c", "d") + fixed("x2", "d", "c")),
       {},
       "bad.urdf:7: joint 'x2' closes a cycle of links (c <- d <- c, each the child of the next): a URDF's links form "
       "a tree",
       false},
      {"a link its own parent",
       urdf(cd + fixed("x1", "b", "c") + fixed("x2", "d", "d")),
       {},
       "bad.urdf:7: joint 'x2' closes a cycle of links (d <- d, each the child of the next): a URDF's links form a "
       "tree",
       false},
      {"cycle of three with a branch",
       urdf(cd + "<link name=\"e\"/>\n" + fixed("x1", "e", "c") + fixed("x2", "c", "d") + fixed("x3", "d", "e") +
            "<link name=\"f\"/>\n" + fixed("x4", "d", "f")),
       {"base", "b"},
       "bad.urdf:9: joint 'x3' closes a cycle of links (c <- e <- d <- c, each the child of the next): a URDF's links "
       "form a tree",
       false},
      {"cycle through the root",
       urdf(fixed("x1", "b", "base")),
       {"base", "b"},
       "bad.urdf:5: joint 'x1' closes a cycle of links (a <- base <- b <- a, each the child of the next): a URDF's "
       "links form a tree",
       true},
      // Two parents (urdfdom keeps the last one).
      {"a chain link child of a side link",
       urdf("<link name=\"c\"/>\n" + fixed("x1", "base", "c") + fixed("x2", "c", "b")),
       {},
       "bad.urdf:7: link 'b' is the child of joint 'x2' and of joint 'j2' (line 4): a link has one parent in a URDF's "
       "tree",
       false},
      {"a side link child of two side joints",
       urdf("<link name=\"c\"/>\n" + fixed("x1", "a", "c") + fixed("x2", "b", "c")),
       {},
       "bad.urdf:7: link 'c' is the child of joint 'x2' and of joint 'x1' (line 6): a link has one parent in a URDF's "
       "tree",
       false},
      {"a link child of two chain joints",
       urdf("<joint name=\"j3\" type=\"continuous\"><parent link=\"base\"/>"
            "<child link=\"b\"/></joint>\n"),
       {},
       "bad.urdf:5: link 'b' is the child of joint 'j3' and of joint 'j2' (line 4): a link has one parent in a URDF's "
       "tree",
       false},
      // Duplicate joint names.
      {"a side joint named as a chain joint",
       urdf(cd + fixed("x1", "b", "c") + fixed("j1", "c", "d")),
       {},
       "bad.urdf:7: joint 'j1' defined twice (first on line 3)",
       true},
      {"two side joints of one name",
       urdf(cd + fixed("x1", "b", "c") + fixed("x1", "b", "d")),
       {},
       "bad.urdf:7: joint 'x1' defined twice (first on line 6)",
       true},
      {"the same joint twice",
       urdf(fixed("j0", "b", "c") + "<link name=\"c\"/>\n" + fixed("j0", "b", "c")),
       {},
       "bad.urdf:7: joint 'j0' defined twice (first on line 5)",
       true},
      // Duplicate link names.
      {"a link twice, empty and with content",
       urdf("<link name=\"b\"><inertial><mass value=\"1\"/></inertial></link>\n"),
       {},
       "bad.urdf:5: link 'b' defined twice (first on line 2)",
       true},
      {"a side link twice",
       urdf(cd + fixed("x1", "b", "c") + "<link name=\"c\"></link>\n"),
       {},
       "bad.urdf:7: link 'c' defined twice (first on line 5)",
       true},
      {"the base link twice",
       urdf("<link name = 'base' />\n"),
       {"base", "b"},
       "bad.urdf:5: link 'base' defined twice (first on line 2)",
       true},
      // A second root, whichever --base-link.
      {"a stray link",
       urdf("<link name=\"c\"/>\n"),
       {"base", "b"},
       "bad.urdf:5: link 'c' is the child of no joint, as is link 'base': a URDF's links form one tree (connect it "
       "with a joint, or remove it)",
       true},
      {"a second tree",
       urdf(cd + fixed("x1", "c", "d")),
       {},
       "bad.urdf:5: link 'c' is the child of no joint, as is link 'base': a URDF's links form one tree (connect it "
       "with a joint, or remove it)",
       true},
      // No robot name; a joint type URDF does not have, off the chain.
      {"a robot without a name",
       "<robot>\n<link name=\"a\"/></robot>",
       {},
       "bad.urdf:1: <robot> without a 'name' attribute, which URDF requires",
       true},
      {"a misspelt type off the chain",
       urdf("<link name=\"c\"/>\n<joint name=\"x1\" type=\"revolut\"><parent link=\"b\"/><child link=\"c\"/>"
            "<limit lower=\"-1\" upper=\"1\" effort=\"1\" velocity=\"1\"/></joint>\n"),
       {},
       "bad.urdf:6: joint 'x1' is of type 'revolut', which URDF does not have (revolute, continuous, prismatic, fixed, "
       "floating, planar)",
       true},
  };
  for (const Case& c : cases) {
    const std::string name = c.name;
    CAPTURE(name);
    CHECK_THROWS_WITH_AS(parse_urdf_chain(c.text, "bad.urdf", c.ends), c.refusal.c_str(), InputError);
    // What check_urdf refuses, kincal refuses; a cycle or a second parent urdfdom's tree check misses.
    CHECK(check_urdf_takes(c.name, c.text) == !c.check_urdf_refuses);
  }
  // What check_urdf takes is no structure kincal refuses: odd values off the chain are not looked at.
  for (const auto& [name, extra] : std::vector<std::pair<const char*, std::string>>{
           {"equal limits off the chain",
            "<joint name=\"x1\" type=\"revolute\"><parent link=\"b\"/><child link=\"c\"/>"
            "<limit lower=\"0.5\" upper=\"0.5\" effort=\"1\" velocity=\"1\"/></joint>\n"},
           {"limits the wrong way off the chain",
            "<joint name=\"x1\" type=\"prismatic\"><parent link=\"a\"/><child link=\"c\"/>"
            "<limit lower=\"1\" upper=\"-1\" effort=\"1\" velocity=\"1\"/></joint>\n"},
           {"a zero axis off the chain",
            "<joint name=\"x1\" type=\"continuous\"><parent link=\"base\"/>"
            "<child link=\"c\"/><axis xyz=\"0 0 0\"/></joint>\n"},
           {"a floating joint off the chain",
            "<joint name=\"x1\" type=\"floating\"><parent link=\"base\"/>"
            "<child link=\"c\"/></joint>\n"}}) {
    CAPTURE(name);
    const std::string text = urdf("<link name=\"c\"/>\n" + extra);
    CHECK(check_urdf_takes(name, text));
    const UrdfChain chain = parse_urdf_chain(text, "ok.urdf", {"", "b"});
    CHECK(chain.movable_count() == 2);
    // On the chain, the same joint is refused at its own line.
    CHECK_THROWS_WITH_AS(parse_urdf_chain(text, "ok.urdf", {"", "c"}), doctest::Contains("ok.urdf:6: joint 'x1'"),
                         InputError);
  }
}
