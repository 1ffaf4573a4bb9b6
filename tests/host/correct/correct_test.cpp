// host/correct (issue #24): the PC's joint correction against the platform's (firmware/core read
// from the correction block, in float) on the plain chain and the joint map; the Newton solve
// where first order is not enough; inverse kinematics with limits, reach and seeds; the nominal
// rebuilt from a calibration record; the predicted spread.
#include <doctest.h>

#include <cmath>
#include <limits>
#include <numbers>
#include <random>

#include "firmware/app/kinematic_correction.hpp"
#include "host/correct/cartesian_targets.hpp"
#include "host/correct/correction_block.hpp"
#include "host/correct/joint_correction.hpp"
#include "host/correct/joint_offsets.hpp"
#include "host/correct/platform_step.hpp"
#include "host/correct/prediction_spread.hpp"
#include "host/correct/target_correction.hpp"
#include "host/model/model_file.hpp"

using namespace kincal;

namespace {

model::RobotModel robot(const char* file) { return model::load_model(std::string(KINCAL_ROBOTS_DIR) + "/" + file); }

// Every link parameter, and the tool, off by up to `angle_rad` / `length_m`.
model::RobotModel perturbed(const model::RobotModel& m, double angle_rad, double length_m, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  model::RobotModel out = m;
  for (model::Joint& j : out.joints) {
    j.parameters.a_m += length_m * u(rng);
    j.parameters.d_m += length_m * u(rng);
    j.parameters.alpha_rad += angle_rad * u(rng);
    j.offset += angle_rad * u(rng);
  }
  out.flange_T_tool.translation += length_m * model::Vector3(u(rng), u(rng), u(rng));
  return out;
}

// The elbow reported relative to the shoulder, masses, gravity; the calibrated arm adds gear
// scales and compliance (as session_test's joint-map case).
void add_joint_map(model::RobotModel& start, model::RobotModel& calibrated) {
  for (model::RobotModel* m : {&start, &calibrated}) {
    m->joints[2].coupling = {0, 1, 1, 0, 0, 0};
    const double mass_kg[6] = {0, 17.4, 4.8, 0.82, 0.34, 0.09};
    for (std::size_t j = 0; j < 6; ++j) m->joints[j].mass_kg = mass_kg[j];
    m->joints[1].centre_of_mass_m = {-0.3638, 0.006, 0.2275};
    m->joints[2].centre_of_mass_m = {-0.0203, -0.0141, 0.070};
    m->payload.mass_kg = 3.0;
    m->payload.centre_of_mass_m = {0, 0, 0.1};
    m->joints[1].compliance = 0.0;
    m->joints[2].compliance = 0.0;
  }
  calibrated.joints[0].scale = 1.0 + 4e-4;
  calibrated.joints[1].scale = 1.0 - 3e-4;
  calibrated.joints[1].compliance = 2e-5;
  calibrated.joints[2].compliance = 3e-5;
}

std::vector<double> random_readings(std::mt19937_64& rng) {
  std::vector<double> q = {0.1, -0.4, 0.3, 0.2, -0.5, 0.7};
  for (double& v : q) v += std::uniform_real_distribution<double>(-0.4, 0.4)(rng);
  return q;
}

model::Vector3 tool_in_frame0(model::RobotModel m, const std::vector<double>& q) {
  m.base_T_frame0 = model::Transform{};
  return model::forward_kinematics(m, q).translation;
}

// PC and platform on the same targets: the tool within 1 um, and the PC on the goal.
void check_agreement(const model::RobotModel& start, const model::RobotModel& calibrated) {
  correct::PlatformStep platform(start, calibrated);
  correct::JointCorrector pc(start, calibrated);
  REQUIRE(pc.platform_step());
  // The platform step is the platform's: the app's correction gives the same readings to its
  // 2^-16 rad quantization (one LSB: the float results may straddle a rounding boundary).
  static app::KinematicCorrection app_correction;
  const shared::CorrectionParameters block = correct::correction_block(start, calibrated);
  std::mt19937_64 rng(5);
  double worst_apart_m = 0.0, worst_goal_m = 0.0, worst_uncorrected_m = 0.0;
  for (int trial = 0; trial < 30; ++trial) {
    const std::vector<double> q = random_readings(rng);
    const correct::JointCorrection c = pc.correct(q);
    REQUIRE(c.solution.outcome == correct::Outcome::reached);
    CHECK(c.platform_step_used);
    const std::optional<std::vector<double>> step = platform.correct(q);
    REQUIRE(step);
    const std::vector<double>& p = *step;
    app::JointRaw raw{}, corrected_raw{};
    for (std::size_t j = 0; j < q.size(); ++j) raw[j] = shared::quantize_joint_angle(q[j]);
    std::vector<double> quantized(q.size());
    for (std::size_t j = 0; j < q.size(); ++j) quantized[j] = shared::joint_angle_rad<double>(raw[j]);
    REQUIRE(app_correction.correct(block, raw, corrected_raw) == app::CorrectStatus::kOk);
    const std::optional<std::vector<double>> from_quantized = platform.correct(quantized);
    REQUIRE(from_quantized);
    for (std::size_t j = 0; j < q.size(); ++j)
      CHECK(std::abs(shared::quantize_joint_angle((*from_quantized)[j]) - corrected_raw[j]) <= 1);
    worst_apart_m =
        std::max(worst_apart_m, (tool_in_frame0(calibrated, c.solution.q) - tool_in_frame0(calibrated, p)).norm());
    worst_goal_m = std::max(worst_goal_m, (tool_in_frame0(calibrated, c.solution.q) - c.goal.translation).norm());
    worst_uncorrected_m = std::max(worst_uncorrected_m, (tool_in_frame0(calibrated, q) - c.goal.translation).norm());
  }
  MESSAGE("uncorrected " << worst_uncorrected_m * 1e3 << " mm, PC to goal " << worst_goal_m * 1e6
                         << " um, PC to platform " << worst_apart_m * 1e6 << " um at the tool");
  CHECK(worst_uncorrected_m > 1e-3);
  CHECK(worst_goal_m < 10e-6);
  CHECK(worst_apart_m < 1e-6);
}

}  // namespace

