#include "firmware/core/correction.hpp"

#include <cmath>

namespace kincal::core {

namespace {

// The damped step in whichever form is the smaller system: up to six joints the n x n normal
// matrix J^T W J + lambda^2 I, beyond six the 6 x 6 matrix W^1/2 J J^T W^1/2 + lambda^2 I, whose
// Cholesky factor stays well defined although J^T J is then rank deficient. Both give
// dq = argmin |W^1/2 (J dq - e)|^2 + lambda^2 |dq|^2. Plain loops over the workspace's arrays:
// this is the control-rate path, and Eigen's expressions do not unroll at -Os.

using Square = Eigen::Matrix<float, kMaxJoints, kMaxJoints>;

// The kernels below work on raw column-major arrays through __restrict pointers (a GCC extension
// supported by every compiler we use): without it the compiler must assume each store into the
// workspace may change the Jacobian it reads, and reloads every operand. N is a compile-time
// constant so that the loops unroll. Element (r, c) of a is a[c * kMaxJoints + r]; of the
// Jacobian, j[c * 6 + k].
// The sums of products are fused multiply-adds (mul_add, rigid_transform.hpp): the same bits on
// both targets, and one instruction each on the M4F.
constexpr int kLd = kMaxJoints;

// In-place Cholesky of the leading size x size block (lower triangle, L L^T). False if it is not
// positive definite.
template <int N>
bool cholesky(float* __restrict a) {
#pragma GCC unroll 8
  for (int c = 0; c < N; ++c) {
    float diagonal = a[c * kLd + c];
#pragma GCC unroll 8
    for (int k = 0; k < c; ++k) diagonal = mul_add(-a[k * kLd + c], a[k * kLd + c], diagonal);
    if (!(diagonal > 0.0f)) return false;
    const float l = std::sqrt(diagonal);
    a[c * kLd + c] = l;
    const float inv_l = 1.0f / l;
#pragma GCC unroll 8
    for (int r = c + 1; r < N; ++r) {
      float sum = a[c * kLd + r];
#pragma GCC unroll 8
      for (int k = 0; k < c; ++k) sum = mul_add(-a[k * kLd + r], a[k * kLd + c], sum);
      a[c * kLd + r] = sum * inv_l;
    }
  }
  return true;
}

// x = (L L^T)^-1 x in place, for the leading N x N factor.
template <int N>
void cholesky_solve(const float* __restrict l, float* __restrict x) {
#pragma GCC unroll 8
  for (int r = 0; r < N; ++r) {
    float sum = x[r];
#pragma GCC unroll 8
    for (int k = 0; k < r; ++k) sum = mul_add(-l[k * kLd + r], x[k], sum);
    x[r] = sum / l[r * kLd + r];
  }
#pragma GCC unroll 8
  for (int r = N - 1; r >= 0; --r) {
    float sum = x[r];
#pragma GCC unroll 8
    for (int k = r + 1; k < N; ++k) sum = mul_add(-l[r * kLd + k], x[k], sum);
    x[r] = sum / l[r * kLd + r];
  }
}

// The step matrix of an N-joint chain from W^1/2 J (j), factored into a.
template <int N>
bool factor_fixed(const float* __restrict j, float lambda2, float* __restrict a) {
  constexpr int size = N <= 6 ? N : 6;
#pragma GCC unroll 8
  for (int c = 0; c < size; ++c) {
#pragma GCC unroll 8
    for (int r = c; r < size; ++r) {
      float sum = 0.0f;
      if constexpr (N <= 6) {
#pragma GCC unroll 8
        for (int k = 0; k < 6; ++k) sum = mul_add(j[r * 6 + k], j[c * 6 + k], sum);
      } else {
#pragma GCC unroll 8
        for (int k = 0; k < N; ++k) sum = mul_add(j[k * 6 + r], j[k * 6 + c], sum);
      }
      a[c * kLd + r] = sum;
    }
    a[c * kLd + c] += lambda2;
  }
  return cholesky<size>(a);
}

template <int N>
void solve_fixed(const float* __restrict j, const float (&ew)[6], const float* __restrict l, float* __restrict x,
                 float* __restrict dq) {
  if constexpr (N <= 6) {
#pragma GCC unroll 8
    for (int c = 0; c < N; ++c) {
      float sum = 0.0f;
#pragma GCC unroll 8
      for (int k = 0; k < 6; ++k) sum = mul_add(j[c * 6 + k], ew[k], sum);
      x[c] = sum;
    }
    cholesky_solve<N>(l, x);
#pragma GCC unroll 8
    for (int c = 0; c < N; ++c) dq[c] = x[c];
  } else {
#pragma GCC unroll 8
    for (int k = 0; k < 6; ++k) x[k] = ew[k];
    cholesky_solve<6>(l, x);
#pragma GCC unroll 8
    for (int c = 0; c < N; ++c) {
      float sum = 0.0f;
#pragma GCC unroll 8
      for (int k = 0; k < 6; ++k) sum = mul_add(j[c * 6 + k], x[k], sum);
      dq[c] = sum;
    }
  }
}

// W^1/2 J into the workspace, then the step matrix and its factor. Not inlined: its frame then
// does not add to those of the forward kinematics passes.
[[gnu::noinline]] bool factor_step_matrix(const JointJacobian<float>& j, int n, const CorrectionOptions& options,
                                          CorrectionWorkspace& ws) {
  JointJacobian<float>& jw = ws.weighted_jacobian;
  const float w = options.rotation_weight_m;
  for (int c = 0; c < n; ++c) {
    for (int k = 0; k < 3; ++k) jw(k, c) = j(k, c);
    for (int k = 3; k < 6; ++k) jw(k, c) = w * j(k, c);
  }
  const float lambda2 = options.damping_m * options.damping_m;
  const float* weighted = jw.data();
  float* a = ws.normal.data();
  switch (n) {
    case 1:
      return factor_fixed<1>(weighted, lambda2, a);
    case 2:
      return factor_fixed<2>(weighted, lambda2, a);
    case 3:
      return factor_fixed<3>(weighted, lambda2, a);
    case 4:
      return factor_fixed<4>(weighted, lambda2, a);
    case 5:
      return factor_fixed<5>(weighted, lambda2, a);
    case 6:
      return factor_fixed<6>(weighted, lambda2, a);
    case 7:
      return factor_fixed<7>(weighted, lambda2, a);
    default:
      return factor_fixed<8>(weighted, lambda2, a);
  }
}

void solve_step(const Twist<float>& e, int n, const CorrectionOptions& options, CorrectionWorkspace& ws,
                JointVector<float>& dq) {
  const float w = options.rotation_weight_m;
  const float ew[6] = {e(0), e(1), e(2), w * e(3), w * e(4), w * e(5)};
  dq.setZero();
  const float* j = ws.weighted_jacobian.data();
  const float* l = ws.normal.data();
  float* x = ws.rhs.data();
  float* out = dq.data();
  switch (n) {
    case 1:
      return solve_fixed<1>(j, ew, l, x, out);
    case 2:
      return solve_fixed<2>(j, ew, l, x, out);
    case 3:
      return solve_fixed<3>(j, ew, l, x, out);
    case 4:
      return solve_fixed<4>(j, ew, l, x, out);
    case 5:
      return solve_fixed<5>(j, ew, l, x, out);
    case 6:
      return solve_fixed<6>(j, ew, l, x, out);
    case 7:
      return solve_fixed<7>(j, ew, l, x, out);
    default:
      return solve_fixed<8>(j, ew, l, x, out);
  }
}

// The first damped step from the nominal target, then the chord refinements, into ws.target.
// False if the total change of a joint exceeds max_joint_step. Not inlined: its frame and the
// forward kinematics' do not stack up in correct_joint_target's.
[[gnu::noinline]] bool damped_steps(const CorrectionModel& model, CorrectionWorkspace& ws,
                                    const JointVector<float>& nominal_joint_target, const Twist<float>& first_error,
                                    const RigidTransform<float>& base_T_target) {
  const int n = model.nominal.joint_count;
  ws.target = nominal_joint_target;
  for (int step = 0; step <= model.options.refinement_steps; ++step) {
    if (step > 0) {
      // Chord refinement: the pose error at the next target, the same factored Jacobian.
      // sin and cos of the next target: from the old ones and the (small) step where it allows.
      bool small = true;
      for (int i = 0; i < n; ++i) small = small && std::fabs(ws.step(i)) <= kSmallAngleMaxRad;
      if (small) {
        for (int i = 0; i < n; ++i) {
          const auto k = static_cast<std::size_t>(i);
          ws.trig[k] = angle_sum(ws.trig[k], small_angle_sin_cos(ws.step(i)));
        }
      } else {
        joint_trig(model.calibrated, ws.target, ws.trig);
      }
      tool_pose(model.calibrated, ws.target, ws.trig, ws.refined_pose);
      ws.error = small_pose_difference(base_T_target, ws.refined_pose);
    }
    solve_step(step == 0 ? first_error : ws.error, n, model.options, ws, ws.step);
    ws.target += ws.step;
  }
  for (int i = 0; i < n; ++i) {
    if (!(std::fabs(ws.target(i) - nominal_joint_target(i)) <= model.options.max_joint_step)) return false;
  }
  return true;
}

}  // namespace

CorrectionStatus prepare_correction(const ChainModel<float>& nominal, const ParameterSet& set,
                                    const ErrorVector<float>& errors, const CorrectionOptions& options,
                                    CorrectionModel& model) noexcept {
  if (nominal.joint_count < 1 || nominal.joint_count > kMaxJoints || !(options.rotation_weight_m > 0.0f) ||
      !(options.damping_m >= 0.0f) || !(options.max_joint_step > 0.0f) || options.refinement_steps < 0 ||
      options.refinement_steps > kMaxRefinementSteps || !errors.allFinite()) {
    return CorrectionStatus::bad_model;
  }
  if (apply_parameter_errors(nominal, set, errors, model.calibrated_chain) != ErrorModelStatus::ok) {
    return CorrectionStatus::bad_model;
  }
  prepare_chain(nominal, model.nominal);
  prepare_chain(model.calibrated_chain, model.calibrated);
  model.options = options;
  return CorrectionStatus::ok;
}

CorrectionStatus correct_joint_target(const CorrectionModel& model, CorrectionWorkspace& ws,
                                      const JointVector<float>& nominal_joint_target, Correction& correction) noexcept {
  const int n = model.nominal.joint_count;
  if (n < 1 || n > kMaxJoints || model.calibrated.joint_count != n) return CorrectionStatus::bad_model;
  for (int i = 0; i < n; ++i) {
    if (!(std::fabs(nominal_joint_target(i)) <= kSinCosMaxArgumentRad)) return CorrectionStatus::non_finite_input;
  }
  // The joint types are the same in both chains, so one sin_cos per joint serves both.
  joint_trig(model.nominal, nominal_joint_target, ws.trig);
  tool_pose(model.nominal, nominal_joint_target, ws.trig, correction.base_T_target);
  forward_kinematics(model.calibrated, nominal_joint_target, ws.trig, ws.calibrated_frames);
  correction.base_T_corrected = ws.calibrated_frames.base_T_tool;
  correction.pose_error = small_pose_difference(correction.base_T_target, correction.base_T_corrected);

  joint_jacobian(model.calibrated, ws.calibrated_frames, ws.jacobian);
  if (!factor_step_matrix(ws.jacobian, n, model.options, ws) ||
      !damped_steps(model, ws, nominal_joint_target, correction.pose_error, correction.base_T_target)) {
    correction.corrected_joint_target = nominal_joint_target;
    return CorrectionStatus::step_too_large;
  }
  correction.corrected_joint_target = ws.target;
  return CorrectionStatus::ok;
}

namespace {

bool finite_map(const JointMap<float>& map, int n) {
  for (int i = 0; i < n; ++i) {
    if (!(map.scale(i) > 0.0f) || !std::isfinite(map.scale(i)) || !std::isfinite(map.compliance(i))) return false;
    for (int k = 0; k < n; ++k)
      if (!std::isfinite(map.coupling(i, k))) return false;
  }
  return true;
}

bool any_compliance(const JointMap<float>& map, int n) {
  bool any = false;
  for (int i = 0; i < n; ++i) any = any || map.compliance(i) != 0.0f;
  return any;
}

}  // namespace

CorrectionStatus prepare_joint_map(const CorrectionModel& model, const JointMap<float>& nominal,
                                   const JointMap<float>& identified, const MassModel<float>& masses,
                                   CorrectionWorkspace& ws, JointMapModel& map) noexcept {
  const int n = model.nominal.joint_count;
  if (nominal.joint_count != n || identified.joint_count != n || !finite_map(nominal, n) || !finite_map(identified, n))
    return CorrectionStatus::bad_model;
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < n; ++k)
      if (nominal.coupling(i, k) != identified.coupling(i, k)) return CorrectionStatus::bad_model;
  bool masses_ok = masses.payload_mass_kg >= 0.0f && std::isfinite(masses.payload_mass_kg);
  for (std::size_t r = 0; r < 3; ++r)
    masses_ok = masses_ok && std::isfinite(masses.payload_centre_of_mass_m[r]) && std::isfinite(masses.gravity_mps2[r]);
  for (std::size_t i = 0; i < static_cast<std::size_t>(n); ++i) {
    masses_ok = masses_ok && masses.link_mass_kg[i] >= 0.0f && std::isfinite(masses.link_mass_kg[i]);
    for (std::size_t r = 0; r < 3; ++r) masses_ok = masses_ok && std::isfinite(masses.link_centre_of_mass_m[i][r]);
  }
  if (!masses_ok || !invert_coupling(identified, ws.normal, map.inverse_coupling)) return CorrectionStatus::bad_model;
  map.nominal = nominal;
  map.identified = identified;
  map.masses = masses;
  map.nominal_deflects = any_compliance(nominal, n);
  map.identified_deflects = any_compliance(identified, n);
  return CorrectionStatus::ok;
}

