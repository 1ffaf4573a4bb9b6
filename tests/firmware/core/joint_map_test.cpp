// joint_map.hpp: the gravity forces against the derivative of an independent potential energy
// (chain_fixtures.hpp's double forward kinematics, central differences), float against double,
// the coupling's inverse, and undeflect inverting deflect. Natively and on the M4.
#include "firmware/core/joint_map.hpp"

#include <doctest.h>

#include <Eigen/Dense>
#include <cmath>

#include "tests/firmware/core/chain_fixtures.hpp"

using namespace kincal::core;
using namespace kincal::test;

namespace {

MassModel<double> random_masses(RandomSource& random) {
  MassModel<double> m;
  for (std::size_t i = 0; i < kMaxJoints; ++i) {
    m.link_mass_kg[i] = random.uniform(0.0, 20.0);
    for (double& c : m.link_centre_of_mass_m[i]) c = random.uniform(-0.3, 0.3);
  }
  m.payload_mass_kg = random.uniform(0.0, 5.0);
  for (double& c : m.payload_centre_of_mass_m) c = random.uniform(-0.2, 0.2);
  const Eigen::Vector3d g = random.unit_vector() * 9.80665;
  m.gravity_mps2 = {g(0), g(1), g(2)};
  return m;
}

MassModel<float> to_float(const MassModel<double>& m) {
  MassModel<float> f;
  for (std::size_t i = 0; i < kMaxJoints; ++i) {
    f.link_mass_kg[i] = static_cast<float>(m.link_mass_kg[i]);
    for (std::size_t k = 0; k < 3; ++k)
      f.link_centre_of_mass_m[i][k] = static_cast<float>(m.link_centre_of_mass_m[i][k]);
  }
  f.payload_mass_kg = static_cast<float>(m.payload_mass_kg);
  for (std::size_t k = 0; k < 3; ++k) {
    f.payload_centre_of_mass_m[k] = static_cast<float>(m.payload_centre_of_mass_m[k]);
    f.gravity_mps2[k] = static_cast<float>(m.gravity_mps2[k]);
  }
  return f;
}

// Gravity's potential energy -sum m g . c at q, every frame from the independent FK.
double potential_energy(const ChainModel<double>& chain, const MassModel<double>& masses, const Eigen::VectorXd& q) {
  const Eigen::Vector3d g0(masses.gravity_mps2[0], masses.gravity_mps2[1], masses.gravity_mps2[2]);
  const Eigen::Vector3d g = chain.base_T_frame0.rotation * g0;
  const auto point = [](const std::array<double, 3>& p) { return Eigen::Vector3d(p[0], p[1], p[2]); };
  double energy = 0.0;
  for (int b = 0; b < chain.joint_count; ++b) {
    ChainModel<double> upto = chain;
    upto.joint_count = b + 1;
    upto.flange_T_tool = RigidTransform<double>{};
    const auto k = static_cast<std::size_t>(b);
    energy -= masses.link_mass_kg[k] * g.dot(reference_fk(upto, q) * point(masses.link_centre_of_mass_m[k]));
  }
  ChainModel<double> flange = chain;
  flange.flange_T_tool = RigidTransform<double>{};
  energy -= masses.payload_mass_kg * g.dot(reference_fk(flange, q) * point(masses.payload_centre_of_mass_m));
  return energy;
}

JointVector<double> forces_at(const ChainModel<double>& chain, const MassModel<double>& masses,
                              const JointVector<double>& q) {
  PreparedChain<double> prepared;
  prepare_chain(chain, prepared);
  DeflectionWorkspace<double> ws;
  joint_trig(prepared, q, ws.trig);
  forward_kinematics(prepared, q, ws.trig, ws.frames);
  gravity_forces(prepared, ws.frames, masses, ws.forces);
  return ws.forces;
}

}  // namespace

TEST_CASE("joint map: gravity forces are minus the derivative of gravity's potential energy") {
  RandomSource random(0x6A09E667F3BCC908ull);
  double worst_double = 0.0, worst_float = 0.0;
  for (int trial = 0; trial < 40; ++trial) {
    const int n = 1 + trial % kMaxJoints;
    const ChainModel<double> chain = random_chain(random, n);
    const MassModel<double> masses = random_masses(random);
    JointVector<double> q = JointVector<double>::Zero();
    for (int i = 0; i < n; ++i) q(i) = random.uniform(-2.5, 2.5);
    const JointVector<double> forces = forces_at(chain, masses, q);
    double scale = 1.0;
    for (int i = 0; i < n; ++i) scale = std::fmax(scale, std::fabs(forces(i)));
    for (int i = 0; i < n; ++i) {
      const double h = 1e-5;
      Eigen::VectorXd plus = q.head(n), minus = q.head(n);
      plus(i) += h;
      minus(i) -= h;
      const double numeric =
          -(potential_energy(chain, masses, plus) - potential_energy(chain, masses, minus)) / (2 * h);
      worst_double = std::fmax(worst_double, std::fabs(forces(i) - numeric) / scale);
    }
    // Float against double, the same inputs rounded to float.
    const ChainModel<float> chain_f = kincal::test::to_float(chain);
    PreparedChain<float> prepared;
    prepare_chain(chain_f, prepared);
    DeflectionWorkspace<float> ws;
    const JointVector<float> qf = q.cast<float>();
    joint_trig(prepared, qf, ws.trig);
    forward_kinematics(prepared, qf, ws.trig, ws.frames);
    gravity_forces(prepared, ws.frames, to_float(masses), ws.forces);
    for (int i = 0; i < n; ++i)
      worst_float = std::fmax(worst_float, std::fabs(static_cast<double>(ws.forces(i)) - forces(i)) / scale);
    for (int i = n; i < kMaxJoints; ++i) CHECK(ws.forces(i) == 0.0f);
  }
  MESSAGE("worst relative error: double " << worst_double << ", float " << worst_float);
  CHECK(worst_double < 1e-7);
  CHECK(worst_float < 2e-5);
}

