// host/model: model files, datasets, kinematics and Jacobians, axes, URDF.
#include <doctest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <regex>
#include <sstream>
#include <string>

#include <Eigen/Geometry>

#include "host/model/axes.hpp"
#include "host/model/dataset.hpp"
#include "host/model/model_file.hpp"
#include "host/model/robot_model.hpp"
#include "host/model/urdf.hpp"

namespace {

using namespace kincal;
using model::RobotModel;
using model::Transform;

constexpr double kDeg = std::numbers::pi / 180.0;

std::string robot_file(const char* name) { return std::string(KINCAL_ROBOTS_DIR) + "/" + name; }

// A random chain of every convention and joint type, with a tool frame.
RobotModel random_model(std::mt19937_64& rng, int n) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  RobotModel m;
  m.name = "random";
  m.tool = model::ToolKind::frame;
  for (int i = 0; i < n; ++i) {
    model::Joint j;
    j.name = "j" + std::to_string(i + 1);
    j.type = u(rng) > -0.5 ? core::JointType::revolute : core::JointType::prismatic;
    j.convention = static_cast<core::LinkConvention>(i % 3);
    j.parameters = {0.3 * u(rng), 3.0 * u(rng), 0.4 * u(rng), 3.0 * u(rng),
                    j.convention == core::LinkConvention::doty ? 0.5 * u(rng) : 0.0};
    j.offset = 0.1 * u(rng);
    m.joints.push_back(j);
  }
  m.base_T_frame0.rotation = model::rotation_from_rpy({u(rng), u(rng), 3 * u(rng)});
  m.base_T_frame0.translation = {u(rng), u(rng), u(rng)};
  m.flange_T_tool.rotation = model::rotation_from_rpy({u(rng), u(rng), u(rng)});
  m.flange_T_tool.translation = {0.1 * u(rng), 0.1 * u(rng), 0.2 * u(rng)};
  return m;
}

std::vector<double> random_q(std::mt19937_64& rng, int n) {
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  std::vector<double> q(static_cast<std::size_t>(n));
  for (double& v : q) v = u(rng);
  return q;
}

// Forward kinematics composed from elementary Eigen transforms, independently of the core.
Eigen::Isometry3d reference_fk(const RobotModel& m, const std::vector<double>& q) {
  Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
  t.linear() = m.base_T_frame0.rotation;
  t.translation() = m.base_T_frame0.translation;
  const auto rot = [](double a, const Eigen::Vector3d& axis) { return Eigen::Isometry3d(Eigen::AngleAxisd(a, axis)); };
  const auto tr = [](const Eigen::Vector3d& v) { return Eigen::Isometry3d(Eigen::Translation3d(v)); };
  for (std::size_t i = 0; i < m.joints.size(); ++i) {
    const model::Joint& j = m.joints[i];
    const auto& p = j.parameters;
    const bool rev = j.type == core::JointType::revolute;
    const double theta = p.theta_rad + (rev ? j.offset + q[i] : 0.0);
    const double d = p.d_m + (rev ? 0.0 : j.offset + q[i]);
    const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
    switch (j.convention) {
      case core::LinkConvention::standard_dh:
        t = t * rot(theta, z) * tr(d * z) * tr(p.a_m * x) * rot(p.alpha_rad, x);
        break;
      case core::LinkConvention::modified_dh:
        t = t * rot(p.alpha_rad, x) * tr(p.a_m * x) * rot(theta, z) * tr(d * z);
        break;
      case core::LinkConvention::doty:
        t = t * tr(d * z) * rot(theta, z) * rot(p.beta_rad, y) * tr(p.a_m * x) * rot(p.alpha_rad, x);
        break;
    }
  }
  Eigen::Isometry3d tool = Eigen::Isometry3d::Identity();
  tool.linear() = m.flange_T_tool.rotation;
  tool.translation() = m.flange_T_tool.translation;
  return t * tool;
}

