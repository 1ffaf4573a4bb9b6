// host/identify priors (issue #23): MAP estimation keeps a parameter the data barely see near its
// nominal with about its prior's sigma (on the real UR10's DH table, where least squares lets
// a5/d5 run off), per-parameter priors from the command line's entries and the model file with
// bad values refused naming where, and the report's 3-sigma warning.
#include <doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "host/identify/identify.hpp"
#include "host/identify/model_selection.hpp"
#include "host/identify/prior.hpp"
#include "host/identify/statistics.hpp"
#include "host/model/model_file.hpp"
#include "host/model/urdf_chain.hpp"
#include "tests/host/identify/simulation.hpp"
#include "tests/host/model/ur10_realdata.hpp"

namespace {

using namespace kincal;
using model::RobotModel;

RobotModel robot(const char* name) { return model::load_model(std::string(KINCAL_ROBOTS_DIR) + "/" + name); }

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

Eigen::Index index_of(const identify::IdentifyResult& r, const std::string& name) {
  for (std::size_t k = 0; k < r.identifiability.identified.size(); ++k)
    if (model::parameter_name(r.identifiability.identified[k]) == name) return static_cast<Eigen::Index>(k);
  return -1;
}

std::string error_of_prior_entry(const std::string& entry) {
  try {
    (void)identify::parse_prior_entry(entry);
  } catch (const model::InputError& e) {
    return e.what();
  }
  return "no error";
}

std::string model_file_error(const std::string& text) {
  const std::string path = "prior_test_model.yaml";
  std::ofstream(path) << text;
  try {
    (void)model::load_model_priors(path);
  } catch (const model::InputError& e) {
    std::remove(path.c_str());
    return e.what();
  }
  std::remove(path.c_str());
  return "no error";
}

const char* const kModel =
    "angles: deg\n"
    "joints:\n"
    "  - {type: revolute, convention: dh, d: 0.3, theta: 0, a: 0.1, alpha: 90}\n"
    "  - {type: revolute, convention: dh, d: 0, theta: 0, a: 0.4, alpha: 0}\n"
    "tool:\n"
    "  point: [0.1, 0, 0]\n";

}  // namespace

TEST_CASE("real UR10 DH table, positions only: the prior holds a5 and d5 near nominal; least squares lets them run") {
  const model::Dataset all = realdata::import_ur10(KINCAL_REALDATA_DIR).data;
  const realdata::Split split = realdata::split_rows(static_cast<int>(all.rows.size()), 500);
  model::Dataset train =
      realdata::subset(all, std::vector<int>(split.train_order.begin(), split.train_order.begin() + 100));
  train.has_orientation = false;  // as the worked example imports it
  for (model::Measurement& m : train.rows) m.orientation.reset();
  const RobotModel ur10 = robot("ur10.yaml");
  // The priors are tested here, not the rejection gate: without it, 24 fewer solves (minutes
  // under the sanitizers).
  identify::IdentifyOptions prior;
  prior.rejection_gate = false;
  const identify::IdentifyResult map = identify::identify(ur10, train, prior);
  identify::IdentifyOptions plain = prior;
  plain.prior.strength = 0.0;
  const identify::IdentifyResult ls = identify::identify(ur10, train, plain);
  // The link lengths' width is the data's (issue #41): about half the 1 mm default here.
  const auto lengths = std::find_if(map.prior_scales.classes.begin(), map.prior_scales.classes.end(),
                                    [](const auto& c) { return c.kind == identify::PriorClass::link_length; });
  REQUIRE(lengths != map.prior_scales.classes.end());
  CHECK(lengths->reason == identify::ScaleReason::evidence);
  CHECK(lengths->scale < 1.0);
  for (const char* name : {"a5", "d5"}) {
    INFO(name);
    const Eigen::Index k = index_of(map, name), l = index_of(ls, name);
    REQUIRE(k >= 0);
    REQUIRE(l >= 0);
    INFO("MAP ", map.change(k) * 1e3, " +- ", map.stddev(k) * 1e3, " mm; least squares ", ls.change(l) * 1e3, " +- ",
         ls.stddev(l) * 1e3, " mm");
    CHECK(map.prior_sigma(k) == doctest::Approx(1e-3 * lengths->scale));
    CHECK(std::abs(map.change(k)) < map.prior_sigma(k));  // stays near its nominal
    CHECK(map.stddev(k) <= map.prior_sigma(k));           // never less certain than the prior
    CHECK(ls.stddev(l) > 100.0 * map.stddev(k));          // the priors hold it, not the data
    CHECK(ls.stddev(l) > 5e-3);                           // least squares: barely determined
  }
  // Parameters the data see well are left to the data.
  const Eigen::Index a2 = index_of(map, "a2");
  REQUIRE(a2 >= 0);
  CHECK(map.prior_share(a2) < 0.05);
  CHECK(identify::accuracy(map.model, realdata::subset(all, split.held_out)).rms_m < 0.6e-3);
}

TEST_CASE("the worked example's two routes, URDF and DH table, reach the same flange on the real UR10") {
  const model::Dataset all = realdata::import_ur10(KINCAL_REALDATA_DIR).data;
  const realdata::Split split = realdata::split_rows(static_cast<int>(all.rows.size()), 500);
  model::Dataset train =
      realdata::subset(all, std::vector<int>(split.train_order.begin(), split.train_order.begin() + 100));
  train.has_orientation = false;  // positions only, as the worked example imports them
  for (model::Measurement& m : train.rows) m.orientation.reset();
  const model::Dataset held_out =
      realdata::subset(all, std::vector<int>(split.held_out.begin(), split.held_out.begin() + 100));
  const RobotModel from_dh = robot("ur10.yaml");
  const RobotModel from_urdf =
      model::load_model(std::string(KINCAL_ROBOTS_DIR) + "/ur10.urdf", model::UrdfChainEnds{"", "tracker_probe"});
  constexpr double kHundredthDeg = 0.01 * std::numbers::pi / 180.0;
  identify::IdentifyOptions o;
  o.rejection_gate = false;  // minutes under the sanitizers; the routes' agreement is what is tested
  const identify::IdentifyResult dh = identify::identify(from_dh, train, o);
  const identify::IdentifyResult urdf = identify::identify(from_urdf, train, o);
  // Both descriptions put the probe where Trafo_TM_F_init.txt plans it, 0.09 mm off the last axis:
  // with it on the axis in one of them (ur10.urdf until this test), a5, alpha5 were exactly
  // dependent there and barely separable in the other, which let them take what the first held
  // fixed -- 0.05 deg apart, 25 deg without priors (realdata_ur10_bench).
  CHECK(simulation::flange_difference(urdf.model, dh.model, held_out).largest_rad < kHundredthDeg);
  identify::IdentifyOptions plain = o;
  plain.prior.strength = 0.0;
  CHECK(simulation::flange_difference(identify::identify(from_urdf, train, plain).model,
                                      identify::identify(from_dh, train, plain).model, held_out)
            .largest_rad < kHundredthDeg);
}

