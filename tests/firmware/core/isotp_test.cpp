// ISO-TP (firmware/core/isotp.hpp), natively and on the M4: frame-exact behaviour for the
// cases Linux can-isotp produces and expects (PCI bytes, lengths, padding 0xCC, flow control),
// transfers of every size class over classic CAN and CAN FD with block size and STmin, and the
// failure paths: sequence errors, timeouts, overflow, FC WAIT, malformed frames.
#include "firmware/core/isotp.hpp"

#include <doctest.h>

#include <array>
#include <cstdint>

using kincal::core::IsoTpBuffers;
using kincal::core::IsoTpConfig;
using kincal::core::IsoTpEndpoint;
using kincal::core::IsoTpEvent;
using kincal::core::IsoTpSendStatus;
using kincal::shared::CanFrame;

namespace {

constexpr std::size_t kBig = 5000;

IsoTpConfig config(std::uint32_t tx, std::uint32_t rx, std::uint8_t tx_dl = 8, bool padding = false) {
  IsoTpConfig c;
  c.tx_id = tx;
  c.rx_id = rx;
  c.tx_dl = tx_dl;
  c.fd = tx_dl > 8;
  c.padding = padding;
  return c;
}

CanFrame frame_of(std::uint32_t id, std::initializer_list<std::uint8_t> bytes, bool fd = false) {
  CanFrame f;
  f.id = id;
  f.fd = fd;
  f.length = static_cast<std::uint8_t>(bytes.size());
  std::size_t i = 0;
  for (const std::uint8_t b : bytes) f.data[i++] = b;
  return f;
}

std::uint8_t pattern(std::size_t i) { return static_cast<std::uint8_t>(i * 7u + 3u); }

// Two endpoints on one simulated bus; the clock advances 10 us per frame on the wire.
struct Link {
  IsoTpBuffers<kBig, kBig> a_buffers, b_buffers;
  IsoTpEndpoint a, b;
  std::uint64_t now_us = 0;
  std::size_t frames = 0;
  std::uint64_t last_cf_us = 0, min_cf_gap_us = ~std::uint64_t{0};
  int fc_frames = 0;

  Link(const IsoTpConfig& ca, const IsoTpConfig& cb) : a(ca, a_buffers), b(cb, b_buffers) {}

  // Runs until b has a message, or nothing moves for a simulated second. Returns b's last event.
  IsoTpEvent run() {
    IsoTpEvent last = IsoTpEvent::kNone;
    for (int idle = 0; idle < 1000000 && frames < 100000;) {
      CanFrame f;
      bool moved = false;
      if (a.next_frame(now_us, f)) {
        if ((f.data[0] >> 4) == 2) {
          if (last_cf_us != 0 && now_us - last_cf_us < min_cf_gap_us) min_cf_gap_us = now_us - last_cf_us;
          last_cf_us = now_us;
        }
        last = b.on_frame(f, now_us);
        moved = true;
        ++frames;
        if (last == IsoTpEvent::kRxComplete) return last;
        if (last != IsoTpEvent::kNone) return last;
      }
      if (b.next_frame(now_us, f)) {
        ++fc_frames;
        last_cf_us = 0;  // STmin separates CFs within a block; the first after an FC goes at once (as in Linux)
        const IsoTpEvent e = a.on_frame(f, now_us);
        if (e != IsoTpEvent::kNone) return e;
        moved = true;
      }
      now_us += 10;
      idle = moved ? 0 : idle + 1;
    }
    return last;
  }
};

bool transfer(std::size_t size, std::uint8_t tx_dl, std::uint8_t bs = 0, std::uint8_t st_min = 0,
              bool padding = false) {
  IsoTpConfig ca = config(0x150, 0x158, tx_dl, padding);
  IsoTpConfig cb = config(0x158, 0x150, tx_dl, padding);
  cb.block_size = bs;
  cb.st_min_raw = st_min;
  Link link(ca, cb);
  std::array<std::uint8_t, kBig> msg{};
  for (std::size_t i = 0; i < size; ++i) msg[i] = pattern(i);
  if (link.a.start_send(std::span<const std::uint8_t>(msg).first(size), 0) != IsoTpSendStatus::kOk) return false;
  if (link.run() != IsoTpEvent::kRxComplete) return false;
  const auto got = link.b.message();
  if (got.size() != size) return false;
  for (std::size_t i = 0; i < size; ++i)
    if (got[i] != pattern(i)) return false;
  return !link.a.tx_busy() && !link.b.rx_busy();
}

}  // namespace

