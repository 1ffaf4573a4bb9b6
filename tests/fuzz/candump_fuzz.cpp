// libFuzzer target for the candump -L log reader (issue #25): can::CandumpReader, what `kincal
// monitor --replay` runs on a log from can-utils' candump. The input is the log's text, written
// to a temporary file. Either CanError with a short message naming the file, or frames each of
// which format_candump_line writes as a line that parse_candump_line reads back to the same
// frame (time, interface, identifier, flags, data). Any other exception, a crash, a leak or
// undefined behaviour is a finding. Runs standalone too (file arguments), and as the ctest
// fuzz.candump for a bounded time; seeds in candump_seeds/ (logs as candump -L writes them:
// classic, extended, CAN FD and remote frames, CRLF).
#include <unistd.h>

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <optional>
#include <string>

#include "host/can/candump_log.hpp"

using namespace kincal;

namespace {

void require(bool condition) {
  if (!condition) std::abort();
}

bool same(const can::LoggedFrame& a, const can::LoggedFrame& b) {
  return a.time_us == b.time_us && a.interface == b.interface && a.remote == b.remote && a.frame.id == b.frame.id &&
         a.frame.extended == b.frame.extended && a.frame.fd == b.frame.fd && a.frame.brs == b.frame.brs &&
         a.frame.length == b.frame.length && a.frame.data == b.frame.data;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string path = "/tmp/kincal_candump_fuzz_" + std::to_string(::getpid()) + ".log";
  std::ofstream(path, std::ios::binary | std::ios::trunc)
      .write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  try {
    can::CandumpReader reader(path);
    for (std::optional<can::LoggedFrame> f = reader.next(); f; f = reader.next())
      require(same(can::parse_candump_line(can::format_candump_line(*f)), *f));
  } catch (const can::CanError& e) {
    const std::string message = e.what();
    require(message.size() < 4096 && message.rfind(path, 0) == 0);
  }
  std::remove(path.c_str());
  return 0;
}
