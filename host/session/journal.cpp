#include "host/session/journal.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <ostream>
#include <span>
#include <string_view>
#include <utility>

#include <Eigen/Cholesky>

#include "host/files/input_file.hpp"
#include "shared/crc32.hpp"

namespace kincal::session {

namespace {

constexpr std::string_view kCrcKey = " crc=";
constexpr std::string_view kMagic = "kincal-journal";
constexpr int kVersion = 1;

// The pose covariance's entries beyond the position block, in the r= field's order (the
// dataset's cxrx..crzrz): the position-rotation block row by row, then the rotation block's
// upper triangle.
constexpr std::array<int, 15> kRestRow{0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3, 4, 4, 5};
constexpr std::array<int, 15> kRestCol{3, 4, 5, 3, 4, 5, 3, 4, 5, 3, 4, 5, 4, 5, 5};

[[noreturn]] void fail(const std::string& path, int line, const std::string& what) {
  throw JournalError(path + (line > 0 ? ":" + std::to_string(line) : std::string()) + ": " + what);
}

[[noreturn]] void fail_os(const std::string& path, const std::string& what) {
  fail(path, 0, what + ": " + std::strerror(errno));
}

std::string with_crc(const std::string& payload) {
  char hex[9];
  std::snprintf(hex, sizeof hex, "%08x", static_cast<unsigned>(shared::crc32_text(payload)));
  return payload + std::string(kCrcKey) + hex + "\n";
}

void append_number(std::string& out, double v) {
  char buffer[32];
  const auto [end, ec] = std::to_chars(buffer, buffer + sizeof buffer, v);
  out.append(buffer, ec == std::errc() ? end : buffer);
}

void append_list(std::string& out, std::string_view key, std::span<const double> values) {
  out += ' ';
  out += key;
  out += '=';
  for (std::size_t i = 0; i < values.size(); ++i) {
    if (i > 0) out += ',';
    append_number(out, values[i]);
  }
}

bool plain_byte(char c) { return c >= '!' && c <= '~' && c != '%'; }

std::string escape(const std::string& value) {
  std::string out;
  for (const char c : value) {
    if (plain_byte(c)) {
      out += c;
    } else {
      char hex[4];
      std::snprintf(hex, sizeof hex, "%%%02X", static_cast<unsigned>(static_cast<unsigned char>(c)));
      out += hex;
    }
  }
  return out;
}

bool valid_key(const std::string& key) {
  return !key.empty() && std::all_of(key.begin(), key.end(), [](char c) {
    return (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '_' || c == '.' ||
           c == '-';
  });
}

std::string header_line(const std::string& path, const JournalIdentity& identity) {
  if (identity.joint_count < 1) fail(path, 0, "a journal needs at least one joint");
  std::string payload =
      std::string(kMagic) + "=" + std::to_string(kVersion) + " joints=" + std::to_string(identity.joint_count) +
      " orientation=" + (identity.orientation ? "1" : "0") + " covariance=" + (identity.covariance ? "1" : "0");
  if (identity.pose_covariance && !(identity.orientation && identity.covariance))
    fail(path, 0, "a journal of pose covariances needs the orientation and the covariance");
  if (identity.pose_covariance) payload += " pose_covariance=1";
  for (const auto& [key, value] : identity.items) {
    if (!valid_key(key)) fail(path, 0, "identity key '" + key + "' is not of [A-Za-z0-9_.-]+");
    payload += " id." + key + "=" + escape(value);
  }
  return with_crc(payload);
}

// ---- Reading ------------------------------------------------------------------------------

// A line's fields, after its CRC has been checked.
struct Fields {
  std::vector<std::pair<std::string_view, std::string_view>> items;
};

// Why a line is bad, or nothing.
std::optional<std::string> split_checked(std::string_view line, Fields& fields) {
  const std::size_t at = line.rfind(kCrcKey);
  if (at == std::string_view::npos) return "no crc= field";
  const std::string_view hex = line.substr(at + kCrcKey.size());
  std::uint32_t stored = 0;
  const auto [end, ec] = std::from_chars(hex.data(), hex.data() + hex.size(), stored, 16);
  if (hex.size() != 8 || ec != std::errc() || end != hex.data() + hex.size()) return "crc= is not 8 hex digits";
  const std::string_view payload = line.substr(0, at);
  if (shared::crc32_text(payload) != stored) return "CRC mismatch (the line is damaged)";
  std::size_t start = 0;
  while (start <= payload.size()) {
    const std::size_t space = std::min(payload.find(' ', start), payload.size());
    const std::string_view token = payload.substr(start, space - start);
    const std::size_t equals = token.find('=');
    if (equals == std::string_view::npos) return "field '" + std::string(token) + "' has no '='";
    fields.items.emplace_back(token.substr(0, equals), token.substr(equals + 1));
    start = space + 1;
  }
  return std::nullopt;
}

class LineReader {
 public:
  LineReader(const Fields& fields, const std::string& path, int line) : fields_(fields), path_(path), line_(line) {}

  bool at_end() const { return next_ == fields_.items.size(); }
  std::string_view peek_key() const { return at_end() ? std::string_view() : fields_.items[next_].first; }

  std::string_view take(std::string_view key) {
    if (at_end() || fields_.items[next_].first != key)
      fail(path_, line_, "expected field '" + std::string(key) + "', found '" + std::string(peek_key()) + "'");
    return fields_.items[next_++].second;
  }
  std::pair<std::string_view, std::string_view> take_any() { return fields_.items[next_++]; }

  template <class Int>
  Int integer(std::string_view key) {
    const std::string_view text = take(key);
    Int v{};
    const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
    if (text.empty() || ec != std::errc() || end != text.data() + text.size())
      fail(path_, line_, std::string(key) + "='" + std::string(text) + "' is not an integer");
    return v;
  }

  std::vector<double> numbers(std::string_view key, std::size_t count) {
    const std::string_view text = take(key);
    std::vector<double> values;
    const char* p = text.data();
    const char* const last = text.data() + text.size();
    while (true) {
      double v = 0.0;
      const auto [end, ec] = std::from_chars(p, last, v);
      if (ec != std::errc() || (end != last && *end != ','))
        fail(path_, line_, std::string(key) + "='" + std::string(text) + "' is not a list of numbers");
      values.push_back(v);
      if (end == last) break;
      p = end + 1;
    }
    if (values.size() != count)
      fail(path_, line_,
           std::string(key) + " has " + std::to_string(values.size()) + " numbers, expected " + std::to_string(count));
    return values;
  }

 private:
  const Fields& fields_;
  const std::string& path_;
  int line_;
  std::size_t next_ = 0;
};

std::string unescape(std::string_view text, const std::string& path, int line) {
  std::string out;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] != '%') {
      out += text[i];
      continue;
    }
    unsigned byte = 0;
    const char* first = text.data() + i + 1;
    const auto [end, ec] = std::from_chars(first, first + std::min<std::size_t>(2, text.size() - i - 1), byte, 16);
    if (ec != std::errc() || end != first + 2) fail(path, line, "bad %-escape in an identity value");
    out += static_cast<char>(byte);
    i += 2;
  }
  return out;
}

