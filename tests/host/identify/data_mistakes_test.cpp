// Mistakes made of plausible numbers (data_mistakes.hpp, issue #41): a mirrored device frame,
// swapped joint columns, a joint in another convention, logs joined out of step and an instrument
// moved halfway are found on every robot here with the measured point off the nominal tool,
// held-out rows that are training rows are counted, and a fit that explains nothing is named --
// while the same data without the mistake, with arms of millimetre errors, give no finding.
#include <doctest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <string>
#include <utility>

#include <Eigen/Geometry>

#include "host/identify/data_mistakes.hpp"
#include "host/identify/identify.hpp"
#include "host/identify/plausibility.hpp"
#include "host/model/dataset.hpp"
#include "host/model/model_file.hpp"
#include "host/sim/robot.hpp"
#include "tests/host/identify/simulation.hpp"

namespace kincal {
namespace {

model::RobotModel robot(const std::string& name) {
  return model::load_model(std::string(KINCAL_ROBOTS_DIR) + "/" + name);
}

bool mentions(const std::vector<std::string>& found, const std::string& text) {
  for (const std::string& f : found)
    if (f.find(text) != std::string::npos) return true;
  return false;
}

// The parameters a calibration identified: what moved_against's significance test counts.
int identified(const identify::IdentifyResult& r) { return static_cast<int>(r.identifiability.identified.size()); }

// A truth with `error` sized geometry errors and a measured point 50-150 mm off the nominal tool,
// measured in a device frame placed anywhere: rows of `count` random configurations.
model::RobotModel tracker_truth(const model::RobotModel& nominal, std::mt19937_64& rng, double error_m) {
  sim::ErrorScale scale;
  scale.length_m = error_m;
  scale.angle_rad = error_m;  // 1 mm ~ 0.06 deg
  model::RobotModel truth = sim::perturbed(nominal, rng, scale);
  std::uniform_real_distribution<double> offset(0.05, 0.15), angle(-3.0, 3.0), unit(-1.0, 1.0);
  const Eigen::Vector3d reflector = offset(rng) * Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized();
  truth.flange_T_tool.translation = nominal.flange_T_tool.translation + nominal.flange_T_tool.rotation * reflector;
  truth.base_T_frame0.rotation =
      Eigen::AngleAxisd(angle(rng), Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized()).toRotationMatrix() *
      truth.base_T_frame0.rotation;
  truth.base_T_frame0.translation += Eigen::Vector3d(unit(rng), unit(rng), unit(rng)) * 3.0;
  return truth;
}

model::Dataset tracker_rows(const model::RobotModel& nominal, std::mt19937_64& rng, double error_m, int count) {
  const model::RobotModel truth = tracker_truth(nominal, rng, error_m);
  return simulation::measure(truth, sim::random_configurations(nominal, count, rng), rng, 2e-5, false, 0.0, false);
}

TEST_CASE("a mirrored device frame and swapped joint columns are found on every robot, correct data never") {
  std::mt19937_64 rng(41);
  for (const char* name : {"ur10.yaml", "puma560.yaml", "stanford_rrp.yaml", "heavy6r.yaml", "arid_prrr.yaml"}) {
    CAPTURE(name);
    const model::RobotModel nominal = robot(name);
    for (const double error_m : {2e-4, 3e-3}) {
      CAPTURE(error_m);
      for (const int count : {20, 150}) {
        CAPTURE(count);
        const model::Dataset data = tracker_rows(nominal, rng, error_m, count);
        CHECK(identify::frame_check(nominal, data).mistakes.empty());
        CHECK(identify::implausibilities(nominal, data).empty());

        model::Dataset mirrored = data;  // x and y exchanged at export
        for (model::Measurement& r : mirrored.rows) std::swap(r.position.x(), r.position.y());
        const std::vector<std::string> found = identify::frame_check(nominal, mirrored).mistakes;
        CHECK(mentions(found, "mirror image"));
        CHECK(mentions(identify::implausibilities(nominal, mirrored), "mirror image"));
        model::Dataset flipped = data;  // one axis flipped
        for (model::Measurement& r : flipped.rows) r.position.z() = -r.position.z();
        CHECK(mentions(identify::frame_check(nominal, flipped).mistakes, "mirror image"));

        model::Dataset swapped = data;  // the first two joint columns of the same type exchanged
        int j = -1, k = -1;
        for (int a = 0; a < nominal.joint_count() && k < 0; ++a)
          for (int b = a + 1; b < nominal.joint_count() && k < 0; ++b)
            if (nominal.joints[static_cast<std::size_t>(a)].type == nominal.joints[static_cast<std::size_t>(b)].type)
              j = a, k = b;
        REQUIRE(k >= 0);
        for (model::Measurement& r : swapped.rows)
          std::swap(r.q[static_cast<std::size_t>(j)], r.q[static_cast<std::size_t>(k)]);
        const std::vector<std::string> swap_found = identify::frame_check(nominal, swapped).mistakes;
        // Exchanging two joints may move the tool by little (the Stanford arm's first two at
        // small readings): found, or nothing found -- never a mirror.
        CHECK_FALSE(mentions(swap_found, "mirror image"));
        if (!swap_found.empty())
          CHECK(mentions(swap_found, "joint columns " + std::to_string(j + 1) + " (" +
                                         nominal.joints[static_cast<std::size_t>(j)].name + ") and " +
                                         std::to_string(k + 1)));
      }
    }
  }
}

TEST_CASE("logs joined out of step and an instrument moved during the session are named on every robot") {
  std::mt19937_64 rng(43);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (const std::string name : {"ur10.yaml", "puma560.yaml", "stanford_rrp.yaml", "heavy6r.yaml", "arid_prrr.yaml"}) {
    CAPTURE(name);
    const model::RobotModel nominal = robot(name);
    for (const int count : {40, 150}) {
      CAPTURE(count);
      const model::Dataset data = tracker_rows(nominal, rng, 1e-3, count);
      CHECK(identify::frame_check(nominal, data).mistakes.empty());

      model::Dataset shifted = data;  // each row's position is the next row's: the logs a row apart
      for (std::size_t i = 0; i + 1 < data.rows.size(); ++i) shifted.rows[i].position = data.rows[i + 1].position;
      shifted.rows.pop_back();
      const std::vector<std::string> shift_found = identify::frame_check(nominal, shifted).mistakes;
      CHECK(mentions(shift_found, "1 row earlier in the file than their readings"));
      CHECK(mentions(shift_found, "joined out of step by 1 row"));

      // The tracker bumped at 60 % of the session: 2 deg and 10 mm (a move that leaves the one
      // registration within 10 mm is not found: data_mistakes.hpp).
      model::Dataset moved = data;
      const std::size_t from = data.rows.size() * 3 / 5;
      const Eigen::AngleAxisd turn(std::numbers::pi / 180.0,
                                   Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized());
      for (std::size_t i = from; i < data.rows.size(); ++i)
        moved.rows[i].position = turn * data.rows[i].position + Eigen::Vector3d(0.006, -0.008, 0.0);
      const std::vector<std::string> move_found = identify::frame_check(nominal, moved).mistakes;
      CHECK(mentions(move_found, "the instrument (or the robot's base) moved during the session"));
      int near = 0;  // the line named is the move's, or next to it (noise decides a row either way)
      for (int d = -2; d <= 2; ++d)
        near += mentions(move_found, "from about line " + std::to_string(data.rows[from].line + d) + " on") ? 1 : 0;
      CHECK(near == 1);
      CHECK(mentions(identify::implausibilities(nominal, moved), "moved during the session"));
    }
  }
}

TEST_CASE("a reflector re-seated in another nest during the session is named as the point, not the instrument") {
  std::mt19937_64 rng(61);
  for (const std::string name : {"ur10.yaml", "puma560.yaml", "stanford_rrp.yaml", "heavy6r.yaml", "arid_prrr.yaml"}) {
    CAPTURE(name);
    const model::RobotModel nominal = robot(name);
    for (const int count : {40, 150}) {
      CAPTURE(count);
      const model::RobotModel truth = tracker_truth(nominal, rng, 1e-3);
      const std::vector<std::vector<double>> q = sim::random_configurations(nominal, count, rng);
      model::Dataset data = simulation::measure(truth, q, rng, 2e-5, false, 0.0, false);
      // The nest 40 mm from the first, from 60 % of the rows on (a move that leaves one offset
      // within 10 mm is not found before the solve: data_mistakes.hpp).
      model::RobotModel reseated = truth;
      reseated.flange_T_tool.translation += truth.flange_T_tool.rotation * model::Vector3(0.032, -0.019, 0.014);
      const model::Dataset second = simulation::measure(reseated, q, rng, 2e-5, false, 0.0, false);
      const std::size_t from = data.rows.size() * 3 / 5;
      for (std::size_t i = from; i < data.rows.size(); ++i) data.rows[i].position = second.rows[i].position;
      const std::vector<std::string> found = identify::frame_check(nominal, data).mistakes;
      CHECK(mentions(found, "the measured point moved on the arm during the session"));
      CHECK_FALSE(mentions(found, "the instrument (or the robot's base) moved"));
    }
  }
}

TEST_CASE("a service arm's tracker moved: found against the calibrated model where its errors hide it") {
  // identify runs frame_check again against the calibrated model when the fit explains nothing:
  // the true model stands in for it here. The heavy arm with 5 mm, 1 deg errors: against the
  // nominal, one registration leaves tens of millimetres and so do two.
  std::mt19937_64 rng(11);
  const model::RobotModel nominal = robot("heavy6r.yaml");
  sim::ErrorScale scale;
  scale.length_m = 5e-3;
  scale.angle_rad = 1.7e-2;
  const model::RobotModel truth = sim::perturbed(nominal, rng, scale);
  model::Dataset moved =
      simulation::measure(truth, sim::random_configurations(nominal, 150, rng), rng, 2e-5, false, 0.0, false);
  const Eigen::AngleAxisd turn(std::numbers::pi / 180.0, Eigen::Vector3d(1.0, 2.0, 3.0).normalized());
  for (std::size_t i = 90; i < moved.rows.size(); ++i) moved.rows[i].position = turn * moved.rows[i].position;
  CHECK(mentions(identify::frame_check(truth, moved).mistakes,
                 "from about line " + std::to_string(moved.rows[90].line) + " on"));
  CHECK(mentions(identify::frame_check(truth, moved).mistakes, "moved during the session"));
}

TEST_CASE("a precise arm's tracker nudged under the floor: found against the calibrated model, clean data never") {
  // 1 deg and 5 mm from 60 % of 40 rows on: one registration leaves millimetres (under
  // kMistakeFloor_m, so frame_check says nothing), and a calibration absorbs some of it into the
  // geometry -- the zoo's irb2400 left 7.4 mm calibrated and its verdict called the arm "close to
  // its nominal geometry". Against the calibrated model, a registration of their own from the
  // move on fits far better; the same rows without the move never do.
  std::mt19937_64 rng(23);
  for (const std::string name : {"ur10.yaml", "puma560.yaml", "heavy6r.yaml"}) {
    CAPTURE(name);
    const model::RobotModel nominal = robot(name);
    const model::Dataset data = tracker_rows(nominal, rng, 2e-4, 40);
    model::Dataset moved = data;
    const std::size_t from = data.rows.size() * 3 / 5;
    const Eigen::AngleAxisd turn(std::numbers::pi / 180.0, Eigen::Vector3d(1.0, -2.0, 0.5).normalized());
    const Eigen::Vector3d centre = data.rows[from].position;  // a tracker turned about itself, near the arm
    for (std::size_t i = from; i < data.rows.size(); ++i)
      moved.rows[i].position = centre + turn * (data.rows[i].position - centre) + Eigen::Vector3d(0.003, 0.0, -0.004);
    const identify::IdentifyResult clean = identify::identify(nominal, data, identify::IdentifyOptions{});
    CHECK_FALSE(identify::moved_against(clean.model, data, false, identified(clean)));
    const identify::IdentifyResult r = identify::identify(nominal, moved, identify::IdentifyOptions{});
    MESSAGE(name << ": calibrated on the moved rows to " << r.residuals.rms_m * 1e3 << " mm RMS");
    const std::optional<std::string> found = identify::moved_against(r.model, moved, false, identified(r));
    REQUIRE(found);
    CHECK(mentions({*found}, "moved during the session"));
    int near = 0;
    for (int d = -2; d <= 2; ++d)
      near += mentions({*found}, "from about line " + std::to_string(data.rows[from].line + d) + " on") ? 1 : 0;
    CHECK(near == 1);
  }
}

TEST_CASE("a reflector re-seated for the last 8 of 20 rows, absorbed by a calibration with scales: named") {
  // The zoo's draw 8, ur10/tracker-point/scaled/20/marker-moved (its independent simulator's rows):
  // a UR10 with a joint's reading off its scale, a reflector 70 mm off the flange re-seated 40 mm
  // away for the last 8 of 20 rows. Calibrated with every joint's scale (model selection's choice
  // there), 33 parameters absorb most of the re-seat and leave 14 mm RMS: unexplained. A second
  // part fits the calibrated model 2.2 times better -- under kCalibratedMovedRatio, which decides
  // alone where a fit looks right, so it was not named -- and its 9 parameters are significant
  // against the 18 degrees of freedom left (p 1.4e-4). The same rows without the re-seat give nothing.
  const std::string dir = KINCAL_TEST_DATA_DIR;
  model::RobotModel nominal = model::load_model(std::string(KINCAL_ROBOTS_DIR) + "/ur10.urdf", {"", "tool0"});
  for (model::Joint& j : nominal.joints) j.scale = 1.0;
  const model::Dataset clean_rows = model::read_dataset(dir + "/ur10_marker_clean.csv");
  const model::Dataset moved = model::read_dataset(dir + "/ur10_marker_reseated.csv");
  const identify::IdentifyResult clean = identify::identify(nominal, clean_rows, identify::IdentifyOptions{});
  const identify::IdentifyResult r = identify::identify(nominal, moved, identify::IdentifyOptions{});
  MESSAGE("calibrated to " << clean.residuals.rms_m * 1e3 << " mm RMS, with the re-seat " << r.residuals.rms_m * 1e3
                           << " mm");
  CHECK_FALSE(identify::moved_against(clean.model, clean_rows, false, identified(clean)));
  REQUIRE(identify::unexplained_fit(r.residuals.rms_m, 0.0));
  CHECK_FALSE(identify::moved_against(r.model, moved, false, identified(r)));
  const std::optional<std::string> found = identify::moved_against(r.model, moved, true, identified(r));
  REQUIRE(found);
  MESSAGE(*found);
  CHECK(mentions({*found}, "the measured point moved on the arm during the session"));
  CHECK(mentions({*found}, "from about line 14 on"));
}

TEST_CASE("single-joint sweeps of an arm far off its drawing: no move, no shift is found") {
  // A sweep of the wrist alone, the others at home, is a rigid motion of the whole wrist whatever
  // the earlier joints' errors: a registration of its own for that part fits it exactly. The move
  // check asks every joint to move in both parts, so such a file is not called "moved" (without
  // that, the PUMA's sweeps below were: 2.2 mm with a second registration after joint 2's sweep,
  // 10.2 mm with one).
  std::mt19937_64 rng(5);
  for (const std::string name : {"ur10.yaml", "puma560.yaml", "heavy6r.yaml"}) {
    CAPTURE(name);
    const model::RobotModel nominal = robot(name);
    model::RobotModel truth = nominal;  // two link lengths 40 mm off (the drawing of another model)
    truth.joints[1].parameters.a_m += 0.04;
    truth.joints[2].parameters.a_m -= 0.04;
    std::vector<std::vector<double>> readings;
    for (std::size_t j = 0; j < nominal.joints.size(); ++j) {  // 12 steps of 0.2 rad each
      readings.emplace_back();
      for (int k = 0; k < 12; ++k) readings.back().push_back(-1.2 + 0.2 * k);
    }
    const model::Dataset sweeps = simulation::measure(
        truth, simulation::single_joint_sweeps(std::vector<double>(nominal.joints.size(), 0.3), readings), rng, 2e-5,
        false, 0.0, false);
    const std::vector<std::string> found = identify::frame_check(nominal, sweeps).mistakes;
    CHECK_FALSE(mentions(found, "moved during the session"));
    CHECK_FALSE(mentions(found, "out of step"));
  }
}

TEST_CASE("joint columns in reverse order are named") {
  std::mt19937_64 rng(71);
  for (const std::string name : {"ur10.yaml", "puma560.yaml", "heavy6r.yaml"}) {
    CAPTURE(name);
    const model::RobotModel nominal = robot(name);
    model::Dataset data = tracker_rows(nominal, rng, 1e-3, 60);
    for (model::Measurement& r : data.rows) std::reverse(r.q.begin(), r.q.end());
    CHECK(mentions(identify::frame_check(nominal, data).mistakes, "the joint columns in reverse order"));
  }
}

TEST_CASE("swapped joint columns of a six-axis arm are named") {
  std::mt19937_64 rng(7);
  const model::RobotModel nominal = robot("ur10.yaml");
  model::Dataset data = tracker_rows(nominal, rng, 1e-3, 60);
  for (model::Measurement& r : data.rows) std::swap(r.q[1], r.q[2]);
  const std::vector<std::string> found = identify::frame_check(nominal, data).mistakes;
  CHECK(mentions(found, "joint columns 2 (" + nominal.joints[1].name + ") and 3 (" + nominal.joints[2].name + ")"));
  CHECK(mentions(found, "likely two joint columns swapped"));
}

TEST_CASE("a joint counted the other way round, from another zero or relative to the one before is named") {
  std::mt19937_64 rng(47);
  int invisible = 0;
  for (const std::string name : {"ur10.yaml", "puma560.yaml", "stanford_rrp.yaml", "heavy6r.yaml", "arid_prrr.yaml"}) {
    CAPTURE(name);
    const model::RobotModel nominal = robot(name);
    const model::Dataset data = tracker_rows(nominal, rng, 1e-3, 60);
    const auto revolute = [&](std::size_t j) { return nominal.joints[j].type == core::JointType::revolute; };
    // The joints between the base (whose zero is the registration's) and the last (whose zero is
    // the measured point's): each way the file may differ, named with its joint -- as the best
    // fit or as one that fits as well (a spherical wrist's joint 5 reversed is joint 4 half a turn on).
    for (std::size_t j = 1; j + 1 < nominal.joints.size(); ++j) {
      CAPTURE(j);
      const std::string joint = "joint " + std::to_string(j + 1) + " (" + nominal.joints[j].name + ") read ";
      model::Dataset negated = data;
      for (model::Measurement& r : negated.rows) r.q[j] = -r.q[j];
      const std::vector<std::string> found = identify::frame_check(nominal, negated).mistakes;
      // Some conventions move the points by a rigid motion and an offset of the measured point
      // (the Stanford arm's shoulder reversed; the ARID's shoulder turned, its axis along the rail
      // before it): nothing to find, nothing harmed (the fit as given is the arm's accuracy).
      if (found.empty())
        ++invisible;
      else
        CHECK(mentions(found, joint + "with its sign reversed"));
      if (!revolute(j)) continue;
      model::Dataset turned = data;  // the controller's zero a quarter turn on: the model wants +90 deg
      for (model::Measurement& r : turned.rows) r.q[j] -= std::numbers::pi / 2;
      const std::vector<std::string> turn_found = identify::frame_check(nominal, turned).mistakes;
      if (turn_found.empty())
        ++invisible;
      else
        CHECK(mentions(turn_found, joint + "plus 90 deg"));
      if (!revolute(j - 1)) continue;
      model::Dataset relative = data;  // joint j against the horizon: the model's j plus j-1
      for (model::Measurement& r : relative.rows) r.q[j] += r.q[j - 1];
      CHECK(mentions(identify::frame_check(nominal, relative).mistakes,
                     joint + "minus joint " + std::to_string(j) + "'s reading"));
    }
  }
  CHECK(invisible <= 2);  // of 30
}

TEST_CASE("the causes a joint convention names") {
  std::mt19937_64 rng(59);
  const model::RobotModel nominal = robot("ur10.yaml");
  model::Dataset data = tracker_rows(nominal, rng, 1e-3, 60);
  for (model::Measurement& r : data.rows) r.q[2] = -r.q[2] + std::numbers::pi / 2;
  const std::vector<std::string> found = identify::frame_check(nominal, data).mistakes;
  CHECK(mentions(found, "joint 3 (" + nominal.joints[2].name + ") read with its sign reversed and plus 90 deg"));
  CHECK(mentions(found,
                 "likely the controller counts joint 3 the other way round from the model, and from a zero a "
                 "quarter turn from the model's"));
}

TEST_CASE("positions exported in centimetres, inches, feet or millimetres are named by their unit") {
  std::mt19937_64 rng(53);
  for (const std::string name : {"ur10.yaml", "arid_prrr.yaml"}) {
    CAPTURE(name);
    const model::RobotModel nominal = robot(name);
    const model::Dataset data = tracker_rows(nominal, rng, 3e-3, 40);
    for (const auto& [metres, unit] : {std::pair{0.001, "millimetres"}, std::pair{0.01, "centimetres"},
                                       std::pair{0.0254, "inches"}, std::pair{0.3048, "feet"}}) {
      CAPTURE(unit);
      model::Dataset scaled = data;
      for (model::Measurement& r : scaled.rows) r.position /= metres;
      CHECK(mentions(identify::implausibilities(nominal, scaled), std::string("likely ") + unit + " given as metres"));
      // A point that moves a third more than the flange the model predicts (a long tool on a small
      // arm) is still named by its unit; a ratio between the units' bands names none.
      if (metres == 0.001) continue;
      for (model::Measurement& r : scaled.rows) r.position *= 1.3;
      CHECK(mentions(identify::implausibilities(nominal, scaled), std::string("likely ") + unit + " given as metres"));
    }
    model::Dataset between = data;
    for (model::Measurement& r : between.rows) r.position *= 1.9;
    const std::vector<std::string> found = identify::implausibilities(nominal, between);
    CHECK(mentions(found, "wrong units, wrong joint readings, or not this robot"));
    CHECK(!mentions(found, "given as metres"));
  }
}

TEST_CASE("orientations in another quaternion convention are named; correct poses and single-joint sweeps never") {
  std::mt19937_64 rng(67);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const auto with = [](model::Dataset data, const auto& convention) {
    for (model::Measurement& r : data.rows) r.orientation = convention(*r.orientation);
    return data;
  };
  // Each written in its convention into the columns qw,qx,qy,qz (Eigen's constructor takes w first).
  const auto as_xyzw = [](const Eigen::Quaterniond& q) { return Eigen::Quaterniond(q.x(), q.y(), q.z(), q.w()); };
  const auto inverse = [](const Eigen::Quaterniond& q) { return q.conjugate(); };
  const auto jpl = [](const Eigen::Quaterniond& q) { return Eigen::Quaterniond(-q.x(), -q.y(), -q.z(), q.w()); };
  for (const std::string name : {"ur10.yaml", "puma560.yaml", "heavy6r.yaml"}) {
    CAPTURE(name);
    const model::RobotModel nominal = robot(name);
    model::RobotModel truth = tracker_truth(nominal, rng, 1e-3);  // a 6-DoF target mounted at any angle
    truth.flange_T_tool.rotation =
        Eigen::AngleAxisd(3.0 * unit(rng), Eigen::Vector3d(unit(rng), unit(rng), unit(rng)).normalized())
            .toRotationMatrix() *
        truth.flange_T_tool.rotation;
    const model::Dataset data =
        simulation::measure(truth, sim::random_configurations(nominal, 40, rng), rng, 2e-5, true, 1e-4, false);
    CHECK(identify::implausibilities(nominal, data).empty());
    std::vector<double> home(nominal.joints.size(), 0.0), sweep;  // within every joint's limits
    for (int k = -3; k <= 3; ++k) sweep.push_back(0.15 * k);
    const model::Dataset sweeps = simulation::measure(
        truth, simulation::single_joint_sweeps(home, std::vector<std::vector<double>>(nominal.joints.size(), sweep)),
        rng, 2e-5, true, 1e-4, false);
    CHECK(identify::implausibilities(nominal, sweeps).empty());
    // A rough description of the arm (every angle some 4 deg off, every length 20 mm): the turns
    // miss by more than 10 deg, and no other convention fits -- not refused.
    sim::ErrorScale rough;
    rough.length_m = 20e-3;
    rough.angle_rad = 4.0 * std::numbers::pi / 180.0;
    model::RobotModel rough_truth = sim::perturbed(nominal, rng, rough);
    rough_truth.base_T_frame0 = truth.base_T_frame0;
    rough_truth.flange_T_tool = truth.flange_T_tool;
    const model::Dataset rough_data =
        simulation::measure(rough_truth, sim::random_configurations(nominal, 40, rng), rng, 2e-5, true, 1e-4, false);
    CHECK(identify::implausibilities(nominal, rough_data).empty());

    CHECK(mentions(identify::implausibilities(nominal, with(data, as_xyzw)), "likely quaternions in x,y,z,w order"));
    CHECK(mentions(identify::implausibilities(nominal, with(data, inverse)),
                   "likely each quaternion the inverse rotation"));
    // JPL's order and inverse together turn every row's rotation by fixed rotations on each side:
    // the turns between rows fit, the frame they turn in is not the positions'.
    const std::vector<std::string> found = identify::implausibilities(nominal, with(data, jpl));
    CHECK(mentions(found, "in a frame"));
    CHECK(mentions(found, "likely JPL quaternions"));
  }
}

TEST_CASE("held-out rows that are training rows are counted, written again with fewer digits too") {
  std::mt19937_64 rng(3);
  const model::RobotModel nominal = robot("puma560.yaml");
  const model::Dataset training = tracker_rows(nominal, rng, 1e-3, 30);
  model::Dataset held_out = tracker_rows(nominal, rng, 1e-3, 10);
  const auto shared = [&] {
    const identify::SharedRows s = identify::training_rows_in(held_out, training);
    return std::pair(s.rows, s.configurations);
  };
  CHECK(shared() == std::pair(0, 0));
  CHECK(identify::training_rows_in(training, training).rows == 30);
  held_out.rows.push_back(training.rows[4]);
  held_out.rows.push_back(training.rows[9]);
  CHECK(shared() == std::pair(2, 2));
  model::Measurement remeasured = training.rows[5];  // the same pose measured again
  remeasured.position.x() += 1e-5;
  held_out.rows.push_back(remeasured);
  CHECK(shared() == std::pair(2, 3));
  // The training file written again with fewer digits (degrees to 3 decimals, mm to 3): the same rows.
  model::Dataset rewritten = training;
  for (model::Measurement& r : rewritten.rows) {
    for (double& q : r.q) q = std::round(q * 180 / std::numbers::pi * 1e3) / 1e3 * std::numbers::pi / 180;
    for (int axis = 0; axis < 3; ++axis) r.position[axis] = std::round(r.position[axis] * 1e6) / 1e6;
  }
  CHECK(identify::training_rows_in(rewritten, training).rows == 30);
}

TEST_CASE("orientations a calibration leaves degrees off are named; an arm's hundredths of a degree are not") {
  const double deg = std::numbers::pi / 180.0;
  CHECK_FALSE(identify::unexplained_orientations(0.05 * deg, 0.0));       // the real UR10's probe
  CHECK_FALSE(identify::unexplained_orientations(2.0 * deg, 0.0));        // a webcam's board far away
  CHECK_FALSE(identify::unexplained_orientations(6.0 * deg, 0.1 * deg));  // 60 times the noise given
  const auto euler = identify::unexplained_orientations(15.6 * deg, 0.0);
  REQUIRE(euler);
  CHECK(euler->find("15.6 deg RMS in orientation") != std::string::npos);
  CHECK(euler->find("another Euler convention") != std::string::npos);
}

// --sigma 0.02 meant as 0.02 mm is 20 mm: the residuals a thousand times below it are named; the
// noise given right, or given too small (the model error is estimated on top), is not. Least
// squares, as the unregularized candidate model selection chooses there: with priors, 20 mm of
// noise gives them the fit.
TEST_CASE("an instrument noise given in mm where kincal takes m is named") {
  std::mt19937_64 rng(12);
  const model::RobotModel nominal = robot("puma560.yaml");
  const model::RobotModel truth = sim::perturbed(nominal, rng);
  const model::Dataset d =
      simulation::measure(truth, sim::random_configurations(nominal, 40, rng), rng, 2e-5, false, 0.0, false);
  for (const double given : {2e-2, 2e-5, 2e-6}) {
    CAPTURE(given);
    identify::IdentifyOptions o;
    o.sigma_m = given;
    o.prior.strength = 0.0;
    const identify::IdentifyResult r = identify::identify(nominal, d, o);
    const auto said = identify::overstated_noise(r.residuals.rms_m, r.median_instrument_sigma_m, 3 * r.residuals.count,
                                                 static_cast<int>(r.identifiability.identified.size()));
    CHECK(said.has_value() == (given == 2e-2));
    if (said) CHECK(said->find("in mm (mm^2) where kincal takes m") != std::string::npos);
  }
  CHECK_FALSE(identify::overstated_noise(1e-6, 1.0, 12, 6));  // too few degrees of freedom to tell
}

TEST_CASE("a fit that explains nothing is named; a service arm's millimetres are not") {
  CHECK_FALSE(identify::unexplained_fit(0.004, 2e-4));   // a service arm under a mocap
  CHECK_FALSE(identify::unexplained_fit(0.0005, 1e-5));  // a UR10 under a tracker
  CHECK_FALSE(identify::unexplained_fit(0.012, 2e-4));   // 60 times a mocap's noise
  const auto mirrored = identify::unexplained_fit(0.271, 2e-5);
  REQUIRE(mirrored);
  CHECK(mirrored->find("271 mm RMS") != std::string::npos);
  CHECK(mirrored->find("mirrored") != std::string::npos);
  CHECK(identify::unexplained_fit(0.05, 0.0));  // noise unknown: the length alone
}

}  // namespace
}  // namespace kincal
