// The platform's correction step against the truth, in double precision: the corrected target
// must put the calibrated arm (firmware/core's link and error models instantiated for double,
// built from the same block) where the nominal arm puts the commanded target. Natively and on
// the M4.
#include "firmware/app/kinematic_correction.hpp"

#include <doctest.h>

#include <array>
#include <cmath>
#include <cstdint>

#include "firmware/app/correction_chain.hpp"
#include "firmware/app/platform_app.hpp"
#include "tests/firmware/app/puma560.hpp"

using namespace kincal;

namespace {

// A PUMA 560 in Craig's modified DH ({a, alpha, d, theta, beta}; link i holds alpha_{i-1},
// a_{i-1}), every identified parameter off by up to 0.9 mrad / 0.5 mm, a tilted 15 cm tool whose
// mounting is off too.
shared::CorrectionParameters puma_parameters() {
  shared::CorrectionParameters c = test::puma560_block();
  for (std::size_t j = 0; j < 6; ++j) {
    const float k = static_cast<float>(j) - 2.5f;
    c.joints[j].error = {2.0e-4f * k, -1.5e-4f * k, 1.0e-4f * (3.0f - k), 5.0e-4f - 1.5e-4f * k, 0};
  }
  c.tool_offset = {0.01f, -0.02f, 0.15f, 0.1f, -0.05f, 0.2f};
  c.tool_error = {1.0e-4f, -2.0e-4f, 3.0e-4f, 2.0e-4f, -1.0e-4f, 3.0e-4f};
  return c;
}

struct DoubleArm {
  core::ChainModel<double> nominal, calibrated;
  explicit DoubleArm(const shared::CorrectionParameters& block) {
    core::ParameterSet ids;
    core::ErrorVector<double> errors;
    REQUIRE(app::correction_chain(block, nominal, ids, errors) == app::ChainStatus::kOk);
    REQUIRE(core::apply_parameter_errors(nominal, ids, errors, calibrated) == core::ErrorModelStatus::ok);
  }
};

core::JointVector<double> joints_rad(const app::JointRaw& raw) {
  core::JointVector<double> q = core::JointVector<double>::Zero();
  for (int i = 0; i < 6; ++i) q(i) = shared::joint_angle_rad<double>(raw[static_cast<std::size_t>(i)]);
  return q;
}

}  // namespace

TEST_CASE("kinematic correction: the calibrated arm at the corrected target reaches the nominal pose") {
  const shared::CorrectionParameters block = puma_parameters();
  const DoubleArm arm(block);
  static app::KinematicCorrection step;  // ~6 KiB: off the stack
  std::uint64_t state = 0x9E3779B97F4A7C15ull;
  auto uniform = [&state](double lo, double hi) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return lo + (hi - lo) * static_cast<double>(state >> 11) / 9007199254740992.0;
  };
  double worst_before_m = 0, worst_after_m = 0, worst_after_rad = 0;
  for (int trial = 0; trial < 50; ++trial) {
    // Postures clear of the singularities: elbow (tan q3 = d4 / a3: q3 = 1.524 or -1.618 rad)
    // and wrist (q5 = 0 or pi).
    app::JointRaw in{};
    const double q[6] = {uniform(-2.5, 2.5), uniform(-1.5, 0.5), uniform(-1.0, 0.9),
                         uniform(-2.5, 2.5), uniform(0.4, 2.4),  uniform(-2.5, 2.5)};
    for (std::size_t j = 0; j < 6; ++j) in[j] = shared::quantize_joint_angle(q[j]);
    app::JointRaw out{};
    REQUIRE(step.correct(block, in, out) == app::CorrectStatus::kOk);
    const core::RigidTransform<double> target = core::forward_kinematics(arm.nominal, joints_rad(in));
    const core::Twist<double> before =
        core::small_pose_difference(target, core::forward_kinematics(arm.calibrated, joints_rad(in)));
    const core::Twist<double> after =
        core::small_pose_difference(target, core::forward_kinematics(arm.calibrated, joints_rad(out)));
    worst_before_m = std::fmax(worst_before_m, before.head<3>().norm());
    worst_after_m = std::fmax(worst_after_m, after.head<3>().norm());
    worst_after_rad = std::fmax(worst_after_rad, after.tail<3>().norm());
  }
  MESSAGE("tool position error: " << worst_before_m * 1e3 << " mm uncorrected, " << worst_after_m * 1e6
                                  << " um corrected; orientation " << worst_after_rad * 1e6 << " urad");
  CHECK(worst_before_m > 5e-4);
  // What is left is the quantization of the corrected joints (2^-16 rad = 15 urad on links of
  // ~0.9 m: up to ~25 um) and the correction's third-order remainder.
  CHECK(worst_after_m < 30e-6);
  CHECK(worst_after_rad < 60e-6);
}