JournalIdentity parse_header(const Fields& fields, const std::string& path) {
  LineReader r(fields, path, 1);
  if (r.peek_key() != kMagic)
    fail(path, 1, "not a kincal journal (the first line does not start with kincal-journal=)");
  const int version = r.integer<int>(kMagic);
  if (version != kVersion)
    fail(path, 1,
         "journal format version " + std::to_string(version) + ", this build reads " + std::to_string(kVersion));
  JournalIdentity identity;
  identity.joint_count = r.integer<int>("joints");
  identity.orientation = r.integer<int>("orientation") != 0;
  identity.covariance = r.integer<int>("covariance") != 0;
  if (r.peek_key() == "pose_covariance") identity.pose_covariance = r.integer<int>("pose_covariance") != 0;
  if (identity.joint_count < 1) fail(path, 1, "joints must be at least 1");
  while (!r.at_end()) {
    const auto [key, value] = r.take_any();
    if (key.substr(0, 3) != "id.") fail(path, 1, "unexpected header field '" + std::string(key) + "'");
    identity.items[std::string(key.substr(3))] = unescape(value, path, 1);
  }
  return identity;
}

JournalRecord parse_record(const Fields& fields, const JournalIdentity& identity, const std::string& path, int line) {
  LineReader r(fields, path, line);
  JournalRecord record;
  record.line = line;
  record.pose_index = r.integer<int>("pose");
  record.sequence = r.integer<std::uint32_t>("seq");
  record.platform_time_us = r.integer<std::uint64_t>("time_us");
  record.q = r.numbers("q", static_cast<std::size_t>(identity.joint_count));
  const std::vector<double> p = r.numbers("p", 3);
  record.position_m = model::Vector3(p[0], p[1], p[2]);
  if (identity.orientation) {
    const std::vector<double> o = r.numbers("o", 4);
    record.orientation = Eigen::Quaterniond(o[0], o[1], o[2], o[3]);
  }
  if (identity.covariance) {
    const std::vector<double> c = r.numbers("c", 6);
    model::Matrix3 m;
    m << c[0], c[1], c[2], c[1], c[3], c[4], c[2], c[4], c[5];
    record.covariance_m2 = m;
  }
  if (identity.pose_covariance) {
    const std::vector<double> r6 = r.numbers("r", kRestRow.size());
    model::Matrix6 m = model::Matrix6::Zero();
    m.topLeftCorner<3, 3>() = *record.covariance_m2;
    for (std::size_t k = 0; k < r6.size(); ++k) {
      m(kRestRow[k], kRestCol[k]) = m(kRestCol[k], kRestRow[k]) = r6[k];
    }
    record.pose_covariance = m;
  }
  if (!r.at_end()) fail(path, line, "unexpected field '" + std::string(r.peek_key()) + "'");
  return record;
}

