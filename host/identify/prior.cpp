#include "host/identify/prior.hpp"

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <numbers>

#include "host/model/robot_model.hpp"

namespace kincal::identify {

namespace {

bool same_parameter(core::ParameterId a, core::ParameterId b) {
  return model::parameter_name(a) == model::parameter_name(b);
}

double default_sigma(const PriorOptions& o, core::ParameterId id, const GravityLoads& loads) {
  using K = core::ParameterKind;
  if (id.kind == model::kJointScale) return o.scale;
  if (id.kind == model::kJointCompliance) {
    const double load = id.link < loads.largest.size() ? loads.largest[id.link] : 0.0;
    if (!(load > 0.0)) return std::numeric_limits<double>::infinity();
    return (loads.prismatic.at(id.link) ? o.deflection_m : o.deflection_rad) / load;
  }
  if (id.kind == model::kLinkMass) return o.mass_kg;
  if (model::is_mass_parameter(id.kind)) return o.centre_m;
  if (id.kind == model::kJointCoupling) return o.coupling;
  if (model::is_gravity_direction_parameter(id.kind)) return o.gravity_direction_rad;
  switch (id.kind) {
    case K::link_d:
    case K::link_a:
      return o.length_m;
    case K::link_theta:
    case K::link_alpha:
    case K::link_beta:
      return o.angle_rad;
    case K::base_x:
    case K::base_y:
    case K::base_z:
      return o.base_length_m;
    case K::base_rx:
    case K::base_ry:
    case K::base_rz:
      return o.base_angle_rad;
    case K::tool_x:
    case K::tool_y:
    case K::tool_z:
      return o.tool_length_m;
    default:
      return o.tool_angle_rad;
  }
}

}  // namespace

std::vector<bool> given_centres(const RobotModel& model) {
  std::vector<bool> out;
  for (const model::Joint& j : model.joints) out.push_back(j.identify_centre && !j.identify_mass);
  return out;
}

bool is_given_centre(core::ParameterId id, const std::vector<bool>& given_centres) {
  return model::is_mass_parameter(id.kind) && id.kind != model::kLinkMass && id.link < given_centres.size() &&
         given_centres[id.link];
}

Eigen::VectorXd prior_sigmas(const PriorOptions& options, const ParameterIds& ids, int joint_count,
                             const std::string& where, const GravityLoads& loads,
                             const std::vector<bool>& given_centres) {
  Eigen::VectorXd s(static_cast<Eigen::Index>(ids.size()));
  for (std::size_t k = 0; k < ids.size(); ++k)
    s(static_cast<Eigen::Index>(k)) =
        is_given_centre(ids[k], given_centres) ? options.given_centre_m : default_sigma(options, ids[k], loads);
  for (const auto& [name, sigma] : options.sigma) {
    core::ParameterId id{};
    try {
      id = model::parse_parameter_name(name, joint_count);
    } catch (const model::InputError& e) {
      throw model::InputError(where + ": prior of '" + name + "': " + e.what());
    }
    if (!(sigma > 0.0))
      throw model::InputError(where + ": prior of '" + name + "': the sigma must be positive (or inf for none)");
    for (std::size_t k = 0; k < ids.size(); ++k)
      if (same_parameter(ids[k], id)) s(static_cast<Eigen::Index>(k)) = sigma;
  }
  return s;
}

Eigen::VectorXd prior_weights(const PriorOptions& options, const Eigen::VectorXd& sigmas) {
  Eigen::VectorXd w(sigmas.size());
  for (Eigen::Index k = 0; k < sigmas.size(); ++k) w(k) = std::isfinite(sigmas(k)) ? options.strength / sigmas(k) : 0.0;
  return w;
}

std::pair<std::string, double> parse_prior_entry(const std::string& entry) {
  const std::size_t eq = entry.find('=');
  const auto fail = [&](const std::string& why) -> std::pair<std::string, double> {
    throw model::InputError("--prior '" + entry + "': " + why +
                            " (expected NAME=SIGMA with a unit: mm, m, deg or rad, kg for mass<i>, none for "
                            "scale<i>, compliance<i> and coupling<i>_<i-1>; inf for no prior)");
  };
  if (eq == std::string::npos || eq == 0) return fail("no NAME=");
  const std::string name = entry.substr(0, eq), value = entry.substr(eq + 1);
  if (value == "inf") return {name, std::numeric_limits<double>::infinity()};
  const char* begin = value.c_str();
  char* end = nullptr;
  errno = 0;
  const double number = std::strtod(begin, &end);
  if (end == begin || errno != 0 || !std::isfinite(number)) return fail("no number after '='");
  const std::string unit(end);
  double per_unit = 1.0;
  if (unit == "mm") {
    per_unit = 1e-3;
  } else if (unit == "deg") {
    per_unit = std::numbers::pi / 180.0;
  } else if (unit != "m" && unit != "rad" && unit != "kg" && !unit.empty()) {
    return fail("unknown unit '" + unit + "'");
  }
  if (!(number > 0.0)) return fail("the sigma must be positive");
  return {name, number * per_unit};
}

}  // namespace kincal::identify
