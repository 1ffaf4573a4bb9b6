#include "host/correct/urscript.hpp"

#include <charconv>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string_view>

#include <Eigen/Geometry>

#include "host/correct/target_table.hpp"
#include "host/files/input_file.hpp"
#include "host/model/number_text.hpp"

namespace kincal::correct {

namespace {

constexpr std::size_t kMaxLineBytes = 65536;
constexpr const char* kCalls[] = {"movej", "movel", "movep", "servoj"};

bool name_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '_'; }

std::size_t skip_blanks(std::string_view s, std::size_t at) {
  while (at < s.size() && (s[at] == ' ' || s[at] == '\t')) ++at;
  return at;
}

// A line as code: the text inside string literals ("..." or '...', a backslash escaping the next
// character) blanked and the line cut at a '#' outside them, so that a motion inside a string or a
// comment is not one. `unclosed`: the offset of a quote its line does not close, else npos.
struct Code {
  std::string text;
  std::size_t unclosed = std::string_view::npos;
};

Code code_of(std::string_view line) {
  Code code{std::string(line)};
  std::string& c = code.text;
  for (std::size_t i = 0; i < c.size(); ++i) {
    if (code.unclosed != std::string_view::npos) {
      if (c[i] == '\\' && i + 1 < c.size()) {
        c[i] = c[i + 1] = ' ';
        ++i;
        continue;
      }
      if (c[i] == c[code.unclosed]) {
        code.unclosed = std::string_view::npos;
        continue;
      }
      c[i] = ' ';
    } else if (c[i] == '"' || c[i] == '\'') {
      code.unclosed = i;
    } else if (c[i] == '#') {
      c.resize(i);
      break;
    }
  }
  return code;
}

// The motion call in a line's code (code_of), if any: the first of kCalls that stands as a whole
// name followed by '('.
struct Call {
  std::string name;
  std::size_t at = std::string_view::npos, open = 0;  // the name's offset, the offset after '('
};

Call find_call(std::string_view code) {
  Call found;
  for (const char* name : kCalls) {
    const std::string_view n(name);
    for (std::size_t at = code.find(n); at != std::string_view::npos; at = code.find(n, at + 1)) {
      if ((at > 0 && name_char(code[at - 1])) || (at + n.size() < code.size() && name_char(code[at + n.size()])))
        continue;
      const std::size_t paren = skip_blanks(code, at + n.size());
      if (paren >= code.size() || code[paren] != '(') continue;
      if (at < found.at) found = {std::string(n), at, paren + 1};
      break;
    }
  }
  return found;
}

}  // namespace

UrProgram read_urscript(const std::string& path, int joint_count, std::size_t max_motions) {
  return parse_urscript(files::read_text_or_throw<model::InputError>(path, files::kProgramFile), path, joint_count,
                        max_motions);
}

