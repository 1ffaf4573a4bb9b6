// The non-geometric joint map between a controller's joint readings and a chain's joint
// variables, templated on the scalar: float for the platform's online correction
// (correction.hpp's correct_joint_readings), double on the host (host/model/robot_model.cpp's
// forward kinematics and Jacobians, host/can/scenario.cpp's reference), from one definition.
//
// The map (host/model/robot_model.hpp's top comment, which is the specification):
//   u_k = scale_k r_k                       r the readings (rad or m), scale a gear-ratio error
//   w_i = sum_k coupling_ik u_k             coupling: identity rows for joints read directly
//                                           (Fanuc's elbow: row 3 = [0, 1, 1, 0, 0, 0])
//   v_i = w_i + compliance_i G_i(w)         gravity deflection; v the chain's variables
// The joint offsets are the chain's (theta or d), not the map's.
//
// G_i(w) is the generalized force gravity puts on joint i at joint values w (N m for a revolute
// joint, N for a prismatic one) from the bodies the joint moves: links i..n-1 (mass m_b, centre
// of mass c_b in frame b+1, the frame at the link's end) and the payload (in the flange frame):
//   revolute   G_i = z_i . ((sum_b m_b c_b - M_i o_i) x g)      (= sum_b m_b g . (z_i x (c_b - o_i)))
//   prismatic  G_i = M_i (z_i . g)
// with M_i the total mass the joint moves, z_i and o_i its axis and a point on it (the frame
// joint_jacobian uses: input frame for DH and Doty links, output frame for modified DH), g the
// gravity vector given in frame 0, all in the base frame. One pass from the last body inwards:
// about 30 flops per joint once the frames are known.
//
// Inverses: readings from chain variables need w from v (undeflect: fixed-point passes w <- v -
// c G(w), each one forward kinematics; the error shrinks by |c dG/dw| per pass, 1e-3..2e-3 for
// a heavy arm's shoulder, so two passes leave a few millionths of the deflection: nanoradians,
// tests/firmware/core/joint_map_test.cpp) and u from w (the
// coupling's inverse, computed once by Gauss-Jordan elimination with partial pivoting).
//
// Bits: plain loops in a fixed order (no Eigen reductions), so float results are the same
// natively and on the M4 (m4.geometry_digest_matches_native). Nothing here allocates or throws.
#pragma once

#include <array>
#include <cmath>

#include "firmware/core/error_model.hpp"
#include "firmware/core/link_model.hpp"

