// The field split of a text line, shared by the dataset reader (dataset.cpp) and the import of
// measurement exports (measurement_import.cpp): fields between separators, each trimmed of
// spaces, tabs and carriage returns. The dataset's and an export's fields may be quoted as RFC
// 4180 says (split_quoted_fields), which a text column (a row id or a spreadsheet's time stamp
// that holds a comma) needs; an export's columns may be aligned by runs of blanks instead
// (split_blank_fields).
#pragma once

#include <optional>
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
inline std::vector<std::string> split_fields(const std::string& line, char separator) {
  std::vector<std::string> fields;
  std::size_t start = 0;
  while (true) {
    const std::size_t at = line.find(separator, start);
    fields.push_back(
        trim_field(std::string_view(line).substr(start, at == std::string::npos ? std::string::npos : at - start)));
    if (at == std::string::npos) break;
    start = at + 1;
  }
  return fields;
}

// The field in double quotes that starts at line[at]: its text ("" standing for one quote) into
// `field`, `at` past the closing quote; false when the quote is not closed on the line.
inline bool read_quoted_field(const std::string& line, std::size_t& at, std::string& field) {
  for (++at; at < line.size(); ++at) {
    if (line[at] != '"') {
      field += line[at];
    } else if (at + 1 < line.size() && line[at + 1] == '"') {
      field += '"';
      ++at;
    } else {
      ++at;
      return true;
    }
  }
  return false;
}

// RFC 4180 fields of `line`: a field that starts (after blanks) with a double quote runs to the
// matching quote, "" inside it standing for one quote, and may hold separators; other fields as
// split_fields(). nullopt when a quote is not closed or text follows a closing quote.
inline std::optional<std::vector<std::string>> split_quoted_fields(const std::string& line, char separator) {
  if (line.find('"') == std::string::npos) return split_fields(line, separator);
  std::vector<std::string> fields;
  std::size_t at = 0;
  while (true) {
    while (at < line.size() && (line[at] == ' ' || line[at] == '\t')) ++at;
    std::string field;
    if (at < line.size() && line[at] == '"') {
      if (!read_quoted_field(line, at, field)) return std::nullopt;
      while (at < line.size() && line[at] != separator) {
        if (line[at] != ' ' && line[at] != '\t' && line[at] != '\r') return std::nullopt;
        ++at;
      }
    } else {
      const std::size_t end = line.find(separator, at);
      field = trim_field(std::string_view(line).substr(at, end == std::string::npos ? std::string::npos : end - at));
      at = end == std::string::npos ? line.size() : end;
    }
    fields.push_back(std::move(field));
    if (at >= line.size()) break;
    ++at;  // the separator
  }
  return fields;
}

// The fields of a whitespace-aligned line (columns padded by runs of spaces or tabs, as
// numpy.savetxt, MATLAB and fixed-width reports write them): the fields between runs of blanks,
// blanks before the first and after the last ignored, so no field is empty; a field in double
// quotes may hold blanks ("" for a quote). nullopt when a quote is not closed or text follows a
// closing quote.
inline std::optional<std::vector<std::string>> split_blank_fields(const std::string& line) {
  const auto blank = [](char c) { return c == ' ' || c == '\t' || c == '\r'; };
  std::vector<std::string> fields;
  std::size_t at = 0;
  while (true) {
    while (at < line.size() && blank(line[at])) ++at;
    if (at >= line.size()) break;
    std::string field;
    if (line[at] == '"') {
      if (!read_quoted_field(line, at, field) || (at < line.size() && !blank(line[at]))) return std::nullopt;
    } else {
      const std::size_t begin = at;
      while (at < line.size() && !blank(line[at])) ++at;
      field = line.substr(begin, at - begin);
    }
    fields.push_back(std::move(field));
  }
  return fields;
}

}  // namespace kincal::model
