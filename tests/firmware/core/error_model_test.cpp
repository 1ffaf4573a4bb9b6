// error_model.hpp: the parameter and joint Jacobians against central differences of the double
// forward kinematics (every convention, base and tool motions), float against double, and
// Doty's closed form 3-11a..e for the ARID reproduced from the general model to float precision.
#include "firmware/core/error_model.hpp"

#include <doctest.h>

#include <cmath>

#include "tests/firmware/core/chain_fixtures.hpp"

using namespace kincal::core;
using namespace kincal::test;

namespace {

template <class S>
struct Evaluated {
  PreparedChain<S> prepared;
  std::array<SinCos<S>, kMaxJoints> trig;
  ChainFrames<S> frames;
};

template <class S>
void evaluate(const ChainModel<S>& chain, const JointVector<S>& q, Evaluated<S>& e) {
  prepare_chain(chain, e.prepared);
  joint_trig(e.prepared, q, e.trig);
  forward_kinematics(e.prepared, q, e.trig, e.frames);
}

// Central difference of the tool pose for parameter i of the set, in double.
Twist<double> numeric_column(const ChainModel<double>& chain, const ParameterSet& set, int i,
                             const JointVector<double>& q, double h) {
  ErrorVector<double> plus = ErrorVector<double>::Zero(), minus = ErrorVector<double>::Zero();
  plus(i) = h;
  minus(i) = -h;
  ChainModel<double> a, b;
  REQUIRE(apply_parameter_errors(chain, set, plus, a) == ErrorModelStatus::ok);
  REQUIRE(apply_parameter_errors(chain, set, minus, b) == ErrorModelStatus::ok);
  return small_pose_difference(forward_kinematics(a, q), forward_kinematics(b, q)) / (2 * h);
}

// Doty's 3-11a..e written out in double straight from the report (psi = beta1..4, alpha1..4).
Eigen::Matrix<double, 5, 8> doty_reference(const std::array<double, 4>& t, const std::array<double, 3>& a) {
  const auto c = [](double x) { return std::cos(x); };
  const auto s = [](double x) { return std::sin(x); };
  const double t1 = t[0], t12 = t[0] + t[1], t123 = t12 + t[2], t1234 = t123 + t[3];
  const double t2 = t[1], t23 = t[1] + t[2], t234 = t23 + t[3], t3 = t[2], t34 = t[2] + t[3], t4 = t[3];
  Eigen::Matrix<double, 5, 8> e;
  // eps1 = b4 c1234 + a4 s1234 + b3 c123 + a3 s123 + b2 c12 + a2 s12 + b1 c1 + a1 s1
  e.row(0) << c(t1), c(t12), c(t123), c(t1234), s(t1), s(t12), s(t123), s(t1234);
  // eps2 = b4 s1234 - a4 c1234 + b3 s123 - a3 c123 + b2 s12 - a2 c12 + b1 s1 - a1 c1
  e.row(1) << s(t1), s(t12), s(t123), s(t1234), -c(t1), -c(t12), -c(t123), -c(t1234);
  // eps3 = -b1 c234 + a1 s234 - b2 c34 + a2 s34 - b3 c4 + a3 s4 - b4
  e.row(2) << -c(t234), -c(t34), -c(t4), -1, s(t234), s(t34), s(t4), 0;
  // eps4 = b1 s234 + a1 c234 + b2 s34 + a2 c34 + b3 s4 + a3 c4 + a4
  e.row(3) << s(t234), s(t34), s(t4), 0, c(t234), c(t34), c(t4), 1;
  // eps5 - d1 = a3(-b1 c23 + a1 s23 - b2 c3 + a2 s3 - b3) + a2(-b1 c2 + a1 s2 - b2) - b1 a1
  e.row(4) << -a[2] * c(t23) - a[1] * c(t2) - a[0], -a[2] * c(t3) - a[1], -a[2], 0, a[2] * s(t23) + a[1] * s(t2),
      a[2] * s(t3), 0, 0;
  return e;
}

// The ARID of Doty's Table 3.1 in his convention: joint 1 prismatic along z (theta1 constant),
// joints 2..4 revolute, all axes parallel (alpha = beta = 0), a4 = 0.
template <class S>
ChainModel<S> arid(const std::array<S, 4>& theta, const std::array<S, 3>& a) {
  ChainModel<S> m;
  m.joint_count = 4;
  for (std::size_t i = 0; i < 4; ++i) {
    m.links[i].convention = LinkConvention::doty;
    m.links[i].joint = i == 0 ? JointType::prismatic : JointType::revolute;
    m.links[i].parameters.a_m = i < 3 ? a[i] : S(0);
  }
  m.links[0].parameters.theta_rad = theta[0];
  return m;
}

ParameterSet doty_psi() {
  ParameterSet set;
  set.count = 8;
  for (int i = 0; i < 4; ++i) {
    set.ids[static_cast<std::size_t>(i)] = {ParameterKind::link_beta, static_cast<std::uint8_t>(i)};
    set.ids[static_cast<std::size_t>(4 + i)] = {ParameterKind::link_alpha, static_cast<std::uint8_t>(i)};
  }
  return set;
}

// Doty's epsilon rows from a general pose-error column [dp; dphi] (see error_model.hpp).
template <class S>
Eigen::Matrix<S, 5, 1> to_doty(const Twist<S>& twist, S theta_sum) {
  const SinCos<S> t = sin_cos(theta_sum);
  const S dx = twist(3), dy = twist(4);
  Eigen::Matrix<S, 5, 1> eps;
  eps << dy, -dx, t.sin * dx - t.cos * dy, t.cos * dx + t.sin * dy, twist(2);
  return eps;
}

}  // namespace