TEST_CASE("classic frames as Linux can-isotp sends them: SF, FF, FC, CF") {
  IsoTpBuffers<64, 64> buffers;
  IsoTpEndpoint ep(config(0x158, 0x150), buffers);
  // Single frame, no padding: DLC = 1 + length.
  auto event = ep.on_frame(frame_of(0x150, {0x03, 0x11, 0x22, 0x33}), 0);
  REQUIRE(event == IsoTpEvent::kRxComplete);
  REQUIRE(ep.message().size() == 3);
  CHECK(ep.message()[2] == 0x33);
  // Padded single frame (CAN_ISOTP_TX_PADDING): the pad bytes are ignored.
  REQUIRE(ep.on_frame(frame_of(0x150, {0x02, 0xAA, 0xBB, 0xCC, 0xCC, 0xCC, 0xCC, 0xCC}), 0) == IsoTpEvent::kRxComplete);
  CHECK(ep.message().size() == 2);
  // First frame of 20 bytes: 10 14 + 6 data bytes; we answer FC CTS, BS 0, STmin 0.
  REQUIRE(ep.on_frame(frame_of(0x150, {0x10, 0x14, 1, 2, 3, 4, 5, 6}), 0) == IsoTpEvent::kNone);
  CanFrame fc;
  REQUIRE(ep.next_frame(0, fc));
  CHECK(fc.id == 0x158);
  CHECK(fc.length == 3);
  CHECK(fc.data[0] == 0x30);
  CHECK(fc.data[1] == 0x00);
  CHECK(fc.data[2] == 0x00);
  CHECK_FALSE(ep.next_frame(0, fc));
  REQUIRE(ep.on_frame(frame_of(0x150, {0x21, 7, 8, 9, 10, 11, 12, 13}), 10) == IsoTpEvent::kNone);
  // The last CF may be short (no padding) and carries the rest.
  REQUIRE(ep.on_frame(frame_of(0x150, {0x22, 14, 15, 16, 17, 18, 19, 20}), 20) == IsoTpEvent::kRxComplete);
  REQUIRE(ep.message().size() == 20);
  for (std::size_t i = 0; i < 20; ++i) CHECK(ep.message()[i] == i + 1);
}

TEST_CASE("what we send: SF and FF/CF layout, padding with 0xCC") {
  IsoTpBuffers<64, 64> buffers;
  IsoTpEndpoint plain(config(0x158, 0x150), buffers);
  const std::array<std::uint8_t, 9> msg{1, 2, 3, 4, 5, 6, 7, 8, 9};
  REQUIRE(plain.start_send(std::span<const std::uint8_t>(msg).first(3), 0) == IsoTpSendStatus::kOk);
  CanFrame f;
  REQUIRE(plain.next_frame(0, f));
  CHECK(f.length == 4);
  CHECK(f.data[0] == 0x03);
  CHECK_FALSE(plain.tx_busy());

  IsoTpBuffers<64, 64> buffers2;
  IsoTpEndpoint padded(config(0x158, 0x150, 8, true), buffers2);
  REQUIRE(padded.start_send(std::span<const std::uint8_t>(msg).first(3), 0) == IsoTpSendStatus::kOk);
  REQUIRE(padded.next_frame(0, f));
  CHECK(f.length == 8);
  CHECK(f.data[3] == 3);
  for (std::size_t i = 4; i < 8; ++i) CHECK(f.data[i] == 0xCC);

  REQUIRE(padded.start_send(msg, 0) == IsoTpSendStatus::kOk);
  REQUIRE(padded.next_frame(0, f));
  CHECK(f.length == 8);
  CHECK(f.data[0] == 0x10);
  CHECK(f.data[1] == 9);
  CHECK(f.data[7] == 6);
  CHECK_FALSE(padded.next_frame(0, f));  // waiting for flow control
  CHECK(padded.on_frame(frame_of(0x150, {0x30, 0x00, 0x00}), 5) == IsoTpEvent::kNone);
  REQUIRE(padded.next_frame(5, f));
  CHECK(f.length == 8);
  CHECK(f.data[0] == 0x21);
  CHECK(f.data[1] == 7);
  CHECK(f.data[3] == 9);
  CHECK(f.data[4] == 0xCC);
  CHECK_FALSE(padded.tx_busy());
  CHECK(padded.stats().tx_messages == 2);
}

