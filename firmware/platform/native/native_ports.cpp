#include "firmware/platform/native/native_ports.hpp"

#include <fcntl.h>
#include <linux/can.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cerrno>
#include <charconv>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>
#include <string_view>
#include <vector>

#include "firmware/app/parameter_store.hpp"
#include "firmware/app/platform_measurement.hpp"

namespace kincal::native {

static_assert(kMaxFrameWidthPx == app::MeasurementPipeline::kMaxWidthPx &&
                  kMaxFrameHeightPx == static_cast<std::size_t>(core::kLabelerMaxRows),
              "read_pgm's frame limit is the labeler's frame, as --camera-size's");

namespace {

[[noreturn]] void fail(const std::string& what) { throw std::runtime_error(what + ": " + std::strerror(errno)); }

}  // namespace

std::uint64_t monotonic_us() {
  return static_cast<std::uint64_t>(
      std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now().time_since_epoch())
          .count());
}

SocketCanPort::SocketCanPort(const std::string& interface, bool fd) : interface_(interface), fd_frames_(fd) {
  fd_ = ::socket(PF_CAN, SOCK_RAW | SOCK_NONBLOCK, CAN_RAW);
  if (fd_ < 0) fail(interface + ": cannot open a CAN_RAW socket (is the module can-raw loaded?)");
  const int on = 1;
  if (fd && setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) < 0)
    fail(interface + ": cannot enable CAN FD frames");
  ifreq request{};
  if (interface.size() >= IFNAMSIZ) throw std::runtime_error("interface name '" + interface + "' is too long");
  std::strncpy(request.ifr_name, interface.c_str(), IFNAMSIZ - 1);
  if (ioctl(fd_, SIOCGIFINDEX, &request) < 0) fail(interface + ": no such CAN interface");
  sockaddr_can address{};
  address.can_family = AF_CAN;
  address.can_ifindex = request.ifr_ifindex;
  if (bind(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) < 0) fail(interface + ": cannot bind");
}

SocketCanPort::~SocketCanPort() {
  if (fd_ >= 0) ::close(fd_);
}

bool SocketCanPort::try_send(const shared::CanFrame& frame) {
  if (frame.fd && !fd_frames_) return true;  // a classic-only bus cannot carry it: dropped like a controller would
  canfd_frame k{};
  k.can_id = frame.id | (frame.extended ? CAN_EFF_FLAG : 0u);
  k.len = frame.length;
  k.flags = frame.fd && frame.brs ? CANFD_BRS : 0;
  std::memcpy(k.data, frame.data.data(), frame.length);
  const std::size_t size = frame.fd ? CANFD_MTU : CAN_MTU;
  const ssize_t n = ::write(fd_, &k, size);
  if (n == static_cast<ssize_t>(size)) return true;
  if (n < 0 && (errno == EAGAIN || errno == ENOBUFS)) return false;  // queue full: retried by the app
  std::cerr << "kincal_platform: " << interface_ << ": send failed: " << std::strerror(errno) << "\n";
  return true;  // a frame the interface refuses would be retried forever
}

