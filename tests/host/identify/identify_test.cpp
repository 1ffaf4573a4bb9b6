// host/identify: statistics, the exact Jacobian, identifiability, recovery of known errors by
// every method, and the errors for bad requests and degenerate data.
#include <doctest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "host/identify/cpa.hpp"
#include "host/identify/identify.hpp"
#include "host/identify/plan.hpp"
#include "host/identify/statistics.hpp"
#include "host/model/model_file.hpp"
#include "tests/host/identify/simulation.hpp"
#include "tests/host/model/ur10_realdata.hpp"

namespace {

using namespace kincal;
using model::RobotModel;

RobotModel robot(const char* name) { return model::load_model(std::string(KINCAL_ROBOTS_DIR) + "/" + name); }

std::string error_of(const RobotModel& m, const model::Dataset& d, const identify::IdentifyOptions& o) {
  try {
    (void)identify::identify(m, d, o);
  } catch (const model::InputError& e) {
    return e.what();
  }
  return "no error";
}

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

using simulation::sweeps;

}  // namespace

TEST_CASE("chi-square and F distributions against tabulated values") {
  CHECK(identify::chi_square_quantile(0.999, 3) == doctest::Approx(16.266).epsilon(1e-4));
  CHECK(identify::chi_square_quantile(0.95, 1) == doctest::Approx(3.841).epsilon(1e-3));
  CHECK(identify::chi_square_quantile(0.5, 6) == doctest::Approx(5.348).epsilon(1e-3));
  CHECK(identify::chi_square_quantile(0.99, 30) == doctest::Approx(50.892).epsilon(1e-4));
  CHECK(identify::fisher_cdf(3.708, 3, 10) == doctest::Approx(0.95).epsilon(1e-3));
  CHECK(identify::fisher_cdf(4.938, 3, 21) == doctest::Approx(0.99).epsilon(1e-3));
  CHECK(identify::median({3, 1, 2}) == 2.0);
}

TEST_CASE("the identification Jacobian is exact away from zero, base and tool rotations included") {
  std::mt19937_64 rng(1);
  const RobotModel m = robot("puma560.yaml");
  const identify::ParameterIds ids = model::all_parameters(m);
  identify::Parameterization p(m, ids);
  std::vector<double> delta(ids.size());
  std::normal_distribution<double> u(0.0, 0.2);
  for (double& d : delta) d = u(rng);
  p.set(delta);
  const std::vector<double> q = sim::random_configuration(m, rng);
  Eigen::MatrixXd j;
  const model::Transform t0 = p.pose(q, &j);
  (void)t0;
  const double h = 1e-6;
  for (std::size_t k = 0; k < ids.size(); ++k) {
    std::vector<double> plus = delta, minus = delta;
    plus[k] += h;
    minus[k] -= h;
    p.set(plus);
    const model::Transform a = p.pose(q, nullptr);
    p.set(minus);
    const model::Transform b = p.pose(q, nullptr);
    Eigen::Matrix<double, 6, 1> numeric;
    numeric.head<3>() = (a.translation - b.translation) / (2 * h);
    numeric.tail<3>() = identify::so3_log(a.rotation * b.rotation.transpose()) / (2 * h);
    INFO(model::parameter_name(ids[k]));
    CHECK((j.col(static_cast<Eigen::Index>(k)) - numeric).norm() < 1e-7);
  }
}

TEST_CASE("identifiability names what point data cannot give") {
  std::mt19937_64 rng(2);
  const RobotModel m = robot("ur5.yaml");
  const model::Dataset d = simulation::measure(m, sim::random_configurations(m, 40, rng), rng, 1e-5, false, 0.0, true);
  const identify::IdentifyResult r = identify::identify(m, d, {});
  // 4 per revolute joint + 3 for the tool point + 6 base - (theta1, d1 to the base) ...: 4R + 3 = 27.
  CHECK(r.identifiability.identified.size() == 27);
  CHECK(r.identifiability.rank == 27);
  std::string held;
  for (const auto& h : r.identifiability.held_fixed) held += model::parameter_name(h.id) + " ";
  CHECK(has(held, "theta1 "));
  CHECK(has(held, "d1 "));
  bool doty = false;
  for (const auto& note : r.notes) doty = doty || has(note, "Doty");
  CHECK(doty);
}