TEST_CASE("joint targets: the PC and the platform agree within 1 um at the tool (plain chain)") {
  const model::RobotModel start = robot("puma560.yaml");
  check_agreement(start, perturbed(start, 1e-3, 1e-3, 1));
}

TEST_CASE("joint targets: the PC and the platform agree within 1 um at the tool (joint map)") {
  model::RobotModel start = robot("puma560.yaml");
  model::RobotModel calibrated = perturbed(start, 1e-3, 1e-3, 2);
  add_joint_map(start, calibrated);
  check_agreement(start, calibrated);
}

TEST_CASE("joint targets: where first order is not enough, the Newton solve reaches the goal") {
  model::RobotModel start = robot("puma560.yaml");
  model::RobotModel calibrated = perturbed(start, 0.01, 0.01, 3);  // 0.6 degree and 10 mm
  add_joint_map(start, calibrated);
  correct::PlatformStep platform(start, calibrated);
  correct::JointCorrector pc(start, calibrated);
  correct::JointCorrectionOptions newton_only;
  newton_only.platform_step = false;
  correct::JointCorrector alone(start, calibrated, newton_only);
  CHECK_FALSE(alone.platform_step());
  std::mt19937_64 rng(7);
  double worst_platform_m = 0.0;
  int refined = 0, refused = 0;
  for (int trial = 0; trial < 20; ++trial) {
    const std::vector<double> q = random_readings(rng);
    const correct::JointCorrection c = pc.correct(q);
    REQUIRE(c.solution.outcome == correct::Outcome::reached);
    refined += c.refined ? 1 : 0;
    CHECK((tool_in_frame0(calibrated, c.solution.q) - c.goal.translation).norm() < 1e-5);
    if (const std::optional<std::vector<double>> p = platform.correct(q))
      worst_platform_m = std::max(worst_platform_m, (tool_in_frame0(calibrated, *p) - c.goal.translation).norm());
    else
      ++refused;
    const correct::JointCorrection d = alone.correct(q);
    REQUIRE(d.solution.outcome == correct::Outcome::reached);
    CHECK(d.solution.residual_m <= 1e-7);
    CHECK(d.solution.residual_rad <= 1e-7);
    for (std::size_t j = 0; j < q.size(); ++j) CHECK(d.solution.q[j] == doctest::Approx(c.solution.q[j]).epsilon(1e-4));
  }
  MESSAGE("platform step alone leaves up to " << worst_platform_m * 1e6 << " um, refuses " << refused
                                              << " targets; refined " << refined << " of 20");
  CHECK((worst_platform_m > 1e-5 || refused > 0));
  CHECK(refined > 0);
}

TEST_CASE("joint targets: models the block cannot carry get the Newton solve alone") {
  const model::RobotModel start = robot("puma560.yaml");
  model::RobotModel calibrated = perturbed(start, 1e-3, 1e-3, 4);
  calibrated.joints[2].coupling = {0.0, 0.003, 1.0, 0.0, 0.0, 0.0};  // the block carries the controller's row
  correct::JointCorrector pc(start, calibrated);
  CHECK_FALSE(pc.platform_step());
  CHECK(pc.platform_note().find("coupling") != std::string::npos);
  const correct::JointCorrection c = pc.correct(std::vector<double>{0.1, -0.4, 0.3, 0.2, -0.5, 0.7});
  CHECK(c.refined);
  CHECK(c.solution.outcome == correct::Outcome::reached);
  CHECK_THROWS_AS(pc.correct(std::vector<double>{0.1, 0.2}), std::invalid_argument);

  // A tool frame turned by more than the platform's largest step: orientation refused, the point
  // corrected.
  model::RobotModel turned = calibrated;
  turned.joints[3].mass_kg = 0.0;
  turned.flange_T_tool.rotation = Eigen::AngleAxisd(0.1, model::Vector3::UnitZ()).toRotationMatrix();
  const std::vector<double> q = {0.1, -0.4, 0.3, 0.2, -0.5, 0.7};
  CHECK_THROWS_WITH_AS(correct::JointCorrector(start, turned).correct(q), doctest::Contains("--position-only"),
                       model::InputError);
  correct::JointCorrectionOptions point;
  point.orientation = false;
  const correct::JointCorrection p = correct::JointCorrector(start, turned, point).correct(q);
  CHECK(p.solution.outcome == correct::Outcome::reached);
  CHECK((tool_in_frame0(turned, p.solution.q) - p.goal.translation).norm() < 1e-5);
}