UrProgram parse_urscript(std::string text, const std::string& source, int joint_count, std::size_t max_motions) {
  UrProgram program;
  program.source = source;
  program.text = std::move(text);
  const std::string_view all(program.text);
  int number = 0;
  for (std::size_t start = 0; start < all.size();) {
    std::size_t end = std::min(all.find('\n', start), all.size());
    const std::size_t next = end + 1;
    if (end > start && all[end - 1] == '\r') --end;
    const std::string_view line = all.substr(start, end - start);
    ++number;
    if (line.size() > kMaxLineBytes)
      throw model::InputError(source + ":" + std::to_string(number) + ":1: a line of " + std::to_string(line.size()) +
                              " bytes: not a URScript program (at most " + std::to_string(kMaxLineBytes) +
                              " bytes a line)");
    const auto where = [&](std::size_t offset) { return static_cast<int>(offset + 1); };
    const auto fail = [&](std::size_t offset, const std::string& what) {
      throw model::InputError(source + ":" + std::to_string(number) + ":" + std::to_string(where(offset)) + ": " +
                              what);
    };
    const Code code = code_of(line);
    if (code.unclosed != std::string_view::npos) fail(code.unclosed, "a string is not closed on its line");
    const Call call = find_call(code.text);
    if (call.at != std::string_view::npos) {
      const std::string_view code_text = code.text;
      std::size_t at = skip_blanks(code_text, call.open);
      const bool pose = at < code_text.size() && code_text[at] == 'p';
      if (pose) at = skip_blanks(code_text, at + 1);
      const std::string not_literal =
          "its value is not known before the program runs, so kincal cannot correct it "
          "(write the target out)";
      if (at >= code_text.size() || code_text[at] != '[')
        fail(at, call.name + "'s target is not a literal [...] or p[...]: " + not_literal);
      const std::size_t close = code_text.find(']', at);
      if (close == std::string_view::npos) fail(at, call.name + ": no ']' closes the target on this line");
      const std::size_t after = skip_blanks(code_text, close + 1);
      if (after >= code_text.size() || (code_text[after] != ',' && code_text[after] != ')'))
        fail(after, call.name +
                        "'s target goes on past its literal (an expression such as [...] + [...], or a call "
                        "continued on the next line): " +
                        not_literal);
      if (program.motions.size() == max_motions)
        fail(call.at, "more than " + std::to_string(max_motions) + " motions, the most kincal correct takes");
      UrMotion m;
      m.call = call.name;
      m.begin = start + at + 1;
      m.end = start + close;
      m.target.line = number;
      m.target.cartesian = pose;
      m.target.orientation = pose;
      std::vector<double> values;
      for (std::size_t from = at + 1; from <= close;) {
        const std::size_t comma = std::min(code_text.find(',', from), close);
        values.push_back(parse_cell(code_text.substr(from, comma - from),
                                    call.name + " value " + std::to_string(values.size() + 1), source, number,
                                    where(from)));
        std::size_t value_end = comma;
        while (value_end > from && (code_text[value_end - 1] == ' ' || code_text[value_end - 1] == '\t')) --value_end;
        m.values.emplace_back(start + skip_blanks(code_text, from), start + value_end);
        from = comma + 1;
      }
      if (pose && values.size() != 6)
        fail(at, call.name + ": a pose p[x, y, z, rx, ry, rz] has 6 values, this one " + std::to_string(values.size()));
      if (!pose && static_cast<int>(values.size()) != joint_count)
        fail(at, call.name + ": " + std::to_string(values.size()) + " joint values, the model has " +
                     std::to_string(joint_count) + " joints");
      if (pose) {
        m.target.pose.translation = {values[0], values[1], values[2]};
        const Eigen::Vector3d r(values[3], values[4], values[5]);
        const double angle = r.stableNorm();  // norm() squares: 1e300 overflowed to a NaN rotation
        if (!(angle <= 2 * std::numbers::pi))
          fail(at, call.name + ": the rotation vector's angle is " + model::shortest_number_text(angle) +
                       " rad, more than a turn: degrees given as radians?");
        if (angle > 0.0) m.target.pose.rotation = Eigen::AngleAxisd(angle, r / angle).toRotationMatrix();
      } else {
        m.target.q = std::move(values);
      }
      program.motions.push_back(std::move(m));
    }
    start = next;
  }
  return program;
}

std::string write_urscript(const UrProgram& program, const std::vector<std::vector<double>>& values) {
  if (values.size() != program.motions.size())
    throw std::invalid_argument("write_urscript: " + std::to_string(values.size()) + " value lists for " +
                                std::to_string(program.motions.size()) + " motions");
  std::string out;
  out.reserve(program.text.size() + 64 * values.size());
  std::size_t copied = 0;
  for (std::size_t i = 0; i < values.size(); ++i) {
    const UrMotion& m = program.motions[i];
    if (values[i].size() != m.values.size())
      throw std::invalid_argument("write_urscript: " + std::to_string(values[i].size()) + " values for motion " +
                                  std::to_string(i + 1) + ", which has " + std::to_string(m.values.size()));
    for (std::size_t k = 0; k < values[i].size(); ++k) {
      const auto [begin, end] = m.values[k];
      out.append(program.text, copied, begin - copied);
      const std::string_view old(program.text.data() + begin, end - begin);
      double was = 0.0;
      const bool unchanged = std::from_chars(old.data(), old.data() + old.size(), was).ec == std::errc() &&
                             was == values[i][k];  // as read (parse_cell): keeps its spelling
      out += unchanged ? std::string(old) : model::shortest_number_text(values[i][k]);
      copied = end;
    }
  }
  out.append(program.text, copied, std::string::npos);
  return out;
}

std::vector<std::vector<double>> urscript_values(const UrProgram& program, const std::vector<TargetResult>& results) {
  std::vector<std::vector<double>> values;
  for (std::size_t i = 0; i < program.motions.size() && i < results.size(); ++i) {
    if (!program.motions[i].target.cartesian) {
      values.push_back(results[i].solution.q);
      continue;
    }
    const model::Transform& c = results[i].command;
    const Eigen::AngleAxisd r{Eigen::Matrix3d(c.rotation)};
    const Eigen::Vector3d v = r.angle() * r.axis();
    values.push_back({c.translation.x(), c.translation.y(), c.translation.z(), v.x(), v.y(), v.z()});
  }
  return values;
}

}  // namespace kincal::correct
