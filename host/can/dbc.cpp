#include "host/can/dbc.hpp"

#include <cstdio>
#include <string>

#include "shared/bit_field.hpp"
#include "shared/protocol.hpp"

namespace kincal::can {

namespace {

std::string number(double v) {
  char b[40];
  std::snprintf(b, sizeof b, "%.17g", v);
  return b;
}

std::string quoted(const char* text) {
  std::string s = "\"";
  for (const char* p = text; *p; ++p) s += *p == '"' ? '\'' : *p;
  return s + "\"";
}

}  // namespace

void write_dbc(std::ostream& out) {
  out << "VERSION \"kincal protocol " << int(shared::kProtocolVersionMajor) << "." << int(shared::kProtocolVersionMinor)
      << "\"\n\n";
  out << "NS_ :\n\tCM_\n\tBA_DEF_\n\tBA_\n\tBA_DEF_DEF_\n\nBS_:\n\nBU_: Host Platform\n\n";
  for (const shared::MessageSpec& m : shared::single_frame_messages()) {
    const bool from_host = m.direction == shared::Direction::kHostToPlatform;
    out << "BO_ " << m.id << " " << m.name << ": " << int(m.length) << " " << (from_host ? "Host" : "Platform") << "\n";
    for (const shared::Signal& s : m.signals) {
      const double lo = static_cast<double>(shared::min_raw(s.bits, s.is_signed)) * s.scale + s.offset;
      const double hi = static_cast<double>(shared::max_raw(s.bits, s.is_signed)) * s.scale + s.offset;
      out << " SG_ " << s.name << " : " << s.start_bit << "|" << int(s.bits) << "@1" << (s.is_signed ? "-" : "+")
          << " (" << number(s.scale) << "," << number(s.offset) << ") [" << number(lo) << "|" << number(hi) << "] "
          << quoted(s.unit) << " " << (from_host ? "Platform" : "Host") << "\n";
    }
    out << "\n";
  }
  for (const shared::MessageSpec& m : shared::single_frame_messages()) {
    out << "CM_ BO_ " << m.id << " " << quoted(m.comment) << ";\n";
    for (const shared::Signal& s : m.signals)
      if (s.comment[0] != '\0') out << "CM_ SG_ " << m.id << " " << s.name << " " << quoted(s.comment) << ";\n";
  }
  out << "BA_DEF_ BO_ \"VFrameFormat\" ENUM \"StandardCAN\",\"ExtendedCAN\",\"reserved\",\"J1939PG\",\"reserved\","
         "\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\",\"reserved\","
         "\"reserved\",\"StandardCAN_FD\",\"ExtendedCAN_FD\";\n";
  out << "BA_DEF_ BO_ \"GenMsgCycleTime\" INT 0 10000;\n";
  out << "BA_DEF_DEF_ \"VFrameFormat\" \"StandardCAN\";\n";
  out << "BA_DEF_DEF_ \"GenMsgCycleTime\" 0;\n";
  for (const shared::MessageSpec& m : shared::single_frame_messages())
    if (m.fd) out << "BA_ \"VFrameFormat\" BO_ " << m.id << " 14;\n";
  out << "BA_ \"GenMsgCycleTime\" BO_ " << shared::can_id::kHeartbeat << " " << shared::kHeartbeatPeriodMs << ";\n";
}

}  // namespace kincal::can
