#include "host/model/dataset.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <istream>
#include <map>
#include <optional>
#include <ostream>
#include <sstream>
#include <utility>

#include "host/files/input_file.hpp"
#include "host/model/csv_fields.hpp"
#include "host/model/number_text.hpp"

namespace kincal::model {

namespace {

// An id as a field of the file: quoted (RFC 4180) when it holds what the split would change.
std::string quoted_field(const std::string& text) {
  if (!text.empty() && text.find_first_of(",\"") == std::string::npos && trim_field(text) == text) return text;
  std::string out = "\"";
  for (char c : text) out += c == '"' ? std::string("\"\"") : std::string(1, c);
  return out + '"';
}

// The pose covariance's columns beyond the position block, with their place in the 6x6.
struct CovarianceColumn {
  const char* name;
  int row, col;
};
constexpr CovarianceColumn kPoseCovariance[] = {{"cxrx", 0, 3},  {"cxry", 0, 4},  {"cxrz", 0, 5},  {"cyrx", 1, 3},
                                                {"cyry", 1, 4},  {"cyrz", 1, 5},  {"czrx", 2, 3},  {"czry", 2, 4},
                                                {"czrz", 2, 5},  {"crxrx", 3, 3}, {"crxry", 3, 4}, {"crxrz", 3, 5},
                                                {"cryry", 4, 4}, {"cryrz", 4, 5}, {"crzrz", 5, 5}};

bool skipped(const std::string& line) {
  const std::string t = trim_field(line);
  return t.empty() || t[0] == '#';
}

double parse_number(const std::string& field, const std::string& column, const std::string& source, int line) {
  double v = 0.0;
  const char* first = field.data();
  const char* last = field.data() + field.size();
  if (first != last && *first == '+') ++first;
  const auto [end, ec] = std::from_chars(first, last, v);
  if (field.empty()) fail_at(source, line, "column " + column + " is empty");
  if (ec != std::errc() || end != last)
    fail_at(source, line, "column " + column + ": '" + files::excerpt(field) + "' is not a number");
  if (!std::isfinite(v)) fail_at(source, line, "column " + column + " is not finite");
  return v;
}

// Column name -> index; q1..qN count.
struct Header {
  std::map<std::string, std::size_t> index;
  int joints = 0;
  std::size_t fields = 0;
};

Header parse_header(const std::string& line, const std::string& source, int number, bool joints_only) {
  Header h;
  const std::vector<std::string> names = split_fields(line, ',');
  h.fields = names.size();
  for (std::size_t i = 0; i < names.size(); ++i) {
    const std::string& n = names[i];
    if (n.empty()) fail_at(source, number, "header: column " + std::to_string(i + 1) + " has no name");
    if (!h.index.emplace(n, i).second)
      fail_at(source, number, "header: column '" + files::excerpt(n) + "' appears twice");
  }
  while (h.index.count("q" + std::to_string(h.joints + 1))) ++h.joints;
  if (h.joints == 0) fail_at(source, number, "header: no joint columns (expected q1, q2, ...)");
  if (joints_only) return h;
  static const char* const kKnown[] = {"x",   "y",   "z",   "qw",  "qx",  "qy",    "qz", "cxx",
                                       "cxy", "cxz", "cyy", "cyz", "czz", "sigma", "id"};
  for (const auto& [name, i] : h.index) {
    bool known = false;
    for (const char* k : kKnown) known = known || name == k;
    for (const CovarianceColumn& k : kPoseCovariance) known = known || name == k.name;
    if (name.size() > 1 && name[0] == 'q' && name.find_first_not_of("0123456789", 1) == std::string::npos) {
      // More digits than any joint count: out of range without overflowing stoi (a fuzzer find).
      const int j = name.size() <= 4 ? std::stoi(name.substr(1)) : 0;
      if (j < 1 || j > h.joints)
        fail_at(source, number,
                "header: column '" + files::excerpt(name) + "' but no q" + std::to_string(h.joints + 1));
      known = true;
    }
    if (!known) fail_at(source, number, "header: unknown column '" + files::excerpt(name) + "'");
  }
  for (const char* k : {"x", "y", "z"})
    if (!h.index.count(k)) fail_at(source, number, std::string("header: missing column '") + k + "'");
  return h;
}

int count_of(const Header& h, std::initializer_list<const char*> names) {
  int n = 0;
  for (const char* k : names) n += h.index.count(k) ? 1 : 0;
  return n;
}

// One data row, its fields checked against the header's count.
struct Row {
  const Header& header;
  const std::vector<std::string>& fields;
  const std::string& source;
  int line = 0;

