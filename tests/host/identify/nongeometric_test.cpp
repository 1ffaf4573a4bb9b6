// Non-geometric parameters (issue #12): joint coupling, scale and gravity compliance in the
// model, its file, its Jacobians and identification, and the simulator's imperfect robots.
#include <doctest.h>

#include <cmath>
#include <random>
#include <string>

#include "host/identify/identify.hpp"
#include "host/model/model_file.hpp"
#include "tests/host/identify/simulation.hpp"

namespace {

using namespace kincal;
using model::RobotModel;
using model::Transform;

RobotModel robot(const char* name) { return model::load_model(std::string(KINCAL_ROBOTS_DIR) + "/" + name); }

Eigen::Matrix<double, 6, 1> twist_difference(const Transform& a, const Transform& b) {
  Eigen::Matrix<double, 6, 1> t;
  t.head<3>() = a.translation - b.translation;
  t.tail<3>() = identify::so3_log(a.rotation * b.rotation.transpose());
  return t;
}

// The heavy arm without its joint map: the same geometry, masses and payload.
RobotModel plain(RobotModel m) {
  for (model::Joint& j : m.joints) {
    j.coupling.clear();
    j.scale.reset();
    j.compliance.reset();
  }
  return m;
}

// The heavy arm with a scale on joint 2 and compliances of a real arm's size.
RobotModel heavy_with_map() {
  RobotModel m = robot("heavy6r.yaml");
  m.joints[1].scale = 1.0007;
  for (model::Joint& j : m.joints) j.compliance = 1.5e-7;
  return m;
}

}  // namespace

TEST_CASE("coupling and scale: forward kinematics equals the plain chain's at the rewritten readings") {
  const RobotModel m = heavy_with_map();
  RobotModel no_compliance = m;
  for (model::Joint& j : no_compliance.joints) j.compliance.reset();
  const RobotModel p = plain(m);
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 20; ++trial) {
    const std::vector<double> r = sim::random_configuration(m, rng);
    std::vector<double> v = r;
    v[1] = 1.0007 * r[1];
    v[2] = v[1] + r[2];  // Fanuc's elbow: J2 + J3
    CHECK(
        (model::forward_kinematics(no_compliance, r).translation - model::forward_kinematics(p, v).translation).norm() <
        1e-13);
  }
  // No joint map: the very same bits as the core's chain.
  const RobotModel puma = robot("puma560.yaml");
  const std::vector<double> q = sim::random_configuration(puma, rng);
  CHECK(model::forward_kinematics(puma, q).translation ==
        core::forward_kinematics(model::to_chain(puma), model::joint_vector(q)).translation);
}

TEST_CASE("gravity deflection: compliance times the derivative of the gravity potential") {
  const RobotModel m = heavy_with_map();
  const RobotModel p = plain(m);
  std::mt19937_64 rng(6);
  // sum of m g . c over the bodies, for chain variables v.
  const auto potential = [&](const core::JointVector<double>& v) {
    core::PreparedChain<double> chain;
    core::prepare_chain(model::to_chain(p), chain);
    std::array<core::SinCos<double>, core::kMaxJoints> trig{};
    core::ChainFrames<double> frames;
    core::joint_trig(chain, v, trig);
    core::forward_kinematics(chain, v, trig, frames);
    const Eigen::Vector3d g = p.base_T_frame0.rotation * p.gravity_mps2;
    double sum = p.payload.mass_kg * g.dot(frames.base_T_frame[6] * p.payload.centre_of_mass_m);
    for (std::size_t b = 0; b < 6; ++b)
      sum += p.joints[b].mass_kg * g.dot(frames.base_T_frame[b + 1] * p.joints[b].centre_of_mass_m);
    return sum;
  };
  for (int trial = 0; trial < 10; ++trial) {
    const std::vector<double> r = sim::random_configuration(m, rng);
    const model::ChainAtJoints at = model::chain_at_joints(m, r);
    const core::JointVector<double> g = model::gravity_forces(m, at.chain, at.coupled);
    for (int i = 0; i < 6; ++i) {
      core::JointVector<double> plus = at.coupled, minus = at.coupled;
      plus(i) += 1e-6;
      minus(i) -= 1e-6;
      CHECK(g(i) == doctest::Approx((potential(plus) - potential(minus)) / 2e-6).epsilon(1e-6).scale(1.0));
      CHECK(at.q(i) - at.coupled(i) == doctest::Approx(1.5e-7 * g(i)).epsilon(1e-12));
    }
    CHECK(std::abs(g(0)) < 1e-9);  // the waist's axis is along gravity
  }
}

