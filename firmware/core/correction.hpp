// Online kinematic correction: the calibrated model applied to every joint target streamed to
// the platform, at the control rate.
//
// The robot's controller computes joint targets q_nom with its nominal model, expecting the tool
// at base_T_target = FK_nominal(q_nom). The real robot follows the calibrated model (nominal
// parameters plus the identified errors of error_model.hpp), so at q_nom its tool is at
// FK_calibrated(q_nom) -- the corrected end-frame pose. correct_joint_target returns both poses
// and the corrected joint target from damped least-squares (Levenberg-Marquardt) steps:
//
//   q_0 = q_nom,   q_k+1 = q_k + (J^T W J + lambda^2 I)^-1 J^T W e(q_k)
//   e(q) = base_T_target (-) FK_calibrated(q)        (twist [dp; dphi], rigid_transform.hpp)
//   J = joint_jacobian of the calibrated chain at q_nom,  W = diag(1, 1, 1, L^2, L^2, L^2)
//
// Rotation errors weigh as L * angle (L = rotation_weight_m); the damping lambda bounds the step
// near singular configurations. The first step is the first-order correction: what it leaves is
// the second-order part of the pose error, which scales with the square of the parameter errors.
// Each further step (refinement_steps, default 1) is a chord step: it reuses J and its Cholesky
// factor and costs one more sin_cos per joint and one forward kinematics pass, and it takes the
// residual to third order. Both poses are exact for their models, not first-order. A chain with
// fewer than six joints gets the least-squares best correction it can make (n x n system); one
// with more, the damped minimum-norm one (6 x 6 system J W J^T + lambda^2 I, well posed although
// J^T J is then singular). tests/bench/correction_residual_bench.cpp measures what is left on a
// simulated 6-joint robot with all 42 parameters off by 0.5 degree / 1 mm, at targets away from
// singularities: 0.33 % of the pose error with the default refinement, 3.2 % after the first-
// order step alone; the residual grows with the error size to the power 3.0 and 2.0.
//
// Error bounds (tests/firmware/core/correction_test.cpp, random chains of 3..8 joints and a
// PUMA-like arm, against the same damped problem solved in double with a numeric Jacobian): the
// float step is within 2e-6 (20 + kappa) of the double one, relative to its size, where kappa is
// the condition number of the damped normal matrix (the 20 is the rounding of the pose error, a
// difference of two float poses); the corrected pose within 2e-6 m and rad of double FK.
//
// Statuses (`correction` is written on ok and on step_too_large):
//   bad_model          prepare: joint count outside [1, kMaxJoints], a bad parameter set, or
//                      non-positive options
//   non_finite_input   a joint value is NaN, infinite, or beyond sin_cos's range
//   step_too_large     some |dq_i| > max_joint_step: the target is near a singularity or the
//                      parameters are wrong. corrected_joint_target is then q_nom unchanged.
//
// Cost on the Cortex-M4F: one sin_cos per revolute joint, two forward kinematics passes sharing
// it, the Jacobian, a 6x6 normal matrix and its Cholesky factorization, and per refinement step
// another sin_cos per joint (cheap: small_angle_sin_cos of the step where it is small), forward
// kinematics pass and two triangular solves. Measured for a 6-joint arm (-O3, tests/bench/
// geometry_m4_bench.cpp): 4,833 instructions with the default refinement, 3,464 for the first-
// order step alone -- 35 kHz and 49 kHz at 168 MHz if an instruction took a cycle. Memory:
// CorrectionModel (constant, about 1.1 KB) and CorrectionWorkspace (about 1.4 KB) are the
// caller's; stack 384 bytes (m4.kincal_core.stack). Reentrant: two workspaces may run at once on
// one model.
#pragma once

#include <cstdint>

#include "firmware/core/error_model.hpp"
#include "firmware/core/joint_map.hpp"
#include "firmware/core/link_model.hpp"