TEST_CASE("kinematic correction: joints beyond the arm pass through; a changed block takes effect") {
  shared::CorrectionParameters block = puma_parameters();
  block.joint_count = 6;
  static app::KinematicCorrection step;
  const app::JointRaw in{30000, -40000, -20000, 10000, 60000, -20000};
  app::JointRaw first{}, second{};
  REQUIRE(step.correct(block, in, first) == app::CorrectStatus::kOk);
  block.joints[0].error.theta_rad += 1.0e-3f;  // a new upload: joint 1 is off by 1 mrad more
  REQUIRE(step.correct(block, in, second) == app::CorrectStatus::kOk);
  CHECK(std::abs(second[0] - (first[0] - 66)) <= 1);  // 1 mrad = 65.5 LSB more correction of joint 1
}

TEST_CASE("kinematic correction: statuses") {
  static app::KinematicCorrection step;
  const app::JointRaw in{30000, -40000, -20000, 10000, 60000, -20000};
  app::JointRaw out{};
  shared::CorrectionParameters block = puma_parameters();
  block.joint_count = 0;
  CHECK(step.correct(block, in, out) == app::CorrectStatus::kNoParameters);
  block = puma_parameters();
  block.joints[2].error.beta_rad = 1.0e-4f;  // modified DH has no pitch parameter
  CHECK(step.correct(block, in, out) == app::CorrectStatus::kNoParameters);
  block = puma_parameters();
  block.joints[1].error.theta_rad = 0.2f;  // far off: more than 0.05 rad of correction
  out = {};
  CHECK(step.correct(block, in, out) == app::CorrectStatus::kNotCorrectable);
  CHECK(out == app::JointRaw{});  // not written
  CHECK(app::reason_for(app::CorrectStatus::kNotCorrectable) == shared::ErrorReason::kBadValue);
  CHECK(app::reason_for(app::CorrectStatus::kNoParameters) == shared::ErrorReason::kNoParameters);
  block = puma_parameters();
  CHECK(step.correct(block, in, out) == app::CorrectStatus::kOk);  // and back
}

TEST_CASE("correction chain: each joint's type and convention, Doty's pitch, the tool and its error") {
  shared::CorrectionParameters block;
  block.joint_count = 2;
  block.joints[0] = {shared::JointKind::kPrismatic, shared::LinkKind::kStandardDh, {0.1f, 0.2f, 0.3f, 0.4f, 0}, {}};
  block.joints[0].error.d_m = 1.0e-3f;
  block.joints[1] = {shared::JointKind::kRevolute, shared::LinkKind::kDoty, {0.5f, 0, 0, 0, 0.01f}, {}};
  block.joints[1].error.beta_rad = 2.0e-3f;
  block.tool_offset = {0, 0, 0.1f, 0, 0, 1.5707964f};
  block.tool_error = {0, 0, 0, 0, 0, 3.0e-3f};
  core::ChainModel<double> chain;
  core::ParameterSet ids;
  core::ErrorVector<double> errors;
  REQUIRE(app::correction_chain(block, chain, ids, errors) == app::ChainStatus::kOk);
  CHECK(chain.joint_count == 2);
  CHECK(chain.links[0].joint == core::JointType::prismatic);
  CHECK(chain.links[0].convention == core::LinkConvention::standard_dh);
  CHECK(chain.links[0].parameters.a_m == doctest::Approx(0.1));
  CHECK(chain.links[0].parameters.alpha_rad == doctest::Approx(0.2));
  CHECK(chain.links[0].parameters.d_m == doctest::Approx(0.3));
  CHECK(chain.links[1].convention == core::LinkConvention::doty);
  CHECK(chain.links[1].parameters.beta_rad == doctest::Approx(0.01));
  CHECK(chain.flange_T_tool.rotation(1, 0) == doctest::Approx(1.0));  // 90 degrees about z
  // Every error lands on its parameter: d of link 0, beta of link 1, the tool's rotation about z.
  int found = 0;
  for (int i = 0; i < ids.count; ++i) {
    const core::ParameterId id = ids.ids[static_cast<std::size_t>(i)];
    const double e = errors(i);
    if (id.kind == core::ParameterKind::link_d && id.link == 0)
      found += e == doctest::Approx(1.0e-3);
    else if (id.kind == core::ParameterKind::link_beta && id.link == 1)
      found += e == doctest::Approx(2.0e-3);
    else if (id.kind == core::ParameterKind::tool_rz)
      found += e == doctest::Approx(3.0e-3);
    else
      CHECK(e == 0.0);
  }
  CHECK(found == 3);
  // A pitch on a DH link is refused.
  block.joints[0].nominal.beta_rad = 0.01f;
  CHECK(app::correction_chain(block, chain, ids, errors) == app::ChainStatus::kPitchSet);
}