TEST_CASE("solve_pose: reachable poses reached within the limits, from a seed in the same branch") {
  const model::RobotModel m = robot("puma560.yaml");
  std::mt19937_64 rng(9);
  for (int trial = 0; trial < 20; ++trial) {
    const std::vector<double> q = random_readings(rng);
    const model::Transform goal = model::forward_kinematics(m, q);
    std::vector<double> seed = q;
    for (double& v : seed) v += std::uniform_real_distribution<double>(-0.05, 0.05)(rng);
    const correct::Solution s = correct::solve_pose(m, goal, true, seed);
    REQUIRE(s.outcome == correct::Outcome::reached);
    for (std::size_t j = 0; j < q.size(); ++j) CHECK(s.q[j] == doctest::Approx(q[j]).epsilon(1e-5));
    const correct::Solution point = correct::solve_pose(m, goal, false, seed);
    REQUIRE(point.outcome == correct::Outcome::reached);
    CHECK((model::forward_kinematics(m, point.q).translation - goal.translation).norm() < 1e-7);
  }
}

TEST_CASE("solve_pose: out of reach, joint limits and a bad seed are reported, never returned as reached") {
  model::RobotModel m = robot("puma560.yaml");
  for (model::Joint& j : m.joints) j.lower = -(j.upper = std::numeric_limits<double>::infinity());
  const std::vector<double> seed = {0.1, -0.4, 0.3, 0.2, -0.5, 0.7};
  model::Transform far = model::forward_kinematics(m, seed);
  far.translation *= 5.0;
  const correct::Solution out = correct::solve_pose(m, far, false, seed);
  CHECK(out.outcome == correct::Outcome::out_of_reach);
  CHECK(out.residual_m > 1.0);
  CHECK(std::string(correct::outcome_name(out.outcome)) == "out-of-reach");

  // A goal only the first joint beyond its limit reaches.
  model::RobotModel limited = m;
  limited.joints[0].lower = -0.2;
  limited.joints[0].upper = 0.2;
  std::vector<double> beyond = seed;
  beyond[0] = 0.6;
  const correct::Solution blocked = correct::solve_pose(limited, model::forward_kinematics(m, beyond), true, seed);
  CHECK(blocked.outcome == correct::Outcome::joint_limit);
  CHECK(blocked.q[0] <= 0.2);
  CHECK(blocked.residual_m > 1e-3);
  CHECK_THROWS_AS(correct::solve_pose(m, far, false, std::vector<double>{0.0}), std::invalid_argument);
}

TEST_CASE("solve_pose: of the readings that reach a goal, the ones nearest the reference (issue #42)") {
  // A point goal leaves a 6-joint arm three spare joints: started with the wrist turned 0.5 rad each
  // way (turns that nearly cancel at the tool), the solve still ends nearest the reference.
  const model::RobotModel m = robot("puma560.yaml");
  const std::vector<double> reference = {0.1, -0.4, 0.3, 0.2, -0.5, 0.7};
  model::Transform goal = model::forward_kinematics(m, reference);
  const model::Vector3 correction(2e-3, -1e-3, 3e-3);
  goal.translation += correction;
  std::vector<double> seed = reference;
  seed[3] += 0.5;
  seed[5] -= 0.5;
  const auto change = [&](const std::vector<double>& q) {
    Eigen::VectorXd d(6);
    for (int j = 0; j < 6; ++j) d(j) = q[static_cast<std::size_t>(j)] - reference[static_cast<std::size_t>(j)];
    return d;
  };
  const correct::Solution s = correct::solve_pose(m, goal, false, seed, {}, reference);
  REQUIRE(s.outcome == correct::Outcome::reached);
  // The smallest change to first order is the minimum-norm one, J^+ e at the reference.
  const Eigen::MatrixXd j = model::joint_jacobian(m, reference).topRows(3);
  const Eigen::VectorXd least = j.completeOrthogonalDecomposition().solve(Eigen::Vector3d(correction));
  CHECK(change(s.q).norm() <= 1.02 * least.norm());
  CHECK(change(s.q).cwiseAbs().maxCoeff() < 0.02);
  // Without the walk toward the reference the turns stay.
  correct::SolveOptions no_walk;
  no_walk.max_nearest_steps = 0;
  const correct::Solution stays = correct::solve_pose(m, goal, false, seed, no_walk, reference);
  REQUIRE(stays.outcome == correct::Outcome::reached);
  CHECK(change(stays.q).cwiseAbs().maxCoeff() > 0.3);
  // A full pose on a 6-joint arm away from singularities has one solution near the seed: not moved.
  const correct::Solution pose = correct::solve_pose(m, model::forward_kinematics(m, reference), true, reference);
  REQUIRE(pose.outcome == correct::Outcome::reached);
  CHECK(change(pose.q).norm() < 1e-9);
  CHECK_THROWS_AS(correct::solve_pose(m, goal, false, seed, {}, std::vector<double>{0.0}), std::invalid_argument);
}