TEST_CASE("transfers of every size class, classic CAN and CAN FD") {
  for (const std::size_t size : {1u, 6u, 7u, 8u, 13u, 14u, 62u, 63u, 64u, 111u, 112u, 113u, 4095u, 4096u, 5000u}) {
    CAPTURE(size);
    CHECK(transfer(size, 8));
    CHECK(transfer(size, 8, 0, 0, true));
    CHECK(transfer(size, 64));
    CHECK(transfer(size, 16, 3));
  }
}

TEST_CASE("block size and STmin are obeyed") {
  IsoTpConfig ca = config(0x150, 0x158);
  IsoTpConfig cb = config(0x158, 0x150);
  cb.block_size = 4;
  cb.st_min_raw = 5;  // 5 ms
  Link link(ca, cb);
  std::array<std::uint8_t, 200> msg{};
  REQUIRE(link.a.start_send(msg, 0) == IsoTpSendStatus::kOk);
  REQUIRE(link.run() == IsoTpEvent::kRxComplete);
  // 200 bytes = FF (6) + 28 CFs -> FCs after the FF and after every 4th CF: 1 + 6 = 7.
  CHECK(link.fc_frames == 7);
  CHECK(link.min_cf_gap_us >= 5000);

  cb.block_size = 0;
  cb.st_min_raw = 0xF3;  // 300 us
  Link fast(ca, cb);
  REQUIRE(fast.a.start_send(msg, 0) == IsoTpSendStatus::kOk);
  REQUIRE(fast.run() == IsoTpEvent::kRxComplete);
  CHECK(fast.fc_frames == 1);
  CHECK(fast.min_cf_gap_us >= 300);
  CHECK(fast.min_cf_gap_us < 5000);
  CHECK(IsoTpEndpoint::st_min_us(0x7F) == 127000);
  CHECK(IsoTpEndpoint::st_min_us(0x80) == 127000);  // reserved
  CHECK(IsoTpEndpoint::st_min_us(0xF9) == 900);
  CHECK(IsoTpEndpoint::st_min_us(0xFA) == 127000);  // reserved
}

TEST_CASE("CAN FD: escape single frame, 64-byte frames, padding to a valid length") {
  IsoTpBuffers<256, 256> buffers;
  IsoTpEndpoint ep(config(0x158, 0x150, 64), buffers);
  std::array<std::uint8_t, 100> msg{};
  for (std::size_t i = 0; i < msg.size(); ++i) msg[i] = pattern(i);
  REQUIRE(ep.start_send(std::span<const std::uint8_t>(msg).first(20), 0) == IsoTpSendStatus::kOk);
  CanFrame f;
  REQUIRE(ep.next_frame(0, f));
  CHECK(f.fd);
  CHECK(f.length == 24);  // 2 PCI + 20 data -> next FD length 24
  CHECK(f.data[0] == 0x00);
  CHECK(f.data[1] == 20);
  CHECK(f.data[22] == 0xCC);
  // Received escape SF.
  IsoTpBuffers<256, 256> rb;
  IsoTpEndpoint rx(config(0x150, 0x158, 64), rb);
  f.id = 0x158;
  REQUIRE(rx.on_frame(f, 0) == IsoTpEvent::kRxComplete);
  CHECK(rx.message().size() == 20);
  CHECK(rx.message()[19] == pattern(19));
  // 100 bytes: FF of 64 bytes (62 data), then one CF of 1 + 38 -> padded to 48.
  REQUIRE(ep.start_send(msg, 0) == IsoTpSendStatus::kOk);
  REQUIRE(ep.next_frame(0, f));
  CHECK(f.length == 64);
  CHECK(f.data[0] == 0x10);
  CHECK(f.data[1] == 100);
  REQUIRE(ep.on_frame(frame_of(0x150, {0x30, 0, 0}, true), 1) == IsoTpEvent::kNone);
  REQUIRE(ep.next_frame(1, f));
  CHECK(f.length == 48);
  CHECK(f.data[0] == 0x21);
  CHECK(f.data[38] == pattern(99));
  CHECK(f.data[39] == 0xCC);
}