TEST_CASE("a prior far tighter than the data: change about zero with the prior's sigma, and the 3-sigma warning") {
  std::mt19937_64 rng(7);
  const RobotModel nominal = model::parse_model(kModel, "two-link");
  RobotModel truth = nominal;
  truth.joints[0].parameters.a_m += 2e-3;  // 2 mm longer
  const auto qs = sim::random_configurations(nominal, 40, rng);
  const model::Dataset d = simulation::measure(truth, qs, rng, 1e-5, false, 0.0, true);
  identify::IdentifyOptions o;
  o.prior.sigma = {{"a1", 1e-9}};  // held at nominal
  const identify::IdentifyResult held = identify::identify(nominal, d, o);
  const Eigen::Index k = index_of(held, "a1");
  REQUIRE(k >= 0);
  CHECK(std::abs(held.change(k)) < 1e-9);  // within one prior sigma
  CHECK(held.stddev(k) == doctest::Approx(1e-9).epsilon(1e-3));
  CHECK(held.prior_share(k) > 0.999);
  // A prior of 0.1 mm that the data's 2 mm overrule: flagged.
  o.prior.sigma = {{"a1", 1e-4}};
  const identify::IdentifyResult flagged = identify::identify(nominal, d, o);
  CHECK(flagged.change(index_of(flagged, "a1")) > 1.9e-3);
  const std::string report = identify::format_report(flagged);
  INFO(report);
  CHECK(has(report, "warning: a1 is "));
  CHECK(has(report, "prior sigmas from its nominal"));
  // The default 1 mm prior: 2 mm is 2 sigmas, recovered, no warning.
  const identify::IdentifyResult plain = identify::identify(nominal, d, {});
  CHECK(plain.change(index_of(plain, "a1")) == doctest::Approx(2e-3).epsilon(1e-3));
  CHECK_FALSE(has(identify::format_report(plain), "warning:"));
}

TEST_CASE("--prior entries: units, and bad entries refused naming the entry") {
  CHECK(identify::parse_prior_entry("a5=0.5mm").second == doctest::Approx(5e-4));
  CHECK(identify::parse_prior_entry("theta5=0.2deg").second == doctest::Approx(0.2 * std::numbers::pi / 180.0));
  CHECK(identify::parse_prior_entry("d1=0.002m").second == doctest::Approx(2e-3));
  CHECK(identify::parse_prior_entry("scale2=0.001").second == doctest::Approx(1e-3));
  CHECK(std::isinf(identify::parse_prior_entry("base_x=inf").second));
  CHECK(has(error_of_prior_entry("a5"), "--prior 'a5': no NAME="));
  CHECK(has(error_of_prior_entry("a5=1furlong"), "unknown unit 'furlong'"));
  CHECK(has(error_of_prior_entry("a5=-1mm"), "must be positive"));
  CHECK(has(error_of_prior_entry("a5=mm"), "no number"));
  identify::PriorOptions o;
  o.sigma = {{"a9", 1e-3}};
  try {
    (void)identify::prior_sigmas(o, {}, 2, "here");
    FAIL("a9 of a two-joint model accepted");
  } catch (const model::InputError& e) {
    CHECK(has(e.what(), "here: prior of 'a9'"));
  }
}

TEST_CASE("model file priors: read in the file's units, bad values refused with FILE:LINE:COLUMN") {
  const std::string path = "prior_test_good.yaml";
  std::ofstream(path) << kModel << "priors:\n  a2: 0.0005\n  theta1: 0.2\n  tool_x: 0.01\n";
  const auto priors = model::load_model_priors(path);
  std::remove(path.c_str());
  REQUIRE(priors.size() == 3);
  CHECK(priors[0].first == "a2");
  CHECK(priors[0].second == doctest::Approx(5e-4));
  CHECK(priors[1].second == doctest::Approx(0.2 * std::numbers::pi / 180.0));  // the file's degrees
  CHECK(has(model_file_error(std::string(kModel) + "priors:\n  a7: 0.001\n"), "prior_test_model.yaml:8:3: priors:"));
  CHECK(has(model_file_error(std::string(kModel) + "priors:\n  a2: -0.001\n"),
            "prior_test_model.yaml:8:7: priors: a2 must be positive"));
  CHECK(has(model_file_error(std::string(kModel) + "priors:\n  a2: wide\n"), "priors: a2: 'wide' is not a number"));
  CHECK(has(model_file_error(std::string(kModel) + "priors: [1, 2]\n"), "priors must be a mapping"));
}

