#include "host/cli/identify_command.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <memory>
#include <numbers>
#include <optional>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include "host/camera/calibration_file.hpp"
#include "host/cli/model_option.hpp"
#include "host/cli/number_options.hpp"
#include "host/cli/urdf_command.hpp"
#include "host/files/input_file.hpp"
#include "host/files/input_limits.hpp"
#include "host/files/output_file.hpp"
#include "host/identify/data_mistakes.hpp"
#include "host/identify/identify.hpp"
#include "host/identify/model_selection.hpp"
#include "host/identify/plausibility.hpp"
#include "host/model/dataset.hpp"
#include "host/model/isometry.hpp"
#include "host/model/model_file.hpp"
#include "host/model/number_text.hpp"
#include "host/model/ur_kinematics.hpp"
#include "host/model/urdf.hpp"
#include "host/report/identify_report.hpp"

namespace kincal::cli {

namespace {

struct IdentifyArgs {
  ModelOption model;
  std::string data, out, method = "full", start = "nominal", validate, urdf, model_select = "auto", hand_eye,
                         mount = "hand", report, marker_link;
  std::vector<std::string> fix, params, prior;
  double sigma_m = 0.0, orientation_sigma_deg = 0.0, outlier_probability = 1e-3, max_rejected_fraction = 0.05;
  bool no_robust = false, no_model_error = false, accept_implausible = false, no_prior = false;
};

std::string stats_line(const char* what, const identify::AccuracyStats& s) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(4);
  out << "  " << what << ": position mean " << s.mean_m * 1e3 << " mm, rms " << s.rms_m * 1e3 << " mm, max "
      << s.max_m * 1e3 << " mm";
  if (s.has_orientation) {
    const double d = 180.0 / std::numbers::pi;
    out << "; orientation mean " << s.mean_rad * d << " deg, rms " << s.rms_rad * d << " deg, max " << s.max_rad * d
        << " deg";
  }
  return out.str() + "\n";
}

// Where the user stands: the registered nominal beside the calibrated model, on the training
// data and on held-out data, and a one-line verdict.
// `calibrated_held_out`: the calibrated model's accuracy on `held_out` (both null without --validate).
// Without --validate, model selection's K-fold RMS of the chosen model (`selection`, null when it
// did not run) is the held-out figure there is: a model that predicts the rows left out of its
// fits at more than twice the registered nominal's training RMS is one the data do not pin down
// (the real UR10's first 30 rows, the arm's zero pose among them: 24.5 mm against 1.24 mm, and
// 1.46 mm on the 500 held-out rows where the registered nominal gives 0.93).
std::string summary(const IdentifyArgs& a, const model::Dataset& data, const identify::IdentifyResult& result,
                    const std::optional<identify::IdentifyResult>& registered, const model::Dataset* held_out,
                    const identify::AccuracyStats* calibrated_held_out, const identify::Selection* selection) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(3);
  const char* const kBaseline = "nominal, registered";  // base (and tool) fitted, geometry nominal
  const char* const kCalibrated = "calibrated         ";
  if (registered) {
    out << "baseline: the nominal geometry with only the registration and the tool fitted ("
        << registered->identifiability.identified.size() << " parameters)\n";
    out << "training (" << a.data << ", " << result.residuals.count << " measurements used):\n"
        << stats_line(kBaseline, registered->residuals) << stats_line(kCalibrated, result.residuals);
  }
  double before = registered ? registered->residuals.rms_m : 0.0, after = result.residuals.rms_m;
  if (held_out != nullptr) {
    const identify::AccuracyStats& calibrated = *calibrated_held_out;
    out << "validation (" << a.validate << ", " << calibrated.count << " held-out measurements):\n";
    if (registered) {
      const identify::AccuracyStats baseline = identify::accuracy(registered->model, *held_out);
      out << stats_line(kBaseline, baseline);
      before = baseline.rms_m;
    }
    out << stats_line(kCalibrated, calibrated);
    after = calibrated.rms_m;
  }
  std::optional<std::string> unexplained =
      identify::unexplained_fit(result.residuals.rms_m, result.median_instrument_sigma_m);
  // The data's checks again against the calibrated model: its geometry no longer hides a move of
  // the instrument or the logs out of step that the nominal's millimetres did (a service arm); and
  // the move alone whatever the residual (data_mistakes.hpp: moved_against).
  std::vector<std::string> found =
      unexplained ? identify::frame_check(result.model, data).mistakes : std::vector<std::string>{};
  if (found.empty())
    if (const auto moved = identify::moved_against(result.model, data, unexplained.has_value(),
                                                   static_cast<int>(result.identifiability.identified.size())))
      found.push_back(*moved);
  for (const std::string& m : found)
    unexplained = (unexplained ? *unexplained + "; " : std::string()) + "against the calibrated model, " + m;
  if (unexplained) std::cerr << "kincal identify: warning: " << *unexplained << '\n';
  if (result.residuals.has_orientation)
    if (const auto turned = identify::unexplained_orientations(result.residuals.rms_rad, result.orientation_sigma_rad))
      std::cerr << "kincal identify: warning: " << *turned << '\n';
  if (const auto overstated = identify::overstated_noise(result.residuals.rms_m, result.median_instrument_sigma_m,
                                                         3 * result.residuals.count,
                                                         static_cast<int>(result.identifiability.identified.size())))
    std::cerr << "kincal identify: warning: " << *overstated << '\n';
  for (const int j : identify::still_joints(data)) {
    const auto k = static_cast<std::size_t>(j);
    const bool validation_moves =
        held_out != nullptr && std::any_of(held_out->rows.begin(), held_out->rows.end(),
                                           [&](const model::Measurement& r) { return r.q[k] != data.rows[0].q[k]; });
    std::cerr << "kincal identify: warning: joint " << j + 1 << " (" << result.model.joints[k].name
              << ") never moved in " << a.data << " (q" << j + 1 << " = " << data.rows[0].q[k]
              << " in every row): the calibrated model holds at that reading alone"
              << (validation_moves ? std::string("; the --validate rows move it, and their errors include its axis, "
                                                 "which these data could not calibrate")
                                   : std::string())
              << '\n';
  }
  if (!registered) return out.str();
  out << "verdict: ";
  if (unexplained) {
    out << "the data do not fit this model: " << *unexplained << '\n';
    return out.str();
  }
  char numbers[96];
  std::snprintf(numbers, sizeof numbers, "(%.3f mm RMS registered nominal, %.3f mm calibrated)", before * 1e3,
                after * 1e3);
  double kfold = -1.0;  // the chosen candidate's K-fold RMS as the selection table prints it
  if (selection != nullptr)
    for (const identify::CandidateScore& c : selection->scores)
      if (c.name == selection->chosen.name) kfold = c.kfold_rms_m;
  char folds[160] = "";
  if (kfold > 0.0)
    std::snprintf(folds, sizeof folds,
                  "fitted without each of %d folds of the rows in turn, it predicts them at %.3f mm RMS",
                  selection->folds, kfold * 1e3);
  if (held_out == nullptr && kfold > 2.0 * before) {
    char times[64];
    std::snprintf(times, sizeof times, "%.1f times the registered nominal's training RMS", kfold / before);
    out << "the data do not pin this model down " << numbers << ": " << folds << ", " << times
        << ": too few or badly spread configurations, or rows unlike the rest (kincal plan; --model-select "
           "registration or joint-offsets for a smaller model); give --validate with measurements not used here\n";
    std::cerr << "kincal identify: warning: the data do not pin the model down: " << folds << ", " << times << " "
              << numbers << '\n';
  } else if (held_out == nullptr) {
    out << "no held-out data to judge by " << numbers << (kfold > 0.0 ? std::string("; ") + folds : std::string())
        << ": the training residuals flatter a larger model; give --validate with measurements not used here\n";
  } else if (after < before / 1.2) {
    out.precision(1);
    out << "the calibration predicts held-out positions " << before / after << " times better " << numbers << '\n';
  } else if (after <= before * 1.05) {
    out << "the calibration gains little on held-out data " << numbers
        << ": the arm is close to its nominal geometry, or the data cannot tell more (try more, better spread "
           "configurations: kincal plan)\n";
  } else {
    out << "the calibration is WORSE on held-out data " << numbers
        << ": too few or badly spread measurements for its parameters (kincal plan; --params for a smaller "
           "model), or the held-out data differ\n";
  }
  return out.str();
}