// What differs between the journal's identity and the caller's, or "" if nothing.
std::string identity_differences(const JournalIdentity& journal, const JournalIdentity& now) {
  std::string out;
  const auto differ = [&out](const std::string& what, const std::string& then_value, const std::string& now_value) {
    out += (out.empty() ? "" : "; ") + what + " is " + then_value + " in the journal, " + now_value + " now";
  };
  if (journal.joint_count != now.joint_count)
    differ("joints", std::to_string(journal.joint_count), std::to_string(now.joint_count));
  if (journal.orientation != now.orientation)
    differ("orientation", journal.orientation ? "on" : "off", now.orientation ? "on" : "off");
  if (journal.covariance != now.covariance)
    differ("covariance", journal.covariance ? "on" : "off", now.covariance ? "on" : "off");
  if (journal.pose_covariance != now.pose_covariance)
    differ("pose covariance", journal.pose_covariance ? "on" : "off", now.pose_covariance ? "on" : "off");
  std::map<std::string, std::pair<std::optional<std::string>, std::optional<std::string>>> keys;
  for (const auto& [k, v] : journal.items) keys[k].first = v;
  for (const auto& [k, v] : now.items) keys[k].second = v;
  const auto shown = [](const std::optional<std::string>& v) { return v ? "'" + *v + "'" : std::string("absent"); };
  for (const auto& [k, values] : keys)
    if (values.first != values.second) differ(k, shown(values.first), shown(values.second));
  return out;
}