TEST_CASE("model selection: the out-of-range split, the candidates, and the choice on the real UR10") {
  model::Dataset d;
  d.joint_count = 2;
  for (int i = 0; i <= 10; ++i) {  // q1 = q2 over 0..10: the central 70 % is [1.5, 8.5]
    model::Measurement m;
    m.q = {static_cast<double>(i), static_cast<double>(i)};
    d.rows.push_back(m);
  }
  d.rows[5].q[1] = 10.0;  // q1 central, q2 at its end: out of range
  const identify::RowSplit s = identify::out_of_range_split(d, 0.7);
  CHECK(s.inside == std::vector<int>{2, 3, 4, 6, 7, 8});
  CHECK(s.outside == std::vector<int>{0, 1, 5, 9, 10});

  const RobotModel ur10 = robot("ur10.yaml");
  std::string names;
  for (const identify::Candidate& c : identify::candidate_models(ur10, {})) names += c.name + " ";
  CHECK(names ==
        "registration joint-offsets geometry-x2 geometry geometry-x0.5 geometry-noprior geometry+gravity "
        "geometry+scales geometry+couplings ");
  {  // the gravity candidate needs masses and no declared compliance
    RobotModel massless = ur10;
    for (model::Joint& j : massless.joints) j.mass_kg = 0.0;
    RobotModel compliant = ur10;
    compliant.joints[1].compliance = 0.0;
    for (const RobotModel& m : {massless, compliant})
      for (const identify::Candidate& c : identify::candidate_models(m, {})) CHECK(c.name != "geometry+gravity");
  }
  CHECK(identify::find_candidate(ur10, {}, "geometry-x2").options.prior.strength == 2.0);
  std::string error;
  try {
    (void)identify::find_candidate(ur10, {}, "everything");
  } catch (const model::InputError& e) {
    error = e.what();
  }
  CHECK(has(error, "'everything': no such candidate model"));
  CHECK(has(error, "joint-offsets"));

  const model::Dataset all = realdata::import_ur10(KINCAL_REALDATA_DIR).data;
  {  // the export's first 300 rows (the worked example's) spread so that none lies inside 70 % of
     // all six ranges: the fold widens until a quarter of the rows train it
    const model::Dataset first = realdata::subset(all, std::vector<int>(300, 0));
    std::vector<int> rows(300);
    for (int i = 0; i < 300; ++i) rows[static_cast<std::size_t>(i)] = i;
    const model::Dataset head = realdata::subset(all, rows);
    CHECK(identify::out_of_range_split(head, 0.7).inside.empty());
    const identify::RowSplit fold = identify::out_of_range_fold(head, {});
    CHECK(fold.fraction == doctest::Approx(0.9));
    CHECK(fold.inside.size() == 123);
    CHECK(fold.inside.size() + fold.outside.size() == 300);
    // one row repeated: every row is inside at once
    CHECK(identify::out_of_range_fold(first, {}).fraction == doctest::Approx(0.7));
  }
  const realdata::Split split = realdata::split_rows(static_cast<int>(all.rows.size()), 500);
  const model::Dataset train =
      realdata::subset(all, std::vector<int>(split.train_order.begin(), split.train_order.begin() + 100));
  const identify::Selection selection = identify::select_model(ur10, train, {});
  REQUIRE(selection.scores.size() == 9);
  CHECK(selection.scores[0].parameters == 12);  // base and tool
  CHECK(selection.scores[1].parameters == 16);  // and four joint offsets (theta1, theta6 go to base, tool)
  // and five compliances: gravity does not turn the last axis (its link's centre of mass is on
  // it), so identifiability holds compliance6 fixed; the first, vertical at the start, is loaded
  // by the tilt of the gravity found, and the sag's tilted stage frees it (sag.hpp); gravity's
  // direction (gravity_rx, gravity_ry) and nine coordinates of the links' given centres of mass
  // (identifiability holds the other nine: on an axis gravity does not turn, or not separable
  // from a compliance)
  CHECK(selection.scores[6].parameters == selection.scores[3].parameters + 5 + 2 + 9);
  CHECK(selection.scores[7].parameters == selection.scores[3].parameters + 6);  // and six scales
  CHECK(selection.scores[8].parameters > selection.scores[3].parameters);       // and couplings
  // The nominal geometry leaves about 1.1 mm; every geometric candidate about half that.
  CHECK(selection.scores[0].kfold_rms_m > 1.5 * selection.scores[3].kfold_rms_m);
  // UR's published masses explain part of what geometry leaves: the gravity candidate wins.
  CHECK(selection.chosen.name == "geometry+gravity");
  // The rule: the chosen beat the default row by row, and holds (UR's masses): every later
  // candidate either did not beat the default or did not beat it row by row.
  const auto chosen = std::find_if(selection.scores.begin(), selection.scores.end(),
                                   [&](const auto& y) { return y.name == selection.chosen.name; });
  CHECK(chosen->holds);
  CHECK(chosen->against == "geometry");
  CHECK(chosen->t <= -2.0);
  for (auto x = selection.scores.begin(); x != selection.scores.end(); ++x) {
    CHECK(x->out_of_range_rms_m > 0.0);
    if (x > chosen)
      CHECK((x->against == "geometry" ||
             (x->against == selection.chosen.name && (x->score_m >= chosen->score_m || x->t > -2.0))));
  }
  // The chosen candidate's scores in full are what identify's rejection gate computes with the
  // rule for it (kincal identify passes them on instead).
  const identify::CrossValidation again =
      identify::cross_validate(selection.chosen.model, train, selection.chosen.options);
  CHECK(again.kfold_error2 == selection.chosen_cross_validation.kfold_error2);
  CHECK(again.out_of_range_error2 == selection.chosen_cross_validation.out_of_range_error2);
  CHECK(again.kfold_error2.size() == train.rows.size());
  // All candidates' solves ran side by side: each candidate's scores are what it gets alone.
  const std::vector<identify::Candidate> candidates = identify::candidate_models(ur10, {});
  const identify::CrossValidation alone = identify::cross_validate(candidates[1].model, train, candidates[1].options);
  CHECK(alone.kfold_rms_m == selection.scores[1].kfold_rms_m);
  CHECK(alone.out_of_range_rms_m == selection.scores[1].out_of_range_rms_m);
  const std::string table = identify::format_selection(selection);
  CHECK(has(table, "chosen: " + selection.chosen.name + ": "));
  // geometry+gravity's 45 parameters leave the out-of-range fold's rows fewer than 5 equations
  // each: the score is the K-fold RMS (model_selection.hpp's rule)
  CHECK(has(table, "a candidate must have a lower K-fold RMS (the out-of-range fold's rows give fewer than 5"));
  CHECK(has(table, "<- chosen"));
}

// A pose measured twice (the copy's readings a thousandth of a degree off, as a file written with
// fewer digits has them) is one configuration, and cross-validation leaves it out whole: with a
// copy in training, the other was predicted by what that pose alone does.
TEST_CASE("cross-validation leaves a configuration measured twice out whole") {
  std::mt19937_64 rng(31);
  const RobotModel nominal = robot("puma560.yaml");
  const RobotModel truth = sim::perturbed(nominal, rng);
  model::Dataset d =
      simulation::measure(truth, sim::random_configurations(nominal, 30, rng), rng, 5e-5, false, 0.0, false);
  const std::size_t n = d.rows.size();
  for (std::size_t i = 0; i < n; ++i) {
    model::Measurement copy = d.rows[i];
    for (double& q : copy.q) q += 1e-5;
    copy.line = static_cast<int>(n + i) + 2;
    d.rows.push_back(copy);
  }
  std::vector<int> expected(n);
  for (std::size_t i = 0; i < n; ++i) expected[i] = static_cast<int>(i);
  expected.insert(expected.end(), expected.begin(), expected.end());
  CHECK(model::configuration_of_rows(d) == expected);
  const identify::CrossValidation cv = identify::cross_validate(nominal, d, {});
  REQUIRE(cv.kfold_rows.size() == 2 * n);
  // Rows fold by fold, a configuration's rows one after the other: a copy next to its row.
  for (std::size_t p = 0; p < cv.kfold_rows.size(); p += 2)
    CHECK(cv.kfold_rows[p + 1] == cv.kfold_rows[p] + static_cast<int>(n));
  // A joint that never moved leaves the others to tell configurations apart.
  for (model::Measurement& r : d.rows) r.q[0] = 0.25;
  CHECK(model::configuration_of_rows(d) == expected);
  // A repeatability test: 20,000 rows at 4 poses, in turn (each row compares with one other: a
  // quadratic grouping would take minutes here).
  model::Dataset repeated = d;
  repeated.rows.clear();
  for (int i = 0; i < 20000; ++i) repeated.rows.push_back(d.rows[static_cast<std::size_t>(i % 4)]);
  const std::vector<int> poses = model::configuration_of_rows(repeated);
  int wrong = 0;
  for (int i = 0; i < 20000; ++i) wrong += poses[static_cast<std::size_t>(i)] == i % 4 ? 0 : 1;
  CHECK(wrong == 0);
}