TEST_CASE("joint map: coupling and scale, their inverse; a singular coupling is refused") {
  JointMap<float> map;
  map.joint_count = 6;
  map.coupling(2, 1) = 1.0f;   // Fanuc's elbow: v3 = u2 + u3
  map.coupling(5, 4) = -0.5f;  // a wrist differential
  map.scale << 1.0004f, 0.9997f, 1.0005f, 1.0f, 1.0f, 0.9998f, 1.0f, 1.0f;
  CouplingMatrix<float> scratch, inverse;
  REQUIRE(invert_coupling(map, scratch, inverse));
  JointVector<float> readings = JointVector<float>::Zero(), coupled, back;
  readings.head(6) << 0.3f, -1.2f, 0.7f, 2.0f, -0.4f, 1.1f;
  coupled_values(map, readings, coupled);
  CHECK(coupled(2) == doctest::Approx((-1.2 * 0.9997 + 0.7 * 1.0005)).epsilon(1e-6));
  CHECK(coupled(5) == doctest::Approx((1.1 * 0.9998 + 0.2)).epsilon(1e-6));
  CHECK(coupled(6) == 0.0f);
  readings_from_coupled(map, inverse, coupled, back);
  for (int i = 0; i < 6; ++i) CHECK(back(i) == doctest::Approx(readings(i)).epsilon(1e-6));
  // Joints read directly keep their bits: an identity row adds only zeros.
  CHECK(coupled(0) == 1.0004f * 0.3f);

  map.coupling(2, 2) = 0.0f;
  map.coupling(2, 1) = 1.0f;
  map.coupling.row(2) = map.coupling.row(1);  // joint 3 = joint 2
  CHECK_FALSE(invert_coupling(map, scratch, inverse));
  map.coupling(2, 2) = std::nanf("");
  CHECK_FALSE(invert_coupling(map, scratch, inverse));
}

TEST_CASE("joint map: undeflect inverts deflect to about (c dG/dq)^passes of the deflection") {
  const ChainModel<double> arm = puma_like_arm();
  PreparedChain<double> chain;
  prepare_chain(arm, chain);
  const MassModel<double> masses = puma_like_masses<double>();
  JointVector<double> compliance = JointVector<double>::Zero();
  compliance(1) = 3e-5;
  compliance(2) = 4e-5;
  RandomSource random(0xBB67AE8584CAA73Bull);
  DeflectionWorkspace<double> ws;
  double worst_deflection = 0.0, worst_error = 0.0;
  for (int trial = 0; trial < 30; ++trial) {
    JointVector<double> w = JointVector<double>::Zero(), v, back;
    for (int i = 0; i < 6; ++i) w(i) = random.uniform(-2.5, 2.5);
    deflect(chain, masses, compliance, w, ws, v);
    worst_deflection = std::fmax(worst_deflection, (v - w).cwiseAbs().maxCoeff());
    back = v;
    undeflect(chain, masses, compliance, v, kUndeflectPasses, ws, back);
    worst_error = std::fmax(worst_error, (back - w).cwiseAbs().maxCoeff());
    // Float: the same passes.
    PreparedChain<float> chain_f;
    prepare_chain(kincal::test::to_float(arm), chain_f);
    DeflectionWorkspace<float> ws_f;
    JointVector<float> back_f = v.cast<float>();
    undeflect(chain_f, to_float(masses), JointVector<float>(compliance.cast<float>()),
              JointVector<float>(v.cast<float>()), kUndeflectPasses, ws_f, back_f);
    CHECK((back_f.cast<double>() - w).cwiseAbs().maxCoeff() < 1e-6);
  }
  MESSAGE("deflection up to " << worst_deflection * 1e3 << " mrad, undeflect error " << worst_error * 1e9 << " nrad");
  CHECK(worst_deflection > 1e-3);
  CHECK(worst_error < 1e-5 * worst_deflection);  // (c dG/dq)^2 with c dG/dq up to ~2e-3 here
}