TEST_CASE("identifiable parameter counts: 4R + 2P + 6 with poses, 4R + 2P + 3 with points") {
  std::mt19937_64 rng(12);
  struct Case {
    const char* file;
    bool pose;
    std::size_t expected;
  };
  for (const Case& c : {Case{"stanford_rrp.yaml", false, 13}, Case{"arid_prrr.yaml", true, 20},
                        Case{"puma560.yaml", true, 30}, Case{"puma560.yaml", false, 27}}) {
    INFO(c.file, c.pose ? " poses" : " points");
    const RobotModel m = robot(c.file);
    const model::Dataset d =
        simulation::measure(m, sim::random_configurations(m, 50, rng), rng, 1e-5, c.pose, 1e-5, true);
    identify::IdentifyOptions o;
    o.orientation_sigma_rad = 1e-5;
    const identify::IdentifyResult r = identify::identify(m, d, o);
    CHECK(r.identifiability.identified.size() == c.expected);
    CHECK(r.stddev.minCoeff() > 0.0);
  }
}

TEST_CASE("full, first-order and cpa recover known errors from noise-free data") {
  std::mt19937_64 rng(3);
  for (const char* name : {"puma560.yaml", "ur5.yaml", "stanford_rrp.yaml", "arid_prrr.yaml"}) {
    INFO(name);
    const RobotModel nominal = robot(name);
    const RobotModel truth = sim::perturbed(nominal, rng);
    const bool pose = nominal.tool == model::ToolKind::frame;
    const auto qs = sim::random_configurations(nominal, 60, rng);
    const model::Dataset d = simulation::measure(truth, qs, rng, 0.0, pose, 0.0, false);
    identify::IdentifyOptions o;
    o.sigma_m = 1e-4;
    o.orientation_sigma_rad = 1e-4;
    o.prior.strength = 0.0;  // exact recovery is least squares' (a prior pulls by its share, 1e-4 here)
    const auto held_out = sim::random_configurations(nominal, 50, rng);
    const identify::IdentifyResult full = identify::identify(nominal, d, o);
    CHECK(simulation::prediction_rms(full.model, truth, held_out) < 1e-9);
    CHECK(full.outlier_lines.empty());
    if (pose) {
      for (const auto& q : held_out) {
        const model::Transform a = model::forward_kinematics(full.model, q), b = model::forward_kinematics(truth, q);
        CHECK((a.rotation - b.rotation).norm() < 1e-9);
      }
    }
    // First order: one linear step, so the error is second order in the parameter errors.
    o.method = identify::Method::first_order;
    const identify::IdentifyResult first = identify::identify(nominal, d, o);
    const double before = simulation::prediction_rms(nominal, truth, held_out);
    CHECK(simulation::prediction_rms(first.model, truth, held_out) < 0.05 * before);
  }
}

TEST_CASE("a 6-DoF probe mounted upside down: the tool's turn registered first, the solve converges") {
  // 18 rows of a 6-DoF tracker on a service-class 7-joint arm (millimetre errors, joint sag), its
  // probe's frame turned 178 deg from the URDF's tool0 (the zoo's sia5d, one cross-validation
  // fold's training rows). The base registration alone (positions) left the solve to turn the
  // tool by half a turn: it settled at 520 mm RMS with orientation and position pulling apart, and
  // every model selection fold it was in scored hundreds of millimetres.
  const RobotModel nominal = model::load_model(
      std::string(KINCAL_REALDATA_DIR) + "/urdf-corpus/motoman/motoman_sia5d_support/urdf/sia5d.urdf", {"", "tool0"});
  const model::Dataset d = model::read_dataset(std::string(KINCAL_TEST_DATA_DIR) + "/sia5d_probe_turned.csv");
  const identify::IdentifyResult r = identify::identify(nominal, d, identify::IdentifyOptions{});
  const auto turned = std::find_if(r.notes.begin(), r.notes.end(),
                                   [](const std::string& n) { return has(n, "the model's tool frame was 17"); });
  REQUIRE(turned != r.notes.end());
  MESSAGE(*turned);
  CHECK(r.residuals.rms_m < 2e-3);  // the geometry's misfit to an arm that sags: 0.47 mm
  CHECK(identify::accuracy(r.model, d).rms_rad < 0.01);

  // A tool frame within a few degrees of the data's is the solve's to refine: no turn first.
  model::Dataset near = d;
  for (model::Measurement& row : near.rows)
    row.orientation = Eigen::Quaterniond(model::forward_kinematics(r.model, row.q).rotation);
  const identify::IdentifyResult again = identify::identify(r.model, near, identify::IdentifyOptions{});
  CHECK(std::none_of(again.notes.begin(), again.notes.end(),
                     [](const std::string& n) { return has(n, "the model's tool frame was "); }));
}