TEST_CASE("prior widths from the data: the evidence per class, the guards, and the user's priors kept") {
  // A linear model where the data see each parameter perfectly or not at all: the evidence's
  // fixed point is then the RMS of the class's deviations over its default sigmas.
  const identify::ParameterIds ids{
      {core::ParameterKind::link_a, 0},     {core::ParameterKind::link_a, 1},     {core::ParameterKind::link_d, 1},
      {core::ParameterKind::link_theta, 1}, {core::ParameterKind::link_alpha, 1}, {core::ParameterKind::tool_x, 0},
      {core::ParameterKind::tool_y, 0},     {core::ParameterKind::base_x, 0},     {core::ParameterKind::link_a, 2}};
  identify::PriorOptions o;
  o.sigma = {{"a3", 2e-3}};  // named by the user: kept as given, in no class
  const identify::PriorScales start = identify::initial_prior_scales(o, ids, 3);
  REQUIRE(start.estimated);
  CHECK(start.class_of.back() == -1);
  REQUIRE(start.classes.size() == 4);  // lengths, angles, registration, measured point
  const Eigen::VectorXd sigma = identify::prior_sigmas(o, ids, 3, "test");
  Eigen::VectorXd seen(9);
  seen << 1e16, 1e16, 1e16, 0.0, 0.0, 1e16, 1e16, 1e16, 1e16;  // the angles unseen
  Eigen::VectorXd delta(9);
  // lengths 3 mm RMS (3x the default 1 mm), angles anything, the tool 1e-9 of its 10 mm, the
  // base 1000x its 100 mm
  delta << 3e-3, -3e-3, 3e-3, 0.02, -0.02, 1e-11, -1e-11, 100.0, 5e-3;
  const Eigen::VectorXd none = Eigen::VectorXd::Zero(9);
  const identify::PriorScales s =
      identify::update_prior_scales(Eigen::MatrixXd(seen.asDiagonal()), none, delta, none, sigma, o, start);
  const auto of = [&](identify::PriorClass c) {
    return *std::find_if(s.classes.begin(), s.classes.end(), [&](const auto& x) { return x.kind == c; });
  };
  CHECK(of(identify::PriorClass::link_length).scale == doctest::Approx(3.0).epsilon(1e-3));
  CHECK(of(identify::PriorClass::link_length).reason == identify::ScaleReason::evidence);
  CHECK(of(identify::PriorClass::link_length).determined == doctest::Approx(3.0).epsilon(1e-3));
  CHECK(of(identify::PriorClass::link_angle).scale == 1.0);  // barely seen: the default
  CHECK(of(identify::PriorClass::link_angle).reason == identify::ScaleReason::barely_seen);
  CHECK(of(identify::PriorClass::measured_point).scale == doctest::Approx(o.min_scale));
  CHECK(of(identify::PriorClass::measured_point).reason == identify::ScaleReason::lower_bound);
  CHECK(of(identify::PriorClass::registration).scale == doctest::Approx(o.max_scale));
  CHECK(of(identify::PriorClass::registration).reason == identify::ScaleReason::upper_bound);
  const Eigen::VectorXd scaled = identify::scaled_sigmas(sigma, s);
  CHECK(scaled(0) == doctest::Approx(3e-3).epsilon(1e-3));
  CHECK(scaled(8) == 2e-3);  // the user's
  const std::string text = identify::format_prior_scales(s);
  INFO(text);
  CHECK(has(text, "link lengths"));
  CHECK(has(text, "evidence: 3.0 of 3 parameters determined by the data"));
  CHECK(has(text, "the default kept: the data barely see this class"));
  CHECK(has(text, "the lower bound"));
  // Off: the fixed widths.
  o.estimate_scales = false;
  CHECK_FALSE(identify::initial_prior_scales(o, ids, 3).estimated);
}

TEST_CASE("a joint ratio is a class of its own: its width in closed form, none within two standard errors") {
  // Three scales and a coupling the data see each alone (information 1 / sigma_d^2, sigma_d 100
  // ppm): the width is sqrt(m^2 - (2 sigma_d)^2), the lower bound for an estimate within two of its
  // standard errors (1.5 here: the evidence's own rule, one, would free it); an unseen ratio keeps
  // its default.
  const identify::ParameterIds ids{{model::kJointScale, 0},
                                   {model::kJointScale, 1},
                                   {model::kJointScale, 2},
                                   {model::kJointCoupling, 2},
                                   {core::ParameterKind::link_a, 1}};
  const identify::PriorOptions o;
  const identify::PriorScales start = identify::initial_prior_scales(o, ids, 3);
  REQUIRE(start.classes.size() == 5);  // link lengths, then one class per ratio
  CHECK(start.classes[0].kind == identify::PriorClass::link_length);
  CHECK(start.classes[1].parameter == "scale1");
  CHECK(start.classes[4].parameter == "coupling3_2");
  CHECK(start.class_of == std::vector<int>{1, 2, 3, 4, 0});
  const Eigen::VectorXd sigma = identify::prior_sigmas(o, ids, 3, "test");
  Eigen::VectorXd seen(5);
  seen << 1e8, 1e8, 0.0, 1e8, 1e16;
  Eigen::VectorXd delta(5);
  delta << 3e-3, 1.5e-4, 1e-3, -2e-3, 1e-3;
  const Eigen::VectorXd none = Eigen::VectorXd::Zero(5);
  const identify::PriorScales s =
      identify::update_prior_scales(Eigen::MatrixXd(seen.asDiagonal()), none, delta, none, sigma, o, start);
  CHECK(s.classes[1].scale == doctest::Approx(std::sqrt(9e-6 - 4e-8) / 0.01).epsilon(1e-3));
  CHECK(s.classes[1].reason == identify::ScaleReason::evidence);
  CHECK(s.classes[2].scale == doctest::Approx(o.min_ratio_scale));
  CHECK(s.classes[2].reason == identify::ScaleReason::lower_bound);
  CHECK(s.classes[3].scale == 1.0);
  CHECK(s.classes[3].reason == identify::ScaleReason::barely_seen);
  CHECK(s.classes[4].scale == doctest::Approx(std::sqrt(4e-6 - 4e-8) / 0.01).epsilon(1e-3));
  const std::string text = identify::format_prior_scales(s);
  INFO(text);
  CHECK(has(text, "a joint ratio's own from 0.0001"));
  CHECK(has(text, "  scale1 "));
  CHECK(has(text, "  coupling3_2 "));
}

