// correction.hpp: the float step against an independent double damped least-squares step
// (numeric Jacobian, Eigen's LDLT), the corrected poses against double forward kinematics, the
// residual left on the simulated true robot scaling with the square of the error size, and the
// refusals.
#include "firmware/core/correction.hpp"

#include <doctest.h>

#include <Eigen/Dense>
#include <cmath>
#include <vector>

#include "tests/firmware/core/chain_fixtures.hpp"

using namespace kincal::core;
using namespace kincal::test;

namespace {

JointVector<double> random_configuration(RandomSource& random, int n) {
  JointVector<double> q = JointVector<double>::Zero();
  for (int i = 0; i < n; ++i) q(i) = random.uniform(-2.5, 2.5);
  return q;
}

// The reference step in double: numeric Jacobian of the calibrated chain, the same damped
// least-squares problem solved by Eigen; also the condition number of its normal matrix, which
// scales the float step's rounding error.
struct ReferenceStep {
  JointVector<double> dq;
  double condition;
};

ReferenceStep reference_step(const ChainModel<double>& nominal, const ChainModel<double>& calibrated,
                             const JointVector<double>& q, const CorrectionOptions& options) {
  const int n = nominal.joint_count;
  const RigidTransform<double> current = forward_kinematics(calibrated, q);
  const Twist<double> e = small_pose_difference(forward_kinematics(nominal, q), current);
  Eigen::MatrixXd j(6, n);
  for (int i = 0; i < n; ++i) {
    JointVector<double> plus = q, minus = q;
    plus(i) += 1e-6;
    minus(i) -= 1e-6;
    j.col(i) =
        small_pose_difference(forward_kinematics(calibrated, plus), forward_kinematics(calibrated, minus)) / 2e-6;
  }
  const double l = static_cast<double>(options.rotation_weight_m), lambda = static_cast<double>(options.damping_m);
  Eigen::VectorXd w(6);
  w << 1, 1, 1, l * l, l * l, l * l;
  const Eigen::MatrixXd a = j.transpose() * w.asDiagonal() * j + lambda * lambda * Eigen::MatrixXd::Identity(n, n);
  const Eigen::VectorXd dq = a.ldlt().solve(j.transpose() * w.asDiagonal() * e);
  const Eigen::VectorXd eigenvalues = Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(a).eigenvalues();
  // Beyond six joints the code solves the 6 x 6 system, whose condition excludes the null space.
  const double smallest = n > 6 ? eigenvalues(n - 6) : eigenvalues(0);
  ReferenceStep out{JointVector<double>::Zero(), eigenvalues(n - 1) / smallest};
  out.dq.head(n) = dq;
  return out;
}

struct Residual {
  double before_m, after_m, before_rad, after_rad;
};

// Pose error of the true robot (the calibrated chain, in double) at the nominal and at the
// corrected targets, against the nominal target pose.
Residual residual(const ChainModel<double>& nominal, const ChainModel<double>& truth, const JointVector<double>& q,
                  const JointVector<double>& q_corrected) {
  const RigidTransform<double> target = forward_kinematics(nominal, q);
  const Twist<double> before = small_pose_difference(target, forward_kinematics(truth, q));
  const Twist<double> after = small_pose_difference(target, forward_kinematics(truth, q_corrected));
  return {before.head<3>().norm(), after.head<3>().norm(), before.tail<3>().norm(), after.tail<3>().norm()};
}

}  // namespace

