#include "host/correct/correction_block.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "host/identify/problem.hpp"

namespace kincal::correct {

namespace {

float to_float(double v, const std::string& what) {
  if (!std::isfinite(v) || std::abs(v) > static_cast<double>(std::numeric_limits<float>::max()))
    throw model::InputError("correction block: " + what + " = " + std::to_string(v) + " does not fit a float");
  return static_cast<float>(v);
}

shared::DhValues values(const core::LinkParameters<double>& p, const std::string& link) {
  return {to_float(p.a_m, link + " a"), to_float(p.alpha_rad, link + " alpha"), to_float(p.d_m, link + " d"),
          to_float(p.theta_rad, link + " theta"), to_float(p.beta_rad, link + " beta")};
}

}  // namespace

shared::CorrectionParameters correction_block(const model::RobotModel& controller,
                                              const model::RobotModel& identified) {
  const int n = controller.joint_count();
  if (n != identified.joint_count())
    throw model::InputError("correction block: the models have " + std::to_string(n) + " and " +
                            std::to_string(identified.joint_count()) + " joints");
  if (n < 1 || n > static_cast<int>(shared::kJoints))
    throw model::InputError("correction block: " + std::to_string(n) + " joints; the protocol carries 1 to " +
                            std::to_string(shared::kJoints));
  const core::ChainModel<double> a = model::to_chain(controller), b = model::to_chain(identified);
  shared::CorrectionParameters block;
  block.joint_count = static_cast<std::uint8_t>(n);
  for (int j = 0; j < n; ++j) {
    const auto& la = a.links[static_cast<std::size_t>(j)];
    const auto& lb = b.links[static_cast<std::size_t>(j)];
    const std::string name = "joint " + std::to_string(j + 1);
    if (la.joint != lb.joint || la.convention != lb.convention)
      throw model::InputError("correction block: " + name + " differs in type or convention between the models");
    shared::JointModel& m = block.joints[static_cast<std::size_t>(j)];
    m.type = la.joint == core::JointType::prismatic ? shared::JointKind::kPrismatic : shared::JointKind::kRevolute;
    m.convention = la.convention == core::LinkConvention::standard_dh   ? shared::LinkKind::kStandardDh
                   : la.convention == core::LinkConvention::modified_dh ? shared::LinkKind::kModifiedDh
                                                                        : shared::LinkKind::kDoty;
    m.nominal = values(la.parameters, name);
    core::LinkParameters<double> d;
    d.d_m = lb.parameters.d_m - la.parameters.d_m;
    d.theta_rad = lb.parameters.theta_rad - la.parameters.theta_rad;
    d.a_m = lb.parameters.a_m - la.parameters.a_m;
    d.alpha_rad = lb.parameters.alpha_rad - la.parameters.alpha_rad;
    d.beta_rad = lb.parameters.beta_rad - la.parameters.beta_rad;
    m.error = values(d, name + " error");
  }
  // The joint map: the block carries one coupling row and one set of masses per joint; scale and
  // compliance as nominal + identified error. An identified coupling (geometry+couplings) has no
  // place in it. Identified masses (geometry+sag, on an arm whose model has none) are exact in it
  // when the controller's model has no compliance: its masses then act on nothing.
  const bool controller_sags = std::any_of(controller.joints.begin(), controller.joints.end(),
                                           [](const model::Joint& j) { return j.compliance.value_or(0.0) != 0.0; });
  // A calibration writes a link's centre of mass anew where it moved the frame it is given in (the
  // mass stays on its body: model::carry_centres_of_mass); carried back to the controller's
  // geometry it is the controller's own, and the block's one set is the controller's (in the
  // calibrated chain's deflection off by the geometry's change times the sag: second order).
  model::RobotModel carried_back = identified;
  model::carry_centres_of_mass(carried_back, b, a);
  for (int j = 0; j < n; ++j) {
    const model::Joint& ja = controller.joints[static_cast<std::size_t>(j)];
    const model::Joint& jb = identified.joints[static_cast<std::size_t>(j)];
    const std::string name = "joint " + std::to_string(j + 1);
    if (ja.coupling != jb.coupling)
      throw model::InputError("correction block: " + name +
                              "'s coupling row differs between the models (an identified coupling): the block carries "
                              "the controller's row only; correct on the PC (kincal correct) instead");
    const bool masses_differ =
        ja.mass_kg != jb.mass_kg ||
        (carried_back.joints[static_cast<std::size_t>(j)].centre_of_mass_m - ja.centre_of_mass_m).norm() > 1e-9;
    if (masses_differ && controller_sags)
      throw model::InputError("correction block: " + name +
                              "'s mass differs between the models while the controller's model has a compliance: the "
                              "block carries one set of masses");
    const model::Joint& gravity = masses_differ ? jb : ja;
    shared::JointMapValues& m = block.joint_maps[static_cast<std::size_t>(j)];
    m.coupled = !ja.coupling.empty();
    for (std::size_t k = 0; k < ja.coupling.size(); ++k) {
      if (k >= static_cast<std::size_t>(n)) {
        if (ja.coupling[k] != 0.0)
          throw model::InputError("correction block: " + name + "'s coupling names reading " + std::to_string(k + 1) +
                                  " of a " + std::to_string(n) + "-joint arm");
        continue;
      }
      m.coupling[k] = to_float(ja.coupling[k], name + " coupling");
    }
    const double scale = ja.scale.value_or(1.0), compliance = ja.compliance.value_or(0.0);
    m.scale = to_float(scale, name + " scale");
    m.scale_error = to_float(jb.scale.value_or(1.0) - scale, name + " scale error");
    m.compliance = to_float(compliance, name + " compliance");
    m.compliance_error = to_float(jb.compliance.value_or(0.0) - compliance, name + " compliance error");
    m.mass_kg = to_float(gravity.mass_kg, name + " mass");
    for (int k = 0; k < 3; ++k)
      m.centre_of_mass_m[static_cast<std::size_t>(k)] = to_float(gravity.centre_of_mass_m(k), name + " centre of mass");
  }
  if (controller.payload.mass_kg != identified.payload.mass_kg ||
      controller.payload.centre_of_mass_m != identified.payload.centre_of_mass_m)
    throw model::InputError("correction block: the models differ in payload (an input, never identified)");
  // An identified direction of gravity (gravity_rx, gravity_ry) is exact in the block on the same
  // terms as identified masses.
  const bool gravity_differs = controller.gravity_mps2 != identified.gravity_mps2;
  if (gravity_differs && controller_sags)
    throw model::InputError(
        "correction block: gravity's direction differs between the models while the controller's model has a "
        "compliance: the block carries one gravity vector");
  const model::Vector3& gravity = gravity_differs ? identified.gravity_mps2 : controller.gravity_mps2;
  block.payload_mass_kg = to_float(controller.payload.mass_kg, "payload mass");
  for (int k = 0; k < 3; ++k) {
    const auto i = static_cast<std::size_t>(k);
    block.payload_centre_of_mass_m[i] = to_float(controller.payload.centre_of_mass_m(k), "payload centre of mass");
    block.gravity_mps2[i] = to_float(gravity(k), "gravity");
  }
  const model::Vector3 tool_r = identify::so3_log(a.flange_T_tool.rotation);
  const Eigen::Matrix<double, 6, 1> tool_error = identify::small_motion(a.flange_T_tool, b.flange_T_tool);
  for (int k = 0; k < 3; ++k) {
    const auto i = static_cast<std::size_t>(k);
    block.tool_offset[i] = to_float(a.flange_T_tool.translation(k), "tool offset");
    block.tool_offset[i + 3] = to_float(tool_r(k), "tool rotation");
    block.tool_error[i] = to_float(tool_error(k), "tool error");
    block.tool_error[i + 3] = to_float(tool_error(k + 3), "tool rotation error");
  }
  return block;
}

}  // namespace kincal::correct