namespace kincal::core {

template <class S>
using CouplingMatrix = Eigen::Matrix<S, kMaxJoints, kMaxJoints>;

// Fixed-point passes of undeflect in the online correction.
inline constexpr int kUndeflectPasses = 2;
// Gauss-Jordan refuses a coupling matrix whose pivot falls to this (coefficients are O(1)).
inline constexpr double kMinCouplingPivot = 1e-4;

// One model's map. Entries at and beyond joint_count are not read.
template <class S>
struct JointMap {
  int joint_count = 0;
  CouplingMatrix<S> coupling = CouplingMatrix<S>::Identity();
  JointVector<S> scale = JointVector<S>::Ones();
  JointVector<S> compliance = JointVector<S>::Zero();  // rad/(N m) or m/N
};

// The gravity inputs: the same for the nominal and the identified model.
template <class S>
struct MassModel {
  std::array<S, kMaxJoints> link_mass_kg{};
  std::array<std::array<S, 3>, kMaxJoints> link_centre_of_mass_m{};  // link i's, in frame i+1
  S payload_mass_kg{};
  std::array<S, 3> payload_centre_of_mass_m{};             // flange frame
  std::array<S, 3> gravity_mps2{S(0), S(0), S(-9.80665)};  // frame 0
};

// Scratch for the forward kinematics passes of deflect/undeflect.
template <class S>
struct DeflectionWorkspace {
  std::array<SinCos<S>, kMaxJoints> trig{};
  ChainFrames<S> frames;
  JointVector<S> forces = JointVector<S>::Zero();
};

// w = coupling (scale .* r) for the first joint_count entries; the rest of w is zero.
template <class S>
void coupled_values(const JointMap<S>& map, const JointVector<S>& readings, JointVector<S>& coupled) noexcept;

// inverse = coupling^-1 (leading joint_count block; identity beyond), `scratch` destroyed.
// False when a pivot is below kMinCouplingPivot or an entry is not finite.
template <class S>
bool invert_coupling(const JointMap<S>& map, CouplingMatrix<S>& scratch, CouplingMatrix<S>& inverse) noexcept;

// r = (inverse w) ./ scale for the first joint_count entries; the rest of r is zero.
template <class S>
void readings_from_coupled(const JointMap<S>& map, const CouplingMatrix<S>& inverse, const JointVector<S>& coupled,
                           JointVector<S>& readings) noexcept;

// G at the chain's frames (forward_kinematics at the joint values): forces(i) for i <
// joint_count, zero beyond.
template <class S>
void gravity_forces(const PreparedChain<S>& chain, const ChainFrames<S>& frames, const MassModel<S>& masses,
                    JointVector<S>& forces) noexcept;

// v = w + compliance .* G(w); one joint_trig and forward kinematics pass at w.
template <class S>
void deflect(const PreparedChain<S>& chain, const MassModel<S>& masses, const JointVector<S>& compliance,
             const JointVector<S>& coupled, DeflectionWorkspace<S>& workspace, JointVector<S>& deflected) noexcept;

// w with w + compliance .* G(w) = v, by `passes` fixed-point passes from the guess that
// `coupled` holds on entry (v itself, or any nearby values).
template <class S>
void undeflect(const PreparedChain<S>& chain, const MassModel<S>& masses, const JointVector<S>& compliance,
               const JointVector<S>& deflected, int passes, DeflectionWorkspace<S>& workspace,
               JointVector<S>& coupled) noexcept;

// ---- Definitions (the contract is above) ------------------------------------------------------

template <class S>
void coupled_values(const JointMap<S>& map, const JointVector<S>& readings, JointVector<S>& coupled) noexcept {
  const int n = std::clamp(map.joint_count, 0, kMaxJoints);
  JointVector<S> u = JointVector<S>::Zero();
  for (int k = 0; k < n; ++k) u(k) = map.scale(k) * readings(k);
  coupled.setZero();
  for (int i = 0; i < n; ++i) {
    S sum = S(0);
    for (int k = 0; k < n; ++k) sum = sum + map.coupling(i, k) * u(k);
    coupled(i) = sum;
  }
}

template <class S>
bool invert_coupling(const JointMap<S>& map, CouplingMatrix<S>& a, CouplingMatrix<S>& inverse) noexcept {
  using std::fabs;
  const int n = std::clamp(map.joint_count, 0, kMaxJoints);
  a = map.coupling;
  inverse.setIdentity();
  for (int c = 0; c < n; ++c) {
    int pivot = c;
    for (int r = c + 1; r < n; ++r)
      if (fabs(a(r, c)) > fabs(a(pivot, c))) pivot = r;
    if (!(fabs(a(pivot, c)) >= S(kMinCouplingPivot))) return false;  // NaN too
    if (pivot != c) {
      a.row(c).swap(a.row(pivot));
      inverse.row(c).swap(inverse.row(pivot));
    }
    const S scale = S(1) / a(c, c);
    for (int k = 0; k < n; ++k) {
      a(c, k) = a(c, k) * scale;
      inverse(c, k) = inverse(c, k) * scale;
    }
    for (int r = 0; r < n; ++r) {
      if (r == c) continue;
      const S f = a(r, c);
      for (int k = 0; k < n; ++k) {
        a(r, k) = a(r, k) - f * a(c, k);
        inverse(r, k) = inverse(r, k) - f * inverse(c, k);
      }
    }
  }
  for (int r = 0; r < n; ++r)
    for (int k = 0; k < n; ++k)
      if (!(fabs(inverse(r, k)) < S(1e30))) return false;
  return true;
}

template <class S>
void readings_from_coupled(const JointMap<S>& map, const CouplingMatrix<S>& inverse, const JointVector<S>& coupled,
                           JointVector<S>& readings) noexcept {
  const int n = std::clamp(map.joint_count, 0, kMaxJoints);
  readings.setZero();
  for (int i = 0; i < n; ++i) {
    S sum = S(0);
    for (int k = 0; k < n; ++k) sum = sum + inverse(i, k) * coupled(k);
    readings(i) = sum / map.scale(i);
  }
}

template <class S>
void gravity_forces(const PreparedChain<S>& chain, const ChainFrames<S>& frames, const MassModel<S>& masses,
                    JointVector<S>& forces) noexcept {
  const int n = std::clamp(chain.joint_count, 0, kMaxJoints);
  forces.setZero();
  // frame * p, entry by entry in a fixed order.
  const auto place = [](const RigidTransform<S>& t, const std::array<S, 3>& p) {
    std::array<S, 3> out{};
    for (int r = 0; r < 3; ++r)
      out[static_cast<std::size_t>(r)] =
          t.translation(r) + t.rotation(r, 0) * p[0] + t.rotation(r, 1) * p[1] + t.rotation(r, 2) * p[2];
    return out;
  };
  const Matrix3<S>& base_R_frame0 = frames.base_T_frame[0].rotation;
  const std::array<S, 3>& g0 = masses.gravity_mps2;
  std::array<S, 3> g{};
  for (int r = 0; r < 3; ++r)
    g[static_cast<std::size_t>(r)] =
        base_R_frame0(r, 0) * g0[0] + base_R_frame0(r, 1) * g0[1] + base_R_frame0(r, 2) * g0[2];
  // Total mass and first moment (sum m c, base frame) of the bodies joint i moves.
  S mass = masses.payload_mass_kg;
  std::array<S, 3> moment{};
  {
    const std::array<S, 3> c = place(frames.base_T_frame[static_cast<std::size_t>(n)], masses.payload_centre_of_mass_m);
    for (std::size_t r = 0; r < 3; ++r) moment[r] = mass * c[r];
  }
  for (int i = n - 1; i >= 0; --i) {
    const auto k = static_cast<std::size_t>(i);
    const S m = masses.link_mass_kg[k];
    const std::array<S, 3> c = place(frames.base_T_frame[k + 1], masses.link_centre_of_mass_m[k]);
    mass = mass + m;
    for (std::size_t r = 0; r < 3; ++r) moment[r] = moment[r] + m * c[r];
    const PreparedLink<S>& link = chain.links[k];
    const RigidTransform<S>& frame = frames.base_T_frame[link.convention == LinkConvention::modified_dh ? k + 1 : k];
    const S wx = frame.rotation(0, 2), wy = frame.rotation(1, 2), wz = frame.rotation(2, 2);
    if (link.joint == JointType::revolute) {
      // (moment - mass o) x g, then . z
      const S px = moment[0] - mass * frame.translation(0), py = moment[1] - mass * frame.translation(1),
              pz = moment[2] - mass * frame.translation(2);
      const S tx = py * g[2] - pz * g[1], ty = pz * g[0] - px * g[2], tz = px * g[1] - py * g[0];
      forces(i) = wx * tx + wy * ty + wz * tz;
    } else {
      forces(i) = mass * (wx * g[0] + wy * g[1] + wz * g[2]);
    }
  }
}

template <class S>
void deflect(const PreparedChain<S>& chain, const MassModel<S>& masses, const JointVector<S>& compliance,
             const JointVector<S>& coupled, DeflectionWorkspace<S>& ws, JointVector<S>& deflected) noexcept {
  const int n = std::clamp(chain.joint_count, 0, kMaxJoints);
  joint_trig(chain, coupled, ws.trig);
  forward_kinematics(chain, coupled, ws.trig, ws.frames);
  gravity_forces(chain, ws.frames, masses, ws.forces);
  deflected = coupled;
  for (int i = 0; i < n; ++i) deflected(i) = coupled(i) + compliance(i) * ws.forces(i);
}

template <class S>
void undeflect(const PreparedChain<S>& chain, const MassModel<S>& masses, const JointVector<S>& compliance,
               const JointVector<S>& deflected, int passes, DeflectionWorkspace<S>& ws,
               JointVector<S>& coupled) noexcept {
  const int n = std::clamp(chain.joint_count, 0, kMaxJoints);
  for (int pass = 0; pass < passes; ++pass) {
    joint_trig(chain, coupled, ws.trig);
    forward_kinematics(chain, coupled, ws.trig, ws.frames);
    gravity_forces(chain, ws.frames, masses, ws.forces);
    for (int i = 0; i < n; ++i) coupled(i) = deflected(i) - compliance(i) * ws.forces(i);
  }
}

// The float versions are compiled once, in the library (joint_map.cpp).
extern template void coupled_values(const JointMap<float>&, const JointVector<float>&, JointVector<float>&) noexcept;
extern template bool invert_coupling(const JointMap<float>&, CouplingMatrix<float>&, CouplingMatrix<float>&) noexcept;
extern template void readings_from_coupled(const JointMap<float>&, const CouplingMatrix<float>&,
                                           const JointVector<float>&, JointVector<float>&) noexcept;
extern template void gravity_forces(const PreparedChain<float>&, const ChainFrames<float>&, const MassModel<float>&,
                                    JointVector<float>&) noexcept;
extern template void deflect(const PreparedChain<float>&, const MassModel<float>&, const JointVector<float>&,
                             const JointVector<float>&, DeflectionWorkspace<float>&, JointVector<float>&) noexcept;
extern template void undeflect(const PreparedChain<float>&, const MassModel<float>&, const JointVector<float>&,
                               const JointVector<float>&, int, DeflectionWorkspace<float>&,
                               JointVector<float>&) noexcept;

}  // namespace kincal::core
