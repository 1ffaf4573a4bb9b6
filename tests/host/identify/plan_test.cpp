// kincal plan's candidates and constraints (issue #23): plans chosen only from the given
// configurations, no planned configuration violating a constraint over random constraint sets
// (checked here from the kinematics, not through violated_constraints), infeasible sets refused
// naming the constraint, and the constraints file's errors naming the key and line.
#include "host/identify/plan.hpp"
#include "host/identify/identify.hpp"
#include "host/identify/model_selection.hpp"
#include "host/identify/plan_constraints.hpp"
#include "host/model/model_file.hpp"

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace identify = kincal::identify;
namespace model = kincal::model;

namespace {

using model::Vector3;

model::RobotModel ur10() { return model::load_model(KINCAL_ROBOTS_DIR "/ur10.yaml"); }

// Frame origins 1..N and the tool point in frame 0, from the chain's frames.
std::vector<Vector3> points_in_frame0(const model::RobotModel& m, const std::vector<double>& q) {
  const model::ChainAtJoints at = model::chain_at_joints(m, q);
  const Eigen::Matrix3d r = m.base_T_frame0.rotation;
  const Vector3 t = m.base_T_frame0.translation;
  std::vector<Vector3> points;
  for (int i = 1; i <= m.joint_count(); ++i)
    points.push_back(r.transpose() * (at.frames.base_T_frame[static_cast<std::size_t>(i)].translation - t));
  points.push_back(r.transpose() * (model::forward_kinematics(m, q).translation - t));  // the tool point, last
  return points;
}

// Whether q meets every constraint, written from the definitions.
bool meets(const model::RobotModel& m, const identify::PlanConstraints& c, const std::vector<double>& q) {
  for (std::size_t j = 0; j < q.size(); ++j)
    if (q[j] < m.joints[j].lower || q[j] > m.joints[j].upper) return false;
  for (const identify::JointRange& r : c.joint_ranges)
    if (q[static_cast<std::size_t>(r.joint)] < r.lower || q[static_cast<std::size_t>(r.joint)] > r.upper) return false;
  const std::vector<Vector3> p = points_in_frame0(m, q);
  const Vector3& tool = p.back();
  if (c.workspace)
    for (int k = 0; k < 3; ++k)
      if (tool(k) < c.workspace->min_m(k) || tool(k) > c.workspace->max_m(k)) return false;
  if (c.floor)
    for (const Vector3& x : p)
      if ((x - c.floor->point_m).dot(c.floor->normal) < 0.0) return false;
  if (c.sight) {
    const Vector3 ray = (tool - c.sight->apex_m).normalized();
    if (std::acos(std::clamp(ray.dot(c.sight->axis), -1.0, 1.0)) > c.sight->half_angle_rad + 1e-12) return false;
  }
  return true;
}

std::vector<std::vector<double>> random_configurations(const model::RobotModel& m, int count, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> angle(-std::numbers::pi, std::numbers::pi);
  std::vector<std::vector<double>> out(static_cast<std::size_t>(count));
  for (auto& q : out)
    for (int j = 0; j < m.joint_count(); ++j) q.push_back(angle(rng));
  return out;
}

// A random constraint set around the UR10's reach: any of a floor, a box, a cone and two joint
// ranges, some of them infeasible with a few hundred candidates.
identify::PlanConstraints random_constraints(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u(0.0, 1.0);
  identify::PlanConstraints c;
  if (u(rng) < 0.7) c.floor = identify::FloorPlane{Vector3(0, 0, -0.3 + 0.5 * u(rng)), Vector3::UnitZ()};
  if (u(rng) < 0.5) {
    const Vector3 centre(u(rng) - 0.5, u(rng) - 0.5, 0.5 * u(rng));
    const Vector3 half = Vector3::Constant(0.4 + 0.8 * u(rng));
    c.workspace = identify::WorkspaceBox{centre - half, centre + half};
  }
  if (u(rng) < 0.5) {
    const Vector3 apex(0.4, -3.0, 0.3);
    c.sight = identify::SightCone{apex, (Vector3(0, 0, 0.5) - apex).normalized(),
                                  (10.0 + 20.0 * u(rng)) * std::numbers::pi / 180.0};
  }
  if (u(rng) < 0.5) {
    c.joint_ranges.push_back({1, -std::numbers::pi * u(rng), 0.5});
    c.joint_ranges.push_back({4, -2.0, -2.0 + 4.0 * u(rng) + 0.1});
  }
  return c;
}

std::string plan_error(const model::RobotModel& m, const identify::PlanOptions& o) {
  try {
    (void)identify::plan_configurations(m, o);
  } catch (const model::InputError& e) {
    return e.what();
  }
  return "";
}

std::string constraints_error(const std::string& text) {
  try {
    (void)identify::parse_plan_constraints(text, "c.yaml", ur10());
  } catch (const model::InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("plan --candidates: the plan holds distinct configurations of the given ones") {
  const model::RobotModel m = ur10();
  std::mt19937_64 rng(7);
  identify::PlanOptions o;
  o.count = 15;
  o.random_sets = 5;
  o.candidates = random_configurations(m, 100, rng);
  const identify::PlanResult r = identify::plan_configurations(m, o);
  REQUIRE(r.configurations.size() == 15);
  REQUIRE(r.chosen.size() == 15);
  std::vector<std::size_t> chosen = r.chosen;
  std::sort(chosen.begin(), chosen.end());
  CHECK(std::adjacent_find(chosen.begin(), chosen.end()) == chosen.end());
  for (std::size_t k = 0; k < r.chosen.size(); ++k) CHECK(r.configurations[k] == o.candidates[r.chosen[k]]);
  CHECK(r.considered == 100);
  CHECK(r.feasible == 100);
  // The exchange improves on random choices from the same candidates.
  CHECK(r.index > r.random_index_mean);
  // A candidate of the wrong length is refused.
  o.candidates[3].pop_back();
  CHECK(plan_error(m, o) == "plan: candidate 4 has 5 joint values, the model 6");
  // The same configuration twice: 100 copies of one row made a plan of 12 copies, exit 0.
  o.candidates[3] = o.candidates[2];
  CHECK(plan_error(m, o) ==
        "plan: candidate 4 is the same configuration as candidate 3 (a plan holds distinct "
        "configurations)");
  // More than kMaxCandidates, given or drawn, before any is evaluated (10^6 took 3.7 GB).
  o.candidates.assign(identify::kMaxCandidates + 1, std::vector<double>(6, 0.0));
  CHECK(plan_error(m, o) == "plan: 100001 candidate configurations, more than the 100000 a plan holds");
  o.candidates.clear();
  o.pool = static_cast<int>(identify::kMaxCandidates) + 1;
  CHECK(plan_error(m, o) == "plan: 100001 candidate configurations, more than the 100000 a plan holds");
}

TEST_CASE("no planned configuration violates a constraint, over random constraint sets and seeds") {
  const model::RobotModel m = ur10();
  int planned = 0, refused = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    CAPTURE(seed);
    std::mt19937_64 rng(seed);
    identify::PlanOptions o;
    o.count = 12;
    o.random_sets = 3;
    o.seed = seed;
    o.constraints = random_constraints(rng);
    o.candidates = random_configurations(m, 100, rng);
    int feasible = 0, floor_rejects = 0;
    for (const auto& q : o.candidates) {
      feasible += meets(m, o.constraints, q) ? 1 : 0;
      if (o.constraints.floor) {
        identify::PlanConstraints floor_only;
        floor_only.floor = o.constraints.floor;
        floor_only.joint_ranges.clear();
        floor_rejects += meets(m, floor_only, q) ? 0 : 1;
      }
    }
    if (feasible < o.count) {
      CHECK(plan_error(m, o).find("meet the constraints, 12 are asked for") != std::string::npos);
      ++refused;
      continue;
    }
    const identify::PlanResult r = identify::plan_configurations(m, o);
    CHECK(r.feasible == feasible);
    for (const identify::ConstraintOutcome& c : r.constraints)
      if (c.constraint == identify::Constraint::floor) CHECK(c.rejected == floor_rejects);
    for (const auto& q : r.configurations) CHECK(meets(m, o.constraints, q));
    ++planned;
    // The random pool is drawn and filtered within the same constraints.
    o.candidates.clear();
    o.pool = 60;
    const std::string error = plan_error(m, o);
    if (!error.empty()) {
      CHECK(error.find("meet the constraints") != std::string::npos);
      continue;
    }
    for (const auto& q : identify::plan_configurations(m, o).configurations) CHECK(meets(m, o.constraints, q));
  }
  // Both outcomes occur over these seeds.
  CHECK(planned >= 2);
  CHECK(refused >= 1);
}

TEST_CASE("an infeasible constraint is refused by name; a binding one is reported active") {
  const model::RobotModel m = ur10();
  std::mt19937_64 rng(3);
  identify::PlanOptions o;
  o.count = 12;
  o.random_sets = 3;
  o.candidates = random_configurations(m, 200, rng);
  o.constraints.floor = identify::FloorPlane{Vector3(0, 0, 3.0), Vector3::UnitZ()};  // above the UR10's reach
  CHECK(
      plan_error(m, o) ==
      "plan: 0 of 200 candidate configurations meet the constraints, 12 are asked for; no candidate meets floor: tool "
      "point and frame origins on the side of (0, 0, 1) of the plane through (0, 0, 3) m");
  o.candidates.clear();
  o.pool = 20;  // 2000 draws
  CHECK(plan_error(m, o).starts_with("plan: 0 of 2000 candidate configurations meet the constraints"));
  // The table at the base: half the candidates are below it, and the plan would take some.
  o.candidates = random_configurations(m, 120, rng);
  o.constraints.floor = identify::FloorPlane{Vector3(0, 0, 0.0), Vector3::UnitZ()};
  const identify::PlanResult r = identify::plan_configurations(m, o);
  REQUIRE(r.constraints.size() == 2);
  CHECK(r.constraints[0].constraint == identify::Constraint::joint_limits);
  CHECK(r.constraints[0].rejected == 0);
  CHECK_FALSE(r.constraints[0].active);
  CHECK(r.constraints[1].constraint == identify::Constraint::floor);
  CHECK(r.constraints[1].rejected > 40);
  CHECK(r.constraints[1].active);
  CHECK(r.constraints[1].index_gain > 1.0);
}

TEST_CASE("the constraints file: read in SI or degrees; errors name the key and line") {
  const identify::PlanConstraints c = identify::parse_plan_constraints(
      "angles: deg\nworkspace:\n  min: [-1, -1, 0.05]\n  max: [1, 1, 1.5]\nfloor:\n  point: [0, 0, 0.02]\n"
      "  normal: [0, 0, 2]\njoints:\n  shoulder_lift: [-180, 0]\n  q5: [-90, 90]\nsight:\n  apex: [0.4, -3.2, 0.2]\n"
      "  axis: [0, 1, 0]\n  half_angle: 30\n",
      "c.yaml", ur10());
  REQUIRE(c.workspace);
  CHECK(c.workspace->min_m == Vector3(-1, -1, 0.05));
  CHECK(c.floor->normal == Vector3::UnitZ());
  REQUIRE(c.joint_ranges.size() == 2);
  CHECK(c.joint_ranges[0].joint == 1);
  CHECK(c.joint_ranges[0].lower == doctest::Approx(-std::numbers::pi));
  CHECK(c.joint_ranges[1].joint == 4);
  CHECK(c.sight->half_angle_rad == doctest::Approx(std::numbers::pi / 6));
  CHECK(constraints_error("") == "c.yaml: no constraints (expected workspace, floor, joints or sight)");
  CHECK(constraints_error("angles: deg\n") ==
        "c.yaml:1:1: the file: no constraints (expected workspace, floor, joints or sight)");

  CHECK(constraints_error("flor:\n  point: [0, 0, 0]\n") ==
        "c.yaml:1:1: flor: unknown key (expected angles, workspace, floor, joints, sight)");
  CHECK(constraints_error("floor:\n  point: [0, 0]\n  normal: [0, 0, 1]\n") ==
        "c.yaml:2:10: floor.point: expected a list of 3 numbers");
  CHECK(constraints_error("floor:\n  point: [0, 0, 0]\n") == "c.yaml:2:3: floor.normal: missing");
  CHECK(constraints_error("floor:\n  point: [0, 0, 0]\n  normal: [0, 0, 0]\n") ==
        "c.yaml:3:11: floor.normal: a zero vector has no direction");
  CHECK(constraints_error("workspace:\n  min: [0, 0, 0]\n  max: [1, 1, x]\n") ==
        "c.yaml:3:15: workspace.max: 'x' is not a number");
  CHECK(constraints_error("workspace:\n  min: [0, 0, 0]\n  max: [1, -1, 1]\n") ==
        "c.yaml:3:8: workspace: min must be below max on every axis");
  CHECK(constraints_error("joints:\n  elbo: [0, 1]\n") ==
        "c.yaml:2:3: joints.elbo: the model 'ur10' has no such joint");
  CHECK(constraints_error("joints:\n  elbow: [0, 1]\n  q3: [0, 1]\n") ==
        "c.yaml:3:3: joints.q3: the joint is named twice");
  CHECK(constraints_error("joints:\n  elbow: [1, 0]\n") ==
        "c.yaml:2:10: joints.elbow: the lower end must be below the upper end");
  CHECK(constraints_error("joints:\n  elbow: [0, 7]\n")
            .starts_with("c.yaml:2:10: joints.elbow: the range leaves the joint's limits [-6.28"));
  CHECK(constraints_error("sight:\n  apex: [0, 0, 0]\n  axis: [0, 1, 0]\n  half_angle: 4\n") ==
        "c.yaml:4:15: sight.half_angle: expected more than 0 and less than 180 deg (pi rad)");
  CHECK(constraints_error("angles: grad\n") == "c.yaml:1:9: angles: expected deg or rad");
  CHECK(constraints_error("floor: [1, 2\n").starts_with("c.yaml:2:1: YAML syntax:"));
  CHECK(constraints_error("- 1\n") == "c.yaml:1:1: the file: expected a mapping");

  // The hostile-input audit: a key given twice or a second document was silently dropped, a
  // normal of 1e300 became the zero vector (every point on the floor's side), a dense list of 14
  // MB took 3.5 GB (files/yaml_limits.hpp).
  CHECK(constraints_error("floor:\n  point: [0, 0, 0]\n  normal: [0, 0, 1]\n  normal: [0, 0, -1]\n") ==
        "c.yaml:4:3: 'normal' given twice in this mapping (first at 3:3)");
  CHECK(constraints_error(
            "floor:\n  point: [0, 0, 0]\n  normal: [0, 0, 1]\nfloor: {point: [0, 0, 9], normal: [0, 0, 1]}\n") ==
        "c.yaml:4:1: 'floor' given twice in this mapping (first at 1:1)");
  CHECK(constraints_error("floor:\n  point: [0, 0, 0]\n  normal: [0, 0, 1]\n---\njoints: {elbow: [1, 0]}\n")
            .find(": a second YAML document") != std::string::npos);
  CHECK(constraints_error("? [floor]\n: 1\n") ==
        "c.yaml:1:3: the file: a key must be a name, not a list, a mapping or null");
  std::string dense = "floor:\n  point: [";
  for (int k = 0; k < 100001; ++k) dense += "0,";
  CHECK(constraints_error(dense + "0]\n  normal: [0, 0, 1]\n").starts_with("c.yaml:2:"));
  CHECK(constraints_error(dense + "0]\n  normal: [0, 0, 1]\n")
            .ends_with(": more than 100000 YAML nodes (values, lists, "
                       "mappings): too many for any file kincal reads"));
  CHECK(constraints_error("floor:\n  point: [" + std::string(600, '[') + std::string(600, ']') + "]\n")
            .find("lists and mappings nested more than") != std::string::npos);
  const identify::PlanConstraints far = identify::parse_plan_constraints(
      "floor:\n  point: [0, 0, 0]\n  normal: [1e300, 0, 1]\nsight:\n  apex: [0, 0, 0]\n  axis: [0, 1e-200, 0]\n"
      "  half_angle: 1\n",
      "c.yaml", ur10());
  CHECK(far.floor->normal == Vector3(1, 0, 1e-300));
  CHECK(far.sight->axis == Vector3::UnitY());
}

TEST_CASE("the constraints as options: read as the file's keys; errors name the key; file and options combine") {
  identify::ConstraintOptions o;
  o.angles = "deg";
  o.workspace = {"-1", "-1", "0.05", "1", "1", "1.5"};
  o.floor = {"0", "0", "0.02", "0", "0", "2"};
  o.joints = {{"shoulder_lift", {"-180", "0"}}, {"q5", {"-90", "90"}}};
  o.sight = {"0.4", "-3.2", "0.2", "0", "1", "0", "30"};
  const identify::PlanConstraints c = identify::plan_constraints_from_options(o, ur10());
  const identify::PlanConstraints f = identify::parse_plan_constraints(
      "angles: deg\nworkspace:\n  min: [-1, -1, 0.05]\n  max: [1, 1, 1.5]\nfloor:\n  point: [0, 0, 0.02]\n"
      "  normal: [0, 0, 2]\njoints:\n  shoulder_lift: [-180, 0]\n  q5: [-90, 90]\nsight:\n  apex: [0.4, -3.2, 0.2]\n"
      "  axis: [0, 1, 0]\n  half_angle: 30\n",
      "c.yaml", ur10());
  REQUIRE(c.workspace);
  CHECK(c.workspace->min_m == f.workspace->min_m);
  CHECK(c.workspace->max_m == f.workspace->max_m);
  CHECK(c.floor->point_m == f.floor->point_m);
  CHECK(c.floor->normal == f.floor->normal);
  REQUIRE(c.joint_ranges.size() == 2);
  for (std::size_t i = 0; i < 2; ++i) {
    CHECK(c.joint_ranges[i].joint == f.joint_ranges[i].joint);
    CHECK(c.joint_ranges[i].lower == f.joint_ranges[i].lower);
    CHECK(c.joint_ranges[i].upper == f.joint_ranges[i].upper);
  }
  CHECK(c.sight->apex_m == f.sight->apex_m);
  CHECK(c.sight->half_angle_rad == f.sight->half_angle_rad);

  const auto error = [](const identify::ConstraintOptions& options) -> std::string {
    try {
      (void)identify::plan_constraints_from_options(options, ur10());
    } catch (const model::InputError& e) {
      return e.what();
    }
    return "";
  };
  identify::ConstraintOptions bad;
  bad.workspace = {"0", "0", "0", "1", "-1", "1"};
  CHECK(error(bad) == "the command line: workspace: min must be below max on every axis");
  bad.workspace = {"0", "0", "0", "1", "1"};
  CHECK(error(bad) == "the command line: workspace.max: expected a list of 3 numbers");
  bad.workspace = {"0", "0", "0", "1", "1", "inf"};
  CHECK(error(bad) == "the command line: workspace.max: not finite");
  bad = {};
  bad.joints = {{"elbow", {"0", "1"}}, {"elbow", {"0", "2"}}};
  CHECK(error(bad) == "the command line: joints.elbow: the joint is named twice");
  bad.joints = {{"elbow", {"0", "x"}}};
  CHECK(error(bad) == "the command line: joints.elbow: 'x' is not a number");
  bad.joints = {{"wrist_9", {"0", "1"}}};
  CHECK(error(bad) == "the command line: joints.wrist_9: the model 'ur10' has no such joint");
  bad = {};
  bad.sight = {"0", "0", "0", "0", "1", "0"};
  CHECK(error(bad).starts_with("the command line: sight: expected 7 numbers"));
  bad = {};
  bad.angles = "deg";
  CHECK(error(bad) == "the command line: no constraint (expected --workspace, --floor, --joint-range or --sight)");

  // Together: the union, and a kind given twice refused, naming the file.
  identify::PlanConstraints from_file;
  from_file.floor = f.floor;
  from_file.joint_ranges = {f.joint_ranges[0]};
  identify::PlanConstraints options;
  options.workspace = f.workspace;
  options.joint_ranges = {f.joint_ranges[1]};
  const identify::PlanConstraints both = identify::combine_plan_constraints(from_file, "c.yaml", options);
  CHECK(both.floor);
  CHECK(both.workspace);
  CHECK(both.joint_ranges.size() == 2);
  options.floor = f.floor;
  CHECK_THROWS_WITH_AS(identify::combine_plan_constraints(from_file, "c.yaml", options),
                       "the command line and c.yaml both give a floor: give it in one place", model::InputError);
  options.floor.reset();
  options.joint_ranges = {f.joint_ranges[0]};
  CHECK_THROWS_WITH_AS(identify::combine_plan_constraints(from_file, "c.yaml", options),
                       "the command line and c.yaml both give a range of q2: give it in one place", model::InputError);
}

namespace {

// The prediction criterion of `plan` recomputed from its definition (plan.hpp), without the
// planner's scaling and updates: rows weighted by the pool's mean spreads of the joints' error
// (every UR10 joint is revolute), V = K K^T at each planned configuration, A the pool's mean of
// P^T P, L identify's default priors against a model error of 0.25 mm;
// sqrt(tr(A (M + L)^-1 (N + L) (M + L)^-1)). gravity: the parameters are those of identify's
// geometry+gravity candidate (the UR10 has masses).
double prediction_rms_of(const model::RobotModel& m, const identify::ParameterIds& ids,
                         const std::vector<std::vector<double>>& pool, const std::vector<std::vector<double>>& plan,
                         int rows, bool gravity) {
  const model::RobotModel start =
      identify::reparameterize_for_identification(gravity ? *identify::gravity_model(m) : m, 0.1, nullptr);
  double position = 0.0, orientation = 0.0;
  for (const auto& q : pool) {
    const Eigen::MatrixXd k = model::joint_jacobian(m, q);
    position += k.topRows(3).squaredNorm();
    orientation += k.bottomRows(3).squaredNorm();
  }
  Eigen::VectorXd w(rows);
  w.head(3).setConstant(std::sqrt(3.0 * static_cast<double>(pool.size()) / position));
  if (rows == 6) w.tail(3).setConstant(std::sqrt(3.0 * static_cast<double>(pool.size()) / orientation));
  const auto p = static_cast<Eigen::Index>(ids.size());
  Eigen::MatrixXd a = Eigen::MatrixXd::Zero(p, p), info = a;
  const Eigen::VectorXd sigmas = identify::prior_sigmas(identify::PriorOptions{}, ids, 6, "test");
  for (Eigen::Index c = 0; c < p; ++c) info(c, c) = std::pow(0.25e-3 * w(0) / sigmas(c), 2);
  Eigen::MatrixXd noise = info;
  for (const auto& q : pool) {
    const Eigen::MatrixXd position_rows = w(0) * model::parameter_jacobian(start, q, ids).topRows(3);
    a += position_rows.transpose() * position_rows / static_cast<double>(pool.size());
  }
  for (const auto& q : plan) {
    const Eigen::MatrixXd j = w.asDiagonal() * model::parameter_jacobian(start, q, ids).topRows(rows);
    const Eigen::MatrixXd k = w.asDiagonal() * model::joint_jacobian(m, q).topRows(rows);
    info += j.transpose() * j;
    noise += j.transpose() * k * k.transpose() * j;
  }
  const Eigen::MatrixXd inverse = info.inverse();
  return std::sqrt((a * inverse * noise * inverse).trace());
}

}  // namespace

TEST_CASE("the prediction criterion: its value recomputed, and no single exchange improves the plan") {
  const model::RobotModel m = ur10();
  std::mt19937_64 rng(11);
  identify::PlanOptions o;
  o.count = 12;
  o.random_sets = 10;
  o.orientation = true;
  o.candidates = random_configurations(m, 80, rng);
  const identify::PlanResult r = identify::plan_configurations(m, o);
  CHECK(r.criterion == identify::PlanCriterion::prediction);
  CHECK(r.gravity);
  const double rms = prediction_rms_of(m, r.identified, o.candidates, r.configurations, 6, r.gravity);
  CHECK(r.prediction_rms == doctest::Approx(rms).epsilon(1e-6));
  CHECK(r.prediction_rms < r.random_prediction_rms);
  // The rotation rows' weight: the joints' lever arm over the candidates.
  double position = 0.0, orientation = 0.0;
  for (const auto& q : o.candidates) {
    position += model::joint_jacobian(m, q).topRows(3).squaredNorm();
    orientation += model::joint_jacobian(m, q).bottomRows(3).squaredNorm();
  }
  CHECK(r.lever_m == doctest::Approx(std::sqrt(position / orientation)).epsilon(1e-9));
  // A local optimum of the criterion as defined: every exchange of a planned configuration for
  // another candidate leaves the recomputed rms as it is or larger.
  int worse = 0;
  for (std::size_t i = 0; i < r.configurations.size(); ++i)
    for (std::size_t c = 0; c < o.candidates.size(); c += 3) {
      if (std::find(r.chosen.begin(), r.chosen.end(), c) != r.chosen.end()) continue;
      std::vector<std::vector<double>> exchanged = r.configurations;
      exchanged[i] = o.candidates[c];
      worse += prediction_rms_of(m, r.identified, o.candidates, exchanged, 6, r.gravity) < rms * (1.0 - 1e-6) ? 1 : 0;
    }
  CHECK(worse == 0);
  // The D-optimal plan of the same candidates predicts worse by this criterion.
  o.criterion = identify::PlanCriterion::d_optimal;
  const identify::PlanResult d = identify::plan_configurations(m, o);
  CHECK(d.criterion == identify::PlanCriterion::d_optimal);
  CHECK_FALSE(d.gravity);  // O1 plans for the geometry (plan.hpp)
  CHECK(
      d.prediction_rms ==
      doctest::Approx(prediction_rms_of(m, d.identified, o.candidates, d.configurations, 6, d.gravity)).epsilon(1e-6));
  CHECK(d.prediction_rms > r.prediction_rms);
}

TEST_CASE("as few configurations as the parameters allow; with masses, the gravity terms when they fit") {
  // Positions only: 3 rows a configuration, so a plan without one of its configurations has fewer
  // rows than parameters (the exchange's direct evaluation). The UR10 has masses: planned for the
  // gravity compliances when the plan's equations carry them, else the geometry alone.
  const model::RobotModel m = ur10();
  std::mt19937_64 rng(5);
  identify::PlanOptions o;
  o.random_sets = 10;
  o.candidates = random_configurations(m, 60, rng);
  o.count = 40;
  const identify::PlanResult loaded = identify::plan_configurations(m, o);
  const auto compliance = [](const identify::ParameterIds& ids) {
    return std::count_if(ids.begin(), ids.end(),
                         [](const kincal::core::ParameterId& id) { return id.kind == model::kJointCompliance; });
  };
  CHECK(loaded.gravity);
  CHECK(loaded.gravity_needs == 0);
  CHECK(compliance(loaded.identified) > 0);
  const auto p = static_cast<int>(loaded.identified.size());
  o.count = (p + 2) / 3;
  CAPTURE(p);
  const identify::PlanResult r = identify::plan_configurations(m, o);
  REQUIRE(r.configurations.size() == static_cast<std::size_t>(o.count));
  CHECK(r.gravity);
  CHECK(r.lever_m == 0.0);
  CHECK(std::isfinite(r.prediction_rms));
  CHECK(
      r.prediction_rms ==
      doctest::Approx(prediction_rms_of(m, r.identified, o.candidates, r.configurations, 3, r.gravity)).epsilon(1e-6));
  // Too few configurations for the gravity terms: the geometry alone, never a refusal, and what
  // gravity needs.
  o.count = p / 3 - 1;
  const identify::PlanResult geometry = identify::plan_configurations(m, o);
  CHECK_FALSE(geometry.gravity);
  CHECK(geometry.gravity_needs == (p + 2) / 3);
  CHECK(compliance(geometry.identified) == 0);
  // Asked not to: the geometry.
  o.count = 40;
  o.gravity = false;
  CHECK_FALSE(identify::plan_configurations(m, o).gravity);
}
