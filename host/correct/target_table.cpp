#include "host/correct/target_table.hpp"

#include <charconv>
#include <cmath>
#include <map>

#include <Eigen/Geometry>

#include "host/files/input_file.hpp"
#include "host/model/csv_fields.hpp"

namespace kincal::correct {

namespace {

[[noreturn]] void fail(const std::string& source, int line, std::size_t column, const std::string& what) {
  throw model::InputError(source + ":" + std::to_string(line) + ":" + std::to_string(column) + ": " + what);
}

// The fields of a line with the 1-based byte column where each starts.
struct Fields {
  std::vector<std::string> text;
  std::vector<std::size_t> column;
};

Fields split(const std::string& line) {
  Fields f;
  f.text = model::split_fields(line, ',');
  std::size_t at = 0;
  for (std::size_t i = 0; i < f.text.size(); ++i) {
    f.column.push_back(at + 1);
    at = line.find(',', at);
    if (at != std::string::npos) ++at;
  }
  return f;
}

}  // namespace

double parse_cell(std::string_view field, const std::string& name, const std::string& source, int line, int column) {
  const std::string trimmed = model::trim_field(field);
  const auto where = static_cast<std::size_t>(column);
  if (trimmed.empty()) fail(source, line, where, "column " + name + " is empty");
  double v = 0.0;
  const char* last = trimmed.data() + trimmed.size();
  const auto [end, ec] = std::from_chars(trimmed.data(), last, v);
  if (ec != std::errc() || end != last)
    fail(source, line, where, "column " + name + ": '" + files::excerpt(trimmed) + "' is not a number");
  if (!std::isfinite(v)) fail(source, line, where, "column " + name + ": " + trimmed + " is not finite");
  return v;
}

TargetTable read_target_table(const std::string& path, int joint_count, std::size_t max_rows) {
  return parse_target_table(files::read_text_or_throw<model::InputError>(path, files::kDatasetFile), path, joint_count,
                            max_rows);
}

TargetTable parse_target_table(std::string_view text, const std::string& source, int joint_count,
                               std::size_t max_rows) {
  TargetTable table;
  table.source = source;
  std::map<std::string, std::size_t> index;
  Fields header;
  int header_line = 0;
  const auto column_of = [&](const char* name) { return index.count(name) ? index.at(name) : std::string::npos; };
  int number = 0;
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    const std::string line(text.substr(start, end - start));
    start = end + 1;
    ++number;
    const std::string trimmed = model::trim_field(line);
    if (trimmed.empty() || trimmed[0] == '#') continue;
    const Fields f = split(line);
    if (header_line == 0) {
      header = f;
      header_line = number;
      for (std::size_t i = 0; i < f.text.size(); ++i) {
        const std::string& name = f.text[i];
        if (name.empty()) fail(source, number, f.column[i], "header: column " + std::to_string(i + 1) + " has no name");
        bool known =
            name == "x" || name == "y" || name == "z" || name == "qw" || name == "qx" || name == "qy" || name == "qz";
        for (int j = 1; j <= joint_count; ++j) known = known || name == "q" + std::to_string(j);
        if (!known)
          fail(source, number, f.column[i],
               "header: unknown column '" + files::excerpt(name) + "' (expected q1..q" + std::to_string(joint_count) +
                   " for the model's " + std::to_string(joint_count) + " joints, x,y,z, qw,qx,qy,qz)");
        if (!index.emplace(name, i).second)
          fail(source, number, f.column[i], "header: column '" + name + "' appears twice");
      }
      const int points = static_cast<int>(index.count("x") + index.count("y") + index.count("z"));
      const int quaternion =
          static_cast<int>(index.count("qw") + index.count("qx") + index.count("qy") + index.count("qz"));
      int joints = 0;
      for (int j = 1; j <= joint_count; ++j) joints += static_cast<int>(index.count("q" + std::to_string(j)));
      table.cartesian = points > 0;
      table.orientation = quaternion == 4;
      if (points != 0 && points != 3) fail(source, number, 1, "header: x, y and z go together (missing one)");
      if (quaternion != 0 && quaternion != 4) fail(source, number, 1, "header: qw, qx, qy and qz go together");
      if (quaternion == 4 && points == 0) fail(source, number, 1, "header: an orientation without x,y,z");
      if (table.cartesian ? (joints != 0 && joints != joint_count) : joints != joint_count)
        fail(source, number, 1,
             "header: " + std::to_string(joints) + " joint columns, the model has " + std::to_string(joint_count) +
                 " joints (expected q1..q" + std::to_string(joint_count) + (table.cartesian ? ", or none)" : ")"));
      continue;
    }
    if (table.rows.size() == max_rows)
      fail(source, number, 1, "more than " + std::to_string(max_rows) + " targets, the most this command takes");
    if (f.text.size() != header.text.size())
      fail(source, number, 1,
           std::to_string(f.text.size()) + " fields, the header (line " + std::to_string(header_line) + ") has " +
               std::to_string(header.text.size()));
    const auto cell = [&](const std::string& name) {
      const std::size_t i = index.at(name);
      return parse_cell(f.text[i], name, source, number, static_cast<int>(f.column[i]));
    };
    TargetRow row;
    row.line = number;
    if (index.count("q1"))
      for (int j = 1; j <= joint_count; ++j) row.q.push_back(cell("q" + std::to_string(j)));
    if (table.cartesian) {
      row.pose.translation = {cell("x"), cell("y"), cell("z")};
      if (table.orientation) {
        Eigen::Quaterniond r(cell("qw"), cell("qx"), cell("qy"), cell("qz"));
        if (std::abs(r.norm() - 1.0) > 1e-3)
          fail(source, number, f.column[column_of("qw")],
               "the quaternion's norm is " + std::to_string(r.norm()) + ", not 1 (within 1e-3)");
        row.pose.rotation = r.normalized().toRotationMatrix();
      }
    }
    table.rows.push_back(std::move(row));
  }
  if (header_line == 0) fail(source, 1, 1, "no header row (expected q1,...,qN or x,y,z[,qw,qx,qy,qz])");
  if (table.rows.empty()) fail(source, header_line, 1, "no targets after the header");
  return table;
}

}  // namespace kincal::correct
