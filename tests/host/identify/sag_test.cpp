// Gravity sag for a model without masses (issue #41, identify/sag.hpp): the geometry+sag
// candidate identifies each link's mass and centre of mass with the joints' compliances, in a
// gauge, from data of an arm that sags under masses its model does not know; geometry+gravity
// identifies the centres of the masses its model gives.
#include <doctest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <string>

#include "host/identify/model_selection.hpp"
#include "host/identify/sag.hpp"
#include "host/model/model_file.hpp"
#include "tests/host/identify/simulation.hpp"

namespace {

using namespace kincal;
using model::RobotModel;

RobotModel robot(const char* name) { return model::load_model(std::string(KINCAL_ROBOTS_DIR) + "/" + name); }

double uniform(std::mt19937_64& rng, double lo, double hi) {
  return std::uniform_real_distribution<double>(lo, hi)(rng);
}

// Small geometric errors for sim::perturbed: 0.3 mm and 0.03 deg.
sim::ErrorScale small_errors() {
  sim::ErrorScale errors;
  errors.length_m = 3e-4;
  errors.angle_rad = 0.03 * std::numbers::pi / 180.0;
  return errors;
}

// `g` turned 0.6 deg about frame 0's x and -0.8 deg about its y: a base on a floor off level.
model::Vector3 off_level(const model::Vector3& g) {
  const double rx = 0.6 * std::numbers::pi / 180.0, ry = -0.8 * std::numbers::pi / 180.0;
  return Eigen::AngleAxisd(ry, model::Vector3::UnitY()) * (Eigen::AngleAxisd(rx, model::Vector3::UnitX()) * g);
}

// `truth` (with masses) with a compliance on each joint that gravity loads by at least a tenth of
// the largest load: 0.05-0.2 deg of deflection at its largest torque (issue #41's service class),
// drawn from `rng`.
RobotModel compliant(RobotModel truth, std::mt19937_64& rng) {
  std::vector<double> largest(truth.joints.size(), 0.0);
  for (const std::vector<double>& q : sim::random_configurations(truth, 300, rng)) {
    const model::ChainAtJoints at = model::chain_at_joints(truth, q);
    const core::JointVector<double> g = model::gravity_forces(truth, at.chain, at.coupled);
    for (std::size_t i = 0; i < largest.size(); ++i)
      largest[i] = std::max(largest[i], std::abs(g(static_cast<Eigen::Index>(i))));
  }
  const double top = *std::max_element(largest.begin(), largest.end());
  for (std::size_t i = 0; i < largest.size(); ++i)
    if (largest[i] >= 0.1 * top)
      truth.joints[i].compliance = uniform(rng, 0.05, 0.2) * std::numbers::pi / 180.0 / largest[i];
  return truth;
}

// `truth` with a mass (2-20 kg) and a centre of mass (within 0.2 m of its frame's origin; along_link:
// half way back to the previous frame's origin at zero readings, within 0.05 m, as a link's mass
// lies along it) on every link, drawn from `rng`, and compliances (above).
RobotModel sagging(RobotModel truth, std::mt19937_64& rng, bool along_link = false) {
  const model::ChainAtJoints zero = model::chain_at_joints(truth, std::vector<double>(truth.joints.size(), 0.0));
  for (std::size_t i = 0; i < truth.joints.size(); ++i) {
    model::Joint& j = truth.joints[i];
    j.mass_kg = uniform(rng, 2.0, 20.0);
    j.centre_of_mass_m = model::Vector3(uniform(rng, -0.2, 0.2), uniform(rng, -0.2, 0.2), uniform(rng, -0.2, 0.2));
    if (!along_link) continue;
    const core::RigidTransform<double>&start = zero.frames.base_T_frame[i], &end = zero.frames.base_T_frame[i + 1];
    j.centre_of_mass_m =
        0.5 * end.rotation.transpose() * (start.translation - end.translation) + 0.25 * j.centre_of_mass_m;
  }
  return compliant(truth, rng);
}

// An arm with small geometric errors that sags (above) under masses its model (`name` without its
// masses and compliances) does not have: `rows` rows measured with 0.02 mm noise and 200 held-out
// readings, all drawn from `rng`.
struct SagCase {
  RobotModel nominal, truth;
  model::Dataset train;
  std::vector<std::vector<double>> held_out;
};
SagCase sag_case(const char* name, std::mt19937_64& rng, int rows, bool along_link = false) {
  SagCase c{robot(name), {}, {}, {}};
  for (model::Joint& j : c.nominal.joints) {
    j.compliance.reset();
    j.mass_kg = 0.0;
  }
  c.nominal.payload.mass_kg = 0.0;
  const sim::ErrorScale errors = small_errors();
  c.truth = sagging(sim::perturbed(c.nominal, rng, errors), rng, along_link);
  c.train =
      simulation::measure(c.truth, sim::random_configurations(c.nominal, rows, rng), rng, 2e-5, false, 0.0, false);
  c.held_out = sim::random_configurations(c.nominal, 200, rng);
  return c;
}

// Held-out RMS of the model identified by the named candidate against the truth's positions.
struct Fit {
  identify::IdentifyResult result;
  double held_out_m = 0.0;
};
Fit fit(const char* candidate, const RobotModel& nominal, const RobotModel& truth, const model::Dataset& train,
        const std::vector<std::vector<double>>& held_out) {
  const identify::Candidate c = identify::find_candidate(nominal, {}, candidate);
  identify::IdentifyOptions o = c.options;
  o.rejection_gate = false;
  Fit f{identify::identify(c.model, train, o), 0.0};
  f.held_out_m = simulation::prediction_rms(f.result.model, truth, held_out);
  return f;
}

// `with` (a model with a feature to identify) and `without` (the same with it switched off)
// identified from `train` with the candidate's options `o`, no rejection gate: `with`'s result and
// both models' held-out RMS against the truth's positions.
struct Compared {
  identify::IdentifyResult with;
  double with_m = 0.0, without_m = 0.0;
};
Compared compare(const RobotModel& with, const RobotModel& without, const model::Dataset& train,
                 identify::IdentifyOptions o, const RobotModel& truth,
                 const std::vector<std::vector<double>>& held_out) {
  o.rejection_gate = false;
  Compared c{identify::identify(with, train, o), 0.0, 0.0};
  c.with_m = simulation::prediction_rms(c.with.model, truth, held_out);
  c.without_m = simulation::prediction_rms(identify::identify(without, train, o).model, truth, held_out);
  return c;
}

}  // namespace

