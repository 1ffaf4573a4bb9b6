#include "host/model/ur_kinematics.hpp"

#include <algorithm>
#include <cmath>
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

// The angle (deg) between two axis directions, as lines (0 to 90).
double line_angle_deg(const Eigen::Vector3d& u, const Eigen::Vector3d& v) {
  return std::acos(std::min(1.0, std::abs(u.normalized().dot(v.normalized())))) * 180.0 / std::numbers::pi;
}

// A UR arm's axes at zero readings: 2 across 1, 2, 3 and 4 parallel, 5 across 4, 6 across 5.
// A calibrated arm stays within a few degrees of that; another arm (a PUMA's wrist is spherical,
// its axis 4 across 3) does not, and its joints have no place in UR's file.
void require_ur_layout(const RobotModel& model, const std::array<Transform, 6>& joint_origins) {
  constexpr double kToleranceDeg = 5.0;
  std::array<Eigen::Vector3d, 6> axes;
  Transform frame;
  for (std::size_t i = 0; i < 6; ++i) {
    frame = frame * joint_origins[i];
    axes[i] = frame.rotation.col(2);
  }
  const struct {
    std::size_t a, b;
    bool parallel;
  } rules[] = {{0, 1, false}, {1, 2, true}, {2, 3, true}, {3, 4, false}, {4, 5, false}};
  for (const auto& r : rules) {
    const double angle = line_angle_deg(axes[r.a], axes[r.b]);
    const double off = r.parallel ? angle : 90.0 - angle;
    if (off > kToleranceDeg) {
      char text[200];
      std::snprintf(text, sizeof text, "axes %zu and %zu are %.1f deg apart where a UR arm's are %s", r.a + 1, r.b + 1,
                    angle, r.parallel ? "parallel" : "perpendicular");
      throw InputError("ur-kinematics: '" + model.name + "' is not a Universal Robots arm: " + text +
                       " (UR's file holds a UR arm's six joint origins; for another robot use `kincal urdf`)");
    }
  }
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
  require_ur_layout(model, k.joint_origins);
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
