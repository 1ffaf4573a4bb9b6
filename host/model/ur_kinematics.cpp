#include "host/model/ur_kinematics.hpp"

#include <cstdint>
#include <cstdio>
#include <numbers>
#include <sstream>

#include "host/model/number_text.hpp"
#include "host/model/urdf.hpp"

namespace kincal::model {

namespace {

// The part of a link before its joint's motion, with the axis along its z: link = head * rest.
// Standard DH: Rz(theta) Tz(d); Doty: Tz(d) Rz(theta) -- the link with a, alpha, beta zeroed.
// Modified DH: the whole link (its axis is z of the frame after it).
Transform link_head(const core::Link<double>& link) {
  if (link.convention == core::LinkConvention::modified_dh) return core::link_transform(link, 0.0);
  core::Link<double> head = link;
  head.parameters.a_m = head.parameters.alpha_rad = head.parameters.beta_rad = 0.0;
  return core::link_transform(head, 0.0);
}

std::string size_text(const Transform& t) {
  char buffer[96];
  std::snprintf(buffer, sizeof buffer, "%.3f mm, %.4f deg", t.translation.norm() * 1e3,
                Eigen::AngleAxisd(t.rotation).angle() * 180.0 / std::numbers::pi);
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
  if (const std::string n = non_geometric_note(model); !n.empty()) k.notes.push_back(n);
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
