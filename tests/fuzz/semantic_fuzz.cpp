// Semantic fuzzer (issue #44): valid files mutated in meaning, one value or one structure at a
// time, against the readers' promise that a value means something or is refused by name. The
// input is
//   byte 0     the reader: even, a robot model (model::parse_model); odd, a measurement export
//              (model::import_measurements with joints J1..J3, position X, Y, Z, in m and rad)
//   byte 1     the mutation (kMutations below, modulo their count)
//   bytes 2-3  which value or column (modulo their count)
//   the rest   the file's text: inputs whose text the reader refuses as it is are skipped, so what
//              is mutated is always a file the reader accepts; the text checks of reading a file
//              (files::decode_text: UTF-8, no CR line end without LF) come first, as in kincal, where
//              no text reaches a reader without them (yaml-cpp counts a lone CR as a line end: a
//              refusal's line was its line, not this fuzzer's).
// A value is a number in the text (a YAML scalar after "key:" or in a flow list; a CSV cell of a
// data row). It becomes 0, its negative, +-1e300, NaN (two spellings), 2^64, a subnormal, or
// itself in a plausible wrong unit (x1000, /1000, x57.2958). Structure: a joint's name set to
// another's (a duplicate), two CSV header names swapped or one duplicated, a row's numbers
// written with decimal commas (quoted in a ',' separated file).
// Each mutant is either refused with InputError whose message names the file and the mutated
// place (its line, or the field's key or column name), or accepted, and then:
//   - a model: its written text (write_model) reads back, with the same joints; 1e300, NaN and
//     2^64 are never accepted (every field of a model has a physical range) except in the
//     calibration record's free numbers (change, stddev, the RMS); a duplicate name is never
//     accepted;
//   - an export: the same number of rows; a value in a column no option names changes nothing;
//     decimal commas read to the same rows as decimal points; NaN is never accepted.
// Anything else (another exception, a crash, undefined behaviour) is a finding. Runs standalone
// too (file arguments), and as the ctest fuzz.semantic for a bounded time.
#include <algorithm>
#include <cctype>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "host/files/input_file.hpp"
#include "host/model/csv_fields.hpp"
#include "host/model/measurement_import.hpp"
#include "host/model/model_file.hpp"
#include "host/model/number_text.hpp"

using namespace kincal;