TEST_CASE("the float correction step matches a double damped least-squares step") {
  RandomSource random(0xC022);
  double worst_step = 0.0, worst_pose = 0.0;
  int checked = 0;
  for (int trial = 0; trial < 300; ++trial) {
    // Random chains of 3..8 joints and the PUMA-like arm.
    const int n = 3 + trial % 6;
    const ChainModel<double> nominal_d = trial % 7 == 0 ? puma_like_arm() : random_chain(random, n);
    const ChainModel<float> nominal = to_float(nominal_d);
    const ChainModel<double> nominal_ref = reference_chain(nominal);
    const ParameterSet set = full_parameter_set(nominal_ref, true, true);
    const ErrorVector<double> errors_d = random_sign_errors(random, set, 0.0087, 0.001);
    const ErrorVector<float> errors = errors_d.cast<float>();
    CorrectionOptions options;
    options.max_joint_step = 0.3f;
    options.refinement_steps = 0;  // the single damped step the reference computes
    CorrectionModel model;
    REQUIRE(prepare_correction(nominal, set, errors, options, model) == CorrectionStatus::ok);
    ChainModel<double> calibrated_ref;
    REQUIRE(apply_parameter_errors(nominal_ref, set, errors.cast<double>().eval(), calibrated_ref) ==
            ErrorModelStatus::ok);

    const JointVector<float> q = random_configuration(random, nominal.joint_count).cast<float>();
    CorrectionWorkspace workspace;
    Correction correction;
    const CorrectionStatus status = correct_joint_target(model, workspace, q, correction);
    const JointVector<double> qd = q.cast<double>();
    const ReferenceStep reference = reference_step(nominal_ref, calibrated_ref, qd, options);
    const JointVector<double>& dq_ref = reference.dq;
    const double largest = dq_ref.cwiseAbs().maxCoeff();
    // Near singular configurations the step is large and refused; elsewhere it must agree.
    if (largest > 0.31) {
      CHECK(status == CorrectionStatus::step_too_large);
      CHECK(correction.corrected_joint_target == q);
      continue;
    }
    if (largest > 0.29) continue;  // too close to the limit to call
    REQUIRE(status == CorrectionStatus::ok);
    const JointVector<double> dq = (correction.corrected_joint_target - q).cast<double>();
    // Two error sources: the pose error is a difference of two float poses (1e-7 m rounding on
    // errors of about 1e-2 m: 1e-5 relative), and float rounding in the normal equations grows
    // with their condition number.
    worst_step =
        std::fmax(worst_step, (dq - dq_ref).cwiseAbs().maxCoeff() / ((1e-3 + largest) * (20.0 + reference.condition)));
    const Eigen::Affine3d corrected = to_affine(correction.base_T_corrected);
    const Eigen::Affine3d expected = to_affine(forward_kinematics(calibrated_ref, qd));
    worst_pose = std::fmax(worst_pose, (corrected.matrix() - expected.matrix()).cwiseAbs().maxCoeff());
    ++checked;
  }
  CHECK(checked > 150);
  CHECK(worst_step <= 2e-6);
  CHECK(worst_pose <= 2e-6);
  MESSAGE("correction step vs double: worst relative / (20 + condition) ", worst_step, ", corrected pose ", worst_pose,
          " over ", checked, " targets");
}