TEST_CASE("sequence error, CF without reception, restart by a new first frame") {
  IsoTpBuffers<64, 64> buffers;
  IsoTpEndpoint ep(config(0x158, 0x150), buffers);
  CHECK(ep.on_frame(frame_of(0x150, {0x21, 1, 2, 3, 4, 5, 6, 7}), 0) == IsoTpEvent::kIgnored);
  REQUIRE(ep.on_frame(frame_of(0x150, {0x10, 0x14, 1, 2, 3, 4, 5, 6}), 0) == IsoTpEvent::kNone);
  CHECK(ep.on_frame(frame_of(0x150, {0x22, 1, 2, 3, 4, 5, 6, 7}), 1) == IsoTpEvent::kSequenceError);
  CHECK_FALSE(ep.rx_busy());
  CHECK(ep.stats().sequence_errors == 1);
  // A new FF in the middle of a reception restarts it.
  REQUIRE(ep.on_frame(frame_of(0x150, {0x10, 0x14, 1, 2, 3, 4, 5, 6}), 2) == IsoTpEvent::kNone);
  REQUIRE(ep.on_frame(frame_of(0x150, {0x10, 0x0A, 9, 9, 9, 9, 9, 9}), 3) == IsoTpEvent::kNone);
  CHECK(ep.stats().rx_restarts == 1);
  REQUIRE(ep.on_frame(frame_of(0x150, {0x21, 8, 8, 8, 8}), 4) == IsoTpEvent::kRxComplete);
  CHECK(ep.message().size() == 10);
  CHECK(ep.message()[9] == 8);
}

TEST_CASE("sequence numbers wrap from 15 to 0") {
  CHECK(transfer(6 + 7 * 20, 8));  // 20 consecutive frames
}

TEST_CASE("timeouts: N_Cr while receiving, N_Bs while waiting for flow control") {
  IsoTpBuffers<64, 64> buffers;
  IsoTpEndpoint ep(config(0x158, 0x150), buffers);
  REQUIRE(ep.on_frame(frame_of(0x150, {0x10, 0x14, 1, 2, 3, 4, 5, 6}), 1000) == IsoTpEvent::kNone);
  CHECK(ep.check_timeouts(1000 + 1000000) == IsoTpEvent::kNone);
  CHECK(ep.next_deadline_us() == 0);  // the flow control is still to be sent
  CanFrame f;
  REQUIRE(ep.next_frame(1000, f));
  CHECK(ep.next_deadline_us() == 1000 + 1000000 + 1);
  CHECK(ep.check_timeouts(1000 + 1000001) == IsoTpEvent::kRxTimeout);
  CHECK_FALSE(ep.rx_busy());

  std::array<std::uint8_t, 30> msg{};
  REQUIRE(ep.start_send(msg, 0) == IsoTpSendStatus::kOk);
  REQUIRE(ep.next_frame(0, f));
  CHECK(ep.start_send(msg, 0) == IsoTpSendStatus::kBusy);
  CHECK(ep.check_timeouts(500000) == IsoTpEvent::kNone);
  CHECK(ep.check_timeouts(1000001) == IsoTpEvent::kTxTimeout);
  CHECK_FALSE(ep.tx_busy());
  CHECK(ep.stats().tx_timeouts == 1);
}

TEST_CASE("overflow: a first frame longer than the buffer gets FC OVERFLOW, and the sender aborts") {
  IsoTpConfig ca = config(0x150, 0x158);
  IsoTpConfig cb = config(0x158, 0x150);
  IsoTpBuffers<256, 256> abuf;
  IsoTpBuffers<32, 32> bbuf;
  IsoTpEndpoint a(ca, abuf), b(cb, bbuf);
  std::array<std::uint8_t, 100> msg{};
  REQUIRE(a.start_send(msg, 0) == IsoTpSendStatus::kOk);
  CanFrame f;
  REQUIRE(a.next_frame(0, f));
  CHECK(b.on_frame(f, 0) == IsoTpEvent::kRxOverflow);
  REQUIRE(b.next_frame(0, f));
  CHECK(f.data[0] == 0x32);
  CHECK(a.on_frame(f, 0) == IsoTpEvent::kRemoteOverflow);
  CHECK_FALSE(a.tx_busy());
  CHECK(b.start_send(msg, 0) == IsoTpSendStatus::kTooLong);
  CHECK(b.start_send({}, 0) == IsoTpSendStatus::kEmpty);
}

