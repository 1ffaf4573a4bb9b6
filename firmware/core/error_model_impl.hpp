// Template definitions of error_model.hpp (the contract is there). Included by it; not a
// public header of its own.
#pragma once

#include <cmath>

#include "firmware/core/error_model.hpp"

namespace kincal::core {

namespace error_model_detail {

enum class Motion : std::uint8_t { rotate, translate };

struct Step {
  Motion motion;
  int axis;  // 0 x, 1 y, 2 z of the moving frame
  ParameterKind kind;
};

// The elementary motions of each convention, in order (link_model.hpp).
inline constexpr std::array<Step, 4> kStandardDhSteps = {{{Motion::rotate, 2, ParameterKind::link_theta},
                                                          {Motion::translate, 2, ParameterKind::link_d},
                                                          {Motion::translate, 0, ParameterKind::link_a},
                                                          {Motion::rotate, 0, ParameterKind::link_alpha}}};
inline constexpr std::array<Step, 4> kModifiedDhSteps = {{{Motion::rotate, 0, ParameterKind::link_alpha},
                                                          {Motion::translate, 0, ParameterKind::link_a},
                                                          {Motion::rotate, 2, ParameterKind::link_theta},
                                                          {Motion::translate, 2, ParameterKind::link_d}}};
inline constexpr std::array<Step, 5> kDotySteps = {{{Motion::translate, 2, ParameterKind::link_d},
                                                    {Motion::rotate, 2, ParameterKind::link_theta},
                                                    {Motion::rotate, 1, ParameterKind::link_beta},
                                                    {Motion::translate, 0, ParameterKind::link_a},
                                                    {Motion::rotate, 0, ParameterKind::link_alpha}}};

inline bool is_link_kind(ParameterKind kind) { return kind <= ParameterKind::link_beta; }

// R * (rotation by (c, s) about the given axis of R's own frame).
template <class S>
void rotate_columns(Matrix3<S>& r, int axis, const SinCos<S>& angle) {
  const int i = (axis + 1) % 3, j = (axis + 2) % 3;
  const Vector3<S> ci = r.col(i), cj = r.col(j);
  r.col(i) = angle.cos * ci + angle.sin * cj;
  r.col(j) = angle.cos * cj - angle.sin * ci;
}

template <class S>
Twist<S> rotation_column(const Vector3<S>& axis, const Vector3<S>& through, const Vector3<S>& tool) {
  Twist<S> column;
  column.template head<3>() = axis.cross(tool - through);
  column.template tail<3>() = axis;
  return column;
}

template <class S>
Twist<S> translation_column(const Vector3<S>& axis) {
  Twist<S> column;
  column.template head<3>() = axis;
  column.template tail<3>().setZero();
  return column;
}

// The column of one link parameter: walk the link's elementary motions from its input frame
// until the parameter's own.
template <class S, std::size_t N>
Twist<S> link_column(const std::array<Step, N>& steps, ParameterKind kind, RigidTransform<S> frame,
                     const PreparedLink<S>& link, const SinCos<S>& theta, const S& d_m, const Vector3<S>& tool) {
  for (const Step& step : steps) {
    const Vector3<S> axis = frame.rotation.col(step.axis);
    if (step.kind == kind) {
      return step.motion == Motion::rotate ? rotation_column<S>(axis, frame.translation, tool)
                                           : translation_column<S>(axis);
    }
    switch (step.kind) {
      case ParameterKind::link_theta:
        rotate_columns(frame.rotation, step.axis, theta);
        break;
      case ParameterKind::link_alpha:
        rotate_columns(frame.rotation, step.axis, link.alpha);
        break;
      case ParameterKind::link_beta:
        rotate_columns(frame.rotation, step.axis, link.beta);
        break;
      case ParameterKind::link_d:
        frame.translation += axis * d_m;
        break;
      default:  // link_a
        frame.translation += axis * link.a_m;
        break;
    }
  }
  return Twist<S>::Zero();  // a parameter the convention does not use (beta in DH)
}

// exp([r]x) by Rodrigues' formula, I + a K + b K^2 with K = [r]x, written out entry by entry
// (small stack). a = sin(t)/t and b = (1 - cos t)/t^2 come from the half angle, which does not
// cancel for small t; below t^2 = 1e-12 their series.
template <class S>
Matrix3<S> rotation_exp(const Vector3<S>& r) {
  using std::sqrt;
  const S angle2 = r.squaredNorm();
  S a, b;
  if (angle2 < S(1e-12)) {
    a = S(1) - angle2 / S(6);
    b = S(0.5) - angle2 / S(24);
  } else {
    const S angle = sqrt(angle2);
    const SinCos<S> half = sin_cos(S(0.5) * angle);
    a = S(2) * half.sin * half.cos / angle;
    b = S(2) * half.sin * half.sin / angle2;
  }
  const S x = r.x(), y = r.y(), z = r.z();
  Matrix3<S> m;
  m << S(1) - b * (y * y + z * z), b * x * y - a * z, b * x * z + a * y,  //
      b * x * y + a * z, S(1) - b * (x * x + z * z), b * y * z - a * x,   //
      b * x * z - a * y, b * y * z + a * x, S(1) - b * (x * x + y * y);
  return m;
}

}  // namespace error_model_detail

template <class S>
ParameterSet full_parameter_set(const ChainModel<S>& model, bool base, bool tool) noexcept {
  ParameterSet set;
  const int n = std::clamp(model.joint_count, 0, kMaxJoints);
  const auto add = [&set](ParameterKind kind, int link) {
    set.ids[static_cast<std::size_t>(set.count++)] = {kind, static_cast<std::uint8_t>(link)};
  };
  for (int i = 0; i < n; ++i) {
    add(ParameterKind::link_d, i);
    add(ParameterKind::link_theta, i);
    add(ParameterKind::link_a, i);
    add(ParameterKind::link_alpha, i);
    if (model.links[static_cast<std::size_t>(i)].convention == LinkConvention::doty) add(ParameterKind::link_beta, i);
  }
  for (int k = 0; k < 6 && base; ++k) add(static_cast<ParameterKind>(static_cast<int>(ParameterKind::base_x) + k), 0);
  for (int k = 0; k < 6 && tool; ++k) add(static_cast<ParameterKind>(static_cast<int>(ParameterKind::tool_x) + k), 0);
  return set;
}

template <class S>
ErrorModelStatus apply_parameter_errors(const ChainModel<S>& nominal, const ParameterSet& set,
                                        const ErrorVector<S>& errors, ChainModel<S>& actual) noexcept {
  if (set.count < 0 || set.count > kMaxErrorParameters) return ErrorModelStatus::bad_parameter;
  const int n = std::clamp(nominal.joint_count, 0, kMaxJoints);
  for (int i = 0; i < set.count; ++i) {
    const ParameterId id = set.ids[static_cast<std::size_t>(i)];
    if (error_model_detail::is_link_kind(id.kind) && id.link >= n) return ErrorModelStatus::bad_parameter;
  }
  actual = nominal;
  Twist<S> base = Twist<S>::Zero(), tool = Twist<S>::Zero();
  for (int i = 0; i < set.count; ++i) {
    const ParameterId id = set.ids[static_cast<std::size_t>(i)];
    const S e = errors(i);
    if (!error_model_detail::is_link_kind(id.kind)) {
      const int k = static_cast<int>(id.kind) - static_cast<int>(ParameterKind::base_x);
      if (k < 6) {
        base(k) += e;
      } else {
        tool(k - 6) += e;
      }
      continue;
    }
    LinkParameters<S>& p = actual.links[id.link].parameters;
    switch (id.kind) {
      case ParameterKind::link_d:
        p.d_m += e;
        break;
      case ParameterKind::link_theta:
        p.theta_rad += e;
        break;
      case ParameterKind::link_a:
        p.a_m += e;
        break;
      case ParameterKind::link_alpha:
        p.alpha_rad += e;
        break;
      default:
        p.beta_rad += e;
        break;
    }
  }
  const auto motion = [](const Twist<S>& t) {
    RigidTransform<S> m;
    m.rotation = error_model_detail::rotation_exp<S>(t.template tail<3>());
    m.translation = t.template head<3>();
    return m;
  };
  actual.base_T_frame0 = nominal.base_T_frame0 * motion(base);
  actual.flange_T_tool = nominal.flange_T_tool * motion(tool);
  return ErrorModelStatus::ok;
}

template <class S>
ErrorModelStatus parameter_jacobian(const PreparedChain<S>& chain, const JointVector<S>& q,
                                    const std::array<SinCos<S>, kMaxJoints>& trig, const ChainFrames<S>& frames,
                                    const ParameterSet& set, ErrorMatrix<S>& error_matrix) noexcept {
  using namespace error_model_detail;
  if (set.count < 0 || set.count > kMaxErrorParameters) return ErrorModelStatus::bad_parameter;
  const int n = std::clamp(chain.joint_count, 0, kMaxJoints);
  const Vector3<S>& tool = frames.base_T_tool.translation;
  for (int i = 0; i < set.count; ++i) {
    const ParameterId id = set.ids[static_cast<std::size_t>(i)];
    Twist<S> column = Twist<S>::Zero();  // every path sets it; zero keeps GCC -O3's maybe-uninitialized quiet
    if (is_link_kind(id.kind)) {
      if (id.link >= n) return ErrorModelStatus::bad_parameter;
      const PreparedLink<S>& link = chain.links[id.link];
      const bool revolute = link.joint == JointType::revolute;
      const SinCos<S> theta = revolute ? angle_sum(link.theta, trig[id.link]) : link.theta;
      const S d = revolute ? link.d_m : S(link.d_m + q(id.link));
      const RigidTransform<S>& input = frames.base_T_frame[id.link];
      switch (link.convention) {
        case LinkConvention::standard_dh:
          column = link_column<S>(kStandardDhSteps, id.kind, input, link, theta, d, tool);
          break;
        case LinkConvention::modified_dh:
          column = link_column<S>(kModifiedDhSteps, id.kind, input, link, theta, d, tool);
          break;
        case LinkConvention::doty:
          column = link_column<S>(kDotySteps, id.kind, input, link, theta, d, tool);
          break;
      }
    } else {
      const int k = static_cast<int>(id.kind) - static_cast<int>(ParameterKind::base_x);
      const RigidTransform<S>& frame = k < 6 ? frames.base_T_frame[0] : frames.base_T_tool;
      const int axis = k % 3;
      const Vector3<S> w = frame.rotation.col(axis);
      column = (k % 6) < 3 ? translation_column<S>(w) : rotation_column<S>(w, frame.translation, tool);
    }
    error_matrix.col(i) = column;
  }
  return ErrorModelStatus::ok;
}

template <class S>
void joint_jacobian(const PreparedChain<S>& chain, const ChainFrames<S>& frames, JointJacobian<S>& jacobian) noexcept {
  const int n = std::clamp(chain.joint_count, 0, kMaxJoints);
  // Raw column-major storage through a restrict pointer: this runs at the control rate, and
  // without it every store would make the compiler reload the frames.
  S* __restrict out = jacobian.data();
  const S tx = frames.base_T_tool.translation(0), ty = frames.base_T_tool.translation(1),
          tz = frames.base_T_tool.translation(2);
  for (int i = 0; i < kMaxJoints; ++i, out += 6) {
    if (i >= n) {
      for (int k = 0; k < 6; ++k) out[k] = S(0);
      continue;
    }
    const auto k = static_cast<std::size_t>(i);
    const PreparedLink<S>& link = chain.links[k];
    // The joint's axis: z of the link's input frame (DH, Doty) or of its output frame (modified
    // DH, whose joint motion comes last).
    const RigidTransform<S>& frame = frames.base_T_frame[link.convention == LinkConvention::modified_dh ? k + 1 : k];
    const S wx = frame.rotation(0, 2), wy = frame.rotation(1, 2), wz = frame.rotation(2, 2);
    if (link.joint == JointType::revolute) {
      const S dx = tx - frame.translation(0), dy = ty - frame.translation(1), dz = tz - frame.translation(2);
      out[0] = mul_add(wy, dz, -(wz * dy));
      out[1] = mul_add(wz, dx, -(wx * dz));
      out[2] = mul_add(wx, dy, -(wy * dx));
      out[3] = wx;
      out[4] = wy;
      out[5] = wz;
    } else {
      out[0] = wx;
      out[1] = wy;
      out[2] = wz;
      out[3] = S(0);
      out[4] = S(0);
      out[5] = S(0);
    }
  }
}

}  // namespace kincal::core