namespace {

// The PUMA above with a joint map: the controller reports the elbow relative to the shoulder
// (Fanuc-style: chain joint 3 = reading 2 + reading 3, in both models), the gears of joints 1-3
// are off by a few hundred ppm and the shoulder and elbow sag under gravity (the controller's
// model has none of it). Masses after Armstrong et al.'s PUMA 560, a 3 kg payload 12 cm out.
shared::CorrectionParameters coupled_sagging_parameters() {
  shared::CorrectionParameters c = puma_parameters();
  c.joint_maps[2].coupled = true;
  c.joint_maps[2].coupling = {0.0f, 1.0f, 1.0f, 0.0f, 0.0f, 0.0f};
  const float scale_errors[6] = {4.0e-4f, -3.0e-4f, 5.0e-4f, 2.0e-4f, 0.0f, -2.0e-4f};
  const float compliance_errors[6] = {0.0f, 2.0e-5f, 3.0e-5f, 0.0f, 0.0f, 0.0f};  // rad/(N m)
  const float mass_kg[6] = {0.0f, 17.4f, 4.8f, 0.82f, 0.34f, 0.09f};
  const std::array<float, 3> centre_m[6] = {
      {0, 0, 0}, {0.068f, 0.006f, -0.016f}, {0, -0.07f, 0.014f}, {0, 0, -0.019f}, {0, 0, 0}, {0, 0, 0.032f}};
  for (std::size_t j = 0; j < 6; ++j) {
    c.joint_maps[j].scale_error = scale_errors[j];
    c.joint_maps[j].compliance_error = compliance_errors[j];
    c.joint_maps[j].mass_kg = mass_kg[j];
    c.joint_maps[j].centre_of_mass_m = centre_m[j];
  }
  c.payload_mass_kg = 3.0f;
  c.payload_centre_of_mass_m = {0.0f, 0.0f, 0.12f};
  return c;
}

// Both arms in double, each through its own joint map: readings -> coupled -> deflected -> FK.
struct DoubleMappedArm {
  DoubleArm arm;
  core::PreparedChain<double> nominal, calibrated;
  core::JointMap<double> nominal_map, identified_map;
  core::MassModel<double> masses;
  explicit DoubleMappedArm(const shared::CorrectionParameters& block) : arm(block) {
    core::prepare_chain(arm.nominal, nominal);
    core::prepare_chain(arm.calibrated, calibrated);
    REQUIRE(app::correction_joint_maps(block, nominal_map, identified_map, masses) == app::ChainStatus::kOk);
  }
  core::RigidTransform<double> pose(bool actual, const app::JointRaw& raw) const {
    const core::PreparedChain<double>& chain = actual ? calibrated : nominal;
    const core::JointMap<double>& map = actual ? identified_map : nominal_map;
    core::JointVector<double> coupled, deflected;
    core::coupled_values(map, joints_rad(raw), coupled);
    core::DeflectionWorkspace<double> ws;
    core::deflect(chain, masses, map.compliance, coupled, ws, deflected);
    core::joint_trig(chain, deflected, ws.trig);
    core::RigidTransform<double> base_T_tool;
    core::tool_pose(chain, deflected, ws.trig, base_T_tool);
    return base_T_tool;
  }
};

struct Residuals {
  double before_m = 0, after_m = 0, after_rad = 0;
};

// The worst errors of the actual arm against the controller's target over 50 postures clear of
// the singularities, before and after `step` corrects the readings with `uploaded`.
Residuals correct_postures(const DoubleMappedArm& truth, const shared::CorrectionParameters& uploaded) {
  static app::KinematicCorrection step;
  std::uint64_t state = 0x2545F4914F6CDD1Dull;
  auto uniform = [&state](double lo, double hi) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return lo + (hi - lo) * static_cast<double>(state >> 11) / 9007199254740992.0;
  };
  Residuals r;
  for (int trial = 0; trial < 50; ++trial) {
    double q2 = 0, q3 = 0;  // q3: the chain's elbow
    do {
      q2 = uniform(-1.5, 0.5);
      q3 = uniform(-1.0, 0.9);
      // Clear of the shoulder singularity too: the wrist centre's distance from the axis of joint 1.
    } while (std::fabs(0.4318 * std::cos(q2) + 0.0203 * std::cos(q2 + q3) - 0.4318 * std::sin(q2 + q3)) < 0.1);
    const double q[6] = {uniform(-2.5, 2.5), q2, q3 - q2, uniform(-2.5, 2.5), uniform(0.4, 2.4), uniform(-2.5, 2.5)};
    app::JointRaw in{};
    for (std::size_t j = 0; j < 6; ++j) in[j] = shared::quantize_joint_angle(q[j]);
    app::JointRaw out{};
    REQUIRE(step.correct(uploaded, in, out) == app::CorrectStatus::kOk);
    const core::RigidTransform<double> target = truth.pose(false, in);
    const core::Twist<double> before = core::small_pose_difference(target, truth.pose(true, in));
    const core::Twist<double> after = core::small_pose_difference(target, truth.pose(true, out));
    r.before_m = std::fmax(r.before_m, before.head<3>().norm());
    r.after_m = std::fmax(r.after_m, after.head<3>().norm());
    r.after_rad = std::fmax(r.after_rad, after.tail<3>().norm());
  }
  return r;
}

}  // namespace

