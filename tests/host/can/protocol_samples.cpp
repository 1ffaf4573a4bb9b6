// Prints frames encoded by our codecs for tests/host/can/dbc_check.py, which decodes them with
// an independent DBC implementation (python3-canmatrix) reading the generated DBC file:
//   HEX_ID HEX_DATA raw0 raw1 ...   (raw values in the order of the catalogue's signals)
#include <cstdint>
#include <cstdio>

#include "shared/bit_field.hpp"
#include "shared/protocol.hpp"

int main() {
  std::uint64_t state = 0x9E3779B97F4A7C15u;
  for (const kincal::shared::MessageSpec& m : kincal::shared::single_frame_messages()) {
    for (int sample = 0; sample < 50; ++sample) {
      std::int64_t raw[16] = {};
      for (std::size_t i = 0; i < m.signals.size(); ++i) {
        const auto& s = m.signals[i];
        state = state * 6364136223846793005u + 1442695040888963407u;
        const std::int64_t lo = kincal::shared::min_raw(s.bits, s.is_signed);
        const std::int64_t hi = kincal::shared::max_raw(s.bits, s.is_signed);
        // Extremes in the first two samples, pseudo-random values after.
        raw[i] = sample == 0 ? lo
                 : sample == 1
                     ? hi
                     : lo + static_cast<std::int64_t>((state >> 11) % static_cast<std::uint64_t>(hi - lo + 1));
      }
      kincal::shared::CanFrame f;
      kincal::shared::encode_raw(m, std::span<const std::int64_t>(raw, m.signals.size()), f);
      std::printf("%X ", static_cast<unsigned>(f.id));
      for (std::size_t b = 0; b < f.length; ++b) std::printf("%02X", f.data[b]);
      for (std::size_t i = 0; i < m.signals.size(); ++i) std::printf(" %lld", static_cast<long long>(raw[i]));
      std::printf("\n");
    }
  }
  return 0;
}
