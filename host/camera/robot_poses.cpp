#include "host/camera/robot_poses.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <limits>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include "host/camera/intrinsics.hpp"
#include "host/files/input_file.hpp"
#include "host/model/number_text.hpp"

namespace kincal::camera {

namespace {

constexpr double kRadPerDegree = std::numbers::pi / 180;
constexpr double kPoseTolerance = 1e-3;

[[noreturn]] void bad_pose(const std::string& source, int line, const std::string& what) {
  throw CalibrationError(source + ":" + std::to_string(line) + ": " + what);
}

std::string trimmed(const std::string& s) {
  const auto first = s.find_first_not_of(" \t\r");
  if (first == std::string::npos) return "";
  return s.substr(first, s.find_last_not_of(" \t\r") - first + 1);
}

// The fields of `text` between separators (any character of `separators`); empty fields are
// kept for a CSV (one separator) and dropped for whitespace-separated matrices.
std::vector<std::string> fields_of(const std::string& text, const std::string& separators, bool keep_empty) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t end = std::min(text.find_first_of(separators, start), text.size());
    const std::string f = trimmed(text.substr(start, end - start));
    if (keep_empty || !f.empty()) out.push_back(f);
    start = end + 1;
  }
  return out;
}

double number_of(const std::string& field, const std::string& source, int line) {
  char* end = nullptr;
  const double v = std::strtod(field.c_str(), &end);
  if (field.empty() || end != field.c_str() + field.size() || !std::isfinite(v))
    bad_pose(source, line, "'" + files::excerpt(field) + "' is not a finite number");
  return v;
}

void check_reach(const RobotPose& p, const std::string& source) {
  if (p.pose.translation().norm() > kMaxRobotReach_m)
    bad_pose(source, p.line,
             "the translation is " + std::to_string(p.pose.translation().norm()) + " m, beyond " +
                 std::to_string(static_cast<int>(kMaxRobotReach_m)) + " m: poses must be in metres (millimetres?)");
}

