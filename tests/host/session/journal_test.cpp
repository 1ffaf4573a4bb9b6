// host/session journal: round trip, torn tails, damage, identity, and recovery after SIGKILL.
#include <doctest.h>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <numbers>
#include <random>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "host/session/journal.hpp"

namespace {

using kincal::session::Journal;
using kincal::session::JournalError;
using kincal::session::JournalIdentity;
using kincal::session::JournalRecord;
namespace fs = std::filesystem;

constexpr int kJoints = 6;

// A fresh directory per test case, removed afterwards.
struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name) {
    path = fs::temp_directory_path() / ("kincal_journal_" + name + "_" + std::to_string(::getpid()));
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  std::string file(const std::string& name) const { return (path / name).string(); }
};

JournalIdentity identity(bool orientation = true, bool covariance = true) {
  JournalIdentity id;
  id.joint_count = kJoints;
  id.orientation = orientation;
  id.covariance = covariance;
  id.items = {{"model_sha256", "5f1c0de"}, {"plan", "30 poses, seed 7"}, {"note", "100% \"odd\"\tvalue\n"}};
  return id;
}

// The measurement of pose i: the same numbers every time it is asked for, with digits that
// need all 17 significant figures.
JournalRecord record_for(int pose, bool orientation = true, bool covariance = true) {
  std::mt19937_64 rng(static_cast<std::uint64_t>(pose) * 7919u + 1u);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  JournalRecord r;
  r.pose_index = pose;
  r.sequence = static_cast<std::uint32_t>(pose * 3 + 1);
  r.platform_time_us = 1'000'000'000'000ull + static_cast<std::uint64_t>(pose) * 33'333u;
  for (int j = 0; j < kJoints; ++j) r.q.push_back(std::numbers::pi * u(rng));
  r.position_m = kincal::model::Vector3(u(rng), u(rng), 1e-300 * u(rng));
  if (orientation) r.orientation = Eigen::Quaterniond(u(rng), u(rng), u(rng), u(rng)).normalized();
  if (covariance) {
    kincal::model::Matrix3 c;
    const double xy = 1e-9 * u(rng), xz = 1e-9 * u(rng), yz = 1e-9 * u(rng);
    c << 4e-8 * (1.5 + u(rng)), xy, xz, xy, 4e-8 * (1.5 + u(rng)), yz, xz, yz, 4e-8 * (1.5 + u(rng));
    r.covariance_m2 = c;
  }
  return r;
}

bool same_bits(double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; }

void check_same(const JournalRecord& a, const JournalRecord& b) {
  CHECK(a.pose_index == b.pose_index);
  CHECK(a.sequence == b.sequence);
  CHECK(a.platform_time_us == b.platform_time_us);
  REQUIRE(a.q.size() == b.q.size());
  for (std::size_t j = 0; j < a.q.size(); ++j) CHECK(same_bits(a.q[j], b.q[j]));
  for (int k = 0; k < 3; ++k) CHECK(same_bits(a.position_m[k], b.position_m[k]));
  REQUIRE(a.orientation.has_value() == b.orientation.has_value());
  if (a.orientation)
    for (int k = 0; k < 4; ++k) CHECK(same_bits(a.orientation->coeffs()[k], b.orientation->coeffs()[k]));
  REQUIRE(a.covariance_m2.has_value() == b.covariance_m2.has_value());
  if (a.covariance_m2)
    for (int k = 0; k < 9; ++k) CHECK(same_bits(a.covariance_m2->data()[k], b.covariance_m2->data()[k]));
}

std::string read_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

void write_file(const std::string& path, const std::string& text) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out << text;
}

std::string csv_of(const Journal& journal) {
  std::ostringstream out;
  journal.write_csv(out);
  return out.str();
}

std::string error_of(const std::string& path, const JournalIdentity& id) {
  try {
    Journal::resume(path, id);
  } catch (const JournalError& e) {
    return e.what();
  }
  return "no error";
}