TEST_CASE("cpa on single-joint sweeps finds the axes; full from cpa converges") {
  std::mt19937_64 rng(4);
  for (const char* name : {"stanford_rrp.yaml", "puma560.yaml", "ur5.yaml"}) {
    INFO(name);
    const RobotModel nominal = robot(name);
    const RobotModel truth = sim::perturbed(nominal, rng);
    std::vector<double> home;
    for (const auto& j : nominal.joints) home.push_back(0.5 * (j.lower + j.upper) + 0.1);
    const model::Dataset d = simulation::measure(truth, sweeps(nominal, home, 10, 0.5), rng, 0.0, false, 0.0, false);
    identify::IdentifyOptions o;
    o.method = identify::Method::cpa;
    const identify::IdentifyResult cpa = identify::identify(nominal, d, o);
    const auto held_out = sim::random_configurations(nominal, 50, rng);
    CHECK(simulation::prediction_rms(cpa.model, truth, held_out) < 1e-7);
    CHECK(cpa.cpa_sweeps.size() == nominal.joints.size());
  }
}

TEST_CASE("cpa rejects an outlier in a sweep and reports its line") {
  std::mt19937_64 rng(5);
  const RobotModel nominal = robot("stanford_rrp.yaml");
  const RobotModel truth = sim::perturbed(nominal, rng);
  const std::vector<double> home = {0.1, 1.6, 0.8};
  model::Dataset d = simulation::measure(truth, sweeps(nominal, home, 12, 0.5), rng, 2e-4, false, 0.0, true);
  d.rows[15].position.x() += 0.02;  // a 2 cm blunder in the sweep of joint 2
  const identify::CpaResult r = identify::circle_point_analysis(nominal, d, {});
  REQUIRE(r.fits.size() == 3);
  CHECK(r.fits[1].rejected_lines == std::vector<int>{d.rows[15].line});
  CHECK(r.fits[0].rejected_lines.empty());
  CHECK(r.fits[0].curved);
  CHECK(!r.fits[2].curved);
}

TEST_CASE("full identification with noise: outliers rejected by line, noise estimated") {
  std::mt19937_64 rng(6);
  const RobotModel nominal = robot("puma560.yaml");
  const RobotModel truth = sim::perturbed(nominal, rng);
  model::Dataset d =
      simulation::measure(truth, sim::random_configurations(nominal, 80, rng), rng, 5e-5, true, 1e-4, false);
  d.rows[10].position.z() += 0.01;
  d.rows[10].id = "2021-03-04 10:11:12";  // the export's time stamp (import --id) names the row too
  const identify::IdentifyResult r = identify::identify(nominal, d, {});
  CHECK(r.outlier_lines == std::vector<int>{d.rows[10].line});
  CHECK(identify::format_noise(r).find("rejected line " + std::to_string(d.rows[10].line) +
                                       " (id 2021-03-04 10:11:12): ") != std::string::npos);
  CHECK(r.model_error_estimated);
  CHECK(r.model_error_position_m == doctest::Approx(5e-5).epsilon(0.15));
  CHECK(r.model_error_orientation_rad == doctest::Approx(1e-4).epsilon(0.15));
  const auto held_out = sim::random_configurations(nominal, 100, rng);
  CHECK(simulation::prediction_rms(r.model, truth, held_out) < 1e-4);
  // The standard deviations describe the errors: the tool point error is within a few sigma.
  CHECK(r.stddev.size() == static_cast<Eigen::Index>(r.identifiability.identified.size()));
  CHECK(r.stddev.maxCoeff() < 1e-2);
  CHECK(r.model.calibration.has_value());
  CHECK(!identify::format_report(r).empty());
}

