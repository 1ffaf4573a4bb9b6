#include "host/model/axes.hpp"

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace kincal::model {

namespace {

double wrap_angle(double a) { return std::remainder(a, 2.0 * std::numbers::pi); }

// `v` made perpendicular to unit `axis` and normalized; `fallback` when v is (nearly) along it.
Vector3 perpendicular(const Vector3& v, const Vector3& axis, const Vector3& fallback) {
  Vector3 p = v - v.dot(axis) * axis;
  if (p.norm() < 1e-9) p = fallback - fallback.dot(axis) * axis;
  if (p.norm() < 1e-9) p = axis.unitOrthogonal();
  // Once more: for v within 1e-8 rad of the axis, rounding leaves p a component along it of
  // about eps / |p|, and frames built on it were 2e-9 off orthonormal (found by fuzz.urdf).
  p = p.normalized();
  return (p - p.dot(axis) * axis).normalized();
}

struct Frame {
  Vector3 origin;
  Matrix3 rotation;  // columns x, y, z
};

// The frame at `origin` whose z is the unit axis direction `z` and whose x is `x` (unit, normal to z).
Frame frame_on_axis(const Vector3& origin, const Vector3& x, const Vector3& z) {
  Frame f;
  f.origin = origin;
  f.rotation.col(0) = x;
  f.rotation.col(1) = z.cross(x);
  f.rotation.col(2) = z;
  return f;
}

// x_i keeps the sign of the template's x_i (x_hint): when x points against it, x and the link
// length `a` along it change sign.
void keep_sign_of_hint(Vector3& x, double& a, const Vector3& x_hint) {
  if (x.dot(x_hint) < 0.0) {
    x = -x;
    a = -a;
  }
}

// The geometric value of link i's joint-dependent parameter at home (theta or d), the other
// parameters, and the next frame.
struct LinkResult {
  core::LinkParameters<double> parameters;  // theta / d at home, q included
  Frame next;
};

LinkResult dh_link(const Frame& f, const AxisLine& next_axis, double d_template, const Vector3& x_hint,
                   double parallel_tolerance) {
  const Vector3 z = f.rotation.col(2);
  const Vector3& u = next_axis.direction;
  const Vector3 w0 = f.origin - next_axis.point;
  const double b = z.dot(u);
  double s = 0.0;
  const double sine = z.cross(u).norm();
  const bool parallel = sine <= std::sin(parallel_tolerance) * 1e-3;
  if (!parallel) {
    const double denom = 1.0 - b * b;
    s = (b * u.dot(w0) - z.dot(w0)) / denom;
  } else {
    s = d_template;  // parallel: any normal will do, take the template's
  }
  const Vector3 a_point = f.origin + s * z;
  const Vector3 b_point = next_axis.point + (a_point - next_axis.point).dot(u) * u;
  const Vector3 n = b_point - a_point;
  double a = n.norm();
  Vector3 x;
  if (!parallel) {
    // Skew or intersecting: the common normal is along z x u, exactly normal to both axes. (Its
    // direction from the foot points, n / a, is off by eps |w0| / a: 1e-7 rad where the axes
    // pass within 1e-9 m of each other.)
    x = z.cross(u) / sine;
    a = n.dot(x);
    if (a < 0.0) {
      x = -x;
      a = -a;
    }
    if (a <= 1e-12) a = 0.0;
  } else {
    x = a > 1e-12 ? Vector3(n / a) : perpendicular(z.cross(u), z, x_hint);
    if (a <= 1e-12) {
      x = perpendicular(x, u, x_hint);
      a = 0.0;
    }
  }
  keep_sign_of_hint(x, a, x_hint);
  LinkResult r;
  r.parameters.d_m = s;
  r.parameters.a_m = a;
  r.parameters.theta_rad = std::atan2(x.dot(f.rotation.col(1)), x.dot(f.rotation.col(0)));
  r.parameters.alpha_rad = std::atan2(z.cross(u).dot(x), z.dot(u));
  r.next = frame_on_axis(b_point, x, u);
  return r;
}

LinkResult doty_link(const Frame& f, const AxisLine& next_axis, double d_template, const Vector3& x_hint) {
  const Vector3 xp = f.rotation.col(0), yp = f.rotation.col(1), z = f.rotation.col(2);
  const Vector3& u = next_axis.direction;
  const Vector3 a_point = f.origin + d_template * z;
  const Vector3 b_point = next_axis.point + (a_point - next_axis.point).dot(u) * u;
  const Vector3 w = b_point - a_point;
  double a = w.norm();
  // x normal to u to the last bit: w is, up to the rounding of points far out (1e-14 m at 400 m),
  // and where the axes pass 1e-6 m apart that tilted x 3e-8 rad off normal, and the link's alpha
  // and beta, fitted to a frame that was not one, turned axis i + 1 by 2e-9 rad (fuzz.urdf,
  // urdf_regressions/nearly_parallel_axes_1e-6_m_apart.urdf).
  Vector3 x = a > 1e-12 ? perpendicular(w, u, z.cross(u)) : perpendicular(x_hint, u, z.cross(u));
  if (a <= 1e-12) a = 0.0;
  keep_sign_of_hint(x, a, x_hint);
  LinkResult r;
  r.parameters.d_m = d_template;
  r.parameters.a_m = a;
  const double theta = std::atan2(x.dot(yp), x.dot(xp));
  const Vector3 x1 = std::cos(theta) * xp + std::sin(theta) * yp;
  const Vector3 y1 = -std::sin(theta) * xp + std::cos(theta) * yp;
  const double beta = std::atan2(-x.dot(z), x.dot(x1));
  const Vector3 z2 = x.cross(y1);
  r.parameters.theta_rad = theta;
  r.parameters.beta_rad = beta;
  r.parameters.alpha_rad = std::atan2(-u.dot(y1), u.dot(z2));
  r.next = frame_on_axis(b_point, x, u);
  return r;
}

}  // namespace

std::vector<AxisLine> joint_axes(const RobotModel& model, std::span<const double> q) {
  const core::ChainFrames<double> frames = chain_at_joints(model, q).frames;
  std::vector<AxisLine> axes;
  for (std::size_t i = 0; i < model.joints.size(); ++i) {
    const bool modified = model.joints[i].convention == core::LinkConvention::modified_dh;
    const Transform& f = frames.base_T_frame[modified ? i + 1 : i];
    axes.push_back({f.translation, f.rotation.col(2), model.joints[i].type});
  }
  return axes;
}

RobotModel chain_from_axes(const RobotModel& template_model, std::span<const AxisLine> axes,
                           std::span<const double> q_home, const Transform& device_T_tool_home,
                           const AxesToChainOptions& options) {
  const std::size_t n = template_model.joints.size();
  if (axes.size() != n || q_home.size() != n) throw std::invalid_argument("chain_from_axes: joint count mismatch");
  const core::ChainFrames<double> hints = chain_at_joints(template_model, q_home).frames;

  RobotModel out = template_model;
  // Frame 0 on axis 1.
  const Transform& t0 = hints.base_T_frame[0];
  const Vector3 z0 = axes[0].direction.normalized();
  const Vector3 origin0 = axes[0].type == core::JointType::revolute
                              ? Vector3(axes[0].point + (t0.translation - axes[0].point).dot(z0) * z0)
                              : t0.translation;
  Frame f = frame_on_axis(origin0, perpendicular(t0.rotation.col(0), z0, t0.rotation.col(1)), z0);
  out.base_T_frame0.translation = f.origin;
  out.base_T_frame0.rotation = f.rotation;

  for (std::size_t i = 0; i < n; ++i) {
    const Joint& tj = template_model.joints[i];
    Joint& j = out.joints[i];
    const bool revolute = tj.type == core::JointType::revolute;
    const bool template_modified = tj.convention == core::LinkConvention::modified_dh;
    // The template's d at home (prismatic: with offset and reading), used where d is a free choice.
    const double d_template = template_modified ? 0.0 : tj.parameters.d_m + (revolute ? 0.0 : tj.offset + q_home[i]);
    core::LinkParameters<double> geometric;
    Frame next;
    if (i + 1 < n) {
      const Vector3 x_hint = hints.base_T_frame[i + 1].rotation.col(0);
      AxisLine next_axis = axes[i + 1];
      next_axis.direction.normalize();
      const double angle = std::acos(std::min(1.0, std::abs(f.rotation.col(2).dot(next_axis.direction))));
      const bool use_doty = tj.convention == core::LinkConvention::doty || angle < options.parallel_tolerance_rad;
      LinkResult r = use_doty ? doty_link(f, next_axis, d_template, x_hint)
                              : dh_link(f, next_axis, d_template, x_hint, options.parallel_tolerance_rad);
      j.convention = use_doty ? core::LinkConvention::doty : core::LinkConvention::standard_dh;
      geometric = r.parameters;
      next = r.next;
    } else {
      // The last link: the template's parameters (a modified-DH template gets a plain DH link).
      j.convention = template_modified ? core::LinkConvention::standard_dh : tj.convention;
      geometric = template_modified ? core::LinkParameters<double>{} : tj.parameters;
      if (template_modified) geometric.theta_rad = tj.parameters.theta_rad;
      if (revolute) {
        geometric.theta_rad += tj.offset + q_home[i];
      } else {
        geometric.d_m += tj.offset + q_home[i];
      }
      core::Link<double> link{j.convention, tj.type, geometric};
      const Transform step = core::link_transform(link, 0.0);
      Transform frame;
      frame.translation = f.origin;
      frame.rotation = f.rotation;
      const Transform nf = frame * step;
      next.origin = nf.translation;
      next.rotation = nf.rotation;
    }
    // Split the joint-dependent parameter into the template's nominal value and the offset.
    j.parameters = geometric;
    double& variable = revolute ? j.parameters.theta_rad : j.parameters.d_m;
    const double home = variable;
    const bool same_family = !template_modified;
    const double nominal = revolute ? tj.parameters.theta_rad : tj.parameters.d_m;
    if (same_family) {
      variable = nominal;
      j.offset = home - nominal - q_home[i];
    } else {
      variable = home - q_home[i] - tj.offset;
      j.offset = tj.offset;
    }
    if (revolute) j.offset = wrap_angle(j.offset);
    f = next;
  }
  Transform flange;
  flange.translation = f.origin;
  flange.rotation = f.rotation;
  const Transform flange_T_tool = flange.inverse() * device_T_tool_home;
  if (out.tool == ToolKind::point) {
    out.flange_T_tool = Transform{};
    out.flange_T_tool.translation = flange_T_tool.translation;
  } else {
    out.flange_T_tool = flange_T_tool;
  }
  out.calibration.reset();
  return out;
}

}  // namespace kincal::model