Eigen::Matrix<double, 6, 1> twist_difference(const Transform& to, const Transform& from) {
  Eigen::Matrix<double, 6, 1> t;
  t.head<3>() = to.translation - from.translation;
  const Eigen::AngleAxisd aa(to.rotation * from.rotation.transpose());
  t.tail<3>() = aa.angle() * aa.axis();
  return t;
}

std::string error_of(const std::string& text) {
  try {
    (void)model::parse_model(text, "m.yaml");
  } catch (const model::InputError& e) {
    return e.what();
  }
  return "no error";
}

std::string dataset_error(const std::string& text) {
  std::istringstream in(text);
  try {
    (void)model::parse_dataset(in, "d.csv");
  } catch (const model::InputError& e) {
    return e.what();
  }
  return "no error";
}

const char* kSmall = R"(name: two
angles: deg
joints:
  - {type: revolute, convention: dh, d: 0.1, theta: 0, a: 0.3, alpha: 90, limits: [-90, 90]}
  - {type: prismatic, convention: doty, d: 0, theta: 10, beta: 1, a: 0.2, alpha: 0}
tool:
  point: [0, 0, 0.05]
)";

}  // namespace

TEST_CASE("forward kinematics matches an independent composition, every convention") {
  std::mt19937_64 rng(7);
  for (int trial = 0; trial < 50; ++trial) {
    const RobotModel m = random_model(rng, 1 + trial % 8);
    const std::vector<double> q = random_q(rng, m.joint_count());
    const Transform t = model::forward_kinematics(m, q);
    const Eigen::Isometry3d r = reference_fk(m, q);
    CHECK((t.translation - r.translation()).norm() < 1e-12);
    CHECK((t.rotation - r.linear()).norm() < 1e-12);
  }
}

// The joint and parameter Jacobians of m at q against central differences of the forward
// kinematics, each column within `tolerance` (relative to the column beyond 1).
void check_jacobians(const RobotModel& m, const std::vector<double>& q, double tolerance) {
  const double h = 1e-6;
  const auto near = [&](const Eigen::Matrix<double, 6, 1>& column, const Transform& plus, const Transform& minus) {
    const Eigen::Matrix<double, 6, 1> numeric = twist_difference(plus, minus) / (2 * h);
    CHECK((column - numeric).norm() < tolerance * std::max(1.0, numeric.norm()));
  };
  const Eigen::MatrixXd jq = model::joint_jacobian(m, q);
  for (int i = 0; i < m.joint_count(); ++i) {
    std::vector<double> qp = q, qm = q;
    qp[static_cast<std::size_t>(i)] += h;
    qm[static_cast<std::size_t>(i)] -= h;
    INFO("joint ", i + 1);
    near(jq.col(i), model::forward_kinematics(m, qp), model::forward_kinematics(m, qm));
  }
  const std::vector<core::ParameterId> ids = model::all_parameters(m);
  const Eigen::MatrixXd jp = model::parameter_jacobian(m, q, ids);
  for (std::size_t k = 0; k < ids.size(); ++k) {
    Eigen::VectorXd e = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(ids.size()));
    e(static_cast<Eigen::Index>(k)) = h;
    INFO("parameter ", model::parameter_name(ids[k]));
    near(jp.col(static_cast<Eigen::Index>(k)), model::forward_kinematics(model::apply_parameter_errors(m, ids, e), q),
         model::forward_kinematics(model::apply_parameter_errors(m, ids, -e), q));
  }
}

TEST_CASE("joint and parameter Jacobians match central differences") {
  std::mt19937_64 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const RobotModel m = random_model(rng, 2 + trial % 7);
    const std::vector<double> q = random_q(rng, m.joint_count());
    INFO("trial ", trial);
    check_jacobians(m, q, 1e-8);
  }
}

