// native_ports.hpp's PGM frames (kincal_platform --frames), on hostile paths and files:
//  - what is not a regular file (a FIFO, /dev/zero, a FIFO named *.pgm in a frames directory) is
//    refused by stat() before anything is opened, naming the path and what it is; a FIFO without
//    a writer would otherwise block open() for ever (the ctest TIMEOUT catches a regression);
//  - read_pgm's bounds: a header token over kMaxPgmTokenBytes (a file of NULs, a long number), a
//    header over kMaxPgmHeaderBytes, a file over kMaxPgmFileBytes, a frame larger than the
//    labeler's, fewer pixel bytes than the header says; each message names the file;
//  - a well-formed frame still reads, with comments in its header and bytes after its pixels.
#include <doctest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "firmware/platform/native/native_ports.hpp"

using kincal::native::PgmFrames;
using kincal::native::read_pgm;

namespace {

std::filesystem::path scratch(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("kincal_pgm_" + std::to_string(::getpid()) + "_" + name);
}

std::filesystem::path write(const std::string& name, const std::string& bytes) {
  const std::filesystem::path path = scratch(name);
  std::ofstream(path, std::ios::binary) << bytes;
  return path;
}

std::string error_of(const std::function<void()>& call) {
  try {
    call();
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

std::string read_error(const std::filesystem::path& path) {
  return error_of([&] {
    std::uint16_t width = 0, height = 0;
    (void)read_pgm(path.string(), width, height);
  });
}

std::string frames_error(const std::filesystem::path& path) {
  return error_of([&] { PgmFrames frames(path.string()); });
}

}  // namespace

TEST_CASE("a FIFO as --frames is refused before open, naming it") {
  const std::filesystem::path fifo = scratch("fifo");
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  CHECK(frames_error(fifo) == "frames " + fifo.string() + " is a FIFO: give a PGM file or a directory of them");
  CHECK(read_error(fifo) == "frame " + fifo.string() + " is a FIFO, not a regular file");
  std::filesystem::remove(fifo);
}

TEST_CASE("a FIFO named *.pgm in a frames directory is refused, naming the directory and the entry") {
  const std::filesystem::path directory = scratch("dir");
  std::filesystem::create_directory(directory);
  const std::filesystem::path fifo = directory / "a.pgm";
  REQUIRE(::mkfifo(fifo.c_str(), 0600) == 0);
  CHECK(frames_error(directory) ==
        "frames directory " + directory.string() + ": frame " + fifo.string() + " is a FIFO, not a regular file");
  std::filesystem::remove_all(directory);
}

TEST_CASE("a device as --frames is refused: /dev/zero would be an endless header token") {
  CHECK(frames_error("/dev/zero") == "frames /dev/zero is a character device: give a PGM file or a directory of them");
  CHECK(read_error("/dev/zero") == "frame /dev/zero is a character device, not a regular file");
}

TEST_CASE("a path that does not exist is named") {
  CHECK(frames_error("/nonexistent/kincal.pgm") == "frames /nonexistent/kincal.pgm: No such file or directory");
}

TEST_CASE("a header token longer than kMaxPgmTokenBytes is refused, naming the file and the byte") {
  const std::filesystem::path nuls = write("nuls.pgm", std::string(100000, '\0'));
  CHECK(read_error(nuls) == "frame " + nuls.string() +
                                ": the PGM header token at byte 0 is longer than 20 bytes (the header is P5, width, "
                                "height, maxval)");
  CHECK(frames_error(nuls) == read_error(nuls));
  const std::filesystem::path long_width = write("long_width.pgm", "P5\n" + std::string(21, '7') + " 4\n255\n");
  CHECK(read_error(long_width) == "frame " + long_width.string() +
                                      ": the PGM header token at byte 3 is longer than 20 bytes (the header is P5, "
                                      "width, height, maxval)");
  // 20 bytes is still a token (leading zeros are digits).
  const std::filesystem::path twenty =
      write("twenty.pgm", "P5\n" + std::string(19, '0') + "4 4\n255\n" + std::string(16, '\0'));
  std::uint16_t width = 0, height = 0;
  CHECK(read_pgm(twenty.string(), width, height).size() == 16);
  CHECK(width == 4);
  std::filesystem::remove(nuls);
  std::filesystem::remove(long_width);
  std::filesystem::remove(twenty);
}

TEST_CASE("header numbers are decimal digits only") {
  const std::filesystem::path path = write("letters.pgm", "P5 4x 4 255\n" + std::string(16, '\0'));
  CHECK(read_error(path) ==
        "frame " + path.string() +
            ": malformed PGM header (width, height, maxval): the width '4x' is not a decimal number");
  std::filesystem::remove(path);
}

TEST_CASE("a header of comments over kMaxPgmHeaderBytes is refused") {
  std::string header = "P5\n";
  for (int i = 0; i < 100; ++i) header += "# " + std::string(60, 'c') + "\n";
  const std::filesystem::path path = write("comments.pgm", header + "4 4\n255\n" + std::string(16, '\0'));
  CHECK(read_error(path) == "frame " + path.string() + ": the PGM header is " + std::to_string(header.size() + 8) +
                                " bytes, more than 4096");
  std::filesystem::remove(path);
}

TEST_CASE("a file over kMaxPgmFileBytes is refused before it is read") {
  const std::filesystem::path path = write("big.pgm", "P5 640 4096 255\n");
  std::filesystem::resize_file(path, kincal::native::kMaxPgmFileBytes + 1);  // sparse: no disk used
  CHECK(read_error(path) == "frame " + path.string() + ": " + std::to_string(kincal::native::kMaxPgmFileBytes + 1) +
                                " bytes is more than a frame file may hold (2625536 bytes: 640 x 4096 pixels and "
                                "4096 header bytes)");
  std::filesystem::remove(path);
}

TEST_CASE("a frame larger than the labeler's, or shorter than its header says, is refused") {
  const std::filesystem::path wide = write("wide.pgm", "P5 641 1 255\n" + std::string(641, '\0'));
  CHECK(read_error(wide) == "frame " + wide.string() + ": frame size 641 x 1 is larger than the labeler's 640 x 4096");
  const std::filesystem::path lie = write("lie.pgm", "P5\n65535 65535\n255\n" + std::string(100, '\0'));
  CHECK(read_error(lie) == "frame " + lie.string() +
                               ": truncated: the header says 65535 x 65535 = 4294836225 pixel bytes, the file holds "
                               "100 after the header");
  std::filesystem::remove(wide);
  std::filesystem::remove(lie);
}

TEST_CASE("a well-formed frame reads, with header comments and bytes after its pixels") {
  std::string pixels;
  for (int i = 0; i < 6; ++i) pixels += static_cast<char>(10 * i);
  const std::filesystem::path path = write("good.pgm", "P5\n# a comment\n3 2 # another\n255\n" + pixels + "tail");
  std::uint16_t width = 0, height = 0;
  const std::vector<std::uint8_t> read = read_pgm(path.string(), width, height);
  CHECK(width == 3);
  CHECK(height == 2);
  CHECK(read == std::vector<std::uint8_t>{0, 10, 20, 30, 40, 50});
  PgmFrames frames(path.string());
  CHECK(frames.width_px() == 3);
  CHECK(frames.height_px() == 2);
  std::filesystem::remove(path);
}
