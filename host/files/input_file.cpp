#include "host/files/input_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>

#include "host/files/file_type.hpp"

namespace kincal::files {

namespace {

[[noreturn]] void refuse(const std::string& path, const std::string& what) { throw InputFileError(path + ": " + what); }

std::string size_text(std::uintmax_t bytes) {
  return bytes < kMiB ? std::to_string(bytes) + " bytes" : std::to_string((bytes + kMiB - 1) / kMiB) + " MiB";
}

void check_size(const std::string& path, const InputKind& kind, std::uintmax_t bytes) {
  if (bytes > kind.max_bytes)
    refuse(path, size_text(bytes) + " is over the limit of " + size_text(kind.max_bytes) + " for a " + kind.what);
}

// The length of the UTF-8 sequence at text[i], or 0 when it is not one (overlong forms,
// surrogates and code points above U+10FFFF are not UTF-8).
std::size_t utf8_length(std::string_view text, std::size_t i) {
  const auto byte = [&](std::size_t k) { return static_cast<unsigned char>(text[k]); };
  const unsigned char b = byte(i);
  if (b < 0x80) return 1;
  std::size_t n = 0;
  unsigned char low = 0x80, high = 0xBF;  // the range of the second byte
  if (b >= 0xC2 && b <= 0xDF) {
    n = 2;
  } else if (b >= 0xE0 && b <= 0xEF) {
    n = 3;
    if (b == 0xE0) low = 0xA0;
    if (b == 0xED) high = 0x9F;
  } else if (b >= 0xF0 && b <= 0xF4) {
    n = 4;
    if (b == 0xF0) low = 0x90;
    if (b == 0xF4) high = 0x8F;
  } else {
    return 0;
  }
  if (i + n > text.size() || byte(i + 1) < low || byte(i + 1) > high) return 0;
  for (std::size_t k = 2; k < n; ++k)
    if (byte(i + k) < 0x80 || byte(i + k) > 0xBF) return 0;
  return n;
}

// Reads `fd` to its end, failing once more than the kind's limit arrives.
std::string read_bounded(int fd, const std::string& path, const InputKind& kind, std::uintmax_t expected) {
  std::string text;
  text.reserve(static_cast<std::size_t>(std::min(expected, kind.max_bytes)));
  char buffer[1 << 16];
  while (true) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) refuse(path, std::string("cannot read: ") + std::strerror(errno));
    if (n == 0) return text;
    if (text.size() + static_cast<std::size_t>(n) > kind.max_bytes)
      refuse(path, "more than the limit of " + size_text(kind.max_bytes) + " for a " + kind.what);
    text.append(buffer, static_cast<std::size_t>(n));
  }
}

// Opens a regular file without blocking (a named pipe swapped in after stat() must not hang us).
class Descriptor {
 public:
  explicit Descriptor(const std::string& path, const InputKind& kind) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0)
      refuse(path, errno == ENOENT ? std::string("no such file") : std::string("cannot open: ") + std::strerror(errno));
    if (const std::string why = not_a_regular_file(st.st_mode); !why.empty()) refuse(path, why);
    check_size(path, kind, static_cast<std::uintmax_t>(st.st_size));
    fd_ = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (fd_ < 0) refuse(path, std::string("cannot open: ") + std::strerror(errno));
  }
  Descriptor(const Descriptor&) = delete;
  Descriptor& operator=(const Descriptor&) = delete;
  ~Descriptor() { ::close(fd_); }
  int fd() const { return fd_; }

 private:
  int fd_ = -1;
};

// A byte as a message names it: "0xE9".
std::string hex_byte(char c) {
  char hex[8];
  std::snprintf(hex, sizeof hex, "0x%02X", static_cast<unsigned>(static_cast<unsigned char>(c)));
  return hex;
}

}  // namespace