TEST_CASE("solve_pose_along: the goal followed from the reference, where the way is plain the solve's readings") {
  const model::RobotModel m = robot("puma560.yaml");
  const std::vector<double> reference = {0.1, -0.4, 0.3, 0.2, -0.5, 0.7};
  model::Transform goal = model::forward_kinematics(m, reference);
  goal.translation += model::Vector3(2e-3, -1e-3, 3e-3);
  goal.rotation = Eigen::AngleAxisd(3e-3, model::Vector3(0.6, 0.0, 0.8)) * goal.rotation;
  for (const bool orientation : {true, false}) {
    const correct::Solution along = correct::solve_pose_along(m, goal, orientation, reference);
    const correct::Solution direct = correct::solve_pose(m, goal, orientation, reference);
    REQUIRE(along.outcome == correct::Outcome::reached);
    REQUIRE(direct.outcome == correct::Outcome::reached);
    CHECK(along.residual_m <= 1e-7);
    CHECK(along.iterations > direct.iterations);  // the steps on the way
    for (std::size_t j = 0; j < reference.size(); ++j) CHECK(along.q[j] == doctest::Approx(direct.q[j]).epsilon(1e-6));
  }
  CHECK_THROWS_AS(correct::solve_pose_along(m, goal, true, std::vector<double>{0.0}), std::invalid_argument);
}

TEST_CASE("target corrector: a solve landed on the mirrored elbow is followed again from the target's seed") {
  // The zoo's draw 5, kr16_2/tracker-6dof/coupled/100, targets.csv:120: the controller's readings
  // for the target (where the calibrated solve starts) lie just past the stretched elbow, and the
  // calibrated solve from them reached the mirrored elbow, 6.75 deg from the seed: refused, where
  // the true arm reaches the target turning joint 3 by 0.12 deg (q3 0.011776 rad).
  const model::RobotModel loaded =
      model::load_model(std::string(KINCAL_CORRECT_TEST_DIR) + "/kr16_coupled_stretched.yaml");
  const model::RobotModel calibrated = model::tool_at_tcp(loaded);
  const model::RobotModel nominal = model::tool_at_tcp(correct::nominal_from_record(loaded));
  const std::vector<double> seed = {2.85667317209, -1.4326681106,   0.00971802035018,
                                    4.91645386579, -0.836853358308, 2.01550899208};
  model::Transform pose;
  pose.translation = model::Vector3(0.132389664456, 3.56857318413, 0.522916241749);
  pose.rotation =
      Eigen::Quaterniond(0.647118708486, -0.401047832779, 0.133022532502, 0.634588858079).toRotationMatrix();
  const correct::CartesianSolver solver(nominal, calibrated, correct::TargetFrame::device);
  const correct::Solution controller = solver.solve_nominal(pose, true, seed);
  REQUIRE(controller.outcome == correct::Outcome::reached);
  const correct::Solution mirrored = solver.solve_calibrated(pose, true, controller.q, seed);
  REQUIRE(mirrored.outcome == correct::Outcome::reached);
  CHECK(std::abs(mirrored.q[2] - seed[2]) > 6.0 * std::numbers::pi / 180.0);  // the case as it was
  correct::TargetCorrector corrector(nominal, calibrated, correct::TargetFrame::device, std::nullopt);
  const correct::TargetResult r = corrector.correct({{120, true, seed, pose, true}}, {}, "targets.csv").front();
  REQUIRE(r.solution.outcome == correct::Outcome::reached);
  CHECK(r.change < 0.2 * std::numbers::pi / 180.0);
  CHECK(std::abs(r.solution.q[2] - 0.011776) < 1e-4);
  // Under a limit below that, the refusal names the smallest change found, not the mirrored elbow's.
  correct::JointChangeLimit tight;
  tight.revolute_rad = 0.05 * std::numbers::pi / 180.0;
  correct::TargetCorrector refusing(nominal, calibrated, correct::TargetFrame::device, std::nullopt, {}, tight);
  const correct::TargetResult refused = refusing.correct({{120, true, seed, pose, true}}, {}, "targets.csv").front();
  CHECK(refused.solution.outcome == correct::Outcome::joint_change_limit);
  CHECK(refused.change_joint == 2);
  CHECK(refused.change < 0.2 * std::numbers::pi / 180.0);
}

TEST_CASE("target corrector: a target whose smallest correction exceeds the limit is refused and named") {
  model::RobotModel start = robot("puma560.yaml");
  start.base_T_frame0 = model::Transform{};
  const model::RobotModel calibrated = perturbed(start, 2e-3, 2e-3, 6);
  const std::vector<double> q = {0.1, -0.4, 0.3, 0.2, -0.5, 0.7};
  model::Transform pose = model::forward_kinematics(start, q);
  const std::vector<correct::Target> targets = {{2, false, q, {}, false}, {3, true, q, pose, true}};
  correct::TargetCorrector within(start, calibrated, correct::TargetFrame::base, std::nullopt);
  for (const correct::TargetResult& r : within.correct(targets, {}, "t.csv")) {
    CHECK(r.solution.outcome == correct::Outcome::reached);
    CHECK(r.change_over_limit > 0.0);
    CHECK(r.change_over_limit <= 1.0);
  }
  correct::JointChangeLimit tight;
  tight.revolute_rad = 1e-5;
  correct::TargetCorrector beyond(start, calibrated, correct::TargetFrame::base, std::nullopt, {}, tight);
  for (const correct::TargetResult& r : beyond.correct(targets, {}, "t.csv")) {
    CHECK(r.solution.outcome == correct::Outcome::joint_change_limit);
    CHECK(r.solution.q == q);  // the readings left as they were
    CHECK(r.change_over_limit > 1.0);
    CHECK(r.change == doctest::Approx(r.change_over_limit * tight.revolute_rad));
    CHECK(r.solution.residual_m > 1e-4);  // the residual of the readings left
    // How near the model comes held within the limit is kept (no spread without a covariance).
    REQUIRE(r.within_limit);
    CHECK(r.within_limit->residual_m < r.solution.residual_m);
    CHECK(!r.within_limit->spread);
  }
}

