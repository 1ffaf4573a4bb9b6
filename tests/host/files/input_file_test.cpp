// host/files/input_file: what every reader of kincal accepts and refuses (issue #25).
#include <doctest/doctest.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/un.h>
#include <unistd.h>

#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>

#include "host/files/input_file.hpp"
#include "host/files/output_file.hpp"

namespace fs = std::filesystem;
namespace files = kincal::files;
using namespace std::string_literals;

namespace {

struct Scratch {
  fs::path dir = fs::temp_directory_path() / ("kincal_input_file_test_" + std::to_string(::getpid()));
  Scratch() {
    fs::remove_all(dir);
    fs::create_directories(dir / "sub");
  }
  ~Scratch() { fs::remove_all(dir); }
  std::string path(const std::string& name) const { return (dir / name).string(); }
  std::string write(const std::string& name, const std::string& bytes) const {
    std::ofstream(path(name), std::ios::binary) << bytes;
    return path(name);
  }
};

constexpr files::InputKind kSmall{"test file", 16};

std::string refusal(const std::string& path, const files::InputKind& kind = files::kDatasetFile) {
  try {
    files::read_text(path, kind);
  } catch (const files::InputFileError& e) {
    return e.what();
  }
  return "";
}

bool has(const std::string& text, const std::string& part) { return text.find(part) != std::string::npos; }

}  // namespace

TEST_CASE("read_text: UTF-8 text with or without a byte-order mark, CRLF kept") {
  const Scratch s;
  CHECK(files::read_text(s.write("a.csv", "q1,x\r\n1,2\r\n"), files::kDatasetFile) == "q1,x\r\n1,2\r\n");
  CHECK(files::read_text(s.write("bom.csv", "\xEF\xBB\xBFq1\n"), files::kDatasetFile) == "q1\n");
  CHECK(files::read_text(s.write("utf8.csv", "caf\xC3\xA9 \xE2\x82\xAC \xF0\x9F\x98\x80\n"), files::kDatasetFile)
            .size() == 15);
  CHECK(files::read_text(s.write("empty.csv", ""), files::kDatasetFile).empty());
  CHECK(files::read_text(s.write("limit", std::string(16, 'x')), kSmall).size() == 16);
}

TEST_CASE("read_text: files that are not regular are refused by name, before reading") {
  const Scratch s;
  CHECK(refusal(s.path("none.csv")) == s.path("none.csv") + ": no such file");
  CHECK(refusal(s.path("sub")) == s.path("sub") + ": is a directory, not a file");
  fs::create_symlink("/dev/zero", s.path("zero.csv"));
  CHECK(refusal(s.path("zero.csv")) == s.path("zero.csv") + ": is a character device, not a regular file");
  REQUIRE(::mkfifo(s.path("fifo.csv").c_str(), 0600) == 0);
  CHECK(has(refusal(s.path("fifo.csv")), "is a named pipe (FIFO), not a regular file"));
  const int fd = ::socket(AF_UNIX, SOCK_STREAM, 0);
  sockaddr_un address{};
  address.sun_family = AF_UNIX;
  const std::string socket_path = s.path("sock.csv");
  if (socket_path.size() < sizeof address.sun_path) {
    std::memcpy(address.sun_path, socket_path.c_str(), socket_path.size() + 1);
    REQUIRE(::bind(fd, reinterpret_cast<const sockaddr*>(&address), sizeof address) == 0);
    CHECK(has(refusal(socket_path), "is a socket, not a regular file"));
  }
  ::close(fd);
  CHECK(has(refusal("-"), "standard input is not read here"));
  CHECK_THROWS_AS(files::check_input_file(s.path("sub"), files::kImageFile), files::InputFileError);
}

TEST_CASE("read_text: the size limit of the kind") {
  const Scratch s;
  CHECK(refusal(s.write("big", std::string(17, 'x')), kSmall) ==
        s.path("big") + ": 17 bytes is over the limit of 16 bytes for a test file");
}

TEST_CASE("read_text: UTF-16, NUL bytes and Latin-1 refused with line, column and byte") {
  const Scratch s;
  CHECK(has(refusal(s.write("le.csv", "\xFF\xFEq\0"s)), "UTF-16 text (byte-order mark FF FE)"));
  CHECK(has(refusal(s.write("be.csv", "\xFE\xFF\0q"s)), "UTF-16 text (byte-order mark FE FF)"));
  CHECK(has(refusal(s.write("nul.csv", "q1\nx\0y\n"s)), "nul.csv:2:2: a NUL byte (byte 4)"));
  CHECK(has(refusal(s.write("latin1.csv", "q1,x\n1,caf\xE9\n")), "latin1.csv:2:6: byte 0xE9 (byte 10) is not UTF-8"));
  CHECK(has(refusal(s.write("overlong.csv", "\xC0\xAF")), "byte 0xC0"));
  CHECK(has(refusal(s.write("surrogate.csv", "ab\xED\xA0\x80")), "surrogate.csv:1:3: byte 0xED"));
  CHECK(has(refusal(s.write("cut.csv", "ab\xE2\x82")), ":1:3: byte 0xE2"));
}