TEST_CASE("a compliance's prior is a deflection at its joint's largest load, each joint a class of its own") {
  // Joint 1 loaded to 100 N m, joint 2 not at all, joint 3 (prismatic) to 50 N.
  const identify::ParameterIds ids{{model::kJointCompliance, 0},
                                   {model::kJointCompliance, 1},
                                   {model::kJointCompliance, 2},
                                   {core::ParameterKind::link_a, 1}};
  const identify::PriorOptions o;
  const identify::GravityLoads loads{{100.0, 0.0, 50.0}, {false, false, true}};
  // Without loads (a model with masses of its own: sag.hpp's compliance_prior_loads) no prior.
  const Eigen::VectorXd without = identify::prior_sigmas(o, ids, 3, "test");
  CHECK(std::isinf(without(0)));
  CHECK(std::isinf(without(2)));
  const Eigen::VectorXd sigma = identify::prior_sigmas(o, ids, 3, "test", loads);
  CHECK(sigma(0) == doctest::Approx(o.deflection_rad / 100.0));
  CHECK(std::isinf(sigma(1)));  // gravity does not load it: nothing to scale by
  CHECK(sigma(2) == doctest::Approx(o.deflection_m / 50.0));
  CHECK(sigma(3) == o.length_m);

  const identify::PriorScales start = identify::initial_prior_scales(o, ids, 3, loads);
  REQUIRE(start.classes.size() == 3);  // link lengths, then one class per loaded compliance
  CHECK(start.classes[1].kind == identify::PriorClass::joint_compliance);
  CHECK(start.classes[1].parameter == "compliance1");
  CHECK(!start.classes[1].prismatic);
  CHECK(start.classes[2].parameter == "compliance3");
  CHECK(start.classes[2].prismatic);
  CHECK(start.class_of == std::vector<int>{1, -1, 2, 0});

  // Compliance 1 seen alone at 1 / (1e-7)^2 and 1e-5 from a rigid joint: the closed form's width;
  // compliance 3 within its standard error of rigid: the classes' lower bound (not a ratio's).
  Eigen::VectorXd seen(4);
  seen << 1e14, 0.0, 1e14, 1e16;
  Eigen::VectorXd delta(4);
  delta << 1e-5, 0.0, 1e-8, 1e-3;
  const Eigen::VectorXd none = Eigen::VectorXd::Zero(4);
  const identify::PriorScales s =
      identify::update_prior_scales(Eigen::MatrixXd(seen.asDiagonal()), none, delta, none, sigma, o, start);
  CHECK(s.classes[1].scale == doctest::Approx(std::sqrt(1e-10 - 1e-14) / sigma(0)).epsilon(1e-3));
  CHECK(s.classes[1].reason == identify::ScaleReason::evidence);
  CHECK(s.classes[2].scale == doctest::Approx(o.min_scale));
  CHECK(s.classes[2].reason == identify::ScaleReason::lower_bound);
  const std::string text = identify::format_prior_scales(s);
  INFO(text);
  CHECK(has(text, "  compliance1 "));
  CHECK(has(text, " deg at its load"));
  CHECK(has(text, "  compliance3 "));
  CHECK(has(text, " mm at its load"));
}

TEST_CASE("a given mass's centre: 1 mm, one class for all; a centre whose mass is identified or held is not one") {
  // Link 2's mass given by the model, its centre identified (geometry+gravity); link 3's mass and
  // centre identified (geometry+sag), its mass held fixed by identifiability, so not among `ids`.
  RobotModel m = robot("puma560.yaml");
  m.joints[1].identify_centre = true;
  m.joints[2].identify_mass = true;
  const std::vector<bool> given = identify::given_centres(m);
  CHECK(given == std::vector<bool>{false, true, false, false, false, false});
  const identify::ParameterIds ids{
      {model::kLinkCentreX, 1}, {model::kLinkCentreZ, 1}, {model::kLinkCentreX, 2}, {core::ParameterKind::link_a, 1}};
  const identify::PriorOptions o;
  const Eigen::VectorXd sigma = identify::prior_sigmas(o, ids, 6, "test", {}, given);
  CHECK(sigma(0) == o.given_centre_m);
  CHECK(sigma(1) == o.given_centre_m);
  CHECK(sigma(2) == o.centre_m);
  const identify::PriorScales s = identify::initial_prior_scales(o, ids, 6, {}, given);
  REQUIRE(s.classes.size() == 3);  // link lengths, com_x3's own class, the given centres together
  CHECK(s.classes[1].kind == identify::PriorClass::mass_centre);
  CHECK(s.classes[1].parameter == "com_x3");
  CHECK(s.classes[2].kind == identify::PriorClass::given_centre);
  CHECK(s.classes[2].parameters == 2);
  CHECK(s.class_of == std::vector<int>{2, 2, 1, 0});
  const std::string text = identify::format_prior_scales(s);
  INFO(text);
  CHECK(has(text, "  given centres "));
  CHECK(has(text, "sigma 1 mm"));
}