TEST_CASE("target corrector: a redundant goal just past the limit in the smallest change is shared within it") {
  // A point target 150 mm off the PUMA's wrist leaves it three spare joints: the smallest change
  // (2-norm) turns one joint most; with the limit below that turn, the others take their share.
  model::RobotModel start = robot("puma560.yaml");
  start.base_T_frame0 = model::Transform{};
  start.flange_T_tool.translation = model::Vector3(0.05, 0.0, 0.15);
  const model::RobotModel calibrated = perturbed(start, 2e-3, 2e-3, 6);
  const std::vector<double> q = {0.1, -0.4, 0.3, 0.2, -0.5, 0.7};
  const std::vector<correct::Target> targets = {{3, true, q, model::forward_kinematics(start, q), false}};
  correct::TargetCorrector free(start, calibrated, correct::TargetFrame::base, std::nullopt);
  const correct::TargetResult smallest = free.correct(targets, {}, "t.csv").front();
  REQUIRE(smallest.solution.outcome == correct::Outcome::reached);
  INFO("the smallest change turns joint ", smallest.change_joint + 1, " by ", smallest.change, " rad");
  correct::JointChangeLimit tighter;
  tighter.revolute_rad = 0.9 * smallest.change;
  correct::TargetCorrector shared(start, calibrated, correct::TargetFrame::base, std::nullopt, {}, tighter);
  const correct::TargetResult r = shared.correct(targets, {}, "t.csv").front();
  CHECK(r.solution.outcome == correct::Outcome::reached);
  CHECK(r.change_over_limit <= 1.0);
  CHECK(r.solution.residual_m <= 1e-7);
  CHECK((model::forward_kinematics(calibrated, r.solution.q).translation - targets[0].pose.translation).norm() < 1e-6);
  // A limit no sharing meets: refused, the readings left.
  tighter.revolute_rad = 0.05 * smallest.change;
  correct::TargetCorrector none(start, calibrated, correct::TargetFrame::base, std::nullopt, {}, tighter);
  const correct::TargetResult refused = none.correct(targets, {}, "t.csv").front();
  CHECK(refused.solution.outcome == correct::Outcome::joint_change_limit);
  CHECK(refused.solution.q == q);
}

TEST_CASE("target corrector: a goal the model misses by less than its predicted spread counts as reached") {
  // The PUMA stretched toward a point far out of reach; goals just past that stretch, by a fifth,
  // 1.3 and three times the spread the model's covariance predicts there.
  model::RobotModel m = robot("puma560.yaml");
  m.base_T_frame0 = model::Transform{};
  for (model::Joint& j : m.joints) j.lower = -(j.upper = std::numeric_limits<double>::infinity());
  m.calibration = model::CalibrationRecord{};
  m.calibration->parameters = {{"a2", 0.0, 1e-4}, {"d3", 0.0, 1e-4}, {"theta2", 0.0, 1e-4}};
  const auto covariance = correct::record_covariance(m);
  REQUIRE(covariance);
  const std::vector<double> seed = {0.1, -0.4, 0.3, 0.2, -0.5, 0.7};
  model::Transform far = model::forward_kinematics(m, seed);
  far.translation *= 5.0;
  correct::SolveOptions to_the_end;  // the stretch to a tolerance far below the spread
  to_the_end.max_iterations = 2000;
  const correct::Solution stretched = correct::solve_pose(m, far, false, seed, to_the_end);
  REQUIRE(stretched.outcome != correct::Outcome::reached);
  INFO("stretched after ", stretched.iterations, " iterations, residual ", stretched.residual_m);
  const model::Vector3 edge = model::forward_kinematics(m, stretched.q).translation;
  const model::Vector3 out = (far.translation - edge).normalized();
  const double spread = correct::predicted_spread(m, *covariance, stretched.q, false).position_m;
  REQUIRE(spread > 1e-5);
  const auto target = [&](double beyond) {
    model::Transform goal = far;
    goal.translation = edge + beyond * spread * out;
    return std::vector<correct::Target>{{2, true, stretched.q, goal, false}};
  };
  correct::TargetCorrector with(m, m, correct::TargetFrame::base, covariance);
  const correct::TargetResult near = with.correct(target(0.2), {}, "t.csv").front();
  INFO("near: residual ", near.solution.residual_m, " of a spread ", spread);
  CHECK(near.solution.outcome == correct::Outcome::reached);
  REQUIRE(near.short_of);
  CHECK(*near.short_of != correct::Outcome::reached);
  CHECK(near.solution.residual_m > 0.1 * spread);  // the model's miss is kept and reported
  CHECK(near.solution.residual_m <= correct::kWithinSpread * spread);
  // A miss of 1.3 spreads is within what the model's own error reaches 19 times in 20 (one spread,
  // the rule before, refused it).
  const correct::TargetResult between = with.correct(target(1.3), {}, "t.csv").front();
  INFO("between: residual ", between.solution.residual_m, " of a spread ", spread);
  CHECK(between.solution.outcome == correct::Outcome::reached);
  CHECK(between.solution.residual_m > 1.1 * spread);
  const correct::TargetResult beyond = with.correct(target(3.0), {}, "t.csv").front();
  CHECK(beyond.solution.outcome != correct::Outcome::reached);
  CHECK(!beyond.short_of);
  // Without a covariance there is no spread to be within.
  correct::TargetCorrector without(m, m, correct::TargetFrame::base, std::nullopt);
  CHECK(without.correct(target(0.2), {}, "t.csv").front().solution.outcome != correct::Outcome::reached);
}

