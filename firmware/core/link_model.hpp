// Serial-chain link models and forward kinematics, templated on the scalar: float on the MCU
// (the online correction), double and ceres::Jet on the host (identification, issue #7), from
// one definition.
//
// A chain is base -> frame 0 (base_T_frame0) -> link 1 -> frame 1 -> ... -> link n -> frame n
// (the flange) -> tool (flange_T_tool), with n <= kMaxJoints joints, each revolute (q adds to
// theta) or prismatic (q adds to d). Each link has five parameters (d, theta, a, alpha, beta);
// its convention says how they make the transform frame i-1 -> frame i:
//
//   standard_dh   Rz(theta) Tz(d) Tx(a) Rx(alpha)                          (beta unused)
//                 joint axis: z of frame i-1.
//   modified_dh   Rx(alpha) Tx(a) Rz(theta) Tz(d)   (Craig: link i holds alpha_{i-1}, a_{i-1})
//                 joint axis: z of frame i.                                (beta unused)
//   doty          Tz(d) Rz(theta) Ry(beta) Tx(a) Rx(alpha)   (Doty's report, 3-1..3-3)
//                 joint axis: z of frame i-1. The pitch beta keeps the model continuous where
//                 adjacent axes are (nearly) parallel, where DH's common normal jumps. Doty sets
//                 d = 0 for revolute joints; here d is a parameter for both joint types.
//
// Conventions of rigid_transform.hpp. Link i's transform in closed form (Doty's 3-2/3-3 for his
// model) costs about 20 multiplies; composing a link 36 multiplies and 30 adds. On the M4F
// (-O3), joint_trig plus forward_kinematics of a 6-joint arm take 1,185 instructions
// (geometry_m4_bench, forward_kinematics_6_joints_m4_instructions).
//
// For the control rate, PreparedChain holds the sines and cosines of every constant angle, so a
// forward kinematics pass costs one sin_cos per revolute joint (shared by several chains through
// joint_trig) and no other trigonometry. ChainFrames keeps every frame for the Jacobians.
//
// Error bounds (tests/firmware/core/link_model_test.cpp, random chains of every convention with
// up to 8 joints and links up to 1 m, against an independent double implementation composed from
// elementary rotations and translations): float base_T_tool within kFkPositionErrorPerM per metre
// of summed link length and kFkRotationErrorRad per joint. Everything here is noexcept and
// allocation-free; nothing fails (malformed counts are clamped to [0, kMaxJoints]).
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>

#include "firmware/core/rigid_transform.hpp"
#include "firmware/core/sin_cos.hpp"