// The deflection's share of each column (compliance x dG/dparameter in closed form: a link
// parameter or a joint moves the chain beyond it rigidly) against the kinematics itself:
// deflections of several degrees, so a wrong share shows far above 1e-7.
TEST_CASE("joint and parameter Jacobians with compliance, masses, a payload and gravity match central differences") {
  std::mt19937_64 rng(23);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  for (int trial = 0; trial < 20; ++trial) {
    RobotModel m = random_model(rng, 2 + trial % 7);
    for (model::Joint& j : m.joints) {
      j.mass_kg = 2.0 + u(rng);
      j.centre_of_mass_m = {0.2 * u(rng), 0.2 * u(rng), 0.2 * u(rng)};
      j.compliance = (j.type == core::JointType::revolute ? 2e-3 : 2e-4) * (1.0 + 0.5 * u(rng));
      j.identify_mass = true;
      if (u(rng) > 0.0) j.scale = 1.0 + 0.01 * u(rng);
    }
    m.payload.mass_kg = 1.5;
    m.payload.centre_of_mass_m = {0.05, -0.02, 0.1};
    m.gravity_mps2 = model::rotation_from_rpy({0.1 * u(rng), 0.1 * u(rng), 0.0}) * Eigen::Vector3d(0, 0, -9.81);
    m.identify_gravity_direction = true;
    INFO("trial ", trial);
    check_jacobians(m, random_q(rng, m.joint_count()), 1e-7);
  }
  // Named on a model without a compliance (`--params compliance2`), the deflection's parameters
  // move nothing: zero columns, as the model deflects nowhere.
  RobotModel rigid = random_model(rng, 3);
  rigid.joints[1].mass_kg = 2.0;
  const std::vector<core::ParameterId> ids = {
      {model::kJointCompliance, 1}, {model::kLinkMass, 1}, {model::kLinkCentreZ, 1}, {model::kGravityRx, 0}};
  CHECK(model::parameter_jacobian(rigid, random_q(rng, 3), ids).isZero());
}

// A calibration that moves the next axis on a body moves the frame a link's centre of mass is
// given in (frame i, at the link's far end), not the mass: it keeps its place on the body its
// joint turns, as a URDF's <inertial> in its link's frame does. theta (and d of Doty's links, before
// the motion) move the body and the mass with it.
TEST_CASE("a link's centre of mass stays on the body its joint turns when a calibration moves the next axis") {
  std::mt19937_64 rng(31);
  using K = core::ParameterKind;
  for (const core::LinkConvention convention :
       {core::LinkConvention::standard_dh, core::LinkConvention::modified_dh, core::LinkConvention::doty}) {
    RobotModel m = random_model(rng, 3);
    for (model::Joint& j : m.joints) j.type = core::JointType::revolute;
    m.joints[1].convention = convention;
    m.joints[1].parameters.beta_rad = convention == core::LinkConvention::doty ? 0.2 : 0.0;
    m.joints[1].mass_kg = 3.0;
    m.joints[1].centre_of_mass_m = {0.15, -0.1, 0.2};
    const std::vector<double> q = random_q(rng, 3);
    const auto centre = [&](const RobotModel& model) {
      return Eigen::Vector3d(model::chain_at_joints(model, q).frames.base_T_frame[2] *
                             model.joints[1].centre_of_mass_m);
    };
    const auto frame = [&](const RobotModel& model) {
      return Eigen::Vector3d(model::chain_at_joints(model, q).frames.base_T_frame[2].translation);
    };
    const std::vector<K> beyond =
        convention == core::LinkConvention::standard_dh ? std::vector<K>{K::link_d, K::link_a, K::link_alpha}
        : convention == core::LinkConvention::doty      ? std::vector<K>{K::link_beta, K::link_a, K::link_alpha}
                                                        : std::vector<K>{K::link_d};
    for (const K kind : {K::link_d, K::link_theta, K::link_a, K::link_alpha, K::link_beta}) {
      if (kind == K::link_beta && convention != core::LinkConvention::doty) continue;
      const std::vector<core::ParameterId> ids = {{kind, 1}};
      const RobotModel moved = model::apply_parameter_errors(m, ids, Eigen::VectorXd::Constant(1, 0.05));
      INFO("convention ", static_cast<int>(convention), ", parameter ", model::parameter_name(ids[0]));
      const bool stays = std::find(beyond.begin(), beyond.end(), kind) != beyond.end();
      if (stays) {
        CHECK((frame(moved) - frame(m)).norm() + (model::chain_at_joints(moved, q).frames.base_T_frame[2].rotation -
                                                  model::chain_at_joints(m, q).frames.base_T_frame[2].rotation)
                                                     .norm() >
              1e-3);                                        // the frame moved ...
        CHECK((centre(moved) - centre(m)).norm() < 1e-12);  // ... the mass did not
      } else {
        CHECK((centre(moved) - centre(m)).norm() > 1e-3);  // the body and its mass moved
      }
      // Undone, the centre comes back where it was given.
      const RobotModel back = model::apply_parameter_errors(moved, ids, Eigen::VectorXd::Constant(1, -0.05));
      CHECK((back.joints[1].centre_of_mass_m - m.joints[1].centre_of_mass_m).norm() < 1e-12);
    }
  }
}