TEST_CASE("target corrector: held within the limit, a goal missed by less than the spread counts as reached") {
  // A full pose on the 6-joint PUMA has one solution near the seed; with the limit just below its
  // largest turn, the solve held within the limit misses the goal by a hair (near a singularity,
  // what the model cannot tell apart): reached when the model's predicted spread is more than
  // that miss, refused and named when it is less.
  model::RobotModel start = robot("puma560.yaml");
  start.base_T_frame0 = model::Transform{};
  const model::RobotModel calibrated = perturbed(start, 2e-3, 2e-3, 6);
  const std::vector<double> q = {0.1, -0.4, 0.3, 0.2, -0.5, 0.7};
  const std::vector<correct::Target> targets = {{3, true, q, model::forward_kinematics(start, q), true}};
  const correct::TargetResult smallest =
      correct::TargetCorrector(start, calibrated, correct::TargetFrame::base, std::nullopt)
          .correct(targets, {}, "t.csv")
          .front();
  REQUIRE(smallest.solution.outcome == correct::Outcome::reached);
  correct::JointChangeLimit limit;
  limit.revolute_rad = 0.99 * smallest.change;
  const auto with_sigma = [&](double sigma) {
    model::RobotModel m = calibrated;
    m.calibration = model::CalibrationRecord{};
    m.calibration->parameters = {{"a2", 0.0, sigma}, {"d3", 0.0, sigma}, {"theta2", 0.0, sigma}};
    const auto covariance = correct::record_covariance(m);
    REQUIRE(covariance);
    return correct::TargetCorrector(start, m, correct::TargetFrame::base, covariance, {}, limit)
        .correct(targets, {}, "t.csv")
        .front();
  };
  const correct::TargetResult wide = with_sigma(1e-3);
  INFO("held within the limit: residual ", wide.solution.residual_m, " m, ", wide.solution.residual_rad, " rad");
  CHECK(wide.solution.outcome == correct::Outcome::reached);
  REQUIRE(wide.short_of);
  CHECK(*wide.short_of != correct::Outcome::reached);
  CHECK(wide.change_over_limit <= 1.0);
  CHECK(wide.solution.residual_m > 1e-9);
  const correct::TargetResult narrow = with_sigma(1e-9);
  CHECK(narrow.solution.outcome == correct::Outcome::joint_change_limit);
  CHECK(narrow.solution.q == q);
  CHECK(narrow.change_over_limit > 1.0);
  // The nearest within the limit is the miss `wide` accepted, beyond the narrow spread there.
  REQUIRE(narrow.within_limit);
  REQUIRE(narrow.within_limit->spread);
  CHECK(narrow.within_limit->residual_m == doctest::Approx(wide.solution.residual_m).epsilon(1e-3));
  CHECK(narrow.within_limit->residual_m > correct::kWithinSpread * narrow.within_limit->spread->position_m);
}

TEST_CASE("Cartesian targets: base and device frames give the same readings; the seed's wrist is kept") {
  model::RobotModel start = robot("puma560.yaml");
  start.base_T_frame0 = model::Transform{};
  model::RobotModel calibrated = perturbed(start, 1e-3, 1e-3, 6);
  calibrated.base_T_frame0.translation = {1.5, -0.3, 0.2};
  calibrated.base_T_frame0.rotation = Eigen::AngleAxisd(0.7, model::Vector3::UnitZ()).toRotationMatrix();
  const correct::CartesianSolver in_base(start, calibrated, correct::TargetFrame::base);
  const correct::CartesianSolver in_device(start, calibrated, correct::TargetFrame::device);
  const std::vector<double> q = {0.1, -0.4, 0.3, 0.2, -0.5, 0.7};
  model::RobotModel arm = calibrated;
  arm.base_T_frame0 = model::Transform{};
  const model::Transform base_T_goal = model::forward_kinematics(start, q);  // start's base is the identity
  const correct::CartesianSolution a = in_base.solve(base_T_goal, true, q);
  const correct::CartesianSolution b = in_device.solve(calibrated.base_T_frame0 * base_T_goal, true, q);
  REQUIRE(a.calibrated.outcome == correct::Outcome::reached);
  REQUIRE(b.calibrated.outcome == correct::Outcome::reached);
  REQUIRE(a.nominal.outcome == correct::Outcome::reached);
  for (std::size_t j = 0; j < q.size(); ++j) {
    CHECK(a.calibrated.q[j] == doctest::Approx(b.calibrated.q[j]).epsilon(1e-6));
    CHECK(a.nominal.q[j] == doctest::Approx(q[j]).epsilon(1e-6));
  }
  CHECK((model::forward_kinematics(arm, a.calibrated.q).translation - base_T_goal.translation).norm() < 1e-7);
  // The wrist flipped (q4 + pi, -q5, q6 + pi): the same pose; each seed keeps its own branch.
  const std::vector<double> wrist = {0.1, -0.4, 0.3, -0.8, -0.5, 0.7};
  const std::vector<double> flipped = {0.1, -0.4, 0.3, -0.8 + std::numbers::pi, 0.5, 0.7 + std::numbers::pi};
  const model::Transform pose = model::forward_kinematics(start, wrist);
  const correct::CartesianSolution w = in_base.solve(pose, true, wrist), f = in_base.solve(pose, true, flipped);
  REQUIRE(w.calibrated.outcome == correct::Outcome::reached);
  REQUIRE(f.calibrated.outcome == correct::Outcome::reached);
  CHECK(std::abs(w.calibrated.q[3] - wrist[3]) < 0.01);
  CHECK(std::abs(f.calibrated.q[3] - flipped[3]) < 0.01);
}