// Held-out rows that are training rows judge nothing: all of them is a mistake (refused), some of
// them a warning; rows at training readings measured anew, a warning (data_mistakes.hpp).
void check_held_out(const model::Dataset& held_out, const model::Dataset& training) {
  const identify::SharedRows shared = identify::training_rows_in(held_out, training);
  const std::string of = " of the " + std::to_string(held_out.rows.size()) + " rows of " + held_out.source;
  const std::string rows =
      std::to_string(shared.rows) + of + " are rows of " + training.source + " (the same readings and measured point)";
  if (shared.rows == static_cast<int>(held_out.rows.size()))
    throw model::InputError("--validate " + held_out.source + ": " + rows +
                            ": a validation needs measurements not used for training");
  if (shared.rows > 0)
    std::cerr << "kincal identify: warning: --validate: " << rows
              << ": they flatter the held-out accuracy; leave them out of one of the files\n";
  else if (shared.configurations > 0)
    std::cerr << "kincal identify: warning: --validate: " << shared.configurations << of << " are at readings of "
              << training.source << " measured again: they judge the arm's repeatability more than the calibration\n";
}

// A frame from the flange as a user types it into a controller: mm, and roll-pitch-yaw in deg.
std::string pose_text(const model::Transform& t, bool rotation) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(3);
  const model::Vector3 p = t.translation * 1e3 + model::Vector3::Zero();  // + 0: no "-0.000"
  out << "x " << p.x() << ", y " << p.y() << ", z " << p.z() << " mm";
  if (rotation) {
    const model::Vector3 rpy =
        model::rpy_from_rotation(t.rotation) * (180.0 / std::numbers::pi) + model::Vector3::Zero();
    out << "; roll " << rpy.x() << ", pitch " << rpy.y() << ", yaw " << rpy.z() << " deg";
  }
  return out.str();
}

