#include "host/identify/sag.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <sstream>

#include "host/model/axes.hpp"

namespace kincal::identify {

RobotModel with_identified_masses(const RobotModel& nominal) {
  RobotModel out = nominal;
  for (model::Joint& j : out.joints) {
    j.compliance = 0.0;
    j.identify_mass = true;
    j.mass_kg = kStartMass_kg;
    j.centre_of_mass_m = model::Vector3::Zero();
  }
  out.identify_gravity_direction = true;
  return out;
}

namespace {

// Whether the model identifies a link's mass (geometry+sag), not only uses the given ones.
bool identifies_masses(const RobotModel& model) {
  return std::any_of(model.joints.begin(), model.joints.end(), [](const model::Joint& j) { return j.identify_mass; });
}

// The largest of `largest` (one load per joint) over the joints of joint `link`'s kind.
double most_of_kind(const RobotModel& model, const std::vector<double>& largest, std::size_t link) {
  double most = 0.0;
  for (std::size_t i = 0; i < largest.size(); ++i)
    if (model.joints[i].type == model.joints[link].type) most = std::max(most, largest[i]);
  return most;
}

}  // namespace

std::vector<double> largest_gravity_loads(const RobotModel& model, const model::Dataset& data) {
  std::vector<double> largest(model.joints.size(), 0.0);
  for (const model::Measurement& m : data.rows) {
    const model::ChainAtJoints at = model::chain_at_joints(model, m.q);
    const core::JointVector<double> g = model::gravity_forces(model, at.chain, at.coupled);
    for (std::size_t i = 0; i < largest.size(); ++i)
      largest[i] = std::max(largest[i], std::abs(g(static_cast<Eigen::Index>(i))));
  }
  return largest;
}

GravityLoads compliance_prior_loads(const RobotModel& model, const model::Dataset& data) {
  if (!identifies_masses(model)) return {};
  GravityLoads loads{largest_gravity_loads(model, data), {}};
  for (const model::Joint& j : model.joints) loads.prismatic.push_back(j.type == core::JointType::prismatic);
  return loads;
}

bool needs_sag_start(const RobotModel& model, const IdentifyOptions& options) {
  const bool compliant = std::any_of(model.joints.begin(), model.joints.end(),
                                     [](const model::Joint& j) { return j.compliance.value_or(0.0) > 0.0; });
  return (identifies_masses(model) || model.identify_gravity_direction) && !compliant && options.requested.empty();
}

IdentifyOptions first_sag_stage(const RobotModel& model, const IdentifyOptions& options) {
  IdentifyOptions first = options;
  for (const core::ParameterId& id : model::all_parameters(model))
    if (model::is_mass_parameter(id.kind) || model::is_gravity_direction_parameter(id.kind)) {
      first.fixed.push_back(model::parameter_name(id));
      first.fixed_because.emplace(first.fixed.back(), "the sag's first stage: compliances under the start's masses");
    }
  return first;
}

SagStage second_sag_stage(const RobotModel& model, const IdentifyOptions& options, const RobotModel& first,
                          const model::Dataset& data) {
  SagStage s{model, options, ""};
  for (std::size_t i = 0; i < s.model.joints.size(); ++i) s.model.joints[i].compliance = first.joints[i].compliance;
  // What the data could not tell from the registration or the measured point without masses stays
  // held: the masses' lever arms would otherwise make it "separable" (d6 beside the tool's offset
  // along the last axis moved 180 mm on the zoo's 6-DoF tracker, the TCP with it).
  std::string held;
  if (first.calibration)
    for (const std::string& name : first.calibration->held_fixed) {
      const core::ParameterId id = model::parse_parameter_name(name, static_cast<int>(s.model.joints.size()));
      if (model::is_joint_map_parameter(id.kind)) continue;
      s.options.fixed.push_back(name);
      s.options.fixed_because.emplace(name, "held as the sag's first stage held it");
      held += (held.empty() ? "" : ", ") + name;
    }
  // The reference: the joint whose deflection compliance_i |G_i| is largest over the data's poses.
  std::vector<double> sag = largest_gravity_loads(s.model, data);
  for (std::size_t i = 0; i < sag.size(); ++i) sag[i] *= s.model.joints[i].compliance.value_or(0.0);
  const auto largest = std::max_element(sag.begin(), sag.end());
  if (largest == sag.end() || !(*largest > 0.0)) {
    for (model::Joint& j : s.model.joints) j.identify_mass = j.identify_centre = false;
    s.model.identify_gravity_direction = false;
    s.note =
        "sag: no joint deflects (every compliance 0 after the first stage); the masses, their centres and gravity's "
        "direction are not identified";
    return s;
  }
  if (!identifies_masses(s.model)) {  // the model's own masses: no gauge to fix
    s.note = "sag: gravity's direction and the links' centres of mass identified from the first stage's compliances";
    if (!held.empty()) s.note += "; held as the first stage held them: " + held;
    return s;
  }
  s.options.negative_masses = true;  // see the top: third_sag_stage keeps them at or above 0
  const auto reference = static_cast<std::uint8_t>(largest - sag.begin());
  const std::string name = model::parameter_name({model::kJointCompliance, reference});
  s.options.fixed.push_back(name);
  s.options.fixed_because.emplace(name, "the sag's gauge: only compliance x first moment is observable");
  std::ostringstream note;
  note << "sag: only compliance x first moment is observable; gauge: " << name << " held at "
       << *s.model.joints[reference].compliance * 1e6 << " urad/Nm (its first-stage value with " << kStartMass_kg
       << " kg per link; it deflects most, " << *largest * 180.0 / std::numbers::pi
       << " deg at the data's poses), so the masses are in that gauge's units";
  if (!held.empty()) note << "; held as the first stage held them (not separable without the masses): " << held;
  s.note = note.str();
  return s;
}

std::optional<RobotModel> spread_masses_evenly(const RobotModel& model) {
  const std::vector<double> zero(model.joints.size(), 0.0);
  const core::ChainFrames<double> frames = model::chain_at_joints(model, zero).frames;
  const std::vector<model::AxisLine> axes = model::joint_axes(model, zero);
  // A point in link i's frame (frame i + 1 of the chain, where its centre of mass is given).
  const auto in_link = [&](std::size_t i, const model::Vector3& p) -> model::Vector3 {
    const model::Transform& f = frames.base_T_frame[i + 1];
    return f.rotation.transpose() * (p - f.translation);
  };
  RobotModel out = model;
  std::vector<model::Vector3> moment;
  for (const model::Joint& j : model.joints) moment.push_back(j.mass_kg * j.centre_of_mass_m);
  for (std::size_t first = 0; first < model.joints.size();) {
    if (!model.joints[first].identify_mass) {
      ++first;
      continue;
    }
    std::size_t last = first;  // the run: links first..last, joints first+1..last revolute
    while (last + 1 < model.joints.size() && model.joints[last + 1].identify_mass &&
           model.joints[last + 1].type == core::JointType::revolute)
      ++last;
    double beyond = 0.0;  // the masses of links k..last
    for (std::size_t k = first; k <= last; ++k) beyond += model.joints[k].mass_kg;
    const double mean = beyond / static_cast<double>(last - first + 1);
    if (!(mean > 0.0)) return std::nullopt;
    for (std::size_t k = first + 1; k <= last; ++k) {
      beyond -= model.joints[k - 1].mass_kg;
      // Across joint k, from links k..last to link k - 1: what they hold beyond their share.
      const double moved = beyond - mean * static_cast<double>(last - k + 1);
      moment[k - 1] += moved * in_link(k - 1, axes[k].point);
      moment[k] -= moved * in_link(k, axes[k].point);
    }
    for (std::size_t k = first; k <= last; ++k) {
      out.joints[k].mass_kg = mean;
      out.joints[k].centre_of_mass_m = moment[k] / mean;
    }
    first = last + 1;
  }
  return out;
}

std::optional<SagStage> third_sag_stage(const SagStage& second, const IdentifyResult& solved) {
  const std::vector<model::Joint>& joints = solved.model.joints;
  const auto negative = std::find_if(joints.begin(), joints.end(),
                                     [](const model::Joint& j) { return j.identify_mass && j.mass_kg < 0.0; });
  if (negative == joints.end()) return std::nullopt;
  SagStage s = second;
  s.options.negative_masses = false;
  std::ostringstream note;
  note << "sag: the free-signed solve left link " << (negative - joints.begin()) + 1 << "'s mass at "
       << negative->mass_kg << " kg (only the masses' sums along revolute joints reach the loads); ";
  const std::optional<RobotModel> spread = spread_masses_evenly(solved.model);
  if (!spread) {
    note << "solved again from the start with no mass below 0 (they summed to 0 or less)";
    s.note = note.str();
    return s;
  }
  // The gauge turned so that the masses average the start's again: masses x f, compliances / f.
  double sum = 0.0;
  int count = 0;
  for (const model::Joint& j : spread->joints) {
    if (!j.identify_mass) continue;
    sum += j.mass_kg;
    ++count;
  }
  const double f = kStartMass_kg * count / sum;
  std::string gauge;
  for (std::size_t i = 0; i < s.model.joints.size(); ++i) {
    model::Joint& j = s.model.joints[i];
    j.mass_kg = f * spread->joints[i].mass_kg;
    j.centre_of_mass_m = spread->joints[i].centre_of_mass_m;
    if (j.compliance) *j.compliance /= f;
    const std::string name = model::parameter_name({model::kJointCompliance, static_cast<std::uint8_t>(i)});
    if (std::find(s.options.fixed.begin(), s.options.fixed.end(), name) != s.options.fixed.end()) {
      std::ostringstream g;
      g << name << " at " << j.compliance.value_or(0.0) * 1e6 << " urad/Nm";
      gauge = g.str();
    }
  }
  // The same parameters as the free-signed solve: only what its held masses hold has changed.
  for (const HeldFixed& h : solved.identifiability.held_fixed) {
    const std::string name = model::parameter_name(h.id);
    if (!model::is_mass_parameter(h.id.kind) ||
        std::find(s.options.fixed.begin(), s.options.fixed.end(), name) != s.options.fixed.end())
      continue;
    s.options.fixed.push_back(name);
    s.options.fixed_because.emplace(name, h.reason);
  }
  note << "solved again from the same loads, the masses spread evenly along the chain at " << kStartMass_kg
       << " kg per link (the gauge: " << gauge << "), none below 0";
  s.note = note.str();
  return s;
}

std::optional<SagStage> tilted_sag_stage(const SagStage& stage, const IdentifyResult& solved,
                                         const model::Dataset& data) {
  if (!stage.model.identify_gravity_direction) return std::nullopt;
  ParameterIds compliances;
  for (const HeldFixed& h : solved.identifiability.held_fixed)
    if (h.id.kind == model::kJointCompliance) compliances.push_back(h.id);
  SagStage s = stage;
  s.model.gravity_mps2 = solved.model.gravity_mps2;
  const std::vector<HeldFixed> before = unloaded_compliances(stage.model, data, compliances);
  const std::vector<HeldFixed> after = unloaded_compliances(s.model, data, compliances);
  // A freed compliance's prior (see the header): the default deflection at the most loaded load.
  const std::vector<double> largest = largest_gravity_loads(s.model, data);
  std::string freed;
  for (const HeldFixed& h : before) {
    if (std::any_of(after.begin(), after.end(), [&](const HeldFixed& a) { return a.id.link == h.id.link; })) continue;
    const std::string name = model::parameter_name(h.id);
    freed += (freed.empty() ? "" : ", ") + name;
    const bool prismatic = s.model.joints[h.id.link].type == core::JointType::prismatic;
    const double most = most_of_kind(s.model, largest, h.id.link);
    // First in the list: a prior the caller named for it, in any spelling, comes later and wins.
    if (most > 0.0)
      s.options.prior.sigma.emplace(s.options.prior.sigma.begin(), name,
                                    (prismatic ? s.options.prior.deflection_m : s.options.prior.deflection_rad) / most);
  }
  if (freed.empty()) return std::nullopt;
  const double turn =
      std::acos(std::clamp(stage.model.gravity_mps2.normalized().dot(s.model.gravity_mps2.normalized()), -1.0, 1.0));
  std::ostringstream note;
  note << "sag: solved again with gravity's direction where the fit found it (" << turn * 180.0 / std::numbers::pi
       << " deg from the start's), which loads what the start held as unloaded (" << freed
       << " freed): a sag of compliance x tilt, invisible from a start with neither";
  s.note = note.str();
  return s;
}

std::vector<HeldFixed> unloaded_compliances(const RobotModel& model, const model::Dataset& data,
                                            const ParameterIds& candidates) {
  std::vector<HeldFixed> out;
  const bool any = std::any_of(candidates.begin(), candidates.end(),
                               [](core::ParameterId id) { return id.kind == model::kJointCompliance; });
  if (!any) return out;
  const std::vector<double> largest = largest_gravity_loads(model, data);
  for (const core::ParameterId id : candidates) {
    if (id.kind != model::kJointCompliance) continue;
    const double most = most_of_kind(model, largest, id.link);
    const double share = most > 0.0 ? largest[id.link] / most : 0.0;
    if (share > kUnloadedShare) continue;
    std::ostringstream reason;
    reason.precision(2);
    reason << "gravity barely loads the joint: its largest load over the data is " << share * 100.0
           << " % of the most loaded joint's";
    out.push_back({id, reason.str()});
  }
  return out;
}

void finish_sag_result(IdentifyResult& r, const RobotModel& nominal) {
  for (std::size_t k = 0; k < r.identifiability.identified.size(); ++k) {
    const core::ParameterId id = r.identifiability.identified[k];
    if (id.kind != model::kJointCompliance) continue;
    std::optional<double>& start = r.start.joints.at(id.link).compliance;
    const std::optional<double>& own = nominal.joints.at(id.link).compliance;
    const double from_own = start.value_or(0.0) - own.value_or(0.0);
    r.change(static_cast<Eigen::Index>(k)) += from_own;
    r.prior_centre(static_cast<Eigen::Index>(k)) += from_own;
    start = own;
  }
  RobotModel& model = r.model;
  double carried_kg = model.payload.mass_kg;
  for (std::size_t i = model.joints.size(); i-- > 0;) {
    carried_kg += model.joints[i].mass_kg;
    if (carried_kg == 0.0) model.joints[i].compliance.reset();
    // A link whose mass went to 0 has no centre: whatever the solve left there (hundreds of
    // metres on the zoo) would only make the file unreadable.
    if (model.joints[i].mass_kg == 0.0) model.joints[i].centre_of_mass_m.setZero();
  }
  if (!model.calibration) return;
  model::CalibrationRecord& record = *model.calibration;
  for (std::size_t i = 0; i < model.joints.size(); ++i) {
    const std::string name = model::parameter_name({model::kJointCompliance, static_cast<std::uint8_t>(i)});
    const auto entry = std::find_if(record.parameters.begin(), record.parameters.end(),
                                    [&](const model::ParameterReport& p) { return p.name == name; });
    if (!model.joints[i].compliance) {
      if (entry != record.parameters.end())
        record.erase_parameter(static_cast<std::size_t>(entry - record.parameters.begin()));
    } else if (entry != record.parameters.end()) {
      entry->value = *model.joints[i].compliance;
    } else {
      record.add_parameter({name, *model.joints[i].compliance, 0.0});
    }
  }
}

}  // namespace kincal::identify
