// The field split of a text line, shared by the dataset reader (dataset.cpp) and the import of
// measurement exports (measurement_import.cpp): fields between separators, each trimmed of
// spaces, tabs and carriage returns; an export's fields may also stand in double quotes.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace kincal::model {

// `s` without surrounding spaces, tabs, carriage returns (and double quotes when `unquote`).
inline std::string trim_field(std::string_view s, bool unquote = false) {
  const auto blank = [unquote](char c) { return c == ' ' || c == '\t' || c == '\r' || (unquote && c == '"'); };
  std::size_t b = 0, e = s.size();
  while (b < e && blank(s[b])) ++b;
  while (e > b && blank(s[e - 1])) --e;
  return std::string(s.substr(b, e - b));
}

// The trimmed fields of `line` between `separator`s (one field for a line without any).
inline std::vector<std::string> split_fields(const std::string& line, char separator, bool unquote = false) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t at = line.find(separator, start);
    fields.push_back(trim_field(
        std::string_view(line).substr(start, at == std::string::npos ? std::string::npos : at - start), unquote));
    if (at == std::string::npos) break;
    start = at + 1;
  }
  return fields;
}

}  // namespace kincal::model
