#include "host/model/measurement_import.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <istream>
#include <map>
#include <numbers>
#include <set>
#include <sstream>
#include <utility>

#include "host/files/input_file.hpp"
#include "host/model/csv_fields.hpp"

namespace kincal::model {

namespace {

constexpr double kRadPerDeg = std::numbers::pi / 180.0;
constexpr int kHeaderSearch = 100;  // lines searched for the header

// The fields of a line split by `separator`: ' ' stands for runs of blanks (split_blank_fields),
// any other as RFC 4180 quotes them (split_quoted_fields).
std::optional<std::vector<std::string>> line_fields(const std::string& line, char separator) {
  return separator == ' ' ? split_blank_fields(line) : split_quoted_fields(line, separator);
}

// The one of ';', tab and ',' that splits the header into the most fields as RFC 4180 quotes them
// (split_quoted_fields: a quoted name may hold any of them); runs of blanks (' ') only when none of
// them splits it at all (a whitespace-aligned export: no header of one column is imported, so the
// blanks cannot be inside a name there).
char detect_separator(const std::string& header) {
  char best = ',';
  std::size_t most = 1;  // one field: no separator, ","
  for (char c : {';', '\t', ','}) {
    const std::optional<std::vector<std::string>> fields = split_quoted_fields(header, c);
    if (fields && fields->size() > most) {
      most = fields->size();
      best = c;
    }
  }
  if (most == 1)
    if (const std::optional<std::vector<std::string>> fields = split_blank_fields(header); fields && fields->size() > 1)
      best = ' ';
  return best;
}

[[noreturn]] void fail(const std::string& source, int line, std::size_t column, const std::string& what) {
  throw InputError(source + ":" + std::to_string(line) + ":" + std::to_string(column + 1) + ": " + what);
}

// The fields of an export's line as RFC 4180 quotes them (a quoted field may hold the separator, ""
// stands for a quote), each trimmed of blanks: a spreadsheet quotes a time stamp or a comment that
// holds a comma. A quote left open (a field spanning lines) or text after a closing quote is
// refused.
std::vector<std::string> export_fields(const std::string& line, char separator, const std::string& source, int number) {
  std::optional<std::vector<std::string>> fields = line_fields(line, separator);
  if (!fields)
    fail(source, number, 0,
         "a double quote is not closed on this line, or text follows a closing quote (a quoted field may hold the "
         "separator, not a line break)");
  for (std::string& f : *fields) f = trim_field(f);
  return *fields;
}

// A field that holds no value: empty, or NaN as tracker and motion-capture software write a
// measurement they did not take.
bool holds_no_value(const std::string& field) {
  std::string lower = field;
  std::transform(lower.begin(), lower.end(), lower.begin(), [](unsigned char c) { return std::tolower(c); });
  return lower.empty() || lower == "nan" || lower == "-nan" || lower == "+nan";
}

// The header names of what the instrument measured: the position and, when named, its standard
// deviations and the orientation (Euler angles and their standard deviations, or a quaternion).
std::vector<std::string> measured_names(const ImportOptions& o) {
  std::vector<std::string> names(o.position.begin(), o.position.end());
  for (const auto* three : {&o.position_std, &o.angles, &o.angle_std})
    if (*three) names.insert(names.end(), (*three)->begin(), (*three)->end());
  if (o.quaternion) names.insert(names.end(), o.quaternion->begin(), o.quaternion->end());
  return names;
}

// A unit word as exports write it under a header ("mm", "[deg]", "Millimeters", "°"): the unit's
// name as the options spell it, or empty when it is none kincal knows.
std::string unit_word(std::string field) {
  std::transform(field.begin(), field.end(), field.begin(), [](unsigned char c) { return std::tolower(c); });
  if (field.size() >= 2 &&
      ((field.front() == '[' && field.back() == ']') || (field.front() == '(' && field.back() == ')')))
    field = trim_field(field.substr(1, field.size() - 2));
  struct Word {
    const char *unit, *word;
  };
  static constexpr Word kWords[] = {
      {"m", "m"},         {"m", "meter"},       {"m", "meters"},       {"m", "metre"},       {"m", "metres"},
      {"mm", "mm"},       {"mm", "millimeter"}, {"mm", "millimeters"}, {"mm", "millimetre"}, {"mm", "millimetres"},
      {"rad", "rad"},     {"rad", "radian"},    {"rad", "radians"},    {"deg", "deg"},       {"deg", "degree"},
      {"deg", "degrees"}, {"deg", "\xc2\xb0"}};
  for (const Word& w : kWords)
    if (field == w.word) return w.unit;
  return {};
}

// Every header name the options give.
std::vector<std::string> named_columns(const ImportOptions& o) {
  std::vector<std::string> names = o.joints;
  const std::vector<std::string> measured = measured_names(o);
  names.insert(names.end(), measured.begin(), measured.end());
  if (o.id) names.push_back(*o.id);
  return names;
}

// The number a field spells, a decimal comma read as a point and a leading '+' allowed; nothing
// when it is none (empty, a word, trailing text).
std::optional<double> plain_number(std::string text) {
  std::replace(text.begin(), text.end(), ',', '.');
  const char* first = text.data();
  const char* last = text.data() + text.size();
  if (first != last && *first == '+') ++first;
  double v = 0.0;
  const auto [end, ec] = std::from_chars(first, last, v);
  if (text.empty() || ec != std::errc() || end != last) return std::nullopt;
  return v;
}

// A column named by its number, "#7" (1-based; a header may hold a name twice: a motion-capture
// export's X, Y, Z of the rotation and of the position); 0 when the name is no such number.
std::size_t column_number(const std::string& name) {
  if (name.size() < 2 || name.size() > 7 || name[0] != '#') return 0;
  std::size_t n = 0;
  const auto [end, ec] = std::from_chars(name.data() + 1, name.data() + name.size(), n);
  return ec == std::errc() && end == name.data() + name.size() ? n : 0;
}

// A header written as a comment, "# J1  J2  X ..." (numpy.savetxt, gnuplot-style data files): the
// '#' and the blank after it are no column. A column named "#" (a row number) is followed by its
// separator, not a blank, and is kept.
void drop_comment_mark(std::string& line) {
  const std::size_t at = line.find_first_not_of(" \t");
  if (at != std::string::npos && line[at] == '#' && at + 1 < line.size() &&
      (line[at + 1] == ' ' || line[at + 1] == '\t'))
    line[at] = ' ';
}

// Whether a line, split by the given separator or the one detected on it, holds every name.
bool holds_every(const std::string& line, char separator, const std::vector<std::string>& names) {
  std::optional<std::vector<std::string>> fields =
      line_fields(line, separator != 0 ? separator : detect_separator(line));
  if (!fields) return false;
  for (std::string& f : *fields) f = trim_field(f);
  return std::all_of(names.begin(), names.end(), [&](const std::string& name) {
    return std::find(fields->begin(), fields->end(), name) != fields->end() ||
           (column_number(name) > 0 && column_number(name) <= fields->size());
  });
}

struct Table {
  const std::string& source;
  std::map<std::string, std::size_t> index;               // each name's first column
  std::map<std::string, std::vector<std::size_t>> twice;  // a name's later columns
  std::vector<std::string> names;
  int header_line = 0;
  char separator = ',';
  // The decimal mark, decided by the numbers together: the first line whose number has a
  // decimal comma, and (in a ',' separated file, where a comma can only be in a quoted field)
  // the first with a decimal point: both in one such file is refused, since there the comma
  // may as well be a thousands separator.
  int first_comma_line = 0;
  int first_point_line = 0;
  std::string row_id;  // of the row being read, for its messages