// A wrist kept facing the tracker, a rail or a seventh axis left still: the rest is calibrated,
// what only that joint's motion shows is held, and the note names it (was refused).
TEST_CASE("a joint that never moved: held, named, and the model calibrated at its reading") {
  std::mt19937_64 rng(8);
  const RobotModel nominal = robot("puma560.yaml");
  const RobotModel truth = sim::perturbed(nominal, rng);
  for (const int still : {0, 3, 5}) {
    CAPTURE(still);
    const auto at_reading = [&](int count) {
      std::vector<std::vector<double>> qs = sim::random_configurations(nominal, count, rng);
      for (auto& q : qs) q[static_cast<std::size_t>(still)] = 0.3;
      return qs;
    };
    const model::Dataset d = simulation::measure(truth, at_reading(60), rng, 2e-5, false, 0.0, false);
    CHECK(identify::still_joints(d) == std::vector<int>{still});
    const identify::IdentifyResult r = identify::identify(nominal, d, {});
    const std::string name = "joint " + std::to_string(still + 1) + " (" +
                             nominal.joints[static_cast<std::size_t>(still)].name + ") never moved: every row has q" +
                             std::to_string(still + 1) + " = 0.3";
    CHECK(std::any_of(r.notes.begin(), r.notes.end(), [&](const std::string& n) { return has(n, name); }));
    // At that reading, the noise's prediction; elsewhere no better than its axis is known.
    CHECK(simulation::prediction_rms(r.model, truth, at_reading(100)) < 6e-5);
  }
}

TEST_CASE("errors: joint count, too few poses, unidentifiable requests") {
  std::mt19937_64 rng(7);
  const RobotModel puma = robot("puma560.yaml");
  const RobotModel rrp = robot("stanford_rrp.yaml");
  const model::Dataset d =
      simulation::measure(rrp, sim::random_configurations(rrp, 30, rng), rng, 1e-4, false, 0.0, true);
  CHECK(has(error_of(puma, d, {}), "the data has 3 joint columns but the model 'puma560' has 6 joints"));

  model::Dataset few = d;
  few.rows.resize(3);
  CHECK(has(error_of(rrp, few, {}), "too few measurements: 3 give 9 equations for"));

  identify::IdentifyOptions o;
  o.requested = {"theta1", "base_rz", "a2"};
  const std::string request = error_of(rrp, d, o);
  CHECK(has(request, "cannot identify the requested parameters"));
  CHECK(has(request, "base_rz: not separable from theta1"));

  o.requested = {"theta9"};
  CHECK(has(error_of(rrp, d, o), "parameter 'theta9': joint 9 does not exist"));
  o.requested = {"gamma1"};
  CHECK(has(error_of(rrp, d, o), "unknown parameter name 'gamma1'"));

  o = {};
  o.method = identify::Method::cpa;
  CHECK(has(error_of(rrp, d, o), "cpa needs a single-joint sweep of every joint"));
}

TEST_CASE("plan beats random configurations on the observability index") {
  const RobotModel m = robot("stanford_rrp.yaml");
  identify::PlanOptions o;
  o.criterion = identify::PlanCriterion::d_optimal;  // the index is what it maximizes
  o.count = 12;
  o.pool = 300;
  o.random_sets = 20;
  const identify::PlanResult r = identify::plan_configurations(m, o);
  CHECK(r.configurations.size() == 12);
  CHECK(r.index > r.random_index_best);
  CHECK(r.prediction_rms < r.random_prediction_rms);
  for (const auto& q : r.configurations)
    for (std::size_t j = 0; j < q.size(); ++j) {
      CHECK(q[j] >= m.joints[j].lower);
      CHECK(q[j] <= m.joints[j].upper);
    }
}

