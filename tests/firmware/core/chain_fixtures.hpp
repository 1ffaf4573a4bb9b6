// Random serial chains for the kinematics tests, and an independent double-precision forward
// kinematics composed from elementary rotations and translations (Eigen's Affine3d), which
// shares no code with firmware/core/link_model.hpp.
#pragma once

#include <Eigen/Dense>
#include <cmath>

#include "firmware/core/error_model.hpp"
#include "firmware/core/joint_map.hpp"
#include "firmware/core/link_model.hpp"
#include "tests/firmware/core/random_source.hpp"

namespace kincal::test {

using core::ChainModel;
using core::JointType;
using core::JointVector;
using core::LinkConvention;

inline Eigen::Affine3d rot(const Eigen::Vector3d& axis, double angle) {
  return Eigen::Affine3d(Eigen::AngleAxisd(angle, axis));
}
inline Eigen::Affine3d trans(const Eigen::Vector3d& v) { return Eigen::Affine3d(Eigen::Translation3d(v)); }

template <class S>
Eigen::Affine3d to_affine(const core::RigidTransform<S>& t) {
  Eigen::Affine3d a = Eigen::Affine3d::Identity();
  a.linear() = t.rotation.template cast<double>();
  a.translation() = t.translation.template cast<double>();
  return a;
}

// Forward kinematics of a chain (with float or double parameters) in double, from the
// elementary transforms of each convention.
template <class S>
Eigen::Affine3d reference_fk(const ChainModel<S>& model, const Eigen::VectorXd& q) {
  const Eigen::Vector3d x = Eigen::Vector3d::UnitX(), y = Eigen::Vector3d::UnitY(), z = Eigen::Vector3d::UnitZ();
  Eigen::Affine3d t = to_affine(model.base_T_frame0);
  for (int i = 0; i < model.joint_count; ++i) {
    const auto& link = model.links[static_cast<std::size_t>(i)];
    const auto& p = link.parameters;
    const bool revolute = link.joint == JointType::revolute;
    const double theta = static_cast<double>(p.theta_rad) + (revolute ? q(i) : 0.0);
    const double d = static_cast<double>(p.d_m) + (revolute ? 0.0 : q(i));
    const double a = static_cast<double>(p.a_m), alpha = static_cast<double>(p.alpha_rad),
                 beta = static_cast<double>(p.beta_rad);
    switch (link.convention) {
      case LinkConvention::standard_dh:
        t = t * rot(z, theta) * trans(d * z) * trans(a * x) * rot(x, alpha);
        break;
      case LinkConvention::modified_dh:
        t = t * rot(x, alpha) * trans(a * x) * rot(z, theta) * trans(d * z);
        break;
      case LinkConvention::doty:
        t = t * trans(d * z) * rot(z, theta) * rot(y, beta) * trans(a * x) * rot(x, alpha);
        break;
    }
  }
  return t * to_affine(model.flange_T_tool);
}

inline core::RigidTransform<double> random_transform(RandomSource& random, double max_offset_m) {
  core::RigidTransform<double> t;
  t.rotation = random.rotation();
  t.translation = Eigen::Vector3d(random.uniform(-1, 1), random.uniform(-1, 1), random.uniform(-1, 1)) * max_offset_m;
  return t;
}

// A random chain of 1..8 links, every convention and joint type mixed.
inline ChainModel<double> random_chain(RandomSource& random, int joint_count) {
  ChainModel<double> m;
  m.joint_count = joint_count;
  for (int i = 0; i < joint_count; ++i) {
    auto& link = m.links[static_cast<std::size_t>(i)];
    link.convention = static_cast<LinkConvention>(random.index(3));
    link.joint = random.index(4) == 0 ? JointType::prismatic : JointType::revolute;
    link.parameters = {random.uniform(-0.5, 0.5), random.uniform(-3.1, 3.1), random.uniform(-1.0, 1.0),
                       random.uniform(-3.1, 3.1), random.uniform(-0.3, 0.3)};
  }
  m.base_T_frame0 = random_transform(random, 0.5);
  m.flange_T_tool = random_transform(random, 0.2);
  return m;
}

inline ChainModel<float> to_float(const ChainModel<double>& m) {
  ChainModel<float> f;
  f.joint_count = m.joint_count;
  for (std::size_t i = 0; i < core::kMaxJoints; ++i) {
    f.links[i].convention = m.links[i].convention;
    f.links[i].joint = m.links[i].joint;
    const auto& p = m.links[i].parameters;
    f.links[i].parameters = {static_cast<float>(p.d_m), static_cast<float>(p.theta_rad), static_cast<float>(p.a_m),
                             static_cast<float>(p.alpha_rad), static_cast<float>(p.beta_rad)};
  }
  f.base_T_frame0.rotation = m.base_T_frame0.rotation.cast<float>();
  f.base_T_frame0.translation = m.base_T_frame0.translation.cast<float>();
  f.flange_T_tool.rotation = m.flange_T_tool.rotation.cast<float>();
  f.flange_T_tool.translation = m.flange_T_tool.translation.cast<float>();
  return f;
}

// A 6R arm with the PUMA 560's geometry (Craig's table, metres) in Doty's convention (beta = 0
// is standard DH), base 0.66 m above the floor and a 0.1 m tool: the arm of the correction's
// tests and benchmarks.
inline ChainModel<double> puma_like_arm() {
  ChainModel<double> m;
  m.joint_count = 6;
  const double half_pi = 1.5707963267948966;
  const double d[6] = {0.0, 0.1501, 0.0, 0.4318, 0.0, 0.0563};
  const double a[6] = {0.0, 0.4318, 0.0203, 0.0, 0.0, 0.0};
  const double alpha[6] = {half_pi, 0.0, -half_pi, half_pi, -half_pi, 0.0};
  for (std::size_t i = 0; i < 6; ++i) {
    m.links[i].convention = LinkConvention::doty;
    m.links[i].parameters = {d[i], 0.0, a[i], alpha[i], 0.0};
  }
  m.base_T_frame0.translation = Eigen::Vector3d(0, 0, 0.6604);
  m.flange_T_tool.translation = Eigen::Vector3d(0.0, 0.0, 0.1);
  return m;
}

// Gravity inputs for puma_like_arm (the joint map's tests and benchmarks): the PUMA 560's
// shoulder and elbow link masses and centres of mass after Armstrong et al. (the wrist's masses,
// centred on their frames), a 3 kg payload 0.1 m out along the flange's z, gravity along -z.
template <class S>
core::MassModel<S> puma_like_masses() {
  core::MassModel<S> m;
  m.link_mass_kg = {S(0), S(17.4), S(4.8), S(0.82), S(0.34), S(0.09)};
  m.link_centre_of_mass_m[1] = {S(-0.3638), S(0.006), S(0.2275)};
  m.link_centre_of_mass_m[2] = {S(-0.0203), S(-0.0141), S(0.070)};
  m.payload_mass_kg = S(3);
  m.payload_centre_of_mass_m = {S(0), S(0), S(0.1)};
  return m;
}

// Every parameter of the set off by exactly +-angle_rad or +-length_m, random signs.
inline core::ErrorVector<double> random_sign_errors(RandomSource& random, const core::ParameterSet& set,
                                                    double angle_rad, double length_m) {
  using core::ParameterKind;
  core::ErrorVector<double> e = core::ErrorVector<double>::Zero();
  for (int i = 0; i < set.count; ++i) {
    const ParameterKind k = set.ids[static_cast<std::size_t>(i)].kind;
    const bool length = k == ParameterKind::link_d || k == ParameterKind::link_a ||
                        (k >= ParameterKind::base_x && k <= ParameterKind::base_z) ||
                        (k >= ParameterKind::tool_x && k <= ParameterKind::tool_z);
    e(i) = random.sign() * (length ? length_m : angle_rad);
  }
  return e;
}

// The smallest singular value of the Jacobian with rotation rows weighted by weight_m: how far
// a configuration is from a singularity, in metres (numeric Jacobian, double).
inline double conditioning_m(const ChainModel<double>& chain, const JointVector<double>& q, double weight_m) {
  const int n = chain.joint_count;
  Eigen::MatrixXd j(6, n);
  for (int i = 0; i < n; ++i) {
    JointVector<double> plus = q, minus = q;
    plus(i) += 1e-6;
    minus(i) -= 1e-6;
    j.col(i) =
        core::small_pose_difference(core::forward_kinematics(chain, plus), core::forward_kinematics(chain, minus)) /
        2e-6;
  }
  j.bottomRows(3) *= weight_m;
  return Eigen::JacobiSVD<Eigen::MatrixXd>(j).singularValues().minCoeff();
}

// A float chain back in double, exactly: the reference for what the float code computes.
inline ChainModel<double> reference_chain(const ChainModel<float>& f) {
  ChainModel<double> m;
  m.joint_count = f.joint_count;
  for (std::size_t i = 0; i < core::kMaxJoints; ++i) {
    m.links[i].convention = f.links[i].convention;
    m.links[i].joint = f.links[i].joint;
    const auto& p = f.links[i].parameters;
    m.links[i].parameters = {static_cast<double>(p.d_m), static_cast<double>(p.theta_rad), static_cast<double>(p.a_m),
                             static_cast<double>(p.alpha_rad), static_cast<double>(p.beta_rad)};
  }
  m.base_T_frame0.rotation = f.base_T_frame0.rotation.cast<double>();
  m.base_T_frame0.translation = f.base_T_frame0.translation.cast<double>();
  m.flange_T_tool.rotation = f.flange_T_tool.rotation.cast<double>();
  m.flange_T_tool.translation = f.flange_T_tool.translation.cast<double>();
  return m;
}

inline Eigen::VectorXd random_joints(RandomSource& random, const ChainModel<double>& m) {
  Eigen::VectorXd q(m.joint_count);
  for (int i = 0; i < m.joint_count; ++i)
    q(i) = m.links[static_cast<std::size_t>(i)].joint == JointType::revolute ? random.uniform(-3.1, 3.1)
                                                                             : random.uniform(-0.5, 0.5);
  return q;
}

template <class S>
JointVector<S> to_joint_vector(const Eigen::VectorXd& q) {
  JointVector<S> v = JointVector<S>::Zero();
  for (int i = 0; i < q.size(); ++i) v(i) = static_cast<S>(q(i));
  return v;
}

inline double rotation_angle(const Eigen::Matrix3d& a, const Eigen::Matrix3d& b) {
  const Eigen::Matrix3d d = a * b.transpose();
  const Eigen::Vector3d axial(d(2, 1) - d(1, 2), d(0, 2) - d(2, 0), d(1, 0) - d(0, 1));
  return std::atan2(0.5 * axial.norm(), 0.5 * (d.trace() - 1.0));
}

// Sum of the chain's lengths: the scale of the rounding error of a position.
inline double chain_length(const ChainModel<double>& m, const Eigen::VectorXd& q) {
  double length = m.base_T_frame0.translation.norm() + m.flange_T_tool.translation.norm();
  for (int i = 0; i < m.joint_count; ++i) {
    const auto& link = m.links[static_cast<std::size_t>(i)];
    length += std::fabs(link.parameters.a_m) +
              std::fabs(link.parameters.d_m + (link.joint == JointType::prismatic ? q(i) : 0.0));
  }
  return length;
}

}  // namespace kincal::test