bool SocketCanPort::try_receive(shared::CanFrame& out) {
  canfd_frame k{};
  const ssize_t n = ::read(fd_, &k, sizeof k);
  if (n != CAN_MTU && n != CANFD_MTU) return false;
  if (k.can_id & CAN_ERR_FLAG) return false;
  out = shared::CanFrame{};
  out.extended = (k.can_id & CAN_EFF_FLAG) != 0;
  out.id = k.can_id & (out.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  out.fd = n == CANFD_MTU;
  out.brs = out.fd && (k.flags & CANFD_BRS) != 0;
  out.length = k.len > 64 ? 64 : k.len;
  std::memcpy(out.data.data(), k.data, out.length);
  if (k.can_id & CAN_RTR_FLAG) out.length = 0;
  return true;
}

FileStorage::FileStorage(const std::string& directory) {
  fds_.fill(-1);
  if (::mkdir(directory.c_str(), 0755) < 0 && errno != EEXIST) fail("cannot create storage directory " + directory);
  for (std::size_t slot = 0; slot < fds_.size(); ++slot) {
    const std::string path = directory + "/slot" + std::to_string(slot) + ".bin";
    fds_[slot] = ::open(path.c_str(), O_RDWR | O_CREAT, 0644);
    if (fds_[slot] < 0) fail("cannot open storage slot " + path);
    struct stat st {};
    if (fstat(fds_[slot], &st) < 0) fail("cannot stat " + path);
    if (static_cast<std::size_t>(st.st_size) != kSlotBytes &&
        erase(static_cast<std::uint8_t>(slot)) != app::StorageStatus::kOk)
      fail("cannot initialise storage slot " + path);
  }
}

FileStorage::~FileStorage() {
  for (const int fd : fds_)
    if (fd >= 0) ::close(fd);
}

app::StorageStatus FileStorage::read(std::uint8_t slot, std::uint32_t offset, std::span<std::uint8_t> out) {
  if (slot >= fds_.size() || offset + out.size() > kSlotBytes) return app::StorageStatus::kFailed;
  const ssize_t n = ::pread(fds_[slot], out.data(), out.size(), offset);
  return n == static_cast<ssize_t>(out.size()) ? app::StorageStatus::kOk : app::StorageStatus::kFailed;
}

app::StorageStatus FileStorage::erase(std::uint8_t slot) {
  if (slot >= fds_.size()) return app::StorageStatus::kFailed;
  const std::vector<std::uint8_t> erased(kSlotBytes, 0xFF);
  if (::pwrite(fds_[slot], erased.data(), erased.size(), 0) != static_cast<ssize_t>(erased.size()) ||
      ::fsync(fds_[slot]) < 0)
    return app::StorageStatus::kFailed;
  return app::StorageStatus::kOk;
}

app::StorageStatus FileStorage::write(std::uint8_t slot, std::uint32_t offset, std::span<const std::uint8_t> in) {
  if (slot >= fds_.size() || offset + in.size() > kSlotBytes) return app::StorageStatus::kFailed;
  if (::pwrite(fds_[slot], in.data(), in.size(), offset) != static_cast<ssize_t>(in.size()) || ::fsync(fds_[slot]) < 0)
    return app::StorageStatus::kFailed;
  return app::StorageStatus::kOk;
}

LineRangers::LineRangers(const std::string& path) : path_(path) {
  if (path.empty()) return;
  if (path == "-") {
    in_ = &std::cin;
    return;
  }
  file_.open(path);
  if (!file_) throw std::runtime_error("cannot open ranges file " + path);
  in_ = &file_;
}

app::RangerStatus LineRangers::read(std::array<std::uint32_t, shared::kRangers>& ranges_um, std::uint64_t& time_us) {
  time_us = monotonic_us();
  if (in_ == nullptr) {
    ranges_um = {200000, 210000, 190000, 200000};
    return app::RangerStatus::kOk;
  }
  std::string line;
  if (!std::getline(*in_, line)) {
    std::cerr << "kincal_platform: " << path_ << ": no more range lines\n";
    return app::RangerStatus::kFailed;
  }
  std::istringstream fields(line);
  for (std::size_t i = 0; i < shared::kRangers; ++i) {
    std::string token;
    double range_m = 0;
    if (!(fields >> token)) {
      std::cerr << "kincal_platform: " << path_ << ": expected 4 ranges in metres, got '" << line << "'\n";
      return app::RangerStatus::kFailed;
    }
    try {
      std::size_t used = 0;
      range_m = std::stod(token, &used);
      if (used != token.size()) throw std::invalid_argument(token);
    } catch (const std::exception&) {
      std::cerr << "kincal_platform: " << path_ << ": '" << token << "' is not a range in metres\n";
      return app::RangerStatus::kFailed;
    }
    ranges_um[i] = std::isfinite(range_m) && range_m >= 0 && range_m < 4000.0
                       ? static_cast<std::uint32_t>(std::lround(range_m * 1e6))
                       : app::kNoEchoUm;
  }
  return app::RangerStatus::kOk;
}

namespace {

// What a file system object is, for messages: "a FIFO", "a character device", ...
std::string file_kind(mode_t mode) {
  if (S_ISREG(mode)) return "a regular file";
  if (S_ISDIR(mode)) return "a directory";
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  return "not a regular file";
}

// The next header token of a PGM from data[at], skipping whitespace and # comments (to the end of
// their line), and the one whitespace byte that ends it. Empty at the end of the data. A token
// longer than kMaxPgmTokenBytes throws, naming the file and the byte where the token starts:
// without the bound, a file of NULs would be one endless token.
std::string pgm_token(std::string_view data, std::size_t& at, const std::string& path) {
  std::string token;
  std::size_t start = 0;
  while (at < data.size()) {
    const char c = data[at];
    if (c == '#') {
      const std::size_t end = data.find('\n', at);
      at = end == std::string_view::npos ? data.size() : end;
    } else if (std::isspace(static_cast<unsigned char>(c))) {
      ++at;
      if (!token.empty()) return token;
    } else {
      if (token.empty()) start = at;
      if (token.size() == kMaxPgmTokenBytes)
        throw std::runtime_error("frame " + path + ": the PGM header token at byte " + std::to_string(start) +
                                 " is longer than " + std::to_string(kMaxPgmTokenBytes) +
                                 " bytes (the header is P5, width, height, maxval)");
      token += c;
      ++at;
    }
  }
  return token;
}

// A header number: decimal digits only, within long.
bool parse_pgm_number(const std::string& token, long& value) {
  if (token.empty() || !std::all_of(token.begin(), token.end(), [](char c) { return c >= '0' && c <= '9'; }))
    return false;
  const auto [end, error] = std::from_chars(token.data(), token.data() + token.size(), value);
  return error == std::errc() && end == token.data() + token.size();
}

// Throws, naming the path and what it is (a FIFO, a device, ...), unless it is a regular file.
// stat() only: nothing is opened.
void require_regular_file(const std::string& path, const std::string& what) {
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) throw std::runtime_error(what + " " + path + ": " + std::strerror(errno));
  if (!S_ISREG(status.st_mode))
    throw std::runtime_error(what + " " + path + " is " + file_kind(status.st_mode) + ", not a regular file");
}

}  // namespace