TEST_CASE("noise model: a model error far above the instrument's covariance is estimated, never refused") {
  std::mt19937_64 rng(21);
  const RobotModel nominal = robot("puma560.yaml");
  const RobotModel truth = sim::perturbed(nominal, rng);
  // The tracker's 0.01 mm recorded as covariance; the robot adds 0.3 mm the model cannot explain.
  model::Dataset d =
      simulation::measure(truth, sim::random_configurations(nominal, 120, rng), rng, 3e-4, false, 0.0, false);
  d.noise = model::NoiseColumns::covariance;
  for (model::Measurement& m : d.rows) m.covariance = Eigen::Matrix3d::Identity() * 1e-10;
  const identify::IdentifyResult r = identify::identify(nominal, d, {});
  CHECK(r.model_error_estimated);
  CHECK(r.model_error_position_m == doctest::Approx(3e-4).epsilon(0.15));
  CHECK(r.rejections.size() <= 6);  // the cap: 5 % of 120
  CHECK(r.chi_square_per_dof == doctest::Approx(1.0).epsilon(0.05));
  // The 95 % prediction ellipsoids hold about 95 % of new measurements.
  int inside = 0;
  const auto held_out = sim::random_configurations(nominal, 200, rng);
  std::normal_distribution<double> unit(0.0, 1.0);
  for (const auto& q : held_out) {
    const Eigen::Vector3d e = model::forward_kinematics(truth, q).translation +
                              3e-4 * Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) -
                              model::forward_kinematics(r.model, q).translation;
    inside += e.dot(identify::prediction_covariance(r, q).ldlt().solve(e)) <= identify::chi_square_quantile(0.95, 3);
  }
  CHECK(inside >= 180);
  CHECK(inside <= 198);
  CHECK(has(identify::format_report(r), "model error 0.3"));
}

TEST_CASE("outlier rejection on a small set with systematic error is no worse than none") {
  // The simulated sagging sweep set: 36 readings; the rows the test would reject are the model's
  // error at the sweeps' ends, not blunders.
  const RobotModel nominal = robot("puma560.yaml");
  double with = 0.0, without = 0.0;
  for (int seed = 0; seed < 8; ++seed) {
    const simulation::SaggingSweeps set =
        simulation::sagging_sweeps(nominal, static_cast<std::uint64_t>(100 + seed), 6);
    identify::IdentifyOptions o;
    const double a = identify::accuracy(identify::identify(nominal, set.train, o).model, set.held_out).rms_m;
    o.robust = false;
    const double b = identify::accuracy(identify::identify(nominal, set.train, o).model, set.held_out).rms_m;
    INFO("seed ", seed, ": with rejection ", a * 1e3, " mm, without ", b * 1e3, " mm");
    CHECK(a <= 1.05 * b);  // one seed: within its noise
    with += a * a;
    without += b * b;
  }
  CHECK(std::sqrt(with) <= std::sqrt(without) * 1.001);
}

TEST_CASE("rejection gate: the model's error at sweep ends is not rejected") {
  // Sweeps of 12 readings a joint (72 rows, enough equations for the test to reject): the rows it
  // flags are the sag the model lacks, where few rows see a direction; cross-validation finds
  // that rejecting them does not lower the held-out error, and the result is the fit without.
  const RobotModel nominal = robot("puma560.yaml");
  int judged = 0;
  for (int seed = 0; seed < 4; ++seed) {
    const simulation::SaggingSweeps set =
        simulation::sagging_sweeps(nominal, static_cast<std::uint64_t>(200 + seed), 12);
    identify::IdentifyOptions o;
    const identify::IdentifyResult r = identify::identify(nominal, set.train, o);
    o.rejection_gate = false;
    const identify::IdentifyResult test_only = identify::identify(nominal, set.train, o);
    o.robust = false;
    const identify::IdentifyResult none = identify::identify(nominal, set.train, o);
    const double a = identify::accuracy(r.model, set.held_out).rms_m;
    const double t = identify::accuracy(test_only.model, set.held_out).rms_m;
    const double b = identify::accuracy(none.model, set.held_out).rms_m;
    MESSAGE("seed ", seed, ": rejected by the test ", test_only.rejections.size(), ", gate judged ",
            r.rejection_gate.judged, " kept ", r.rejection_gate.kept, " (t ", r.rejection_gate.kfold_t,
            "); held out: default ", a * 1e3, " mm, test only ", t * 1e3, " mm, none ", b * 1e3, " mm");
    CHECK(r.rejection_gate.judged == !test_only.rejections.empty());
    judged += r.rejection_gate.judged ? 1 : 0;
    if (r.rejection_gate.judged && !r.rejection_gate.kept) {  // the test's fit before its first rejection
      CHECK((r.change.array() == none.change.array()).all());
      CHECK((r.covariance.array() == none.covariance.array()).all());
      CHECK(r.model_error_position_m == none.model_error_position_m);
      CHECK(r.residuals.rms_m == none.residuals.rms_m);
      CHECK(r.iterations == none.iterations);
      CHECK(r.notes == none.notes);
      CHECK(r.outlier_lines.empty());
      CHECK(r.rejection_gate.undone.size() == test_only.rejections.size());
    }
  }
  CHECK(judged > 0);
}

