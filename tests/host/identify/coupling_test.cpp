// Identified joint couplings (issue #41's coupled class): coupling<i>_<i-1>, joint i's share of
// its upstream neighbour's reading (model/robot_model.hpp), its name, its exact Jacobian column,
// the model selection candidate geometry+couplings on a simulated arm whose elbow reads
// J3 + k J2, and the written model as every command reads it.
#include <doctest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "host/correct/joint_correction.hpp"
#include "host/identify/identify.hpp"
#include "host/identify/model_selection.hpp"
#include "host/model/model_file.hpp"
#include "host/model/urdf.hpp"
#include "tests/host/identify/simulation.hpp"

namespace {

using namespace kincal;
using model::RobotModel;

RobotModel robot(const char* name) { return model::load_model(std::string(KINCAL_ROBOTS_DIR) + "/" + name); }

std::string error_of(const std::string& name, int joints) {
  try {
    (void)model::parse_parameter_name(name, joints);
  } catch (const model::InputError& e) {
    return e.what();
  }
  return "";
}

// The PUMA 560 whose elbow (joint 3) moves by `k` times the shoulder's (joint 2) reading beside
// its own, as a Fanuc-style J2 + J3 transmission with its ratio off; the geometry perturbed as
// a precise industrial arm's (0.2 mm, 0.02 deg), a tracker's 0.02 mm of noise.
struct CoupledArm {
  RobotModel nominal;
  simulation::ArmCase data;
};
CoupledArm coupled_arm(double k, int rows, std::uint64_t seed) {
  CoupledArm a{robot("puma560.yaml"), {}};
  sim::ErrorScale errors;
  errors.length_m = 2e-4;
  errors.angle_rad = 0.02 * std::numbers::pi / 180.0;
  a.data = simulation::simulated_arm(a.nominal, errors, 2e-5, rows, seed);
  const RobotModel plain_truth = a.data.truth;
  a.data.truth.joints[2].coupling = {0.0, k, 1.0, 0.0, 0.0, 0.0};
  // The rows again, of the coupled truth (same readings, fresh noise).
  std::mt19937_64 rng(seed + 1);
  std::vector<std::vector<double>> qs;
  for (const model::Measurement& m : a.data.train.rows) qs.push_back(m.q);
  a.data.train = simulation::measure(a.data.truth, qs, rng, 2e-5, false, 0.0, false);
  CHECK(simulation::prediction_rms(plain_truth, a.data.truth, a.data.held_out) > 1e-3);  // the coupling shows
  return a;
}

}  // namespace

TEST_CASE("coupling names: coupling<i>_<i-1> only, read back as written, bad ones refused naming why") {
  const core::ParameterId id{model::kJointCoupling, 2};
  CHECK(model::parameter_name(id) == "coupling3_2");
  const core::ParameterId back = model::parse_parameter_name("coupling3_2", 6);
  CHECK(back.kind == model::kJointCoupling);
  CHECK(back.link == 2);
  CHECK(model::is_joint_map_parameter(model::kJointCoupling));
  CHECK_FALSE(model::is_motion_parameter(model::kJointCoupling));
  CHECK(error_of("coupling3_1", 6).find("upstream neighbour's reading") != std::string::npos);
  CHECK(error_of("coupling1_0", 6).find("no upstream neighbour") != std::string::npos);
  CHECK(error_of("coupling7_6", 6).find("no upstream neighbour") != std::string::npos);
  CHECK(error_of("coupling3", 6).find("unknown parameter name") != std::string::npos);
  // Only between two revolute joints: the ARID's prismatic first joint has no coupling to joint 2.
  const RobotModel arid = robot("arid_prrr.yaml");
  CHECK_FALSE(model::can_identify_coupling(arid, 0));
  CHECK_FALSE(model::can_identify_coupling(arid, 1));
  CHECK(model::can_identify_coupling(arid, 2));
}