TEST_CASE("the parameter Jacobian is the derivative of forward kinematics, for every convention") {
  RandomSource random(0xE770);
  double worst_numeric = 0.0, worst_float = 0.0, worst_joint = 0.0, worst_joint_float = 0.0;
  for (int trial = 0; trial < 120; ++trial) {
    const int n = 1 + trial % kMaxJoints;
    const ChainModel<double> chain = random_chain(random, n);
    const ChainModel<float> chain_f = to_float(chain);
    const ChainModel<double> chain_d = reference_chain(chain_f);
    const Eigen::VectorXd qx = random_joints(random, chain);
    const JointVector<float> q_f = to_joint_vector<float>(qx);
    const JointVector<double> q = q_f.cast<double>();
    const ParameterSet set = full_parameter_set(chain_d, true, true);
    REQUIRE(set.count == 12 + [&] {
      int count = 0;
      for (int i = 0; i < n; ++i)
        count += chain.links[static_cast<std::size_t>(i)].convention == LinkConvention::doty ? 5 : 4;
      return count;
    }());

    // Against central differences: the double chain itself (orthonormal rotations).
    const JointVector<double> q_exact = to_joint_vector<double>(qx);
    Evaluated<double> exact;
    evaluate(chain, q_exact, exact);
    ErrorMatrix<double> e_exact = ErrorMatrix<double>::Zero();
    REQUIRE(parameter_jacobian(exact.prepared, q_exact, exact.trig, exact.frames, set, e_exact) ==
            ErrorModelStatus::ok);
    // Against float: the float chain's values in double.
    Evaluated<double> ed;
    evaluate(chain_d, q, ed);
    ErrorMatrix<double> e = ErrorMatrix<double>::Zero();
    REQUIRE(parameter_jacobian(ed.prepared, q, ed.trig, ed.frames, set, e) == ErrorModelStatus::ok);
    Evaluated<float> ef;
    evaluate(chain_f, q_f, ef);
    ErrorMatrix<float> e_f = ErrorMatrix<float>::Zero();
    REQUIRE(parameter_jacobian(ef.prepared, q_f, ef.trig, ef.frames, set, e_f) == ErrorModelStatus::ok);
    const double length = chain_length(chain, qx) + 1.0;
    for (int i = 0; i < set.count; ++i) {
      const Twist<double> numeric = numeric_column(chain, set, i, q_exact, 1e-6);
      worst_numeric = std::fmax(worst_numeric, (numeric - e_exact.col(i)).cwiseAbs().maxCoeff() / length);
    }
    worst_float = std::fmax(worst_float, (e_f.cast<double>() - e).leftCols(set.count).cwiseAbs().maxCoeff() / length);

    JointJacobian<double> j_exact, j;
    joint_jacobian(exact.prepared, exact.frames, j_exact);
    joint_jacobian(ed.prepared, ed.frames, j);
    JointJacobian<float> j_f;
    joint_jacobian(ef.prepared, ef.frames, j_f);
    for (int i = 0; i < n; ++i) {
      JointVector<double> plus = q_exact, minus = q_exact;
      plus(i) += 1e-6;
      minus(i) -= 1e-6;
      const Twist<double> numeric =
          small_pose_difference(forward_kinematics(chain, plus), forward_kinematics(chain, minus)) / 2e-6;
      worst_joint = std::fmax(worst_joint, (numeric - j_exact.col(i)).cwiseAbs().maxCoeff() / length);
    }
    CHECK(j.rightCols(kMaxJoints - n).isZero());
    worst_joint_float = std::fmax(worst_joint_float, (j_f.cast<double>() - j).cwiseAbs().maxCoeff() / length);
  }
  CHECK(worst_numeric <= 1e-8);
  CHECK(worst_joint <= 1e-8);
  CHECK(worst_float <= static_cast<double>(kErrorMatrixAbsError));
  CHECK(worst_joint_float <= static_cast<double>(kErrorMatrixAbsError));
  MESSAGE("error matrix vs central differences ", worst_numeric, " per m, float vs double ", worst_float,
          "; joint Jacobian ", worst_joint, ", float ", worst_joint_float);
}

