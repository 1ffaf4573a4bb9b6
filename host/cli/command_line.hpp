// The command line as the ecosystem's tools treat it: bare `kincal` prints the help on standard
// error and exits kUsageError (it ran nothing); an unknown
// subcommand or option, or a value the option refuses, is a usage error that exits 2 naming the
// word and, where one is close, the valid word meant ("did you mean identify?"). So is an empty
// word ('--constraints ""', an unset shell variable): taken as the option not given, it would
// silently drop what it names. An option that would have no effect with the others given is a
// usage error naming the option it needs or excludes (CLI11's needs/excludes where each command
// adds its options: import --euler needs --orientation, monitor --log needs --can, ...).
#pragma once

#include <CLI/App.hpp>
#include <optional>
#include <string>
#include <vector>

namespace kincal::cli {

// The exit status of a usage error (as getopt-based tools and Python's argparse use).
inline constexpr int kUsageError = 2;

// Parses argv into `app` (whose subcommands' callbacks then run). Returns the exit status when
// the program should stop here (help, version, a usage error: the message is already printed),
// nothing when the parse succeeded and the subcommand's status stands.
std::optional<int> parse_command_line(CLI::App& app, int argc, const char* const* argv);

// The candidate nearest to `word` by edit distance, if near enough to be a likely typo.
std::optional<std::string> nearest_word(const std::string& word, const std::vector<std::string>& candidates);

}  // namespace kincal::cli
