#include <doctest/doctest.h>

#include <sys/stat.h>
#include <unistd.h>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio.hpp>

#include "host/capture/frame_source.hpp"
#include "host/capture/stereo_source.hpp"

namespace fs = std::filesystem;
using namespace kincal::capture;

namespace {

// A fresh directory per test case, removed at the end.
struct TempDir {
  fs::path path;
  explicit TempDir(const std::string& name)
      : path(fs::temp_directory_path() / ("kincal_capture_" + std::to_string(getpid()) + "_" + name)) {
    fs::remove_all(path);
    fs::create_directories(path);
  }
  ~TempDir() { fs::remove_all(path); }
  std::string file(const std::string& name) const { return (path / name).string(); }
};

cv::Mat grey_image(int level) { return cv::Mat(24, 32, CV_8UC1, cv::Scalar(level)); }

void write_text(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

Frame stamped(double t_s, std::int64_t index) {
  Frame f;
  f.image = grey_image(0);
  f.timestamp_s = t_s;
  f.index = index;
  f.origin = "frame " + std::to_string(index);
  return f;
}

std::unique_ptr<FrameSource> memory(const std::string& name, const std::vector<double>& times_s) {
  std::vector<Frame> frames;
  for (std::size_t i = 0; i < times_s.size(); ++i) frames.push_back(stamped(times_s[i], static_cast<std::int64_t>(i)));
  return std::make_unique<MemorySource>(name, std::move(frames));
}

}  // namespace

TEST_CASE("natural order puts img2 before img10") {
  CHECK(natural_less("img2.png", "img10.png"));
  CHECK_FALSE(natural_less("img10.png", "img2.png"));
  CHECK(natural_less("a.png", "b.png"));
  CHECK(natural_less("img9", "img09a"));
  CHECK_FALSE(natural_less("img1.png", "img1.png"));
}

TEST_CASE("a directory of images is read in natural order with file-order timestamps") {
  TempDir dir("sequence");
  cv::imwrite(dir.file("img10.png"), grey_image(30));
  cv::imwrite(dir.file("img2.png"), grey_image(20));
  cv::imwrite(dir.file("img1.png"), grey_image(10));
  write_text(dir.file("notes.txt"), "not an image, ignored");

  ImageSequenceSource source(dir.path.string(), 0.5);
  std::vector<int> levels;
  std::vector<double> times;
  while (std::optional<Frame> f = source.next()) {
    levels.push_back(f->image.at<unsigned char>(0, 0));
    times.push_back(f->timestamp_s);
    CHECK(f->origin == source.files()[static_cast<std::size_t>(f->index)]);
  }
  CHECK(levels == std::vector<int>{10, 20, 30});
  CHECK(times == std::vector<double>{0.0, 0.5, 1.0});
  CHECK_FALSE(source.next().has_value());
}

TEST_CASE("an explicit image list keeps its order") {
  TempDir dir("list");
  cv::imwrite(dir.file("b.png"), grey_image(2));
  cv::imwrite(dir.file("a.png"), grey_image(1));
  std::unique_ptr<FrameSource> source = open_source({dir.file("b.png"), dir.file("a.png")});
  CHECK(source->next()->image.at<unsigned char>(0, 0) == 2);
  CHECK(source->next()->image.at<unsigned char>(0, 0) == 1);
  CHECK_FALSE(source->next().has_value());
}

TEST_CASE("image sequence errors name the directory or the file") {
  TempDir dir("errors");
  fs::create_directories(dir.path / "empty");
  write_text(dir.file("empty/readme.txt"), "no images here");
  const std::string empty = (dir.path / "empty").string();
  CHECK_THROWS_WITH(ImageSequenceSource(empty, 1.0), (empty + ": no image files in the directory").c_str());
  CHECK_THROWS_WITH(ImageSequenceSource(dir.file("missing")), (dir.file("missing") + ": no such directory").c_str());
  CHECK_THROWS_WITH(ImageSequenceSource(std::vector<std::string>{dir.file("gone.png")}),
                    (dir.file("gone.png") + ": no such file").c_str());

  write_text(dir.file("bad.png"), "this is text, not a PNG");
  cv::imwrite(dir.file("good.png"), grey_image(5));
  ImageSequenceSource source(std::vector<std::string>{dir.file("good.png"), dir.file("bad.png")});
  CHECK(source.next().has_value());
  CHECK_THROWS_WITH(source.next(), doctest::Contains((dir.file("bad.png") + ": not an image kincal reads").c_str()));
}

TEST_CASE("a JPEG cut short and a named pipe are refused by name") {
  TempDir dir("cut");
  cv::Mat gradient(48, 64, CV_8UC1);
  for (int y = 0; y < gradient.rows; ++y)
    for (int x = 0; x < gradient.cols; ++x) gradient.at<std::uint8_t>(y, x) = static_cast<std::uint8_t>(3 * x + y);
  std::vector<std::uint8_t> jpeg;
  REQUIRE(cv::imencode(".jpg", gradient, jpeg));
  std::ofstream(dir.file("whole.jpg"), std::ios::binary)
      .write(reinterpret_cast<const char*>(jpeg.data()), static_cast<std::streamsize>(jpeg.size()));
  std::ofstream(dir.file("cut.jpg"), std::ios::binary)
      .write(reinterpret_cast<const char*>(jpeg.data()), static_cast<std::streamsize>(jpeg.size() * 9 / 10));
  ImageSequenceSource source(std::vector<std::string>{dir.file("whole.jpg"), dir.file("cut.jpg")});
  CHECK(source.next().has_value());
  CHECK_THROWS_WITH(source.next(), doctest::Contains((dir.file("cut.jpg") + ": a JPEG cut short").c_str()));
  REQUIRE(::mkfifo(dir.file("pipe.png").c_str(), 0600) == 0);
  CHECK_THROWS_WITH(ImageSequenceSource(std::vector<std::string>{dir.file("pipe.png")}),
                    doctest::Contains((dir.file("pipe.png") + ": is a named pipe").c_str()));
  REQUIRE(::mkfifo(dir.file("pipe.avi").c_str(), 0600) == 0);
  CHECK_THROWS_WITH(VideoFileSource(dir.file("pipe.avi")),
                    doctest::Contains((dir.file("pipe.avi") + ": is a named pipe").c_str()));
}

TEST_CASE("a video file gives its frames at index / fps") {
  TempDir dir("video");
  const std::string path = dir.file("clip.avi");
  const double fps = 25;
  {
    cv::VideoWriter writer(path, cv::VideoWriter::fourcc('M', 'J', 'P', 'G'), fps, cv::Size(64, 48), false);
    if (!writer.isOpened()) {
      MESSAGE("skipped: this OpenCV cannot write MJPG video");
      return;
    }
    for (int i = 0; i < 8; ++i) writer.write(cv::Mat(48, 64, CV_8UC1, cv::Scalar(20 + 25 * i)));
  }
  VideoFileSource source(path);
  CHECK(source.fps() == doctest::Approx(fps));
  int count = 0;
  while (std::optional<Frame> f = source.next()) {
    CHECK(f->index == count);
    CHECK(f->timestamp_s == doctest::Approx(count / fps));
    // MJPG is lossy, but a flat frame keeps its level within a few counts.
    CHECK(cv::mean(f->image)[0] == doctest::Approx(20 + 25 * count).epsilon(0.05));
    ++count;
  }
  CHECK(count == 8);
  CHECK(open_source({path})->name() == path);

  VideoFileSource slow(path, 2.0);
  (void)slow.next();
  CHECK(slow.next()->timestamp_s == doctest::Approx(0.5));
}

TEST_CASE("video and camera errors name the source") {
  TempDir dir("video_errors");
  write_text(dir.file("notes.avi"), "plain text");
  CHECK_THROWS_WITH(VideoFileSource(dir.file("notes.avi")),
                    doctest::Contains((dir.file("notes.avi") + ": not a video").c_str()));
  cv::imwrite(dir.file("still.png"), grey_image(1));
  CHECK_THROWS_WITH(VideoFileSource(dir.file("still.png")),
                    (dir.file("still.png") + ": an image, not a video (use an image sequence)").c_str());
  CHECK_THROWS_WITH(VideoFileSource(dir.file("none.avi")), (dir.file("none.avi") + ": no such file").c_str());
  CHECK_THROWS_WITH(CameraSource("/dev/video977"), "/dev/video977: no such device");
  CHECK_THROWS_WITH(CameraSource("977"), "977: no such device (/dev/video977)");
  CHECK_THROWS_WITH(open_source({}), doctest::Contains("no input given"));
}

TEST_CASE("stereo pairs by nearest timestamp and reports dropped and duplicated frames") {
  // Right drops the frame near 0.2 s and delivers two near 0.3 s; left has a late extra frame.
  StereoSource stereo(memory("left", {0.0, 0.1, 0.2, 0.3, 0.4, 0.9}),
                      memory("right", {0.004, 0.103, 0.296, 0.31, 0.402}), 0.02);
  std::vector<std::pair<std::int64_t, std::int64_t>> pairs;
  while (std::optional<StereoFrame> p = stereo.next()) pairs.emplace_back(p->left.index, p->right.index);
  CHECK(pairs == std::vector<std::pair<std::int64_t, std::int64_t>>{{0, 0}, {1, 1}, {3, 2}, {4, 4}});
  REQUIRE(stereo.unpaired().size() == 3);
  CHECK(stereo.unpaired()[0].side == Side::kLeft);
  CHECK(stereo.unpaired()[0].index == 2);
  CHECK(stereo.unpaired()[1].side == Side::kRight);
  CHECK(stereo.unpaired()[1].index == 3);
  CHECK(stereo.unpaired()[2].side == Side::kLeft);
  CHECK(stereo.unpaired()[2].index == 5);
  CHECK(stereo.unpaired()[2].origin == "frame 5");
}

TEST_CASE("stereo prefers the nearer of two candidates on the earlier side") {
  // Left 0.0 and 0.015 are both within tolerance of right 0.012; the second is nearer.
  StereoSource stereo(memory("left", {0.0, 0.015}), memory("right", {0.012}), 0.02);
  std::optional<StereoFrame> p = stereo.next();
  REQUIRE(p.has_value());
  CHECK(p->left.index == 1);
  CHECK_FALSE(stereo.next().has_value());
  REQUIRE(stereo.unpaired().size() == 1);
  CHECK(stereo.unpaired()[0].index == 0);
}

TEST_CASE("stereo refuses time going backwards and bad tolerances") {
  // The look-ahead reads one frame beyond the pair it returns.
  StereoSource stereo(memory("left", {0.0, 0.2, 0.3, 0.1}), memory("right", {0.0, 0.2, 0.3}), 0.01);
  CHECK(stereo.next().has_value());
  CHECK(stereo.next().has_value());
  CHECK_THROWS_WITH(stereo.next(), doctest::Contains("left: time goes backwards at frame 3"));
  CHECK_THROWS_WITH(StereoSource(memory("l", {}), memory("r", {}), -1), doctest::Contains("tolerance_s"));
}