// line: where the record is in the journal, 0 before it is appended.
void check_record(const JournalRecord& record, const JournalIdentity& identity, const std::string& path, int line) {
  const std::string where = "pose " + std::to_string(record.pose_index) + ": ";
  const auto reject = [&](const std::string& what) { session::fail(path, line, where + what); };
  if (record.pose_index < 0) reject("a pose index must not be negative");
  if (record.q.size() != static_cast<std::size_t>(identity.joint_count))
    reject(std::to_string(record.q.size()) + " joint readings, the journal has " +
           std::to_string(identity.joint_count) + " joints");
  if (record.orientation.has_value() != identity.orientation)
    reject((identity.orientation ? "no orientation, the journal needs one" : "an orientation, the journal has none"));
  if (record.covariance_m2.has_value() != identity.covariance)
    reject((identity.covariance ? "no covariance, the journal needs one" : "a covariance, the journal has none"));
  if (record.pose_covariance.has_value() != identity.pose_covariance)
    reject((identity.pose_covariance ? "no pose covariance, the journal needs one"
                                     : "a pose covariance, the journal has none"));
  const bool finite = std::all_of(record.q.begin(), record.q.end(), [](double v) { return std::isfinite(v); }) &&
                      record.position_m.allFinite() &&
                      (!record.orientation || record.orientation->coeffs().allFinite()) &&
                      (!record.covariance_m2 || record.covariance_m2->allFinite()) &&
                      (!record.pose_covariance || record.pose_covariance->allFinite());
  if (!finite) reject("a number is not finite");
  if (record.orientation && std::abs(record.orientation->norm() - 1.0) > 1e-3)
    reject("the orientation is not a unit quaternion");
  if (record.covariance_m2) {
    const model::Matrix3& c = *record.covariance_m2;
    if (c != c.transpose() || Eigen::LLT<model::Matrix3>(c).info() != Eigen::Success)
      reject("the covariance is not symmetric positive definite");
  }
  if (record.pose_covariance) {
    const model::Matrix6& c = *record.pose_covariance;
    if (c != c.transpose() || Eigen::LLT<model::Matrix6>(c).info() != Eigen::Success)
      reject("the pose covariance is not symmetric positive definite");
    if (c.topLeftCorner<3, 3>() != *record.covariance_m2)
      reject("the pose covariance's position block is not the covariance");
  }
}

std::string record_line(const JournalRecord& record) {
  std::string payload = "pose=" + std::to_string(record.pose_index) + " seq=" + std::to_string(record.sequence) +
                        " time_us=" + std::to_string(record.platform_time_us);
  append_list(payload, "q", record.q);
  append_list(payload, "p", std::span<const double>(record.position_m.data(), 3));
  if (record.orientation) {
    const Eigen::Quaterniond& o = *record.orientation;
    const double values[] = {o.w(), o.x(), o.y(), o.z()};
    append_list(payload, "o", values);
  }
  if (record.covariance_m2) {
    const model::Matrix3& c = *record.covariance_m2;
    const double values[] = {c(0, 0), c(0, 1), c(0, 2), c(1, 1), c(1, 2), c(2, 2)};
    append_list(payload, "c", values);
  }
  if (record.pose_covariance) {
    std::array<double, kRestRow.size()> values{};
    for (std::size_t k = 0; k < values.size(); ++k) values[k] = (*record.pose_covariance)(kRestRow[k], kRestCol[k]);
    append_list(payload, "r", values);
  }
  return with_crc(payload);
}

// Writes all of `text` (retrying short writes); false with errno set on failure.
bool write_all(int fd, std::string_view text) {
  while (!text.empty()) {
    const ssize_t n = ::write(fd, text.data(), text.size());
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) return false;
    text.remove_prefix(static_cast<std::size_t>(n));
  }
  return true;
}

