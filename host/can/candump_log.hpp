// candump -L log files: the lingua franca of CAN tools. One frame per line:
//   (1436509052.249713) vcan0 123#DEADBEEF         classic frame, 11-bit ID (3 hex digits)
//   (1436509052.249713) vcan0 12345678#0102        29-bit ID (8 hex digits)
//   (1436509052.249713) vcan0 123##1DEADBEEF       CAN FD: flags nibble (1 = BRS, 2 = ESI), data
//   (1436509052.249713) vcan0 123#R                remote frame (read and skipped by decoders)
// can-utils' canplayer replays what CandumpWriter writes; CandumpReader reads what candump -L
// writes. No Debian library exposes this format to C++ (can-utils' lib.c is not packaged as a
// library), so the reader is strict instead: anything else is an error naming file and line.
//
// CandumpReader reads the log through files::read_text() (files/input_file.hpp): a regular file
// of at most files::kCandumpFile.max_bytes, UTF-8 (ASCII in practice), LF or CRLF; anything else
// (a directory, a device, a pipe, binary data) is refused by name before any frame is decoded.
// Fields quoted in messages are cut to 80 bytes. A time stamp's seconds must fit the 64-bit
// microsecond clock of LoggedFrame::time_us (at most 18446744073708 s): a larger one is refused
// naming the line, never wrapped.
#pragma once

#include <cstdint>
#include <fstream>
#include <istream>
#include <optional>
#include <sstream>
#include <string>

#include "host/can/transport.hpp"

namespace kincal::can {

struct LoggedFrame {
  std::uint64_t time_us = 0;  // since the Unix epoch
  std::string interface;
  CanFrame frame;
  bool remote = false;
};

// Formats one frame as a candump -L line (without the newline).
std::string format_candump_line(const LoggedFrame& logged);
// Parses one line; throws CanError("what is wrong") for a malformed line.
LoggedFrame parse_candump_line(const std::string& line);

class CandumpWriter {
 public:
  // Throws CanError if the file cannot be created.
  explicit CandumpWriter(const std::string& path);
  void write(const LoggedFrame& logged);
  void write(const std::string& interface, const CanFrame& frame);  // stamped with the current time
  const std::string& path() const { return path_; }

 private:
  std::string path_;
  std::ofstream out_;
};

class CandumpReader {
 public:
  // Reads the whole log; throws CanError naming the path when it is refused (see above).
  explicit CandumpReader(const std::string& path);
  // The next frame, or nullopt at the end; throws CanError("PATH:LINE: ...") on a bad line.
  std::optional<LoggedFrame> next();

 private:
  std::string path_;
  std::istringstream in_;
  std::size_t line_number_ = 0;
};

std::uint64_t now_unix_us();

}  // namespace kincal::can