namespace {

// A property that must hold; the line that failed on stderr, then abort (libFuzzer keeps the input).
void require(bool condition, int line = __builtin_LINE()) {
  if (condition) return;
  std::fprintf(stderr, "semantic_fuzz.cpp:%d: property failed\n", line);
  std::abort();
}

enum Mutation {
  kZero,
  kNegative,
  kHuge,
  kMinusHuge,
  kNan,
  kDotNan,
  kTwoTo64,
  kSubnormal,
  kTimes1000,
  kOver1000,
  kTimesDegPerRad,
  kDuplicateName,
  kSwapColumns,
  kDuplicateColumn,
  kDecimalComma,
  kMutations
};

// A number in the text: where, on which 1-based line, and the key or column it belongs to.
struct Value {
  std::size_t at = 0, size = 0;
  int line = 0;
  std::string key;
};

bool number_char(char c) { return (c >= '0' && c <= '9') || c == '.' || c == '-' || c == '+' || c == 'e' || c == 'E'; }

std::optional<double> as_number(const std::string& text) {
  std::istringstream in(text);
  double v = 0.0;
  if (!(in >> v) || !in.eof()) return std::nullopt;
  return v;
}

std::string replaced_value(const std::string& text, Mutation m) {
  const double v = as_number(text).value_or(0.0);
  switch (m) {
    case kZero:
      return "0";
    case kNegative:
      return text[0] == '-' ? text.substr(1) : "-" + text;
    case kHuge:
      return "1e300";
    case kMinusHuge:
      return "-1e300";
    case kNan:
      return "nan";
    case kDotNan:
      return ".nan";
    case kTwoTo64:
      return "18446744073709551616";
    case kSubnormal:
      return "4.9e-324";
    case kTimes1000:
      return model::shortest_number_text(v * 1000.0);
    case kOver1000:
      return model::shortest_number_text(v / 1000.0);
    default:
      return model::shortest_number_text(v * 57.29577951308232);
  }
}

// ---- Models ------------------------------------------------------------------------------------

// Numbers of a YAML text that follow "key:", "[" or "," and end at a delimiter, each with the
// nearest key before it on its line (a flow list's values take the list's key).
std::vector<Value> yaml_values(const std::string& text) {
  std::vector<Value> out;
  int line = 1;
  std::size_t line_start = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '\n') {
      ++line;
      line_start = i + 1;
      continue;
    }
    if (text[i] == '#') {  // a comment: to the line's end
      while (i + 1 < text.size() && text[i + 1] != '\n') ++i;
      continue;
    }
    if (!number_char(text[i]) || (i > 0 && number_char(text[i - 1]))) continue;
    std::size_t b = i;
    while (b > line_start && text[b - 1] == ' ') --b;
    if (b == line_start || (text[b - 1] != ':' && text[b - 1] != '[' && text[b - 1] != ',')) continue;
    std::size_t e = i;
    while (e < text.size() && number_char(text[e])) ++e;
    if (e < text.size() && text[e] != ' ' && text[e] != ',' && text[e] != ']' && text[e] != '}' && text[e] != '\n' &&
        text[e] != '\r')
      continue;
    if (!as_number(text.substr(i, e - i))) continue;
    // The key: the word before the last ':' before the value on its line, outside a list.
    std::string key;
    std::size_t depth = 0;
    for (std::size_t k = i; k-- > line_start;) {
      if (text[k] == ']') ++depth;
      if (text[k] == '[' && depth > 0) --depth;
      if (text[k] == ':' && depth == 0) {
        std::size_t s = k;
        while (s > line_start && text[s - 1] != ' ' && text[s - 1] != '{' && text[s - 1] != ',') --s;
        key = text.substr(s, k - s);
        break;
      }
    }
    out.push_back({i, e - i, line, key});
    i = e - 1;
  }
  return out;
}

std::optional<model::RobotModel> parsed_model(const std::string& text, std::string& error) {
  try {
    return model::parse_model(text, "fuzz.yaml");
  } catch (const model::InputError& e) {
    error = e.what();
    return std::nullopt;
  }
}

// A joint's "name: X" (in the joints list, up to the next top-level key; not in a comment) set to
// the name of the joint before it.
std::optional<std::string> duplicate_name(const std::string& text, std::size_t which, int& line) {
  const std::size_t joints = text.rfind("joints:", 0) == 0 ? 0 : text.find("\njoints:");
  if (joints == std::string::npos) return std::nullopt;
  std::size_t end = text.find('\n', joints + 1);  // from the line after "joints:"
  if (end == std::string::npos) return std::nullopt;
  ++end;
  while (end < text.size() && !(text[end - 1] == '\n' && std::isalpha(static_cast<unsigned char>(text[end])))) ++end;
  std::vector<std::pair<std::size_t, std::size_t>> names;  // value start, size
  for (std::size_t at = text.find("name: ", joints); at < end; at = text.find("name: ", at + 1)) {
    if (text[at - 1] != ' ' && text[at - 1] != '{') continue;
    const std::size_t line_start = text.rfind('\n', at) + 1;  // npos + 1 = 0 on the first line
    if (text.find('#', line_start) < at) continue;            // in a comment: no name of the model's
    const std::size_t v = at + 6;
    const std::size_t e = text.find_first_of(",}\n\r", v);
    if (e == std::string::npos || e == v) continue;
    names.emplace_back(v, e - v);
  }
  if (names.size() < 2) return std::nullopt;
  const std::size_t k = 1 + which % (names.size() - 1);
  std::string out = text;
  out.replace(names[k].first, names[k].second, text.substr(names[k - 1].first, names[k - 1].second));
  line =
      1 + static_cast<int>(std::count(text.begin(), text.begin() + static_cast<std::ptrdiff_t>(names[k].first), '\n'));
  return out;
}

