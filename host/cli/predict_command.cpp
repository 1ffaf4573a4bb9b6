#include "host/cli/predict_command.hpp"

#include <charconv>
#include <iostream>
#include <memory>
#include <sstream>

#include <Eigen/Geometry>

#include "host/cli/model_option.hpp"
#include "host/files/output_file.hpp"
#include "host/model/dataset.hpp"
#include "host/model/model_file.hpp"
#include "host/model/reading_coverage.hpp"

namespace kincal::cli {

namespace {

std::string number_text(double v) {
  if (v == 0.0) v = 0.0;
  char buffer[64];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, v);
  return ec == std::errc() ? std::string(buffer, end) : std::string("nan");
}

int run_predict(const ModelOption& model_option, const std::string& joints_path, const std::string& out_path,
                const std::string& at) {
  try {
    files::refuse_overwriting({{"-o", out_path, true}}, {{"--model", model_option.path}, {"--joints", joints_path}});
    const model::RobotModel loaded = model_option.load();
    if (at == "tcp" && !loaded.flange_T_tcp)
      throw model::InputError(
          model_option.path +
          ": --at tcp: the model has no TCP (a model file's 'tcp:', set from a URDF's tip link); its "
          "measured point is what it predicts");
    const model::RobotModel m = at == "tcp" ? model::tool_at_tcp(loaded) : loaded;
    const std::vector<std::vector<double>> rows = model::read_joints(joints_path);
    if (!rows.empty()) model::check_joint_count(m, static_cast<int>(rows.front().size()), joints_path);
    std::ostringstream out;
    const bool pose = m.tool == model::ToolKind::frame;
    for (int j = 1; j <= m.joint_count(); ++j) out << 'q' << j << ',';
    out << "x,y,z" << (pose ? ",qw,qx,qy,qz" : "") << '\n';
    for (const std::vector<double>& q : rows) {
      const model::Transform t = model::forward_kinematics(m, q);
      for (double v : q) out << number_text(v) << ',';
      out << number_text(t.translation.x()) << ',' << number_text(t.translation.y()) << ','
          << number_text(t.translation.z());
      if (pose) {
        Eigen::Quaterniond r(t.rotation);
        if (r.w() < 0) r.coeffs() *= -1.0;
        out << ',' << number_text(r.w()) << ',' << number_text(r.x()) << ',' << number_text(r.y()) << ','
            << number_text(r.z());
      }
      out << '\n';
    }
    files::write_output(out_path, out.str());
    for (const model::CoverageFinding& f : model::readings_outside_calibration(m, rows, "rows"))
      std::cerr << "kincal predict: " << (f.still ? "warning: " : "note: ") << f.text << '\n';
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "kincal predict: " << e.what() << '\n';
    return 1;
  }
}

}  // namespace

void add_predict_command(CLI::App& app, int& status) {
  auto model_option = std::make_shared<ModelOption>();
  auto joints_path = std::make_shared<std::string>();
  auto out_path = std::make_shared<std::string>();
  auto at = std::make_shared<std::string>("measured");
  auto* cmd = app.add_subcommand("predict",
                                 "Predict the measured point (pose) or the TCP of a model for rows of joint readings");
  add_model_option(*cmd, *model_option, "model");
  cmd->add_option("--joints", *joints_path, "joint readings (CSV with header q1..qN; other columns ignored)")
      ->required();
  cmd->add_option("-o,--out", *out_path, "output CSV (default or '-': standard output)");
  cmd->add_option("--at", *at,
                  "measured: the point or frame the data measured (reflector, marker, board), what a held-out "
                  "measurement is compared with; tcp: the controller's TCP (a pose), what correct aims")
      ->check(CLI::IsMember({"measured", "tcp"}))
      ->capture_default_str();
  cmd->callback([=, &status] { status = run_predict(*model_option, *joints_path, *out_path, *at); });
}

}  // namespace kincal::cli
