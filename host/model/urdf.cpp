#include "host/model/urdf.hpp"

#include <cmath>
#include <cstdio>
#include <sstream>

#include "host/model/xml_text.hpp"

namespace kincal::model {

namespace {

std::string num(double v) {
  if (v == 0.0) v = 0.0;
  char buffer[40];
  std::snprintf(buffer, sizeof buffer, "%.17g", v);
  return buffer;
}

std::string origin(const Transform& t) {
  const Vector3 rpy = rpy_from_rotation(t.rotation);
  return "<origin xyz=\"" + num(t.translation.x()) + " " + num(t.translation.y()) + " " + num(t.translation.z()) +
         "\" rpy=\"" + num(rpy.x()) + " " + num(rpy.y()) + " " + num(rpy.z()) + "\"/>";
}

Transform rx(double angle) {
  Transform t;
  t.rotation = Eigen::AngleAxisd(angle, Vector3::UnitX()).toRotationMatrix();
  return t;
}
Transform rz(double angle) {
  Transform t;
  t.rotation = Eigen::AngleAxisd(angle, Vector3::UnitZ()).toRotationMatrix();
  return t;
}
Transform translate(const Vector3& v) {
  Transform t;
  t.translation = v;
  return t;
}

}  // namespace

std::string write_urdf(const RobotModel& model) {
  const core::ChainModel<double> chain = to_chain(model);
  std::ostringstream out;
  out << "<?xml version=\"1.0\"?>\n";
  out << "<!-- kincal: geometry of '" << escape_xml_text(model.name)
      << "' in the joint origins; joint values are the controller's readings (SI units) -->\n";
  out << "<robot name=\"" << escape_xml_text(model.name) << "\">\n";
  out << "  <link name=\"device\"/>\n";
  Transform previous_s = chain.base_T_frame0;
  std::string parent = "device";
  for (int i = 0; i < model.joint_count(); ++i) {
    const auto k = static_cast<std::size_t>(i);
    const core::Link<double>& link = chain.links[k];
    const core::LinkParameters<double>& p = link.parameters;
    Transform pre, post;
    if (link.convention == core::LinkConvention::modified_dh) {
      pre = rx(p.alpha_rad) * translate(Vector3(p.a_m, 0, 0));
      post = rz(p.theta_rad) * translate(Vector3(0, 0, p.d_m));
    } else {
      post = core::link_transform(link, 0.0);
    }
    const Joint& j = model.joints[k];
    const bool revolute = j.type == core::JointType::revolute;
    const bool limited = std::isfinite(j.lower) && std::isfinite(j.upper);
    const std::string child = "link" + std::to_string(i + 1);
    out << "  <link name=\"" << child << "\"/>\n";
    out << "  <joint name=\"" << escape_xml_text(j.name) << "\" type=\""
        << (revolute ? (limited ? "revolute" : "continuous") : "prismatic") << "\">\n";
    out << "    <parent link=\"" << parent << "\"/>\n    <child link=\"" << child << "\"/>\n";
    out << "    " << origin(previous_s * pre) << "\n    <axis xyz=\"0 0 1\"/>\n";
    if (limited || !revolute) {
      out << "    <limit lower=\"" << num(limited ? j.lower : -1e9) << "\" upper=\"" << num(limited ? j.upper : 1e9)
          << "\" effort=\"0\" velocity=\"0\"/>\n";
    }
    out << "  </joint>\n";
    previous_s = post;
    parent = child;
  }
  out << "  <link name=\"tool\"/>\n";
  out << "  <joint name=\"tool_mount\" type=\"fixed\">\n    <parent link=\"" << parent
      << "\"/>\n    <child link=\"tool\"/>\n";
  out << "    " << origin(previous_s * chain.flange_T_tool) << "\n  </joint>\n";
  out << "</robot>\n";
  return out.str();
}

}  // namespace kincal::model