  double value(const std::string& column) const {
    return parse_number(fields[header.index.at(column)], column, source, line);
  }
  std::vector<double> joints() const {
    std::vector<double> q;
    for (int j = 1; j <= header.joints; ++j) q.push_back(value("q" + std::to_string(j)));
    return q;
  }
};

// The one reading loop of both file kinds: skips blank and '#' lines, hands the header to
// on_header(header, line) and every later line to on_row(row). joints_only: a joints file (the
// header needs only q1..qN, and other columns are ignored). Fails without a header row.
template <class OnHeader, class OnRow>
void read_table(std::istream& in, const std::string& source, bool joints_only, OnHeader on_header, OnRow on_row) {
  std::string line;
  int number = 0;
  std::optional<Header> h;
  std::size_t rows = 0;
  while (std::getline(in, line)) {
    ++number;
    if (skipped(line)) continue;
    if (!h) {
      h = parse_header(line, source, number, joints_only);
      on_header(*h, number);
      continue;
    }
    if (rows++ == kMaxRows) fail_at(source, number, too_many_rows());
    const std::optional<std::vector<std::string>> split = split_quoted_fields(line, ',');
    if (!split) fail_at(source, number, "a double quote is not closed, or text follows a closing quote");
    const std::vector<std::string>& fields = *split;
    if (fields.size() != h->fields)
      fail_at(
          source, number,
          "expected " + std::to_string(h->fields) + " fields as in the header, found " + std::to_string(fields.size()));
    on_row(Row{*h, fields, source, number});
  }
  if (!h)
    fail_at(source, number,
            joints_only ? "no header row (expected q1,...,qN)" : "no header row (expected q1,...,qN,x,y,z)");
}

}  // namespace

std::string too_many_rows() {
  return "more than " + std::to_string(kMaxRows) +
         " data rows, the most a dataset holds (a calibration needs hundreds: keep every n-th row)";
}

Dataset parse_dataset(std::istream& in, const std::string& source) {
  Dataset data;
  data.source = source;
  bool has_id = false;
  const auto on_header = [&](const Header& h, int number) {
    data.joint_count = h.joints;
    const int quaternion = count_of(h, {"qw", "qx", "qy", "qz"});
    if (quaternion != 0 && quaternion != 4)
      fail_at(source, number, "header: an orientation needs all of qw, qx, qy, qz");
    data.has_orientation = quaternion == 4;
    const int covariance = count_of(h, {"cxx", "cxy", "cxz", "cyy", "cyz", "czz"});
    if (covariance != 0 && covariance != 6)
      fail_at(source, number, "header: a covariance needs all of cxx, cxy, cxz, cyy, cyz, czz");
    if (covariance == 6 && h.index.count("sigma"))
      fail_at(source, number, "header: give a covariance or sigma, not both");
    data.noise = covariance == 6          ? NoiseColumns::covariance
                 : h.index.count("sigma") ? NoiseColumns::sigma
                                          : NoiseColumns::none;
    int pose = 0;
    for (const CovarianceColumn& k : kPoseCovariance) pose += h.index.count(k.name) ? 1 : 0;
    if (pose != 0 && pose != 15) fail_at(source, number, "header: a pose covariance needs all of cxrx..crzrz");
    if (pose == 15 && (covariance != 6 || !data.has_orientation))
      fail_at(source, number,
              "header: a pose covariance (cxrx..crzrz) needs the orientation (qw..qz) and the position covariance "
              "(cxx..czz)");
    data.has_pose_covariance = pose == 15;
    has_id = h.index.count("id") != 0;
  };
  const auto values = [&](const Row& row, Measurement& m) {
    const auto value = [&](const char* column) { return row.value(column); };
    m.q = row.joints();
    m.position = Vector3(value("x"), value("y"), value("z"));
    if (data.has_orientation) {
      Eigen::Quaterniond q(value("qw"), value("qx"), value("qy"), value("qz"));
      if (std::abs(q.norm() - 1.0) > 1e-3)
        fail_at(
            source, row.line,
            "the quaternion (qw, qx, qy, qz) is not a unit quaternion (norm " + shortest_number_text(q.norm()) + ")");
      m.orientation = q.normalized();
    }
    if (data.noise == NoiseColumns::covariance) {
      Matrix3 c;
      c << value("cxx"), value("cxy"), value("cxz"), value("cxy"), value("cyy"), value("cyz"), value("cxz"),
          value("cyz"), value("czz");
      Eigen::LLT<Matrix3> llt(c);
      if (llt.info() != Eigen::Success || c.diagonal().minCoeff() <= 0.0)
        fail_at(source, row.line, "the covariance (cxx..czz) is not positive definite");
      m.covariance = c;
      if (data.has_pose_covariance) {
        Matrix6 p;
        p.topLeftCorner<3, 3>() = c;
        for (const CovarianceColumn& k : kPoseCovariance) p(k.row, k.col) = p(k.col, k.row) = row.value(k.name);
        Eigen::LLT<Matrix6> pose_llt(p);
        if (pose_llt.info() != Eigen::Success || p.diagonal().minCoeff() <= 0.0)
          fail_at(source, row.line, "the pose covariance (cxx..crzrz) is not positive definite");
        m.pose_covariance = p;
      }
    } else if (data.noise == NoiseColumns::sigma) {
      const double s = value("sigma");
      if (!(s > 0.0)) fail_at(source, row.line, "sigma must be positive");
      m.covariance = Matrix3::Identity() * (s * s);
    }
  };
  const auto on_row = [&](const Row& row) {
    Measurement m;
    m.line = row.line;
    if (has_id) {
      m.id = row.fields[row.header.index.at("id")];
      if (m.id.empty()) fail_at(source, row.line, "column id is empty");
    }
    try {
      values(row, m);
    } catch (const InputError& e) {
      if (m.id.empty()) throw;
      throw InputError(e.what() + id_suffix(m));
    }
    data.rows.push_back(std::move(m));
  };
  read_table(in, source, false, on_header, on_row);
  return data;
}

Dataset read_dataset(const std::string& path) {
  std::istringstream in(files::read_text_or_throw<InputError>(path, files::kDatasetFile));
  return parse_dataset(in, path);
}

std::vector<std::vector<double>> parse_joints(std::istream& in, const std::string& source) {
  std::vector<std::vector<double>> rows;
  read_table(
      in, source, true, [](const Header&, int) {}, [&](const Row& row) { rows.push_back(row.joints()); });
  return rows;
}

std::vector<std::vector<double>> read_joints(const std::string& path) {
  std::istringstream in(files::read_text_or_throw<InputError>(path, files::kDatasetFile));
  return parse_joints(in, path);
}

void check_joint_count(const RobotModel& model, int data_joints, const std::string& source) {
  if (data_joints != model.joint_count())
    throw InputError(source + ": the data has " + std::to_string(data_joints) + " joint columns but the model '" +
                     model.name + "' has " + std::to_string(model.joint_count()) + " joints");
}

Measurement pose_row(std::vector<double> q, const Eigen::Isometry3d& device_T_tool, const Matrix6& covariance,
                     int line) {
  Measurement m;
  m.q = std::move(q);
  m.position = device_T_tool.translation();
  m.orientation = Eigen::Quaterniond(device_T_tool.linear()).normalized();
  m.covariance = covariance.topLeftCorner<3, 3>();
  m.pose_covariance = covariance;
  m.line = line;
  return m;
}

bool same_readings(const Measurement& a, const Measurement& b) {
  if (a.q.size() != b.q.size()) return false;
  for (std::size_t j = 0; j < a.q.size(); ++j)
    if (!(std::abs(a.q[j] - b.q[j]) <= kSameReading)) return false;
  return true;
}

namespace {
// Weights of incommensurate ratios: distinct configurations meet in a window only by chance.
double reading_key_weight(std::size_t joint) { return 1.0 + 0.6180339887 * static_cast<double>(joint); }
}  // namespace

double reading_key(const std::vector<double>& q) {
  double key = 0.0;
  for (std::size_t j = 0; j < q.size(); ++j) key += reading_key_weight(j) * q[j];
  return key;
}

double reading_key_window(std::size_t joints) {
  double sum = 0.0;
  for (std::size_t j = 0; j < joints; ++j) sum += reading_key_weight(j);
  return kSameReading * sum;
}

std::vector<int> configuration_of_rows(const Dataset& data) {
  // The rows sorted by reading_key(): each compares with those within its window only, and joins
  // the first of them at its readings (union-find, the file's first row of each configuration the
  // root) -- one match, so that a pose measured 100,000 times costs as many comparisons.
  const std::size_t n = data.rows.size();
  std::vector<double> key(n);
  for (std::size_t i = 0; i < n; ++i) key[i] = reading_key(data.rows[i].q);
  std::vector<std::size_t> sorted(n);
  for (std::size_t i = 0; i < n; ++i) sorted[i] = i;
  std::sort(sorted.begin(), sorted.end(), [&](std::size_t a, std::size_t b) { return key[a] < key[b]; });
  std::vector<std::size_t> root(n);
  for (std::size_t i = 0; i < n; ++i) root[i] = i;
  const auto find = [&](std::size_t i) {
    while (root[i] != i) i = root[i] = root[root[i]];
    return i;
  };
  const double window = reading_key_window(static_cast<std::size_t>(data.joint_count));
  for (std::size_t s = 0; s < n; ++s)
    for (std::size_t t = s; t-- > 0 && key[sorted[s]] - key[sorted[t]] <= window;)
      if (same_readings(data.rows[sorted[s]], data.rows[sorted[t]])) {
        const std::size_t a = find(sorted[s]), b = find(sorted[t]);
        root[std::max(a, b)] = std::min(a, b);
        break;
      }
  std::vector<int> out(n, -1);
  int next = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const std::size_t r = find(i);
    out[i] = r == i ? next++ : out[r];
  }
  return out;
}

