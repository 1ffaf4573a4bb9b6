// Frame sources over OpenCV (issue #6): where the host's images come from -- a V4L2 camera, a
// video file, an image sequence on disk, or frames already in memory (the simulator) -- each
// frame stamped with a time in seconds, so that two sources can be paired (stereo_source.hpp).
//
// Timestamps, by source:
//   camera      the device's buffer time (V4L2's CAP_PROP_POS_MSEC, usually CLOCK_MONOTONIC),
//               falling back to the host's steady clock when the driver gives none;
//   video file  frame index / frame rate (the container's rate, or the one given);
//   images      index * period_s (file order; period_s = 1 s unless given);
//   memory      whatever the caller stamped.
// Indices count the frames a source has delivered, from 0.
//
// Every failure throws CaptureError with a message that starts with the source's name (device,
// path or file): "no such device", "cannot open", "not a video OpenCV can read", "an image, not a
// video", "frame rate unknown", "no such directory", "no image files", "unreadable image",
// "frame grab failed". A source that is merely exhausted returns std::nullopt from next().
//
// Cost: one decode per frame (OpenCV); a directory is listed once, at construction.
// Thread safety: a source is used by one thread at a time; distinct sources are independent.
#pragma once

#include <cstdint>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/videoio.hpp>

namespace kincal::capture {

class CaptureError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct Frame {
  cv::Mat image;  // 8-bit, grey or BGR as the source delivers it; its own pixels, which no later frame overwrites
  double timestamp_s = 0;
  std::int64_t index = 0;
  std::string origin;  // the file, or "SOURCE frame N"
};

class FrameSource {
 public:
  virtual ~FrameSource() = default;
  // The next frame, or std::nullopt at the end of the stream (never for a camera).
  virtual std::optional<Frame> next() = 0;
  // The device, path or label errors and reports name.
  virtual const std::string& name() const = 0;
};

// A V4L2 camera: `device` is an index ("0") or a device path ("/dev/video0").
// Optional width/height request a capture size (0: the driver's default).
class CameraSource final : public FrameSource {
 public:
  explicit CameraSource(const std::string& device, int width_px = 0, int height_px = 0);
  std::optional<Frame> next() override;
  const std::string& name() const override { return name_; }

 private:
  std::string name_;
  cv::VideoCapture capture_;
  std::int64_t index_ = 0;
};

// A video file. fps_override > 0 replaces the container's frame rate in the timestamps.
class VideoFileSource final : public FrameSource {
 public:
  explicit VideoFileSource(const std::string& path, double fps_override = 0);
  std::optional<Frame> next() override;
  const std::string& name() const override { return name_; }
  double fps() const { return fps_; }

 private:
  std::string name_;
  cv::VideoCapture capture_;
  double fps_ = 0;
  std::int64_t index_ = 0;
};

// Still images: every image file of a directory (extensions OpenCV reads: png, jpg, jpeg, bmp,
// tif, tiff, pgm, ppm, pbm, pnm, webp, exr, hdr, jp2), sorted in natural order (img2 before
// img10); or an explicit list of files, in the order given (so that it can match rows of robot
// poses). A file that does not decode fails at next() with "unreadable image" and its path.
class ImageSequenceSource final : public FrameSource {
 public:
  explicit ImageSequenceSource(const std::string& directory, double period_s = 1.0);
  explicit ImageSequenceSource(std::vector<std::string> files, double period_s = 1.0);
  std::optional<Frame> next() override;
  const std::string& name() const override { return name_; }
  const std::vector<std::string>& files() const { return files_; }

 private:
  std::string name_;
  std::vector<std::string> files_;
  double period_s_ = 1.0;
  std::size_t next_ = 0;
};

// Frames the caller made (the simulator's renders, tests), delivered in the order given.
class MemorySource final : public FrameSource {
 public:
  MemorySource(std::string name, std::vector<Frame> frames);
  std::optional<Frame> next() override;
  const std::string& name() const override { return name_; }

 private:
  std::string name_;
  std::vector<Frame> frames_;
  std::size_t next_ = 0;
};

// The source a command-line argument list means: one argument that is a number or a /dev/video*
// path -> camera; one directory -> its images; one file that OpenCV opens as a video -> the
// video; otherwise the files as an image list. Patterns are expanded first (expand_patterns).
// Throws CaptureError as the sources do.
std::unique_ptr<FrameSource> open_source(const std::vector<std::string>& arguments);

// Each argument with a glob character (* ? [) that names no existing path replaced by the files
// it matches (POSIX glob), in natural order: a quoted 'left/img*.png' as the shell would expand
// it. A pattern that matches nothing throws CaptureError naming it.
std::vector<std::string> expand_patterns(const std::vector<std::string>& arguments);

// Natural order of file names: runs of digits compare by value ("img2" < "img10").
bool natural_less(const std::string& a, const std::string& b);

}  // namespace kincal::capture
