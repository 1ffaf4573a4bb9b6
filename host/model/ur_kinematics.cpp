#include "host/model/ur_kinematics.hpp"

#include <cstdint>
#include <cstdio>
#include <sstream>

#include "host/model/number_text.hpp"

namespace kincal::model {

namespace {

Transform rotation_z(double angle) {
  Transform t;
  t.rotation = Eigen::AngleAxisd(angle, Vector3::UnitZ()).toRotationMatrix();
  return t;
}
Transform translation_z(double d) {
  Transform t;
  t.translation = Vector3(0, 0, d);
  return t;
}

// The part of a link before its joint's motion, with the axis along its z: link = head * rest.
Transform link_head(const core::Link<double>& link) {
  const core::LinkParameters<double>& p = link.parameters;
  switch (link.convention) {
    case core::LinkConvention::standard_dh:
      return rotation_z(p.theta_rad) * translation_z(p.d_m);
    case core::LinkConvention::doty:
      return translation_z(p.d_m) * rotation_z(p.theta_rad);
    case core::LinkConvention::modified_dh:
      break;
  }
  return core::link_transform(link, 0.0);
}

std::string size_text(const Transform& t) {
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, "%.3f mm, %.4f deg", t.translation.norm() * 1e3,
                Eigen::AngleAxisd(t.rotation).angle() * 180.0 / 3.14159265358979323846);
  return buffer;
}

}  // namespace

UrKinematics ur_kinematics(const RobotModel& model) {
  if (model.joint_count() != 6)
    throw InputError("ur-kinematics: the model has " + std::to_string(model.joint_count()) + " joints; a UR arm has 6");
  for (const Joint& j : model.joints)
    if (j.type != core::JointType::revolute) throw InputError("ur-kinematics: joint '" + j.name + "' is not revolute");
  const core::ChainModel<double> chain = to_chain(model);
  UrKinematics k;
  Transform previous_rest;  // frame i-1 relative to the joint-(i-1) frame at zero reading
  for (std::size_t i = 0; i < 6; ++i) {
    const core::Link<double>& link = chain.links[i];
    const Transform head = link_head(link);
    k.joint_origins[i] = previous_rest * head;
    previous_rest = head.inverse() * core::link_transform(link, 0.0);
  }
  k.wrist_3_T_flange = previous_rest;
  const auto note = [&](const Transform& t, const std::string& what) {
    if (t.translation.norm() > 1e-12 || Eigen::AngleAxisd(t.rotation).angle() > 1e-12)
      k.notes.push_back(what + " (" + size_text(t) + ") is not in this file");
  };
  note(chain.base_T_frame0, "the base transform base_T_frame0 (the registration to the measuring device)");
  note(k.wrist_3_T_flange, "link 6 beyond the wrist_3 frame (a6, alpha6, beta6)");
  note(chain.flange_T_tool, "the tool flange_T_tool (set the TCP on the controller)");
  return k;
}

std::string write_ur_kinematics(const UrKinematics& kinematics) {
  std::ostringstream body;
  for (std::size_t i = 0; i < 6; ++i) {
    const Transform& t = kinematics.joint_origins[i];
    const Vector3 rpy = rpy_from_rotation(t.rotation);
    body << "  " << kUrKinematicsSections[i] << ":\n";
    const char* names[6] = {"x", "y", "z", "roll", "pitch", "yaw"};
    const double values[6] = {t.translation.x(), t.translation.y(), t.translation.z(), rpy.x(), rpy.y(), rpy.z()};
    for (int v = 0; v < 6; ++v) body << "    " << names[v] << ": " << shortest_number_text(values[v]) << '\n';
  }
  // FNV-1a over the numbers' text: a different calibration gets a different hash.
  std::uint64_t hash = 14695981039346656037ull;
  for (const char c : body.str()) hash = (hash ^ static_cast<unsigned char>(c)) * 1099511628211ull;
  char hex[17];
  std::snprintf(hex, sizeof hex, "%016llx", static_cast<unsigned long long>(hash));
  std::ostringstream out;
  out << "# Written by kincal export --format ur-kinematics: the calibrated joint origins for\n"
      << "# ur_description's kinematics_params_file (metres, radians).\n";
  for (const std::string& n : kinematics.notes) out << "# note: " << n << '\n';
  out << "kinematics:\n" << body.str() << "  hash: kincal_" << hex << '\n';
  return out.str();
}

}  // namespace kincal::model