std::string id_suffix(const Measurement& row) {
  return row.id.empty() ? std::string() : " (id " + files::excerpt(row.id) + ")";
}

void write_dataset(std::ostream& out, const Dataset& data) {
  bool covariance = !data.rows.empty(), id = !data.rows.empty();
  for (const Measurement& m : data.rows) {
    covariance = covariance && m.covariance.has_value();
    id = id && !m.id.empty();
  }
  bool pose = data.has_orientation && covariance;
  for (const Measurement& m : data.rows) pose = pose && m.pose_covariance.has_value();
  for (int j = 1; j <= data.joint_count; ++j) out << 'q' << j << ',';
  out << "x,y,z";
  if (data.has_orientation) out << ",qw,qx,qy,qz";
  if (covariance) out << ",cxx,cxy,cxz,cyy,cyz,czz";
  if (pose)
    for (const CovarianceColumn& k : kPoseCovariance) out << ',' << k.name;
  if (id) out << ",id";
  out << '\n';
  for (const Measurement& m : data.rows) {
    for (double q : m.q) out << shortest_number_text(q) << ',';
    out << shortest_number_text(m.position.x()) << ',' << shortest_number_text(m.position.y()) << ','
        << shortest_number_text(m.position.z());
    if (data.has_orientation) {
      const Eigen::Quaterniond q = m.orientation.value_or(Eigen::Quaterniond::Identity());
      out << ',' << shortest_number_text(q.w()) << ',' << shortest_number_text(q.x()) << ','
          << shortest_number_text(q.y()) << ',' << shortest_number_text(q.z());
    }
    if (covariance) {
      const Matrix3& c = *m.covariance;
      out << ',' << shortest_number_text(c(0, 0)) << ',' << shortest_number_text(c(0, 1)) << ','
          << shortest_number_text(c(0, 2)) << ',' << shortest_number_text(c(1, 1)) << ','
          << shortest_number_text(c(1, 2)) << ',' << shortest_number_text(c(2, 2));
    }
    if (pose)
      for (const CovarianceColumn& k : kPoseCovariance)
        out << ',' << shortest_number_text((*m.pose_covariance)(k.row, k.col));
    if (id) out << ',' << quoted_field(m.id);
    out << '\n';
  }
}

}  // namespace kincal::model
