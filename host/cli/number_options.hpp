// CLI11 checks for numeric options (issue #16): NaN passes CLI::Range and CLI::PositiveNumber
// (every comparison with NaN is false), and their messages print DBL_MAX with 309 digits. These
// accept only finite numbers in the stated interval and print bounds with 6 significant digits.
#pragma once

#include <CLI/CLI.hpp>

namespace kincal::cli {

// A finite number in [lower, upper].
CLI::Validator finite_in(double lower, double upper);
// A whole number in [lower, upper] (CLI::Range says "Value abc not in range" for a word).
CLI::Validator whole_in(long long lower, long long upper);
// A finite number > 0.
CLI::Validator finite_positive();
// A finite number >= 0.
CLI::Validator finite_non_negative();

}  // namespace kincal::cli