void fuzz_model(const std::string& text, Mutation m, std::size_t which) {
  std::string error;
  if (!parsed_model(text, error)) return;
  std::string mutant;
  int line = 0;
  std::string key;
  if (m == kDuplicateName) {
    const std::optional<std::string> d = duplicate_name(text, which, line);
    if (!d) return;
    mutant = *d;
    key = "name";
  } else if (m < kDuplicateName) {
    const std::vector<Value> values = yaml_values(text);
    if (values.empty()) return;
    const Value& v = values[which % values.size()];
    mutant = text;
    mutant.replace(v.at, v.size, replaced_value(text.substr(v.at, v.size), m));
    line = v.line;
    key = v.key;
  } else {
    return;  // the structure mutations of a CSV
  }
  const std::optional<model::RobotModel> r = parsed_model(mutant, error);
  if (!r) {
    // Refused: naming the file and the place (the line, or the field's key).
    require(error.rfind("fuzz.yaml:", 0) == 0);
    require(error.find(":" + std::to_string(line) + ":") != std::string::npos ||
            (!key.empty() && error.find(key) != std::string::npos));
    return;
  }
  const bool record =
      key == "change" || key == "stddev" || key == "rms_residual_m" || key == "validation_rms_m" || key == "name";
  // A duplicate name is never accepted. (The mutation copies the name's text up to the line end: a
  // name a flow scalar folds over two lines is not copied whole, and no duplicate is made.)
  for (std::size_t i = 0; i < r->joints.size(); ++i)
    for (std::size_t k = 0; k < i; ++k) require(r->joints[i].name != r->joints[k].name);
  require(m != kNan && m != kDotNan);
  require(record || (m != kHuge && m != kMinusHuge && m != kTwoTo64));
  // What the reader accepts, written, it accepts again (identify writes what it read).
  const std::optional<model::RobotModel> back = parsed_model(model::write_model(*r), error);
  require(back && back->joint_count() == r->joint_count());
}

// ---- Exports -----------------------------------------------------------------------------------

model::ImportOptions export_options() {
  model::ImportOptions o;
  o.joints = {"J1", "J2", "J3"};
  o.position = {"X", "Y", "Z"};
  return o;
}

std::optional<model::ImportResult> imported(const std::string& text, std::string& error) {
  try {
    std::istringstream in(text);
    return model::import_measurements(in, "fuzz.csv", export_options());
  } catch (const model::InputError& e) {
    error = e.what();
    return std::nullopt;
  }
}