// The measured point and the TCP, each from the flange it is given from (robot_model.hpp).
std::string frames_lines(const model::RobotModel& m) {
  const std::string flange = model::flange_name(m);
  const bool frame = m.tool == model::ToolKind::frame;
  std::string out =
      "  the measured point (the model's tool: the reflector, marker or board the data measured) from the "
      "flange, " +
      flange + ": " + pose_text(model::flange_T_measured(m), frame) + "\n";
  if (m.flange_T_tcp)
    out += "  on the controller, the TCP from the flange, " + flange + ": " + pose_text(*m.flange_T_tcp, true) +
           " (not calibrated: as given)\n";
  else
    out += "  on the controller, the TCP (the measured point: the model names no other) from the flange, " + flange +
           ": " + pose_text(model::flange_T_measured(m), frame) + "\n";
  return out;
}

// What to do with the calibrated model next.
std::string next_steps(const IdentifyArgs& a, const identify::IdentifyResult& result) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(3);
  out << "next:\n";
  if (a.urdf.empty()) {
    std::string original;  // the robot's own URDF, and the chain in it
    if (model::is_urdf_path(a.model.path)) {
      original = " --original " + a.model.path;
      if (!a.model.ends.base_link.empty()) original += " --base-link " + a.model.ends.base_link;
      if (!a.model.ends.tip_link.empty()) original += " --tip-link " + a.model.ends.tip_link;
    }
    out << "  kincal urdf --model " << a.out << original << " -o calibrated.urdf    # for a ROS stack\n";
  }
  try {
    model::ur_kinematics(result.model);  // refuses a model that is not a UR arm
    out << "  kincal export --format ur-kinematics --model " << a.out
        << " -o ur_calibration.yaml    # the UR description's kinematics_params_file\n";
  } catch (const model::InputError&) {
  }
  out << "  kincal predict --model " << a.out << " --joints q.csv    # where the calibrated arm puts its tool\n";
  out << frames_lines(result.model);
  return out.str();
}

// The option that leaves --model-select no choice (the candidates are full solves from the
// nominal with their own parameters and priors), or "" if none does.
std::string model_fixed_by(const IdentifyArgs& a, const identify::IdentifyOptions& options) {
  std::string not_here;
  if (!a.params.empty()) not_here = "--params";
  if (a.no_prior) not_here = "--no-prior";
  if (options.method != identify::Method::full) not_here = "--method " + a.method;
  if (options.start != identify::Start::nominal) not_here = "--start " + a.start;
  return not_here;
}

