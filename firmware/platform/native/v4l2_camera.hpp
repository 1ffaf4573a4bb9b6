// A live camera for the Linux platform: the CameraPort (firmware/app/ports.hpp) over a V4L2
// capture device (/dev/videoN), through the kernel's API directly (<linux/videodev2.h>: open,
// ioctl, mmap streaming I/O) so the firmware build needs no OpenCV. With it the platform can be
// prototyped on a Linux board with a USB camera and a CAN adapter.
//
// Set-up (the constructor): VIDIOC_QUERYCAP (a video capture device with streaming I/O),
// VIDIOC_S_FMT to 8-bit GREY, else YUYV (the Y bytes are taken), at the requested size — the
// frame size the camera's intrinsics were calibrated at. A driver that offers a larger frame is
// cropped to its top-left width x height window, so pixel (x, y) keeps its place (the intrinsics
// must have been calibrated on frames cropped the same way); a smaller frame, or neither format,
// is refused. Then VIDIOC_REQBUFS (kBuffers mmap buffers), VIDIOC_QBUF of each, VIDIOC_STREAMON.
// Any failure throws std::runtime_error naming the device, the step or ioctl, and errno's text
// (no such device, not a V4L2 device, not a capture device, format refused, ...).
//
// Snapshots from a stream: the device streams all the time; begin_frame() re-queues the frames
// already completed, notes the request time and returns at once; read_row() takes (poll with a
// zero timeout, then VIDIOC_DQBUF) the first frame completed after that — with a monotonic
// driver clock, the first whose time stamp is not older than the request — and hands out its
// rows (kPending until it has arrived). exposure_us = the request time (platform clock): the
// frame taken is the next one, so its exposure lies within about a frame period of it. No frame within
// kFrameTimeoutMs of the request: kFailed with a message (shorter than PlatformMeasurement's own
// frame timeout, so the port's message names the failure). A device that disappears mid-stream
// (unplugged: ENODEV, POLLERR) fails this and every later frame with one message; the platform
// keeps running and reports camera failures over CAN.
//
// Memory: the driver's mmap buffers; nothing per frame. Runs only in the native platform (heap,
// exceptions and the OS are allowed there).
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

#include "firmware/app/ports.hpp"

namespace kincal::native {

// How one captured frame lies in its buffer: what VIDIOC_S_FMT returned.
enum class V4l2PixelFormat : std::uint8_t { kGrey, kYuyv };
struct V4l2FrameLayout {
  V4l2PixelFormat format = V4l2PixelFormat::kGrey;
  std::uint32_t width_px = 0, height_px = 0;  // the driver's frame
  std::uint32_t bytes_per_line = 0;           // stride: >= width_px (GREY) or 2 width_px (YUYV)
};

// Grey row `row` of a captured frame (buffer = the bytes the driver filled), cropped to
// out.size() pixels from the left. false (nothing written) if the row or its first out.size()
// pixels lie outside the frame or the buffer (a short frame).
bool v4l2_grey_row(std::span<const std::uint8_t> buffer, const V4l2FrameLayout& layout, std::uint32_t row,
                   std::span<std::uint8_t> out);

class V4l2Camera {
 public:
  static constexpr std::uint32_t kBuffers = 4;
  static constexpr int kFrameTimeoutMs = 700;

  // Opens and starts device at width_px x height_px; throws std::runtime_error (see above).
  V4l2Camera(const std::string& device, std::uint16_t width_px, std::uint16_t height_px);
  ~V4l2Camera();
  V4l2Camera(const V4l2Camera&) = delete;
  V4l2Camera& operator=(const V4l2Camera&) = delete;

  std::uint16_t width_px() const { return width_px_; }
  std::uint16_t height_px() const { return height_px_; }
  const V4l2FrameLayout& layout() const { return layout_; }
  int descriptor() const { return fd_; }
  app::CaptureStatus begin_frame(app::FrameUse use, std::uint64_t& exposure_us);
  app::CaptureStatus read_row(std::span<std::uint8_t> row);

 private:
  struct Buffer {
    void* start = nullptr;
    std::size_t length = 0;
  };
  // Dequeues a fresh frame into current_ if one is ready: kOk, kPending or kFailed.
  app::CaptureStatus take_frame();
  app::CaptureStatus lost(const std::string& what);  // the device is gone: message once, kFailed
  void release();                                    // stream off, unmap, close
  void requeue_current();

  std::string device_;
  int fd_ = -1;
  V4l2FrameLayout layout_;
  std::uint16_t width_px_ = 0, height_px_ = 0;
  std::array<Buffer, kBuffers> buffers_{};
  std::uint32_t buffer_count_ = 0;
  bool streaming_ = false, dead_ = false;
  bool requested_ = false;  // begin_frame called, frame not yet failed or finished
  int current_ = -1;        // the dequeued buffer being read out, or -1
  std::uint32_t bytes_used_ = 0;
  std::uint64_t request_us_ = 0;
  bool monotonic_stamps_ = false;  // V4L2_BUF_FLAG_TIMESTAMP_MONOTONIC: comparable with monotonic_us()
  std::uint32_t row_ = 0;
};

}  // namespace kincal::native
