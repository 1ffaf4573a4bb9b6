// The platform's ports on Linux (firmware/app/ports.hpp): the firmware as a process.
//   SocketCanPort   a CAN_RAW socket (classic + CAN FD) on can0/vcan0/...; non-blocking sends;
//                   CanHealth stays "error active" (SocketCAN reports controller errors as
//                   error frames, which vcan never produces and this port does not subscribe to).
//   FileStorage     eight slot files of kSlotBytes in a directory, written with pwrite + fsync,
//                   so a killed process behaves like a power cut between two byte writes.
//   LineRangers     four ranges in metres per line ("0.200 0.210 0.190 0.205", "nan" = no echo)
//                   from a file or a pipe, one line per measurement; without a source, a fixed
//                   reading (0.2, 0.21, 0.19, 0.2 m), which the end-to-end tests check for.
//   PgmFrames       the CameraPort: binary 8-bit PGM files (P5, maxval <= 255), either every
//                   *.pgm of a directory in name order, one per measurement (the metering frame
//                   moves to the next file, the measurement frame reads the same file again;
//                   after the last file every frame fails), or a single file for every
//                   measurement. All frames must have the first file's size, at most the
//                   labeler's frame (640 x 4096, as --camera-size). Only regular files are read:
//                   a FIFO, a device or a socket is refused before it is opened. Without a source
//                   the camera is absent: size 0 x 0, every frame fails (camera sections
//                   report kCameraFailure). Rows are always ready (never kPending); the
//                   exposure time is the clock when the frame was requested.
// Errors at start-up (no interface, unwritable directory, unreadable file) throw
// std::runtime_error naming what and where; at run time, ports report failure by status.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <fstream>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "firmware/app/parameter_store.hpp"
#include "firmware/app/ports.hpp"

namespace kincal::native {

class SocketCanPort {
 public:
  SocketCanPort(const std::string& interface, bool fd);
  ~SocketCanPort();
  SocketCanPort(const SocketCanPort&) = delete;
  SocketCanPort& operator=(const SocketCanPort&) = delete;

  bool try_send(const shared::CanFrame& frame);
  app::CanHealth health() { return {}; }
  // Reads one frame if one is waiting.
  bool try_receive(shared::CanFrame& out);
  int descriptor() const { return fd_; }

 private:
  std::string interface_;
  int fd_ = -1;
  bool fd_frames_ = false;
};

class FileStorage {
 public:
  static constexpr std::size_t kSlotBytes = 4096;
  explicit FileStorage(const std::string& directory);
  ~FileStorage();
  FileStorage(const FileStorage&) = delete;
  FileStorage& operator=(const FileStorage&) = delete;

  app::StorageStatus read(std::uint8_t slot, std::uint32_t offset, std::span<std::uint8_t> out);
  app::StorageStatus erase(std::uint8_t slot);
  app::StorageStatus write(std::uint8_t slot, std::uint32_t offset, std::span<const std::uint8_t> in);

 private:
  std::array<int, app::slot_format::kSlotCount> fds_{};
};

class LineRangers {
 public:
  // path empty: the fixed reading. "-" reads standard input.
  explicit LineRangers(const std::string& path);
  app::RangerStatus read(std::array<std::uint32_t, shared::kRangers>& ranges_um, std::uint64_t& time_us);

 private:
  std::string path_;
  std::ifstream file_;
  std::istream* in_ = nullptr;
};

class PgmFrames {
 public:
  // path empty: no camera. Throws std::runtime_error naming the path if it is neither a
  // readable PGM file nor a directory holding at least one, if it or one of the directory's
  // *.pgm is not a regular file (naming what it is: a FIFO, a character device, ...; checked with
  // stat() before anything is opened, so a FIFO never blocks), or if the first file is malformed.
  explicit PgmFrames(const std::string& path);
  std::uint16_t width_px() const { return width_px_; }
  std::uint16_t height_px() const { return height_px_; }
  app::CaptureStatus begin_frame(app::FrameUse use, std::uint64_t& exposure_us);
  app::CaptureStatus read_row(std::span<std::uint8_t> row);

 private:
  bool load(const std::string& path);  // false (with a message on stderr) if the file is unusable

  std::vector<std::string> files_;
  std::size_t next_file_ = 0;
  std::string current_;
  std::vector<std::uint8_t> pixels_;
  std::uint16_t width_px_ = 0, height_px_ = 0;
  std::size_t row_ = 0;
  bool frame_ok_ = false;
};

// read_pgm's bounds, so that no input makes it block or grow without limit: a header token (P5,
// width, height, maxval) is at most kMaxPgmTokenBytes; the header, comments included, at most
// kMaxPgmHeaderBytes; the frame at most the labeler's frame (kMaxFrameWidthPx x
// kMaxFrameHeightPx, MeasurementPipeline::kMaxWidthPx x core::kLabelerMaxRows, static_assert in
// native_ports.cpp); the file at most kMaxPgmFileBytes (a header and the largest frame).
inline constexpr std::size_t kMaxPgmTokenBytes = 20;
inline constexpr std::size_t kMaxPgmHeaderBytes = 4096;
inline constexpr std::size_t kMaxFrameWidthPx = 640;
inline constexpr std::size_t kMaxFrameHeightPx = 4096;
inline constexpr std::size_t kMaxPgmFileBytes = kMaxPgmHeaderBytes + kMaxFrameWidthPx * kMaxFrameHeightPx;

// Reads a binary 8-bit PGM (P5): the first image of the file (bytes after it are ignored).
// Throws std::runtime_error naming the file and what is wrong: not a regular file (checked with
// stat() before open, and again with fstat() on the descriptor, opened O_NONBLOCK), over
// kMaxPgmFileBytes, not P5, a header token over kMaxPgmTokenBytes or not a decimal number, a header
// over kMaxPgmHeaderBytes, a size outside 1..65535, maxval outside 1..255, fewer pixel bytes than
// the header says, or a frame larger than kMaxFrameWidthPx x kMaxFrameHeightPx. Memory: the file,
// then the pixels (width x height bytes), both within kMaxPgmFileBytes.
std::vector<std::uint8_t> read_pgm(const std::string& path, std::uint16_t& width_px, std::uint16_t& height_px);

std::uint64_t monotonic_us();

}  // namespace kincal::native
