// How much of the pose error the online correction (firmware/core/correction.hpp) leaves on a
// simulated robot, and how that residual scales with the size of the parameter errors.
//
// The robot: a PUMA-560-like 6R arm (tests/firmware/core/chain_fixtures.hpp). Its true geometry
// is the nominal one with every one of its 42 parameters (five per link in Doty's model, six base
// and six tool motions) off by exactly +-0.5 degree or +-1 mm times a scale, random signs, 20
// such robots. The controller asks for 50 random targets per robot whose Jacobian's smallest
// singular value (rotation rows weighted by 0.5 m) is at least 0.1 m: away from the elbow, wrist
// and shoulder singularities (the share of random configurations that qualify is printed as
// correction_targets_kept; the figures with _near_singular use 0.05 m). The correction runs in float with the true
// errors loaded (perfect identification); the truth is evaluated in double. Before: the true tool pose at the nominal
// joint target against the target pose; after: at the corrected joint target.
//
// Figures (fractions are RMS after / RMS before, the worse of position and orientation):
//   correction_residual_fraction                     the default (first step + one chord step)
//   correction_residual_fraction_first_order_step    the first-order step alone
//   correction_residual_*_mm / *_mrad at scales 0.25..2, and the slope of log(residual) against
//   log(scale): 2 for the first-order step (second-order remainder), 3 with the refinement.
//   correction_joint_map_residual_fraction  the same robots at scale 1 read through a joint map
//                                            (core::correct_joint_readings): the controller
//                                            reports the elbow relative to the shoulder (chain
//                                            joint 3 = reading 2 + reading 3), every gear is off
//                                            by +-500 ppm, shoulder and elbow sag under gravity
//                                            (PUMA masses, 3 kg payload; 2e-5 and 3e-5 rad/(N m));
//                                            the truth through the same map in double.
#include <cmath>
#include <cstdio>
#include <vector>

#include "firmware/core/correction.hpp"
#include "firmware/core/joint_map.hpp"
#include "tests/firmware/core/chain_fixtures.hpp"

using namespace kincal::core;
using namespace kincal::test;