CorrectionStatus correct_joint_readings(const CorrectionModel& model, const JointMapModel& map, CorrectionWorkspace& ws,
                                        const JointVector<float>& readings, Correction& correction,
                                        JointVector<float>& corrected_readings) noexcept {
  const int n = model.nominal.joint_count;
  if (n < 1 || n > kMaxJoints || map.nominal.joint_count != n || map.identified.joint_count != n)
    return CorrectionStatus::bad_model;
  corrected_readings = readings;
  for (int i = 0; i < n; ++i) {
    if (!(std::fabs(readings(i)) <= kSinCosMaxArgumentRad)) return CorrectionStatus::non_finite_input;
  }
  coupled_values(map.nominal, readings, ws.coupled);
  if (map.nominal_deflects)
    deflect(model.nominal, map.masses, map.nominal.compliance, ws.coupled, ws.deflection, ws.chain_target);
  else
    ws.chain_target = ws.coupled;
  const CorrectionStatus status = correct_joint_target(model, ws, ws.chain_target, correction);
  if (status != CorrectionStatus::ok) return status;
  if (map.identified_deflects) {
    // The first pass from the chain target, whose calibrated frames the correction left in the
    // workspace: one forward kinematics pass fewer than starting from v*.
    gravity_forces(model.calibrated, ws.calibrated_frames, map.masses, ws.deflection.forces);
    for (int i = 0; i < n; ++i)
      ws.coupled(i) = correction.corrected_joint_target(i) - map.identified.compliance(i) * ws.deflection.forces(i);
    undeflect(model.calibrated, map.masses, map.identified.compliance, correction.corrected_joint_target,
              kUndeflectPasses - 1, ws.deflection, ws.coupled);
  } else {
    ws.coupled = correction.corrected_joint_target;
  }
  readings_from_coupled(map.identified, map.inverse_coupling, ws.coupled, corrected_readings);
  return CorrectionStatus::ok;
}

}  // namespace kincal::core