TEST_CASE("one scaled joint among six: its ratio is freed, the others held, as if the scaled joint were known") {
  // The PUMA 560 with every joint's scale identified where the truth scales joint 2 by 0.3 %
  // (a gear's ratio): with one width for all six scales, the scaled joint widened every joint's
  // prior and the five others fitted the noise (the zoo's scaled cases, 1.2 times the oracle's
  // held-out error). Judged against the fit that frees only scale2, the truth's structure, and
  // against one width for every scale.
  const RobotModel base = robot("puma560.yaml");
  RobotModel every = base, known = base;
  for (model::Joint& j : every.joints) j.scale = 1.0;
  known.joints[1].scale = 1.0;
  double every2 = 0.0, known2 = 0.0, shared2 = 0.0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    std::mt19937_64 rng(5200 + seed);
    RobotModel truth = sim::perturbed(base, rng, sim::ErrorScale{});
    truth.joints[1].scale = 1.003;
    const model::Dataset data =
        simulation::measure(truth, sim::random_configurations(base, 60, rng), rng, 2e-5, false, 0.0, false);
    const auto held_out = sim::random_configurations(base, 200, rng);
    identify::IdentifyOptions o;
    o.rejection_gate = false;
    const identify::IdentifyResult r = identify::identify(every, data, o);
    INFO(identify::format_report(r));
    int ratios = 0;
    for (const identify::ClassScale& c : r.prior_scales.classes) {
      if (c.kind != identify::PriorClass::joint_ratio) continue;
      ++ratios;
      INFO(c.parameter, " scale ", c.scale);
      if (c.parameter == "scale2")
        CHECK(c.scale > 0.1);  // 0.3 % against the 1 % default
      else
        CHECK(c.scale < 0.05);  // half the lower bound of a class of all six
    }
    CHECK(ratios >= 5);
    every2 += std::pow(simulation::prediction_rms(r.model, truth, held_out), 2);
    known2 += std::pow(simulation::prediction_rms(identify::identify(known, data, o).model, truth, held_out), 2);
    // One width for all six, the truth's 0.3 % (a class of all six gave them one width).
    for (int j = 1; j <= 6; ++j) o.prior.sigma.emplace_back("scale" + std::to_string(j), 3e-3);
    shared2 += std::pow(simulation::prediction_rms(identify::identify(every, data, o).model, truth, held_out), 2);
  }
  // Measured: 0.0145 mm every scale, 0.0134 scale2 alone, 0.0156 one width of 0.3 % for all six.
  INFO("every scale ", std::sqrt(every2 / 3.0) * 1e3, " mm, scale2 alone ", std::sqrt(known2 / 3.0) * 1e3,
       " mm, one width for all six ", std::sqrt(shared2 / 3.0) * 1e3, " mm");
  CHECK(std::sqrt(every2) <= 1.1 * std::sqrt(known2));
  CHECK(every2 < shared2);
}

namespace {

// Held-out RMS against the truth (pooled over seeds) of the defaults and of --no-prior, and the
// link lengths' chosen scale, for an arm of an error class at `rows` rows.
struct ClassOutcome {
  double defaults_m = 0.0, noprior_m = 0.0;
  std::vector<double> length_scales;
  std::string report;
};

ClassOutcome judge_class(const RobotModel& nominal, const sim::ErrorScale& errors, double noise_m, int rows) {
  ClassOutcome out;
  double with2 = 0.0, without2 = 0.0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const simulation::ArmCase arm = simulation::simulated_arm(nominal, errors, noise_m, rows, 4100 + seed);
    identify::IdentifyOptions o;
    o.rejection_gate = false;
    const identify::IdentifyResult r = identify::identify(nominal, arm.train, o);
    o.prior.strength = 0.0;
    const identify::IdentifyResult ls = identify::identify(nominal, arm.train, o);
    with2 += std::pow(simulation::prediction_rms(r.model, arm.truth, arm.held_out), 2);
    without2 += std::pow(simulation::prediction_rms(ls.model, arm.truth, arm.held_out), 2);
    for (const identify::ClassScale& c : r.prior_scales.classes)
      if (c.kind == identify::PriorClass::link_length) out.length_scales.push_back(c.scale);
    out.report = identify::format_report(r);
  }
  out.defaults_m = std::sqrt(with2 / 3.0);
  out.noprior_m = std::sqrt(without2 / 3.0);
  return out;
}

}  // namespace

TEST_CASE("a service arm with millimetre errors at 37 rows: the data widen the priors, no worse than no prior") {
  // 8 joints with a prismatic torso, 3 mm / 0.5 deg errors, a mocap's 0.2 mm: the UR10's 1 mm
  // default held such an arm toward its nominal (issue #41: 22 % worse than no prior held out).
  sim::ErrorScale errors;
  errors.length_m = 3e-3;
  errors.angle_rad = 0.5 * std::numbers::pi / 180.0;
  const ClassOutcome c = judge_class(simulation::service_arm(), errors, 2e-4, 37);
  INFO(c.report);
  INFO("defaults ", c.defaults_m * 1e3, " mm, no prior ", c.noprior_m * 1e3, " mm");
  CHECK(c.defaults_m <= c.noprior_m);
  for (const double s : c.length_scales) CHECK(s > 1.5);  // wider than the UR10's 1 mm
  CHECK(has(c.report, "prior widths chosen by the data"));
}

TEST_CASE("a precise arm (0.2 mm errors): the data narrow the link lengths' priors, no worse than no prior") {
  sim::ErrorScale errors;
  errors.length_m = 2e-4;
  errors.angle_rad = 0.02 * std::numbers::pi / 180.0;
  const ClassOutcome c = judge_class(robot("puma560.yaml"), errors, 2e-5, 40);
  INFO(c.report);
  INFO("defaults ", c.defaults_m * 1e3, " mm, no prior ", c.noprior_m * 1e3, " mm");
  CHECK(c.defaults_m <= c.noprior_m);
  for (const double s : c.length_scales) CHECK(s < 0.7);
}

namespace {

// A 6R arm of the precise class (0.2 mm, 0.02 deg) measured at `rows` random postures by a
// tracker (0.02 mm), its reading of joint 2 scaled by `scale2` and of joint 3 by `scale3` (a gear
// ratio off by a few tenths of a percent, which the nominal model does not declare).
struct ScaledArm {
  RobotModel nominal, truth;
  model::Dataset train;
  std::vector<std::vector<double>> held_out;
};
ScaledArm scaled_arm(double scale2, double scale3, int rows, std::uint64_t seed) {
  ScaledArm a;
  a.nominal = robot("puma560.yaml");
  sim::ErrorScale precise;
  precise.length_m = 2e-4;
  precise.angle_rad = 0.02 * std::numbers::pi / 180.0;
  std::mt19937_64 rng(seed);
  a.truth = sim::perturbed(a.nominal, rng, precise);
  a.truth.joints[1].scale = scale2;
  a.truth.joints[2].scale = scale3;
  a.train =
      simulation::measure(a.truth, sim::random_configurations(a.nominal, rows, rng), rng, 2e-5, false, 0.0, false);
  a.held_out = sim::random_configurations(a.nominal, 200, rng);
  return a;
}

}  // namespace