TEST_CASE("coupling columns: the Jacobian equals central differences, through a scale and a nominal coupling") {
  RobotModel m = robot("heavy6r.yaml");  // joint 3 = reading 2 + reading 3 (Fanuc's elbow)
  m.joints[1].scale = 1.002;             // the upstream reading's scale reaches the coupling
  for (std::size_t i = 1; i < m.joints.size(); ++i) m.joints[i].identify_coupling = true;
  const std::vector<core::ParameterId> all = model::all_parameters(m);
  std::vector<core::ParameterId> ids;
  for (const core::ParameterId& id : all)
    if (id.kind == model::kJointCoupling) ids.push_back(id);
  REQUIRE(ids.size() == 5);
  const std::vector<double> q = {0.3, -0.7, 0.9, 1.1, -0.4, 0.6};
  const Eigen::MatrixXd j = model::parameter_jacobian(m, q, ids);
  constexpr double h = 1e-6;
  for (std::size_t c = 0; c < ids.size(); ++c) {
    INFO(model::parameter_name(ids[c]));
    Eigen::VectorXd plus = Eigen::VectorXd::Zero(static_cast<Eigen::Index>(ids.size())), minus = plus;
    plus(static_cast<Eigen::Index>(c)) = h;
    minus(static_cast<Eigen::Index>(c)) = -h;
    const model::Transform a = model::forward_kinematics(model::apply_parameter_errors(m, ids, plus), q);
    const model::Transform b = model::forward_kinematics(model::apply_parameter_errors(m, ids, minus), q);
    const Eigen::Vector3d dp = (a.translation - b.translation) / (2.0 * h);
    const Eigen::Vector3d dr = identify::so3_log(a.rotation * b.rotation.transpose()) / (2.0 * h);
    CHECK((j.col(static_cast<Eigen::Index>(c)).head<3>() - dp).norm() < 1e-7);
    CHECK((j.col(static_cast<Eigen::Index>(c)).tail<3>() - dr).norm() < 1e-7);
  }
  // The change adds to the nominal row; an absent row starts from the identity row.
  const RobotModel moved = model::apply_parameter_errors(m, ids, Eigen::VectorXd::Constant(5, 0.01));
  CHECK(moved.joints[2].coupling == std::vector<double>{0.0, 1.0 + 0.01, 1.0, 0.0, 0.0, 0.0});
  CHECK(moved.joints[4].coupling == std::vector<double>{0.0, 0.0, 0.0, 0.01, 1.0, 0.0});
}

TEST_CASE("an elbow that reads J3 + k J2: geometry+couplings finds k and predicts held-out far better") {
  constexpr double k = 0.003;
  const CoupledArm arm = coupled_arm(k, 120, 41);
  const identify::Candidate couplings = identify::find_candidate(arm.nominal, {}, "geometry+couplings");
  const identify::Candidate geometry = identify::find_candidate(arm.nominal, {}, "geometry");
  const identify::IdentifyResult with = identify::identify(couplings.model, arm.data.train, couplings.options);
  const identify::IdentifyResult without = identify::identify(geometry.model, arm.data.train, geometry.options);
  // k itself, within three of its standard deviations, and that deviation far below k.
  bool found = false;
  for (std::size_t i = 0; i < with.identifiability.identified.size(); ++i) {
    if (model::parameter_name(with.identifiability.identified[i]) != "coupling3_2") continue;
    found = true;
    const auto c = static_cast<Eigen::Index>(i);
    INFO("coupling3_2 = ", with.change(c), " +- ", with.stddev(c));
    CHECK(std::abs(with.change(c) - k) < 3.0 * with.stddev(c));
    CHECK(with.stddev(c) < 0.1 * k);
  }
  CHECK(found);
  const double rms_with = simulation::prediction_rms(with.model, arm.data.truth, arm.data.held_out);
  const double rms_without = simulation::prediction_rms(without.model, arm.data.truth, arm.data.held_out);
  INFO("held-out RMS: geometry+couplings ", rms_with * 1e3, " mm, geometry ", rms_without * 1e3, " mm");
  CHECK(rms_with < 0.2 * rms_without);
  CHECK(rms_with < 5e-5);  // a few times the tracker's noise

  // Written and read back as every command reads it: the coupling row bit for bit, and the
  // record undone gives the nominal's row (joint 3's share of reading 2 back to 0).
  const RobotModel back = model::parse_model(model::write_model(with.model), "identified.yaml");
  CHECK(back.joints[2].coupling == with.model.joints[2].coupling);
  CHECK(simulation::prediction_rms(back, with.model, arm.data.held_out) < 1e-12);  // text round trip
  const RobotModel nominal = correct::nominal_from_record(back);
  REQUIRE(nominal.joints[2].coupling.size() == 6);
  CHECK(std::abs(nominal.joints[2].coupling[1]) < 1e-15);
  CHECK(nominal.joints[2].coupling[2] == 1.0);
  CHECK(model::write_urdf(back).find("<robot") != std::string::npos);
}

TEST_CASE("model selection: on the coupled elbow the data choose geometry+couplings") {
  const CoupledArm arm = coupled_arm(-0.004, 120, 7);
  const identify::Selection s = identify::select_model(arm.nominal, arm.data.train, {});
  INFO(identify::format_selection(s));
  CHECK(s.chosen.name == "geometry+couplings");
}