// A journal of `count` poses appended in order 0..count-1.
void write_journal(const std::string& path, int count) {
  Journal journal = Journal::create(path, identity());
  for (int i = 0; i < count; ++i) journal.append(record_for(i));
}

}  // namespace

TEST_CASE("journal: records round-trip bit for bit; the dataset is in plan order") {
  TempDir dir("round_trip");
  const std::string path = dir.file("session.journal");
  const std::vector<int> order = {4, 0, 3, 1, 2};
  std::string csv;
  {
    Journal journal = Journal::create(path, identity());
    for (int pose : order) journal.append(record_for(pose));
    CHECK(journal.done(3));
    CHECK_FALSE(journal.done(5));
    csv = csv_of(journal);
  }
  CHECK_FALSE(fs::exists(path + ".tmp"));
  Journal resumed = Journal::resume(path, identity());
  CHECK(resumed.notes().empty());
  REQUIRE(resumed.records().size() == order.size());
  for (std::size_t i = 0; i < order.size(); ++i) {
    check_same(resumed.records()[i], record_for(order[i]));
    CHECK(resumed.records()[i].line == static_cast<int>(i) + 2);
  }
  CHECK(resumed.identity().items == identity().items);
  CHECK(csv_of(resumed) == csv);

  const kincal::model::Dataset data = resumed.dataset();
  CHECK(data.source == path);
  CHECK(data.joint_count == kJoints);
  CHECK(data.has_orientation);
  CHECK(data.noise == kincal::model::NoiseColumns::covariance);
  REQUIRE(data.rows.size() == order.size());
  for (std::size_t i = 0; i < data.rows.size(); ++i) {
    const JournalRecord expected = record_for(static_cast<int>(i));
    CHECK(data.rows[i].q == expected.q);
    CHECK(data.rows[i].position == expected.position_m);
    CHECK(*data.rows[i].covariance == *expected.covariance_m2);
  }
  CHECK(data.rows[0].line == 3);  // pose 0 was the second record appended

  // The CSV reads back to the same numbers (the dataset reader's own check).
  std::istringstream in(csv);
  const kincal::model::Dataset back = kincal::model::parse_dataset(in, "csv");
  REQUIRE(back.rows.size() == order.size());
  for (std::size_t i = 0; i < back.rows.size(); ++i) CHECK(back.rows[i].q == data.rows[i].q);

  // Appending continues after a resume; while open, nobody else may write the journal.
  resumed.append(record_for(5));
  CHECK(error_of(path, identity()).find("in use by another process") != std::string::npos);
  CHECK_THROWS_WITH_AS(resumed.append(record_for(5)), doctest::Contains("pose 5 is already recorded (line 7)"),
                       JournalError);
}

TEST_CASE("journal: a journal without orientation or covariance") {
  TempDir dir("plain");
  const std::string path = dir.file("plain.journal");
  const JournalIdentity id = identity(false, false);
  {
    Journal journal = Journal::create(path, id);
    journal.append(record_for(0, false, false));
    CHECK_THROWS_WITH_AS(journal.append(record_for(1, true, false)),
                         doctest::Contains("pose 1: an orientation, the journal has none"), JournalError);
  }
  Journal resumed = Journal::resume(path, id);
  REQUIRE(resumed.records().size() == 1);
  check_same(resumed.records()[0], record_for(0, false, false));
  CHECK(csv_of(resumed).rfind("q1,q2,q3,q4,q5,q6,x,y,z\n", 0) == 0);
}

