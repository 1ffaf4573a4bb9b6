#include "host/capture/frame_source.hpp"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <system_error>
#include <utility>

#include <glob.h>

#include <opencv2/imgcodecs.hpp>
#include <opencv2/videoio/registry.hpp>

#include "host/files/input_file.hpp"
#include "host/files/input_limits.hpp"

namespace kincal::capture {

namespace {

namespace fs = std::filesystem;

// FFmpeg's demuxers a video file may be read by (FFmpeg matches any of a demuxer's names:
// "mov" is "mov,mp4,m4a,3gp,3g2,mj2", "matroska" is "matroska,webm") and the protocol: a local file.
constexpr const char* kFfmpegCaptureOptions =
    "protocol_whitelist;file|format_whitelist;avi,mov,matroska,mpeg,mpegts,mjpeg,h264,hevc,asf,flv,ogg";
constexpr const char* kVideoContainers = "AVI, MP4/MOV, MKV/WebM, MPEG-PS/TS, MJPEG, H.264/H.265, ASF, FLV, Ogg";

// A regular file within the kind's limit, else CaptureError naming what the path is instead
// ("no such file", a named pipe, a device, a directory).
void check_file(const std::string& path, const files::InputKind& kind) {
  try {
    files::check_input_file(path, kind);
  } catch (const files::InputFileError& e) {
    throw CaptureError(e.what());
  }
}

bool all_digits(const std::string& s) {
  return !s.empty() && std::all_of(s.begin(), s.end(), [](unsigned char c) { return std::isdigit(c) != 0; });
}

double steady_seconds() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

bool natural_less(const std::string& a, const std::string& b) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    const bool da = std::isdigit(static_cast<unsigned char>(a[i])) != 0;
    const bool db = std::isdigit(static_cast<unsigned char>(b[j])) != 0;
    if (da && db) {
      std::size_t ie = i, je = j;
      while (ie < a.size() && std::isdigit(static_cast<unsigned char>(a[ie])) != 0) ++ie;
      while (je < b.size() && std::isdigit(static_cast<unsigned char>(b[je])) != 0) ++je;
      // Compare the runs by value without converting: strip leading zeros, then length, then text.
      std::size_t is = i, js = j;
      while (is + 1 < ie && a[is] == '0') ++is;
      while (js + 1 < je && b[js] == '0') ++js;
      if (ie - is != je - js) return ie - is < je - js;
      const int c = a.compare(is, ie - is, b, js, je - js);
      if (c != 0) return c < 0;
      i = ie;
      j = je;
    } else {
      if (a[i] != b[j]) return a[i] < b[j];
      ++i;
      ++j;
    }
  }
  if (a.size() - i != b.size() - j) return a.size() - i < b.size() - j;
  return a < b;  // equal in natural order ("img01" vs "img1"): fall back to the text
}

CameraSource::CameraSource(const std::string& device, int width_px, int height_px) : name_(device) {
  bool opened = false;
  if (all_digits(device)) {
    std::error_code ec;
    if (device.size() > 9 || !fs::exists("/dev/video" + device, ec))
      throw CaptureError(name_ + ": no such device (/dev/video" + device + ")");
    opened = capture_.open(std::stoi(device), cv::CAP_V4L2);
  } else {
    std::error_code ec;
    if (!fs::exists(device, ec)) throw CaptureError(name_ + ": no such device");
    opened = capture_.open(device, cv::CAP_V4L2);
  }
  if (!opened || !capture_.isOpened()) throw CaptureError(name_ + ": cannot open the device as a V4L2 camera");
  if (width_px > 0) capture_.set(cv::CAP_PROP_FRAME_WIDTH, width_px);
  if (height_px > 0) capture_.set(cv::CAP_PROP_FRAME_HEIGHT, height_px);
}

std::optional<Frame> CameraSource::next() {
  Frame f;
  if (!capture_.read(f.image) || f.image.empty()) {
    throw CaptureError(name_ + ": frame grab failed after " + std::to_string(index_) + " frames");
  }
  // A backend may hand out its own buffer, which the next grab overwrites: the frame is a copy.
  f.image = f.image.clone();
  const double device_ms = capture_.get(cv::CAP_PROP_POS_MSEC);
  f.timestamp_s = device_ms > 0 ? device_ms * 1e-3 : steady_seconds();
  f.index = index_++;
  f.origin = name_ + " frame " + std::to_string(f.index);
  return f;
}

