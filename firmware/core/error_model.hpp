// The first-order kinematic error model: how small errors in the chain's parameters move the
// end frame, for any chain of link_model.hpp and any chosen set of parameters -- and Doty's
// closed form of it for the ARID.
//
// The end-frame pose error is a twist [dp; dphi] in the base frame (rigid_transform.hpp): dp
// the displacement of the tool origin (m), dphi the small rotation (rad). To first order
//
//   pose error = E(q) * parameter errors,   E(q) = parameter_jacobian(...)   (6 x P)
//
// Doty's 3-10..3-12 is this for the ARID (PRRR, all axes nominally parallel) with the eight
// angles psi = (beta1..beta4, alpha1..alpha4) at zero: his (eps1, eps2, eps3, eps4, eps5 - d1)
// are (dphi_y, -dphi_x, s1234 dphi_x - c1234 dphi_y, c1234 dphi_x + s1234 dphi_y, dp_z).
// doty_arid_error_matrix() evaluates his closed form (3-11a..e) with psi in his stated order;
// tests/firmware/core/error_model_test.cpp reproduces it from the general E to float precision.
// (The report's printed E matrix is garbled by the PDF extraction: its first two rows list the
// columns in reverse order -- beta4 first -- and row 2 ends in c1 where 3-11b gives -c1. The
// closed form here follows the equations 3-11a..e, which were checked by re-deriving them.)
//
// Parameters: a ParameterSet lists up to kMaxErrorParameters ParameterIds -- a link's d, theta,
// a, alpha or beta, or one of six small motions of the base frame (translation along, rotation
// about the axes of frame 0) or of the tool frame (along and about the tool's own axes).
// apply_parameter_errors adds errors to a chain exactly (link parameters summed; base and tool
// motions composed as base_T_frame0 * [exp(r), t] and flange_T_tool * [exp(r), t]), so E is the
// derivative of forward_kinematics(apply_parameter_errors(...)) at zero error.
//
// Columns (p = tool origin, all in the base frame): a rotation parameter about unit axis w
// through point o gives [w x (p - o); w]; a translation along w gives [w; 0]. The axis of each
// parameter is found by walking the link's elementary motions (link_model.hpp) from its input
// frame.
//
// Error bounds (asserted against central differences of the double forward kinematics, and
// float against double): E in float within kErrorMatrixAbsError per metre of chain length
// (measured 9e-8); the ARID closed form and the general model agree with 3-11 (double) within
// 5e-7 per metre of reach (measured 2.8e-7: a few units of 2^-24).
// Cost: O(P) with about 40 flops per parameter; joint_jacobian about 15 flops per joint.
// Not on the control-rate path (correction.hpp needs only joint_jacobian).
#pragma once

#include <array>
#include <cstdint>

#include "firmware/core/link_model.hpp"

namespace kincal::core {

inline constexpr int kMaxErrorParameters = 5 * kMaxJoints + 12;
inline constexpr float kErrorMatrixAbsError = 3.0e-7f;

enum class ParameterKind : std::uint8_t {
  link_d,
  link_theta,
  link_a,
  link_alpha,
  link_beta,
  base_x,
  base_y,
  base_z,
  base_rx,
  base_ry,
  base_rz,
  tool_x,
  tool_y,
  tool_z,
  tool_rx,
  tool_ry,
  tool_rz,
};

struct ParameterId {
  ParameterKind kind = ParameterKind::link_theta;
  std::uint8_t link = 0;  // 0-based link index, for the link_* kinds
};

struct ParameterSet {
  int count = 0;
  std::array<ParameterId, kMaxErrorParameters> ids{};
};
static_assert(kMaxErrorParameters == 52, "five per link and twelve base/tool motions");

template <class S>
using ErrorMatrix = Eigen::Matrix<S, 6, kMaxErrorParameters>;
template <class S>
using ErrorVector = Eigen::Matrix<S, kMaxErrorParameters, 1>;
template <class S>
using JointJacobian = Eigen::Matrix<S, 6, kMaxJoints>;

enum class [[nodiscard]] ErrorModelStatus : std::uint8_t{
    ok,
    bad_parameter,  // count outside [0, kMaxErrorParameters], or a link index >= joint_count
};

// The parameters each link's convention uses (DH: d, theta, a, alpha; Doty: all five), link by
// link, then the six base motions and the six tool motions if asked.
template <class S>
ParameterSet full_parameter_set(const ChainModel<S>& model, bool base, bool tool) noexcept;

template <class S>
ErrorModelStatus apply_parameter_errors(const ChainModel<S>& nominal, const ParameterSet& set,
                                        const ErrorVector<S>& errors, ChainModel<S>& actual) noexcept;

// E for the chain at the joint values of `frames` (forward_kinematics with the same q and trig).
// Columns beyond set.count are left as they were.
template <class S>
ErrorModelStatus parameter_jacobian(const PreparedChain<S>& chain, const JointVector<S>& q,
                                    const std::array<SinCos<S>, kMaxJoints>& trig, const ChainFrames<S>& frames,
                                    const ParameterSet& set, ErrorMatrix<S>& error_matrix) noexcept;

// d(pose error)/dq: the geometric Jacobian at the tool origin, in the base frame. Columns beyond
// the joint count are zero.
template <class S>
void joint_jacobian(const PreparedChain<S>& chain, const ChainFrames<S>& frames, JointJacobian<S>& jacobian) noexcept;

// Doty's E (3-11a..e, 3-12) for the ARID: rows eps1, eps2, eps3, eps4, eps5 - d1; columns
// psi = (beta1, beta2, beta3, beta4, alpha1, alpha2, alpha3, alpha4). theta_rad are his
// theta1..theta4 (theta1 the constant angle of the prismatic first joint), a_m his a1..a3
// (a4 = 0 in his Table 3.1).
using AridErrorMatrix = Eigen::Matrix<float, 5, 8>;
void doty_arid_error_matrix(const std::array<float, 4>& theta_rad, const std::array<float, 3>& a_m,
                            AridErrorMatrix& error_matrix) noexcept;

extern template ParameterSet full_parameter_set(const ChainModel<float>&, bool, bool) noexcept;
extern template ErrorModelStatus apply_parameter_errors(const ChainModel<float>&, const ParameterSet&,
                                                        const ErrorVector<float>&, ChainModel<float>&) noexcept;
extern template ErrorModelStatus parameter_jacobian(const PreparedChain<float>&, const JointVector<float>&,
                                                    const JointTrig&, const ChainFrames<float>&, const ParameterSet&,
                                                    ErrorMatrix<float>&) noexcept;
extern template void joint_jacobian(const PreparedChain<float>&, const ChainFrames<float>&,
                                    JointJacobian<float>&) noexcept;

}  // namespace kincal::core

#include "firmware/core/error_model_impl.hpp"