TEST_CASE("journal: the full pose covariance (issue #26) round-trips into the dataset's 6x6 columns") {
  TempDir dir("pose_covariance");
  const std::string path = dir.file("pose.journal");
  JournalIdentity id = identity();
  id.pose_covariance = true;
  // A pose record: the position block of a random positive definite 6x6 is the covariance.
  auto pose_record = [](int pose) {
    JournalRecord r = record_for(pose);
    std::mt19937_64 rng(static_cast<std::uint64_t>(pose) + 99u);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    Eigen::Matrix<double, 6, 6> a;
    for (int i = 0; i < 36; ++i) a.data()[i] = u(rng);
    const Eigen::Matrix<double, 6, 1> scale(1e-4, 1e-4, 1e-4, 1e-3, 1e-3, 1e-3);  // m, rad
    kincal::model::Matrix6 c =
        scale.asDiagonal() * (a * a.transpose() + kincal::model::Matrix6::Identity()) * scale.asDiagonal();
    c = ((c + c.transpose()) / 2).eval();
    r.pose_covariance = c;
    r.covariance_m2 = c.topLeftCorner<3, 3>();
    return r;
  };
  std::string csv;
  {
    Journal journal = Journal::create(path, id);
    journal.append(pose_record(1));
    journal.append(pose_record(0));
    JournalRecord bad = pose_record(2);
    bad.covariance_m2->operator()(0, 0) *= 2;
    CHECK_THROWS_WITH_AS(journal.append(bad),
                         doctest::Contains("pose 2: the pose covariance's position block is not the covariance"),
                         JournalError);
    bad = pose_record(2);
    bad.pose_covariance->operator()(5, 5) = -1e-6;
    CHECK_THROWS_WITH_AS(journal.append(bad),
                         doctest::Contains("pose 2: the pose covariance is not symmetric positive definite"),
                         JournalError);
    CHECK_THROWS_WITH_AS(journal.append(record_for(2)), doctest::Contains("pose 2: no pose covariance"), JournalError);
    csv = csv_of(journal);
  }
  CHECK(read_file(path).find(" pose_covariance=1 ") != std::string::npos);
  // A journal of positions only is another session's.
  CHECK(error_of(path, identity()).find("pose covariance is on in the journal, off now") != std::string::npos);
  const Journal resumed = Journal::resume(path, id);
  REQUIRE(resumed.records().size() == 2);
  for (int k = 0; k < 36; ++k)
    CHECK(same_bits(resumed.records()[0].pose_covariance->data()[k], pose_record(1).pose_covariance->data()[k]));
  CHECK(csv_of(resumed) == csv);
  std::istringstream in(csv);
  const kincal::model::Dataset back = kincal::model::parse_dataset(in, "csv");
  CHECK(back.has_pose_covariance);
  REQUIRE(back.rows.size() == 2);
  for (int i = 0; i < 2; ++i) {
    const kincal::model::Matrix6 expected = *pose_record(i).pose_covariance;
    REQUIRE(back.rows[static_cast<std::size_t>(i)].pose_covariance.has_value());
    CHECK((*back.rows[static_cast<std::size_t>(i)].pose_covariance - expected).norm() == 0.0);
  }
  // Without the orientation and the covariance there is no pose covariance.
  JournalIdentity lone = identity(true, false);
  lone.pose_covariance = true;
  CHECK_THROWS_WITH_AS(Journal::create(dir.file("lone.journal"), lone),
                       doctest::Contains("needs the orientation and the covariance"), JournalError);
}

TEST_CASE("journal: a torn last line is cut off with a note, and appending goes on") {
  TempDir dir("torn");
  const std::string path = dir.file("torn.journal");
  write_journal(path, 4);
  const std::string whole = read_file(path);
  const std::size_t last_start = whole.rfind('\n', whole.size() - 2) + 1;
  const std::string kept = whole.substr(0, last_start);
  const std::string last = whole.substr(last_start);

  std::string damaged;
  SUBCASE("cut in the middle") { damaged = kept + last.substr(0, last.size() / 2); }
  SUBCASE("the newline missing") { damaged = kept + last.substr(0, last.size() - 1); }
  SUBCASE("a digit changed, newline kept") {
    std::string line = last;
    const std::size_t digit = line.find("q=") + 3;
    line[digit] = line[digit] == '5' ? '6' : '5';
    damaged = kept + line;
  }
  SUBCASE("zeros where the line should be") { damaged = kept + std::string(last.size(), '\0'); }
  write_file(path, damaged);

  {
    Journal journal = Journal::resume(path, identity());
    REQUIRE(journal.notes().size() == 1);
    CHECK(journal.notes()[0].find("torn.journal:5: the last line was torn") != std::string::npos);
    CHECK(journal.records().size() == 3);
    CHECK_FALSE(journal.done(3));
    CHECK(read_file(path) == kept);
    journal.append(record_for(3));
  }
  CHECK(read_file(path) == whole);
  CHECK(Journal::resume(path, identity()).notes().empty());
}