TEST_CASE("rejection gate: real blunders stay rejected and help the other rows") {
  // 80 random poses of a PUMA with 0.05 mm noise and three 20-sigma blunders (1 mm).
  std::mt19937_64 rng(31);
  const RobotModel nominal = robot("puma560.yaml");
  const RobotModel truth = sim::perturbed(nominal, rng);
  model::Dataset d =
      simulation::measure(truth, sim::random_configurations(nominal, 80, rng), rng, 5e-5, false, 0.0, false);
  const std::vector<int> blunders{7, 33, 61};
  std::vector<int> clean;
  for (int i = 0; i < 80; ++i)
    if (std::find(blunders.begin(), blunders.end(), i) == blunders.end()) clean.push_back(i);
  for (const int i : blunders) d.rows[static_cast<std::size_t>(i)].position += Eigen::Vector3d(1e-3, 0, 0);
  identify::IdentifyOptions o;
  const identify::IdentifyResult r = identify::identify(nominal, d, o);
  o.robust = false;
  const identify::IdentifyResult none = identify::identify(nominal, d, o);
  INFO(identify::format_noise(r));
  CHECK(r.rejection_gate.judged);
  CHECK(r.rejection_gate.kept);
  CHECK(r.rejection_gate.kfold_t <= -2.0);
  for (const int i : blunders)
    CHECK(has(identify::format_noise(r),
              "rejected line " + std::to_string(d.rows[static_cast<std::size_t>(i)].line) + ":"));
  CHECK(has(identify::format_noise(r), "the rejections stand"));
  // Held out: the clean truth at new configurations, and the training set's clean rows.
  const auto held_out = sim::random_configurations(nominal, 100, rng);
  CHECK(simulation::prediction_rms(r.model, truth, held_out) < simulation::prediction_rms(none.model, truth, held_out));
  CHECK(identify::accuracy(r.model, d, clean).rms_m < identify::accuracy(none.model, d, clean).rms_m);
}

TEST_CASE("real UR10 data: the tracker's covariance columns neither refuse nor hurt") {
  const model::Dataset all = realdata::import_ur10(KINCAL_REALDATA_DIR).data;
  const realdata::Split split = realdata::split_rows(static_cast<int>(all.rows.size()), 500);
  const model::Dataset train =
      realdata::subset(all, std::vector<int>(split.train_order.begin(), split.train_order.begin() + 100));
  const model::Dataset held_out = realdata::subset(all, split.held_out);
  const RobotModel ur10 = robot("ur10.yaml");
  const identify::IdentifyResult with = identify::identify(ur10, train, {});
  model::Dataset bare = train;
  for (model::Measurement& m : bare.rows) m.covariance.reset();
  bare.noise = model::NoiseColumns::none;
  const identify::IdentifyResult without = identify::identify(ur10, bare, {});
  const double a = identify::accuracy(with.model, held_out).rms_m,
               b = identify::accuracy(without.model, held_out).rms_m;
  INFO("held-out rms with the covariance columns ", a * 1e3, " mm, without ", b * 1e3, " mm");
  CHECK(a <= 1.02 * b);
  CHECK(a < 0.6e-3);  // about 0.45 mm; the nominal model after registration is about 1.1 mm
  CHECK(with.model_error_position_m > 0.1e-3);
  CHECK(with.model_error_position_m < 0.5e-3);
}