// The rotation of rx,ry,rz. An angle beyond a turn is refused: a rotation vector's length, or a
// roll, pitch or yaw, over 2 pi rad (360 deg) is most likely degrees given as radians, and at
// 1e300 no angle at all (OpenCV's hand-eye solve then failed on the motions).
Eigen::Matrix3d rotation_of(RotationColumns rotation, const Eigen::Vector3d& r, const std::string& source, int line) {
  const double turn = rotation == RotationColumns::kRpyDeg ? 360.0 : 2 * std::numbers::pi;
  const double largest = rotation == RotationColumns::kRotationVector ? r.stableNorm() : r.cwiseAbs().maxCoeff();
  if (!(largest <= turn))
    bad_pose(source, line,
             std::string(rotation == RotationColumns::kRotationVector ? "the rotation vector's angle" : "an angle") +
                 " is " + model::shortest_number_text(largest) +
                 (rotation == RotationColumns::kRpyDeg ? " deg" : " rad") + ", more than a turn: " +
                 (rotation == RotationColumns::kRpyDeg ? "not degrees?" : "degrees given as radians?"));
  if (rotation == RotationColumns::kRotationVector) {
    const double angle = r.norm();
    return angle > 0 ? Eigen::AngleAxisd(angle, r / angle).toRotationMatrix() : Eigen::Matrix3d::Identity();
  }
  const Eigen::Vector3d a = rotation == RotationColumns::kRpyDeg ? Eigen::Vector3d(r * kRadPerDegree) : r;
  return (Eigen::AngleAxisd(a.z(), Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(a.y(), Eigen::Vector3d::UnitY()) *
          Eigen::AngleAxisd(a.x(), Eigen::Vector3d::UnitX()))
      .toRotationMatrix();
}

struct Line {
  std::string text;
  int number;
};

// A time column's name (see the header): its nanoseconds per unit, or none for another name.
std::optional<double> time_unit_ns(const std::string& name) {
  for (const char* base : {"timestamp", "time", "t", "stamp"}) {
    const std::string b = base;
    if (name.rfind(b, 0) != 0) continue;
    const std::string unit = name.substr(b.size());
    if (unit == " [ns]" || unit == "[ns]" || unit == "_ns") return 1.0;
    if (unit == " [s]" || unit == "[s]" || unit == "_s") return 1e9;
  }
  return std::nullopt;
}

// A time field in nanoseconds: a whole number of them, or seconds (ns_per_unit 1e9) within
// the 64-bit range of nanoseconds (+-292 years).
std::int64_t time_of(const std::string& field, double ns_per_unit, const std::string& source, int line) {
  if (ns_per_unit == 1.0) {
    char* end = nullptr;
    errno = 0;
    const long long v = std::strtoll(field.c_str(), &end, 10);
    if (field.empty() || end != field.c_str() + field.size() || errno == ERANGE)
      bad_pose(source, line, "time '" + files::excerpt(field) + "' is not a whole number of nanoseconds");
    return static_cast<std::int64_t>(v);
  }
  const double s = number_of(field, source, line);
  if (!(std::abs(s) < 9.2e9)) bad_pose(source, line, "time '" + files::excerpt(field) + " s' is out of range");
  return static_cast<std::int64_t>(std::llround(s * ns_per_unit));
}

std::vector<RobotPose> parse_csv(const std::vector<Line>& lines, const std::string& source, RotationColumns rotation) {
  const std::string& first = lines.front().text;
  // ',' or ';' between fields, or else spaces and tabs (a whitespace-separated table).
  const bool blank_separated = first.find_first_of(",;") == std::string::npos;
  const std::string separator = first.find(',') != std::string::npos ? "," : blank_separated ? " \t" : ";";
  std::vector<std::string> header = fields_of(first, separator, !blank_separated);
  for (std::string& name : header)
    std::transform(name.begin(), name.end(), name.begin(), [](unsigned char c) { return std::tolower(c); });
  const int header_line = lines.front().number;
  std::map<std::string, std::size_t> column;
  for (std::size_t i = 0; i < header.size(); ++i) {
    static const std::set<std::string> kRead{"x", "y", "z", "qw", "qx", "qy", "qz", "rx", "ry", "rz"};
    if (!column.emplace(header[i], i).second && kRead.count(header[i]) > 0)
      bad_pose(source, header_line, "the header names column " + header[i] + " twice");
  }
  const auto has = [&](std::initializer_list<const char*> names) {
    return std::all_of(names.begin(), names.end(), [&](const char* n) { return column.count(n) > 0; });
  };
  std::optional<std::size_t> time_column;
  std::optional<double> ns_per_unit;
  for (std::size_t i = 0; i < header.size(); ++i) {
    const std::optional<double> unit = time_unit_ns(header[i]);
    if (!unit) continue;
    if (time_column)
      bad_pose(source, header_line, "the header names two time columns, " + header[*time_column] + " and " + header[i]);
    time_column = i;
    ns_per_unit = unit;
  }
  if (!has({"x", "y", "z"})) {
    std::string names;
    for (const std::string& name : header) names += (names.empty() ? "" : ",") + files::excerpt(name);
    bad_pose(source, header_line, "the header has no x,y,z columns (it names " + names + ")");
  }
  const bool quaternion = has({"qw", "qx", "qy", "qz"});
  if (!quaternion && !has({"rx", "ry", "rz"}))
    bad_pose(source, header_line, "the header has no rotation columns: qw,qx,qy,qz or rx,ry,rz");
  if (quaternion && has({"rx", "ry", "rz"}))
    bad_pose(source, header_line, "the header has both qw,qx,qy,qz and rx,ry,rz: which is the rotation?");
  if (quaternion && rotation != RotationColumns::kUnnamed)
    bad_pose(source, header_line,
             "the rotation is qw,qx,qy,qz, yet a meaning of rx,ry,rz (rotvec, rpy or rpy-deg) was named");
  if (!quaternion && rotation == RotationColumns::kUnnamed)
    bad_pose(source, header_line,
             "rx,ry,rz can mean a rotation vector or roll-pitch-yaw angles: name which (rotvec, rpy or rpy-deg)");
  std::vector<RobotPose> poses;
  for (std::size_t k = 1; k < lines.size(); ++k) {
    const std::vector<std::string> f = fields_of(lines[k].text, separator, !blank_separated);
    const auto value = [&](const char* name) {
      const std::size_t i = column.at(name);
      if (i >= f.size()) bad_pose(source, lines[k].number, "no field for column " + std::string(name));
      return number_of(f[i], source, lines[k].number);
    };
    RobotPose p;
    p.line = lines[k].number;
    p.pose.translation() = Eigen::Vector3d(value("x"), value("y"), value("z"));
    if (quaternion) {
      const Eigen::Quaterniond q(value("qw"), value("qx"), value("qy"), value("qz"));
      if (std::abs(q.norm() - 1) > kPoseTolerance)
        bad_pose(source, p.line, "the quaternion's norm is " + std::to_string(q.norm()) + ", not 1");
      p.pose.linear() = q.normalized().toRotationMatrix();
    } else {
      p.pose.linear() = rotation_of(rotation, Eigen::Vector3d(value("rx"), value("ry"), value("rz")), source, p.line);
    }
    if (time_column) {
      if (*time_column >= f.size()) bad_pose(source, p.line, "no field for column " + header[*time_column]);
      p.time_ns = time_of(f[*time_column], *ns_per_unit, source, p.line);
    }
    check_reach(p, source);
    poses.push_back(p);
  }
  return poses;
}

std::vector<RobotPose> parse_matrices(const std::vector<Line>& lines, const std::string& source) {
  std::vector<RobotPose> poses;
  std::vector<double> m;  // the pose being read, row-major
  int first_line = 0;
  for (const Line& l : lines) {
    const std::vector<std::string> f = fields_of(l.text, " \t,", false);
    if (f.size() == 7 || f.size() == 8)
      bad_pose(source, l.number,
               std::to_string(f.size()) +
                   " numbers and no header: a trajectory row (TUM's is t x y z qx qy qz qw)? Name the columns in a "
                   "first line, e.g. t x y z qx qy qz qw");
    if (f.size() != 16 && f.size() != 12 && f.size() != 4)
      bad_pose(source, l.number,
               std::to_string(f.size()) +
                   " numbers: a line holds a 4x4 matrix (16 numbers), its top 3x4 (12, as KITTI's poses) or one of "
                   "a 4x4's rows (4)");
    if (f.size() != 4 && !m.empty()) bad_pose(source, l.number, "a whole matrix inside an unfinished one");
    if (m.empty()) first_line = l.number;
    for (const std::string& s : f) m.push_back(number_of(s, source, l.number));
    if (f.size() == 12) m.insert(m.end(), {0, 0, 0, 1});
    if (m.size() < 16) continue;
    const Eigen::Matrix4d t = Eigen::Map<const Eigen::Matrix<double, 4, 4, Eigen::RowMajor>>(m.data());
    const Eigen::Matrix3d r = t.topLeftCorner<3, 3>();
    if ((t.row(3) - Eigen::RowVector4d(0, 0, 0, 1)).norm() > kPoseTolerance)
      bad_pose(source, first_line, "the last row is not 0 0 0 1");
    if ((r.transpose() * r - Eigen::Matrix3d::Identity()).norm() > kPoseTolerance || r.determinant() < 0)
      bad_pose(source, first_line, "the rotation is not orthonormal with determinant +1 (within 1e-3)");
    RobotPose p;
    p.line = first_line;
    p.pose.linear() = Eigen::Quaterniond(r).normalized().toRotationMatrix();
    p.pose.translation() = t.topRightCorner<3, 1>();
    check_reach(p, source);
    poses.push_back(p);
    m.clear();
  }
  if (!m.empty()) bad_pose(source, first_line, "an unfinished 4x4 matrix (" + std::to_string(m.size()) + " numbers)");
  return poses;
}

}  // namespace

