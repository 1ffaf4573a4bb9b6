// cpa on sweeps as real robots give them (issue #12) and discovery without a model (issue #14):
// sweeps over more than a turn in steps over 180 deg, 5-reading sweeps with unknown noise, a
// declared type the data contradicts, outliers, uneven steps; the link table of a 6R arm and of
// Kapucu & Baysec's RRP arm found from sweeps alone.
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <string>

#include "host/identify/cpa.hpp"
#include "host/identify/discover.hpp"
#include "host/model/model_file.hpp"
#include "tests/host/identify/simulation.hpp"

namespace {

using namespace kincal;
using model::RobotModel;

constexpr double kDeg = std::numbers::pi / 180.0;

RobotModel robot(const char* name) { return model::load_model(std::string(KINCAL_ROBOTS_DIR) + "/" + name); }

std::vector<double> mid_limits(const RobotModel& m) {
  std::vector<double> home;
  for (const auto& j : m.joints) home.push_back(0.5 * (j.lower + j.upper) + 0.1);
  return home;
}

// `count` readings over `fraction` of each joint's range around home, uneven when `jitter`.
std::vector<std::vector<double>> readings(const RobotModel& m, const std::vector<double>& home, int count,
                                          double fraction, std::mt19937_64* jitter) {
  std::vector<std::vector<double>> r;
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (std::size_t j = 0; j < m.joints.size(); ++j) {
    const double span = fraction * (m.joints[j].upper - m.joints[j].lower);
    std::vector<double> q;
    for (int k = 0; k < count; ++k) {
      const double step = (k + (jitter && k > 0 && k + 1 < count ? u(*jitter) : 0.0)) / (count - 1);
      q.push_back(home[j] - 0.5 * span + span * step);
    }
    r.push_back(q);
  }
  return r;
}

bool has_note(const std::vector<std::string>& notes, const std::string& what) {
  for (const std::string& n : notes)
    if (n.find(what) != std::string::npos) return true;
  return false;
}

}  // namespace

TEST_CASE("cpa: a wrist sweep from -360 to +360 deg in 144 deg steps is a circle") {
  std::mt19937_64 rng(11);
  const RobotModel nominal = robot("puma560.yaml");
  const RobotModel truth = sim::perturbed(nominal, rng);
  const std::vector<double> home = mid_limits(nominal);
  auto r = readings(nominal, home, 10, 0.5, nullptr);
  r[5] = {-360 * kDeg, -216 * kDeg, -72 * kDeg, 72 * kDeg, 216 * kDeg, 360 * kDeg};
  const model::Dataset d =
      simulation::measure(truth, simulation::single_joint_sweeps(home, r), rng, 2e-5, false, 0.0, false);
  const identify::CpaResult cpa = identify::circle_point_analysis(nominal, d, {});
  const identify::SweepFit& wrist = cpa.fits[5];
  CHECK(wrist.test.p_line < 1e-6);
  CHECK(wrist.test.p_circle > 1e-3);
  CHECK(wrist.test.verdict == core::JointType::revolute);
  CHECK(!wrist.contradicts_model);
  CHECK(wrist.q_max - wrist.q_min == doctest::Approx(720 * kDeg));
  CHECK(!has_note(cpa.notes, "the model says"));
  const auto held_out = sim::random_configurations(nominal, 50, rng);
  CHECK(simulation::prediction_rms(cpa.model, truth, held_out) < 1e-3);
}

TEST_CASE("cpa: 5-reading sweeps with unknown noise; the noise is estimated") {
  std::mt19937_64 rng(12);
  const RobotModel nominal = robot("stanford_rrp.yaml");
  const RobotModel truth = sim::perturbed(nominal, rng);
  const std::vector<double> home = {0.1, 1.6, 0.8};
  const model::Dataset d =
      simulation::measure(truth, simulation::single_joint_sweeps(home, readings(nominal, home, 5, 0.5, &rng)), rng,
                          1e-4, false, 0.0, false);
  const identify::CpaResult cpa = identify::circle_point_analysis(nominal, d, {});
  for (const identify::SweepFit& f : cpa.fits) {
    CHECK(f.used == 5);
    CHECK(f.test.tested);
    CHECK(f.rms_m < 3e-4);
    CHECK(f.direction_stddev_rad > 0.0);
  }
  CHECK(has_note(cpa.notes, "too few to screen for outliers"));
  const auto held_out = sim::random_configurations(nominal, 50, rng);
  CHECK(simulation::prediction_rms(cpa.model, truth, held_out) < 2e-3);
}

TEST_CASE("cpa never refuses a type the data contradicts: it notes the p-values and fits the declared type") {
  std::mt19937_64 rng(13);
  const RobotModel nominal = robot("stanford_rrp.yaml");
  const std::vector<double> home = {0.1, 1.6, 0.8};
  const model::Dataset d =
      simulation::measure(nominal, simulation::single_joint_sweeps(home, readings(nominal, home, 10, 0.5, nullptr)),
                          rng, 1e-4, false, 0.0, true);
  RobotModel wrong = nominal;
  wrong.joints[0].type = core::JointType::prismatic;
  const identify::CpaResult cpa = identify::circle_point_analysis(wrong, d, {});
  CHECK(cpa.fits[0].contradicts_model);
  CHECK(!cpa.fits[0].curved);
  CHECK(cpa.fits[0].test.verdict == core::JointType::revolute);
  CHECK(has_note(cpa.notes, "joint 1 (lines 2-11): the model says prismatic but the sweep does not fit a line"));
  CHECK(has_note(cpa.notes, "p(line) = "));
  CHECK(!cpa.fits[2].contradicts_model);
}

