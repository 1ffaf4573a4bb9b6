// libFuzzer target for the session journal's reader (issue #25): session::Journal::resume, what
// `kincal session --resume` runs on a journal left by a crash. The first input byte chooses the
// layout the caller expects (orientation, covariance) and whether the fuzzer signs each line
// with its CRC (so that mutations reach the parser behind the CRC check, not only the check);
// the rest is the journal's text, written to a temporary file. Either JournalError with a short
// message naming the file, or a journal whose records fit the layout (joint count, finite
// numbers, unique pose indices) and which a second resume reads back to the same records (the
// first one cut off any torn last line). Any other exception, a crash, a leak or undefined
// behaviour is a finding. Runs standalone too (file arguments), and as the ctest fuzz.journal
// for a bounded time; seeds in journal_seeds/ (a journal kincal wrote, and a torn one).
#include <unistd.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include "host/session/journal.hpp"
#include "shared/crc32.hpp"

using namespace kincal;

namespace {

void require(bool condition) {
  if (!condition) std::abort();
}

// Each line of `text` followed by " crc=XXXXXXXX", as Journal writes it.
std::string signed_lines(const std::string& text) {
  std::string out;
  for (std::size_t start = 0; start < text.size();) {
    const std::size_t end = std::min(text.find('\n', start), text.size());
    const std::string line = text.substr(start, end - start);
    char crc[16];
    std::snprintf(crc, sizeof crc, "%08x", static_cast<unsigned>(shared::crc32_text(line)));
    out += line + " crc=" + crc + (end < text.size() ? "\n" : "");
    start = end + 1;
  }
  return out;
}

bool same(const std::vector<session::JournalRecord>& a, const std::vector<session::JournalRecord>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].pose_index != b[i].pose_index || a[i].q != b[i].q || a[i].position_m != b[i].position_m) return false;
  return true;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return 0;
  session::JournalIdentity identity;
  identity.joint_count = 3;
  identity.orientation = (data[0] & 1) != 0;
  identity.covariance = (data[0] & 2) != 0;
  identity.items = {{"seed", "7"}};
  std::string text(reinterpret_cast<const char*>(data) + 1, size - 1);
  if (data[0] & 4) text = signed_lines(text);
  const std::string path = "/tmp/kincal_journal_fuzz_" + std::to_string(::getpid()) + ".journal";
  std::ofstream(path, std::ios::binary | std::ios::trunc) << text;
  try {
    std::vector<session::JournalRecord> records;
    {
      const session::Journal journal = session::Journal::resume(path, identity);
      records = journal.records();
    }
    std::set<int> poses;
    for (const session::JournalRecord& r : records) {
      require(r.q.size() == 3 && r.pose_index >= 0 && poses.insert(r.pose_index).second);
      require(r.position_m.allFinite());
      require(r.orientation.has_value() == identity.orientation);
      require(r.covariance_m2.has_value() == identity.covariance);
    }
    const session::Journal again = session::Journal::resume(path, identity);
    require(same(again.records(), records));
  } catch (const session::JournalError& e) {
    const std::string message = e.what();
    require(message.size() < 4096 && message.rfind(path, 0) == 0);
  }
  std::remove(path.c_str());
  return 0;
}
