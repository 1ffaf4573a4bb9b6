#include "host/can/socketcan.hpp"

#include <linux/can.h>
#include <linux/can/isotp.h>
#include <linux/can/raw.h>
#include <net/if.h>
#include <poll.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>

#include "host/can/frame_filter.hpp"
#include "shared/protocol.hpp"

namespace kincal::can {

namespace {

[[noreturn]] void fail(const std::string& interface, const std::string& what, const char* hint = "") {
  throw CanError(interface + ": " + what + ": " + std::strerror(errno) + hint);
}

int interface_index(int fd, const std::string& interface) {
  if (interface.size() >= IFNAMSIZ) throw CanError("interface name '" + interface + "' is too long");
  ifreq request{};
  std::strncpy(request.ifr_name, interface.c_str(), IFNAMSIZ - 1);
  if (ioctl(fd, SIOCGIFINDEX, &request) < 0) fail(interface, "no such CAN interface");
  return request.ifr_ifindex;
}

int poll_one(int fd, std::chrono::milliseconds timeout) {
  pollfd p{fd, POLLIN, 0};
  const int n = ::poll(&p, 1, static_cast<int>(timeout.count()));
  return n;
}

}  // namespace

RawCanSocket::RawCanSocket(const std::string& interface, bool fd, const std::vector<IdFilter>& filters)
    : interface_(interface), can_fd_(fd) {
  fd_ = ::socket(PF_CAN, SOCK_RAW, CAN_RAW);
  if (fd_ < 0) fail(interface, "cannot open a CAN_RAW socket", " (is the module can-raw loaded?)");
  try {
    if (fd) {
      const int on = 1;
      if (setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FD_FRAMES, &on, sizeof on) < 0)
        fail(interface, "cannot enable CAN FD frames");
    }
    if (!filters.empty()) {
      std::vector<can_filter> kernel;
      for (const IdFilter& f : filters) kernel.push_back({f.id, f.mask | CAN_EFF_FLAG | CAN_RTR_FLAG});
      if (setsockopt(fd_, SOL_CAN_RAW, CAN_RAW_FILTER, kernel.data(),
                     static_cast<socklen_t>(kernel.size() * sizeof(can_filter))) < 0)
        fail(interface, "cannot set CAN_RAW_FILTER");
    }
    sockaddr_can address{};
    address.can_family = AF_CAN;
    address.can_ifindex = interface_index(fd_, interface);
    if (bind(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) < 0)
      fail(interface, "cannot bind CAN_RAW socket");
  } catch (...) {
    ::close(fd_);
    throw;
  }
}

RawCanSocket::~RawCanSocket() {
  if (fd_ >= 0) ::close(fd_);
}

void RawCanSocket::send(const CanFrame& frame) {
  if (frame.fd && !can_fd_) throw CanError(interface_ + ": CAN FD frame on a socket opened for classic CAN");
  canfd_frame k{};
  k.can_id = frame.id | (frame.extended ? CAN_EFF_FLAG : 0u);
  k.len = frame.length;
  k.flags = frame.fd && frame.brs ? CANFD_BRS : 0;
  std::memcpy(k.data, frame.data.data(), frame.length);
  const std::size_t size = frame.fd ? CANFD_MTU : CAN_MTU;
  for (int attempt = 0; attempt < 100; ++attempt) {
    const ssize_t n = ::write(fd_, &k, size);
    if (n == static_cast<ssize_t>(size)) return;
    if (n < 0 && errno == ENOBUFS) {  // the interface queue is full: wait for it to drain
      ::usleep(1000);
      continue;
    }
    fail(interface_, "cannot send a CAN frame");
  }
  throw CanError(interface_ + ": transmit queue stayed full for 100 ms");
}

CanFrame RawCanSocket::read_ready() {
  canfd_frame k{};
  const ssize_t n = ::read(fd_, &k, sizeof k);
  if (n != CAN_MTU && n != CANFD_MTU) fail(interface_, "cannot read a CAN frame");
  CanFrame f;
  f.extended = (k.can_id & CAN_EFF_FLAG) != 0;
  f.id = k.can_id & (f.extended ? CAN_EFF_MASK : CAN_SFF_MASK);
  f.fd = n == CANFD_MTU;
  f.brs = f.fd && (k.flags & CANFD_BRS) != 0;
  f.length = k.len > 64 ? 64 : k.len;
  std::memcpy(f.data.data(), k.data, f.length);
  return f;
}

bool RawCanSocket::receive(CanFrame& out, std::chrono::milliseconds timeout) {
  const int n = poll_one(fd_, timeout);
  if (n < 0) fail(interface_, "poll failed");
  if (n == 0) return false;
  out = read_ready();
  return true;
}