namespace kincal::core {

inline constexpr int kMaxRefinementSteps = 3;

struct CorrectionOptions {
  float rotation_weight_m = 0.5f;  // L: a radian of orientation error weighs as L metres
  float damping_m = 1.0e-3f;       // lambda (weighted metres): lambda^2 stays above float rounding of J^T W J
  float max_joint_step = 0.05f;    // rad (revolute) or m (prismatic), total correction per joint
  int refinement_steps = 1;        // chord steps after the first, 0..kMaxRefinementSteps
};

enum class [[nodiscard]] CorrectionStatus : std::uint8_t{
    ok,
    bad_model,
    non_finite_input,
    step_too_large,
};

// Constant once loaded: the nominal chain the controller uses and the calibrated one (also in
// parameter form, for reports).
struct CorrectionModel {
  ChainModel<float> calibrated_chain;
  PreparedChain<float> nominal;
  PreparedChain<float> calibrated;
  CorrectionOptions options;
};

// Scratch for one correction at a time; its contents on return are internals of the last call.
struct CorrectionWorkspace {
  JointTrig trig;
  ChainFrames<float> calibrated_frames;
  RigidTransform<float> refined_pose;
  JointJacobian<float> jacobian;
  JointJacobian<float> weighted_jacobian;               // rotation rows times rotation_weight_m
  Eigen::Matrix<float, kMaxJoints, kMaxJoints> normal;  // the damped step's matrix, then its Cholesky factor
  JointVector<float> rhs;
  Twist<float> error;
  JointVector<float> step;
  JointVector<float> target;
  // correct_joint_readings: the chain target, the coupled values, the deflection's passes.
  JointVector<float> chain_target;
  JointVector<float> coupled;
  DeflectionWorkspace<float> deflection;
};

struct Correction {
  RigidTransform<float> base_T_target;     // FK_nominal(q_nom): where the controller wants the tool
  RigidTransform<float> base_T_corrected;  // FK_calibrated(q_nom): where the tool really is
  Twist<float> pose_error;                 // target (-) corrected, base frame
  JointVector<float> corrected_joint_target;
};

// Builds the model from the nominal chain and the calibrated errors (error_model.hpp's
// apply_parameter_errors): done once, when parameters are loaded.
CorrectionStatus prepare_correction(const ChainModel<float>& nominal, const ParameterSet& set,
                                    const ErrorVector<float>& errors, const CorrectionOptions& options,
                                    CorrectionModel& model) noexcept;

CorrectionStatus correct_joint_target(const CorrectionModel& model, CorrectionWorkspace& workspace,
                                      const JointVector<float>& nominal_joint_target, Correction& correction) noexcept;

// ---- With the joint map (joint_map.hpp) ---------------------------------------------------------
// The correction of controller readings r when the chains' variables are not the readings:
//   w_nom = C S_nom r,  v_nom = w_nom + c_nom G_nom(w_nom)      the nominal map: what the controller means
//   v*    = correct_joint_target(v_nom)                         the calibrated chain's variables
//   w*    = undeflect_identified(v*)   (kUndeflectPasses passes from w = v_nom, the first on the
//                                       frames the correction computed there; skipped without compliance)
//   r*    = S_id^-1 C^-1 w*                                     the readings that make the real arm reach it
// The coupling C is one input of both models (never identified); the scales and compliances are
// the nominal model's and the identified one's; the masses and gravity are shared. A map with no
// compliance skips its deflection pass, so an identity map gives the same bits as
// correct_joint_target. The chain-variable change is bounded by max_joint_step as there.
// Cost on the M4F for a 6-joint arm with coupling and scale, and compliance in the identified
// model: 8,295 instructions (correction_joint_map_m4_instructions; 4,834 without the map): the
// correction, one more forward kinematics pass, two gravity-force passes and the map's products.
// A nominal model with compliance adds one more forward kinematics pass.
struct JointMapModel {
  JointMap<float> nominal, identified;     // coupling equal in both
  CouplingMatrix<float> inverse_coupling;  // identified.coupling^-1
  MassModel<float> masses;
  bool nominal_deflects = false, identified_deflects = false;  // any compliance != 0
};

// The inputs may be `map`'s own members (the platform reads the block into them).
// bad_model: joint counts differ from the correction model's, a scale not > 0, a non-finite
// value or negative mass, or a coupling that is singular (pivot below kMinCouplingPivot) or
// differs between the models. `workspace` is scratch for the elimination.
CorrectionStatus prepare_joint_map(const CorrectionModel& model, const JointMap<float>& nominal,
                                   const JointMap<float>& identified, const MassModel<float>& masses,
                                   CorrectionWorkspace& workspace, JointMapModel& map) noexcept;

// Statuses as correct_joint_target (on step_too_large and non_finite_input, corrected_readings =
// readings); `correction` describes the chain-variable step.
CorrectionStatus correct_joint_readings(const CorrectionModel& model, const JointMapModel& map,
                                        CorrectionWorkspace& workspace, const JointVector<float>& readings,
                                        Correction& correction, JointVector<float>& corrected_readings) noexcept;

}  // namespace kincal::core