TEST_CASE("read_text: CR line ends without LF, and over-long lines of a line-oriented kind, refused with their line") {
  const Scratch s;
  CHECK(has(refusal(s.write("mac.csv", "q1,q2\r1,2\r")),
            "mac.csv:1:6: a CR line end without LF (byte 5): a dataset takes LF or CRLF line ends"));
  CHECK(refusal(s.write("crlf.csv", "q1,q2\r\n1,2\r\n")).empty());
  constexpr files::InputKind kLines{"test table", 1024, files::Decoding::utf8, 8};
  CHECK(refusal(s.write("long.csv", "q1,q2\n1,2,3,4,5\n"), kLines) ==
        s.path("long.csv") + ":2:1: a line of 9 bytes, more than the 8 bytes a test table line may have");
  CHECK(refusal(s.write("last.csv", "q1,q2\n1,2,3,4,5"), kLines) ==
        s.path("last.csv") + ":2:1: a line of 9 bytes, more than the 8 bytes a test table line may have");
  CHECK(refusal(s.write("short.csv", "q1,q2\n1,2,3,4\n"), kLines).empty());
}

TEST_CASE("excerpt and line_column") {
  CHECK(files::excerpt("short") == "short");
  const std::string cell(8 << 20, '7');
  const std::string e = files::excerpt(cell);
  CHECK(e.size() < 120);
  CHECK(has(e, "... (8388608 bytes)"));
  std::string accented;
  for (int i = 0; i < 50; ++i) accented += "\xC3\xA9";  // 100 bytes of 2-byte characters
  CHECK(files::first_invalid_utf8(files::excerpt(accented)) == std::string_view::npos);
  CHECK(files::line_column("ab\ncd\n", 4) == "2:2");
  CHECK(files::line_column("abc", 0) == "1:1");
}

TEST_CASE("outputs: special files refused by name and never replaced; '-' only where documented") {
  const Scratch s;
  REQUIRE(::mkfifo(s.path("pipe").c_str(), 0600) == 0);
  CHECK_THROWS_WITH_AS(files::refuse_overwriting({{"-o", s.path("pipe")}}, {}),
                       doctest::Contains("is a named pipe (FIFO), not a regular file: refusing to replace it"),
                       files::OutputError);
  CHECK_THROWS_AS(files::write_file_atomically(s.path("pipe"), "x"), files::OutputError);
  struct stat st {};
  REQUIRE(::stat(s.path("pipe").c_str(), &st) == 0);
  CHECK(S_ISFIFO(st.st_mode));
  CHECK_THROWS_WITH_AS(files::refuse_overwriting({{"-o", "/dev/null"}}, {}), doctest::Contains("is a character device"),
                       files::OutputError);
  CHECK_THROWS_WITH_AS(files::refuse_overwriting({{"-o", "-"}}, {}),
                       doctest::Contains("does not write to standard output"), files::OutputError);
  CHECK_NOTHROW(files::refuse_overwriting({{"-o", "-", true}}, {}));
  CHECK_THROWS_WITH_AS(files::refuse_overwriting({{"--out", s.path("nodir/o.yaml")}}, {}),
                       doctest::Contains("does not exist"), files::OutputError);
  CHECK_NOTHROW(files::refuse_overwriting({{"--out", s.path("o.yaml")}}, {}));
  for (const fs::directory_entry& e : fs::directory_iterator(s.dir))  // the check's trial file is gone again
    CHECK(e.path().filename().string().find(".kincal-") == std::string::npos);
  // A directory that takes no new file is refused before any work, not when the output is written:
  // procfs (for root too, whom access() would let write), and a read-only directory for anyone else.
  CHECK_THROWS_WITH_AS(files::refuse_overwriting({{"-o", "/proc/o.csv"}}, {}),
                       "-o /proc/o.csv: cannot create a file in the directory /proc (No such file or directory)",
                       files::OutputError);
  std::filesystem::create_directory(s.path("read_only"));
  std::ofstream(s.path("read_only/o.csv")) << "old\n";
  std::filesystem::permissions(s.path("read_only"),
                               std::filesystem::perms::owner_read | std::filesystem::perms::owner_exec);
  if (::geteuid() != 0) {
    CHECK_THROWS_WITH_AS(files::refuse_overwriting({{"-o", s.path("read_only/o.csv")}}, {}),
                         doctest::Contains("cannot create a file in the directory"), files::OutputError);
    CHECK_THROWS_WITH_AS(files::refuse_overwriting({{"-o", s.path("read_only/new.csv")}}, {}),
                         doctest::Contains("(Permission denied)"), files::OutputError);
  }
  std::filesystem::permissions(s.path("read_only"), std::filesystem::perms::owner_all);
}
