#include "firmware/platform/native/v4l2_camera.hpp"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <iostream>
#include <stdexcept>

#include "firmware/app/platform_measurement.hpp"
#include "firmware/core/pixel_formats.hpp"
#include "firmware/platform/native/native_ports.hpp"

namespace kincal::native {

static_assert(app::CameraPort<V4l2Camera>);
// The port's timeout must expire first, so that its message names the failure.
static_assert(V4l2Camera::kFrameTimeoutMs * 1000ull <
              app::PlatformMeasurement<V4l2Camera, LineRangers>::kFrameTimeoutUs);

namespace {

int xioctl(int fd, unsigned long request, void* argument) {
  int result = 0;
  do {
    result = ::ioctl(fd, request, argument);
  } while (result < 0 && errno == EINTR);
  return result;
}

std::string fourcc(std::uint32_t code) {
  std::string text;
  for (int shift = 0; shift < 32; shift += 8) {
    const char c = static_cast<char>((code >> shift) & 0xFFu);
    text += c >= ' ' && c <= '~' ? c : '?';
  }
  return text;
}

std::uint64_t stamp_us(const timeval& t) {
  return static_cast<std::uint64_t>(t.tv_sec) * 1000000u + static_cast<std::uint64_t>(t.tv_usec);
}

}  // namespace

bool v4l2_grey_row(std::span<const std::uint8_t> buffer, const V4l2FrameLayout& layout, std::uint32_t row,
                   std::span<std::uint8_t> out) {
  const std::size_t bytes_per_pixel = layout.format == V4l2PixelFormat::kYuyv ? 2 : 1;
  if (row >= layout.height_px || out.size() > layout.width_px ||
      layout.bytes_per_line < std::size_t{layout.width_px} * bytes_per_pixel)
    return false;
  const std::size_t begin = std::size_t{row} * layout.bytes_per_line;
  const std::size_t used = out.size() * bytes_per_pixel;
  if (begin + used > buffer.size()) return false;
  const std::span<const std::uint8_t> source = buffer.subspan(begin, used);
  if (layout.format == V4l2PixelFormat::kGrey) {
    std::copy(source.begin(), source.end(), out.begin());
    return true;
  }
  return core::yuv422_to_luma(source, out) == core::PixelStatus::kOk;
}

V4l2Camera::V4l2Camera(const std::string& device, std::uint16_t width_px, std::uint16_t height_px)
    : device_(device), width_px_(width_px), height_px_(height_px) {
  const auto fail = [this](const std::string& step, const std::string& meaning) {
    const std::string reason = std::strerror(errno);
    release();
    throw std::runtime_error("camera " + device_ + ": " + step + ": " + reason +
                             (meaning.empty() ? "" : " (" + meaning + ")"));
  };
  const auto refuse = [this](const std::string& what) {
    release();
    throw std::runtime_error("camera " + device_ + ": " + what);
  };
  if (width_px == 0 || height_px == 0) refuse("the requested frame size is 0");
  fd_ = ::open(device.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
  if (fd_ < 0) fail("open", errno == ENOENT ? "no such device" : "");

  v4l2_capability capability{};
  if (xioctl(fd_, VIDIOC_QUERYCAP, &capability) < 0)
    fail("VIDIOC_QUERYCAP", errno == ENOTTY || errno == EINVAL ? "not a V4L2 device" : "");
  const std::uint32_t caps =
      (capability.capabilities & V4L2_CAP_DEVICE_CAPS) != 0 ? capability.device_caps : capability.capabilities;
  const std::string card(reinterpret_cast<const char*>(capability.card),
                         strnlen(reinterpret_cast<const char*>(capability.card), sizeof capability.card));
  if ((caps & V4L2_CAP_VIDEO_CAPTURE) == 0)
    refuse("'" + card + "' is not a video capture device (VIDIOC_QUERYCAP: no V4L2_CAP_VIDEO_CAPTURE)");
  if ((caps & V4L2_CAP_STREAMING) == 0)
    refuse("'" + card + "' has no streaming I/O (VIDIOC_QUERYCAP: no V4L2_CAP_STREAMING)");

  // GREY first (no conversion), else YUYV; the driver answers with what it will deliver.
  v4l2_format format{};
  bool accepted = false;
  for (const std::uint32_t wanted : {V4L2_PIX_FMT_GREY, V4L2_PIX_FMT_YUYV}) {
    format = v4l2_format{};
    format.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    format.fmt.pix.width = width_px;
    format.fmt.pix.height = height_px;
    format.fmt.pix.pixelformat = wanted;
    format.fmt.pix.field = V4L2_FIELD_NONE;
    if (xioctl(fd_, VIDIOC_S_FMT, &format) < 0)
      fail("VIDIOC_S_FMT", errno == EBUSY ? "the device is busy: another program streams from it" : "format refused");
    if (format.fmt.pix.pixelformat == wanted) {
      accepted = true;
      break;
    }
  }
  const auto offered = [&format] {
    return fourcc(format.fmt.pix.pixelformat) + " " + std::to_string(format.fmt.pix.width) + " x " +
           std::to_string(format.fmt.pix.height);
  };
  if (!accepted) refuse("VIDIOC_S_FMT: format refused: the driver offers " + offered() + ", not GREY or YUYV");
  if (format.fmt.pix.width < width_px || format.fmt.pix.height < height_px)
    refuse("VIDIOC_S_FMT: format refused: the driver offers " + offered() + ", smaller than the requested " +
           std::to_string(width_px) + " x " + std::to_string(height_px));
  layout_.format = format.fmt.pix.pixelformat == V4L2_PIX_FMT_GREY ? V4l2PixelFormat::kGrey : V4l2PixelFormat::kYuyv;
  layout_.width_px = format.fmt.pix.width;
  layout_.height_px = format.fmt.pix.height;
  const std::uint32_t min_line = layout_.width_px * (layout_.format == V4l2PixelFormat::kYuyv ? 2u : 1u);
  layout_.bytes_per_line = std::max(format.fmt.pix.bytesperline, min_line);

  v4l2_requestbuffers request{};
  request.count = kBuffers;
  request.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  request.memory = V4L2_MEMORY_MMAP;
  if (xioctl(fd_, VIDIOC_REQBUFS, &request) < 0) fail("VIDIOC_REQBUFS", errno == EINVAL ? "no mmap streaming" : "");
  if (request.count < 2) refuse("VIDIOC_REQBUFS: the driver grants " + std::to_string(request.count) + " buffer(s)");
  buffer_count_ = std::min(request.count, kBuffers);
  for (std::uint32_t i = 0; i < buffer_count_; ++i) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    buffer.index = i;
    if (xioctl(fd_, VIDIOC_QUERYBUF, &buffer) < 0) fail("VIDIOC_QUERYBUF", "");
    monotonic_stamps_ = (buffer.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK) == V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC;
    void* start = ::mmap(nullptr, buffer.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, buffer.m.offset);
    if (start == MAP_FAILED) fail("mmap of buffer " + std::to_string(i), "");
    buffers_[i] = {start, buffer.length};
    if (xioctl(fd_, VIDIOC_QBUF, &buffer) < 0) fail("VIDIOC_QBUF", "");
  }
  v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  if (xioctl(fd_, VIDIOC_STREAMON, &type) < 0) fail("VIDIOC_STREAMON", "");
  streaming_ = true;
  std::cerr << "kincal_platform: camera " << device_ << " ('" << card << "'): " << offered()
            << (layout_.width_px != width_px_ || layout_.height_px != height_px_
                    ? ", cropped to " + std::to_string(width_px_) + " x " + std::to_string(height_px_)
                    : std::string{})
            << "\n";
}

V4l2Camera::~V4l2Camera() { release(); }

void V4l2Camera::release() {
  if (streaming_) {
    v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    (void)xioctl(fd_, VIDIOC_STREAMOFF, &type);
    streaming_ = false;
  }
  for (Buffer& buffer : buffers_) {
    if (buffer.start != nullptr) ::munmap(buffer.start, buffer.length);
    buffer = {};
  }
  if (fd_ >= 0) ::close(fd_);
  fd_ = -1;
}

app::CaptureStatus V4l2Camera::lost(const std::string& what) {
  if (!dead_)
    std::cerr << "kincal_platform: camera " << device_ << ": " << what << ": " << std::strerror(errno)
              << " (the device is gone, unplugged?; every camera section fails until kincal_platform restarts)\n";
  dead_ = true;
  requested_ = false;
  current_ = -1;
  return app::CaptureStatus::kFailed;
}

void V4l2Camera::requeue_current() {
  if (current_ < 0) return;
  v4l2_buffer buffer{};
  buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
  buffer.memory = V4L2_MEMORY_MMAP;
  buffer.index = static_cast<std::uint32_t>(current_);
  current_ = -1;
  if (xioctl(fd_, VIDIOC_QBUF, &buffer) < 0) (void)lost("VIDIOC_QBUF");
}

app::CaptureStatus V4l2Camera::begin_frame(app::FrameUse, std::uint64_t& exposure_us) {
  exposure_us = monotonic_us();
  request_us_ = exposure_us;
  row_ = 0;
  requested_ = false;
  if (dead_) return app::CaptureStatus::kFailed;
  requeue_current();
  // Frames completed before the request are stale: back to the driver.
  for (std::uint32_t i = 0; i < buffer_count_ && !dead_; ++i) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    if (xioctl(fd_, VIDIOC_DQBUF, &buffer) < 0) {
      if (errno == EAGAIN) break;
      if (errno == ENODEV) return lost("VIDIOC_DQBUF");
      continue;  // EIO: a failed frame; the buffer is the driver's again
    }
    current_ = static_cast<int>(buffer.index);
    requeue_current();
  }
  if (dead_) return app::CaptureStatus::kFailed;
  requested_ = true;
  return app::CaptureStatus::kOk;
}