namespace {

constexpr double kDegree = 0.017453292519943295;
constexpr int kRobots = 20;
constexpr int kTargetsPerRobot = 50;

struct Rms {
  double before_m2 = 0, after_m2 = 0, before_rad2 = 0, after_rad2 = 0;
  int count = 0, refused = 0, candidates = 0;
  void add(const Twist<double>& before, const Twist<double>& after) {
    before_m2 += before.head<3>().squaredNorm();
    before_rad2 += before.tail<3>().squaredNorm();
    after_m2 += after.head<3>().squaredNorm();
    after_rad2 += after.tail<3>().squaredNorm();
    ++count;
  }
  double fraction() const { return std::fmax(std::sqrt(after_m2 / before_m2), std::sqrt(after_rad2 / before_rad2)); }
  double after_mm() const { return 1e3 * std::sqrt(after_m2 / count); }
  double after_mrad() const { return 1e3 * std::sqrt(after_rad2 / count); }
  double before_mm() const { return 1e3 * std::sqrt(before_m2 / count); }
  double before_mrad() const { return 1e3 * std::sqrt(before_rad2 / count); }
};

Rms measure(double scale, int refinement_steps, double min_conditioning_m) {
  const ChainModel<float> nominal = to_float(puma_like_arm());
  const ChainModel<double> nominal_d = reference_chain(nominal);
  const ParameterSet set = full_parameter_set(nominal_d, true, true);
  RandomSource random(0xBE4C);  // the same robots and targets at every scale
  Rms rms;
  CorrectionOptions options;
  options.refinement_steps = refinement_steps;
  options.max_joint_step = 0.5f;
  for (int robot = 0; robot < kRobots; ++robot) {
    const ErrorVector<double> errors = random_sign_errors(random, set, 0.5 * kDegree * scale, 0.001 * scale);
    ChainModel<double> truth;
    if (apply_parameter_errors(nominal_d, set, errors, truth) != ErrorModelStatus::ok) return rms;
    CorrectionModel model;
    if (prepare_correction(nominal, set, errors.cast<float>(), options, model) != CorrectionStatus::ok) return rms;
    for (int t = 0; t < kTargetsPerRobot;) {
      JointVector<double> q = JointVector<double>::Zero();
      for (int i = 0; i < 6; ++i) q(i) = random.uniform(-2.8, 2.8);
      ++rms.candidates;
      if (conditioning_m(nominal_d, q, static_cast<double>(options.rotation_weight_m)) < min_conditioning_m) continue;
      ++t;
      CorrectionWorkspace workspace;
      Correction correction;
      if (correct_joint_target(model, workspace, q.cast<float>(), correction) != CorrectionStatus::ok) {
        ++rms.refused;
        continue;
      }
      const RigidTransform<double> target = forward_kinematics(nominal_d, q);
      const Twist<double> before = small_pose_difference(target, forward_kinematics(truth, q));
      const JointVector<double> q_corrected = correction.corrected_joint_target.cast<double>();
      const Twist<double> after = small_pose_difference(target, forward_kinematics(truth, q_corrected));
      rms.add(before, after);
    }
  }
  return rms;
}

// The joint-map case of the top comment: robots and targets drawn as in measure(1, default), each
// robot's gear signs drawn after its errors.
Rms measure_joint_map() {
  const ChainModel<float> nominal = to_float(puma_like_arm());
  const ChainModel<double> nominal_d = reference_chain(nominal);
  const ParameterSet set = full_parameter_set(nominal_d, true, true);
  RandomSource random(0xBE4C);
  Rms rms;
  CorrectionOptions options;
  options.max_joint_step = 0.5f;
  const MassModel<double> masses = puma_like_masses<double>();
  const MassModel<float> masses_f = puma_like_masses<float>();
  for (int robot = 0; robot < kRobots; ++robot) {
    const ErrorVector<double> errors = random_sign_errors(random, set, 0.5 * kDegree, 0.001);
    ChainModel<double> truth;
    if (apply_parameter_errors(nominal_d, set, errors, truth) != ErrorModelStatus::ok) return rms;
    JointMap<double> nominal_map;
    nominal_map.joint_count = 6;
    nominal_map.coupling(2, 1) = 1.0;
    JointMap<double> true_map = nominal_map;
    for (int i = 0; i < 6; ++i) true_map.scale(i) = 1.0 + 5e-4 * random.sign();
    true_map.compliance(1) = 2e-5;
    true_map.compliance(2) = 3e-5;
    static CorrectionModel model;
    static CorrectionWorkspace workspace;
    static JointMapModel map_model;
    JointMap<float> nominal_map_f, true_map_f;
    nominal_map_f.joint_count = true_map_f.joint_count = 6;
    nominal_map_f.coupling = nominal_map.coupling.cast<float>();
    true_map_f.coupling = true_map.coupling.cast<float>();
    true_map_f.scale = true_map.scale.cast<float>();
    true_map_f.compliance = true_map.compliance.cast<float>();
    if (prepare_correction(nominal, set, errors.cast<float>(), options, model) != CorrectionStatus::ok ||
        prepare_joint_map(model, nominal_map_f, true_map_f, masses_f, workspace, map_model) != CorrectionStatus::ok)
      return rms;
    PreparedChain<double> nominal_chain, true_chain;
    prepare_chain(nominal_d, nominal_chain);
    prepare_chain(truth, true_chain);
    // Readings -> the chain's variables through a map -> the tool, in double.
    const auto pose = [&masses](const PreparedChain<double>& chain, const JointMap<double>& map,
                                const JointVector<double>& readings) {
      DeflectionWorkspace<double> ws;
      JointVector<double> coupled, deflected;
      coupled_values(map, readings, coupled);
      deflect(chain, masses, map.compliance, coupled, ws, deflected);
      joint_trig(chain, deflected, ws.trig);
      RigidTransform<double> base_T_tool;
      tool_pose(chain, deflected, ws.trig, base_T_tool);
      return base_T_tool;
    };
    for (int t = 0; t < kTargetsPerRobot;) {
      JointVector<double> q = JointVector<double>::Zero();
      for (int i = 0; i < 6; ++i) q(i) = random.uniform(-2.8, 2.8);
      if (conditioning_m(nominal_d, q, static_cast<double>(options.rotation_weight_m)) < 0.1) continue;
      ++t;
      JointVector<double> readings = q;
      readings(2) = q(2) - q(1);
      Correction correction;
      JointVector<float> corrected;
      if (correct_joint_readings(model, map_model, workspace, readings.cast<float>(), correction, corrected) !=
          CorrectionStatus::ok) {
        ++rms.refused;
        continue;
      }
      const RigidTransform<double> target = pose(nominal_chain, nominal_map, readings);
      const Twist<double> before = small_pose_difference(target, pose(true_chain, true_map, readings));
      const Twist<double> after = small_pose_difference(target, pose(true_chain, true_map, corrected.cast<double>()));
      rms.add(before, after);
    }
  }
  return rms;
}

// Least-squares slope of log(y) against log(x).
double slope(const std::vector<double>& x, const std::vector<double>& y) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = static_cast<double>(x.size());
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double lx = std::log(x[i]), ly = std::log(y[i]);
    sx += lx;
    sy += ly;
    sxx += lx * lx;
    sxy += lx * ly;
  }
  return (n * sxy - sx * sy) / (n * sxx - sx * sx);
}

}  // namespace

