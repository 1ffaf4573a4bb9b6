#include "host/correct/urscript.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <map>
#include <numbers>
#include <optional>
#include <stdexcept>
#include <string_view>

#include <Eigen/Geometry>

#include "host/correct/target_table.hpp"
#include "host/files/input_file.hpp"
#include "host/model/number_text.hpp"

namespace kincal::correct {

namespace {

constexpr std::size_t kMaxLineBytes = 65536;
constexpr const char* kCalls[] = {"movej", "movel", "movep", "movec", "servoj", "servoc"};
constexpr const char* kSetTcp[] = {"set_tcp"};

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

// The call in a line's code (code_of), if any: the first of `names` that stands as a whole name
// followed by '('.
struct Call {
  std::string name;
  std::size_t at = std::string_view::npos, open = 0;  // the name's offset, the offset after '('
};

template <std::size_t N>
Call find_call(std::string_view code, const char* const (&names)[N]) {
  Call found;
  for (const char* name : names) {
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

// A motion target's value is not known before the program runs (UrProgram::left).
struct Unknown : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// Where a line stands in the text, for messages: "SOURCE:LINE:COLUMN: what".
struct LineAt {
  const std::string& source;
  int number = 0;
  std::size_t start = 0;  // the line's first byte in the text

  std::string at(std::size_t offset) const {
    return source + ":" + std::to_string(number) + ":" + std::to_string(offset + 1) + ": ";
  }
  // Malformed: the program is refused.
  [[noreturn]] void fail(std::size_t offset, const std::string& what) const {
    throw model::InputError(at(offset) + what);
  }
  // A target whose value is not known before the program runs: its motion is left as written.
  [[noreturn]] void unknown(std::size_t offset, const std::string& what) const { throw Unknown(at(offset) + what); }
};

// A target's values in a line's code: a literal's brackets, or a variable's name.
struct Ref {
  bool literal = false, pose = false;
  std::size_t open = 0, close = 0;  // a literal's '[' and ']' (offsets in the line)
  std::string name;                 // a variable
  std::size_t at = 0, after = 0;    // where it starts; the first non-blank after it
};

std::size_t name_end(std::string_view code, std::size_t at) {
  while (at < code.size() && name_char(code[at])) ++at;
  return at;
}

// The literal or the variable at `at`, or nothing when it is neither (a call, an element, any
// other expression). A literal its line does not close is refused when `line` is given (a
// motion's), else nothing (an assignment's: a list written over several lines is no target).
std::optional<Ref> read_ref(std::string_view code, std::size_t at, const LineAt* line, const std::string& what) {
  Ref r;
  r.at = at;
  std::size_t open = at;
  if (at < code.size() && code[at] == 'p') {
    const std::size_t bracket = skip_blanks(code, at + 1);
    if (bracket < code.size() && code[bracket] == '[') r.pose = true, open = bracket;
  }
  if (open < code.size() && code[open] == '[') {
    r.close = code.find(']', open);
    if (r.close == std::string_view::npos) {
      if (line == nullptr) return std::nullopt;
      line->unknown(open, what + ": no ']' closes the target on this line");
    }
    r.literal = true;
    r.open = open;
    r.after = skip_blanks(code, r.close + 1);
    return r;
  }
  const std::size_t end = name_end(code, at);
  if (end == at || std::isdigit(static_cast<unsigned char>(code[at])) != 0) return std::nullopt;
  r.name = std::string(code.substr(at, end - at));
  r.after = skip_blanks(code, end);
  if (r.after < code.size() && (code[r.after] == '(' || code[r.after] == '[' || code[r.after] == '.'))
    return std::nullopt;
  return r;
}

// An assignment at the start of a line's code: [global|local] NAME [ [...] ] = VALUE (not ==).
// `value`: the literal assigned, when the whole value is one; an element assignment never is.
struct Assignment {
  std::string name;
  int line = 0;
  std::size_t start = 0, end = 0;  // the line in the text
  std::optional<Ref> value;
};

std::optional<Assignment> find_assignment(std::string_view code, const LineAt& line) {
  std::size_t at = skip_blanks(code, 0), end = name_end(code, at);
  if (const std::string_view word = code.substr(at, end - at); word == "global" || word == "local") {
    at = skip_blanks(code, end);
    if (at == end) return std::nullopt;
    end = name_end(code, at);
  }
  if (end == at || std::isdigit(static_cast<unsigned char>(code[at])) != 0) return std::nullopt;
  Assignment a{std::string(code.substr(at, end - at)), line.number, line.start, 0, std::nullopt};
  std::size_t next = skip_blanks(code, end);
  const bool element = next < code.size() && code[next] == '[';
  if (element) {
    next = code.find(']', next);
    if (next == std::string_view::npos) return std::nullopt;
    next = skip_blanks(code, next + 1);
  }
  if (next >= code.size() || code[next] != '=' || (next + 1 < code.size() && code[next + 1] == '='))
    return std::nullopt;
  if (element) return a;
  const std::optional<Ref> value = read_ref(code, skip_blanks(code, next + 1), nullptr, a.name);
  if (value && value->literal && value->after == code.size()) a.value = value;
  return a;
}

// Skips an argument's value to the ',' or ')' that ends it (brackets and parentheses nested).
std::size_t skip_argument(std::string_view code, std::size_t at) {
  int depth = 0;
  for (; at < code.size(); ++at) {
    const char c = code[at];
    if (c == '(' || c == '[') ++depth;
    if ((c == ')' || c == ']') && depth-- == 0) break;
    if (c == ',' && depth == 0) break;
  }
  return at;
}

// A motion's target as written: the literal or variable, get_inverse_kin's qnear, pose_trans's frame.
struct Site {
  std::string call;
  LineAt line;
  std::size_t end = 0;  // the line's end in the text
  Ref target;
  std::optional<Ref> seed, frame;
  bool inverse = false;  // get_inverse_kin's: the target must be a pose
};

const std::string kNotKnown =
    "its value is not known before the program runs, so kincal cannot correct it (write the target out, or assign "
    "it a literal once)";

// The target argument of the motion `call` at `at` of a line's code; `after`: the ',' or ')' that
// ends it.
Site read_target(const std::string& call, std::string_view code, std::size_t at, const LineAt& line,
                 std::size_t line_end, std::size_t& after) {
  Site site{call, line, line_end, {}, std::nullopt, std::nullopt, false};
  const std::size_t word = name_end(code, at);
  const std::size_t paren = skip_blanks(code, word);
  const std::string_view name = code.substr(at, word - at);
  const bool called = paren < code.size() && code[paren] == '(';
  const bool inverse = called && name == "get_inverse_kin", in_frame = called && name == "pose_trans";
  const std::string target_what = inverse ? "get_inverse_kin" : in_frame ? "pose_trans" : call;
  site.inverse = inverse;
  if (inverse || in_frame) at = skip_blanks(code, paren + 1);
  if (in_frame) {
    site.frame = read_ref(code, at, &line, "pose_trans");
    if (!site.frame || site.frame->after >= code.size() || code[site.frame->after] != ',')
      line.unknown(
          site.frame ? site.frame->after : at,
          "pose_trans's frame is not a literal p[...] or a variable assigned one, followed by the pose: " + kNotKnown);
    at = skip_blanks(code, site.frame->after + 1);
  }
  const std::optional<Ref> target = read_ref(code, at, &line, target_what);
  if (!target)
    line.unknown(at, target_what +
                         "'s target is not a literal [...] or p[...], a variable assigned one, or get_inverse_kin(...) "
                         "or pose_trans(...) of them: " +
                         kNotKnown);
  site.target = *target;
  after = target->after;
  const auto ends_argument = [&](std::size_t offset, const std::string& what) {
    if (offset >= code.size() || (code[offset] != ',' && code[offset] != ')'))
      line.unknown(offset, what +
                               "'s target goes on past its literal or name (an expression such as [...] + [...], or a "
                               "call continued on the next line): " +
                               kNotKnown);
  };
  ends_argument(after, target_what);
  if (in_frame) {
    if (code[after] != ')') line.unknown(after, "pose_trans takes a frame and a pose, nothing more");
    after = skip_blanks(code, after + 1);
    ends_argument(after, call);
  }
  if (!inverse) return site;
  for (int positional = 1; code[after] == ','; ++positional) {
    std::size_t value = skip_blanks(code, after + 1);
    const std::size_t key_end = name_end(code, value), equals = skip_blanks(code, key_end);
    std::string key = positional == 1 ? "qnear" : positional == 4 ? "tcp" : "";
    if (key_end > value && equals < code.size() && code[equals] == '=' &&
        (equals + 1 >= code.size() || code[equals + 1] != '=')) {
      key = std::string(code.substr(value, key_end - value));
      value = skip_blanks(code, equals + 1);
      --positional;
    }
    if (key == "tcp")
      line.unknown(value,
                   "get_inverse_kin with a tcp of its own: kincal corrects the targets of one TCP (--tcp); give the "
                   "pose of the program's TCP instead");
    if (key == "qnear") {
      site.seed = read_ref(code, value, &line, "qnear");
      if (!site.seed)
        line.unknown(value, "get_inverse_kin's qnear is not a literal [...] or a variable assigned one: " + kNotKnown);
      after = site.seed->after;
      ends_argument(after, "qnear");
    } else {
      after = skip_argument(code, value);
    }
    if (after >= code.size()) break;
  }
  if (after >= code.size() || code[after] != ')') line.unknown(after, "get_inverse_kin: no ')' closes it on this line");
  after = skip_blanks(code, after + 1);
  ends_argument(after, call);
  return site;
}

// A pose p[x, y, z, rx, ry, rz] (6 values) as a transform; nothing when its rotation vector is
// longer than a turn (or not finite).
std::optional<model::Transform> pose_of(const std::vector<double>& v) {
  const Eigen::Vector3d r(v[3], v[4], v[5]);
  const double angle = r.stableNorm();  // norm() squares: 1e300 overflowed to a NaN rotation
  if (!(angle <= 2 * std::numbers::pi)) return std::nullopt;
  model::Transform t;
  t.translation = {v[0], v[1], v[2]};
  if (angle > 0.0) t.rotation = Eigen::AngleAxisd(angle, r / angle).toRotationMatrix();
  return t;
}

// The numbers of a literal (ref, in the line the text holds at [start, end)), refused with the
// line and column of the value that is not one.
UrLiteral read_literal(const std::string& text, const Ref& ref, const LineAt& line, std::size_t end,
                       const std::string& what) {
  const std::string code = code_of(std::string_view(text).substr(line.start, end - line.start)).text;
  const std::string_view c = code;
  UrLiteral literal;
  literal.line = line.number;
  literal.pose = ref.pose;
  literal.begin = line.start + ref.open + 1;
  literal.end = line.start + ref.close;
  for (std::size_t from = ref.open + 1; from <= ref.close;) {
    const std::size_t comma = std::min(c.find(',', from), ref.close);
    literal.numbers.push_back(parse_cell(c.substr(from, comma - from),
                                         what + " value " + std::to_string(literal.numbers.size() + 1), line.source,
                                         line.number, static_cast<int>(from + 1)));
    std::size_t value_end = comma;
    while (value_end > from && (c[value_end - 1] == ' ' || c[value_end - 1] == '\t')) --value_end;
    literal.values.emplace_back(line.start + skip_blanks(c, from), line.start + value_end);
    from = comma + 1;
  }
  return literal;
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
  // First the lines: every assignment and every motion's target as written; then each motion's
  // target resolved (a variable may be assigned below the motion that names it).
  std::map<std::string, std::vector<Assignment>> assigned;
  std::vector<Site> sites;
  struct SetTcp {
    int line = 0;
    std::optional<Site> argument;  // a literal or a variable, read as a motion's target is
  };
  std::vector<SetTcp> set_tcps;
  int number = 0;
  for (std::size_t start = 0; start < all.size();) {
    std::size_t end = std::min(all.find('\n', start), all.size());
    const std::size_t next = end + 1;
    if (end > start && all[end - 1] == '\r') --end;
    const std::string_view text_line = all.substr(start, end - start);
    const LineAt line{source, ++number, start};
    if (text_line.size() > kMaxLineBytes)
      line.fail(0, "a line of " + std::to_string(text_line.size()) + " bytes: not a URScript program (at most " +
                       std::to_string(kMaxLineBytes) + " bytes a line)");
    const Code code = code_of(text_line);
    if (code.unclosed != std::string_view::npos) line.fail(code.unclosed, "a string is not closed on its line");
    if (std::optional<Assignment> a = find_assignment(code.text, line)) {
      a->end = end;
      assigned[a->name].push_back(std::move(*a));
    }
    if (const Call set = find_call(code.text, kSetTcp); set.at != std::string_view::npos) {
      const std::optional<Ref> pose = read_ref(code.text, skip_blanks(code.text, set.open), nullptr, "set_tcp");
      set_tcps.push_back(
          {number, pose ? std::optional<Site>(Site{"set_tcp", line, end, *pose, std::nullopt, std::nullopt, false})
                        : std::nullopt});
    }
    const Call call = find_call(code.text, kCalls);
    // movec's via point and its end are two targets, read in order; one not known leaves both.
    std::size_t after = call.open - 1;  // the '(' (unused without a call)
    std::vector<Site> read;
    try {
      for (int k = 0; call.at != std::string_view::npos && k < (call.name == "movec" ? 2 : 1); ++k) {
        if (sites.size() + read.size() == max_motions)
          line.fail(call.at, "more than " + std::to_string(max_motions) + " motions, the most kincal correct takes");
        if (code.text[after] != (k == 0 ? '(' : ','))
          line.fail(after, "movec takes a via point and an end: [...] or p[...] each, or a variable assigned one");
        read.push_back(read_target(call.name, code.text, skip_blanks(code.text, after + 1), line, end, after));
      }
      for (Site& site : read) sites.push_back(std::move(site));
    } catch (const Unknown& e) {
      program.left.push_back({number, call.name, e.what()});
    }
    start = next;
  }

  // Where the literal a reference names is: the motion's own, or its variable's one assignment.
  struct Located {
    const Ref* ref;
    LineAt line;
    std::size_t end;
  };
  const auto locate = [&](const Site& site, const Ref& ref, const std::string& what) -> Located {
    if (ref.literal) return {&ref, site.line, site.end};
    const auto it = assigned.find(ref.name);
    const std::string named = what + "'s target " + ref.name;
    if (it == assigned.end()) site.line.unknown(ref.at, named + " is not assigned in this program: " + kNotKnown);
    const std::vector<Assignment>& a = it->second;
    if (a.size() > 1) {
      std::string lines;
      for (std::size_t k = 0; k < a.size() && k < 5; ++k) lines += (k ? ", " : "") + std::to_string(a[k].line);
      site.line.unknown(ref.at, named + " is assigned " + std::to_string(a.size()) + " times (lines " + lines +
                                    (a.size() > 5 ? ", ..." : "") + "): " + kNotKnown);
    }
    if (!a[0].value)
      site.line.unknown(ref.at, named + " is assigned an expression on line " + std::to_string(a[0].line) +
                                    ", not a literal [...] or p[...]: " + kNotKnown);
    return {&*a[0].value, LineAt{source, a[0].line, a[0].start}, a[0].end};
  };
  const auto read = [&](const Located& l, const Ref& ref, const std::string& what) {
    return read_literal(program.text, *l.ref, l.line, l.end, ref.literal ? what : ref.name);
  };
  // The literal's column in its line, for messages about its values.
  const auto column_of = [&](const UrLiteral& literal) {
    const std::size_t bracket = literal.begin - 1, newline = program.text.rfind('\n', bracket);
    return bracket - (newline == std::string::npos ? 0 : newline + 1);
  };
  const auto pose_or_fail = [&](const UrLiteral& literal, const std::string& what) {
    const LineAt at{source, literal.line, 0};
    if (!literal.pose || literal.numbers.size() != 6)
      at.fail(column_of(literal), what + ": a pose p[x, y, z, rx, ry, rz] has 6 values, this one " +
                                      (literal.pose ? std::to_string(literal.numbers.size()) : "is a list [...]"));
    const std::optional<model::Transform> pose = pose_of(literal.numbers);
    if (!pose)
      at.fail(column_of(literal),
              what + ": the rotation vector's angle is " +
                  model::shortest_number_text(
                      Eigen::Vector3d(literal.numbers[3], literal.numbers[4], literal.numbers[5]).stableNorm()) +
                  " rad, more than a turn: degrees given as radians?");
    return *pose;
  };
  std::map<std::string, std::size_t> literal_of;  // a variable's literal in program.literals
  // The literal a reference names, in program.literals (a variable's once).
  const auto resolve = [&](const Site& site, const Ref& ref, const std::string& what) -> std::size_t {
    if (!ref.literal)
      if (const auto it = literal_of.find(ref.name); it != literal_of.end()) return it->second;
    program.literals.push_back(read(locate(site, ref, what), ref, what));
    if (!ref.literal) literal_of[ref.name] = program.literals.size() - 1;
    return program.literals.size() - 1;
  };
  std::map<std::size_t, std::optional<model::Transform>> frame_of;  // the frame a literal's pose is in
  std::map<std::string, const Site&> frame_used;                    // each variable named as a frame, at its first use
  const auto locate_all = [&](const Site& site) {
    locate(site, site.target, site.frame ? "pose_trans" : site.call);
    if (site.frame) locate(site, *site.frame, "pose_trans");
    if (site.seed) locate(site, *site.seed, "qnear");
  };
  std::size_t pair_end = 0;  // a movec's via point and end (consecutive sites) are left together
  for (std::size_t i = 0; i < sites.size(); ++i) {
    const Site& site = sites[i];
    if (i >= pair_end) {
      pair_end = i + (site.call == "movec" ? 2 : 1);
      try {  // every value the motion names known before anything is taken from it
        for (std::size_t k = i; k < pair_end && k < sites.size(); ++k) locate_all(sites[k]);
      } catch (const Unknown& e) {
        program.left.push_back({site.line.number, site.call, e.what()});
        i = pair_end - 1;
        continue;
      }
    }
    UrMotion m;
    m.call = site.call;
    m.target.line = site.line.number;
    const std::string what = site.target.literal ? site.call : site.target.name;
    m.literal = resolve(site, site.target, site.call);
    const UrLiteral& target = program.literals[m.literal];
    m.target.cartesian = m.target.orientation = target.pose;
    if (target.pose || site.frame || site.inverse) {
      m.target.pose = pose_or_fail(target, what);
    } else if (static_cast<int>(target.numbers.size()) != joint_count) {
      LineAt{source, target.line, 0}.fail(column_of(target), what + ": " + std::to_string(target.numbers.size()) +
                                                                 " joint values, the model has " +
                                                                 std::to_string(joint_count) + " joints");
    } else {
      m.target.q = target.numbers;
    }
    if (site.frame) {
      const std::string frame_what = site.frame->literal ? "pose_trans" : site.frame->name;
      m.base_T_frame =
          pose_or_fail(read(locate(site, *site.frame, "pose_trans"), *site.frame, "pose_trans"), frame_what);
      m.target.pose = *m.base_T_frame * m.target.pose;
      if (!site.frame->literal) frame_used.emplace(site.frame->name, site);
    }
    // A variable's pose written back in one frame: every motion naming it must see it in that one.
    const auto [first, inserted] = frame_of.emplace(m.literal, m.base_T_frame);
    if (!inserted && first->second.has_value() != m.base_T_frame.has_value())
      site.line.fail(site.target.at, what +
                                         " is a target in the robot's base frame and in a pose_trans frame: "
                                         "one corrected value cannot serve both");
    if (!inserted && first->second &&
        ((first->second->translation - m.base_T_frame->translation).norm() > 0.0 ||
         (first->second->rotation - m.base_T_frame->rotation).norm() > 0.0))
      site.line.fail(site.target.at,
                     what + " is a target in two pose_trans frames: one corrected value cannot serve both");
    if (site.seed) {
      m.seed = resolve(site, *site.seed, "qnear");
      const UrLiteral& seed = program.literals[*m.seed];
      if (seed.pose || static_cast<int>(seed.numbers.size()) != joint_count)
        site.line.fail(site.seed->at, "get_inverse_kin's qnear " + (site.seed->literal ? "" : site.seed->name + " ") +
                                          "holds " +
                                          (seed.pose ? "a pose" : std::to_string(seed.numbers.size()) + " values") +
                                          ", not the model's " + std::to_string(joint_count) + " joint positions");
      m.target.q = seed.numbers;
    }
    program.motions.push_back(std::move(m));
  }
  // A frame is kept as written: a variable that is a frame and a target too would be rewritten
  // under the motions in its frame, moving them by its own correction.
  for (const auto& [name, site] : frame_used)
    if (literal_of.count(name) != 0)
      site.line.fail(site.frame->at, name +
                                         " is the frame of this pose_trans and a target corrected elsewhere: its "
                                         "rewritten value would move the motions in its frame");
  std::stable_sort(program.left.begin(), program.left.end(),
                   [](const UrLeft& a, const UrLeft& b) { return a.line < b.line; });
  // The TCPs the program sets: a pose literal, or a variable assigned one once; else unknown.
  for (const SetTcp& set : set_tcps) {
    UrTcp& tcp = program.tcps.emplace_back();
    tcp.line = set.line;
    if (!set.argument) continue;
    try {
      const Ref& ref = set.argument->target;
      const UrLiteral literal = read(locate(*set.argument, ref, "set_tcp"), ref, "set_tcp");
      if (literal.pose && literal.numbers.size() == 6) tcp.flange_T_tcp = pose_of(literal.numbers);
    } catch (const Unknown&) {
      // a variable not assigned a literal once: a TCP not known before the program runs
    } catch (const model::InputError&) {
      // a value that is no number: the same
    }
  }
  return program;
}

std::string write_urscript(const UrProgram& program, const std::vector<std::vector<double>>& values) {
  if (values.size() != program.literals.size())
    throw std::invalid_argument("write_urscript: " + std::to_string(values.size()) + " value lists for " +
                                std::to_string(program.literals.size()) + " literals");
  std::vector<std::size_t> order(values.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return program.literals[a].begin < program.literals[b].begin; });
  std::string out;
  out.reserve(program.text.size() + 64 * values.size());
  std::size_t copied = 0;
  for (const std::size_t i : order) {
    const UrLiteral& literal = program.literals[i];
    if (values[i].size() != literal.values.size())
      throw std::invalid_argument("write_urscript: " + std::to_string(values[i].size()) + " values for literal " +
                                  std::to_string(i + 1) + ", which has " + std::to_string(literal.values.size()));
    for (std::size_t k = 0; k < values[i].size(); ++k) {
      const auto [begin, end] = literal.values[k];
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
  std::vector<std::optional<std::vector<double>>> by_literal(program.literals.size());
  const std::size_t n = std::min(program.motions.size(), results.size());
  for (std::size_t i = 0; i < n; ++i) {
    std::optional<std::vector<double>>& values = by_literal[program.motions[i].literal];
    if (values) continue;
    if (!program.motions[i].target.cartesian) {
      values = results[i].solution.q;
      continue;
    }
    const model::Transform c = program.motions[i].base_T_frame
                                   ? program.motions[i].base_T_frame->inverse() * results[i].command
                                   : results[i].command;
    const Eigen::AngleAxisd r{Eigen::Matrix3d(c.rotation)};
    const Eigen::Vector3d v = r.angle() * r.axis();
    values = std::vector<double>{c.translation.x(), c.translation.y(), c.translation.z(), v.x(), v.y(), v.z()};
  }
  for (std::size_t i = 0; i < n; ++i)
    if (const auto seed = program.motions[i].seed; seed && !by_literal[*seed])
      by_literal[*seed] = results[i].solution.q;
  std::vector<std::vector<double>> values;
  for (std::size_t i = 0; i < by_literal.size(); ++i)
    values.push_back(by_literal[i] ? *by_literal[i] : program.literals[i].numbers);
  return values;
}

}  // namespace kincal::correct
