#include "host/cli/demo.hpp"

#include <filesystem>
#include <iostream>
#include <memory>

#include "host/demo/demo.hpp"
#include "host/session/session_error.hpp"

namespace kincal::cli {

namespace {

// The example robots, found relative to this program: installed (PREFIX/bin/kincal and
// PREFIX/share/kincal/robots) or in its build tree. Empty when neither holds them.
std::string robots_beside_program() {
  std::error_code error;
  const std::filesystem::path program = std::filesystem::read_symlink("/proc/self/exe", error);
  if (error) return {};
  for (const char* relative : {KINCAL_ROBOTS_FROM_INSTALLED_BIN, KINCAL_ROBOTS_FROM_BUILD_BIN}) {
    const std::filesystem::path dir = (program.parent_path() / relative).lexically_normal();
    if (std::filesystem::is_regular_file(dir / "arid_prrr.yaml", error)) return dir.string();
  }
  return {};
}

}  // namespace

void add_demo_command(CLI::App& app, int& status) {
  auto options = std::make_shared<session::DemoOptions>();
  options->robots_dir = robots_beside_program();
  auto* demo = app.add_subcommand(
      "demo",
      "Run the main job end to end: calibrate the simulated ARID platform rig and Kapucu & Baysec's rig, "
      "with the real firmware in the loop, and a camera-and-board rig, and write the report");
  demo->add_option("-o,--output", options->output_dir, "folder for the report, journals and bus logs")
      ->capture_default_str();
  demo->add_option("--seed", options->seed, "seed of the hidden errors and the noise")->capture_default_str();
  demo->add_option("--robots", options->robots_dir, "folder of the robot model files")->capture_default_str();
  demo->add_flag("--quick", options->quick, "about half the poses (a faster, rougher run)");
  demo->callback([&status, options] {
    if (options->robots_dir.empty()) {
      std::cerr << "kincal demo: the example robots are not beside this program (share/kincal/robots of its "
                   "install prefix, or of its build tree): give --robots DIR (host/model/robots of the source)\n";
      status = 1;
      return;
    }
    try {
      session::run_demo(*options, std::cout);
      status = 0;
    } catch (const std::exception& e) {
      std::cerr << "kincal demo: " << e.what() << "\n";
      status = 1;
    }
  });
}

}  // namespace kincal::cli