TEST_CASE(
    "the selection rule: beat the default row by row, then the smaller structure unless beaten; the arm's own physics "
    "holds") {
  // Held-out errors of 200 rows (K folds only): a common spread, each candidate shifted by `shift`
  // mm with its own jitter.
  std::mt19937_64 rng(5);
  std::normal_distribution<double> spread(0.0, 0.05);
  std::vector<double> common(200);
  for (double& x : common) x = 0.5 + std::abs(spread(rng));
  const auto errors = [](const std::vector<double>& mm) {
    identify::CrossValidation v;
    double sum2 = 0.0;
    for (const double x : mm) {
      v.kfold_rows.push_back(static_cast<int>(v.kfold_error2.size()));
      v.kfold_error2.push_back(x * x * 1e-6);
      sum2 += x * x * 1e-6;
    }
    v.kfold_rms_m = std::sqrt(sum2 / static_cast<double>(mm.size()));
    return v;
  };
  const auto scored = [&](double shift, double jitter) {
    std::normal_distribution<double> own(0.0, jitter);
    std::vector<double> mm;
    for (const double x : common) mm.push_back(std::max(0.0, x + shift + own(rng)));
    return errors(mm);
  };
  struct Named {
    std::string name;
    bool holds;
    int parameters = 0;
  };
  const auto choose = [](const std::vector<Named>& names, const std::vector<identify::CrossValidation>& v,
                         std::vector<identify::CandidateScore>& scores) {
    scores.clear();
    for (std::size_t i = 0; i < names.size(); ++i) {
      identify::CandidateScore x;
      x.name = names[i].name;
      x.holds = names[i].holds;
      x.parameters = names[i].parameters;
      x.kfold_rms_m = v[i].kfold_rms_m;
      x.score_m = v[i].kfold_rms_m;
      scores.push_back(x);
    }
    const int c = identify::choose_candidate(scores, v, false);
    return c < 0 ? std::string("none") : names[static_cast<std::size_t>(c)].name;
  };
  const std::vector<Named> with_masses{
      {"registration", false}, {"geometry", false}, {"geometry+gravity", true}, {"geometry+couplings", false}};
  std::vector<identify::CandidateScore> scores;
  // Gravity beats the default by far; couplings scores a hair lower than gravity, by chance:
  // gravity, built on the arm's masses, holds.
  std::vector<identify::CrossValidation> v{scored(0.5, 0.01), scored(0.1, 0.01), scored(0.0, 0.01),
                                           scored(-0.0005, 0.02)};
  REQUIRE(v[3].kfold_rms_m < v[2].kfold_rms_m);
  CHECK(choose(with_masses, v, scores) == "geometry+gravity");
  CHECK(scores[0].against == "geometry");  // the smaller model judged against the default, not better
  CHECK(scores[0].t > 2.0);
  CHECK(scores[1].against.empty());  // the default
  CHECK(scores[2].against == "geometry");
  CHECK(scores[2].t <= -2.0);
  CHECK(scores[3].against == "geometry+gravity");
  CHECK(scores[3].t > -2.0);
  // Without the hold (sag from identified masses, say) the lowest score of those better than the
  // default wins.
  const std::vector<Named> without{
      {"registration", false}, {"geometry", false}, {"geometry+sag", false}, {"geometry+couplings", false}};
  CHECK(choose(without, v, scores) == "geometry+couplings");
  CHECK(scores[3].against == "geometry");
  CHECK(scores[3].t <= -2.0);
  // Couplings lower than gravity row by row: it replaces gravity.
  v[3] = scored(-0.05, 0.01);
  CHECK(choose(with_masses, v, scores) == "geometry+couplings");
  CHECK(scores[3].against == "geometry+gravity");
  CHECK(scores[3].t <= -2.0);
  // Lower row by row but with a higher score (better where the holder is good, worse where it is
  // not): not chosen.
  const auto alternating = [&](double low, double high) {
    std::normal_distribution<double> own(0.0, 0.01);
    std::vector<double> mm;
    for (std::size_t i = 0; i < 200; ++i) mm.push_back((i % 2 == 0 ? low : high) + own(rng));
    return errors(mm);
  };
  const std::vector<identify::CrossValidation> w{scored(0.5, 0.01), alternating(0.4, 1.2), alternating(0.2, 1.0),
                                                 alternating(0.1, 1.06)};
  REQUIRE(w[3].kfold_rms_m > w[2].kfold_rms_m);
  CHECK(choose(with_masses, w, scores) == "geometry+gravity");
  CHECK(scores[3].t <= -2.0);
  // A lower score that is chance (not lower row by row than the default's): the default stands.
  const std::vector<identify::CrossValidation> u{scored(0.5, 0.01), scored(0.0, 0.01), scored(-0.001, 0.05),
                                                 scored(0.2, 0.01)};
  REQUIRE(u[2].kfold_rms_m < u[1].kfold_rms_m);
  CHECK(choose(without, u, scores) == "geometry");
  CHECK(scores[2].t > -2.0);
  // The same lower score built on the arm's physics: a lower score is its bar, it replaces the
  // default.
  CHECK(choose(with_masses, u, scores) == "geometry+gravity");
  CHECK(scores[2].t > -2.0);
  // ... where the rows see that physics: its gravity deflection at the held-out rows below their
  // scatter (a rigid arm's compliances fitting the rows' noise), it takes the 2-error bar.
  std::vector<identify::CrossValidation> unseen = u;
  unseen[2].kfold_deflection2.assign(u[2].kfold_error2.size(), std::pow(0.5 * u[2].kfold_rms_m, 2));
  CHECK(choose(with_masses, unseen, scores) == "geometry");
  unseen[2].kfold_deflection2.assign(u[2].kfold_error2.size(), std::pow(2.0 * u[2].kfold_rms_m, 2));
  CHECK(choose(with_masses, unseen, scores) == "geometry+gravity");
  // The default unscored stands.
  v[1].kfold_rms_m = -1.0;
  CHECK(choose(with_masses, v, scores) == "geometry");
  // Of two that beat the default, the larger replaces the smaller only by beating it row by row
  // too: a hair lower by chance, the smaller stands (a 7-joint Franka Panda, motion capture, 20
  // rows, one joint's scale off: geometry+sag's 49 parameters scored 9 % under geometry+scales'
  // 38 at paired t -0.9 between them, and predicted 1.35 times the oracle's error against 1.11).
  const std::vector<Named> sized{
      {"registration", false, 9}, {"geometry", false, 31}, {"geometry+sag", false, 49}, {"geometry+scales", false, 38}};
  std::vector<identify::CrossValidation> by_size{scored(0.5, 0.01), scored(0.1, 0.01), scored(-0.0005, 0.02),
                                                 scored(0.0, 0.01)};
  REQUIRE(by_size[2].kfold_rms_m < by_size[3].kfold_rms_m);
  CHECK(choose(sized, by_size, scores) == "geometry+scales");
  CHECK(scores[2].against == "geometry+scales");
  CHECK(scores[2].t > -2.0);
  by_size[2] = scored(-0.05, 0.01);  // lower row by row: it replaces the smaller
  CHECK(choose(sized, by_size, scores) == "geometry+sag");
  CHECK(scores[2].against == "geometry+scales");
  CHECK(scores[2].t <= -2.0);
  // One parameter apart, one size: the lower score alone decides (a ViperX 300 s, motion capture,
  // 20 rows, one joint's scale off: geometry+scales' 33 parameters scored 20 % under
  // geometry+couplings' 32 at paired t -1.9, and predicted 1.10 times the oracle's error where the
  // couplings left 1.84).
  const std::vector<Named> one_apart{{"registration", false, 9},
                                     {"geometry", false, 27},
                                     {"geometry+scales", false, 33},
                                     {"geometry+couplings", false, 32}};
  std::vector<identify::CrossValidation> apart{scored(0.5, 0.01), scored(0.1, 0.01), scored(-0.0005, 0.02),
                                               scored(0.0, 0.01)};
  REQUIRE(apart[2].kfold_rms_m < apart[3].kfold_rms_m);
  CHECK(choose(one_apart, apart, scores) == "geometry+scales");
  CHECK(scores[2].against == "geometry");  // judged against the default only: against the couplings, the score
}