TEST_CASE("journal: damage before the last line is an error naming the line; nothing is cut") {
  TempDir dir("damaged");
  const std::string path = dir.file("damaged.journal");
  write_journal(path, 4);
  std::string text = read_file(path);
  std::size_t line3 = 0;
  for (int i = 0; i < 2; ++i) line3 = text.find('\n', line3) + 1;

  SUBCASE("a changed digit") {
    const std::size_t at = text.find("p=", line3) + 4;
    text[at] = text[at] == '1' ? '2' : '1';
    write_file(path, text);
    CHECK(error_of(path, identity())
              .find("damaged.journal:3: damaged record before the end of the journal: CRC "
                    "mismatch") != std::string::npos);
  }
  SUBCASE("a lost newline joins two lines") {
    text.erase(text.find('\n', line3), 1);
    write_file(path, text);
    CHECK(error_of(path, identity()).find("damaged.journal:3: damaged record") != std::string::npos);
  }
  SUBCASE("a damaged header") {
    text[3] = 'X';
    write_file(path, text);
    CHECK(error_of(path, identity()).find("damaged.journal:1: the journal header is damaged") != std::string::npos);
  }
  SUBCASE("a pose recorded twice") {
    const std::size_t line4 = text.find('\n', line3) + 1;
    text += text.substr(line3, line4 - line3);
    write_file(path, text);
    CHECK(error_of(path, identity()).find("damaged.journal:6: pose 1 is recorded again (first on line 3)") !=
          std::string::npos);
  }
  CHECK(read_file(path) == text);
}

TEST_CASE("journal: another session's journal is refused, saying what differs") {
  TempDir dir("identity");
  const std::string path = dir.file("id.journal");
  write_journal(path, 2);
  JournalIdentity other = identity();
  other.items["plan"] = "30 poses, seed 8";
  other.items.erase("model_sha256");
  other.items["options"] = "--fd";
  other.covariance = false;
  const std::string message = error_of(path, other);
  CHECK(message.find("id.journal: the journal belongs to a different session") != std::string::npos);
  CHECK(message.find("covariance is on in the journal, off now") != std::string::npos);
  CHECK(message.find("plan is '30 poses, seed 7' in the journal, '30 poses, seed 8' now") != std::string::npos);
  CHECK(message.find("model_sha256 is '5f1c0de' in the journal, absent now") != std::string::npos);
  CHECK(message.find("options is absent in the journal, '--fd' now") != std::string::npos);
  CHECK(message.find("note") == std::string::npos);  // the same, escaped and back
}

