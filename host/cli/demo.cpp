#include "host/cli/demo.hpp"

#include <cmath>
#include <cstdio>
#include <iostream>
#include <ostream>

#include "firmware/core/fixed_point.hpp"

namespace kincal::cli {

namespace {

// One quantity through a fixed-point format and back, with the error and its bound (half an LSB).
template <class Q>
void show(std::ostream& out, const char* what, const char* format, double value, const char* unit) {
  const Q q = Q::from_double(value);
  const double back = q.to_double();
  const double lsb = Q::epsilon().to_double();
  char line[200];
  std::snprintf(line, sizeof line, "  %-26s %-7s %14.9f %-3s -> raw %11lld -> %14.9f  error %.2e (bound %.2e)\n", what,
                format, value, unit, static_cast<long long>(q.raw()), back, std::fabs(back - value), lsb / 2);
  out << line;
}

int run_demo(std::ostream& out) {
  out << "kincal demo: the calibration loop (simulated Kapucu & Baysec rig and ARID platform,\n"
         "identification, report) is not built yet; it lands with issue #6.\n\n"
         "What this build runs today: the firmware core's fixed-point formats for the pixel path,\n"
         "the same bits natively and on the Cortex-M4 (see `ctest -L m4`).\n\n";
  show<core::q16_16>(out, "beacon centroid x", "q16_16", 321.123456789, "px");
  show<core::q16_16>(out, "beacon centroid y", "q16_16", -17.000003, "px");
  show<core::q24_8>(out, "blob area", "q24_8", 1234.56789, "px2");
  show<core::uq8_8>(out, "background level", "uq8_8", 37.3, "DN");
  show<core::q15>(out, "colour weight", "q15", -0.333333333, "");
  const auto second_moment = core::q24_8::from_double(2.25);
  char line[200];
  std::snprintf(line, sizeof line, "  %-26s %-7s %14.9f %-3s -> sqrt  %14.9f px (blob sigma)\n", "second moment",
                "q24_8", second_moment.to_double(), "px2", core::sqrt(second_moment).to_double());
  out << line;
  return 0;
}

}  // namespace

void add_demo_command(CLI::App& app, int& status) {
  auto* demo = app.add_subcommand("demo", "Run the main job end to end (today: what the build already does)");
  demo->callback([&status] { status = run_demo(std::cout); });
}

}  // namespace kincal::cli