void decode_text(std::string& text, const std::string& path, const InputKind& kind) {
  if (kind.decoding == Decoding::none) return;
  if (kind.decoding == Decoding::utf8 && text.starts_with("\xEF\xBB\xBF")) text.erase(0, 3);
  if (text.starts_with("\xFF\xFE") || text.starts_with("\xFE\xFF"))
    refuse(path, std::string("UTF-16 text (byte-order mark ") + (text[0] == '\xFF' ? "FF FE" : "FE FF") + "): a " +
                     kind.what + " must be UTF-8 (save it as UTF-8)");
  if (const std::size_t i = text.find('\0'); i != std::string::npos)
    refuse(path + ":" + line_column(text, i), "a NUL byte (byte " + std::to_string(i) +
                                                  "): UTF-16 text or a binary file, not a " + kind.what + " in UTF-8");
  for (std::size_t i = text.find('\r'); i != std::string::npos; i = text.find('\r', i + 1))
    if (i + 1 == text.size() || text[i + 1] != '\n')
      refuse(path + ":" + line_column(text, i), "a CR line end without LF (byte " + std::to_string(i) + "): a " +
                                                    kind.what + " takes LF or CRLF line ends");
  if (kind.max_line_bytes > 0)
    for (std::size_t start = 0; start < text.size();) {
      const std::size_t end = std::min(text.find('\n', start), text.size());
      if (end - start > kind.max_line_bytes)
        refuse(path + ":" + line_column(text, start), "a line of " + size_text(end - start) + ", more than the " +
                                                          size_text(kind.max_line_bytes) + " a " + kind.what +
                                                          " line may have");
      start = end + 1;
    }
  if (const std::size_t i = first_invalid_utf8(text); i != std::string::npos) {
    refuse(path + ":" + line_column(text, i), "byte " + hex_byte(text[i]) + " (byte " + std::to_string(i) +
                                                  ") is not UTF-8: Latin-1 or another 8-bit encoding? a " + kind.what +
                                                  " must be UTF-8 (save it as UTF-8)");
  }
}

std::string read_text_from(int fd, const std::string& path, const InputKind& kind) {
  struct stat st {};
  if (::fstat(fd, &st) != 0) refuse(path, std::string("cannot read: ") + std::strerror(errno));
  if (const std::string why = not_a_regular_file(st.st_mode); !why.empty()) refuse(path, why);
  check_size(path, kind, static_cast<std::uintmax_t>(st.st_size));
  std::string text = read_bounded(fd, path, kind, static_cast<std::uintmax_t>(st.st_size));
  decode_text(text, path, kind);
  return text;
}

std::string read_text(const std::string& path, const InputKind& kind, StandardInput standard_input) {
  if (path == "-") {
    if (standard_input == StandardInput::refused)
      refuse(path, std::string("standard input is not read here: name the ") + kind.what +
                       " file (./- for a file named '-')");
    std::string text = read_bounded(STDIN_FILENO, "standard input", kind, 0);
    decode_text(text, "standard input", kind);
    return text;
  }
  const Descriptor file(path, kind);
  return read_text_from(file.fd(), path, kind);
}

void check_input_file(const std::string& path, const InputKind& kind) { const Descriptor file(path, kind); }

std::size_t first_invalid_utf8(std::string_view text) {
  for (std::size_t i = 0; i < text.size();) {
    const std::size_t n = utf8_length(text, i);
    if (n == 0) return i;
    i += n;
  }
  return std::string_view::npos;
}

std::size_t first_control_character(std::string_view text) {
  for (std::size_t i = 0; i < text.size(); ++i)
    if (const auto c = static_cast<unsigned char>(text[i]); c < 0x20 || c == 0x7F) return i;
  return std::string_view::npos;
}

std::string control_character_text(std::string_view text, std::size_t offset) {
  return "a control character (" + hex_byte(text[offset]) + ", byte " + std::to_string(offset + 1) + ")";
}

std::string excerpt(std::string_view field) {
  constexpr std::size_t kShown = 80;
  if (field.size() <= kShown) return std::string(field);
  std::size_t cut = kShown;
  while (cut > 0 && (static_cast<unsigned char>(field[cut]) & 0xC0) == 0x80) --cut;  // not inside a character
  return std::string(field.substr(0, cut)) + "... (" + std::to_string(field.size()) + " bytes)";
}

std::string line_column(std::string_view text, std::size_t offset) {
  const std::string_view before = text.substr(0, offset);
  const std::size_t line = 1 + static_cast<std::size_t>(std::count(before.begin(), before.end(), '\n'));
  const std::size_t newline = before.rfind('\n');
  const std::size_t column = offset - (newline == std::string_view::npos ? 0 : newline + 1) + 1;
  return std::to_string(line) + ":" + std::to_string(column);
}

}  // namespace kincal::files
