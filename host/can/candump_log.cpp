#include "host/can/candump_log.hpp"

#include <charconv>
#include <chrono>
#include <cstdio>
#include <limits>

#include "host/files/input_file.hpp"

namespace kincal::can {

namespace {

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

std::uint64_t parse_unsigned(const std::string& text, int base, const char* what) {
  std::uint64_t value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value, base);
  if (text.empty() || ec != std::errc() || ptr != end)
    throw CanError(std::string("bad ") + what + " '" + files::excerpt(text) + "'");
  return value;
}

// The seconds of a time stamp, held to what LoggedFrame::time_us (64 bits of microseconds)
// holds: beyond it they would wrap and reorder the log.
std::uint64_t parse_seconds(const std::string& stamp, const std::string& text) {
  constexpr std::uint64_t kMaxSeconds = std::numeric_limits<std::uint64_t>::max() / 1000000 - 1;
  std::uint64_t value = 0;
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value, 10);
  const bool digits = !text.empty() && ptr == end;
  if (digits && (ec == std::errc::result_out_of_range || (ec == std::errc() && value > kMaxSeconds)))
    throw CanError("timestamp '" + files::excerpt(stamp) + "': " + files::excerpt(text) +
                   " s is beyond the 64-bit microsecond clock (at most " + std::to_string(kMaxSeconds) + " s)");
  if (!digits || ec != std::errc()) throw CanError("bad timestamp seconds '" + files::excerpt(text) + "'");
  return value;
}

}  // namespace

std::uint64_t now_unix_us() {
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::system_clock::now().time_since_epoch())
          .count());
}

std::string format_candump_line(const LoggedFrame& logged) {
  const CanFrame& f = logged.frame;
  char head[64];
  std::snprintf(head, sizeof head, "(%010llu.%06llu) ", static_cast<unsigned long long>(logged.time_us / 1000000),
                static_cast<unsigned long long>(logged.time_us % 1000000));
  std::string line = head + logged.interface + " ";
  char id[16];
  std::snprintf(id, sizeof id, f.extended ? "%08X" : "%03X", static_cast<unsigned>(f.id));
  line += id;
  if (logged.remote) return line + "#R";
  static const char* kHex = "0123456789ABCDEF";
  if (f.fd) {
    line += "##";
    line += kHex[f.brs ? 1 : 0];
  } else {
    line += "#";
  }
  for (std::size_t i = 0; i < f.length; ++i) {
    line += kHex[f.data[i] >> 4];
    line += kHex[f.data[i] & 0xF];
  }
  return line;
}

LoggedFrame parse_candump_line(const std::string& line) {
  LoggedFrame out;
  // (seconds.micros) interface frame
  if (line.size() < 4 || line[0] != '(') throw CanError("expected '(' and a timestamp at the start");
  const auto close = line.find(')');
  if (close == std::string::npos) throw CanError("timestamp is not closed by ')'");
  const std::string stamp = line.substr(1, close - 1);
  const auto dot = stamp.find('.');
  if (dot == std::string::npos || stamp.size() - dot - 1 != 6)
    throw CanError("timestamp '" + files::excerpt(stamp) + "' is not SECONDS.MICROSECONDS with 6 digits");
  out.time_us = parse_seconds(stamp, stamp.substr(0, dot)) * 1000000 +
                parse_unsigned(stamp.substr(dot + 1), 10, "timestamp microseconds");
  if (close + 1 >= line.size() || line[close + 1] != ' ') throw CanError("expected a space after the timestamp");
  const auto space = line.find(' ', close + 2);
  if (space == std::string::npos) throw CanError("expected 'INTERFACE FRAME' after the timestamp");
  out.interface = line.substr(close + 2, space - close - 2);
  if (out.interface.empty()) throw CanError("empty interface name");
  std::string frame = line.substr(space + 1);
  while (!frame.empty() && (frame.back() == '\r' || frame.back() == ' ')) frame.pop_back();
  const auto hash = frame.find('#');
  if (hash == std::string::npos) throw CanError("frame '" + files::excerpt(frame) + "' has no '#'");
  const std::string id = frame.substr(0, hash);
  CanFrame& f = out.frame;
  if (id.size() == 3) {
    f.id = static_cast<std::uint32_t>(parse_unsigned(id, 16, "CAN ID"));
    if (f.id > CanFrame::kMaxStandardId) throw CanError("standard CAN ID '" + id + "' is above 7FF");
  } else if (id.size() == 8) {
    const std::uint64_t v = parse_unsigned(id, 16, "CAN ID");
    if (v > CanFrame::kMaxExtendedId) throw CanError("CAN ID '" + id + "' is an error frame or out of range");
    f.id = static_cast<std::uint32_t>(v);
    f.extended = true;
  } else {
    throw CanError("CAN ID '" + files::excerpt(id) + "' must have 3 (standard) or 8 (extended) hex digits");
  }
  std::string data = frame.substr(hash + 1);
  if (!data.empty() && data[0] == 'R') {
    out.remote = true;
    return out;
  }
  if (!data.empty() && data[0] == '#') {
    if (data.size() < 2) throw CanError("CAN FD frame '" + files::excerpt(frame) + "' has no flags nibble after '##'");
    const int flags = hex_value(data[1]);
    if (flags < 0) throw CanError("CAN FD flags '" + data.substr(1, 1) + "' is not a hex digit");
    f.fd = true;
    f.brs = (flags & 1) != 0;
    data = data.substr(2);
  }
  if (data.size() % 2 != 0) throw CanError("data '" + files::excerpt(data) + "' has an odd number of hex digits");
  const std::size_t length = data.size() / 2;
  if (!shared::is_valid_length(f.fd, length))
    throw CanError(std::to_string(length) + " data bytes is not a valid " + (f.fd ? "CAN FD" : "classic CAN") +
                   " length");
  for (std::size_t i = 0; i < length; ++i) {
    const int hi = hex_value(data[2 * i]), lo = hex_value(data[2 * i + 1]);
    if (hi < 0 || lo < 0) throw CanError("data '" + files::excerpt(data) + "' is not hex");
    f.data[i] = static_cast<std::uint8_t>(hi * 16 + lo);
  }
  f.length = static_cast<std::uint8_t>(length);
  return out;
}

CandumpWriter::CandumpWriter(const std::string& path) : path_(path), out_(path) {
  if (!out_) throw CanError("cannot create log file " + path);
}

void CandumpWriter::write(const LoggedFrame& logged) {
  out_ << format_candump_line(logged) << '\n';
  out_.flush();
}

void CandumpWriter::write(const std::string& interface, const CanFrame& frame) {
  write(LoggedFrame{now_unix_us(), interface, frame, false});
}

CandumpReader::CandumpReader(const std::string& path)
    : path_(path), in_(files::read_text_or_throw<CanError>(path, files::kCandumpFile)) {}

std::optional<LoggedFrame> CandumpReader::next() {
  std::string line;
  while (std::getline(in_, line)) {
    ++line_number_;
    if (line.empty()) continue;
    try {
      return parse_candump_line(line);
    } catch (const CanError& e) {
      throw CanError(path_ + ":" + std::to_string(line_number_) + ": " + e.what());
    }
  }
  return std::nullopt;
}

}  // namespace kincal::can