TEST_CASE("nominal_from_record undoes the recorded changes; the spread is the covariance propagated") {
  const model::RobotModel start = robot("puma560.yaml");
  const std::vector<core::ParameterId> ids = {{core::ParameterKind::link_a, 1},
                                              {core::ParameterKind::link_theta, 2},
                                              {core::ParameterKind::tool_x, 0},
                                              {core::ParameterKind::tool_rz, 0},
                                              {core::ParameterKind::base_y, 0}};
  Eigen::VectorXd change(5);
  change << 1e-3, 2e-3, -5e-4, 3e-3, 0.02;
  model::RobotModel calibrated = model::apply_parameter_errors(start, ids, change);
  calibrated.calibration = model::CalibrationRecord{};
  const double stddev[5] = {1e-5, 2e-5, 3e-5, 4e-5, 5e-5};
  for (std::size_t k = 0; k < ids.size(); ++k)
    calibrated.calibration->parameters.push_back(
        {model::parameter_name(ids[k]), change(static_cast<Eigen::Index>(k)), stddev[k]});
  const model::RobotModel nominal = correct::nominal_from_record(calibrated);
  const std::vector<double> q = {0.1, -0.4, 0.3, 0.2, -0.5, 0.7};
  const model::Transform want = model::forward_kinematics(start, q), got = model::forward_kinematics(nominal, q);
  CHECK((want.translation - got.translation).norm() < 1e-12);
  CHECK((want.rotation - got.rotation).norm() < 1e-12);
  CHECK_THROWS_AS(correct::nominal_from_record(start), model::InputError);

  const auto covariance = correct::record_covariance(calibrated);
  REQUIRE(covariance);
  const Eigen::MatrixXd e = model::parameter_jacobian(calibrated, q, ids);
  double with_base = 0.0, without_base = 0.0;
  for (Eigen::Index k = 0; k < 5; ++k) {
    const double s2 = stddev[k] * stddev[k] * e.col(k).head<3>().squaredNorm();
    with_base += s2;
    if (k != 4) without_base += s2;
  }
  CHECK(correct::predicted_spread(calibrated, *covariance, q, true).position_m ==
        doctest::Approx(std::sqrt(with_base)));
  CHECK(correct::predicted_spread(calibrated, *covariance, q, false).position_m ==
        doctest::Approx(std::sqrt(without_base)));
  CHECK(correct::predicted_spread(calibrated, *covariance, q, true).orientation_rad > 0.0);
}