TEST_CASE("the selection rule pairs each row once: a row predicted in both folds is one difference") {
  // 40 rows; the out-of-range fold predicts rows 0..14 again. The candidate is better by 0.1 mm
  // with 0.2 mm of jitter in the K folds, and on the out-of-range rows by the same again: the
  // rule's t is that of the 40 rows' summed differences, not of 55 entries.
  std::mt19937_64 rng(9);
  std::normal_distribution<double> jitter(0.0, 0.2);
  identify::CrossValidation a, b;
  std::vector<double> per_row(40);
  for (int i = 0; i < 40; ++i) {
    const int row = (i * 7) % 40;  // fold order, not row order
    const double d = -0.1 + jitter(rng);
    a.kfold_rows.push_back(row);
    b.kfold_rows.push_back(row);
    a.kfold_error2.push_back(std::pow((1.0 + d) * 1e-3, 2));
    b.kfold_error2.push_back(1e-6);
    per_row[static_cast<std::size_t>(row)] += d;
  }
  for (int row = 0; row < 15; ++row) {
    const double d = per_row[static_cast<std::size_t>(row)];
    a.out_of_range_rows.push_back(row);
    b.out_of_range_rows.push_back(row);
    a.out_of_range_error2.push_back(std::pow((2.0 + d) * 1e-3, 2));
    b.out_of_range_error2.push_back(4e-6);
    per_row[static_cast<std::size_t>(row)] += d;
  }
  for (identify::CrossValidation* v : {&a, &b}) {
    double k = 0.0, r = 0.0;
    for (const double e : v->kfold_error2) k += e / 40.0;
    for (const double e : v->out_of_range_error2) r += e / 15.0;
    v->kfold_rms_m = std::sqrt(k);
    v->out_of_range_rms_m = std::sqrt(r);
  }
  std::vector<identify::CandidateScore> scores(2);
  scores[0].name = "geometry";
  scores[1].name = "geometry+scales";
  for (std::size_t i = 0; i < 2; ++i) {
    const identify::CrossValidation& v = i == 0 ? b : a;
    scores[i].kfold_rms_m = v.kfold_rms_m;
    scores[i].out_of_range_rms_m = v.out_of_range_rms_m;
    scores[i].score_m = 0.5 * (v.kfold_rms_m + v.out_of_range_rms_m);
  }
  identify::choose_candidate(scores, {b, a}, true);
  CHECK(scores[1].against == "geometry");
  CHECK(scores[1].t == doctest::Approx(identify::paired_t(per_row)).epsilon(1e-9));
}

TEST_CASE("model selection below 100 rows: 10 folds; the default stands unless beaten row by row (issue #41)") {
  CHECK(identify::kMinRowsForSelection <= 20);
  CHECK(identify::selection_folds(20) == 10);
  CHECK(identify::selection_folds(30) == 10);
  CHECK(identify::selection_folds(99) == 10);
  CHECK(identify::selection_folds(100) == 5);

  SUBCASE("a joint scale of 0.4 % at 30 rows: the scale candidate wins and predicts far better") {
    const ScaledArm a = scaled_arm(1.004, 0.997, 30, 41);
    const identify::Selection s = identify::select_model(a.nominal, a.train, {});
    const std::string table = identify::format_selection(s);
    INFO(table);
    CHECK(s.folds == 10);
    CHECK(s.chosen.name == "geometry+scales");
    CHECK(has(table, "paired t vs"));
    CHECK(has(s.reason, "geometry+scales: "));
    CHECK(has(s.reason, "beats geometry"));
    // The gate's cross-validation of the chosen model is the default 5 folds' (identify.hpp).
    CHECK(s.chosen_cross_validation.kfold_error2 ==
          identify::cross_validate(s.chosen.model, a.train, s.chosen.options).kfold_error2);
    identify::IdentifyOptions geometry;
    geometry.rejection_gate = false;
    identify::IdentifyOptions chosen = s.chosen.options;
    chosen.rejection_gate = false;
    const double with_scales =
        simulation::prediction_rms(identify::identify(s.chosen.model, a.train, chosen).model, a.truth, a.held_out);
    const double without =
        simulation::prediction_rms(identify::identify(a.nominal, a.train, geometry).model, a.truth, a.held_out);
    INFO("held out against the truth: geometry+scales ", with_scales * 1e3, " mm, geometry ", without * 1e3, " mm");
    CHECK(with_scales < 0.2 * without);
  }
  SUBCASE("clean precise arms at 30 rows: the default stands") {
    for (std::uint64_t seed = 1; seed <= 2; ++seed) {
      const ScaledArm a = scaled_arm(1.0, 1.0, 30, seed);
      const identify::Selection s = identify::select_model(a.nominal, a.train, {});
      INFO("seed ", seed, "\n", identify::format_selection(s));
      CHECK(s.chosen.name == "geometry");
      CHECK(has(s.reason, "the default"));
    }
  }
}
