#include "host/cli/demo.hpp"

#include <iostream>
#include <memory>

#include "host/demo/demo.hpp"
#include "host/session/session_error.hpp"

namespace kincal::cli {

void add_demo_command(CLI::App& app, int& status) {
  auto options = std::make_shared<session::DemoOptions>();
  options->robots_dir = KINCAL_ROBOTS_DIR;
  auto* demo = app.add_subcommand(
      "demo",
      "Run the main job end to end: calibrate the simulated ARID platform rig and Kapucu & Baysec's rig, "
      "with the real firmware in the loop, and write the report");
  demo->add_option("-o,--output", options->output_dir, "folder for the report, journals and bus logs")
      ->capture_default_str();
  demo->add_option("--seed", options->seed, "seed of the hidden errors and the noise")->capture_default_str();
  demo->add_option("--robots", options->robots_dir, "folder of the robot model files")->capture_default_str();
  demo->add_flag("--quick", options->quick, "about half the poses (a faster, rougher run)");
  demo->callback([&status, options] {
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