TEST_CASE("one step leaves a second-order residual, a chord refinement a third-order one") {
  const ChainModel<double> nominal_d = puma_like_arm();
  const ChainModel<float> nominal = to_float(nominal_d);
  const ChainModel<double> nominal_ref = reference_chain(nominal);
  const ParameterSet set = full_parameter_set(nominal_ref, true, true);
  RandomSource random(0x5C41);
  const ErrorVector<double> direction = random_sign_errors(random, set, 1.0, 1.0 / 8.7266);  // 0.5 deg : 1 mm
  // Targets at least 5 cm (weighted) from a singularity, the same for every error size.
  std::vector<JointVector<float>> targets;
  RandomSource configurations(77);
  while (targets.size() < 30) {
    const JointVector<double> q = random_configuration(configurations, 6);
    if (conditioning_m(nominal_ref, q, 0.5) > 0.05) targets.push_back(q.cast<float>());
  }
  for (const int refinement : {0, 1}) {
    double previous = 0.0;
    for (const double size : {0.0174533, 0.00872665, 0.00436332}) {  // 1, 0.5, 0.25 degree (2, 1, 0.5 mm)
      const ErrorVector<double> errors_d = direction * size;
      CorrectionOptions options;
      options.refinement_steps = refinement;
      options.max_joint_step = 0.5f;
      CorrectionModel model;
      REQUIRE(prepare_correction(nominal, set, errors_d.cast<float>(), options, model) == CorrectionStatus::ok);
      ChainModel<double> truth;
      REQUIRE(apply_parameter_errors(nominal_ref, set, errors_d, truth) == ErrorModelStatus::ok);
      double before2 = 0.0, after2 = 0.0;
      for (const JointVector<float>& q : targets) {
        CorrectionWorkspace workspace;
        Correction correction;
        REQUIRE(correct_joint_target(model, workspace, q, correction) == CorrectionStatus::ok);
        const Residual r =
            residual(nominal_ref, truth, q.cast<double>(), correction.corrected_joint_target.cast<double>());
        before2 += r.before_m * r.before_m + 0.25 * r.before_rad * r.before_rad;
        after2 += r.after_m * r.after_m + 0.25 * r.after_rad * r.after_rad;
      }
      const double fraction = std::sqrt(after2 / before2);
      // Bounds with a margin over what this arm gives (0.052 and 0.0051 at 0.5 degree / 1 mm).
      CHECK(fraction < (refinement == 0 ? 7.0 * size : 100.0 * size * size));
      // Halving the errors divides the residual by 4 (second order) or 8 (third order).
      if (previous > 0.0) {
        const double ratio = std::sqrt(after2) / previous;
        if (refinement == 0) CHECK(ratio == doctest::Approx(0.25).epsilon(0.1));
        if (refinement == 1) CHECK(ratio == doctest::Approx(0.125).epsilon(0.2));
      }
      previous = std::sqrt(after2);
      MESSAGE("refinement ", refinement, ", error size ", size, " rad: residual fraction ", fraction);
    }
  }
}

TEST_CASE("correction refusals") {
  const ChainModel<float> nominal = to_float(puma_like_arm());
  const ParameterSet set = full_parameter_set(nominal, false, false);
  ErrorVector<float> errors = ErrorVector<float>::Zero();
  CorrectionModel model;
  REQUIRE(prepare_correction(nominal, set, errors, CorrectionOptions{}, model) == CorrectionStatus::ok);
  CorrectionWorkspace workspace;
  Correction correction;
  JointVector<float> q = JointVector<float>::Constant(0.3f);
  REQUIRE(correct_joint_target(model, workspace, q, correction) == CorrectionStatus::ok);
  // No errors: nothing to correct (to rounding: the two chains may be contracted into fused
  // multiply-adds differently on the M4).
  CHECK((correction.corrected_joint_target - q).cwiseAbs().maxCoeff() <= 1e-5f);
  q(2) = NAN;
  CHECK(correct_joint_target(model, workspace, q, correction) == CorrectionStatus::non_finite_input);

  errors(1) = 0.3f;  // 17 degrees off on joint 1's theta: far beyond a 0.05 rad step
  REQUIRE(prepare_correction(nominal, set, errors, CorrectionOptions{}, model) == CorrectionStatus::ok);
  q = JointVector<float>::Constant(0.3f);
  CHECK(correct_joint_target(model, workspace, q, correction) == CorrectionStatus::step_too_large);
  CHECK(correction.corrected_joint_target == q);

  ChainModel<float> empty;
  CHECK(prepare_correction(empty, set, errors, CorrectionOptions{}, model) == CorrectionStatus::bad_model);
  CorrectionOptions bad;
  bad.rotation_weight_m = 0.0f;
  CHECK(prepare_correction(nominal, set, errors, bad, model) == CorrectionStatus::bad_model);
  ParameterSet wrong = set;
  wrong.ids[0].link = 7;
  CHECK(prepare_correction(nominal, wrong, errors, CorrectionOptions{}, model) == CorrectionStatus::bad_model);
}