TEST_CASE("Jacobians through the joint map match central differences") {
  const RobotModel m = heavy_with_map();
  std::mt19937_64 rng(7);
  const double h = 1e-6;
  for (int trial = 0; trial < 5; ++trial) {
    const std::vector<double> q = sim::random_configuration(m, rng);
    const Eigen::MatrixXd jq = model::joint_jacobian(m, q);
    for (std::size_t i = 0; i < q.size(); ++i) {
      std::vector<double> qp = q, qm = q;
      qp[i] += h;
      qm[i] -= h;
      CHECK((jq.col(static_cast<Eigen::Index>(i)) -
             twist_difference(model::forward_kinematics(m, qp), model::forward_kinematics(m, qm)) / (2 * h))
                .norm() < 1e-8);
    }
  }
  // The identification's Jacobian away from zero, every parameter of the model.
  const identify::ParameterIds ids = model::all_parameters(m);
  identify::Parameterization p(m, ids);
  std::vector<double> delta(ids.size());
  std::normal_distribution<double> u(0.0, 0.01);
  for (std::size_t k = 0; k < ids.size(); ++k)
    delta[k] = u(rng) * (ids[k].kind == model::kJointCompliance ? 1e-5 : 1.0);
  p.set(delta);
  const std::vector<double> q = sim::random_configuration(m, rng);
  Eigen::MatrixXd j;
  (void)p.pose(q, &j);
  for (std::size_t k = 0; k < ids.size(); ++k) {
    const double step = ids[k].kind == model::kJointCompliance ? 1e-9 : h;
    std::vector<double> plus = delta, minus = delta;
    plus[k] += step;
    minus[k] -= step;
    p.set(plus);
    const Transform a = p.pose(q, nullptr);
    p.set(minus);
    const Transform b = p.pose(q, nullptr);
    const Eigen::Matrix<double, 6, 1> numeric = twist_difference(a, b) / (2 * step);
    INFO(model::parameter_name(ids[k]));
    CHECK((j.col(static_cast<Eigen::Index>(k)) - numeric).norm() < 1e-7 * std::max(1.0, numeric.norm()));
  }
}