app::CaptureStatus V4l2Camera::take_frame() {
  const auto timed_out = [this] {
    if (monotonic_us() - request_us_ <= static_cast<std::uint64_t>(kFrameTimeoutMs) * 1000u) return false;
    std::cerr << "kincal_platform: camera " << device_ << ": no frame within " << kFrameTimeoutMs
              << " ms of the request (poll + VIDIOC_DQBUF timed out)\n";
    requested_ = false;
    return true;
  };
  pollfd p{fd_, POLLIN, 0};
  const int ready = ::poll(&p, 1, 0);
  if (ready < 0 && errno != EINTR) return lost("poll");
  if (ready > 0 && (p.revents & POLLIN) == 0 && (p.revents & (POLLERR | POLLHUP | POLLNVAL)) != 0) {
    errno = ENODEV;
    return lost("poll reports an error on the stream");
  }
  if (ready <= 0) return timed_out() ? app::CaptureStatus::kFailed : app::CaptureStatus::kPending;
  for (std::uint32_t i = 0; i <= buffer_count_; ++i) {
    v4l2_buffer buffer{};
    buffer.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    buffer.memory = V4L2_MEMORY_MMAP;
    if (xioctl(fd_, VIDIOC_DQBUF, &buffer) < 0) {
      if (errno == ENODEV) return lost("VIDIOC_DQBUF");
      if (errno != EAGAIN && errno != EIO) return lost("VIDIOC_DQBUF");
      break;  // nothing (more) ready, or one failed frame
    }
    current_ = static_cast<int>(buffer.index);
    const bool stale = monotonic_stamps_ && stamp_us(buffer.timestamp) < request_us_;
    if ((buffer.flags & V4L2_BUF_FLAG_ERROR) != 0 || stale || buffer.index >= buffer_count_) {
      requeue_current();
      if (dead_) return app::CaptureStatus::kFailed;
      continue;
    }
    bytes_used_ = buffer.bytesused;
    return app::CaptureStatus::kOk;
  }
  return timed_out() ? app::CaptureStatus::kFailed : app::CaptureStatus::kPending;
}

app::CaptureStatus V4l2Camera::read_row(std::span<std::uint8_t> row) {
  if (dead_ || !requested_ || row.size() != width_px_ || row_ >= height_px_) return app::CaptureStatus::kFailed;
  if (current_ < 0) {
    const app::CaptureStatus status = take_frame();
    if (status != app::CaptureStatus::kOk) return status;
  }
  const Buffer& buffer = buffers_[static_cast<std::size_t>(current_)];
  const std::span<const std::uint8_t> bytes(static_cast<const std::uint8_t*>(buffer.start),
                                            std::min<std::size_t>(bytes_used_, buffer.length));
  if (!v4l2_grey_row(bytes, layout_, row_, row)) {
    std::cerr << "kincal_platform: camera " << device_ << ": short frame: " << bytes.size() << " bytes, row " << row_
              << " starts at byte " << row_ * layout_.bytes_per_line << " (" << layout_.bytes_per_line
              << " bytes per line)\n";
    requeue_current();
    requested_ = false;
    return app::CaptureStatus::kFailed;
  }
  if (++row_ == height_px_) {
    requeue_current();
    requested_ = false;
  }
  return app::CaptureStatus::kOk;
}

}  // namespace kincal::native