int main() {
  const std::vector<double> scales = {0.25, 0.5, 1.0, 2.0};
  for (const int refinement : {0, 1}) {
    const char* name = refinement == 0 ? "_first_order_step" : "";
    std::vector<double> residuals;
    for (const double scale : scales) {
      const Rms rms = measure(scale, refinement, 0.1);
      if (rms.count == 0) return 1;
      // Position and orientation in one number: metres plus 0.5 m per radian (the correction's L).
      residuals.push_back(std::sqrt(rms.after_m2 + 0.25 * rms.after_rad2));
      char label[32];
      std::snprintf(label, sizeof label, "%gx", scale);
      if (refinement == 0) {
        std::printf("FIGURE correction_error_before_%s_mm %.3f mm\n", label, rms.before_mm());
        std::printf("FIGURE correction_error_before_%s_mrad %.3f mrad\n", label, rms.before_mrad());
      }
      std::printf("FIGURE correction_residual%s_%s_mm %.5f mm\n", name, label, rms.after_mm());
      std::printf("FIGURE correction_residual%s_%s_mrad %.5f mrad\n", name, label, rms.after_mrad());
      std::printf("FIGURE correction_residual_fraction%s_%s %.5f ratio\n", name, label, rms.fraction());
      if (scale == 1.0) {
        std::printf("FIGURE correction_residual_fraction%s %.5f ratio\n", name, rms.fraction());
        const Rms near = measure(scale, refinement, 0.05);
        std::printf("FIGURE correction_residual_fraction%s_near_singular %.5f ratio\n", name, near.fraction());
        if (refinement == 0) {
          std::printf("FIGURE correction_targets_kept %.3f ratio\n",
                      static_cast<double>(kRobots * kTargetsPerRobot) / rms.candidates);
        }
      }
      if (rms.refused > 0) std::printf("FIGURE correction_refused%s_%s %d targets\n", name, label, rms.refused);
    }
    std::printf("FIGURE correction_residual_scaling_exponent%s %.3f power\n", name, slope(scales, residuals));
  }
  const Rms mapped = measure_joint_map();
  if (mapped.count == 0) return 1;
  std::printf("FIGURE correction_joint_map_error_before_mm %.3f mm\n", mapped.before_mm());
  std::printf("FIGURE correction_joint_map_residual_mm %.5f mm\n", mapped.after_mm());
  std::printf("FIGURE correction_joint_map_residual_mrad %.5f mrad\n", mapped.after_mrad());
  std::printf("FIGURE correction_joint_map_residual_fraction %.5f ratio\n", mapped.fraction());
  if (mapped.refused > 0) std::printf("FIGURE correction_joint_map_refused %d targets\n", mapped.refused);
  return 0;
}