// --model-select: auto (cross-validation over the candidate models, model_selection.hpp, with
// enough rows), off (every parameter the model names, the default priors), or a candidate's name.
// Returns the model to identify from (the nominal, or the nominal with scales added); `how` says
// how it was chosen, `selection` holds the table when cross-validation ran.
model::RobotModel choose_model(const IdentifyArgs& a, const model::RobotModel& nominal, const model::Dataset& data,
                               identify::IdentifyOptions& options, std::string& how,
                               std::optional<identify::Selection>& selection) {
  how = "every parameter the model names, the default priors (--model-select " + a.model_select + ")";
  if (a.model_select == "off") return nominal;
  const std::string not_here = model_fixed_by(a, options);
  if (!not_here.empty()) {
    if (a.model_select != "auto")
      throw model::InputError(
          "--model-select " + a.model_select + ": not with " + not_here +
          " (the candidates are full solves from the nominal with their own parameters and priors)");
    how = not_here + " chooses the model";
    std::cout << "model selection: off (" << how << ")\n";
    return nominal;
  }
  if (a.model_select != "auto") {
    const identify::Candidate chosen = identify::find_candidate(nominal, options, a.model_select);
    options = chosen.options;
    how = a.model_select + " (--model-select)";
    std::cout << "model: " << how << '\n';
    return chosen.model;
  }
  if (static_cast<int>(data.rows.size()) < identify::kMinRowsForSelection) {
    how = "every parameter the model names, the default priors (" + std::to_string(data.rows.size()) +
          " rows, fewer than " + std::to_string(identify::kMinRowsForSelection) +
          " for cross-validation: the larger candidates cannot be identified on a fold's rows)";
    std::cout << "model selection: off: " << how << '\n';
    return nominal;
  }
  // It fits every candidate once a fold: minutes on many thousands of rows (15,000 UR10 rows took
  // 90 s on two cores), so it says so first.
  const int rows = static_cast<int>(data.rows.size());
  std::cerr << "kincal identify: choosing the model: " << identify::candidate_models(nominal, options).size()
            << " candidates, each fitted " << identify::selection_folds(rows) + 1 << " times on " << rows << " rows ("
            << identify::parallel_solves() << " at a time)" << std::endl;
  selection = identify::select_model(nominal, data, options);
  std::cout << identify::format_selection(*selection);
  options = selection->chosen.options;
  how = selection->chosen.name + " (chosen by cross-validation)";
  return selection->chosen.model;
}

// What parse_prior_entry (identify/prior.hpp) leaves to the command, which knows the parameter:
// the unit must be of its kind ("theta5=0.2mm" was taken as 0.2 mrad, "a5=0.5" as 0.5 m) and the
// sigma at least model::kMinPriorSigma (1e-160 mm made every standard deviation NaN).
void check_prior_entry(const std::string& entry, const std::pair<std::string, double>& prior,
                       const model::RobotModel& m, core::ParameterId id) {
  if (std::isinf(prior.second)) return;  // no prior
  const std::string value = entry.substr(entry.find('=') + 1);
  char* end = nullptr;
  (void)std::strtod(value.c_str(), &end);
  const std::string unit(end);
  const std::string kind = model::display_unit(m, id).name;  // mm, deg, ppm, urad/Nm or um/N
  const bool fits = kind == "mm"    ? unit == "mm" || unit == "m"
                    : kind == "deg" ? unit == "deg" || unit == "rad"
                                    : unit.empty();
  if (!fits)
    throw model::InputError("--prior '" + entry + "': " + prior.first + " is " +
                            (kind == "mm"    ? "a length: give its unit, mm or m"
                             : kind == "deg" ? "an angle: give its unit, deg or rad"
                                             : "a scale or compliance: give no unit (SI)"));
  if (!(prior.second >= model::kMinPriorSigma))
    throw model::InputError("--prior '" + entry + "': " + model::shortest_number_text(prior.second) +
                            " (m or rad) is below " + model::shortest_number_text(model::kMinPriorSigma) +
                            ", too small for the solve; hold the parameter with --fix instead");
}