TEST_CASE("journal: bad use and bad records are errors that say what and where") {
  TempDir dir("misuse");
  const std::string path = dir.file("m.journal");
  CHECK(error_of(path, identity()).find("m.journal: no journal to resume") != std::string::npos);
  Journal journal = Journal::create(path, identity());
  CHECK_THROWS_WITH_AS(Journal::create(path, identity()), doctest::Contains("m.journal: the journal already exists"),
                       JournalError);
  JournalRecord r = record_for(7);
  r.q.pop_back();
  CHECK_THROWS_WITH_AS(journal.append(r), doctest::Contains("pose 7: 5 joint readings, the journal has 6 joints"),
                       JournalError);
  r = record_for(7);
  r.position_m.y() = std::numeric_limits<double>::quiet_NaN();
  CHECK_THROWS_WITH_AS(journal.append(r), doctest::Contains("pose 7: a number is not finite"), JournalError);
  r = record_for(7);
  // Through a named matrix: GCC 12 at -O2 warns (maybe-uninitialized) when an optional is
  // assigned an expression that reads the same optional.
  const Eigen::Matrix3d negated = -r.covariance_m2.value();
  r.covariance_m2 = negated;
  CHECK_THROWS_WITH_AS(journal.append(r), doctest::Contains("pose 7: the covariance is not symmetric positive"),
                       JournalError);
  r = record_for(7);
  r.pose_index = -1;
  CHECK_THROWS_WITH_AS(journal.append(r), doctest::Contains("pose -1: a pose index must not be negative"),
                       JournalError);
  CHECK(journal.records().empty());
  JournalIdentity bad_key = identity();
  bad_key.items["has space"] = "x";
  CHECK_THROWS_WITH_AS(Journal::create(dir.file("k.journal"), bad_key),
                       doctest::Contains("identity key 'has space' is not of"), JournalError);
  write_file(dir.file("other.txt"), "q1,x,y,z\n");
  CHECK(error_of(dir.file("other.txt"), identity()).find("other.txt:1: the journal header is damaged") !=
        std::string::npos);
}

namespace {

constexpr int kPoses = 40;

// What the session does: the poses not yet done, in a fixed shuffled order (a session may
// retry poses out of order), each appended as soon as it is measured.
void run_session(const std::string& path) {
  Journal journal = fs::exists(path) ? Journal::resume(path, identity()) : Journal::create(path, identity());
  std::vector<int> order(kPoses);
  for (int i = 0; i < kPoses; ++i) order[static_cast<std::size_t>(i)] = i;
  std::shuffle(order.begin(), order.end(), std::mt19937(12345));
  for (int pose : order)
    if (!journal.done(pose)) journal.append(record_for(pose));
}

}  // namespace

TEST_CASE("journal: killed at random moments, resumed, the dataset equals an uninterrupted run's") {
  TempDir dir("crash");
  const std::string reference_path = dir.file("reference.journal");
  const auto begin = std::chrono::steady_clock::now();
  run_session(reference_path);
  const double uninterrupted_us =
      std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - begin).count();
  const std::string reference_csv = csv_of(Journal::resume(reference_path, identity()));

  // Kill times spread over the uninterrupted run's duration on this machine (so the kills land
  // at different stages whatever its speed); runs that finish before the kill do not count.
  std::mt19937_64 rng(99);
  std::uniform_real_distribution<double> fraction(0.0, 1.0);
  int killed = 0;
  for (int attempt = 0; attempt < 40 && killed < 5; ++attempt) {
    const std::string path = dir.file("crash" + std::to_string(attempt) + ".journal");
    const pid_t child = ::fork();
    REQUIRE(child >= 0);
    if (child == 0) {
      try {
        run_session(path);
      } catch (...) {
        ::_exit(3);
      }
      ::_exit(0);
    }
    std::this_thread::sleep_for(std::chrono::microseconds(static_cast<long>(fraction(rng) * uninterrupted_us)));
    ::kill(child, SIGKILL);
    int status = 0;
    REQUIRE(::waitpid(child, &status, 0) == child);
    if (WIFEXITED(status)) {
      REQUIRE(WEXITSTATUS(status) == 0);
      continue;
    }
    REQUIRE(WIFSIGNALED(status));
    ++killed;
    std::size_t before = 0, torn = 0;
    if (fs::exists(path)) {
      const Journal interrupted = Journal::resume(path, identity());
      before = interrupted.records().size();
      torn = interrupted.notes().size();
    }
    run_session(path);
    Journal resumed = Journal::resume(path, identity());
    MESSAGE("killed after " << before << " of " << kPoses << " records; " << torn << " torn line(s) cut");
    CHECK(resumed.records().size() == kPoses);
    CHECK(csv_of(resumed) == reference_csv);
  }
  CHECK(killed >= 3);
}
