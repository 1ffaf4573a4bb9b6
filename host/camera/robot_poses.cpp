#include "host/camera/robot_poses.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
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

}  // namespace kincal::camera