// The parameters named by --params or --fix, "base" and "tool" as their six motions; each with
// the entry that named it. Throws InputError naming the option and the entry for an unknown name.
std::vector<std::pair<std::string, std::string>> named_parameters(const std::string& option,
                                                                  const std::vector<std::string>& names,
                                                                  int joint_count) {
  std::vector<std::pair<std::string, std::string>> out;
  for (const std::string& name : names) {
    try {
      for (const core::ParameterId& id : identify::parameter_entry_ids(name, joint_count))
        out.emplace_back(model::parameter_name(id), name);
    } catch (const model::InputError& e) {
      throw model::InputError(option + " '" + name + "': " + e.what());
    }
  }
  return out;
}

// A parameter is identified (--params) or held at its start value (--fix), not both: given both, it
// was reported "fixed on request" and identified all the same.
void refuse_fixed_and_requested(const IdentifyArgs& a, int joint_count) {
  const auto fixed = named_parameters("--fix", a.fix, joint_count);
  for (const auto& [name, entry] : named_parameters("--params", a.params, joint_count))
    for (const auto& [fixed_name, fixed_entry] : fixed)
      if (name == fixed_name)
        throw model::InputError("--params '" + entry + "' and --fix '" + fixed_entry + "' both name " + name +
                                ": a parameter is identified or held fixed, not both");
}

// The models choose_model may give the solve: the nominal, the candidate --model-select names, or
// with cross-validation every candidate (model_selection.hpp: geometry+scales adds a scale to each
// joint, geometry+gravity a compliance).
std::vector<model::RobotModel> models_in_play(const IdentifyArgs& a, const model::RobotModel& nominal,
                                              const identify::IdentifyOptions& options, std::size_t rows) {
  if (a.model_select == "off" || !model_fixed_by(a, options).empty()) return {nominal};
  if (a.model_select != "auto") return {identify::find_candidate(nominal, options, a.model_select).model};
  if (rows < static_cast<std::size_t>(identify::kMinRowsForSelection)) return {nominal};
  std::vector<model::RobotModel> models;
  for (const identify::Candidate& c : identify::candidate_models(nominal, options)) models.push_back(c.model);
  return models;
}

// A prior for a parameter none of `models` has was silently ignored (scale1 for a model whose
// joints declare no scale, tool_rx for a point tool): refused, naming it (`priors`: how each was
// given -- "--prior 'scale1=0.01'" -- and the parameter's name). A parameter the
// solve has but holds fixed or cannot identify may take a prior. The models as identify
// parameterizes them (a link promoted to Doty's convention has a beta); with a CPA start or
// method, the start model's conventions come from the data, so beta<i> is taken for every link.
void refuse_priors_of_absent_parameters(const std::vector<std::pair<std::string, std::string>>& priors,
                                        const std::vector<model::RobotModel>& models,
                                        const identify::IdentifyOptions& options) {
  std::vector<std::string> present;
  for (const model::RobotModel& m : models)
    for (const core::ParameterId& id :
         model::all_parameters(identify::reparameterize_for_identification(m, options.parallel_tolerance_rad, nullptr)))
      present.push_back(model::parameter_name(id));
  if (options.method == identify::Method::cpa || options.start == identify::Start::cpa)
    for (int i = 0; i < models.front().joint_count(); ++i)
      present.push_back(model::parameter_name({core::ParameterKind::link_beta, static_cast<std::uint8_t>(i)}));
  for (const auto& [given, name] : priors)
    if (std::find(present.begin(), present.end(), name) == present.end())
      throw model::InputError(given + ": the model '" + models.front().name + "' has no parameter " + name +
                              (models.size() > 1 ? " (nor has any candidate of --model-select)" : "") +
                              ", so the prior would be ignored");
}