void fsync_directory_of(const std::string& path) {
  const std::filesystem::path parent = std::filesystem::absolute(path).parent_path();
  const int dir = ::open(parent.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (dir < 0) fail_os(path, "cannot open its directory to sync it");
  const int status = ::fsync(dir);
  ::close(dir);
  if (status != 0) fail_os(path, "cannot sync its directory");
}

int open_locked(const std::string& path, int flags) {
  const int fd = ::open(path.c_str(), flags | O_CLOEXEC);
  if (fd < 0) fail_os(path, "cannot open the journal");
  if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    const int error = errno;
    ::close(fd);
    errno = error;
    fail_os(path, "the journal is in use by another process");
  }
  return fd;
}

}  // namespace

Journal::Journal(std::string path, JournalIdentity identity, int fd)
    : path_(std::move(path)), identity_(std::move(identity)), fd_(fd) {}

Journal::Journal(Journal&& other) noexcept
    : path_(std::move(other.path_)),
      identity_(std::move(other.identity_)),
      fd_(std::exchange(other.fd_, -1)),
      broken_(other.broken_),
      lines_(other.lines_),
      bytes_(other.bytes_),
      notes_(std::move(other.notes_)),
      records_(std::move(other.records_)),
      lines_by_pose_(std::move(other.lines_by_pose_)) {}

Journal& Journal::operator=(Journal&& other) noexcept {
  if (this != &other) {
    if (fd_ >= 0) ::close(fd_);
    path_ = std::move(other.path_);
    identity_ = std::move(other.identity_);
    fd_ = std::exchange(other.fd_, -1);
    broken_ = other.broken_;
    lines_ = other.lines_;
    bytes_ = other.bytes_;
    notes_ = std::move(other.notes_);
    records_ = std::move(other.records_);
    lines_by_pose_ = std::move(other.lines_by_pose_);
  }
  return *this;
}

Journal::~Journal() {
  if (fd_ >= 0) ::close(fd_);
}