TEST_CASE("an arm that sags under masses its model does not have: geometry+sag predicts far better than geometry") {
  for (const char* name : {"puma560.yaml", "ur5.yaml"}) {
    std::mt19937_64 rng(41);
    const auto [nominal, truth, train, held_out] = sag_case(name, rng, 150);
    INFO(std::string(name));

    const Fit geometry = fit("geometry", nominal, truth, train, held_out);
    const Fit sag = fit("geometry+sag", nominal, truth, train, held_out);
    MESSAGE(std::string(name), ": held out ", geometry.held_out_m * 1e3, " mm (geometry), ", sag.held_out_m * 1e3,
            " mm (geometry+sag)");
    // Measured (seed 41, 150 rows): PUMA 0.402 -> 0.093 mm (0.121 before the masses' priors), UR5
    // 0.531 -> 0.0092 mm (the noise's level). The PUMA's stays well above the noise: the solve does
    // not find the truth's masses there.
    CHECK(sag.held_out_m < 0.5 * geometry.held_out_m);

    // Physical and in the gauge the notes name: the reference compliance held, nothing negative.
    const RobotModel& m = sag.result.model;
    const auto note = std::find_if(sag.result.notes.begin(), sag.result.notes.end(), [](const std::string& s) {
      return s.find("gauge: compliance") != std::string::npos;
    });
    REQUIRE(note != sag.result.notes.end());
    const std::string reference =
        note->substr(note->find("gauge: ") + 7, note->find(" held") - note->find("gauge: ") - 7);
    const std::vector<std::string>& fixed = m.calibration->held_fixed;
    CHECK(std::find(fixed.begin(), fixed.end(), reference) != fixed.end());
    // Nothing was fixed on request: each held parameter says why the sag held it.
    for (const identify::HeldFixed& h : sag.result.identifiability.held_fixed) {
      INFO(model::parameter_name(h.id), ": ", h.reason);
      CHECK(h.reason != "fixed on request");
      if (model::parameter_name(h.id) == reference) CHECK(h.reason.find("the sag's gauge") == 0);
    }
    int masses = 0;
    for (const core::ParameterId& id : sag.result.identifiability.identified) masses += id.kind == model::kLinkMass;
    CHECK(masses >= 2);
    for (const model::Joint& j : m.joints) {
      CHECK(j.mass_kg >= 0.0);
      CHECK(j.compliance.value_or(0.0) >= 0.0);
    }
    // The report counts each compliance from the nominal's 0, as the record does, not from stage
    // 1's values (a compliance stage 2 took back to 0 was printed as a change of -87 urad/Nm).
    int compliances = 0;
    for (std::size_t k = 0; k < sag.result.identifiability.identified.size(); ++k) {
      const core::ParameterId id = sag.result.identifiability.identified[k];
      if (id.kind != model::kJointCompliance) continue;
      ++compliances;
      CHECK(sag.result.change(static_cast<Eigen::Index>(k)) ==
            doctest::Approx(m.joints[id.link].compliance.value_or(0.0)).epsilon(1e-9));
      CHECK(sag.result.start.joints[id.link].compliance.value_or(0.0) == 0.0);
      // Its prior is on the deflection, centred on a rigid joint (prior.hpp), not on stage 1's value.
      CHECK(sag.result.prior_centre(static_cast<Eigen::Index>(k)) == 0.0);
      CHECK(std::isfinite(sag.result.prior_sigma(static_cast<Eigen::Index>(k))));
    }
    CHECK(compliances >= 1);
    // Only compliance x first moment is seen: twice the masses and half the compliances predict
    // the same.
    RobotModel scaled = m;
    for (model::Joint& j : scaled.joints) {
      j.mass_kg *= 2.0;
      if (j.compliance) *j.compliance *= 0.5;
    }
    CHECK(simulation::prediction_rms(scaled, m, held_out) < 1e-12);
    // The written model is an ordinary one: read back, it predicts the same.
    const RobotModel read = model::parse_model(model::write_model(m), "written");
    CHECK(simulation::prediction_rms(read, m, held_out) < 1e-9);
  }
}

