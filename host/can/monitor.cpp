#include "host/can/monitor.hpp"

#include <cstdio>
#include <sstream>

#include "firmware/core/isotp.hpp"
#include "host/can/platform_client.hpp"
#include "shared/measurement_report.hpp"
#include "shared/parameters.hpp"
#include "shared/protocol.hpp"

namespace kincal::can {

namespace {

const char* decode_error(shared::DecodeStatus s) {
  switch (s) {
    case shared::DecodeStatus::kOk:
      return "ok";
    case shared::DecodeStatus::kWrongId:
      return "wrong ID";
    case shared::DecodeStatus::kWrongFormat:
      return "wrong format (classic/FD or extended ID)";
    case shared::DecodeStatus::kWrongLength:
      return "wrong length";
    case shared::DecodeStatus::kBadValue:
      return "reserved bits set or value out of range";
  }
  return "?";
}

std::string hex_id(std::uint32_t id) {
  char b[16];
  std::snprintf(b, sizeof b, "%03X", static_cast<unsigned>(id));
  return b;
}

}  // namespace

std::string describe_frame(const shared::CanFrame& frame) {
  std::ostringstream out;
  out << hex_id(frame.id) << " ";
  if (frame.id == shared::can_id::kIsoTpRequest || frame.id == shared::can_id::kIsoTpResponse) {
    out << (frame.id == shared::can_id::kIsoTpRequest ? "ISO-TP host->platform" : "ISO-TP platform->host");
    static const char* kTypes[] = {"single", "first", "consecutive", "flow control"};
    const unsigned type = frame.length > 0 ? frame.data[0] >> 4 : 15;
    out << " " << (type < 4 ? kTypes[type] : "malformed") << " frame, " << int(frame.length) << " bytes";
    return out.str();
  }
  const shared::MessageSpec* spec = frame.extended ? nullptr : shared::find_message(frame.id);
  if (spec == nullptr) {
    const bool ours =
        !frame.extended && frame.id >= shared::can_id::kBlockFirst && frame.id <= shared::can_id::kBlockLast;
    out << (ours ? "unknown ID in the kincal block" : "other node") << ", " << int(frame.length) << " bytes";
    return out.str();
  }
  std::int64_t raw[16] = {};
  const shared::DecodeStatus status = shared::decode_raw(*spec, frame, std::span<std::int64_t>(raw, 16));
  out << spec->name;
  if (status != shared::DecodeStatus::kOk) {
    out << " MALFORMED: " << decode_error(status) << " (" << int(frame.length) << " bytes, expected "
        << int(spec->length) << (spec->fd ? " CAN FD" : "") << ")";
    return out.str();
  }
  for (std::size_t i = 0; i < spec->signals.size(); ++i) {
    const shared::Signal& s = spec->signals[i];
    out << " " << s.name << "=";
    if (s.scale == 1.0 && s.offset == 0.0)
      out << raw[i];
    else
      out << static_cast<double>(raw[i]) * s.scale + s.offset;
    if (s.unit[0] != '\0') out << " " << s.unit;
  }
  return out.str();
}

std::string describe_message(std::span<const std::uint8_t> message, bool to_platform) {
  std::ostringstream out;
  out << (to_platform ? "message host->platform: " : "message platform->host: ");
  if (message.empty()) return out.str() + "empty";
  switch (static_cast<shared::MessageType>(message[0])) {
    case shared::MessageType::kMeasurementReport: {
      shared::MeasurementReport r;
      const shared::DecodeStatus s = shared::decode(message, r);
      if (s != shared::DecodeStatus::kOk) return out.str() + "MeasurementReport MALFORMED: " + decode_error(s);
      out << "MeasurementReport seq=" << int(r.sequence) << " t=" << r.timestamp_us
          << "us status=" << to_string(r.status) << " sections=0x" << std::hex << int(r.sections) << std::dec;
      if (r.sections & shared::section::kRanges) {
        out << " ranges_m=";
        for (const auto v : r.range_raw)
          out << (v == shared::kNoEcho ? std::string("none") : std::to_string(v * shared::kRangeLsbM)) << ",";
      }
      if (r.sections & shared::section::kFiducials) out << " fiducials=" << int(r.fiducial_count);
      if (r.sections & shared::section::kBlobs) out << " blobs=" << int(r.blob_count);
      if (r.sections & shared::section::kPose)
        out << " pose_squares=" << int(r.pose_squares) << " t_m=" << r.translation_raw[0] * shared::kTranslationLsbM
            << "," << r.translation_raw[1] * shared::kTranslationLsbM << ","
            << r.translation_raw[2] * shared::kTranslationLsbM;
      return out.str();
    }
    case shared::MessageType::kParameterWrite:
    case shared::MessageType::kParameterData: {
      shared::ParameterHeader h;
      std::span<const std::uint8_t> payload;
      const shared::DecodeStatus s = shared::decode_parameter_message(message, h, payload);
      if (s != shared::DecodeStatus::kOk) return out.str() + "parameter message MALFORMED: " + decode_error(s);
      out << (h.type == shared::MessageType::kParameterWrite ? "ParameterWrite" : "ParameterData")
          << " block=" << int(h.block) << " version=" << h.version << " length=" << h.length
          << " check=" << to_string(shared::check_parameter_payload(h, payload));
      return out.str();
    }
    case shared::MessageType::kParameterRead: {
      std::uint8_t block = 0;
      const shared::DecodeStatus s = shared::decode_parameter_read(message, block);
      if (s != shared::DecodeStatus::kOk) return out.str() + "ParameterRead MALFORMED: " + decode_error(s);
      out << "ParameterRead block=" << int(block);
      return out.str();
    }
  }
  out << "unknown message type 0x" << std::hex << int(message[0]) << ", " << std::dec << message.size() << " bytes";
  return out.str();
}

struct Monitor::Reassembly {
  static core::IsoTpConfig listen(std::uint32_t rx) {
    core::IsoTpConfig c;
    c.rx_id = rx;
    c.listen_only = true;
    return c;
  }
  core::IsoTpBuffers<8192, 8> to_platform_buffers, to_host_buffers;
  core::IsoTpEndpoint to_platform{listen(shared::can_id::kIsoTpRequest), to_platform_buffers};
  core::IsoTpEndpoint to_host{listen(shared::can_id::kIsoTpResponse), to_host_buffers};
};

Monitor::Monitor() : reassembly_(std::make_unique<Reassembly>()) {}
Monitor::~Monitor() = default;

std::vector<std::string> Monitor::feed(const shared::CanFrame& frame, std::uint64_t time_us) {
  std::vector<std::string> lines;
  ++frames_;
  char stamp[32];
  std::snprintf(stamp, sizeof stamp, "%llu.%06llu ", static_cast<unsigned long long>(time_us / 1000000),
                static_cast<unsigned long long>(time_us % 1000000));
  const std::string line = describe_frame(frame);
  if (line.find("MALFORMED") != std::string::npos) ++undecodable_;
  lines.push_back(stamp + line);
  for (auto* endpoint : {&reassembly_->to_platform, &reassembly_->to_host}) {
    // Flow control frames travel on the other direction's ID; the listener of that ID sees them
    // as its own data frames, which is harmless: an FC is not SF/FF/CF and is ignored.
    const core::IsoTpEvent e = endpoint->on_frame(frame, time_us);
    if (e == core::IsoTpEvent::kRxComplete) {
      ++messages_;
      const std::string m = describe_message(endpoint->message(), endpoint == &reassembly_->to_platform);
      if (m.find("MALFORMED") != std::string::npos) ++undecodable_;
      lines.push_back(stamp + m);
    } else if (e == core::IsoTpEvent::kBadFrame || e == core::IsoTpEvent::kSequenceError ||
               e == core::IsoTpEvent::kRxOverflow) {
      lines.push_back(std::string(stamp) + "ISO-TP transfer broken on " + hex_id(frame.id));
    }
    (void)endpoint->check_timeouts(time_us);
  }
  return lines;
}

}  // namespace kincal::can