VideoFileSource::VideoFileSource(const std::string& path, double fps_override) : name_(path) {
  check_file(path, files::kVideoFile);
  if (files::is_image_file(path)) throw CaptureError(name_ + ": an image, not a video (use an image sequence)");
  // FFmpeg reads this file and nothing else: local files only (no network, no pipes), and only
  // the containers of recorded video -- an HLS playlist or a concat list named .avi made FFmpeg
  // open the files it lists, a FIFO among them blocking forever. OpenCV passes these options to
  // avformat_open_input at every open.
  setenv("OPENCV_FFMPEG_CAPTURE_OPTIONS", kFfmpegCaptureOptions, 1);
  // Only the file backends: probing every backend (CAP_ANY) wakes GStreamer and camera
  // libraries that print noise and leak for a file none of them reads.
  for (const cv::VideoCaptureAPIs api : {cv::CAP_FFMPEG, cv::CAP_OPENCV_MJPEG}) {
    if (!cv::videoio_registry::hasBackend(api)) continue;
    try {
      if (capture_.open(path, api)) break;
    } catch (const cv::Exception&) {
      // this backend cannot read it; try the next
    }
  }
  if (!capture_.isOpened())
    throw CaptureError(name_ + ": not a video OpenCV can read (containers read: " + kVideoContainers + ")");
  fps_ = fps_override > 0 ? fps_override : capture_.get(cv::CAP_PROP_FPS);
  if (!(fps_ > 0) || !std::isfinite(fps_)) throw CaptureError(name_ + ": frame rate unknown (give one)");
}

std::optional<Frame> VideoFileSource::next() {
  Frame f;
  if (!capture_.read(f.image) || f.image.empty()) return std::nullopt;
  f.image = f.image.clone();  // as a camera's frame (above)
  f.index = index_++;
  f.timestamp_s = static_cast<double>(f.index) / fps_;
  f.origin = name_ + " frame " + std::to_string(f.index);
  return f;
}

ImageSequenceSource::ImageSequenceSource(const std::string& directory, double period_s)
    : name_(directory), period_s_(period_s) {
  std::error_code ec;
  if (!fs::is_directory(directory, ec)) throw CaptureError(name_ + ": no such directory");
  for (const fs::directory_entry& entry : fs::directory_iterator(directory, ec)) {
    if (entry.is_regular_file(ec) && files::is_image_file(entry.path())) files_.push_back(entry.path().string());
  }
  if (ec) throw CaptureError(name_ + ": cannot list the directory (" + ec.message() + ")");
  if (files_.empty()) throw CaptureError(name_ + ": no image files in the directory");
  std::sort(files_.begin(), files_.end(), natural_less);
}

ImageSequenceSource::ImageSequenceSource(std::vector<std::string> files, double period_s)
    : name_(files.empty() ? std::string("image list") : files.front()), files_(std::move(files)), period_s_(period_s) {
  if (files_.empty()) throw CaptureError("image list: no image files given");
  for (const std::string& f : files_) check_file(f, files::kImageFile);
}

std::optional<Frame> ImageSequenceSource::next() {
  if (next_ >= files_.size()) return std::nullopt;
  const std::string& path = files_[next_];
  Frame f;
  try {
    files::check_image_header(path);
    f.image = cv::imread(path, cv::IMREAD_ANYCOLOR);
  } catch (const cv::Exception& e) {
    throw CaptureError(path + ": unreadable image (" + e.what() + ")");
  }
  if (f.image.empty()) throw CaptureError(path + ": unreadable image (not a format OpenCV decodes)");
  files::check_image_size(path, f.image.cols, f.image.rows);
  f.index = static_cast<std::int64_t>(next_);
  f.timestamp_s = static_cast<double>(next_) * period_s_;
  f.origin = path;
  ++next_;
  return f;
}

MemorySource::MemorySource(std::string name, std::vector<Frame> frames)
    : name_(std::move(name)), frames_(std::move(frames)) {}

std::optional<Frame> MemorySource::next() {
  if (next_ >= frames_.size()) return std::nullopt;
  return std::move(frames_[next_++]);
}

std::vector<std::string> expand_patterns(const std::vector<std::string>& arguments) {
  std::vector<std::string> out;
  for (const std::string& a : arguments) {
    std::error_code ec;
    if (a.find_first_of("*?[") == std::string::npos || fs::exists(a, ec)) {
      out.push_back(a);
      continue;
    }
    glob_t matches{};
    const int status = ::glob(a.c_str(), 0, nullptr, &matches);
    std::vector<std::string> files(matches.gl_pathv, matches.gl_pathv + matches.gl_pathc);
    ::globfree(&matches);
    if (status == GLOB_NOMATCH || files.empty()) throw CaptureError(a + ": no file matches the pattern");
    if (status != 0) throw CaptureError(a + ": cannot expand the pattern");
    std::sort(files.begin(), files.end(), natural_less);
    out.insert(out.end(), files.begin(), files.end());
  }
  return out;
}

std::unique_ptr<FrameSource> open_source(const std::vector<std::string>& given) {
  if (given.empty()) throw CaptureError("no input given (a camera, a video, a directory or image files)");
  const std::vector<std::string> arguments = expand_patterns(given);
  if (arguments.size() == 1) {
    const std::string& a = arguments.front();
    std::error_code ec;
    if (all_digits(a) || a.rfind("/dev/video", 0) == 0) return std::make_unique<CameraSource>(a);
    if (fs::is_directory(a, ec)) return std::make_unique<ImageSequenceSource>(a);
    if (fs::is_regular_file(a, ec) && !files::is_image_file(a)) return std::make_unique<VideoFileSource>(a);
  }
  return std::make_unique<ImageSequenceSource>(arguments);
}

}  // namespace kincal::capture