TEST_CASE("on a handful of rows the sag's priors keep geometry+sag from fitting the noise") {
  // Three arms, three seeds, 20 rows each, the links' masses along the links: pooled held-out
  // RMS against the truth, the default (the masses and centres drawn toward the start by priors
  // whose widths the evidence chooses, each compliance toward a rigid joint by a deflection's
  // prior) against those terms free (before).
  double drawn2 = 0.0, free2 = 0.0;
  int masses = 0, centres = 0;
  for (std::uint64_t seed : {19u, 20u, 21u})
    for (const char* name : {"puma560.yaml", "ur5.yaml", "heavy6r.yaml"}) {
      std::mt19937_64 rng(seed);
      const auto [nominal, truth, train, held_out] = sag_case(name, rng, 20, true);
      const identify::Candidate c = identify::find_candidate(nominal, {}, "geometry+sag");
      identify::IdentifyOptions o = c.options;
      o.rejection_gate = false;
      const identify::IdentifyResult drawn = identify::identify(c.model, train, o);
      identify::IdentifyOptions free = o;
      simulation::free_sag_priors(free.prior, nominal.joints.size());
      const double drawn_m = simulation::prediction_rms(drawn.model, truth, held_out);
      const double free_m = simulation::prediction_rms(identify::identify(c.model, train, free).model, truth, held_out);
      MESSAGE(std::string(name), " seed ", seed, ": held out ", free_m * 1e3, " mm (free), ", drawn_m * 1e3,
              " mm (drawn toward the start)");
      drawn2 += drawn_m * drawn_m;
      free2 += free_m * free_m;
      for (const identify::ClassScale& s : drawn.prior_scales.classes) {
        masses += s.kind == identify::PriorClass::link_mass;
        centres += s.kind == identify::PriorClass::mass_centre && s.parameters == 1;
      }
    }
  // Measured: 0.048 mm RMS pooled against 0.092 free (0.050 against 0.094 with one width for all
  // centres); case by case from 0.19 to 1.09 times the free fit's (heavy6r seed 21: 0.229 mm free,
  // 0.043 drawn), the priors' gain is the blow-ups avoided.
  CHECK(std::sqrt(drawn2) < 0.7 * std::sqrt(free2));
  CHECK(masses == 9);       // the masses' class in every fit
  CHECK(centres >= 3 * 9);  // every mass centre its own class: three or more per fit on average
}

