#include "host/cli/command_line.hpp"

#include <algorithm>
#include <cctype>
#include <iostream>

namespace kincal::cli {

namespace {

// Edit distance with adjacent transpositions (optimal string alignment): "mdoel" is one edit
// from "model".
std::size_t edit_distance(const std::string& a, const std::string& b) {
  std::vector<std::vector<std::size_t>> d(a.size() + 1, std::vector<std::size_t>(b.size() + 1));
  for (std::size_t i = 0; i <= a.size(); ++i) d[i][0] = i;
  for (std::size_t j = 0; j <= b.size(); ++j) d[0][j] = j;
  for (std::size_t i = 1; i <= a.size(); ++i) {
    for (std::size_t j = 1; j <= b.size(); ++j) {
      const std::size_t substitution = a[i - 1] == b[j - 1] ? 0 : 1;
      d[i][j] = std::min({d[i - 1][j] + 1, d[i][j - 1] + 1, d[i - 1][j - 1] + substitution});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        d[i][j] = std::min(d[i][j], d[i - 2][j - 2] + 1);
      }
    }
  }
  return d[a.size()][b.size()];
}

std::string command_path(const CLI::App* command) {
  std::string path = command->get_name();
  for (const CLI::App* parent = command->get_parent(); parent != nullptr; parent = parent->get_parent()) {
    path = parent->get_name() + " " + path;
  }
  return path;
}

std::vector<std::string> subcommand_names(const CLI::App* command) {
  std::vector<std::string> names;
  for (const CLI::App* sub : command->get_subcommands([](const CLI::App*) { return true; })) {
    names.push_back(sub->get_name());
  }
  return names;
}

std::vector<std::string> option_names(const CLI::App* command) {
  std::vector<std::string> names;
  for (const CLI::Option* option : command->get_options()) {
    for (const std::string& name : option->get_lnames()) names.push_back("--" + name);
    for (const std::string& name : option->get_snames()) names.push_back("-" + name);
  }
  return names;
}

CLI::App* subcommand_named(CLI::App* command, const std::string& name) {
  for (CLI::App* sub : command->get_subcommands([](CLI::App*) { return true; })) {
    if (sub->check_name(name)) return sub;
  }
  return nullptr;
}

bool takes_positionals(const CLI::App* command) {
  const auto options = command->get_options();
  return std::any_of(options.begin(), options.end(), [](const CLI::Option* o) { return o->get_positional(); });
}

// "-0.5" and "-1,2" are values, not options.
bool looks_like_number(const std::string& token) {
  return token.size() > 1 && (std::isdigit(static_cast<unsigned char>(token[1])) != 0 || token[1] == '.');
}

int usage_error(const CLI::App* command, const std::string& message,
                const std::optional<std::string>& suggestion = std::nullopt) {
  const std::string path = command_path(command);
  std::cerr << path << ": " << message;
  if (suggestion) std::cerr << " (did you mean " << *suggestion << "?)";
  std::cerr << "\nRun '" << path << " --help' for the " << (command->get_parent() == nullptr ? "commands" : "options")
            << ".\n";
  return kUsageError;
}

// Names every word CLI11 would refuse, before it parses: CLI11 reports a missing required option
// ahead of the unknown one that was probably meant to be it (`identify --mdoel x`), and an
// unknown subcommand as "A subcommand is required". Returns the deepest command named.
std::optional<int> check_words(CLI::App& app, int argc, const char* const* argv, CLI::App*& command) {
  command = &app;
  for (int i = 1; i < argc; ++i) {
    const std::string token = argv[i];
    if (token == "--") return std::nullopt;
    if (token.size() > 1 && token[0] == '-' && !looks_like_number(token)) {
      const bool is_long = token.rfind("--", 0) == 0;
      const std::string name = is_long ? token.substr(0, token.find('=')) : token.substr(0, 2);
      const CLI::Option* option = command->get_option_no_throw(name);
      if (option == nullptr || option->get_positional()) {
        return usage_error(command, "unknown option '" + name + "'", nearest_word(name, option_names(command)));
      }
      const bool value_attached = is_long ? token.find('=') != std::string::npos : token.size() > 2;
      // An empty value is one left out (an unset shell variable): taken as "not given", an empty
      // --constraints or --candidates would plan without them.
      const bool empty_value = value_attached
                                   ? is_long && token.back() == '='
                                   : option->get_items_expected_min() > 0 && i + 1 < argc && *argv[i + 1] == '\0';
      if (empty_value) return usage_error(command, "option '" + name + "' is given an empty value");
      if (!value_attached && option->get_items_expected_min() > 0) ++i;  // its value, whatever it looks like
      continue;
    }
    if (token.empty())  // a positional or a further value of an option, left out
      return usage_error(command, "an empty argument (word " + std::to_string(i) + ")");
    if (CLI::App* sub = subcommand_named(command, token)) {
      command = sub;
      continue;
    }
    if (!subcommand_names(command).empty() && !takes_positionals(command)) {
      return usage_error(command, "unknown command '" + token + "'", nearest_word(token, subcommand_names(command)));
    }
  }
  return std::nullopt;
}

std::string joined(const std::vector<std::string>& words) {
  std::string text;
  for (const std::string& w : words) text += (text.empty() ? "" : ", ") + w;
  return text;
}

}  // namespace

std::optional<std::string> nearest_word(const std::string& word, const std::vector<std::string>& candidates) {
  std::optional<std::string> best;
  std::size_t best_distance = word.size() <= 4 ? 1 : 2;  // farther is a different word, not a typo
  for (const std::string& candidate : candidates) {
    const std::size_t distance = edit_distance(word, candidate);
    if (distance <= best_distance) {
      best = candidate;
      best_distance = distance;
    }
  }
  if (best) return best;
  // An abbreviation: the one candidate that starts with the word.
  std::optional<std::string> prefixed;
  for (const std::string& candidate : candidates) {
    if (word.size() >= 3 && candidate.rfind(word, 0) == 0) {
      if (prefixed) return std::nullopt;
      prefixed = candidate;
    }
  }
  return prefixed;
}

std::optional<int> parse_command_line(CLI::App& app, int argc, const char* const* argv) {
  if (argc <= 1) {  // no command: nothing was done, which a script must see
    std::cerr << app.help();
    return kUsageError;
  }
  CLI::App* command = nullptr;
  if (const auto status = check_words(app, argc, argv, command)) return status;
  try {
    app.parse(argc, argv);
  } catch (const CLI::Success& e) {  // --help, --help-all, --version
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    if (!subcommand_names(command).empty() && command->get_subcommands().empty()) {
      return usage_error(command, "give a command: " + joined(subcommand_names(command)));
    }
    return usage_error(command, e.what());
  }
  return std::nullopt;
}

}  // namespace kincal::cli
