#include "host/can/platform_client.hpp"

namespace kincal::can {

const char* to_string(shared::DecodeStatus status) {
  switch (status) {
    case shared::DecodeStatus::kOk:
      return "ok";
    case shared::DecodeStatus::kWrongId:
      return "not a measurement report";
    case shared::DecodeStatus::kWrongFormat:
      return "wrong frame format";
    case shared::DecodeStatus::kWrongLength:
      return "wrong length for its sections";
    case shared::DecodeStatus::kBadValue:
      return "a value out of range or non-zero padding";
  }
  return "?";
}

std::string protocol_version_mismatch(const shared::Heartbeat& h) {
  if (h.version_major == shared::kProtocolVersionMajor) return {};
  return "the platform speaks protocol " + std::to_string(h.version_major) + "." + std::to_string(h.version_minor) +
         ", this host speaks " + std::to_string(shared::kProtocolVersionMajor) + "." +
         std::to_string(shared::kProtocolVersionMinor) +
         ": their messages differ (update the platform's firmware or use a matching kincal)";
}

const char* to_string(shared::ErrorReason reason) {
  switch (reason) {
    case shared::ErrorReason::kUnknownId:
      return "unknown ID";
    case shared::ErrorReason::kWrongLength:
      return "wrong length";
    case shared::ErrorReason::kWrongFormat:
      return "wrong frame format";
    case shared::ErrorReason::kBadValue:
      return "bad value";
    case shared::ErrorReason::kSequence:
      return "sequence";
    case shared::ErrorReason::kNotInMode:
      return "not in mode";
    case shared::ErrorReason::kNoParameters:
      return "no parameters";
    case shared::ErrorReason::kBusy:
      return "busy";
    case shared::ErrorReason::kIsoTpProtocol:
      return "ISO-TP protocol";
    case shared::ErrorReason::kIsoTpTimeout:
      return "ISO-TP timeout";
    case shared::ErrorReason::kIsoTpOverflow:
      return "ISO-TP overflow";
    case shared::ErrorReason::kUnknownMessage:
      return "unknown message";
  }
  return "?";
}

const char* to_string(shared::AckStatus status) {
  switch (status) {
    case shared::AckStatus::kOk:
      return "ok";
    case shared::AckStatus::kCrcMismatch:
      return "CRC mismatch";
    case shared::AckStatus::kBadLength:
      return "bad length";
    case shared::AckStatus::kBadVersion:
      // Every block carries shared::kBlockFormatVersion; format 4 added the geometry block's
      // square pitch (format 3 the correction block's joint map), so firmware from before it
      // refuses this kincal's blocks (and the reverse).
      return "bad version: the platform's firmware reads another parameter block format than this kincal writes; "
             "update the firmware or kincal so that both agree";
    case shared::AckStatus::kBadValue:
      return "bad value";
    case shared::AckStatus::kStorageFailure:
      return "storage failure";
    case shared::AckStatus::kBusy:
      return "busy";
    case shared::AckStatus::kNotIdle:
      // The ack alone says why: the platform takes parameters only in the idle state.
      return "not idle (the platform is measuring or correcting: it takes parameters only when idle; stop the "
             "session or the correction stream first)";
    case shared::AckStatus::kUnknownBlock:
      return "unknown block";
    case shared::AckStatus::kMissing:
      return "missing";
  }
  return "?";
}

const char* to_string(shared::PlatformState state) {
  switch (state) {
    case shared::PlatformState::kStartup:
      return "startup";
    case shared::PlatformState::kIdle:
      return "idle";
    case shared::PlatformState::kRunning:
      return "running";
    case shared::PlatformState::kFault:
      return "fault";
  }
  return "?";
}

const char* to_string(shared::MeasureStatus status) {
  switch (status) {
    case shared::MeasureStatus::kOk:
      return "ok";
    case shared::MeasureStatus::kNotAvailable:
      return "not available";
    case shared::MeasureStatus::kNoParameters:
      return "no parameters";
    case shared::MeasureStatus::kCameraFailure:
      return "camera failure";
    case shared::MeasureStatus::kRangerFailure:
      return "ranger failure";
    case shared::MeasureStatus::kNoTarget:
      return "no target";
  }
  return "?";
}

template <class Accept>
bool PlatformClient::wait_for(Milliseconds timeout, Accept accept) {
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  for (;;) {
    const auto left = std::chrono::duration_cast<Milliseconds>(deadline - std::chrono::steady_clock::now());
    if (left.count() <= 0) return false;
    Received r;
    if (!transport_.receive(r, left)) return false;
    if (r.kind == Received::Kind::kFrame) {
      shared::Heartbeat h;
      if (r.frame.id == shared::can_id::kHeartbeat && shared::decode(r.frame, h) == shared::DecodeStatus::kOk) {
        heartbeat_ = h;
        if (const std::string mismatch = protocol_version_mismatch(h); !mismatch.empty())
          throw PlatformError(mismatch + " (heartbeat on " + transport_.name() + ")");
      }
      shared::ErrorReport e;
      if (r.frame.id == shared::can_id::kErrorReport && shared::decode(r.frame, e) == shared::DecodeStatus::kOk)
        errors_.push_back(e);
    }
    if (accept(r)) return true;
  }
}

void PlatformClient::fail_with_last_error(const std::string& what, std::uint32_t id) {
  for (auto it = errors_.rbegin(); it != errors_.rend(); ++it)
    if (it->offending_id == id)
      throw PlatformError(what + ": the platform rejected it (" + to_string(it->reason) + ")");
  throw PlatformError(what + ": no answer from the platform on " + transport_.name());
}

shared::Heartbeat PlatformClient::wait_heartbeat(Milliseconds timeout) {
  std::optional<shared::Heartbeat> got;
  wait_for(timeout, [&got](const Received& r) {
    shared::Heartbeat h;
    if (r.kind == Received::Kind::kFrame && r.frame.id == shared::can_id::kHeartbeat &&
        shared::decode(r.frame, h) == shared::DecodeStatus::kOk) {
      got = h;
      return true;
    }
    return false;
  });
  if (!got) throw PlatformError("no heartbeat from the platform on " + transport_.name());
  return *got;
}

void PlatformClient::set_mode(bool measure, bool correct, bool clear_errors) {
  CanFrame f;
  shared::encode(shared::ModeCommand{measure, correct, clear_errors}, f);
  transport_.send_frame(f);
}

shared::MeasurementReport PlatformClient::measure(std::uint8_t sections, Milliseconds timeout) {
  const std::uint8_t sequence = ++trigger_sequence_;
  CanFrame f;
  shared::encode(shared::MeasureTrigger{sequence, sections}, f);
  const std::size_t errors_before = errors_.size();
  transport_.send_frame(f);
  shared::MeasurementReport report;
  bool rejected = false;
  const bool ok = wait_for(timeout, [&](const Received& r) {
    if (errors_.size() > errors_before && errors_.back().offending_id == shared::can_id::kMeasureTrigger) {
      rejected = true;
      return true;
    }
    if (r.kind != Received::Kind::kMessage || r.message.size() < 2 ||
        r.message[0] != static_cast<std::uint8_t>(shared::MessageType::kMeasurementReport) || r.message[1] != sequence)
      return false;
    const shared::DecodeStatus status = shared::decode(r.message, report);
    if (status != shared::DecodeStatus::kOk)
      throw PlatformError("measurement " + std::to_string(sequence) + ": the report of " +
                          std::to_string(r.message.size()) + " bytes does not decode (" + to_string(status) +
                          "; protocol " + std::to_string(shared::kProtocolVersionMajor) + "." +
                          std::to_string(shared::kProtocolVersionMinor) + " expected)");
    return true;
  });
  if (!ok || rejected) fail_with_last_error("measurement " + std::to_string(sequence), shared::can_id::kMeasureTrigger);
  return report;
}

std::uint32_t PlatformClient::upload(shared::ParameterBlock block, std::span<const std::uint8_t> image,
                                     Milliseconds timeout) {
  std::vector<std::uint8_t> message(shared::kParameterHeaderBytes + image.size());
  if (shared::encode_parameter_message(shared::MessageType::kParameterWrite, block, image, message) == 0)
    throw PlatformError("parameter block of " + std::to_string(image.size()) + " bytes is too large");
  transport_.send_message(message);
  shared::ParameterAck ack;
  const bool ok = wait_for(timeout, [&](const Received& r) {
    return r.kind == Received::Kind::kFrame && r.frame.id == shared::can_id::kParameterAck &&
           shared::decode(r.frame, ack) == shared::DecodeStatus::kOk && !ack.read &&
           ack.block == static_cast<std::uint8_t>(block);
  });
  if (!ok) fail_with_last_error("parameter upload", shared::can_id::kIsoTpRequest);
  if (ack.status != shared::AckStatus::kOk)
    throw PlatformError(std::string("parameter upload refused: ") + to_string(ack.status));
  return ack.slot_sequence;
}

std::vector<std::uint8_t> PlatformClient::download(shared::ParameterBlock block, Milliseconds timeout) {
  std::array<std::uint8_t, 2> request{};
  if (shared::encode_parameter_read(block, request) != request.size()) throw PlatformError("bad parameter block");
  transport_.send_message(request);
  std::vector<std::uint8_t> payload;
  std::optional<shared::AckStatus> refused;
  const bool ok = wait_for(timeout, [&](const Received& r) {
    shared::ParameterAck ack;
    if (r.kind == Received::Kind::kFrame && r.frame.id == shared::can_id::kParameterAck &&
        shared::decode(r.frame, ack) == shared::DecodeStatus::kOk && ack.read &&
        ack.block == static_cast<std::uint8_t>(block)) {
      refused = ack.status;
      return true;
    }
    shared::ParameterHeader header;
    std::span<const std::uint8_t> body;
    if (r.kind != Received::Kind::kMessage ||
        shared::decode_parameter_message(r.message, header, body) != shared::DecodeStatus::kOk ||
        header.type != shared::MessageType::kParameterData || header.block != static_cast<std::uint8_t>(block))
      return false;
    const shared::AckStatus check = shared::check_parameter_payload(header, body);
    if (check != shared::AckStatus::kOk) throw PlatformError(std::string("parameter download: ") + to_string(check));
    payload.assign(body.begin(), body.end());
    return true;
  });
  if (refused) throw PlatformError(std::string("parameter download refused: ") + to_string(*refused));
  if (!ok) fail_with_last_error("parameter download", shared::can_id::kIsoTpRequest);
  return payload;
}

std::array<std::int32_t, shared::kJoints> PlatformClient::correct(
    const std::array<std::int32_t, shared::kJoints>& joints_raw, bool fd, Milliseconds timeout) {
  std::array<std::int32_t, shared::kJoints> out{};
  const std::size_t errors_before = errors_.size();
  if (fd) {
    const std::uint8_t sequence = joint_sequence_++;
    shared::JointFull in;
    in.sequence = sequence;
    in.angle_raw = joints_raw;
    CanFrame f;
    shared::encode_joint_full(shared::can_id::kJointStateFd, in, f);
    transport_.send_frame(f);
    bool rejected = false;
    const bool ok = wait_for(timeout, [&](const Received& r) {
      if (errors_.size() > errors_before) return rejected = true;
      shared::JointFull c;
      if (r.kind == Received::Kind::kFrame &&
          shared::decode_joint_full(shared::can_id::kCorrectedFd, r.frame, c) == shared::DecodeStatus::kOk &&
          c.sequence == sequence) {
        out = c.angle_raw;
        return true;
      }
      return false;
    });
    if (!ok || rejected) fail_with_last_error("correction (CAN FD)", shared::can_id::kJointStateFd);
    return out;
  }
  const std::uint8_t sequence = joint_sequence_++ & 0xF;
  shared::JointHalf a, b;
  a.sequence = b.sequence = sequence;
  for (std::size_t j = 0; j < shared::kJointsPerClassicFrame; ++j) {
    a.angle_raw[j] = joints_raw[j];
    b.angle_raw[j] = joints_raw[j + shared::kJointsPerClassicFrame];
  }
  CanFrame fa, fb;
  shared::encode_joint_half(shared::can_id::kJointStateA, a, fa);
  shared::encode_joint_half(shared::can_id::kJointStateB, b, fb);
  transport_.send_frame(fa);
  transport_.send_frame(fb);
  bool got_a = false, got_b = false, rejected = false;
  const bool ok = wait_for(timeout, [&](const Received& r) {
    if (errors_.size() > errors_before) return rejected = true;
    if (r.kind != Received::Kind::kFrame) return false;
    shared::JointHalf c;
    if (shared::decode_joint_half(shared::can_id::kCorrectedA, r.frame, c) == shared::DecodeStatus::kOk &&
        c.sequence == sequence) {
      for (std::size_t j = 0; j < shared::kJointsPerClassicFrame; ++j) out[j] = c.angle_raw[j];
      got_a = true;
    }
    if (shared::decode_joint_half(shared::can_id::kCorrectedB, r.frame, c) == shared::DecodeStatus::kOk &&
        c.sequence == sequence) {
      for (std::size_t j = 0; j < shared::kJointsPerClassicFrame; ++j)
        out[j + shared::kJointsPerClassicFrame] = c.angle_raw[j];
      got_b = true;
    }
    return got_a && got_b;
  });
  if (!ok || rejected) fail_with_last_error("correction", shared::can_id::kJointStateB);
  return out;
}

}  // namespace kincal::can
