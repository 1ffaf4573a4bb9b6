#include "host/cli/number_options.hpp"

#include <cmath>
#include <cstdio>
#include <limits>
#include <string>

namespace kincal::cli {

namespace {

std::string readable(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.6g", v);
  return text;
}

// lower_open: the lower bound itself is refused (a positive quantity).
CLI::Validator finite_check(double lower, double upper, bool lower_open, std::string description) {
  return CLI::Validator(
      [=](std::string& input) -> std::string {
        double v = 0.0;
        if (!CLI::detail::lexical_cast(input, v)) return "'" + input + "' is not a number";
        if (!std::isfinite(v)) return "'" + input + "' is not a finite number";
        if (lower_open ? !(v > lower) : !(v >= lower)) {
          return readable(v) + " is too small: must be " + (lower_open ? "> " : ">= ") + readable(lower);
        }
        if (!(v <= upper)) return readable(v) + " is too large: must be <= " + readable(upper);
        return {};
      },
      std::move(description));
}

}  // namespace

CLI::Validator finite_in(double lower, double upper) {
  return finite_check(lower, upper, false, "NUMBER in [" + readable(lower) + ", " + readable(upper) + "]");
}

CLI::Validator whole_in(long long lower, long long upper) {
  const std::string range = "[" + std::to_string(lower) + ", " + std::to_string(upper) + "]";
  return CLI::Validator(
      [=](std::string& input) -> std::string {
        long long v = 0;
        if (!CLI::detail::lexical_cast(input, v)) return "'" + input + "' is not a whole number in " + range;
        if (v < lower || v > upper) return input + " is out of range: must be in " + range;
        return {};
      },
      "INTEGER in " + range);
}

CLI::Validator finite_positive() {
  return finite_check(0.0, std::numeric_limits<double>::max(), true, "finite NUMBER > 0");
}

CLI::Validator finite_non_negative() {
  return finite_check(0.0, std::numeric_limits<double>::max(), false, "finite NUMBER >= 0");
}

}  // namespace kincal::cli