namespace kincal::core {

inline constexpr int kMaxJoints = 8;
inline constexpr float kFkPositionErrorPerM = 3.0e-7f;
inline constexpr float kFkRotationErrorRad = 3.0e-7f;

enum class JointType : std::uint8_t { revolute, prismatic };
enum class LinkConvention : std::uint8_t { standard_dh, modified_dh, doty };

template <class S>
struct LinkParameters {
  S d_m{}, theta_rad{}, a_m{}, alpha_rad{}, beta_rad{};
};

template <class S>
struct Link {
  LinkConvention convention = LinkConvention::doty;
  JointType joint = JointType::revolute;
  LinkParameters<S> parameters{};
};

template <class S>
struct ChainModel {
  int joint_count = 0;
  std::array<Link<S>, kMaxJoints> links{};
  RigidTransform<S> base_T_frame0{};
  RigidTransform<S> flange_T_tool{};
};

template <class S>
using JointVector = Eigen::Matrix<S, kMaxJoints, 1>;

template <class S>
struct PreparedLink {
  LinkConvention convention = LinkConvention::doty;
  JointType joint = JointType::revolute;
  S d_m{}, a_m{};
  SinCos<S> theta{}, alpha{}, beta{};
};

// A chain with its constant trigonometry evaluated; build with prepare_chain.
template <class S>
struct PreparedChain {
  int joint_count = 0;
  std::array<PreparedLink<S>, kMaxJoints> links{};
  RigidTransform<S> base_T_frame0{};
  RigidTransform<S> flange_T_tool{};
};

// base_T_frame[i] for i = 0..joint_count (frame 0 = base_T_frame0, frame n = the flange), and
// the tool.
template <class S>
struct ChainFrames {
  int joint_count = 0;
  std::array<RigidTransform<S>, kMaxJoints + 1> base_T_frame{};
  RigidTransform<S> base_T_tool{};
};

using JointTrig = std::array<SinCos<float>, kMaxJoints>;

// frame i-1 -> frame i for the given convention, from d, a and the sines and cosines of theta,
// alpha and beta (joint value already included).
template <class S>
RigidTransform<S> link_transform(LinkConvention convention, const S& d_m, const S& a_m, const SinCos<S>& theta,
                                 const SinCos<S>& alpha, const SinCos<S>& beta) noexcept;

// The same from a link's parameters and its joint value q (rad or m).
template <class S>
RigidTransform<S> link_transform(const Link<S>& link, const S& q) noexcept;

template <class S>
void prepare_chain(const ChainModel<S>& model, PreparedChain<S>& prepared) noexcept;

// sin and cos of each revolute joint value (prismatic entries unused): one sin_cos per joint.
template <class S>
void joint_trig(const PreparedChain<S>& chain, const JointVector<S>& q,
                std::array<SinCos<S>, kMaxJoints>& trig) noexcept;

// Every frame of the chain at joint values q, reusing joint_trig's result.
template <class S>
void forward_kinematics(const PreparedChain<S>& chain, const JointVector<S>& q,
                        const std::array<SinCos<S>, kMaxJoints>& trig, ChainFrames<S>& frames) noexcept;

// base_T_tool only, no frames kept: the cheaper pass when no Jacobian is needed.
template <class S>
void tool_pose(const PreparedChain<S>& chain, const JointVector<S>& q, const std::array<SinCos<S>, kMaxJoints>& trig,
               RigidTransform<S>& base_T_tool) noexcept;

// base_T_tool straight from the parameters, no preparation and no workspace (host and tests).
template <class S>
RigidTransform<S> forward_kinematics(const ChainModel<S>& model, const JointVector<S>& q) noexcept;

// ---- Definitions (the contract is above) ------------------------------------------------------

// link_transform into `t`, entry by entry (no temporaries: this is the inner loop of forward
// kinematics).
template <class S>
[[gnu::always_inline]] inline void write_link_transform(LinkConvention convention, const S& d_m, const S& a_m,
                                                        const SinCos<S>& theta, const SinCos<S>& alpha,
                                                        const SinCos<S>& beta, RigidTransform<S>& t) noexcept {
  const S &ct = theta.cos, &st = theta.sin, &ca = alpha.cos, &sa = alpha.sin;
  Matrix3<S>& r = t.rotation;
  Vector3<S>& p = t.translation;
  switch (convention) {
    case LinkConvention::standard_dh:
      r(0, 0) = ct, r(0, 1) = -st * ca, r(0, 2) = st * sa;
      r(1, 0) = st, r(1, 1) = ct * ca, r(1, 2) = -ct * sa;
      r(2, 0) = S(0), r(2, 1) = sa, r(2, 2) = ca;
      p(0) = a_m * ct, p(1) = a_m * st, p(2) = d_m;
      break;
    case LinkConvention::modified_dh:
      r(0, 0) = ct, r(0, 1) = -st, r(0, 2) = S(0);
      r(1, 0) = st * ca, r(1, 1) = ct * ca, r(1, 2) = -sa;
      r(2, 0) = st * sa, r(2, 1) = ct * sa, r(2, 2) = ca;
      p(0) = a_m, p(1) = -sa * d_m, p(2) = ca * d_m;
      break;
    case LinkConvention::doty: {
      // Doty 3-2 and 3-3.
      const S &cb = beta.cos, &sb = beta.sin;
      const S sa_sb = sa * sb, ca_sb = ca * sb;
      // Sums of two products fused for float (mul_add.hpp); for double the same as written plainly.
      r(0, 0) = cb * ct, r(0, 1) = mul_add(ct, sa_sb, -(ca * st)), r(0, 2) = mul_add(ct, ca_sb, sa * st);
      r(1, 0) = cb * st, r(1, 1) = mul_add(ca, ct, sa_sb * st), r(1, 2) = mul_add(st, ca_sb, -(ct * sa));
      r(2, 0) = -sb, r(2, 1) = cb * sa, r(2, 2) = ca * cb;
      p(0) = a_m * r(0, 0), p(1) = a_m * r(1, 0), p(2) = mul_add(-a_m, sb, d_m);
      break;
    }
  }
}

template <class S>
RigidTransform<S> link_transform(LinkConvention convention, const S& d_m, const S& a_m, const SinCos<S>& theta,
                                 const SinCos<S>& alpha, const SinCos<S>& beta) noexcept {
  RigidTransform<S> t;
  write_link_transform(convention, d_m, a_m, theta, alpha, beta, t);
  return t;
}

template <class S>
RigidTransform<S> link_transform(const Link<S>& link, const S& q) noexcept {
  const LinkParameters<S>& p = link.parameters;
  const bool revolute = link.joint == JointType::revolute;
  const S theta = revolute ? S(p.theta_rad + q) : p.theta_rad;
  const S d = revolute ? p.d_m : S(p.d_m + q);
  return link_transform(link.convention, d, p.a_m, sin_cos(theta), sin_cos(p.alpha_rad), sin_cos(p.beta_rad));
}

template <class S>
void prepare_chain(const ChainModel<S>& model, PreparedChain<S>& prepared) noexcept {
  prepared.joint_count = std::clamp(model.joint_count, 0, kMaxJoints);
  for (std::size_t i = 0; i < static_cast<std::size_t>(prepared.joint_count); ++i) {
    const Link<S>& link = model.links[i];
    PreparedLink<S>& out = prepared.links[i];
    out.convention = link.convention;
    out.joint = link.joint;
    out.d_m = link.parameters.d_m;
    out.a_m = link.parameters.a_m;
    out.theta = sin_cos(link.parameters.theta_rad);
    out.alpha = sin_cos(link.parameters.alpha_rad);
    out.beta = sin_cos(link.parameters.beta_rad);
  }
  prepared.base_T_frame0 = model.base_T_frame0;
  prepared.flange_T_tool = model.flange_T_tool;
}

template <class S>
void joint_trig(const PreparedChain<S>& chain, const JointVector<S>& q,
                std::array<SinCos<S>, kMaxJoints>& trig) noexcept {
  const int n = std::clamp(chain.joint_count, 0, kMaxJoints);
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    trig[k] = chain.links[k].joint == JointType::revolute ? sin_cos(q(i)) : SinCos<S>{S(0), S(1)};
  }
}