  [[noreturn]] void fail_row(int line, std::size_t column, const std::string& what) const {
    fail(source, line, column, row_id.empty() ? what : what + " (id " + files::excerpt(row_id) + ")");
  }

  std::size_t column(const std::string& name) const {
    const auto it = index.find(name);
    if (const auto again = twice.find(name); it != index.end() && again != twice.end())
      fail(source, header_line, again->second.front(),
           "header: column '" + files::excerpt(name) + "' appears " + std::to_string(again->second.size() + 1) +
               " times (columns " + std::to_string(it->second + 1) + " and " +
               std::to_string(again->second.front() + 1) + (again->second.size() > 1 ? ", ..." : "") +
               "): name the one meant by its number, #" + std::to_string(it->second + 1) + " or #" +
               std::to_string(again->second.front() + 1));
    if (it == index.end() && column_number(name) > 0) {
      if (column_number(name) > names.size())
        fail(source, header_line, names.size(),
             "column " + name + ": the header has " + std::to_string(names.size()) + " columns");
      return column_number(name) - 1;
    }
    if (it == index.end()) {
      constexpr std::size_t kListed = 20;  // a header of 100,000 names is not listed whole
      std::string known;
      for (std::size_t i = 0; i < names.size() && i < kListed; ++i)
        known += (known.empty() ? "'" : ", '") + files::excerpt(names[i]) + "'";
      if (names.size() > kListed) known += " and " + std::to_string(names.size() - kListed) + " more";
      fail(source, header_line, names.size(),
           "no column named '" + files::excerpt(name) + "' in the header (it has " + known + ")");
    }
    return it->second;
  }

