// Joint axes as lines in space, and the link parameters that describe a chain of given axes:
// the geometric core of circle-point analysis (host/identify/cpa.hpp) and of comparing models
// written in different conventions.
//
// An axis is the line joint i turns about (revolute, positive q turns counter-clockwise about
// `direction`) or moves along (prismatic, positive q moves along `direction`; only the
// direction is physical, the line is where the tool point moves). Lines are in the device frame.
//
// chain_from_axes() builds frames 0..n on the axes by the classic rules, link by link:
//   dh    frame i on the common normal of axes i and i+1 (skew: unique; intersecting: x along
//         +-z_{i-1} x z_i, a = 0; parallel: the normal through the template's d_i, since any
//         is valid -- the DH discontinuity: for nearly parallel axes the common normal runs off
//         by a / sin(angle)).
//   doty  Doty's construction (his Fig. 3.1): the perpendicular from frame i-1's origin to
//         axis i+1 (d_i = 0 for revolute joints), then theta, beta (pitch about y) and alpha.
//         Continuous for every pair of axes, so it is used wherever consecutive axes are within
//         `parallel_tolerance_rad` of parallel, whatever the template says.
//   mdh   template links in modified DH come out as dh (or doty where nearly parallel).
// Free choices follow the template model, so the result reads like it: frame 0's origin is the
// template's projected onto axis 1 and its x axis the template's made perpendicular; x_i keeps
// the sign of the template's x_i (a_i and alpha_i change sign instead); the last link keeps
// the template's d_n, a_n, alpha_n (beta_n) and the tool takes up the rest.
#pragma once

#include <span>
#include <vector>

#include "host/model/robot_model.hpp"

namespace kincal::model {

struct AxisLine {
  Vector3 point = Vector3::Zero();
  Vector3 direction = Vector3::UnitZ();  // unit
  core::JointType type = core::JointType::revolute;
};

// The axes of `model` at joint readings q.
std::vector<AxisLine> joint_axes(const RobotModel& model, std::span<const double> q);

struct AxesToChainOptions {
  double parallel_tolerance_rad = 0.1;  // below this angle between consecutive axes: doty
};

// A model whose joint axes at readings q_home are `axes` and whose tool (point or frame) is at
// device_T_tool_home, with names, limits, tool kind and free choices from `template_model`.
// Joint offsets take up the difference between the template's theta (revolute) / d (prismatic)
// and the geometry. axes.size() must equal the template's joint count.
RobotModel chain_from_axes(const RobotModel& template_model, std::span<const AxisLine> axes,
                           std::span<const double> q_home, const Transform& device_T_tool_home,
                           const AxesToChainOptions& options = {});

}  // namespace kincal::model