TEST_CASE("the spread: the recorded correlations and model error propagated; a record they cannot be is refused") {
  const model::RobotModel start = robot("puma560.yaml");
  const std::vector<core::ParameterId> ids = {
      {core::ParameterKind::link_a, 1}, {core::ParameterKind::link_theta, 2}, {core::ParameterKind::link_d, 3}};
  model::RobotModel calibrated = start;
  calibrated.calibration = model::CalibrationRecord{};
  model::CalibrationRecord& record = *calibrated.calibration;
  const double stddev[3] = {2e-5, 3e-5, 4e-5};
  for (std::size_t k = 0; k < ids.size(); ++k)
    record.parameters.push_back({model::parameter_name(ids[k]), 0.0, stddev[k]});
  record.correlations = {{-0.9}, {0.3, -0.2}};
  Eigen::Matrix3d c;
  c << 1.0, -0.9, 0.3, -0.9, 1.0, -0.2, 0.3, -0.2, 1.0;
  const Eigen::Vector3d s(stddev[0], stddev[1], stddev[2]);
  const Eigen::Matrix3d want = s.asDiagonal() * c * s.asDiagonal();
  const std::vector<double> q = {0.1, -0.4, 0.3, 0.2, -0.5, 0.7};
  const Eigen::MatrixXd e = model::parameter_jacobian(calibrated, q, ids);
  const auto position = [&](const Eigen::Matrix3d& parameters, double model_error) {
    return std::sqrt((e.topRows<3>() * parameters * e.topRows<3>().transpose()).trace() +
                     3.0 * model_error * model_error);
  };
  {
    const auto covariance = correct::record_covariance(calibrated);
    REQUIRE(covariance);
    CHECK((covariance->covariance - want).norm() < 1e-24);
    CHECK(correct::predicted_spread(calibrated, *covariance, q, false).position_m ==
          doctest::Approx(position(want, 0.0)));
    // The correlation is what makes the spread differ from the diagonal's rough scale.
    CHECK(std::abs(position(want, 0.0) - position(s.cwiseAbs2().asDiagonal(), 0.0)) > 0.05 * position(want, 0.0));
  }
  record.model_error_m = 1e-4;
  record.model_error_rad = 2e-4;
  {
    const auto covariance = correct::record_covariance(calibrated);
    REQUIRE(covariance);
    const correct::PoseSpread spread = correct::predicted_spread(calibrated, *covariance, q, false);
    CHECK(spread.position_m == doctest::Approx(position(want, 1e-4)));
    const Eigen::Matrix3d o = e.bottomRows<3>() * want * e.bottomRows<3>().transpose();
    CHECK(spread.orientation_rad == doctest::Approx(std::sqrt(o.trace() + 3.0 * 4e-8)));
  }
  // A parameter erased or added keeps the rows one per parameter after the first.
  model::CalibrationRecord edited = record;
  edited.erase_parameter(1);
  REQUIRE(edited.correlations.size() == 1);
  CHECK(edited.correlations[0] == std::vector<double>{0.3});
  edited.add_parameter({"d5", 0.0, 1e-5});
  CHECK(edited.correlations.back() == std::vector<double>{0.0, 0.0});
  edited.erase_parameter(0);
  CHECK(edited.correlations == std::vector<std::vector<double>>{{0.0}});
  // Correlations no covariance has (1, 2 and 1, 3 nearly one, 2, 3 nearly minus one), or of the wrong
  // shape: refused, naming what.
  record.correlations = {{0.99}, {0.99, -0.99}};
  CHECK_THROWS_WITH_AS(correct::record_covariance(calibrated), doctest::Contains("not positive semi-definite"),
                       model::InputError);
  record.correlations = {{0.5}};
  CHECK_THROWS_WITH_AS(correct::record_covariance(calibrated), doctest::Contains("one row per parameter"),
                       model::InputError);
}

TEST_CASE("joint offsets: the zero errors, exact when they are all the calibration found, partial otherwise") {
  const model::RobotModel start = robot("puma560.yaml");
  model::RobotModel zeros = start;
  const double error[6] = {1e-3, -2e-3, 5e-4, 0.0, 3e-3, -1e-3};
  for (std::size_t j = 0; j < 6; ++j) zeros.joints[j].offset += error[j];
  zeros.joints[1].parameters.theta_rad += 1e-3;  // theta and offset both count
  const std::vector<double> offsets = correct::joint_offsets(start, zeros);
  for (std::size_t j = 0; j < 6; ++j) CHECK(offsets[j] == doctest::Approx(error[j] + (j == 1 ? 1e-3 : 0.0)));
  const correct::OffsetShare all = correct::offset_share(start, zeros, offsets, 200, 1);
  CHECK(all.offsets_only.max_m < 1e-12);
  CHECK(all.nominal.rms_m > 1e-4);
  CHECK(all.carried == doctest::Approx(1.0));

  const model::RobotModel full = perturbed(start, 1e-3, 1e-3, 8);
  // Zero changes alone may even do harm where they compensate other changes; the fitted offsets
  // take what offsets can carry (judged on other readings than they were fitted on).
  const std::vector<double> raw = correct::joint_offsets(start, full);
  const std::vector<double> some = correct::fitted_joint_offsets(start, full, 300, 2);
  const correct::OffsetShare part = correct::offset_share(start, full, some, 200, 1);
  MESSAGE("zero changes carry " << correct::offset_share(start, full, raw, 200, 1).carried << ", fitted offsets "
                                << part.carried);
  CHECK(part.carried > correct::offset_share(start, full, raw, 200, 1).carried);
  CHECK(part.carried > 0.05);
  CHECK(part.carried < 0.95);
  // On measured rows (here the zero-error arm's own points): the offsets are all it takes.
  model::Dataset data;
  data.source = "rows";
  data.joint_count = 6;
  std::mt19937_64 rng(3);
  for (int i = 0; i < 30; ++i) {
    model::Measurement m;
    m.q = random_readings(rng);
    m.position = model::forward_kinematics(zeros, m.q).translation;
    data.rows.push_back(m);
  }
  const correct::OffsetShare measured = correct::offset_share(start, zeros, offsets, data);
  CHECK(measured.rows == 30);
  CHECK(measured.calibrated.max_m < 1e-12);
  CHECK(measured.offsets_only.max_m < 1e-12);
  CHECK(measured.nominal.rms_m > 1e-4);
  data.joint_count = 5;
  CHECK_THROWS_AS(correct::offset_share(start, zeros, offsets, data), model::InputError);
  const std::string file = correct::write_joint_offsets(full, some);
  CHECK(file.find("joint,name,type,offset\n1,waist,revolute,") != std::string::npos);

  model::RobotModel other = full;
  other.joints[2].convention = core::LinkConvention::modified_dh;
  CHECK_THROWS_WITH_AS(correct::joint_offsets(start, other), doctest::Contains("joint 3 differs"), model::InputError);
}
