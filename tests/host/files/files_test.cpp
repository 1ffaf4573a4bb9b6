// host/files: the refusal to overwrite inputs, the whole-or-nothing write, the image header limits.
#include <doctest/doctest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>

#include "host/files/input_file.hpp"
#include "host/files/input_limits.hpp"
#include "host/files/output_file.hpp"

namespace fs = std::filesystem;
using kincal::files::NamedPath;

namespace {

// A fresh directory under the system's temporary directory, removed at the end of the test.
struct Scratch {
  fs::path dir = fs::temp_directory_path() / ("kincal_files_test_" + std::to_string(::getpid()));
  Scratch() {
    fs::remove_all(dir);
    fs::create_directories(dir / "sub");
  }
  ~Scratch() { fs::remove_all(dir); }
  std::string path(const std::string& name) const { return (dir / name).string(); }
};

std::string contents(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

bool temporaries_left(const fs::path& dir) {
  for (const auto& e : fs::directory_iterator(dir))
    if (e.path().filename().string().find(".kincal-") != std::string::npos) return true;
  return false;
}

}  // namespace

TEST_CASE("an output that resolves to an input is refused, naming both options") {
  Scratch s;
  kincal::files::write_file_atomically(s.path("d.csv"), "data\n");
  fs::create_hard_link(s.path("d.csv"), s.path("link.csv"));
  fs::create_symlink(s.path("d.csv"), s.path("sym.csv"));
  for (const std::string& spelling : {s.path("d.csv"), s.path("sub/../d.csv"), s.path("link.csv"), s.path("sym.csv")}) {
    CAPTURE(spelling);
    try {
      kincal::files::refuse_overwriting({{"--out", spelling}}, {{"--data", s.path("d.csv")}});
      FAIL("not refused");
    } catch (const kincal::files::OutputError& e) {
      const std::string what = e.what();
      CHECK(what.find("--out") != std::string::npos);
      CHECK(what.find("--data") != std::string::npos);
    }
  }
  CHECK_THROWS_AS(kincal::files::refuse_overwriting({{"--out", s.path("x")}, {"--urdf", s.path("sub/../x")}}, {}),
                  kincal::files::OutputError);
  CHECK_NOTHROW(kincal::files::refuse_overwriting({{"--out", s.path("o.yaml")}, {"--urdf", ""}, {"-o", "-", true}},
                                                  {{"--data", s.path("d.csv")}, {"--validate", ""}}));
  CHECK(contents(s.path("d.csv")) == "data\n");
  // A directory given as an input (of images): an output with an image's name in it, over one of
  // its views or a new one, by any spelling, is refused; one beside the directory, or another kind
  // of file in it (a calibration beside its views), is not.
  kincal::files::write_file_atomically(s.path("sub/view_00.png"), "png\n");
  for (const std::string& spelling :
       {s.path("sub/view_00.png"), s.path("sub/report.JPG"), s.path("sub/../sub/new.png")}) {
    CAPTURE(spelling);
    CHECK_THROWS_WITH_AS(kincal::files::refuse_overwriting({{"--report", spelling}}, {{"--images", s.path("sub")}}),
                         ("--report " + spelling + " is an image in the directory --images " + s.path("sub") +
                          ": refusing to write among its views (choose another path for --report)")
                             .c_str(),
                         kincal::files::OutputError);
  }
  CHECK_NOTHROW(kincal::files::refuse_overwriting({{"--report", s.path("r.png")}}, {{"--images", s.path("sub")}}));
  CHECK_NOTHROW(kincal::files::refuse_overwriting({{"-o", s.path("sub/camera.yaml")}}, {{"--images", s.path("sub")}}));
  CHECK(contents(s.path("sub/view_00.png")) == "png\n");
}

TEST_CASE("a write replaces the file whole, keeps its permissions and leaves no temporary file") {
  Scratch s;
  const std::string p = s.path("out.txt");
  kincal::files::write_file_atomically(p, "first");
  ::chmod(p.c_str(), 0640);
  kincal::files::write_file_atomically(p, std::string(1 << 20, 'x'));
  CHECK(contents(p).size() == (1u << 20));
  struct stat st {};
  REQUIRE(::stat(p.c_str(), &st) == 0);
  CHECK((st.st_mode & 0777) == 0640);
  CHECK_FALSE(temporaries_left(s.dir));
}

TEST_CASE("a failed write leaves the target as it was") {
  Scratch s;
  CHECK_THROWS_AS(kincal::files::write_file_atomically(s.path("no/such/dir/out.txt"), "x"), kincal::files::OutputError);
  CHECK_THROWS_AS(kincal::files::write_file_atomically(s.path("sub"), "x"), kincal::files::OutputError);
  CHECK(fs::is_directory(s.path("sub")));
  CHECK_FALSE(temporaries_left(s.dir));
}

TEST_CASE("image headers over the limits are refused before decoding") {
  Scratch s;
  const auto write = [&](const std::string& name, const std::string& bytes) {
    std::ofstream(s.path(name), std::ios::binary) << bytes;
    return s.path(name);
  };
  // PNG signature, IHDR length and type, then width and height big-endian.
  const std::string png_head = std::string("\x89PNG\r\n\x1a\n\0\0\0\x0dIHDR", 16);
  CHECK_THROWS_AS(
      kincal::files::check_image_header(write("big.png", png_head + std::string("\0\0\x4e\x20\0\0\x4e\x20", 8))),
      kincal::files::InputLimitError);
  CHECK_NOTHROW(
      kincal::files::check_image_header(write("vga.png", png_head + std::string("\0\0\x02\x80\0\0\x01\xe0", 8))));
  CHECK_THROWS_AS(kincal::files::check_image_header(write("big.pgm", "P5\n# comment\n65535 65535\n255\n")),
                  kincal::files::InputLimitError);
  CHECK_NOTHROW(kincal::files::check_image_header(write("small.pgm", "P5 640 480 255\n")));
  // JPEG: SOI, an APP0 segment, then SOF0 with height 20000 and width 20000.
  const std::string jpeg = std::string("\xff\xd8\xff\xe0\x00\x04\x00\x00\xff\xc0\x00\x11\x08\x4e\x20\x4e\x20", 17);
  CHECK_THROWS_AS(kincal::files::check_image_header(write("big.jpg", jpeg)), kincal::files::InputLimitError);
  // Formats whose size is not read before decoding are refused: a 20 KB TIFF of 32000 x 32000
  // took 3.1 GB; TIFF's and BMP's headers are read.
  CHECK_THROWS_WITH_AS(kincal::files::check_image_header(write("text.png", "not an image")),
                       doctest::Contains("text.png: not an image kincal reads (PNG, JPEG, TIFF, BMP or PNM"),
                       kincal::files::InputFileError);
  std::string tiff("II*\0\x08\0\0\0\x02\0", 10);  // little-endian, two entries: width and length, LONG
  for (const int tag : {256, 257}) {
    tiff += std::string(1, static_cast<char>(tag & 0xFF)) + std::string(1, static_cast<char>(tag >> 8));
    tiff += std::string("\x04\0\x01\0\0\0\x00\x7d\0\0", 10);  // 32000
  }
  tiff += std::string(4, '\0');
  CHECK_THROWS_WITH_AS(kincal::files::check_image_header(write("big.tif", tiff)),
                       doctest::Contains("image of 32000 x 32000 pixels is over the limit"),
                       kincal::files::InputLimitError);
  std::string bmp("BM", 2);
  bmp += std::string(12, '\0') + std::string("\x28\0\0\0", 4);                 // BITMAPINFOHEADER
  bmp += std::string("\x20\x4e\0\0", 4) + std::string("\xe0\xb1\xff\xff", 4);  // 20000, -20000 (top-down)
  CHECK_THROWS_WITH_AS(kincal::files::check_image_header(write("big.bmp", bmp)),
                       doctest::Contains("image of 20000 x 20000 pixels is over the limit"),
                       kincal::files::InputLimitError);
  CHECK_THROWS_WITH_AS(kincal::files::check_image_size("x.bmp", 20000, 20000),
                       "x.bmp: image of 20000 x 20000 pixels is over the limit of 16384 pixels a side and 64 Mpx",
                       kincal::files::InputLimitError);
}
