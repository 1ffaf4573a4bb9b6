#include "host/identify/discover.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>
#include <sstream>

namespace kincal::identify {

namespace {

const double kDeg = 180.0 / std::numbers::pi;

RobotModel discovery_template(const model::Dataset& data, const std::vector<SweepFit>& fits, const std::string& name) {
  RobotModel t;
  t.name = name;
  t.file_angles = model::AngleUnit::deg;
  t.tool = data.has_orientation ? model::ToolKind::frame : model::ToolKind::point;
  for (const SweepFit& f : fits) {
    model::Joint j;
    j.name = "j" + std::to_string(f.joint + 1);
    j.type = f.type;
    j.convention = core::LinkConvention::standard_dh;
    j.lower = f.q_min;
    j.upper = f.q_max;
    t.joints.push_back(j);
  }
  return t;
}

// The joint's zero-dependent parameter with its offset: theta (revolute) or d (prismatic).
LinkSpread link_values(const model::Joint& j) {
  const bool revolute = j.type == core::JointType::revolute;
  return {j.parameters.theta_rad + (revolute ? j.offset : 0.0), j.parameters.d_m + (revolute ? 0.0 : j.offset),
          j.parameters.a_m, j.parameters.alpha_rad, j.parameters.beta_rad};
}

// A draw of the measured axis from its covariance (axis_covariance in the normal basis).
model::AxisLine draw(const SweepFit& f, std::mt19937_64& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const Eigen::Matrix4d l = f.axis_covariance.llt().matrixL();
  const Eigen::Vector4d x = l * Eigen::Vector4d(n(rng), n(rng), n(rng), n(rng));
  model::AxisLine a = f.axis;
  a.point += f.normal_basis * x.head<2>();
  a.direction = (a.direction + f.normal_basis * x.tail<2>()).normalized();
  return a;
}

}  // namespace

DiscoverResult discover(const model::Dataset& data, const DiscoverOptions& options) {
  if (data.joint_count < 1) throw model::InputError(data.source + ": no joint columns (q1, q2, ...)");
  if (data.joint_count > static_cast<int>(core::kMaxJoints))
    throw model::InputError(data.source + ": " + std::to_string(data.joint_count) + " joint columns; at most " +
                            std::to_string(core::kMaxJoints) + " joints are supported");
  const std::vector<std::optional<core::JointType>> free_types(static_cast<std::size_t>(data.joint_count));
  SweepAnalysis a = analyse_sweeps(data, free_types, data.has_orientation, options.cpa);
  DiscoverResult result;
  const RobotModel tmpl = discovery_template(data, a.fits, options.name);
  const std::vector<double> zero(static_cast<std::size_t>(data.joint_count), 0.0);
  model::AxesToChainOptions axes_options;
  axes_options.parallel_tolerance_rad = options.cpa.parallel_tolerance_rad;
  result.model = model::chain_from_axes(tmpl, a.zero_axes, zero, a.tool_home, axes_options);

  // Spreads of the link parameters: the axes drawn from their covariances, the chain redone.
  const std::size_t n = a.fits.size();
  std::vector<LinkSpread> sum2(n);
  std::mt19937_64 rng(1);
  const auto wrap = [](double x) { return std::remainder(x, 2.0 * std::numbers::pi); };
  for (int s = 0; s < options.samples; ++s) {
    std::vector<model::AxisLine> measured;
    for (const SweepFit& f : a.fits) measured.push_back(draw(f, rng));
    const RobotModel m =
        model::chain_from_axes(tmpl, axes_at_zero(measured, a.sweep_readings), zero, a.tool_home, axes_options);
    for (std::size_t j = 0; j < n; ++j) {
      const LinkSpread v = link_values(m.joints[j]), c = link_values(result.model.joints[j]);
      sum2[j].theta_rad += std::pow(wrap(v.theta_rad - c.theta_rad), 2);
      sum2[j].d_m += std::pow(v.d_m - c.d_m, 2);
      sum2[j].a_m += std::pow(v.a_m - c.a_m, 2);
      sum2[j].alpha_rad += std::pow(wrap(v.alpha_rad - c.alpha_rad), 2);
      sum2[j].beta_rad += std::pow(wrap(v.beta_rad - c.beta_rad), 2);
    }
  }
  const double count = std::max(1, options.samples);
  for (const LinkSpread& s : sum2)
    result.stddev.push_back({std::sqrt(s.theta_rad / count), std::sqrt(s.d_m / count), std::sqrt(s.a_m / count),
                             std::sqrt(s.alpha_rad / count), std::sqrt(s.beta_rad / count)});

  result.notes.push_back(
      "frame 0 (by convention): the device frame moved to the foot of the perpendicular from the device origin onto "
      "axis 1, z along axis 1, x the device's x made normal to it");
  result.notes.push_back("the last link's d, a and alpha are 0 by convention; the tool " +
                         std::string(data.has_orientation ? "frame" : "point") +
                         " takes up the rest; joint limits are the readings "
                         "observed");
  for (const SweepFit& f : a.fits)
    if (!f.test.conclusive)
      result.notes.push_back("joint " + std::to_string(f.joint + 1) +
                             ": the type tests were not conclusive (see the p-values); taken as " +
                             (f.curved ? "revolute" : "prismatic"));
  result.notes.insert(result.notes.end(), a.notes.begin(), a.notes.end());
  result.fits = std::move(a.fits);
  return result;
}

std::string format_discovery(const DiscoverResult& r) {
  std::ostringstream out;
  out.precision(4);
  out << "joints: " << r.fits.size() << '\n';
  for (const SweepFit& f : r.fits) {
    const bool revolute = f.curved;
    out << "joint " << f.joint + 1 << ": " << (revolute ? "revolute" : "prismatic")
        << (f.test.conclusive ? "" : " (inconclusive)") << "; p(line affine in q) = " << f.test.p_line
        << ", p(circle at angle q) = " << f.test.p_circle << ", p(unit-speed line) = " << f.test.p_unit_speed << '\n';
    out << "  axis through (" << f.axis.point.x() << ", " << f.axis.point.y() << ", " << f.axis.point.z()
        << ") m, direction (" << f.axis.direction.x() << ", " << f.axis.direction.y() << ", " << f.axis.direction.z()
        << "); +- " << f.position_stddev_m * 1e3 << " mm, +- " << f.direction_stddev_rad * kDeg << " deg\n";
    out << "  range observed: ";
    if (revolute) {
      out << f.q_min * kDeg << " .. " << f.q_max * kDeg << " deg (" << (f.q_max - f.q_min) * kDeg
          << " deg swept); beacon radius " << f.radius_m * 1e3 << " +- " << f.radius_stddev_m * 1e3 << " mm";
    } else {
      out << f.q_min * 1e3 << " .. " << f.q_max * 1e3 << " mm (" << (f.q_max - f.q_min) * 1e3 << " mm stroke)";
    }
    out << "\n  " << f.used << " points (lines " << f.first_line << "-" << f.last_line << "), fit rms " << f.rms_m * 1e3
        << " mm, noise " << f.noise_scale << " x the stated";
    if (!f.rejected_lines.empty()) {
      out << ", rejected lines";
      for (int l : f.rejected_lines) out << ' ' << l;
    }
    out << '\n';
  }
  out << "link table (theta includes the joint offset; +- 1 sigma):\n";
  for (std::size_t j = 0; j < r.model.joints.size(); ++j) {
    const model::Joint& joint = r.model.joints[j];
    const LinkSpread v = link_values(joint), s = r.stddev[j];
    const bool doty = joint.convention == core::LinkConvention::doty;
    out << "  " << j + 1 << ' ' << (joint.type == core::JointType::revolute ? "R" : "P") << ' '
        << (doty ? "doty" : "dh  ") << "  theta " << v.theta_rad * kDeg << " +- " << s.theta_rad * kDeg << " deg, d "
        << v.d_m * 1e3 << " +- " << s.d_m * 1e3 << " mm, a " << v.a_m * 1e3 << " +- " << s.a_m * 1e3 << " mm, alpha "
        << v.alpha_rad * kDeg << " +- " << s.alpha_rad * kDeg << " deg";
    if (doty) out << ", beta " << v.beta_rad * kDeg << " +- " << s.beta_rad * kDeg << " deg";
    out << '\n';
  }
  const model::Transform& tool = r.model.flange_T_tool;
  out << "tool in the last frame: (" << tool.translation.x() * 1e3 << ", " << tool.translation.y() * 1e3 << ", "
      << tool.translation.z() * 1e3 << ") mm\n";
  for (const std::string& n : r.notes) out << "note: " << n << '\n';
  return out.str();
}

}  // namespace kincal::identify