TEST_CASE("FC WAIT: tolerated up to max_wait_frames, then the transmission aborts") {
  IsoTpConfig c = config(0x158, 0x150);
  c.max_wait_frames = 2;
  IsoTpBuffers<64, 64> buffers;
  IsoTpEndpoint ep(c, buffers);
  std::array<std::uint8_t, 30> msg{};
  REQUIRE(ep.start_send(msg, 0) == IsoTpSendStatus::kOk);
  CanFrame f;
  REQUIRE(ep.next_frame(0, f));
  CHECK(ep.on_frame(frame_of(0x150, {0x31, 0, 0}), 900000) == IsoTpEvent::kNone);
  CHECK(ep.check_timeouts(1500000) == IsoTpEvent::kNone);  // WAIT restarted N_Bs
  CHECK(ep.on_frame(frame_of(0x150, {0x31, 0, 0}), 1600000) == IsoTpEvent::kNone);
  CHECK(ep.on_frame(frame_of(0x150, {0x31, 0, 0}), 1700000) == IsoTpEvent::kWaitLimit);
  CHECK_FALSE(ep.tx_busy());
}

TEST_CASE("malformed frames are dropped with kBadFrame") {
  IsoTpBuffers<64, 64> buffers;
  IsoTpEndpoint ep(config(0x158, 0x150), buffers);
  CHECK(ep.on_frame(frame_of(0x150, {}), 0) == IsoTpEvent::kBadFrame);                     // empty
  CHECK(ep.on_frame(frame_of(0x150, {0x00, 1, 2}), 0) == IsoTpEvent::kBadFrame);           // SF_DL 0 in classic
  CHECK(ep.on_frame(frame_of(0x150, {0x05, 1, 2}), 0) == IsoTpEvent::kBadFrame);           // SF_DL > data
  CHECK(ep.on_frame(frame_of(0x150, {0x10, 0x14, 1, 2, 3}), 0) == IsoTpEvent::kBadFrame);  // short FF
  CHECK(ep.on_frame(frame_of(0x150, {0x10, 0x05, 1, 2, 3, 4, 5, 6}), 0) == IsoTpEvent::kBadFrame);  // FF_DL <= 7
  CHECK(ep.on_frame(frame_of(0x150, {0x10, 0x00, 0, 0, 0x0F, 0xFF, 1, 2}), 0) ==
        IsoTpEvent::kBadFrame);                                                   // escape <= 4095
  CHECK(ep.on_frame(frame_of(0x150, {0x40, 1, 2}), 0) == IsoTpEvent::kBadFrame);  // reserved PCI type
  CHECK(ep.on_frame(frame_of(0x150, {0xF0}), 0) == IsoTpEvent::kBadFrame);
  CHECK(ep.on_frame(frame_of(0x151, {0x01, 1}), 0) == IsoTpEvent::kIgnored);     // other ID
  CHECK(ep.on_frame(frame_of(0x150, {0x30, 0, 0}), 0) == IsoTpEvent::kIgnored);  // stray FC
  CanFrame bad_len = frame_of(0x150, {0x01, 1});
  bad_len.length = 9;  // not a classic length
  CHECK(ep.on_frame(bad_len, 0) == IsoTpEvent::kBadFrame);
  // A short consecutive frame that is not the last one aborts the reception.
  REQUIRE(ep.on_frame(frame_of(0x150, {0x10, 0x14, 1, 2, 3, 4, 5, 6}), 0) == IsoTpEvent::kNone);
  CHECK(ep.on_frame(frame_of(0x150, {0x21, 1, 2, 3}), 0) == IsoTpEvent::kBadFrame);
  CHECK_FALSE(ep.rx_busy());
  CHECK(ep.stats().bad_frames == 10);
}

TEST_CASE("pseudo-random frames never break the endpoint") {
  IsoTpBuffers<128, 128> buffers;
  IsoTpEndpoint ep(config(0x158, 0x150, 64), buffers);
  std::uint32_t state = 12345;
  auto next = [&state] {
    state = state * 1664525u + 1013904223u;
    return state >> 8;
  };
  std::uint64_t now = 0;
  for (int i = 0; i < 20000; ++i) {
    CanFrame f;
    f.id = 0x150;
    f.fd = (next() & 1) != 0;
    f.length = f.fd ? kincal::shared::kFdLengthByDlc[next() % 16] : static_cast<std::uint8_t>(next() % 9);
    for (std::size_t b = 0; b < f.length; ++b) f.data[b] = static_cast<std::uint8_t>(next());
    if (next() % 4 == 0) f.data[0] = static_cast<std::uint8_t>(0x20 | (next() & 0x1F));
    (void)ep.on_frame(f, now);
    CanFrame out;
    while (ep.next_frame(now, out)) CHECK(out.length <= 64);
    (void)ep.check_timeouts(now);
    REQUIRE(ep.message().size() <= 128);
    now += next() % 2000;
  }
}