TEST_CASE("kinematic correction: a coupled, scaled, sagging arm reaches the nominal pose through its joint map") {
  const shared::CorrectionParameters block = coupled_sagging_parameters();
  const DoubleMappedArm truth(block);
  const Residuals with_map = correct_postures(truth, block);
  MESSAGE("joint map applied: " << with_map.before_m * 1e3 << " mm uncorrected, " << with_map.after_m * 1e6
                                << " um corrected; orientation " << with_map.after_rad * 1e6 << " urad");
  CHECK(with_map.before_m > 1e-3);
  // As for the plain arm: quantization of the corrected readings and the third-order remainder
  // (the map's inverse is exact but for undeflect's remaining ~1e-6 of the deflection).
  CHECK(with_map.after_m < 30e-6);
  CHECK(with_map.after_rad < 60e-6);

  // The same block with the identified map left out (scale and compliance errors dropped): the
  // platform corrects the geometry only, and the real arm misses by far more.
  shared::CorrectionParameters geometry_only = block;
  for (shared::JointMapValues& m : geometry_only.joint_maps) {
    m.scale_error = 0.0f;
    m.compliance_error = 0.0f;
  }
  const Residuals without_map = correct_postures(truth, geometry_only);
  MESSAGE("identified joint map ignored: " << without_map.after_m * 1e6 << " um");
  CHECK(without_map.after_m > 10 * with_map.after_m);
  CHECK(without_map.after_m > 3e-4);
}

TEST_CASE("kinematic correction: a joint map the platform cannot use is refused") {
  static app::KinematicCorrection step;
  const app::JointRaw in{30000, -40000, -20000, 10000, 60000, -20000};
  app::JointRaw out{};
  shared::CorrectionParameters block = coupled_sagging_parameters();
  REQUIRE(step.correct(block, in, out) == app::CorrectStatus::kOk);
  block.joint_maps[2].coupling = {0.0f, 1.0f, 0.0f, 0.0f, 0.0f, 0.0f};  // joint 3 = joint 2: singular
  CHECK(step.correct(block, in, out) == app::CorrectStatus::kNoParameters);
  block = coupled_sagging_parameters();
  block.joint_maps[1].scale_error = -1.0f;  // identified scale 0
  CHECK(step.correct(block, in, out) == app::CorrectStatus::kNoParameters);
  block = coupled_sagging_parameters();
  block.joint_count = 5;  // the coupling row of joint 3 is fine, but joint 6 is beyond the arm now
  block.joint_maps[2].coupling[5] = 0.5f;
  CHECK(step.correct(block, in, out) == app::CorrectStatus::kNoParameters);
  block = coupled_sagging_parameters();
  block.joint_maps[4].mass_kg = -1.0f;
  CHECK(step.correct(block, in, out) == app::CorrectStatus::kNoParameters);
  block = coupled_sagging_parameters();
  CHECK(step.correct(block, in, out) == app::CorrectStatus::kOk);
}