TEST_CASE("model files: coupling, scale, compliance, masses, payload and gravity read back bit for bit") {
  RobotModel m = heavy_with_map();
  m.file_angles = model::AngleUnit::rad;
  m.gravity_mps2 = {0.1, 0.2, -9.8};
  const RobotModel back = model::parse_model(model::write_model(m), "back.yaml");
  for (std::size_t i = 0; i < m.joints.size(); ++i) {
    CHECK(back.joints[i].coupling == m.joints[i].coupling);
    CHECK(back.joints[i].scale == m.joints[i].scale);
    CHECK(back.joints[i].compliance == m.joints[i].compliance);
    CHECK(back.joints[i].mass_kg == m.joints[i].mass_kg);
    CHECK(back.joints[i].centre_of_mass_m == m.joints[i].centre_of_mass_m);
  }
  CHECK(back.payload.mass_kg == m.payload.mass_kg);
  CHECK(back.payload.centre_of_mass_m == m.payload.centre_of_mass_m);
  CHECK(back.gravity_mps2 == m.gravity_mps2);
  const std::vector<double> q{0.1, 0.2, -0.3, 0.4, 0.5, 0.6};
  CHECK(model::forward_kinematics(back, q).translation == model::forward_kinematics(m, q).translation);
  // A model without them writes none of the new keys.
  const std::string puma = model::write_model(robot("puma560.yaml"));
  for (const char* key : {"coupling", "scale", "compliance", "mass", "gravity", "payload"})
    CHECK(puma.find(key) == std::string::npos);

  const auto error_of = [](const std::string& text) {
    try {
      (void)model::parse_model(text, "m.yaml");
    } catch (const model::InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  const std::string head = "joints:\n  - {type: revolute, convention: dh, d: 0, theta: 0, a: 1, alpha: 0";
  const std::string second = "\n  - {type: revolute, convention: dh, d: 0, theta: 0, a: 1, alpha: 0";
  CHECK(error_of(head + ", coupling: [1]}" + second + "}\n").find("m.yaml:2:") == 0);
  CHECK(error_of(head + ", coupling: [1]}" + second + "}\n").find("coupling must be a list of 2") != std::string::npos);
  CHECK(error_of(head + ", coupling: [1, 1]}" + second + ", coupling: [2, 2]}\n").find("linearly dependent") !=
        std::string::npos);
  CHECK(error_of(head + ", scale: 0}" + second + "}\n").find("scale must be positive") != std::string::npos);
  CHECK(error_of(head + ", mass: -1}" + second + "}\n").find("mass must not be negative") != std::string::npos);
  CHECK(error_of(head + "}" + second + "}\npayload: {mass: 1, com: [0, 0, 0]}\n").find("unknown key 'com'") !=
        std::string::npos);
  CHECK(model::parse_parameter_name("compliance3", 6).kind == model::kJointCompliance);
  CHECK(model::parameter_name({model::kJointScale, 1}) == "scale2");
}

TEST_CASE("scale and compliance identified on simulated data recover the truth within their stddevs") {
  RobotModel nominal = robot("heavy6r.yaml");
  nominal.joints[1].scale = 1.0;
  std::mt19937_64 rng(8);
  sim::ErrorScale errors;
  errors.scale_sigma = 3e-4;
  RobotModel truth = sim::perturbed(nominal, rng, errors);
  for (std::size_t i = 0; i < truth.joints.size(); ++i) truth.joints[i].compliance = (i == 1 || i == 2) ? 2e-7 : 5e-8;
  const auto qs = sim::random_configurations(nominal, 80, rng);
  const model::Dataset data = simulation::measure(truth, qs, rng, 2e-5, false, 0.0, true);
  identify::IdentifyOptions options;
  const identify::IdentifyResult r = identify::identify(nominal, data, options);
  const std::string report = identify::format_report(r);
  CHECK(report.find("compliance2") != std::string::npos);
  CHECK(report.find("urad/Nm") != std::string::npos);
  CHECK(report.find("scale2") != std::string::npos);
  int checked = 0;
  for (std::size_t k = 0; k < r.identifiability.identified.size(); ++k) {
    const core::ParameterId id = r.identifiability.identified[k];
    if (!model::is_joint_map_parameter(id.kind)) continue;
    const model::Joint& t = truth.joints[id.link];
    const model::Joint& n = nominal.joints[id.link];
    const double true_change = id.kind == model::kJointScale ? *t.scale - *n.scale : *t.compliance - *n.compliance;
    const auto i = static_cast<Eigen::Index>(k);
    INFO(model::parameter_name(id), " change ", r.change(i), " truth ", true_change, " stddev ", r.stddev(i));
    ++checked;
    if (r.at_bound[k]) {  // the noise drove it onto its bound (a compliance of 0), which holds it: no stddev
      CHECK(r.model.joints[id.link].compliance.value_or(-1.0) == 0.0);
      CHECK(r.stddev(i) == 0.0);
      CHECK(std::abs(true_change) < 0.5 * 2e-7);  // a small truth, not joint 2's or 3's
      continue;
    }
    CHECK(std::abs(r.change(i) - true_change) < 3.0 * r.stddev(i));
    if (id.kind == model::kJointScale || id.link == 1 || id.link == 2) CHECK(r.stddev(i) < 0.1 * std::abs(true_change));
  }
  CHECK(checked == 5);  // scale2 and the compliances of joints 2..5
  // No torque on the waist (axis along gravity) nor on joint 6 (the payload on its axis).
  std::string held;
  for (const identify::HeldFixed& h : r.identifiability.held_fixed) held += model::parameter_name(h.id) + " ";
  CHECK(held.find("compliance1 ") != std::string::npos);
  CHECK(held.find("compliance6 ") != std::string::npos);
}

TEST_CASE("simulated robots: imperfections sag, and each visit has its own repeatability error") {
  const RobotModel nominal = robot("puma560.yaml");
  const sim::Imperfections imperfect = sim::typical_imperfections(0.9);
  const sim::SimulatedRobot exact(nominal, 3), real(nominal, 3, {}, imperfect);
  std::mt19937_64 rng(9);
  const std::vector<double> q = sim::random_configuration(nominal, rng);
  const double sag = (exact.tool_pose(q).translation - real.tool_pose(q).translation).norm();
  CHECK(sag > 1e-5);
  CHECK(sag < 1e-3);
  CHECK(real.visit_pose(q, 4).translation == real.visit_pose(q, 4).translation);
  double sum2 = 0.0;
  for (std::uint64_t visit = 0; visit < 200; ++visit)
    sum2 += (real.visit_pose(q, visit).translation - real.tool_pose(q).translation).squaredNorm();
  const double rms = std::sqrt(sum2 / 200);
  CHECK(rms > imperfect.position_jitter_m);
  CHECK(rms < 10 * imperfect.position_jitter_m + 2 * imperfect.joint_repeatability_rad);
  CHECK(exact.visit_pose(q, 4).translation == exact.tool_pose(q).translation);
}