TEST_CASE("geometry+sag is a candidate exactly when the model has neither masses nor a compliance") {
  const auto names = [](const RobotModel& m) {
    std::string out;
    for (const identify::Candidate& c : identify::candidate_models(m, {})) out += c.name + " ";
    return out;
  };
  const RobotModel puma = robot("puma560.yaml");
  CHECK(names(puma).find("geometry+sag") != std::string::npos);
  CHECK(names(robot("ur10.yaml")).find("geometry+sag") == std::string::npos);  // UR's masses
  RobotModel compliant = puma;
  compliant.joints[1].compliance = 1e-6;
  compliant.joints[1].mass_kg = 10.0;
  CHECK(names(compliant).find("geometry+sag") == std::string::npos);
  // The candidate's start assumes nothing of the robot: the same mass on every link, at its frame.
  const identify::Candidate c = identify::find_candidate(puma, {}, "geometry+sag");
  for (const model::Joint& j : c.model.joints) {
    CHECK(j.identify_mass);
    CHECK(j.mass_kg == identify::kStartMass_kg);
    CHECK(j.centre_of_mass_m.isZero(0.0));
    CHECK(j.compliance == 0.0);
  }
}

TEST_CASE("spreading the identified masses along revolute joints changes no gravity load") {
  std::mt19937_64 rng(5);
  // The PUMA's six revolute joints are one run; the Stanford arm's boom and the ARID's first
  // joint are prismatic: a run ends before each (its mass is what the prismatic joint carries).
  // DH, Doty's convention and (the PUMA's table read as) modified DH.
  RobotModel modified = robot("puma560.yaml");
  for (model::Joint& j : modified.joints) j.convention = core::LinkConvention::modified_dh;
  for (const RobotModel& arm : {robot("puma560.yaml"), robot("stanford_rrp.yaml"), robot("arid_prrr.yaml"), modified}) {
    CAPTURE(arm.name);
    RobotModel m = identify::with_identified_masses(sim::perturbed(arm, rng));
    for (model::Joint& j : m.joints) {
      j.mass_kg = uniform(rng, -0.5, 3.0);  // a free-signed solve's masses, some below 0
      j.centre_of_mass_m = model::Vector3(uniform(rng, -0.3, 0.3), uniform(rng, -0.3, 0.3), uniform(rng, -0.3, 0.3));
    }
    const std::optional<RobotModel> spread = identify::spread_masses_evenly(m);
    REQUIRE(spread);
    for (const std::vector<double>& q : sim::random_configurations(m, 20, rng)) {
      const model::ChainAtJoints at = model::chain_at_joints(m, q);
      const core::JointVector<double> before = model::gravity_forces(m, at.chain, at.coupled);
      const core::JointVector<double> after = model::gravity_forces(*spread, at.chain, at.coupled);
      CHECK((after - before).cwiseAbs().maxCoeff() <= 1e-9 * std::max(1.0, before.cwiseAbs().maxCoeff()));
    }
    // Over each run every link the run's mean mass, above 0.
    for (std::size_t first = 0; first < m.joints.size();) {
      std::size_t last = first;
      while (last + 1 < m.joints.size() && m.joints[last + 1].type == core::JointType::revolute) ++last;
      double sum = 0.0;
      for (std::size_t k = first; k <= last; ++k) sum += m.joints[k].mass_kg;
      for (std::size_t k = first; k <= last; ++k)
        CHECK(spread->joints[k].mass_kg == doctest::Approx(sum / static_cast<double>(last - first + 1)));
      first = last + 1;
    }
    // A run whose masses sum to 0 or less has no such spread.
    for (model::Joint& j : m.joints) j.mass_kg = -std::abs(j.mass_kg);
    CHECK_FALSE(identify::spread_masses_evenly(m));
  }
}