TEST_CASE("pose rows with a full 6x6 covariance: whitened by it, and identified at the bound its correlation allows") {
  // A camera 0.6 m from what it sees: the rotation error d (1 mrad) moves the measured position by
  // the lever arm, -[t]x d, far above the position's own 0.02 mm. The dataset carries the 6 x 6.
  std::mt19937_64 rng(26);
  const RobotModel nominal = robot("puma560.yaml");
  const RobotModel truth = sim::perturbed(nominal, rng);
  const double sigma_p = 2e-5, sigma_r = 1e-3;
  std::normal_distribution<double> unit(0.0, 1.0);
  model::Dataset d;
  d.source = "correlated";
  d.joint_count = nominal.joint_count();
  d.has_orientation = true;
  d.has_pose_covariance = true;
  d.noise = model::NoiseColumns::covariance;
  double chi2_at_truth = 0.0;
  const auto qs = sim::random_configurations(nominal, 60, rng);
  for (const auto& q : qs) {
    const model::Transform t = model::forward_kinematics(truth, q);
    const Eigen::Vector3d lever = 0.6 * Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized();
    Eigen::Matrix<double, 6, 6> a = Eigen::Matrix<double, 6, 6>::Identity();
    a.topRightCorner<3, 3>() << 0, lever.z(), -lever.y(), -lever.z(), 0, lever.x(), lever.y(), -lever.x(), 0;
    Eigen::Matrix<double, 6, 1> s;
    s << sigma_p, sigma_p, sigma_p, sigma_r, sigma_r, sigma_r;
    const model::Matrix6 v = a * s.cwiseAbs2().asDiagonal() * a.transpose();
    Eigen::Matrix<double, 6, 1> z;
    for (double& x : z) x = unit(rng);
    const Eigen::Matrix<double, 6, 1> e = a * s.asDiagonal() * z;  // ~ N(0, v)
    Eigen::Isometry3d measured = Eigen::Isometry3d::Identity();
    measured.translation() = t.translation + e.head<3>();
    measured.linear() = Eigen::AngleAxisd(e.tail<3>().norm(), e.tail<3>().normalized()).toRotationMatrix() * t.rotation;
    d.rows.push_back(model::pose_row(q, measured, v, static_cast<int>(d.rows.size()) + 2));
    chi2_at_truth += e.dot(v.ldlt().solve(e));
  }
  // At the truth, the whitened residuals are the noise whitened by its own covariance.
  identify::Parameterization at_truth(truth, {});
  Eigen::VectorXd r;
  std::vector<int> rows(d.rows.size());
  for (std::size_t i = 0; i < rows.size(); ++i) rows[i] = static_cast<int>(i);
  identify::stacked(at_truth, d, identify::make_weights(d, 1.0, 1.0), rows, r, nullptr);
  CHECK(r.squaredNorm() == doctest::Approx(chi2_at_truth).epsilon(1e-6));

  // Held out against the truth, over the bound from the same covariances.
  const auto held_out = sim::random_configurations(nominal, 50, rng);
  const identify::IdentifyResult full = identify::identify(nominal, d, {});
  const double bound2 = simulation::prediction_bound(full.start, full.identifiability.identified, d,
                                                     identify::make_weights(d, 1.0, 1.0), held_out) /
                        static_cast<double>(held_out.size());
  const double full_rms = simulation::prediction_rms(full.model, truth, held_out);
  CHECK(full_rms < 1.5 * std::sqrt(bound2));
  CHECK(full.chi_square_per_dof == doctest::Approx(1.0).epsilon(0.25));

  // The same rows weighted by their position block and an estimated orientation sigma (the
  // correlation dropped) lose most of what the rotation error tells about the position.
  model::Dataset blocks = d;
  blocks.has_pose_covariance = false;
  for (model::Measurement& m : blocks.rows) m.pose_covariance.reset();
  const double block_rms = simulation::prediction_rms(identify::identify(nominal, blocks, {}).model, truth, held_out);
  MESSAGE("held out: full " << full_rms * 1e3 << " mm, bound " << std::sqrt(bound2) * 1e3 << " mm, blocks "
                            << block_rms * 1e3 << " mm");
  CHECK(full_rms < 0.6 * block_rms);
}