TEST_CASE("discover: a 6R arm from sweeps alone, with an outlier and uneven steps") {
  std::mt19937_64 rng(14);
  const RobotModel nominal = robot("puma560.yaml");
  const RobotModel truth = sim::perturbed(nominal, rng);
  const std::vector<double> home = mid_limits(nominal);
  model::Dataset d =
      simulation::measure(truth, simulation::single_joint_sweeps(home, readings(nominal, home, 10, 0.5, &rng)), rng,
                          2e-5, false, 0.0, false);
  d.rows[24].position.y() += 0.005;  // a 5 mm blunder in the sweep of joint 3
  identify::DiscoverOptions o;
  const identify::DiscoverResult r = identify::discover(d, o);
  REQUIRE(r.model.joint_count() == 6);
  for (const identify::SweepFit& f : r.fits) {
    CHECK(f.curved);
    CHECK(f.test.conclusive);
  }
  CHECK(r.fits[2].rejected_lines == std::vector<int>{d.rows[24].line});
  // Shoulder and elbow axes are parallel: a Doty link between them.
  CHECK(r.model.joints[1].convention == core::LinkConvention::doty);
  const auto held_out = sim::random_configurations(nominal, 100, rng);
  CHECK(simulation::prediction_rms(r.model, truth, held_out) < 1e-3);
  for (const identify::LinkSpread& s : r.stddev) CHECK(s.a_m < 5e-3);
  CHECK(r.stddev[1].a_m > 0.0);
  const std::string text = identify::format_discovery(r);
  CHECK(text.find("joint 6: revolute; p(line affine in q) = ") != std::string::npos);
  CHECK(text.find("frame 0 (by convention)") != std::string::npos);
  // The model writes and reads back.
  const RobotModel back = model::parse_model(model::write_model(r.model), "discovered.yaml");
  CHECK(simulation::prediction_rms(back, r.model, held_out) < 1e-9);
}

TEST_CASE("discover: Kapucu & Baysec's RRP arm, the prismatic joint found") {
  std::mt19937_64 rng(15);
  const RobotModel truth = robot("stanford_rrp.yaml");
  const std::vector<double> home = {0.1, 1.6, 0.8};
  const model::Dataset d = simulation::measure(
      truth, simulation::single_joint_sweeps(home, readings(truth, home, 8, 0.5, &rng)), rng, 1e-9, false, 0.0, false);
  const identify::DiscoverResult r = identify::discover(d, {});
  REQUIRE(r.fits.size() == 3);
  CHECK(r.fits[0].curved);
  CHECK(r.fits[1].curved);
  CHECK(!r.fits[2].curved);
  CHECK(r.model.joints[2].type == core::JointType::prismatic);
  CHECK(r.model.joints[2].lower == doctest::Approx(d.rows[16].q[2]));
  const auto held_out = sim::random_configurations(truth, 50, rng);
  CHECK(simulation::prediction_rms(r.model, truth, held_out) < 1e-6);
}

TEST_CASE("discover: a joint that never moved alone is named") {
  std::mt19937_64 rng(16);
  const RobotModel truth = robot("stanford_rrp.yaml");
  const std::vector<double> home = {0.1, 1.6, 0.8};
  auto r = readings(truth, home, 8, 0.5, nullptr);
  r[1] = {home[1], home[1], home[1]};
  const model::Dataset d =
      simulation::measure(truth, simulation::single_joint_sweeps(home, r), rng, 1e-5, false, 0.0, false);
  try {
    (void)identify::discover(d, {});
    FAIL("no error");
  } catch (const model::InputError& e) {
    CHECK(std::string(e.what()).find("joint 2 has none") != std::string::npos);
  }
}

// Issue #44: a still tolerance above a joint's every step is named as such, not as a missing sweep.
TEST_CASE("discover: a still tolerance that leaves a joint still in every row is named") {
  std::mt19937_64 rng(17);
  const RobotModel truth = robot("stanford_rrp.yaml");
  const std::vector<double> home = {0.1, 1.6, 0.8};
  const model::Dataset d =
      simulation::measure(truth, simulation::single_joint_sweeps(home, readings(truth, home, 8, 0.5, nullptr)), rng,
                          1e-9, false, 0.0, false);
  identify::DiscoverOptions options;
  options.cpa.still_tolerance = 1.5;  // joint 1's steps: 0.37 rad in its sweep, 1.31 rad to and from home
  try {
    (void)identify::discover(d, options);
    FAIL("no error");
  } catch (const model::InputError& e) {
    INFO(e.what());
    CHECK(std::string(e.what()).find("--still-tolerance 1.5 leaves joint 1 still in every row: its reading changes by "
                                     "at most 1.3") != std::string::npos);
  }
  options.cpa.still_tolerance = 0.01;  // below every step: discovered as without one
  CHECK(identify::discover(d, options).fits.size() == 3);
}
