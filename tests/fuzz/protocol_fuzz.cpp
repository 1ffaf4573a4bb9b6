// libFuzzer target for every decoder of the protocol and the firmware's ISO-TP receiver
// (nanopb habit: decode, and where decoding succeeds, encode again and require the same bytes).
// The first input byte selects the target; the rest is its input:
//   0  ISO-TP endpoint (classic and FD): a stream of frames [flags, length, bytes...] with time
//   1  single-frame messages: [id index, fd?, length, data...] through decode_raw and the typed
//      decoders; success must re-encode to the same frame
//   2  measurement report;  3  parameter message and all four blocks;  4  parameter read
// Runs standalone too (a file argument), and as the ctest fuzz.protocol for a bounded time.
#include <cstddef>
#include <cstdint>
#include <cstdlib>
#include <cstring>

#include "firmware/core/isotp.hpp"
#include "shared/measurement_report.hpp"
#include "shared/parameters.hpp"
#include "shared/protocol.hpp"

using namespace kincal;

namespace {

void require(bool condition) {
  if (!condition) std::abort();
}

void fuzz_isotp(const std::uint8_t* data, std::size_t size) {
  core::IsoTpConfig c;
  c.tx_id = 0x158;
  c.rx_id = 0x150;
  c.tx_dl = (size > 0 && (data[0] & 1)) ? 64 : 8;
  c.fd = c.tx_dl > 8;
  c.block_size = size > 1 ? data[1] % 4 : 0;
  static core::IsoTpBuffers<256, 256> buffers;
  core::IsoTpEndpoint ep(c, buffers);
  std::uint64_t now = 0;
  std::size_t i = 2;
  while (i + 2 <= size) {
    shared::CanFrame f;
    f.id = (data[i] & 0x80) ? 0x151 : 0x150;
    f.fd = (data[i] & 0x40) != 0;
    const std::size_t want = data[i + 1] % 65;
    f.length = static_cast<std::uint8_t>(f.fd ? shared::fd_length_at_least(want) : want % 9);
    now += (data[i] & 0x3F) * 20000u;
    i += 2;
    for (std::size_t b = 0; b < f.length && i < size; ++b) f.data[b] = data[i++];
    const core::IsoTpEvent e = ep.on_frame(f, now);
    if (e == core::IsoTpEvent::kRxComplete) require(ep.message().size() <= 256);
    shared::CanFrame out;
    for (int n = 0; n < 8 && ep.next_frame(now, out); ++n) require(shared::is_valid_length(out.fd, out.length));
    (void)ep.check_timeouts(now);
    if ((data[i - 1] & 0x0F) == 0x0F)
      (void)ep.start_send(std::span<const std::uint8_t>(data, size > 200 ? 200 : size), now);
  }
}

void fuzz_single_frame(const std::uint8_t* data, std::size_t size) {
  if (size < 3) return;
  const auto messages = shared::single_frame_messages();
  const shared::MessageSpec& spec = messages[data[0] % messages.size()];
  shared::CanFrame f;
  f.id = spec.id;
  f.fd = (data[1] & 1) != 0;
  f.length = static_cast<std::uint8_t>(data[2] % 65);
  for (std::size_t b = 0; b < f.length && 3 + b < size; ++b) f.data[b] = data[3 + b];
  std::int64_t raw[16] = {};
  if (shared::decode_raw(spec, f, std::span<std::int64_t>(raw, 16)) == shared::DecodeStatus::kOk) {
    shared::CanFrame again;
    shared::encode_raw(spec, std::span<const std::int64_t>(raw, spec.signals.size()), again);
    require(again.length == f.length && std::memcmp(again.data.data(), f.data.data(), f.length) == 0);
  }
  shared::ModeCommand m;
  (void)shared::decode(f, m);
  shared::MeasureTrigger t;
  (void)shared::decode(f, t);
  shared::ParameterAck a;
  if (shared::decode(f, a) == shared::DecodeStatus::kOk) {
    shared::CanFrame again;
    shared::encode(a, again);
    require(std::memcmp(again.data.data(), f.data.data(), f.length) == 0);
  }
  shared::ErrorReport e;
  (void)shared::decode(f, e);
  shared::Heartbeat h;
  if (shared::decode(f, h) == shared::DecodeStatus::kOk) {
    shared::CanFrame again;
    shared::encode(h, again);
    require(std::memcmp(again.data.data(), f.data.data(), f.length) == 0);
  }
  shared::JointHalf half;
  (void)shared::decode_joint_half(f.id, f, half);
  shared::JointFull full;
  if (shared::decode_joint_full(f.id, f, full) == shared::DecodeStatus::kOk) {
    shared::CanFrame again;
    shared::encode_joint_full(f.id, full, again);
    require(std::memcmp(again.data.data(), f.data.data(), f.length) == 0);
  }
}

void fuzz_report(const std::uint8_t* data, std::size_t size) {
  static shared::MeasurementReport r;
  if (shared::decode(std::span<const std::uint8_t>(data, size), r) != shared::DecodeStatus::kOk) return;
  static std::uint8_t out[shared::kMaxReportBytes];
  const std::size_t n = shared::encode(r, out);
  require(n == size && std::memcmp(out, data, size) == 0);
}

template <class Block>
void block_round_trip(std::span<const std::uint8_t> image) {
  static Block b;
  if (shared::decode_block(image, b) != shared::DecodeStatus::kOk) return;
  static std::uint8_t out[shared::kMaxBlockBytes];
  const std::size_t n = shared::encode_block(b, out);
  require(n == image.size() && std::memcmp(out, image.data(), n) == 0);
}

void fuzz_parameters(const std::uint8_t* data, std::size_t size) {
  const std::span<const std::uint8_t> message(data, size);
  shared::ParameterHeader h;
  std::span<const std::uint8_t> payload;
  if (shared::decode_parameter_message(message, h, payload) == shared::DecodeStatus::kOk) {
    (void)shared::check_parameter_payload(h, payload);
    require(payload.size() == h.length);
  }
  block_round_trip<shared::CameraIntrinsics>(message);
  block_round_trip<shared::ColourLut>(message);
  block_round_trip<shared::PlatformGeometry>(message);
  block_round_trip<shared::CorrectionParameters>(message);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  switch (data[0] % 5) {
    case 0:
      fuzz_isotp(data + 1, size - 1);
      break;
    case 1:
      fuzz_single_frame(data + 1, size - 1);
      break;
    case 2:
      fuzz_report(data + 1, size - 1);
      break;
    case 3:
      fuzz_parameters(data + 1, size - 1);
      break;
    default: {
      std::uint8_t block = 0;
      (void)shared::decode_parameter_read(std::span<const std::uint8_t>(data + 1, size - 1), block);
    }
  }
  return 0;
}
