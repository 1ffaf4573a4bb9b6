#include "host/cli/identify_command.hpp"

#include <fstream>
#include <iostream>
#include <memory>
#include <numbers>
#include <sstream>

#include "host/cli/model_option.hpp"
#include "host/cli/number_options.hpp"
#include "host/cli/urdf_command.hpp"
#include "host/files/input_limits.hpp"
#include "host/files/output_file.hpp"
#include "host/identify/identify.hpp"
#include "host/identify/plausibility.hpp"
#include "host/model/dataset.hpp"
#include "host/model/model_file.hpp"
#include "host/model/urdf.hpp"

namespace kincal::cli {

namespace {

struct IdentifyArgs {
  ModelOption model;
  std::string data, out, method = "full", start = "nominal", validate, urdf;
  std::vector<std::string> fix, params;
  double sigma_m = 0.0, orientation_sigma_deg = 0.0, outlier_probability = 1e-3, max_rejected_fraction = 0.05;
  bool no_robust = false, no_model_error = false, accept_implausible = false;
};

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
    files::refuse_overwriting({{"--out", a.out}, {"--urdf", a.urdf}},
                              {{"--model", a.model.path}, {"--data", a.data}, {"--validate", a.validate}});
    const model::RobotModel nominal = a.model.load();
    const model::Dataset data = model::read_dataset(a.data);
    if (!a.accept_implausible)
      identify::require_plausible(nominal, data, "--accept-implausible", {.noise_given = a.sigma_m > 0});
    identify::IdentifyResult result = identify::identify(nominal, data, options);
    std::cout << "kincal identify: " << nominal.name << " from " << a.data << '\n' << identify::format_report(result);
    if (!a.validate.empty()) {
      const model::Dataset held_out = model::read_dataset(a.validate);
      model::check_joint_count(nominal, held_out.joint_count, held_out.source);
      const identify::AccuracyStats before = identify::accuracy(nominal, held_out);
      const identify::AccuracyStats after = identify::accuracy(result.model, held_out);
      const auto line = [](const char* what, const identify::AccuracyStats& s) {
        std::ostringstream out;
        out.setf(std::ios::fixed);
        out.precision(4);
        out << "  " << what << ": position mean " << s.mean_m * 1e3 << " mm, rms " << s.rms_m * 1e3 << " mm, max "
            << s.max_m * 1e3 << " mm";
        if (s.has_orientation) {
          const double d = 180.0 / std::numbers::pi;
          out << "; orientation mean " << s.mean_rad * d << " deg, rms " << s.rms_rad * d << " deg, max "
              << s.max_rad * d << " deg";
        }
        return out.str();
      };
      std::cout << "validation on " << a.validate << " (" << after.count << " held-out measurements):\n"
                << line("nominal   ", before) << '\n'
                << line("calibrated", after) << '\n';
      result.model.calibration->validation_rms_m = after.rms_m;
    }
    model::save_model(result.model, a.out);
    std::cout << "wrote " << a.out << '\n';
    if (!a.urdf.empty()) {
      if (model::is_urdf_path(a.model.path)) {  // the robot's own URDF, calibrated
        std::ifstream in(a.model.path);
        std::ostringstream original;
        original << in.rdbuf();
        const model::CalibratedUrdf c =
            model::write_calibrated_urdf(original.str(), a.model.path, a.model.ends, result.model);
        files::write_file_atomically(a.urdf, c.text);
        std::cout << "wrote " << a.urdf << " (" << a.model.path << " with the calibrated joint origins)\n"
                  << print_registration(c);
      } else {
        files::write_file_atomically(a.urdf, model::write_urdf(result.model));
        std::cout << "wrote " << a.urdf << '\n';
      }
    }
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
  cmd->add_option("--method", a->method,
                  "full (default): nonlinear least squares; first-order: Doty's linear model; "
                  "cpa: circle-point analysis")
      ->check(CLI::IsMember({"full", "first-order", "cpa"}));
  cmd->add_option("--start", a->start, "where full starts: nominal (default) or cpa")
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
  cmd->add_option("--outlier-probability", a->outlier_probability,
                  "reject rows whose studentized residual is beyond this tail probability over all rows "
                  "(default 0.001)")
      ->check(finite_in(1e-12, 0.5));
  cmd->add_option("--max-rejected-fraction", a->max_rejected_fraction,
                  "reject at most this fraction of the rows (default 0.05)")
      ->check(finite_in(0.0, 0.5));
  cmd->add_flag("--no-robust", a->no_robust, "reject no outliers");
  cmd->add_flag("--no-model-error", a->no_model_error,
                "no model-error variance: the noise is the data's covariance (or --sigma) alone, estimated only "
                "where nothing gives it");
  cmd->add_flag("--accept-implausible", a->accept_implausible,
                "solve even when the data look wrong for the model (units, quaternion order, limits)");
  cmd->add_option(
      "--urdf", a->urdf,
      "also write the calibrated model as URDF (a URDF --model: that URDF with the calibrated joint origins)");
  cmd->callback([a, &status] { status = run_identify(*a); });
}

}  // namespace kincal::cli