int run_identify(const IdentifyArgs& a) {
  identify::IdentifyOptions options;
  options.method = a.method == "cpa"           ? identify::Method::cpa
                   : a.method == "first-order" ? identify::Method::first_order
                                               : identify::Method::full;
  options.start = a.start == "cpa" ? identify::Start::cpa : identify::Start::nominal;
  options.fixed = a.fix;
  options.requested = a.params;
  options.sigma_m = a.sigma_m;
  options.orientation_sigma_rad = a.orientation_sigma_deg * std::numbers::pi / 180.0;
  options.robust = !a.no_robust;
  options.outlier_probability = a.outlier_probability;
  options.max_rejected_fraction = a.max_rejected_fraction;
  options.model_error = !a.no_model_error;
  try {
    files::refuse_overwriting(
        {{"--out", a.out}, {"--urdf", a.urdf}, {"--hand-eye", a.hand_eye}, {"--report", a.report}},
        {{"--model", a.model.path}, {"--data", a.data}, {"--validate", a.validate}});
    const model::RobotModel nominal = a.model.load();
    refuse_fixed_and_requested(a, nominal.joint_count());
    // Priors: the model file's (a YAML model), then --prior's, which win; each parameter at most
    // once on the command line.
    if (!model::is_urdf_path(a.model.path)) options.prior.sigma = model::load_model_priors(a.model.path);
    // A model file's priors hold for every run of the model: checked against every candidate model
    // (geometry+scales has a scale1 whether or not this run's data choose it).
    std::vector<std::pair<std::string, std::string>> file_priors;  // (how given, parameter name)
    for (const auto& [name, sigma] : options.prior.sigma)
      file_priors.emplace_back(a.model.path + ": priors: " + name, name);
    if (!file_priors.empty()) {
      std::vector<model::RobotModel> models = {nominal};
      for (const identify::Candidate& c : identify::candidate_models(nominal, options)) models.push_back(c.model);
      refuse_priors_of_absent_parameters(file_priors, models, options);
    }
    std::vector<std::pair<std::string, std::string>> prior_entries;  // (--prior 'entry', parameter name)
    for (const std::string& entry : a.prior) {
      options.prior.sigma.push_back(identify::parse_prior_entry(entry));
      core::ParameterId id{};
      try {
        id = model::parse_parameter_name(options.prior.sigma.back().first, nominal.joint_count());
      } catch (const model::InputError& e) {
        throw model::InputError("--prior '" + entry + "': " + e.what());
      }
      const std::string name = model::parameter_name(id);
      for (const auto& [earlier, earlier_name] : prior_entries)
        if (earlier_name == name)
          throw model::InputError(earlier + " and --prior '" + entry + "' both give the prior of " + name +
                                  ": give it once");
      prior_entries.emplace_back("--prior '" + entry + "'", name);
      check_prior_entry(entry, options.prior.sigma.back(), nominal, id);
    }
    if (a.no_prior) options.prior.strength = 0.0;
    if (!a.hand_eye.empty() && nominal.tool != model::ToolKind::frame)
      throw model::InputError(
          "--hand-eye: the model's tool is a point; a camera or a board on the flange is a frame "
          "(tool: frame in the model file)");
    const model::Dataset data = model::read_dataset(a.data);
    if (!prior_entries.empty())
      refuse_priors_of_absent_parameters(prior_entries, models_in_play(a, nominal, options, data.rows.size()), options);
    std::optional<model::Dataset> held_out;  // read before the solve: a bad file fails in a second
    if (!a.validate.empty()) {
      held_out = model::read_dataset(a.validate);
      model::check_joint_count(nominal, held_out->joint_count, held_out->source);
      check_held_out(*held_out, data);
    }
    if (!a.accept_implausible)
      identify::require_plausible(nominal, data, "--accept-implausible", {.noise_given = a.sigma_m > 0});
    std::string model_choice;
    std::optional<identify::Selection> selection;
    const model::RobotModel start = choose_model(a, nominal, data, options, model_choice, selection);
    // The rejection gate reuses model selection's cross-validation of the chosen model.
    identify::IdentifyResult result = selection
                                          ? identify::identify(start, data, options, selection->chosen_cross_validation)
                                          : identify::identify(start, data, options);
    std::cout << "kincal identify: " << nominal.name << " from " << a.data << '\n' << identify::format_report(result);
    // The baseline: the nominal geometry registered to the device, its tool fitted.
    std::optional<identify::IdentifyResult> registered;
    if (a.params.empty() && result.identifiability.identified.size() > 0) {
      try {  // the baseline only informs: without it the calibration still stands
        registered = identify::identify_registration(nominal, data, options, result);
      } catch (const model::InputError& e) {
        std::cout << "baseline: not available (" << e.what() << ")\n";
      }
    }
    std::optional<identify::AccuracyStats> calibrated_held_out;
    if (held_out) calibrated_held_out = identify::accuracy(result.model, *held_out);
    std::cout << summary(a, data, result, registered, held_out ? &*held_out : nullptr,
                         calibrated_held_out ? &*calibrated_held_out : nullptr, selection ? &*selection : nullptr);
    if (calibrated_held_out) result.model.calibration->validation_rms_m = calibrated_held_out->rms_m;
    // Point data determine a point: the model file says so, and `correct` then aims positions only.
    if (!result.orientation_used && options.method != identify::Method::cpa) result.model.tool = model::ToolKind::point;
    // Every output is made before the first is written: a URDF that cannot be written leaves no --out.
    const std::string model_text = model::write_model(result.model);
    std::optional<model::CalibratedUrdf> calibrated_urdf;
    std::string urdf_text;
    if (!a.urdf.empty() && model::is_urdf_path(a.model.path)) {  // the robot's own URDF, calibrated
      // With its byte-order mark, if any: every byte but the changed values is written back.
      calibrated_urdf = model::write_calibrated_urdf(files::read_text(a.model.path, files::kOriginalUrdfFile),
                                                     a.model.path, a.model.ends, result.model, a.marker_link);
      urdf_text = calibrated_urdf->text;
    } else if (!a.urdf.empty()) {
      if (!a.marker_link.empty())
        throw model::InputError(
            "--marker-link: only with a URDF --model (the URDF made from a model file ends at "
            "its tool)");
      urdf_text = model::write_urdf(result.model);
    }
    const std::string hand_eye_text =
        a.hand_eye.empty() ? std::string()
                           : camera::rig_hand_eye_text(a.mount == "hand", model::isometry(result.model.flange_T_tool),
                                                       model::isometry(result.model.base_T_frame0).inverse());
    const std::string report_html = a.report.empty()
                                        ? std::string()
                                        : report::render_html(report::identify_report(
                                              {nominal, data, result, model_choice, selection ? &*selection : nullptr,
                                               registered ? &*registered : nullptr, held_out ? &*held_out : nullptr},
                                              report::utc_date_now()));
    files::write_file_atomically(a.out, model_text);
    std::cout << "wrote " << a.out << '\n';
    if (!a.hand_eye.empty()) {
      files::write_file_atomically(a.hand_eye, hand_eye_text);
      std::cout << "wrote " << a.hand_eye << " (the hand-eye, mount " << a.mount << ", from this solve)\n";
    }
    if (!a.urdf.empty()) {
      files::write_file_atomically(a.urdf, urdf_text);
      std::cout << "wrote " << a.urdf;
      if (calibrated_urdf)
        std::cout << " (" << a.model.path << " with the calibrated joint origins)\n"
                  << print_registration(*calibrated_urdf);
      else
        std::cout << '\n';
    }
    if (!a.report.empty()) {
      report::write_page(report_html, a.report);
      std::cout << "wrote " << a.report << " (the HTML report)\n";
    }
    std::cout << next_steps(a, result);
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "kincal identify: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

void add_identify_command(CLI::App& app, int& status) {
  auto a = std::make_shared<IdentifyArgs>();
  auto* cmd = app.add_subcommand("identify", "Identify a robot's kinematic parameters from measurements");
  add_model_option(*cmd, a->model, "nominal model");
  cmd->add_option(
         "--data", a->data,
         std::string("measurements (CSV: q1..qN,x,y,z[,qw,qx,qy,qz][,cxx..czz|,sigma]; ") + files::kTextLimitText + ")")
      ->required();
  cmd->add_option("--out", a->out, "calibrated model to write (YAML, same schema)")->required();
  cmd->add_option("--report", a->report,
                  "also write an HTML report: the model selection table, each parameter's prior and posterior, the "
                  "residuals against each joint, the rejected rows with their line and id");
  auto* hand_eye =
      cmd->add_option("--hand-eye", a->hand_eye,
                      "also write the identified tool and device registration as `camera hand-eye` does (OpenCV YAML)");
  cmd->add_option("--mount", a->mount,
                  "with --hand-eye: hand (a camera on the flange, the board measures) or world (a board on the flange)")
      ->check(CLI::IsMember({"hand", "world"}))
      ->capture_default_str()
      ->needs(hand_eye);
  cmd->add_option("--method", a->method,
                  "full (default): nonlinear least squares; first-order: Doty's linear model; "
                  "cpa: circle-point analysis")
      ->check(CLI::IsMember({"full", "first-order", "cpa"}));
  auto* start = cmd->add_option("--start", a->start, "where full starts: nominal (default) or cpa")
                    ->check(CLI::IsMember({"nominal", "cpa"}));
  cmd->add_option("--validate", a->validate, "held-out measurements (CSV): accuracy of nominal and calibrated model");
  cmd->add_option("--fix", a->fix, "parameters held at their start value (e.g. base,theta1,tool_z)")->delimiter(',');
  cmd->add_option("--params", a->params, "identify exactly these parameters (error if the data cannot)")
      ->delimiter(',');
  cmd->add_option("--sigma", a->sigma_m,
                  "instrument position noise (m) of rows without covariance (default: none; the model error is "
                  "estimated on top)")
      ->check(finite_positive());
  cmd->add_option("--orientation-sigma-deg", a->orientation_sigma_deg,
                  "instrument orientation noise (deg) of pose measurements (default: none; the model error is "
                  "estimated on top)")
      ->check(finite_in(1e-9, 180.0));
  auto* no_robust = cmd->add_flag("--no-robust", a->no_robust, "reject no outliers");
  cmd->add_option("--outlier-probability", a->outlier_probability,
                  "reject rows whose studentized residual is beyond this tail probability over all rows "
                  "(default 0.001)")
      ->check(finite_in(1e-12, 0.5))
      ->excludes(no_robust);
  cmd->add_option("--max-rejected-fraction", a->max_rejected_fraction,
                  "reject at most this fraction of the rows (default 0.05)")
      ->check(finite_in(0.0, 0.5))
      ->excludes(no_robust);
  auto* prior =
      cmd->add_option(
             "--prior", a->prior,
             "prior sigma of a parameter's deviation from the nominal, NAME=SIGMA with a unit (e.g. "
             "a5=0.5mm,theta5=0.2deg,base_x=inf); defaults, each class rescaled by the data: 1 mm lengths, "
             "0.5 deg angles, base 100 mm / 10 deg, tool 10 mm / 5 deg, scale and coupling 0.01 (each its own class), "
             "an identified mass 1 kg and its centre 0.1 m; these win over the model file's priors:")
          ->delimiter(',');
  cmd->add_option("--model-select", a->model_select,
                  "auto (default, with at least 20 rows): the candidate model chosen by cross-validation (5 folds "
                  "from 100 rows, 10 below, and an out-of-range fold; the default geometry stands unless a "
                  "candidate scores lower and predicts better row by row) among registration, joint-offsets, "
                  "geometry-x2, geometry, geometry-x0.5, geometry-noprior, geometry+nongeometric when the model has "
                  "scales or compliances, geometry+gravity when its links have masses and it declares no "
                  "compliance, geometry+sag when it has neither, geometry+scales when a joint has no scale, "
                  "geometry+couplings when a revolute joint follows a revolute one; off: every parameter, default "
                  "priors; or a candidate's name");
  cmd->add_flag("--no-prior", a->no_prior,
                "no priors: plain least squares (the parameters the data see poorly may run off)")
      ->excludes(prior);
  cmd->add_flag("--no-model-error", a->no_model_error,
                "no model-error variance: the noise is the data's covariance (or --sigma) alone, estimated only "
                "where nothing gives it");
  cmd->add_flag("--accept-implausible", a->accept_implausible,
                "solve even when the data look wrong for the model (units, quaternion order, limits)");
  cmd->add_option(
      "--urdf", a->urdf,
      "also write the calibrated model as URDF (a URDF --model: that URDF with the calibrated joint origins)");
  cmd->add_option("--marker-link", a->marker_link,
                  "with --urdf and a URDF --model: also write the measured point (the tool the data measured: a "
                  "reflector, a marker) as a new link of this name fixed to the tip link; without it no link moves "
                  "beyond the last movable joint and none is added");
  cmd->callback([a, &status, start] {
    if (start->count() > 0 && a->method != "full")
      throw CLI::ValidationError("--start", "--start is where --method full starts: not with --method " + a->method);
    status = run_identify(*a);
  });
}

}  // namespace kincal::cli
