#include "host/cli/threshold_option.hpp"

#include <exception>
#include <string>

namespace kincal::cli {

namespace {

// The grey level `text` names, or none when it is not a whole integer 0..255.
std::optional<std::uint8_t> grey_level(const std::string& text) {
  try {
    std::size_t used = 0;
    const int n = std::stoi(text, &used);
    if (used == text.size() && n >= 0 && n <= 255) return static_cast<std::uint8_t>(n);
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

}  // namespace

CLI::Option* add_threshold_option(CLI::App& command, std::optional<std::uint8_t>& level) {
  return command
      .add_option_function<std::string>(
          "--threshold", [&level](const std::string& text) { level = grey_level(text); },
          "Grey level N (0..255) or auto (Otsu)")
      ->check([](const std::string& text) -> std::string {
        if (text == "auto" || grey_level(text)) return {};
        return "threshold must be auto or an integer 0..255, not '" + text + "'";
      })
      ->default_str("auto");
}

}  // namespace kincal::cli