std::vector<std::string> lines_of(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// A field as RFC 4180 writes it: quoted when it holds the separator or a quote.
std::string csv_field(const std::string& f, char separator) {
  if (f.find(separator) == std::string::npos && f.find('"') == std::string::npos) return f;
  std::string out = "\"";
  for (const char c : f) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + "\"";
}

std::string joined(const std::vector<std::string>& fields, char separator) {
  std::string out;
  for (std::size_t i = 0; i < fields.size(); ++i)
    out += (i ? std::string(1, separator) : "") + csv_field(fields[i], separator);
  return out;
}

bool same_rows(const model::ImportResult& a, const model::ImportResult& b) {
  if (a.data.rows.size() != b.data.rows.size()) return false;
  for (std::size_t i = 0; i < a.data.rows.size(); ++i)
    if (a.data.rows[i].q != b.data.rows[i].q || a.data.rows[i].position != b.data.rows[i].position) return false;
  return true;
}

void fuzz_export(const std::string& text, Mutation m, std::size_t which) {
  std::string error;
  const std::optional<model::ImportResult> base = imported(text, error);
  if (!base || m == kDuplicateName) return;
  const char sep = base->separator;
  std::vector<std::string> lines = lines_of(text);
  // The header and the data rows (1-based line numbers), fields as the reader splits them.
  std::size_t header = 0;
  while (header < lines.size() && model::trim_field(lines[header], true).empty()) ++header;
  const std::optional<std::vector<std::string>> names = model::split_quoted_fields(lines[header], sep);
  if (!names) return;
  std::vector<std::size_t> rows;
  for (std::size_t i = header + 1; i < lines.size(); ++i)
    if (!model::trim_field(lines[i], true).empty()) rows.push_back(i);
  const auto used = [&](std::size_t c) {
    for (const char* n : {"J1", "J2", "J3", "X", "Y", "Z"})
      if (model::trim_field((*names)[c]) == n) return true;
    return false;
  };
  int line = static_cast<int>(header) + 1;
  std::vector<std::string> columns;  // the names a refusal may give instead of the line
  bool meaningless = false;
  bool duplicate = false;
  if (m == kSwapColumns || m == kDuplicateColumn) {
    if (names->size() < 2) return;
    std::vector<std::string> n = *names;
    const std::size_t a = which % n.size(), b = (a + 1 + (which / n.size()) % (n.size() - 1)) % n.size();
    columns = {model::trim_field(n[a]), model::trim_field(n[b])};
    if (m == kSwapColumns) std::swap(n[a], n[b]);
    if (m == kDuplicateColumn) n[b] = n[a];
    duplicate = m == kDuplicateColumn && !model::trim_field(n[a]).empty() &&
                model::trim_field(n[a]) != model::trim_field((*names)[b]);
    lines[header] = joined(n, sep);
  } else if (m == kDecimalComma) {
    // Every number of every row with a decimal comma (quoted by joined() where ',' separates):
    // the same rows.
    for (const std::size_t r : rows) {
      std::optional<std::vector<std::string>> f = model::split_quoted_fields(lines[r], sep);
      if (!f) return;
      for (std::string& x : *f)
        if (as_number(model::trim_field(x)))
          for (char& c : x)
            if (c == '.') c = ',';
      lines[r] = joined(*f, sep);
    }
    meaningless = true;
  } else {
    const std::size_t r = rows[which % rows.size()];
    std::optional<std::vector<std::string>> f = model::split_quoted_fields(lines[r], sep);
    if (!f || f->size() != names->size()) return;
    const std::size_t c = (which / rows.size()) % f->size();
    std::string cell = model::trim_field((*f)[c]);
    std::replace(cell.begin(), cell.end(), ',', '.');  // a decimal comma's value, mutated
    if (!as_number(cell)) return;
    (*f)[c] = replaced_value(cell, m);
    lines[r] = joined(*f, sep);
    line = static_cast<int>(r) + 1;
    columns = {model::trim_field((*names)[c])};
    meaningless = !used(c);
  }
  std::string mutant;
  for (const std::string& l : lines) mutant += l + "\n";
  const std::optional<model::ImportResult> result = imported(mutant, error);
  if (!result) {
    require(!meaningless);
    require(error.rfind("fuzz.csv:", 0) == 0);
    bool named = error.find(":" + std::to_string(line) + ":") != std::string::npos;
    for (const std::string& c : columns)
      named = named || (!c.empty() && error.find("'" + c + "'") != std::string::npos);
    require(named);
    return;
  }
  require(!duplicate);
  require((m != kNan && m != kDotNan) || meaningless);
  require(result->data.rows.size() == base->data.rows.size());
  if (meaningless) require(same_rows(*result, *base));
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 4) return 0;
  const auto m = static_cast<Mutation>(data[1] % kMutations);
  const std::size_t which = data[2] | (std::size_t{data[3]} << 8);
  std::string text(reinterpret_cast<const char*>(data) + 4, size - 4);
  const bool model = data[0] % 2 == 0;
  try {
    files::decode_text(text, "fuzz", model ? files::kModelFile : files::kExportFile);
  } catch (const files::InputFileError&) {
    return 0;  // no file kincal reads
  }
  if (model)
    fuzz_model(text, m, which);
  else
    fuzz_export(text, m, which);
  return 0;
}