std::vector<std::uint8_t> read_pgm(const std::string& path, std::uint16_t& width_px, std::uint16_t& height_px) {
  const auto bad = [&path](const std::string& what) { return std::runtime_error("frame " + path + ": " + what); };
  // Checked before open (opening a FIFO would wait for a writer, a device may act on open) and
  // again on the descriptor, opened non-blocking, in case the path changed in between.
  require_regular_file(path, "frame");
  const int fd = ::open(path.c_str(), O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
  if (fd < 0) throw bad(std::string("cannot open: ") + std::strerror(errno));
  const struct Closer {
    int descriptor;
    ~Closer() { ::close(descriptor); }
  } closer{fd};
  struct stat status {};
  if (::fstat(fd, &status) != 0) throw bad(std::string("fstat: ") + std::strerror(errno));
  if (!S_ISREG(status.st_mode)) throw bad("is " + file_kind(status.st_mode) + ", not a regular file");
  if (status.st_size < 0 || static_cast<std::uint64_t>(status.st_size) > kMaxPgmFileBytes)
    throw bad(std::to_string(status.st_size) + " bytes is more than a frame file may hold (" +
              std::to_string(kMaxPgmFileBytes) + " bytes: " + std::to_string(kMaxFrameWidthPx) + " x " +
              std::to_string(kMaxFrameHeightPx) + " pixels and " + std::to_string(kMaxPgmHeaderBytes) +
              " header bytes)");
  std::string data(static_cast<std::size_t>(status.st_size), '\0');
  std::size_t got = 0;
  while (got < data.size()) {
    const ssize_t n = ::read(fd, data.data() + got, data.size() - got);
    if (n < 0 && errno == EINTR) continue;
    if (n < 0) throw bad(std::string("read: ") + std::strerror(errno));
    if (n == 0) break;  // the file shrank since fstat: the checks below see what was read
    got += static_cast<std::size_t>(n);
  }
  data.resize(got);

  std::size_t at = 0;
  if (pgm_token(data, at, path) != "P5") throw bad("not a binary PGM (the file must start with P5)");
  const auto number = [&](const char* name) {
    const std::string token = pgm_token(data, at, path);
    long value = 0;
    if (!parse_pgm_number(token, value))
      throw bad("malformed PGM header (width, height, maxval): the " + std::string(name) + " '" + token +
                "' is not a decimal number");
    return value;
  };
  const long width = number("width");
  const long height = number("height");
  const long maxval = number("maxval");
  if (at > kMaxPgmHeaderBytes)
    throw bad("the PGM header is " + std::to_string(at) + " bytes, more than " + std::to_string(kMaxPgmHeaderBytes));
  if (width < 1 || width > 65535 || height < 1 || height > 65535)
    throw bad("frame size " + std::to_string(width) + " x " + std::to_string(height) + " is outside 1..65535");
  if (maxval < 1 || maxval > 255) throw bad("maxval " + std::to_string(maxval) + " is not 8-bit (1..255)");
  const auto width_u = static_cast<std::size_t>(width), height_u = static_cast<std::size_t>(height);
  const std::size_t pixel_bytes = width_u * height_u;
  if (data.size() - at < pixel_bytes)
    throw bad("truncated: the header says " + std::to_string(width) + " x " + std::to_string(height) + " = " +
              std::to_string(pixel_bytes) + " pixel bytes, the file holds " + std::to_string(data.size() - at) +
              " after the header");
  if (width_u > kMaxFrameWidthPx || height_u > kMaxFrameHeightPx)
    throw bad("frame size " + std::to_string(width) + " x " + std::to_string(height) +
              " is larger than the labeler's " + std::to_string(kMaxFrameWidthPx) + " x " +
              std::to_string(kMaxFrameHeightPx));
  std::vector<std::uint8_t> pixels(pixel_bytes);
  std::transform(data.begin() + static_cast<std::ptrdiff_t>(at),
                 data.begin() + static_cast<std::ptrdiff_t>(at + pixel_bytes), pixels.begin(),
                 [](char c) { return static_cast<std::uint8_t>(c); });
  width_px = static_cast<std::uint16_t>(width);
  height_px = static_cast<std::uint16_t>(height);
  return pixels;
}

PgmFrames::PgmFrames(const std::string& path) {
  if (path.empty()) return;
  namespace fs = std::filesystem;
  // What the path is, before anything opens it: a FIFO would block open() until a writer came.
  struct stat status {};
  if (::stat(path.c_str(), &status) != 0) throw std::runtime_error("frames " + path + ": " + std::strerror(errno));
  if (S_ISDIR(status.st_mode)) {
    for (const fs::directory_entry& e : fs::directory_iterator(path)) {
      if (e.path().extension() != ".pgm") continue;
      const std::string file = e.path().string();
      require_regular_file(file, "frames directory " + path + ": frame");
      files_.push_back(file);
    }
    std::sort(files_.begin(), files_.end());
    if (files_.empty()) throw std::runtime_error("frames directory " + path + " holds no .pgm file");
  } else if (S_ISREG(status.st_mode)) {
    files_.push_back(path);
  } else {
    throw std::runtime_error("frames " + path + " is " + file_kind(status.st_mode) +
                             ": give a PGM file or a directory of them");
  }
  pixels_ = read_pgm(files_.front(), width_px_, height_px_);  // the frame size, and an early error
}

bool PgmFrames::load(const std::string& path) {
  try {
    std::uint16_t width = 0, height = 0;
    std::vector<std::uint8_t> pixels = read_pgm(path, width, height);
    if (width != width_px_ || height != height_px_) {
      std::cerr << "kincal_platform: frame " << path << " is " << width << " x " << height
                << ", the camera's frames are " << width_px_ << " x " << height_px_ << "\n";
      return false;
    }
    pixels_ = std::move(pixels);
    current_ = path;
    return true;
  } catch (const std::exception& e) {
    std::cerr << "kincal_platform: " << e.what() << "\n";
    return false;
  }
}

app::CaptureStatus PgmFrames::begin_frame(app::FrameUse use, std::uint64_t& exposure_us) {
  exposure_us = monotonic_us();
  row_ = 0;
  frame_ok_ = false;
  if (files_.empty()) {
    std::cerr << "kincal_platform: a camera section was asked for, but no --frames were given\n";
    return app::CaptureStatus::kFailed;
  }
  if (use == app::FrameUse::kMetering || current_.empty()) {
    if (next_file_ >= files_.size()) {
      if (files_.size() > 1) {
        std::cerr << "kincal_platform: no more frames (all " << files_.size() << " files were used)\n";
        return app::CaptureStatus::kFailed;
      }
      next_file_ = 0;  // a single file serves every measurement
    }
    if (!load(files_[next_file_++])) return app::CaptureStatus::kFailed;
  }
  frame_ok_ = true;
  return app::CaptureStatus::kOk;
}

app::CaptureStatus PgmFrames::read_row(std::span<std::uint8_t> row) {
  if (!frame_ok_ || row_ >= height_px_ || row.size() != width_px_) return app::CaptureStatus::kFailed;
  std::copy_n(pixels_.begin() + static_cast<std::ptrdiff_t>(row_ * width_px_), width_px_, row.begin());
  ++row_;
  return app::CaptureStatus::kOk;
}

static_assert(app::CameraPort<PgmFrames>);

}  // namespace kincal::native
