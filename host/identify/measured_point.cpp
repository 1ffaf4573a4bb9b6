#include "host/identify/measured_point.hpp"

#include <algorithm>
#include <iomanip>
#include <sstream>

namespace kincal::identify {

namespace {

bool is_tool_position(core::ParameterId id) {
  return id.kind >= core::ParameterKind::tool_x && id.kind <= core::ParameterKind::tool_z;
}

// Whether the options leave the stage anything to do (see the header).
bool applies(const IdentifyOptions& options, int joint_count) {
  if (!options.estimate_measured_point || options.method == Method::cpa || options.start == Start::cpa) return false;
  for (const std::string& entry : options.fixed)
    for (const core::ParameterId& id : parameter_entry_ids(entry, joint_count))
      if (is_tool_position(id)) return false;
  if (options.requested.empty()) return true;
  bool tool = false, link = false;
  for (const std::string& entry : options.requested)
    for (const core::ParameterId& id : parameter_entry_ids(entry, joint_count)) {
      tool = tool || is_tool_position(id);
      link = link || !model::is_motion_parameter(id.kind);
    }
  return tool && link;
}

}  // namespace

RobotModel with_estimated_measured_point(const RobotModel& start, const model::Dataset& data,
                                         const IdentifyOptions& options, bool orientation_used,
                                         std::vector<std::string>& notes) {
  const int n = start.joint_count();
  if (!applies(options, n)) return start;
  IdentifyOptions fit = options;
  fit.method = Method::full;
  fit.start = Start::nominal;
  fit.estimate_measured_point = false;
  fit.robust = false;
  fit.rejection_gate = false;
  fit.prior.strength = 0.0;
  fit.prior.sigma.clear();
  // Every other parameter held at the start, so that a coordinate of the point the data cannot
  // tell from the registration is held too instead of failing the fit (a SCARA's reflector height
  // along its parallel axes).
  const bool base_fixed = std::any_of(options.fixed.begin(), options.fixed.end(),
                                      [](const std::string& f) { return f.starts_with("base"); });
  const bool frame = orientation_used && start.tool == model::ToolKind::frame;
  fit.requested.clear();
  fit.fixed.clear();
  for (const core::ParameterId& id : candidate_parameters(start)) {
    const bool base = model::is_base_parameter(id.kind);
    const bool tool_turn = id.kind >= core::ParameterKind::tool_rx && id.kind <= core::ParameterKind::tool_rz;
    if ((base && !base_fixed) || is_tool_position(id) || (tool_turn && frame)) continue;
    fit.fixed.push_back(model::parameter_name(id));
  }
  RobotModel out = start;
  std::ostringstream note;
  note.setf(std::ios::fixed);
  note.precision(1);
  try {
    const IdentifyResult r = identify(start, data, fit);
    out.base_T_frame0 = r.model.base_T_frame0;
    out.flange_T_tool = r.model.flange_T_tool;
    note << "the measured point first, at the nominal geometry: "
         << model::flange_T_measured(out).translation.norm() * 1e3 << " mm from the flange (" << model::flange_name(out)
         << "), "
         << (model::flange_T_measured(out).translation - model::flange_T_measured(start).translation).norm() * 1e3
         << " mm from the start's tool, fitting to " << std::setprecision(3) << r.residuals.rms_m * 1e3
         << " mm RMS; what the data identify is decided there";
  } catch (const model::InputError& e) {
    note << "the measured point could not be estimated first (" << e.what()
         << "): what the data identify is decided at the start's tool";
  }
  notes.push_back(note.str());
  return out;
}

}  // namespace kincal::identify