RotationColumns rotation_columns(const std::string& name) {
  if (name == "rotvec") return RotationColumns::kRotationVector;
  if (name == "rpy") return RotationColumns::kRpy;
  if (name == "rpy-deg") return RotationColumns::kRpyDeg;
  throw std::invalid_argument("rotation columns '" + name + "': expected rotvec, rpy or rpy-deg");
}

std::vector<RobotPose> parse_robot_poses(std::istream& in, const std::string& source, RotationColumns rotation) {
  std::vector<Line> lines;
  std::string text;
  for (int number = 1; std::getline(in, text); ++number) {
    const std::string t = trimmed(text);
    if (!t.empty() && t.front() != '#') lines.push_back({t, number});
  }
  if (lines.empty()) throw CalibrationError(source + ": no robot poses");
  const bool header = std::any_of(lines.front().text.begin(), lines.front().text.end(), [](char c) {
    return std::isalpha(static_cast<unsigned char>(c)) && c != 'e' && c != 'E';
  });
  if (!header && rotation != RotationColumns::kUnnamed)
    bad_pose(source, lines.front().number,
             "the poses are 4x4 matrices, yet a meaning of rx,ry,rz (rotvec, rpy or rpy-deg) was named");
  std::vector<RobotPose> poses = header ? parse_csv(lines, source, rotation) : parse_matrices(lines, source);
  if (poses.empty()) throw CalibrationError(source + ": no robot poses");
  return poses;
}

std::vector<RobotPose> read_robot_poses(const std::string& path, RotationColumns rotation) {
  std::istringstream in(files::read_text_or_throw<CalibrationError>(path, files::kDatasetFile));
  return parse_robot_poses(in, path, rotation);
}

