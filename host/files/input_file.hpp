// The one way kincal reads a file given on its command line (issue #25). Every reader goes
// through read_text() (text: datasets, exports, models, URDF, journals, candump logs, platform
// and camera files, plans) or check_input_file() (binary inputs a library decodes: images).
//
// Accepted: a regular file, or a symbolic link to one; "-" is standard input only where the
// caller passes StandardInput::allowed (a command that documents it). Text must be UTF-8: a
// UTF-8 byte-order mark is accepted and removed (kept for files written back byte for byte:
// kOriginalUrdfFile, kProgramFile); CRLF line ends are kept as they are
// (every reader takes them).
//
// Refused, by name, before anything is read (InputFileError "PATH: what"):
//   - a path that does not exist ("PATH: no such file") or cannot be opened (the system's reason);
//   - a directory, a character or block device (/dev/zero under any name), a named pipe, a socket;
//   - "-" where standard input is not allowed;
//   - a file larger than its kind's limit (the size is checked before reading, and reading stops
//     at the limit whatever the size said, so a file that grows, or standard input, is bounded).
// Refused after reading, with "PATH:LINE:COLUMN (byte N)": UTF-16 or UTF-32 text (a byte-order
// mark, or NUL bytes), bytes that are not UTF-8 (Latin-1, Windows-1252 ...), a CR line end
// without LF (a classic Mac file: every reader saw one long line and named a wrong cause), and
// in a line-oriented kind a line longer than its max_line_bytes.
//
// Cost: one open(), one fstat() and reads of 64 KiB; memory: the file's text, at most the limit.
#pragma once

#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>

namespace kincal::files {

// A refused input: the message names the path and the cause.
class InputFileError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// What a file holds (for messages), how large it may be, and whether its text is decoded: a
// journal checks every line's CRC itself, and a journal torn by a crash may end in NUL bytes;
// utf8_keeping_mark checks as utf8 but keeps a byte-order mark, for a file written back byte for
// byte (`urdf --original`, a URScript program); none reads the bytes as they are (a binary colour table).
enum class Decoding { utf8, utf8_keeping_mark, none };
struct InputKind {
  const char* what;
  std::uintmax_t max_bytes;
  Decoding decoding = Decoding::utf8;
  std::size_t max_line_bytes = 0;  // a line-oriented kind's longest line (0: no limit)
};

inline constexpr std::uintmax_t kMiB = std::uintmax_t{1} << 20;
// The longest line of a table or log: a row of a few hundred numbers is kilobytes; a 240 MB line
// took 35 bytes of memory a byte as its fields were split (8.4 GB).
inline constexpr std::size_t kMaxTableLineBytes = kMiB;
inline constexpr InputKind kDatasetFile{"dataset", 256 * kMiB, Decoding::utf8,
                                        kMaxTableLineBytes};  // also joints files, plans, targets
inline constexpr InputKind kExportFile{"measurement export", 256 * kMiB, Decoding::utf8, kMaxTableLineBytes};
inline constexpr InputKind kModelFile{"model file", 16 * kMiB};
inline constexpr InputKind kUrdfFile{"URDF", 64 * kMiB};
inline constexpr InputKind kJournalFile{"journal", 256 * kMiB, Decoding::none};
inline constexpr InputKind kCandumpFile{"candump log", 256 * kMiB, Decoding::utf8, kMaxTableLineBytes};
inline constexpr InputKind kSettingsFile{"settings file (YAML)", 16 * kMiB};  // platform, camera
inline constexpr InputKind kImageFile{"image", 512 * kMiB};
inline constexpr InputKind kVideoFile{"video", 64 * 1024 * kMiB, Decoding::none};
inline constexpr InputKind kProgramFile{"robot program", 64 * kMiB, Decoding::utf8_keeping_mark};  // URScript (correct)
inline constexpr InputKind kOriginalUrdfFile{"URDF", 64 * kMiB, Decoding::utf8_keeping_mark};
inline constexpr InputKind kColourTableFile{"colour table", kMiB, Decoding::none};

enum class StandardInput { refused, allowed };

// The file's text (without a byte-order mark), checked as above.
std::string read_text(const std::string& path, const InputKind& kind,
                      StandardInput standard_input = StandardInput::refused);

// The same for a descriptor the caller opened (a journal, held under a lock): checks that it is a
// regular file, reads it from the current offset to its end within the limit, decodes.
std::string read_text_from(int fd, const std::string& path, const InputKind& kind);

// The checks after reading alone, on a text that came another way (a fuzzer's input): removes
// a UTF-8 byte-order mark unless the kind keeps it; throws InputFileError as read_text() does.
void decode_text(std::string& text, const std::string& path, const InputKind& kind);

// The checks before reading alone, for inputs a library decodes (images): a regular file within
// the limit.
void check_input_file(const std::string& path, const InputKind& kind);

// read_text() throwing the reader's own error type (constructible from a string).
template <class Error>
std::string read_text_or_throw(const std::string& path, const InputKind& kind,
                               StandardInput standard_input = StandardInput::refused) {
  try {
    return read_text(path, kind, standard_input);
  } catch (const InputFileError& e) {
    throw Error(e.what());
  }
}

// The offset of the first byte of `text` that is not well-formed UTF-8 (RFC 3629: no overlong
// forms, no surrogates, at most U+10FFFF), or std::string_view::npos.
std::size_t first_invalid_utf8(std::string_view text);

// The offset of the first control character of `text` (below 0x20, or DEL), or npos; and how a
// message names it: "a control character (0x01, byte 3)". A name that goes into XML (a robot's,
// a joint's, a link's) may hold none: XML 1.0 takes none, not even as a character reference.
std::size_t first_control_character(std::string_view text);
std::string control_character_text(std::string_view text, std::size_t offset);

// A field for a message: itself when at most 80 bytes, else its first 80 bytes (cut at a UTF-8
// character boundary) and "... (N bytes)", so that an 8 MB cell is never echoed whole.
std::string excerpt(std::string_view field);

// "LINE:COLUMN" (1-based; the column counts bytes) of byte `offset` of `text`.
std::string line_column(std::string_view text, std::size_t offset);

}  // namespace kincal::files