IsoTpSocket::IsoTpSocket(const std::string& interface, const IsoTpOptions& options) : interface_(interface) {
  fd_ = ::socket(PF_CAN, SOCK_DGRAM, CAN_ISOTP);
  if (fd_ < 0) fail(interface, "cannot open a CAN_ISOTP socket", " (is the module can-isotp loaded?)");
  try {
    can_isotp_options opts{};
    opts.flags = options.padding ? CAN_ISOTP_TX_PADDING : 0;
    opts.txpad_content = CAN_ISOTP_DEFAULT_PAD_CONTENT;
    opts.rxpad_content = CAN_ISOTP_DEFAULT_PAD_CONTENT;
    opts.frame_txtime = CAN_ISOTP_DEFAULT_FRAME_TXTIME;
    if (setsockopt(fd_, SOL_CAN_ISOTP, CAN_ISOTP_OPTS, &opts, sizeof opts) < 0)
      fail(interface, "cannot set CAN_ISOTP_OPTS");
    can_isotp_fc_options fc{options.block_size, options.st_min_raw, 0};
    if (setsockopt(fd_, SOL_CAN_ISOTP, CAN_ISOTP_RECV_FC, &fc, sizeof fc) < 0)
      fail(interface, "cannot set CAN_ISOTP_RECV_FC");
    if (options.fd) {
      can_isotp_ll_options ll{CANFD_MTU, 64, CANFD_BRS};
      if (setsockopt(fd_, SOL_CAN_ISOTP, CAN_ISOTP_LL_OPTS, &ll, sizeof ll) < 0)
        fail(interface, "cannot set CAN_ISOTP_LL_OPTS for CAN FD");
    }
    sockaddr_can address{};
    address.can_family = AF_CAN;
    address.can_ifindex = interface_index(fd_, interface);
    address.can_addr.tp.tx_id = options.tx_id;
    address.can_addr.tp.rx_id = options.rx_id;
    if (bind(fd_, reinterpret_cast<sockaddr*>(&address), sizeof address) < 0)
      fail(interface, "cannot bind CAN_ISOTP socket");
  } catch (...) {
    ::close(fd_);
    throw;
  }
}

IsoTpSocket::~IsoTpSocket() {
  if (fd_ >= 0) ::close(fd_);
}

void IsoTpSocket::send(std::span<const std::uint8_t> message) {
  const ssize_t n = ::write(fd_, message.data(), message.size());
  if (n != static_cast<ssize_t>(message.size()))
    fail(interface_, "ISO-TP send of " + std::to_string(message.size()) + " bytes failed",
         errno == ECOMM ? " (no flow control from the platform: is it running?)" : "");
}

std::vector<std::uint8_t> IsoTpSocket::read_ready() {
  std::vector<std::uint8_t> buffer(8192);
  const ssize_t n = ::read(fd_, buffer.data(), buffer.size());
  if (n < 0) fail(interface_, "ISO-TP receive failed", " (malformed or timed-out transfer from the platform)");
  buffer.resize(static_cast<std::size_t>(n));
  return buffer;
}

namespace {

std::vector<IdFilter> platform_filters() {
  std::vector<IdFilter> filters;
  for (const std::uint32_t id : platform_frame_ids()) filters.push_back({id, CAN_SFF_MASK});
  return filters;
}

}  // namespace

SocketCanTransport::SocketCanTransport(const std::string& interface, const SocketCanOptions& options)
    : interface_(interface),
      raw_(interface, options.fd, platform_filters()),
      isotp_(interface, IsoTpOptions{shared::can_id::kIsoTpRequest, shared::can_id::kIsoTpResponse, options.padding,
                                     options.fd, 0, 0}) {
  if (!options.log_path.empty()) {
    tap_ = std::make_unique<RawCanSocket>(interface, true, std::vector<IdFilter>{});
    log_ = std::make_unique<CandumpWriter>(options.log_path);
  }
}

void SocketCanTransport::drain_tap() {
  if (!tap_) return;
  CanFrame f;
  while (tap_->receive(f, std::chrono::milliseconds(0))) log_->write(interface_, f);
}

void SocketCanTransport::send_frame(const CanFrame& frame) {
  raw_.send(frame);
  drain_tap();
}

void SocketCanTransport::send_message(std::span<const std::uint8_t> message) {
  isotp_.send(message);
  drain_tap();
}

bool SocketCanTransport::receive(Received& out, std::chrono::milliseconds timeout) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    drain_tap();
    const auto left =
        std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
    pollfd fds[3] = {{raw_.descriptor(), POLLIN, 0}, {isotp_.descriptor(), POLLIN, 0}, {-1, POLLIN, 0}};
    if (tap_) fds[2].fd = tap_->descriptor();
    const int n = ::poll(fds, 3, left.count() > 0 ? static_cast<int>(left.count()) : 0);
    if (n < 0 && errno != EINTR) fail(interface_, "poll failed");
    if (n > 0 && (fds[1].revents & (POLLIN | POLLERR))) {
      out.kind = Received::Kind::kMessage;
      out.message = isotp_.read_ready();
      drain_tap();
      return true;
    }
    if (n > 0 && (fds[0].revents & POLLIN)) {
      out.kind = Received::Kind::kFrame;
      out.frame = raw_.read_ready();
      drain_tap();
      return true;
    }
    if (std::chrono::steady_clock::now() >= deadline) {
      drain_tap();
      return false;
    }
  }
}

}  // namespace kincal::can