TEST_CASE("Doty's closed form 3-11a..e for the ARID, reproduced from the general model") {
  RandomSource random(0xA41D);
  double worst_general = 0.0, worst_closed = 0.0;
  for (int trial = 0; trial < 500; ++trial) {
    const std::array<float, 4> theta = {static_cast<float>(random.uniform(-3.1, 3.1)),
                                        static_cast<float>(random.uniform(0.07, 1.95)),  // his joint limits
                                        static_cast<float>(random.uniform(1.78, 2.58)),
                                        static_cast<float>(random.uniform(-2.04, -0.28))};
    const std::array<float, 3> a = {static_cast<float>(random.uniform(0.0, 0.5)),
                                    static_cast<float>(random.uniform(0.3, 1.5)),
                                    static_cast<float>(random.uniform(0.3, 1.5))};
    const ChainModel<float> chain = arid(theta, a);
    JointVector<float> q = JointVector<float>::Zero();
    q(0) = static_cast<float>(random.uniform(0.0, 18.0));  // 718 inches of travel
    q(1) = theta[1];
    q(2) = theta[2];
    q(3) = theta[3];
    Evaluated<float> ev;
    evaluate(chain, q, ev);
    ErrorMatrix<float> general = ErrorMatrix<float>::Zero();
    REQUIRE(parameter_jacobian(ev.prepared, q, ev.trig, ev.frames, doty_psi(), general) == ErrorModelStatus::ok);
    AridErrorMatrix closed;
    doty_arid_error_matrix(theta, a, closed);
    const Eigen::Matrix<double, 5, 8> reference =
        doty_reference({static_cast<double>(theta[0]), static_cast<double>(theta[1]), static_cast<double>(theta[2]),
                        static_cast<double>(theta[3])},
                       {static_cast<double>(a[0]), static_cast<double>(a[1]), static_cast<double>(a[2])});
    const float theta_sum = theta[0] + theta[1] + theta[2] + theta[3];
    const double scale = 1.0 + static_cast<double>(a[0] + a[1] + a[2]);
    for (int k = 0; k < 8; ++k) {
      const Eigen::Matrix<double, 5, 1> eps = to_doty<float>(general.col(k), theta_sum).cast<double>();
      worst_general = std::fmax(worst_general, (eps - reference.col(k)).cwiseAbs().maxCoeff() / scale);
    }
    worst_closed = std::fmax(worst_closed, (closed.cast<double>() - reference).cwiseAbs().maxCoeff() / scale);
  }
  // Float precision: a few units of 2^-24 on entries of size up to the arm's reach.
  CHECK(worst_general <= 5e-7);
  CHECK(worst_closed <= 5e-7);
  MESSAGE("ARID: general model vs Doty 3-11 ", worst_general, ", closed form ", worst_closed, " (per m of reach)");
}