TEST_CASE("model files: read, write, read back") {
  const RobotModel m = model::parse_model(kSmall, "small.yaml");
  REQUIRE(m.joint_count() == 2);
  CHECK(m.joints[0].parameters.alpha_rad == doctest::Approx(std::numbers::pi / 2));
  CHECK(m.joints[0].lower == doctest::Approx(-90 * kDeg));
  CHECK(m.joints[1].type == core::JointType::prismatic);
  CHECK(m.joints[1].parameters.beta_rad == doctest::Approx(kDeg));
  CHECK(m.tool == model::ToolKind::point);
  const RobotModel back = model::parse_model(model::write_model(m), "back.yaml");
  CHECK(back.joints[1].parameters.theta_rad == doctest::Approx(m.joints[1].parameters.theta_rad).epsilon(1e-15));

  // Radians: bit for bit, including a calibration record.
  std::mt19937_64 rng(3);
  RobotModel r = random_model(rng, 6);
  r.calibration = model::CalibrationRecord{"full",
                                           "meas.csv",
                                           12,
                                           1e-4,
                                           {{"theta2", 1e-3, 2e-5}},
                                           {"theta1"},
                                           2e-4,
                                           std::vector<std::array<double, 2>>(6, {-1.0 / 3.0, 0.1}),
                                           {},
                                           std::nullopt,
                                           std::nullopt};
  const RobotModel rb = model::parse_model(model::write_model(r), "r.yaml");
  for (int i = 0; i < 6; ++i) {
    const auto& a = r.joints[static_cast<std::size_t>(i)];
    const auto& b = rb.joints[static_cast<std::size_t>(i)];
    CHECK(a.parameters.d_m == b.parameters.d_m);
    CHECK(a.parameters.theta_rad == b.parameters.theta_rad);
    CHECK(a.parameters.a_m == b.parameters.a_m);
    CHECK(a.parameters.alpha_rad == b.parameters.alpha_rad);
    CHECK(a.parameters.beta_rad == b.parameters.beta_rad);
    CHECK(a.offset == b.offset);
    CHECK(a.convention == b.convention);
  }
  const std::vector<double> q = random_q(rng, 6);
  CHECK((model::forward_kinematics(r, q).translation - model::forward_kinematics(rb, q).translation).norm() < 1e-14);
  REQUIRE(rb.calibration.has_value());
  CHECK(rb.calibration->parameters.at(0).name == "theta2");
  CHECK(rb.calibration->validation_rms_m.value() == 2e-4);
  CHECK(rb.calibration->reading_ranges == r.calibration->reading_ranges);
  CHECK(rb.calibration->correlations.empty());
  CHECK_FALSE(rb.calibration->model_error_m);

  // The correlations and the model error read back bit for bit.
  r.calibration->parameters = {{"theta2", 1e-3, 2e-5}, {"d3", -1e-4, 1e-6}, {"a4", 2e-4, 3e-6}};
  r.calibration->correlations = {{-1.0 / 3.0}, {0.1, -0.7}};
  r.calibration->model_error_m = 1.0 / 7.0 * 1e-3;
  r.calibration->model_error_rad = 0.25;
  const RobotModel rc = model::parse_model(model::write_model(r), "r.yaml");
  CHECK(rc.calibration->correlations == r.calibration->correlations);
  CHECK(rc.calibration->model_error_m == r.calibration->model_error_m);
  CHECK(rc.calibration->model_error_rad == r.calibration->model_error_rad);
  // What the record's reader refuses: rows not one per parameter after the first, a row of the
  // wrong length, a correlation past one, a parameter named twice, a negative model error.
  const std::string text = model::write_model(r);
  const auto refused = [&](const std::string& from, const std::string& to) {
    const std::size_t at = text.find(from);
    REQUIRE(at != std::string::npos);
    std::string changed = text;
    changed.replace(at, from.size(), to);
    try {
      (void)model::parse_model(changed, "r.yaml");
    } catch (const model::InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  CHECK(refused("- [0.1, -0.7]", "").find("one row per parameter after the first (2)") != std::string::npos);
  CHECK(refused("[0.1, -0.7]", "[0.1]").find("row 2 must list 2 correlations") != std::string::npos);
  CHECK(refused("-0.7", "-1.2").find("(a correlation)") != std::string::npos);
  CHECK(refused("name: d3", "name: theta2").find("'theta2' named twice") != std::string::npos);
  CHECK(refused("model_error_rad: 0.25", "model_error_rad: -0.25").find("model_error_rad") != std::string::npos);

  for (const char* name : {"puma560.yaml", "ur5.yaml", "stanford_rrp.yaml", "arid_prrr.yaml"})
    CHECK(model::load_model(robot_file(name)).joint_count() >= 3);
}

TEST_CASE("model files: errors name the place and the problem") {
  std::string s = kSmall;
  const std::string convention = error_of(std::regex_replace(s, std::regex("convention: dh"), "convention: dhx"));
  CHECK(convention.find("m.yaml:4:") == 0);
  CHECK(convention.find(": joint 1: unknown convention 'dhx' (expected dh, mdh or doty)") != std::string::npos);
  CHECK(error_of(std::regex_replace(s, std::regex("type: prismatic"), "type: spherical"))
            .find("joint 2: unknown joint type 'spherical'") != std::string::npos);
  CHECK(error_of(std::regex_replace(s, std::regex("alpha: 90"), "alfa: 90")).find("unknown key 'alfa'") !=
        std::string::npos);
  CHECK(error_of(std::regex_replace(s, std::regex("a: 0.3"), "a: 0.3x")).find("m.yaml:4:") == 0);
  CHECK(error_of(std::regex_replace(s, std::regex("beta: 1, "), "")) == "no error");
  CHECK(error_of(std::regex_replace(s, std::regex("convention: dh, d: 0.1"), "convention: dh, beta: 2, d: 0.1"))
            .find("beta belongs to the doty convention") != std::string::npos);
  CHECK(error_of(std::regex_replace(s, std::regex("\\[-90, 90\\]"), "[90, -90]")).find("lower limit") !=
        std::string::npos);
  CHECK(error_of("name: x\njoints: [\n").find("m.yaml:") == 0);
  CHECK(error_of("name: x\n").find("no 'joints'") != std::string::npos);
  std::string nine = "joints:\n";
  for (int i = 0; i < 9; ++i) nine += "  - {type: revolute, convention: dh, d: 0, theta: 0, a: 0, alpha: 0}\n";
  CHECK(error_of(nine).find("9 joints; at most 8") != std::string::npos);
  CHECK(error_of(std::regex_replace(s, std::regex("theta: 0, "), "")).find("missing parameter 'theta'") !=
        std::string::npos);
}

TEST_CASE("datasets: read, write, read back, and malformed rows") {
  const std::string good =
      "# a comment\nq1,q2,x,y,z,qw,qx,qy,qz,cxx,cxy,cxz,cyy,cyz,czz\n"
      "0.1,0.2,1,2,3,1,0,0,0,1e-6,0,0,1e-6,0,4e-6\n\n"
      "0.3,-0.2,1.5,2,3,0.7071067811865476,0.7071067811865476,0,0,1e-6,1e-7,0,1e-6,0,4e-6\n";
  std::istringstream in(good);
  const model::Dataset d = model::parse_dataset(in, "d.csv");
  REQUIRE(d.rows.size() == 2);
  CHECK(d.joint_count == 2);
  CHECK(d.has_orientation);
  CHECK(d.noise == model::NoiseColumns::covariance);
  CHECK(d.rows[1].line == 5);
  CHECK((*d.rows[1].covariance)(1, 0) == 1e-7);
  std::ostringstream out;
  model::write_dataset(out, d);
  std::istringstream back_in(out.str());
  const model::Dataset back = model::parse_dataset(back_in, "back.csv");
  CHECK(back.rows[1].position == d.rows[1].position);
  CHECK(*back.rows[1].covariance == *d.rows[1].covariance);

  CHECK(dataset_error("q1,x,y,z\n0,1,2\n") == "d.csv:2: expected 4 fields as in the header, found 3");
  CHECK(dataset_error("q1,x,y,z\n0,1,2,abc\n") == "d.csv:2: column z: 'abc' is not a number");
  CHECK(dataset_error("q1,x,y,z\n0,1,,3\n") == "d.csv:2: column y is empty");
  CHECK(dataset_error("q1,x,y,w\n") == "d.csv:1: header: unknown column 'w'");
  CHECK(dataset_error("q1,x,y\n") == "d.csv:1: header: missing column 'z'");
  CHECK(dataset_error("x,y,z\n") == "d.csv:1: header: no joint columns (expected q1, q2, ...)");
  CHECK(dataset_error("q1,q3,x,y,z\n") == "d.csv:1: header: column 'q3' but no q2");
  CHECK(dataset_error("q1,x,y,z,qw,qx\n") == "d.csv:1: header: an orientation needs all of qw, qx, qy, qz");
  CHECK(dataset_error("q1,x,y,z,qw,qx,qy,qz\n0,1,2,3,1,1,0,0\n").find("d.csv:2: the quaternion") == 0);
  CHECK(dataset_error("q1,x,y,z,sigma\n0,1,2,3,0\n") == "d.csv:2: sigma must be positive");
  CHECK(dataset_error("q1,x,y,z,cxx,cxy,cxz,cyy,cyz,czz\n0,1,2,3,1,2,0,1,0,1\n") ==
        "d.csv:2: the covariance (cxx..czz) is not positive definite");
  CHECK(dataset_error("") == "d.csv:0: no header row (expected q1,...,qN,x,y,z)");
  CHECK(dataset_error("q1,x,y,z\n0,1,2,inf\n") == "d.csv:2: column z is not finite");

  // At most kMaxRows data rows, in datasets and joints files alike; blank and comment lines do not count.
  std::string rows = "# a comment\nq1,x,y,z\n\n";
  for (std::size_t i = 0; i < model::kMaxRows; ++i) rows += "0,1,2,3\n";
  std::istringstream full(rows);
  CHECK(model::parse_dataset(full, "d.csv").rows.size() == model::kMaxRows);
  rows += "# the last one\n0,1,2,3\n";
  const std::string past = "d.csv:" + std::to_string(model::kMaxRows + 5) + ": " + model::too_many_rows();
  CHECK(dataset_error(rows) == past);
  std::istringstream joints(rows);
  CHECK_THROWS_WITH_AS(model::parse_joints(joints, "d.csv"), past.c_str(), model::InputError);
  CHECK(model::too_many_rows().starts_with("more than 100000 data rows"));
}

TEST_CASE("axes to chain reproduces the kinematics of any model") {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 40; ++trial) {
    RobotModel m = random_model(rng, 2 + trial % 7);
    // Now and then a pair of exactly parallel or intersecting axes.
    if (trial % 4 == 1 && m.joints[0].convention != core::LinkConvention::modified_dh) {
      m.joints[0].parameters.alpha_rad = 0.0;
      m.joints[0].parameters.beta_rad = 0.0;
    }
    if (trial % 4 == 2) m.joints[0].parameters.a_m = 0.0;
    const std::vector<double> home = random_q(rng, m.joint_count());
    const std::vector<model::AxisLine> axes = model::joint_axes(m, home);
    const RobotModel c = model::chain_from_axes(m, axes, home, model::forward_kinematics(m, home));
    for (int k = 0; k < 5; ++k) {
      const std::vector<double> q = random_q(rng, m.joint_count());
      const Transform a = model::forward_kinematics(m, q), b = model::forward_kinematics(c, q);
      INFO("trial ", trial);
      CHECK((a.translation - b.translation).norm() < 1e-9);
      CHECK((a.rotation - b.rotation).norm() < 1e-9);
    }
    for (const model::Joint& j : c.joints) CHECK(j.convention != core::LinkConvention::modified_dh);
  }
}

TEST_CASE("URDF: composing the joint origins gives the model's tool pose") {
  std::mt19937_64 rng(9);
  for (int trial = 0; trial < 10; ++trial) {
    RobotModel m = random_model(rng, 1 + trial % 8);
    m.joints[0].lower = -1.0;
    m.joints[0].upper = 1.0;
    const std::string urdf = model::write_urdf(m);
    // Parse the origins and axes back with a regular expression and compose them.
    const std::regex joint_re(
        "<joint name=\"[^\"]*\" type=\"(\\w+)\">[\\s\\S]*?<origin xyz=\"(\\S+) (\\S+) (\\S+)\" rpy=\"(\\S+) (\\S+) "
        "(\\S+)\"/>");
    const std::vector<double> q = random_q(rng, m.joint_count());
    Eigen::Isometry3d t = Eigen::Isometry3d::Identity();
    std::size_t k = 0;
    for (auto it = std::sregex_iterator(urdf.begin(), urdf.end(), joint_re); it != std::sregex_iterator(); ++it) {
      const std::smatch& mm = *it;
      const Eigen::Vector3d xyz(std::stod(mm[2]), std::stod(mm[3]), std::stod(mm[4]));
      const Eigen::Matrix3d r = (Eigen::AngleAxisd(std::stod(mm[7]), Eigen::Vector3d::UnitZ()) *
                                 Eigen::AngleAxisd(std::stod(mm[6]), Eigen::Vector3d::UnitY()) *
                                 Eigen::AngleAxisd(std::stod(mm[5]), Eigen::Vector3d::UnitX()))
                                    .toRotationMatrix();
      Eigen::Isometry3d o = Eigen::Isometry3d::Identity();
      o.linear() = r;
      o.translation() = xyz;
      t = t * o;
      const std::string type = mm[1];
      if (type == "fixed") continue;
      const double v = q.at(k++);
      if (type == "prismatic") {
        t = t * Eigen::Translation3d(0, 0, v);
      } else {
        t = t * Eigen::AngleAxisd(v, Eigen::Vector3d::UnitZ());
      }
    }
    CHECK(k == static_cast<std::size_t>(m.joint_count()));
    const Transform f = model::forward_kinematics(m, q);
    CHECK((f.translation - t.translation()).norm() < 1e-12);
    CHECK((f.rotation - t.linear()).norm() < 1e-12);
    CHECK(urdf.find("<calibration") == std::string::npos);
  }
}

// Issue #44: every value of a model file means something or is refused naming its place.
TEST_CASE("model files: names unique, angles in their unit, every number in its physical range") {
  const std::string s = kSmall;
  const auto with = [&](const char* from, const char* to) {
    return error_of(std::regex_replace(s, std::regex(from), to));
  };
  const auto refused = [](const std::string& error, const std::string& place, const std::string& what) {
    INFO(error);
    CHECK(error.starts_with(place));
    CHECK(error.find(what) != std::string::npos);
  };
  // Two joints of one name, given or a given name equal to another's default j<i>: both named.
  const std::string named = std::regex_replace(s, std::regex("type: revolute"), "name: arm, type: revolute");
  refused(error_of(std::regex_replace(named, std::regex("type: prismatic"), "name: arm, type: prismatic")),
          "m.yaml:5:", "joint 2's name 'arm' is joint 1's name too (line 4)");
  refused(with("type: revolute", "name: j2, type: revolute"), "m.yaml:5:", "joint 2's name 'j2' is joint 1's name too");
  // Degrees without 'angles: deg': alpha 90 in radians is 14 turns.
  refused(with("angles: deg\n", ""), "m.yaml:3:",
          "joint 1 alpha: 90 rad is more than a turn: are the file's angles "
          "degrees? then say 'angles: deg'");
  refused(with("angles: deg\n", "angles: rad\n"), "m.yaml:4:", "say 'angles: deg'");
  refused(with("theta: 10", "theta: 400"), "m.yaml:5:", "joint 2 theta: 400 deg is more than a turn");
  refused(with("\\[-90, 90\\]", "[-9000, 90]"), "m.yaml:4:", "joint 1 lower limit: -9000 deg is more than 8 turns");
  CHECK(with("\\[-90, 90\\]", "[-720, 720]") == "no error");  // a wrist's two turns either way
  // Lengths: metres, at most 100 m (a length in millimetres is refused).
  refused(with("d: 0.1", "d: 100.5"),
          "m.yaml:4:", "joint 1 d: 100.5 is outside [-100, 100] (m: is it in millimetres?)");
  refused(with("point: \\[0, 0, 0.05\\]", "point: [0, 0, 150]"), "m.yaml:7:", "tool point: 150 is outside");
  // Scale near 1, masses and compliances physically possible.
  refused(with("alpha: 0\\}", "alpha: 0, scale: 57.2958}"), "m.yaml:5:", "joint 2 scale: 57.2958 is outside [0.5, 2]");
  refused(with("alpha: 0\\}", "alpha: 0, scale: 1e300}"), "m.yaml:5:", "scale: 1e300 is outside");
  CHECK(with("alpha: 0\\}", "alpha: 0, scale: 1.02}") == "no error");
  refused(with("alpha: 0\\}", "alpha: 0, mass: 1e300}"), "m.yaml:5:", "joint 2 mass: 1e300 kg is more than 1e+05 kg");
  refused(with("alpha: 0\\}", "alpha: 0, mass: 3, compliance: 5}"),
          "m.yaml:5:", "joint 2 compliance: 5 is outside [0, 1] (m/N: 1 N would move the joint by a metre)");
  // A compliance with no mass to carry can do nothing; on a prismatic joint that carries one it
  // is a deflection in m/N along the axis, which the model evaluates.
  refused(with("alpha: 0\\}", "alpha: 0, compliance: 1e-6}"),
          "m.yaml:5:", "joint 2 compliance: neither the links this joint moves nor a payload have a mass");
  refused(with("alpha: 90, ", "alpha: 90, compliance: 1e-6, "), "m.yaml:4:", "joint 1 compliance: neither");
  CHECK(with("alpha: 0\\}", "alpha: 0, mass: 3, compliance: 1e-6}") == "no error");
  CHECK(error_of(s + "payload: {mass: 2}\n") == "no error");
  CHECK(error_of(std::regex_replace(s, std::regex("alpha: 90, "), "alpha: 90, compliance: 1e-6, ") +
                 "payload: {mass: 2}\n") == "no error");
  refused(error_of(s + "gravity: [0, 0, -9806.65]\n"), "m.yaml:8:", "gravity: 9806.65 m/s^2 is more than");
  refused(error_of(s + "priors: {a1: 0.001, a01: 0.002}\n"),
          "m.yaml:8:", "priors: 'a01' names the parameter that 'a1' (line 8) names");
  refused(error_of(s + "calibration: {measurements: 1e300}\n"), "m.yaml:8:", "measurements: 1e300 is outside");
  // Every robot the project ships still reads.
  for (const char* name :
       {"puma560.yaml", "ur5.yaml", "ur10.yaml", "stanford_rrp.yaml", "arid_prrr.yaml", "heavy6r.yaml"})
    CHECK(model::load_model(robot_file(name)).joint_count() >= 3);
}