TEST_CASE("an arm standing off level: gravity's direction is identified with the sag") {
  const RobotModel nominal = robot("ur5.yaml");
  std::mt19937_64 rng(7);
  const sim::ErrorScale errors = small_errors();
  RobotModel truth = sagging(sim::perturbed(nominal, rng, errors), rng);
  truth.gravity_mps2 = off_level(truth.gravity_mps2);
  const model::Dataset train =
      simulation::measure(truth, sim::random_configurations(nominal, 150, rng), rng, 2e-5, false, 0.0, false);
  const std::vector<std::vector<double>> held_out = sim::random_configurations(nominal, 200, rng);

  const identify::Candidate c = identify::find_candidate(nominal, {}, "geometry+sag");
  CHECK(c.model.identify_gravity_direction);
  RobotModel level = c.model;
  level.identify_gravity_direction = false;
  const auto [with, with_m, without_m] = compare(c.model, level, train, c.options, truth, held_out);
  MESSAGE("held out ", without_m * 1e3, " mm (gravity along frame 0's -z), ", with_m * 1e3,
          " mm (its direction identified)");
  // Measured (seed 7, 150 rows, 0.02 mm noise): 0.0201 -> 0.0100 mm, the second near what the
  // noise leaves.
  CHECK(with_m < 0.7 * without_m);
  // The direction found is the truth's (in frame 0, which the registration finds as the truth's).
  const double off =
      std::acos(std::clamp(with.model.gravity_mps2.normalized().dot(truth.gravity_mps2.normalized()), -1.0, 1.0));
  MESSAGE("identified gravity ", off * 180.0 / std::numbers::pi, " deg from the truth's");
  CHECK(off < 0.15 * std::numbers::pi / 180.0);  // measured 0.062 deg of the 1 deg tilt
  // Written and read back, the direction stays (gravity is a key of the model file).
  const RobotModel read = model::parse_model(model::write_model(with.model), "written");
  CHECK(simulation::prediction_rms(read, with.model, held_out) < 1e-9);
}

TEST_CASE("an arm off level whose first joint gives way too: its sag under the tilt is identified") {
  // The UR10 with its masses (geometry+gravity: compliances in rad/(N m)) standing 1 deg off level,
  // and its first joint as compliant as the joint that gives way most: gravity loads the first
  // joint only through the tilt, so its sag is compliance x tilt, zero in both at the start, where
  // gravity lies along the first axis (sag.hpp's tilted stage).
  const RobotModel nominal = robot("ur10.yaml");
  const identify::Candidate c = identify::find_candidate(nominal, {}, "geometry+gravity");
  std::mt19937_64 rng(19);
  const sim::ErrorScale errors = small_errors();
  RobotModel truth = compliant(sim::perturbed(nominal, rng, errors), rng);
  double largest_compliance = 0.0;
  for (const model::Joint& j : truth.joints)
    largest_compliance = std::max(largest_compliance, j.compliance.value_or(0.0));
  truth.joints[0].compliance = largest_compliance;
  truth.gravity_mps2 = off_level(truth.gravity_mps2);
  const model::Dataset train =
      simulation::measure(truth, sim::random_configurations(nominal, 150, rng), rng, 2e-5, false, 0.0, false);
  const std::vector<std::vector<double>> held_out = sim::random_configurations(nominal, 200, rng);

  identify::IdentifyOptions held = c.options;  // what the start alone decides: compliance1 held
  held.rejection_gate = false;
  held.fixed.push_back("compliance1");
  const double held_m = simulation::prediction_rms(identify::identify(c.model, train, held).model, truth, held_out);
  identify::IdentifyOptions o = c.options;
  o.rejection_gate = false;
  const identify::IdentifyResult r = identify::identify(c.model, train, o);
  const double freed_m = simulation::prediction_rms(r.model, truth, held_out);
  MESSAGE("held out ", held_m * 1e3, " mm (compliance1 held), ", freed_m * 1e3, " mm (freed at the found tilt)");
  const auto identified = std::find_if(r.identifiability.identified.begin(), r.identifiability.identified.end(),
                                       [](core::ParameterId id) { return model::parameter_name(id) == "compliance1"; });
  CHECK(identified != r.identifiability.identified.end());
  const auto note = std::find_if(r.notes.begin(), r.notes.end(), [](const std::string& n) {
    return n.find("solved again with gravity's direction where the fit found it") != std::string::npos;
  });
  CHECK(note != r.notes.end());
  const double c1 = r.model.joints[0].compliance.value_or(0.0);
  MESSAGE("compliance1 ", c1 * 1e6, " urad/Nm, the truth's ", largest_compliance * 1e6);
  // Measured (seed 19, 150 rows, 0.02 mm noise): 0.0511 -> 0.0110 mm, compliance1 65.2 urad/Nm of
  // the truth's 77.2 (drawn toward a rigid joint by its prior, the default deflection at the most
  // loaded joint's load; 76.2 without it); held, as the start alone decided before, the first two.
  CHECK(freed_m < 0.5 * held_m);
  CHECK(std::abs(c1 - largest_compliance) < 0.25 * largest_compliance);
}