  double number(const std::vector<std::string>& fields, std::size_t c, int line) {
    const std::string& text = fields[c];
    decimal_mark(text, c, line);
    if (text.empty()) fail_row(line, c, "column '" + names[c] + "' is empty");
    const std::optional<double> v = plain_number(text);
    if (!v)
      fail_row(line, c,
               "column '" + files::excerpt(names[c]) + "': '" + files::excerpt(fields[c]) + "' is not a number");
    if (!std::isfinite(*v)) fail_row(line, c, "column '" + names[c] + "' is not finite");
    return *v;
  }

  // Records the decimal mark of a number's text; refuses one with both marks, and a ','
  // separated file whose numbers use both.
  void decimal_mark(const std::string& text, std::size_t c, int line) {
    const bool comma = text.find(',') != std::string::npos;
    const bool point = text.find('.') != std::string::npos;
    const auto field = [&] { return "column '" + files::excerpt(names[c]) + "': '" + files::excerpt(text) + "'"; };
    if (comma && point)
      fail_row(line, c, field() + " has both '.' and ',' (a thousands separator?): export the numbers without one");
    if (comma && first_comma_line == 0) first_comma_line = line;
    if (point && separator == ',' && first_point_line == 0) first_point_line = line;
    if (separator == ',' && first_comma_line != 0 && first_point_line != 0)
      fail_row(line, c,
               field() + ": this ',' separated file writes numbers with a decimal comma (line " +
                   std::to_string(first_comma_line) + ") and with a decimal point (line " +
                   std::to_string(first_point_line) +
                   "), so a comma may be a thousands separator: export with one decimal mark");
  }
};

std::array<std::size_t, 3> columns(const Table& t, const std::array<std::string, 3>& names) {
  return {t.column(names[0]), t.column(names[1]), t.column(names[2])};
}

double median_of(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

EulerConvention parse_euler_convention(const std::string& text) {
  EulerConvention c;
  const auto dash = text.find('-');
  const std::string kind = text.substr(0, dash);
  const std::string order = dash == std::string::npos ? "" : text.substr(dash + 1);
  const bool good_kind = kind == "intrinsic" || kind == "extrinsic";
  bool good_order = order.size() == 3;
  for (std::size_t i = 0; good_order && i < 3; ++i) {
    const char a = order[i];
    good_order = a == 'x' || a == 'y' || a == 'z';
    if (good_order) c.axes[i] = a - 'x';
    if (good_order && i > 0) good_order = order[i] != order[i - 1];
  }
  if (!good_kind || !good_order)
    throw InputError(
        "Euler convention '" + text +
        "': expected intrinsic-ABC or extrinsic-ABC with axes x, y, z (e.g. intrinsic-xyz, extrinsic-zyx)");
  c.intrinsic = kind == "intrinsic";
  return c;
}

namespace {

constexpr std::pair<const char*, JointUnit> kJointUnitNames[] = {
    {"rad", JointUnit::rad}, {"deg", JointUnit::deg}, {"m", JointUnit::m}, {"mm", JointUnit::mm}};

// A joint unit as the options spell it.
const char* joint_unit_name(JointUnit unit) {
  for (const auto& [name, u] : kJointUnitNames)
    if (u == unit) return name;
  return "?";
}

}  // namespace

LengthUnit parse_length_unit(const std::string& text) {
  if (text == "m") return LengthUnit::m;
  if (text == "mm") return LengthUnit::mm;
  throw InputError("length unit '" + text + "': expected m or mm");
}

AngleUnit parse_angle_unit(const std::string& text) {
  if (text == "rad") return AngleUnit::rad;
  if (text == "deg") return AngleUnit::deg;
  throw InputError("angle unit '" + text + "': expected rad or deg");
}

JointUnit parse_joint_unit(const std::string& text) {
  for (const auto& [name, unit] : kJointUnitNames)
    if (text == name) return unit;
  throw InputError("joint unit '" + files::excerpt(text) + "': expected rad or deg (revolute), m or mm (prismatic)");
}

void check_joint_units(const std::vector<JointUnit>& units, const RobotModel& model) {
  if (units.size() != 1 && units.size() != model.joints.size())
    throw InputError("--joint-unit: " + std::to_string(units.size()) + " units for the " +
                     std::to_string(model.joints.size()) + " joints of '" + model.name +
                     "' (give one for all joints or one per joint)");
  for (std::size_t j = 0; j < model.joints.size(); ++j) {
    const JointUnit u = units[units.size() == 1 ? 0 : j];
    const bool angle = u == JointUnit::rad || u == JointUnit::deg;
    const bool revolute = model.joints[j].type == core::JointType::revolute;
    if (angle != revolute)
      throw InputError("--joint-unit: joint " + std::to_string(j + 1) + " '" + model.joints[j].name + "' of '" +
                       model.name + "' is " + (revolute ? "revolute" : "prismatic") + " but its unit is " +
                       joint_unit_name(u) +
                       (revolute ? " (a revolute joint reads rad or deg" : " (a prismatic joint reads m or mm") +
                       "; give one unit per joint, e.g. --joint-unit deg,deg,m,...)");
  }
}

Eigen::Matrix3d rotation_from_euler(const EulerConvention& c, const Eigen::Vector3d& angles_rad) {
  Eigen::Matrix3d r = Eigen::Matrix3d::Identity();
  for (int k = 0; k < 3; ++k) {
    const auto i = static_cast<std::size_t>(k);
    const Eigen::Matrix3d step = Eigen::AngleAxisd(angles_rad(k), Eigen::Vector3d::Unit(c.axes[i])).toRotationMatrix();
    r = c.intrinsic ? Eigen::Matrix3d(r * step) : Eigen::Matrix3d(step * r);
  }
  return r;
}

ImportResult import_measurements(std::istream& in, const std::string& source, const ImportOptions& o) {
  if (o.joints.empty()) throw InputError(source + ": no joint columns named");
  ImportResult result;
  result.data.source = source;
  result.data.joint_count = static_cast<int>(o.joints.size());
  result.data.has_orientation = o.angles.has_value() || o.quaternion.has_value();
  if (o.angles && o.quaternion)
    throw InputError(source + ": orientation given both as Euler angles and as a quaternion");
  result.data.noise = o.position_std ? NoiseColumns::covariance : NoiseColumns::none;
  const double length = o.position_unit == LengthUnit::mm ? 1e-3 : 1.0;
  if (o.joint_units.size() != 1 && o.joint_units.size() != o.joints.size())
    throw InputError("--joint-unit: " + std::to_string(o.joint_units.size()) + " units for " +
                     std::to_string(o.joints.size()) + " joint columns (give one for all joints or one per joint)");
  std::vector<double> joint_scale;
  for (std::size_t j = 0; j < o.joints.size(); ++j) {
    const JointUnit u = o.joint_units[o.joint_units.size() == 1 ? 0 : j];
    joint_scale.push_back(u == JointUnit::deg ? kRadPerDeg : u == JointUnit::mm ? 1e-3 : 1.0);
  }
  const double angle = o.angle_unit == AngleUnit::deg ? kRadPerDeg : 1.0;

  Table t{source, {}, {}, {}, 0, ',', 0, 0, {}};
  // The header: the first line that holds every named column, among the first kHeaderSearch (an
  // export may open with its title, its settings or a spreadsheet's "sep=;"); when none does, the
  // first line that is not blank, and the message names the column it lacks.
  std::string line, first_line;
  int number = 0, first_number = 0;
  std::istream::pos_type after_first{-1};
  const std::vector<std::string> names = named_columns(o);
  bool found = false;
  while (!found && number < kHeaderSearch && std::getline(in, line)) {
    ++number;
    drop_comment_mark(line);
    if (trim_field(line, true).empty()) continue;
    if (first_number == 0) {
      first_number = number;
      first_line = line;
      after_first = in.tellg();
    }
    found = holds_every(line, o.separator, names);
  }
  if (first_number == 0) throw InputError(source + ": empty file (expected a header row)");
  if (!found) {
    line = first_line;
    number = first_number;
    in.clear();
    if (after_first != std::istream::pos_type{-1})
      in.seekg(after_first);
    else
      in.setstate(std::ios::eofbit);
  }
  t.header_line = result.header_line = number;
  result.separator = o.separator != 0 ? o.separator : detect_separator(line);
  t.separator = result.separator;
  t.names = export_fields(line, result.separator, source, number);
  for (std::size_t i = 0; i < t.names.size(); ++i)
    if (!t.names[i].empty() && !t.index.emplace(t.names[i], i).second) t.twice[t.names[i]].push_back(i);
  std::vector<std::size_t> joint_columns;
  for (const std::string& j : o.joints) joint_columns.push_back(t.column(j));
  const auto position = columns(t, o.position);
  const auto position_std = o.position_std ? std::optional(columns(t, *o.position_std)) : std::nullopt;
  const auto angles = o.angles ? std::optional(columns(t, *o.angles)) : std::nullopt;
  const auto angle_std = o.angle_std ? std::optional(columns(t, *o.angle_std)) : std::nullopt;
  std::optional<std::array<std::size_t, 4>> quaternion;
  if (o.quaternion) {
    quaternion.emplace();
    for (std::size_t k = 0; k < 4; ++k) (*quaternion)[k] = t.column((*o.quaternion)[k]);
  }
  // A plain index with o.id as its flag: GCC 12 at -O3 takes an optional's value as maybe unset.
  const std::size_t id_column = o.id ? t.column(*o.id) : 0;
  if (angle_std && !angles) throw InputError(source + ": orientation standard deviations without orientation columns");
  // Every header column feeds one value: a column named for two roles is a typing slip.
  std::map<std::size_t, std::string> role_of;
  const auto use = [&](std::size_t column, const std::string& role) {
    const auto [it, fresh] = role_of.emplace(column, role);
    if (!fresh)
      fail(source, t.header_line, column,
           "column '" + files::excerpt(t.names[column]) + "' is named twice: as " + it->second + " and as " + role +
               " (every column feeds one value)");
  };
  for (std::size_t j = 0; j < joint_columns.size(); ++j)
    use(joint_columns[j], "joint " + std::to_string(j + 1) + " (--joints)");
  const auto use_three = [&](const std::optional<std::array<std::size_t, 3>>& c, const char* option) {
    for (std::size_t k = 0; c && k < 3; ++k) use((*c)[k], "value " + std::to_string(k + 1) + " of " + option);
  };
  use_three(std::optional(position), "--position");
  use_three(position_std, "--position-std");
  use_three(angles, "--orientation");
  use_three(angle_std, "--orientation-std");
  for (std::size_t k = 0; quaternion && k < 4; ++k)
    use((*quaternion)[k], std::string("value ") + "wxyz"[k] + " of --quaternion");
  if (o.id) use(id_column, "the row id (--id)");
  // The columns of what the instrument measured: a row in which every one holds no value is a
  // measurement not taken (a lost beam, an occluded marker), left out and counted.
  std::vector<std::size_t> measured;
  for (const std::string& name : measured_names(o)) measured.push_back(t.column(name));

  // The unit each named column holds, as the options say (a quaternion's is none).
  std::map<std::size_t, std::pair<std::string, std::string>> unit_of;  // column: unit, option
  const char* const length_name = o.position_unit == LengthUnit::mm ? "mm" : "m";
  const char* const angle_name = o.angle_unit == AngleUnit::deg ? "deg" : "rad";
  for (std::size_t j = 0; j < joint_columns.size(); ++j)
    unit_of[joint_columns[j]] = {joint_unit_name(o.joint_units[o.joint_units.size() == 1 ? 0 : j]), "--joint-unit"};
  for (const auto* three : {&position_std, &angles, &angle_std})
    for (std::size_t k = 0; *three && k < 3; ++k)
      unit_of[(**three)[k]] = three == &position_std
                                  ? std::pair{std::string(length_name), std::string("--position-unit")}
                                  : std::pair{std::string(angle_name), std::string("--angle-unit")};
  for (std::size_t k = 0; k < 3; ++k) unit_of[position[k]] = {length_name, "--position-unit"};

  std::vector<double> position_stds, angle_stds;
  std::set<std::string> ids;
  bool first_row = true;
  while (std::getline(in, line)) {
    ++number;
    if (trim_field(line, true).empty()) continue;
    if (result.data.rows.size() == kMaxRows) fail(source, number, 0, too_many_rows());
    const std::vector<std::string> fields = export_fields(line, result.separator, source, number);
    if (fields.size() != t.names.size())
      fail(source, number, std::min(fields.size(), t.names.size()),
           "expected " + std::to_string(t.names.size()) + " fields as in the header, found " +
               std::to_string(fields.size()) +
               (result.separator == ',' && fields.size() > t.names.size()
                    ? " (decimal commas in a ',' separated file must be quoted, \"-21,14\", or the file "
                      "separated by ';' or tabs)"
                    : ""));
    // A units row under the header (motion-capture and tracker exports: "mm", "deg"): no named
    // column holds a number and one holds a unit word. Each unit it gives is held against the
    // options: a file in mm imported as m is refused, naming both.
    if (std::exchange(first_row, false) &&
        std::any_of(unit_of.begin(), unit_of.end(),
                    [&](const auto& u) { return !unit_word(fields[u.first]).empty(); }) &&
        std::none_of(unit_of.begin(), unit_of.end(),
                     [&](const auto& u) { return plain_number(fields[u.first]).has_value(); })) {
      for (const auto& [column, unit] : unit_of) {
        const std::string& cell = fields[column];
        const std::string word = unit_word(cell);
        if (cell.empty() || word == unit.first) continue;
        fail(source, number, column,
             "the units row under the header gives '" + files::excerpt(cell) + "' for column '" +
                 files::excerpt(t.names[column]) + "', " + unit.second + " says " + unit.first +
                 (word.empty() ? " (and '" + files::excerpt(cell) + "' is no unit kincal reads: m, mm, rad, deg)"
                               : ": give " + unit.second + " " + word + " if the file is in " + word));
      }
      result.units_line = number;
      continue;
    }
    Measurement m;
    m.line = number;
    if (o.id) {
      m.id = fields[id_column];
      if (m.id.empty())
        fail(source, number, id_column, "column '" + files::excerpt(t.names[id_column]) + "' (--id) is empty");
      t.row_id = m.id;
    }
    if (std::all_of(measured.begin(), measured.end(), [&](std::size_t c) { return holds_no_value(fields[c]); })) {
      result.skipped.push_back({number, m.id});
      continue;
    }
    if (o.id) ids.insert(m.id);
    for (std::size_t j = 0; j < joint_columns.size(); ++j)
      m.q.push_back(t.number(fields, joint_columns[j], number) * joint_scale[j]);
    for (int k = 0; k < 3; ++k)
      m.position(k) = t.number(fields, position[static_cast<std::size_t>(k)], number) * length;
    if (position_std) {
      Matrix3 c = Matrix3::Zero();
      for (int k = 0; k < 3; ++k) {
        const std::size_t col = (*position_std)[static_cast<std::size_t>(k)];
        const double s = t.number(fields, col, number) * length;
        if (!(s > 0.0)) t.fail_row(number, col, "column '" + t.names[col] + "': a standard deviation must be > 0");
        c(k, k) = s * s;
        position_stds.push_back(s);
      }
      m.covariance = c;
    }
    if (angles) {
      Eigen::Vector3d a;
      for (int k = 0; k < 3; ++k) a(k) = t.number(fields, (*angles)[static_cast<std::size_t>(k)], number) * angle;
      m.orientation = Eigen::Quaterniond(rotation_from_euler(o.convention, a));
      if (angle_std) {
        for (std::size_t col : *angle_std) {
          const double s = t.number(fields, col, number) * angle;
          if (!(s > 0.0)) t.fail_row(number, col, "column '" + t.names[col] + "': a standard deviation must be > 0");
          angle_stds.push_back(s);
        }
      }
    }
    if (quaternion) {
      Eigen::Vector4d wxyz;
      for (std::size_t k = 0; k < 4; ++k) wxyz(static_cast<int>(k)) = t.number(fields, (*quaternion)[k], number);
      constexpr double kUnitTolerance = 0.01;  // a unit quaternion written to 3 digits passes
      if (!(std::abs(wxyz.norm() - 1.0) <= kUnitTolerance))
        t.fail_row(number, (*quaternion)[0],
                   "the quaternion (--quaternion) has norm " + std::to_string(wxyz.norm()) +
                       ", not 1: are its columns the ones named, in the order w, x, y, z?");
      wxyz.normalize();
      m.orientation = Eigen::Quaterniond(wxyz(0), wxyz(1), wxyz(2), wxyz(3));
    }
    result.data.rows.push_back(std::move(m));
  }
  if (result.data.rows.empty() && !result.skipped.empty())
    throw InputError(source + ": none of the " + std::to_string(result.skipped.size()) +
                     " data rows holds a measurement (every measured column empty or NaN)");
  if (result.data.rows.empty()) throw InputError(source + ": no data rows after the header");
  result.decimal_comma = t.first_comma_line != 0;
  result.median_position_std_m = median_of(position_stds);
  result.median_angle_std_rad = median_of(angle_stds);
  result.distinct_ids = ids.size();
  return result;
}

ImportResult import_measurements_file(const std::string& path, const ImportOptions& options) {
  std::istringstream in(files::read_text_or_throw<InputError>(path, files::kExportFile, files::StandardInput::allowed));
  return import_measurements(in, path == "-" ? "standard input" : path, options);
}

}  // namespace kincal::model
