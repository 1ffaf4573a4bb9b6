// v4l2_camera.hpp, the Linux platform's live camera, on a machine without a camera:
//  - the set-up's error paths against the real kernel: a path that does not exist, /dev/null (a
//    character device that is not V4L2), a regular file and a directory; each message must name
//    the device, the step or ioctl, and errno's text;
//  - the frame conversion on in-memory buffers: GREY and YUYV rows, a stride wider than the row
//    (bytesperline), cropping to the requested width, rows outside the frame or the buffer.
// Streaming from a real device is not covered here (no /dev/video* on the build machines).
#include "firmware/platform/native/v4l2_camera.hpp"

#include <doctest.h>
#include <unistd.h>

#include <array>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

using kincal::native::v4l2_grey_row;
using kincal::native::V4l2Camera;
using kincal::native::V4l2FrameLayout;
using kincal::native::V4l2PixelFormat;

namespace {

std::string open_error(const std::string& device) {
  try {
    V4l2Camera camera(device, 640, 480);
  } catch (const std::runtime_error& e) {
    return e.what();
  }
  return "";
}

std::filesystem::path scratch(const std::string& name) {
  return std::filesystem::temp_directory_path() / ("kincal_v4l2_" + std::to_string(::getpid()) + "_" + name);
}

}  // namespace

TEST_CASE("a path that does not exist: open fails with ENOENT, named") {
  const std::string message = open_error("/dev/kincal-no-such-video9");
  CHECK(message == "camera /dev/kincal-no-such-video9: open: No such file or directory (no such device)");
}

TEST_CASE("/dev/null is a character device but not V4L2: VIDIOC_QUERYCAP fails") {
  const std::string message = open_error("/dev/null");
  CHECK(message == "camera /dev/null: VIDIOC_QUERYCAP: Inappropriate ioctl for device (not a V4L2 device)");
}

TEST_CASE("a regular file is not a V4L2 device") {
  const std::filesystem::path file = scratch("file");
  std::ofstream(file) << "not a camera\n";
  const std::string message = open_error(file.string());
  std::filesystem::remove(file);
  CHECK(message == "camera " + file.string() + ": VIDIOC_QUERYCAP: Inappropriate ioctl for device (not a V4L2 device)");
}

TEST_CASE("a directory cannot be opened as a device") {
  const std::filesystem::path directory = scratch("dir");
  std::filesystem::create_directory(directory);
  const std::string message = open_error(directory.string());
  std::filesystem::remove(directory);
  CHECK(message == "camera " + directory.string() + ": open: Is a directory");
}

TEST_CASE("a zero frame size is refused before the device is touched") {
  try {
    V4l2Camera camera("/dev/null", 0, 480);
    FAIL("no error");
  } catch (const std::runtime_error& e) {
    CHECK(std::string(e.what()) == "camera /dev/null: the requested frame size is 0");
  }
}

TEST_CASE("GREY rows with a stride wider than the row, cropped to the requested width") {
  // 5 x 3 pixels, 8 bytes per line (3 bytes of padding, set to 0xEE so they would show).
  const V4l2FrameLayout layout{V4l2PixelFormat::kGrey, 5, 3, 8};
  std::vector<std::uint8_t> buffer(3 * 8, 0xEE);
  for (std::uint32_t y = 0; y < 3; ++y)
    for (std::uint32_t x = 0; x < 5; ++x) buffer[y * 8 + x] = static_cast<std::uint8_t>(10 * y + x);
  std::array<std::uint8_t, 5> full{};
  REQUIRE(v4l2_grey_row(buffer, layout, 2, full));
  CHECK(full == std::array<std::uint8_t, 5>{20, 21, 22, 23, 24});
  std::array<std::uint8_t, 3> cropped{};
  REQUIRE(v4l2_grey_row(buffer, layout, 1, cropped));
  CHECK(cropped == std::array<std::uint8_t, 3>{10, 11, 12});
}

TEST_CASE("YUYV rows: the Y bytes, with the stride and the crop") {
  // 4 x 2 pixels, Y0 U Y1 V per pair, 12 bytes per line (4 of padding).
  const V4l2FrameLayout layout{V4l2PixelFormat::kYuyv, 4, 2, 12};
  std::vector<std::uint8_t> buffer(2 * 12, 0xEE);
  for (std::uint32_t y = 0; y < 2; ++y)
    for (std::uint32_t x = 0; x < 4; ++x) {
      buffer[y * 12 + 2 * x] = static_cast<std::uint8_t>(100 + 10 * y + x);              // Y
      buffer[y * 12 + 2 * x + 1] = static_cast<std::uint8_t>(x % 2 == 0 ? 0x80 : 0x40);  // U or V
    }
  std::array<std::uint8_t, 4> row{};
  REQUIRE(v4l2_grey_row(buffer, layout, 1, row));
  CHECK(row == std::array<std::uint8_t, 4>{110, 111, 112, 113});
  std::array<std::uint8_t, 3> odd_crop{};
  REQUIRE(v4l2_grey_row(buffer, layout, 0, odd_crop));
  CHECK(odd_crop == std::array<std::uint8_t, 3>{100, 101, 102});
}

TEST_CASE("rows outside the frame or the buffer, and layouts narrower than their pixels, are refused") {
  const V4l2FrameLayout layout{V4l2PixelFormat::kYuyv, 4, 2, 8};
  std::vector<std::uint8_t> buffer(16, 7);
  std::array<std::uint8_t, 4> row{};
  row.fill(1);
  CHECK_FALSE(v4l2_grey_row(buffer, layout, 2, row));  // past the last row
  std::array<std::uint8_t, 5> wide{};
  CHECK_FALSE(v4l2_grey_row(buffer, layout, 0, wide));  // wider than the frame
  const std::span<const std::uint8_t> short_frame(buffer.data(), 12);
  CHECK_FALSE(v4l2_grey_row(short_frame, layout, 1, row));  // the driver filled 12 of 16 bytes
  CHECK(row == std::array<std::uint8_t, 4>{1, 1, 1, 1});    // nothing written
  const V4l2FrameLayout narrow_stride{V4l2PixelFormat::kYuyv, 4, 2, 6};
  CHECK_FALSE(v4l2_grey_row(buffer, narrow_stride, 0, row));
}