// For the ARID the remainder is even third order: with all axes parallel and alpha = beta = 0 the
// second-order terms of these five entries cancel (e.g. z = d - a sin(beta) for one link).
TEST_CASE("Doty's first-order model leaves an (at least) second-order remainder") {
  const std::array<double, 4> theta = {0.3, 1.1, 2.2, -0.9};
  const std::array<double, 3> a = {0.2, 1.0, 0.8};
  const ChainModel<double> nominal = arid(theta, a);
  JointVector<double> q = JointVector<double>::Zero();
  q << 5.0, theta[1], theta[2], theta[3], 0, 0, 0, 0;
  const RigidTransform<double> t0 = forward_kinematics(nominal, q);
  const Eigen::Matrix<double, 5, 8> e = doty_reference(theta, a);
  ErrorVector<double> psi = ErrorVector<double>::Zero();
  psi.head<8>() << 0.8, -0.3, 0.5, 0.2, -0.6, 0.9, -0.4, 0.7;
  double previous = 0.0;
  for (const double size : {4e-3, 2e-3, 1e-3}) {
    ChainModel<double> actual;
    const ErrorVector<double> errors = psi * size;
    REQUIRE(apply_parameter_errors(nominal, doty_psi(), errors, actual) == ErrorModelStatus::ok);
    const RigidTransform<double> t = forward_kinematics(actual, q);
    // Doty's epsilons read off the matrices as in 3-10.
    Eigen::Matrix<double, 5, 1> eps;
    eps << t.rotation(0, 2), t.rotation(1, 2), t.rotation(2, 0), t.rotation(2, 1),
        t.translation.z() - t0.translation.z();
    const double remainder = (eps - e * (psi.head<8>() * size)).cwiseAbs().maxCoeff();
    CHECK(remainder < 2.0 * size * size);
    if (previous > 0.0) CHECK(remainder / previous <= 0.26);
    previous = remainder;
  }
}

TEST_CASE("parameter sets that name missing links are refused") {
  RandomSource random(1);
  const ChainModel<double> chain = random_chain(random, 3);
  ParameterSet set;
  set.count = 1;
  set.ids[0] = {ParameterKind::link_theta, 3};
  ChainModel<double> actual;
  const ErrorVector<double> zero = ErrorVector<double>::Zero();
  CHECK(apply_parameter_errors(chain, set, zero, actual) == ErrorModelStatus::bad_parameter);
  Evaluated<double> ev;
  const JointVector<double> q = JointVector<double>::Zero();
  evaluate(chain, q, ev);
  ErrorMatrix<double> e;
  CHECK(parameter_jacobian(ev.prepared, q, ev.trig, ev.frames, set, e) == ErrorModelStatus::bad_parameter);
  set.count = kMaxErrorParameters + 1;
  CHECK(parameter_jacobian(ev.prepared, q, ev.trig, ev.frames, set, e) == ErrorModelStatus::bad_parameter);
}