template <class S>
void forward_kinematics(const PreparedChain<S>& chain, const JointVector<S>& q,
                        const std::array<SinCos<S>, kMaxJoints>& trig, ChainFrames<S>& frames) noexcept {
  const int n = std::clamp(chain.joint_count, 0, kMaxJoints);
  frames.joint_count = n;
  frames.base_T_frame[0] = chain.base_T_frame0;
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const PreparedLink<S>& link = chain.links[k];
    const bool revolute = link.joint == JointType::revolute;
    const SinCos<S> theta = revolute ? angle_sum(link.theta, trig[k]) : link.theta;
    const S d = revolute ? link.d_m : S(link.d_m + q(i));
    RigidTransform<S> frame_T_next;
    write_link_transform(link.convention, d, link.a_m, theta, link.alpha, link.beta, frame_T_next);
    compose(frames.base_T_frame[k], frame_T_next, frames.base_T_frame[k + 1]);
  }
  compose(frames.base_T_frame[static_cast<std::size_t>(n)], chain.flange_T_tool, frames.base_T_tool);
}

template <class S>
void tool_pose(const PreparedChain<S>& chain, const JointVector<S>& q, const std::array<SinCos<S>, kMaxJoints>& trig,
               RigidTransform<S>& base_T_tool) noexcept {
  const int n = std::clamp(chain.joint_count, 0, kMaxJoints);
  RigidTransform<S> base_T_frame = chain.base_T_frame0;
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const PreparedLink<S>& link = chain.links[k];
    const bool revolute = link.joint == JointType::revolute;
    const SinCos<S> theta = revolute ? angle_sum(link.theta, trig[k]) : link.theta;
    const S d = revolute ? link.d_m : S(link.d_m + q(i));
    RigidTransform<S> frame_T_next;
    write_link_transform(link.convention, d, link.a_m, theta, link.alpha, link.beta, frame_T_next);
    compose(base_T_frame, frame_T_next, base_T_frame);  // in place: allowed for the left operand
  }
  compose(base_T_frame, chain.flange_T_tool, base_T_tool);
}

template <class S>
RigidTransform<S> forward_kinematics(const ChainModel<S>& model, const JointVector<S>& q) noexcept {
  const int n = std::clamp(model.joint_count, 0, kMaxJoints);
  RigidTransform<S> base_T_frame = model.base_T_frame0;
  for (int i = 0; i < n; ++i)
    base_T_frame = base_T_frame * link_transform(model.links[static_cast<std::size_t>(i)], q(i));
  return base_T_frame * model.flange_T_tool;
}

// The float versions are compiled once, in the library (link_model.cpp), where the firmware
// checks (stack, no heap) see them.
extern template RigidTransform<float> link_transform(LinkConvention, const float&, const float&, const SinCos<float>&,
                                                     const SinCos<float>&, const SinCos<float>&) noexcept;
extern template RigidTransform<float> link_transform(const Link<float>&, const float&) noexcept;
extern template void prepare_chain(const ChainModel<float>&, PreparedChain<float>&) noexcept;
extern template void joint_trig(const PreparedChain<float>&, const JointVector<float>&, JointTrig&) noexcept;
extern template void forward_kinematics(const PreparedChain<float>&, const JointVector<float>&, const JointTrig&,
                                        ChainFrames<float>&) noexcept;
extern template void tool_pose(const PreparedChain<float>&, const JointVector<float>&, const JointTrig&,
                               RigidTransform<float>&) noexcept;
extern template RigidTransform<float> forward_kinematics(const ChainModel<float>&, const JointVector<float>&) noexcept;

}  // namespace kincal::core