std::vector<RobotPose> parse_timed_poses(std::istream& in, const std::string& source, RotationColumns rotation) {
  std::vector<RobotPose> poses = parse_robot_poses(in, source, rotation);
  if (!poses.front().time_ns)
    bad_pose(source, poses.front().line,
             "the poses have no time column: name one in the header, e.g. timestamp [ns] (nanoseconds) or "
             "timestamp [s]");
  for (std::size_t i = 1; i < poses.size(); ++i)
    if (*poses[i].time_ns <= *poses[i - 1].time_ns)
      bad_pose(source, poses[i].line,
               "time " + std::to_string(*poses[i].time_ns) + " ns is not after the previous pose's (line " +
                   std::to_string(poses[i - 1].line) + ", " + std::to_string(*poses[i - 1].time_ns) + " ns)");
  return poses;
}

std::vector<RobotPose> read_timed_poses(const std::string& path, RotationColumns rotation) {
  std::istringstream in(files::read_text_or_throw<CalibrationError>(path, files::kDatasetFile));
  return parse_timed_poses(in, path, rotation);
}

PoseAtTime pose_at_time(const std::vector<RobotPose>& timed, std::int64_t time_ns, double max_gap_s) {
  PoseAtTime out;
  const auto seconds = [](std::int64_t ns) { return model::shortest_number_text(static_cast<double>(ns) * 1e-9); };
  const auto after = std::lower_bound(timed.begin(), timed.end(), time_ns,
                                      [](const RobotPose& p, std::int64_t t) { return *p.time_ns < t; });
  if (after != timed.end() && *after->time_ns == time_ns) {
    out.pose = after->pose;
    out.line_before = out.line_after = after->line;
    return out;
  }
  if (timed.empty() || after == timed.begin() || after == timed.end()) {
    out.refusal = timed.empty() ? "no timed poses"
                                : "no pose " + std::string(after == timed.begin() ? "before" : "after") +
                                      " it: the poses run from " + std::to_string(*timed.front().time_ns) + " to " +
                                      std::to_string(*timed.back().time_ns) + " ns";
    return out;
  }
  const RobotPose& a = *(after - 1);
  const RobotPose& b = *after;
  out.line_before = a.line;
  out.line_after = b.line;
  const std::int64_t gap_ns = *b.time_ns - *a.time_ns;
  if (static_cast<double>(gap_ns) * 1e-9 > max_gap_s) {
    out.refusal = "the poses around it (lines " + std::to_string(a.line) + " and " + std::to_string(b.line) + ") are " +
                  seconds(gap_ns) + " s apart, more than " + model::shortest_number_text(max_gap_s) +
                  " s: the pose source lost the body between them?";
    return out;
  }
  const double s = static_cast<double>(time_ns - *a.time_ns) / static_cast<double>(gap_ns);
  Eigen::Isometry3d pose = Eigen::Isometry3d::Identity();
  pose.linear() =
      Eigen::Quaterniond(a.pose.linear()).slerp(s, Eigen::Quaterniond(b.pose.linear())).normalized().toRotationMatrix();
  pose.translation() = (1 - s) * a.pose.translation() + s * b.pose.translation();
  out.pose = pose;
  return out;
}

std::optional<std::int64_t> image_time_ns(const std::string& path) {
  const std::string stem = std::filesystem::path(path).stem().string();
  const std::size_t point = stem.find('.');
  const std::string whole = stem.substr(0, point);
  const std::string fraction = point == std::string::npos ? "" : stem.substr(point + 1);
  const auto digits = [](const std::string& t) {
    return !t.empty() && std::all_of(t.begin(), t.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
  };
  if (!digits(whole) || (point != std::string::npos && !digits(fraction))) return std::nullopt;
  errno = 0;
  const long long w = std::strtoll(whole.c_str(), nullptr, 10);
  if (errno == ERANGE) return std::nullopt;
  if (point == std::string::npos) return static_cast<std::int64_t>(w);
  // Seconds with at most nanoseconds' decimals, within the 64-bit range of nanoseconds.
  constexpr long long kNsPerS = 1'000'000'000;
  if (fraction.size() > 9 || w > std::numeric_limits<long long>::max() / kNsPerS - 1) return std::nullopt;
  const std::string ns = fraction + std::string(9 - fraction.size(), '0');
  return static_cast<std::int64_t>(w * kNsPerS + std::strtoll(ns.c_str(), nullptr, 10));
}

}  // namespace kincal::camera