Journal Journal::create(const std::string& path, const JournalIdentity& identity) {
  const std::string header = header_line(path, identity);
  if (std::filesystem::exists(path)) fail(path, 0, "the journal already exists (resume it, or remove it)");
  const std::string temporary = path + ".tmp";
  const int tmp = ::open(temporary.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (tmp < 0) fail_os(temporary, "cannot create");
  const bool written = write_all(tmp, header) && ::fsync(tmp) == 0;
  const int error = errno;
  ::close(tmp);
  if (!written) {
    ::unlink(temporary.c_str());
    errno = error;
    fail_os(temporary, "cannot write the journal header");
  }
  if (::link(temporary.c_str(), path.c_str()) != 0) {
    const int link_error = errno;
    ::unlink(temporary.c_str());
    errno = link_error;
    fail_os(path, "cannot create the journal");
  }
  ::unlink(temporary.c_str());
  fsync_directory_of(path);
  Journal journal(path, identity, open_locked(path, O_WRONLY | O_APPEND));
  journal.lines_ = 1;
  journal.bytes_ = static_cast<std::int64_t>(header.size());
  return journal;
}

Journal Journal::resume(const std::string& path, const JournalIdentity& identity) {
  if (!std::filesystem::exists(path)) fail(path, 0, "no journal to resume");
  try {  // before open(): a directory, a device or a named pipe is refused by name
    files::check_input_file(path, files::kJournalFile);
  } catch (const files::InputFileError& e) {
    throw JournalError(e.what());
  }
  const int fd = open_locked(path, O_RDWR | O_APPEND);
  Journal journal(path, identity, fd);
  std::string text;
  try {
    text = files::read_text_from(fd, path, files::kJournalFile);
  } catch (const files::InputFileError& e) {
    throw JournalError(e.what());
  }

  std::size_t start = 0;
  int line = 0;
  while (start < text.size()) {
    ++line;
    const std::size_t newline = text.find('\n', start);
    const bool complete = newline != std::string::npos;
    const std::string_view content(text.data() + start, (complete ? newline : text.size()) - start);
    const bool last = !complete || newline + 1 == text.size();
    Fields fields;
    std::optional<std::string> bad = complete ? split_checked(content, fields) : "no newline at its end";
    // A torn line (cut short, or its bytes not all on disk) can only be the last; a line whose
    // CRC holds was written whole, so anything wrong inside it is an error wherever it is.
    if (bad && line == 1) fail(path, 1, "the journal header is damaged: " + *bad);
    if (bad && !last) fail(path, line, "damaged record before the end of the journal: " + *bad);
    if (bad) {
      if (::ftruncate(fd, static_cast<off_t>(start)) != 0 || ::fsync(fd) != 0)
        fail_os(path, "cannot cut off the torn last line");
      journal.notes_.push_back(path + ":" + std::to_string(line) + ": the last line was torn (" + *bad + "); cut off " +
                               std::to_string(text.size() - start) + " bytes");
      break;
    }
    if (line == 1) {
      const std::string differences = identity_differences(parse_header(fields, path), identity);
      if (!differences.empty()) fail(path, 0, "the journal belongs to a different session: " + differences);
    } else {
      JournalRecord record = parse_record(fields, identity, path, line);
      check_record(record, identity, path, line);
      const auto [it, inserted] = journal.lines_by_pose_.emplace(record.pose_index, line);
      if (!inserted)
        fail(path, line,
             "pose " + std::to_string(record.pose_index) + " is recorded again (first on line " +
                 std::to_string(it->second) + ")");
      journal.records_.push_back(std::move(record));
    }
    journal.lines_ = line;
    start = newline + 1;
    journal.bytes_ = static_cast<std::int64_t>(start);
  }
  if (journal.lines_ == 0) fail(path, 1, "the journal has no header");
  return journal;
}

void Journal::append(const JournalRecord& record) {
  if (broken_) fail(path_, 0, "an earlier append failed and could not be undone; resume the journal");
  check_record(record, identity_, path_, 0);
  const auto existing = lines_by_pose_.find(record.pose_index);
  if (existing != lines_by_pose_.end())
    fail(path_, 0,
         "pose " + std::to_string(record.pose_index) + " is already recorded (line " +
             std::to_string(existing->second) + ")");
  const std::string text = record_line(record);
  if (!write_all(fd_, text) || ::fsync(fd_) != 0) {
    const int error = errno;
    broken_ = ::ftruncate(fd_, static_cast<off_t>(bytes_)) != 0 || ::fsync(fd_) != 0;
    errno = error;
    fail_os(path_, "cannot append pose " + std::to_string(record.pose_index));
  }
  bytes_ += static_cast<std::int64_t>(text.size());
  ++lines_;
  lines_by_pose_.emplace(record.pose_index, lines_);
  records_.push_back(record);
  records_.back().line = lines_;
}

model::Dataset Journal::dataset() const {
  model::Dataset data;
  data.source = path_;
  data.joint_count = identity_.joint_count;
  data.has_orientation = identity_.orientation;
  data.noise = identity_.covariance ? model::NoiseColumns::covariance : model::NoiseColumns::none;
  data.has_pose_covariance = identity_.pose_covariance;
  std::vector<const JournalRecord*> ordered;
  for (const JournalRecord& r : records_) ordered.push_back(&r);
  std::sort(ordered.begin(), ordered.end(),
            [](const JournalRecord* a, const JournalRecord* b) { return a->pose_index < b->pose_index; });
  for (const JournalRecord* r : ordered) {
    model::Measurement m;
    m.q = r->q;
    m.position = r->position_m;
    m.orientation = r->orientation;
    m.covariance = r->covariance_m2;
    m.pose_covariance = r->pose_covariance;
    m.line = r->line;
    data.rows.push_back(std::move(m));
  }
  return data;
}

void Journal::write_csv(std::ostream& out) const { model::write_dataset(out, dataset()); }

}  // namespace kincal::session