TEST_CASE("geometry+gravity identifies each link's centre of mass, drawn toward the model's") {
  const RobotModel nominal = robot("ur10.yaml");
  const identify::Candidate c = identify::find_candidate(nominal, {}, "geometry+gravity");
  for (const model::Joint& j : c.model.joints) {
    CHECK(j.identify_centre == (j.mass_kg > 0.0));  // the mass given, its centre a parameter
    CHECK(!j.identify_mass);
  }
  // The truth: small geometric errors, the UR10's centres of mass up to 50 mm from its file's (a
  // CAD estimate, a cable, a link's zero that turned its mass where the model turns only the next
  // axis), compliances on the joints gravity loads.
  std::mt19937_64 rng(13);
  const sim::ErrorScale errors = small_errors();
  RobotModel truth = sim::perturbed(nominal, rng, errors);
  for (model::Joint& j : truth.joints)
    j.centre_of_mass_m +=
        model::Vector3(uniform(rng, -0.05, 0.05), uniform(rng, -0.05, 0.05), uniform(rng, -0.05, 0.05));
  truth = compliant(truth, rng);
  const model::Dataset train =
      simulation::measure(truth, sim::random_configurations(nominal, 150, rng), rng, 2e-5, false, 0.0, false);
  const std::vector<std::vector<double>> held_out = sim::random_configurations(nominal, 200, rng);

  RobotModel given = c.model;
  for (model::Joint& j : given.joints) j.identify_centre = false;
  const auto [with, with_m, without_m] = compare(c.model, given, train, c.options, truth, held_out);
  MESSAGE("held out ", without_m * 1e3, " mm (the file's centres of mass), ", with_m * 1e3,
          " mm (identified, drawn toward them)");
  // Measured (seed 13, 150 rows, 0.02 mm noise): 0.0462 -> 0.0097 mm, the 'given centres' class
  // widened by the data (held at its 1 mm default: 0.0405).
  CHECK(with_m < 0.8 * without_m);
  // Written and read back, the identified centres stay (centre_of_mass is a key of the model file).
  const RobotModel read = model::parse_model(model::write_model(with.model), "written");
  CHECK(simulation::prediction_rms(read, with.model, held_out) < 1e-9);
}

TEST_CASE("geometry+gravity's cross-validation measures its deflection: below the rows' scatter on a rigid arm") {
  // The UR10's file with its masses, 30 rows at 0.02 mm: a rigid arm (small geometric errors
  // only) and the same arm with compliances. Model selection lets geometry+gravity stand on a
  // lower score alone only where its gravity deflection at the folds' held-out rows reaches their
  // scatter (model_selection.cpp): on the rigid arm its free compliances fit only the rows' noise.
  const RobotModel nominal = robot("ur10.yaml");
  const identify::Candidate c = identify::find_candidate(nominal, {}, "geometry+gravity");
  std::mt19937_64 rng(17);
  const sim::ErrorScale errors = small_errors();
  const RobotModel rigid = sim::perturbed(nominal, rng, errors);
  const RobotModel sagging_arm = compliant(rigid, rng);
  const auto deflection_over_scatter = [&](const RobotModel& truth) {
    const model::Dataset rows =
        simulation::measure(truth, sim::random_configurations(nominal, 30, rng), rng, 2e-5, false, 0.0, false);
    identify::SelectionOptions few;
    few.folds = identify::selection_folds(30);
    const identify::CrossValidation v = identify::cross_validate(c.model, rows, c.options, few);
    REQUIRE(v.kfold_deflection2.size() == v.kfold_error2.size());
    double d = 0.0;
    for (const double x : v.kfold_deflection2) d += x;
    return std::sqrt(d / static_cast<double>(v.kfold_deflection2.size())) / v.kfold_rms_m;
  };
  const double on_rigid = deflection_over_scatter(rigid), on_sagging = deflection_over_scatter(sagging_arm);
  MESSAGE("geometry+gravity's deflection over its K-fold RMS: ", on_rigid, " (rigid), ", on_sagging, " (sagging)");
  CHECK(on_rigid < 1.0);
  CHECK(on_sagging > 1.0);
  // A model without compliances has none to measure.
  const model::Dataset rows =
      simulation::measure(rigid, sim::random_configurations(nominal, 30, rng), rng, 2e-5, false, 0.0, false);
  CHECK(identify::cross_validate(nominal, rows, {}).kfold_deflection2.empty());
}
