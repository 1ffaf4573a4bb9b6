// The platform application end to end at frame level, natively and on the M4: a host-side
// ISO-TP endpoint and hand-made frames drive the app through its state machine, a measurement,
// a parameter upload (which survives a reboot), a parameter download, the correction stream
// (classic and CAN FD), and every defined response to bad input.
#include "firmware/app/platform_app.hpp"

#include <doctest.h>

#include <array>
#include <cstdint>

#include "firmware/app/kinematic_correction.hpp"
#include "firmware/app/platform_measurement.hpp"
#include "tests/firmware/app/fake_ports.hpp"
#include "tests/firmware/app/puma560.hpp"

using namespace kincal;
using shared::CanFrame;

namespace {

using Measure = app::PlatformMeasurement<test::FakeCamera, test::FakeRangers>;
using App = app::PlatformApp<test::FakeCan, test::FakeStorage, Measure, app::KinematicCorrection>;

struct Harness {
  test::FakeCan can;
  test::FakeStorage& storage;
  test::FakeCamera camera;  // no image: camera sections report kCameraFailure
  test::FakeRangers rangers;
  Measure measure{camera, rangers};
  app::KinematicCorrection correct;
  App app;
  core::IsoTpBuffers<4096, 4096> host_buffers;
  core::IsoTpEndpoint host;
  std::uint64_t now_us = 1000;
  // What the platform sent, ISO-TP frames excluded.
  std::array<CanFrame, 512> frames{};
  std::size_t frame_count = 0;
  std::array<std::uint8_t, 4096> message{};
  std::size_t message_length = 0;  // last complete ISO-TP message from the platform

  static core::IsoTpConfig host_config() {
    core::IsoTpConfig c;
    c.tx_id = shared::can_id::kIsoTpRequest;
    c.rx_id = shared::can_id::kIsoTpResponse;
    return c;
  }

  explicit Harness(test::FakeStorage& s, const app::AppConfig& config = {})
      : storage(s), app(config, can, storage, measure, correct), host(host_config(), host_buffers) {
    app.start(now_us);
  }

  void send(const CanFrame& f) { app.on_frame(f, now_us); }

  // Runs the bus for `steps` x 100 us.
  void run(int steps = 50) {
    for (int i = 0; i < steps; ++i) {
      now_us += 100;
      app.poll(now_us);
      for (std::size_t k = 0; k < can.count; ++k) {
        const CanFrame& f = can.sent[k];
        if (f.id == shared::can_id::kIsoTpResponse) {
          if (host.on_frame(f, now_us) == core::IsoTpEvent::kRxComplete) {
            message_length = host.message().size();
            for (std::size_t b = 0; b < message_length; ++b) message[b] = host.message()[b];
          }
        } else if (frame_count < frames.size()) {
          frames[frame_count++] = f;
        }
      }
      can.count = 0;
      CanFrame out;
      while (host.next_frame(now_us, out)) app.on_frame(out, now_us);
    }
  }

  void send_message(std::span<const std::uint8_t> bytes) {
    REQUIRE(host.start_send(bytes, now_us) == core::IsoTpSendStatus::kOk);
    CanFrame out;
    for (int i = 0; i < 2000 && host.tx_busy(); ++i) {
      while (host.next_frame(now_us, out)) app.on_frame(out, now_us);
      run(1);
    }
  }

  // The last frame with this ID since index `from`, or nullptr.
  const CanFrame* last(std::uint32_t id, std::size_t from = 0) const {
    const CanFrame* found = nullptr;
    for (std::size_t i = from; i < frame_count; ++i)
      if (frames[i].id == id) found = &frames[i];
    return found;
  }
  std::size_t count(std::uint32_t id, std::size_t from = 0) const {
    std::size_t n = 0;
    for (std::size_t i = from; i < frame_count; ++i) n += frames[i].id == id;
    return n;
  }
  shared::Heartbeat heartbeat() {
    run(1001);  // > 100 ms: at least one heartbeat
    const CanFrame* f = last(shared::can_id::kHeartbeat);
    shared::Heartbeat h;
    REQUIRE(f != nullptr);
    REQUIRE(shared::decode(*f, h) == shared::DecodeStatus::kOk);
    return h;
  }
  void mode(bool measure_on, bool correct_on, bool clear = false) {
    CanFrame f;
    shared::encode(shared::ModeCommand{measure_on, correct_on, clear}, f);
    send(f);
  }
};

CanFrame raw_frame(std::uint32_t id, std::initializer_list<std::uint8_t> bytes) {
  CanFrame f;
  f.id = id;
  f.length = static_cast<std::uint8_t>(bytes.size());
  std::size_t i = 0;
  for (const std::uint8_t b : bytes) f.data[i++] = b;
  return f;
}

// A PUMA 560 in Craig's modified DH with joint zero offsets of 1..6 mrad: the corrected target
// of a well-conditioned posture is then the target minus the offsets (to third order).
shared::CorrectionParameters correction_parameters() {
  shared::CorrectionParameters c = test::puma560_block();
  for (std::size_t j = 0; j < shared::kJoints; ++j) c.joints[j].error.theta_rad = 0.001f * static_cast<float>(j + 1);
  return c;
}

// Joint j corrected by -0.001 (j + 1) rad = -65.536 (j + 1) LSB, within one LSB (rounding).
void check_offsets_removed(const std::int32_t* in, const std::int32_t* out, std::size_t first_joint, std::size_t n) {
  for (std::size_t k = 0; k < n; ++k) {
    const auto expected = in[k] - static_cast<std::int32_t>(65.536 * static_cast<double>(first_joint + k + 1) + 0.5);
    CHECK(out[k] - expected <= 1);
    CHECK(expected - out[k] <= 1);
  }
}

void upload_correction(Harness& h, std::uint8_t expect_status = 0) {
  std::array<std::uint8_t, shared::kCorrectionBytes> image{};
  REQUIRE(shared::encode_block(correction_parameters(), image) == image.size());
  std::array<std::uint8_t, shared::kMaxParameterMessageBytes> msg{};
  const std::size_t n = shared::encode_parameter_message(shared::MessageType::kParameterWrite,
                                                         shared::ParameterBlock::kCorrection, image, msg);
  const std::size_t from = h.frame_count;
  h.send_message(std::span<const std::uint8_t>(msg).first(n));
  h.run(10);
  const CanFrame* f = h.last(shared::can_id::kParameterAck, from);
  REQUIRE(f != nullptr);
  shared::ParameterAck ack;
  REQUIRE(shared::decode(*f, ack) == shared::DecodeStatus::kOk);
  CHECK(ack.block == 4);
  CHECK(static_cast<int>(ack.status) == expect_status);
  CHECK_FALSE(ack.read);
}

}  // namespace

TEST_CASE("start: idle, every parameter block missing, heartbeat every 100 ms") {
  test::FakeStorage storage;
  Harness h(storage);
  CHECK(h.app.state() == shared::PlatformState::kIdle);
  h.run(2001);                                      // 200.1 ms
  CHECK(h.count(shared::can_id::kHeartbeat) == 3);  // at 0, 100 and 200 ms
  const shared::Heartbeat hb = h.heartbeat();
  CHECK(hb.state == shared::PlatformState::kIdle);
  CHECK(hb.error_flags == (shared::error_flag::kNoIntrinsics | shared::error_flag::kNoColourLut |
                           shared::error_flag::kNoGeometry | shared::error_flag::kNoCorrection));
  CHECK(hb.version_major == shared::kProtocolVersionMajor);
}

TEST_CASE("start: a stored block of format 3 is ignored, one of format 4 is loaded with its square pitch") {
  test::FakeStorage storage;
  app::ParameterStore<test::FakeStorage> store(storage);
  shared::PlatformGeometry g;
  g.fiducial_count = 6;
  g.square_pitch_m = 0.1016f;
  std::array<std::uint8_t, shared::kGeometryBytes> image{};
  REQUIRE(shared::encode_block(g, image) == image.size());
  std::uint32_t sequence = 0;
  // What a format 3 platform stored (193 bytes, no pitch); then a format 4 image under version
  // 3, which only the version tells apart.
  for (const std::size_t length : {std::size_t{193}, shared::kGeometryBytes}) {
    REQUIRE(store.save(shared::ParameterBlock::kGeometry, 3, std::span<const std::uint8_t>(image).first(length),
                       sequence) == app::StoreStatus::kOk);
    Harness h(storage);
    CHECK_FALSE(h.app.parameters().has_geometry);
    CHECK((h.heartbeat().error_flags & shared::error_flag::kNoGeometry) != 0);
  }
  REQUIRE(store.save(shared::ParameterBlock::kGeometry, shared::kBlockFormatVersion, image, sequence) ==
          app::StoreStatus::kOk);
  Harness h(storage);
  CHECK(h.app.parameters().has_geometry);
  CHECK(h.app.parameters().geometry.square_pitch_m == 0.1016f);
  CHECK((h.heartbeat().error_flags & shared::error_flag::kNoGeometry) == 0);
}

TEST_CASE("measurement: trigger -> ISO-TP report with the trigger's sequence and the ranges") {
  test::FakeStorage storage;
  Harness h(storage);
  h.rangers.time_us = 123456;
  h.mode(true, false);
  CHECK(h.app.state() == shared::PlatformState::kRunning);
  CanFrame t;
  shared::encode(shared::MeasureTrigger{42, shared::section::kRanges}, t);
  h.send(t);
  h.run(20);
  REQUIRE(h.message_length > 0);
  shared::MeasurementReport r;
  REQUIRE(shared::decode(std::span<const std::uint8_t>(h.message).first(h.message_length), r) ==
          shared::DecodeStatus::kOk);
  CHECK(r.sequence == 42);
  CHECK(r.timestamp_us == 123456);
  CHECK(r.status == shared::MeasureStatus::kOk);
  CHECK(r.sections == shared::section::kRanges);
  CHECK(r.range_raw[0] == 13107);  // 0.2 m * 65536 = 13107.2
  CHECK(r.range_raw[1] == 13763);  // 0.21 m -> 13762.56
  CHECK(r.range_raw[3] == shared::kNoEcho);
  // Sections this platform cannot produce are absent, with a status that says so.
  shared::encode(shared::MeasureTrigger{43, shared::section::kRanges | shared::section::kPoint}, t);
  h.send(t);
  h.run(20);
  REQUIRE(shared::decode(std::span<const std::uint8_t>(h.message).first(h.message_length), r) ==
          shared::DecodeStatus::kOk);
  CHECK(r.sequence == 43);
  CHECK(r.sections == shared::section::kRanges);
  CHECK(r.status == shared::MeasureStatus::kNotAvailable);
  // A failing ranger is reported and latched.
  h.rangers.fail = true;
  shared::encode(shared::MeasureTrigger{44, shared::section::kRanges}, t);
  h.send(t);
  h.run(20);
  REQUIRE(shared::decode(std::span<const std::uint8_t>(h.message).first(h.message_length), r) ==
          shared::DecodeStatus::kOk);
  CHECK(r.status == shared::MeasureStatus::kRangerFailure);
  CHECK((h.heartbeat().error_flags & shared::error_flag::kMeasurementFailed) != 0);
  CHECK(h.heartbeat().measurements == 3);
}

TEST_CASE("parameter upload: acked, applied, stored, loaded after a reboot, read back") {
  test::FakeStorage storage;
  {
    Harness h(storage);
    upload_correction(h);
    CHECK(h.app.parameters().has_correction);
    CHECK(h.app.parameters().correction.joints[2].error.theta_rad == 0.003f);
  }
  Harness h(storage);  // reboot on the same storage
  CHECK(h.app.parameters().has_correction);
  CHECK((h.heartbeat().error_flags & shared::error_flag::kNoCorrection) == 0);
  std::array<std::uint8_t, 2> read{};
  REQUIRE(shared::encode_parameter_read(shared::ParameterBlock::kCorrection, read) == 2);
  h.message_length = 0;
  h.send_message(read);
  h.run(50);
  shared::ParameterHeader header;
  std::span<const std::uint8_t> payload;
  REQUIRE(shared::decode_parameter_message(std::span<const std::uint8_t>(h.message).first(h.message_length), header,
                                           payload) == shared::DecodeStatus::kOk);
  CHECK(header.type == shared::MessageType::kParameterData);
  CHECK(shared::check_parameter_payload(header, payload) == shared::AckStatus::kOk);
  shared::CorrectionParameters back;
  REQUIRE(shared::decode_block(payload, back) == shared::DecodeStatus::kOk);
  CHECK(back.joints[5].error.theta_rad == 0.006f);
  // A block the platform does not have: ParameterAck kMissing.
  REQUIRE(shared::encode_parameter_read(shared::ParameterBlock::kColourLut, read) == 2);
  const std::size_t from = h.frame_count;
  h.send_message(read);
  h.run(10);
  const CanFrame* f = h.last(shared::can_id::kParameterAck, from);
  REQUIRE(f != nullptr);
  shared::ParameterAck ack;
  REQUIRE(shared::decode(*f, ack) == shared::DecodeStatus::kOk);
  CHECK(ack.status == shared::AckStatus::kMissing);
  CHECK(ack.read);
}

TEST_CASE("parameter upload refused: bad CRC, not idle, storage failure keeps the old copy") {
  test::FakeStorage storage;
  Harness h(storage);
  std::array<std::uint8_t, shared::kCorrectionBytes> image{};
  REQUIRE(shared::encode_block(correction_parameters(), image) == image.size());
  std::array<std::uint8_t, shared::kMaxParameterMessageBytes> msg{};
  const std::size_t n = shared::encode_parameter_message(shared::MessageType::kParameterWrite,
                                                         shared::ParameterBlock::kCorrection, image, msg);
  msg[n - 1] ^= 0xFF;
  std::size_t from = h.frame_count;
  h.send_message(std::span<const std::uint8_t>(msg).first(n));
  h.run(10);
  shared::ParameterAck ack;
  REQUIRE(h.last(shared::can_id::kParameterAck, from) != nullptr);
  REQUIRE(shared::decode(*h.last(shared::can_id::kParameterAck, from), ack) == shared::DecodeStatus::kOk);
  CHECK(ack.status == shared::AckStatus::kCrcMismatch);
  CHECK_FALSE(h.app.parameters().has_correction);

  h.mode(true, false);
  upload_correction(h, static_cast<std::uint8_t>(shared::AckStatus::kNotIdle));
  h.mode(false, false);
  upload_correction(h);
  storage.budget = 100;  // the power fails in the middle of the next save
  upload_correction(h, static_cast<std::uint8_t>(shared::AckStatus::kStorageFailure));
  storage.power_on();
  CHECK((h.heartbeat().error_flags & shared::error_flag::kStorageFailure) != 0);
  Harness rebooted(storage);
  CHECK(rebooted.app.parameters().has_correction);
}

TEST_CASE("correction stream: classic A+B pairs and CAN FD frames, same sequence, offsets applied") {
  test::FakeStorage storage;
  Harness h(storage);
  upload_correction(h);
  h.mode(false, true);
  shared::JointHalf a, b;
  a.sequence = b.sequence = 7;
  a.angle_raw = {65536, -32768, -20000};  // a posture away from the PUMA's singularities
  b.angle_raw = {20000, 50000, 30000};
  CanFrame fa, fb;
  shared::encode_joint_half(shared::can_id::kJointStateA, a, fa);
  shared::encode_joint_half(shared::can_id::kJointStateB, b, fb);
  const std::size_t from = h.frame_count;
  h.send(fa);
  h.send(fb);
  h.run(1);
  const CanFrame* ca = h.last(shared::can_id::kCorrectedA, from);
  const CanFrame* cb = h.last(shared::can_id::kCorrectedB, from);
  REQUIRE(ca != nullptr);
  REQUIRE(cb != nullptr);
  shared::JointHalf oa, ob;
  REQUIRE(shared::decode_joint_half(shared::can_id::kCorrectedA, *ca, oa) == shared::DecodeStatus::kOk);
  REQUIRE(shared::decode_joint_half(shared::can_id::kCorrectedB, *cb, ob) == shared::DecodeStatus::kOk);
  CHECK(oa.sequence == 7);
  CHECK(ob.sequence == 7);
  check_offsets_removed(a.angle_raw.data(), oa.angle_raw.data(), 0, 3);
  check_offsets_removed(b.angle_raw.data(), ob.angle_raw.data(), 3, 3);

  shared::JointFull full;
  full.sequence = 99;
  full.angle_raw = {10000, -30000, -30000, 20000, 60000, 300000};
  CanFrame ff;
  shared::encode_joint_full(shared::can_id::kJointStateFd, full, ff);
  h.send(ff);
  h.run(1);
  const CanFrame* cf = h.last(shared::can_id::kCorrectedFd, from);
  REQUIRE(cf != nullptr);
  CHECK(cf->fd);
  shared::JointFull out;
  REQUIRE(shared::decode_joint_full(shared::can_id::kCorrectedFd, *cf, out) == shared::DecodeStatus::kOk);
  CHECK(out.sequence == 99);
  check_offsets_removed(full.angle_raw.data(), out.angle_raw.data(), 0, 6);
  CHECK(h.heartbeat().corrections == 2);
}

TEST_CASE("defined responses to bad input, rate-limited, and the platform keeps working") {
  test::FakeStorage storage;
  Harness h(storage);
  std::size_t from = h.frame_count;
  auto expect_report = [&h, &from](shared::ErrorReason reason, std::uint32_t id) {
    h.run(101);  // past the 10 ms report interval
    const CanFrame* f = h.last(shared::can_id::kErrorReport, from);
    REQUIRE(f != nullptr);
    shared::ErrorReport e;
    REQUIRE(shared::decode(*f, e) == shared::DecodeStatus::kOk);
    CHECK(e.reason == reason);
    CHECK(e.offending_id == id);
    from = h.frame_count;
  };
  h.send(raw_frame(0x17E, {1, 2, 3}));
  expect_report(shared::ErrorReason::kUnknownId, 0x17E);
  h.send(raw_frame(shared::can_id::kModeCommand, {0x01, 0x00}));
  expect_report(shared::ErrorReason::kWrongLength, shared::can_id::kModeCommand);
  h.send(raw_frame(shared::can_id::kModeCommand, {0x80}));
  expect_report(shared::ErrorReason::kBadValue, shared::can_id::kModeCommand);
  h.send(raw_frame(shared::can_id::kMeasureTrigger, {1, 1}));
  expect_report(shared::ErrorReason::kNotInMode, shared::can_id::kMeasureTrigger);
  h.mode(false, true);
  h.send(raw_frame(shared::can_id::kJointStateB, {0, 0, 0, 0, 0, 0, 0, 0x10}));
  expect_report(shared::ErrorReason::kNoParameters, shared::can_id::kJointStateB);
  h.mode(false, false);
  upload_correction(h);
  h.mode(false, true);
  from = h.frame_count;
  h.send(raw_frame(shared::can_id::kJointStateA, {0, 0, 0, 0, 0, 0, 0, 0x10}));
  h.send(raw_frame(shared::can_id::kJointStateB, {0, 0, 0, 0, 0, 0, 0, 0x20}));  // sequence 2 after A's 1
  expect_report(shared::ErrorReason::kSequence, shared::can_id::kJointStateB);
  CHECK(h.count(shared::can_id::kCorrectedA, 0) == 0);
  // ISO-TP: a consecutive frame out of sequence.
  h.send(raw_frame(shared::can_id::kIsoTpRequest, {0x10, 0x20, 1, 2, 3, 4, 5, 6}));
  h.send(raw_frame(shared::can_id::kIsoTpRequest, {0x23, 1, 2, 3, 4, 5, 6, 7}));
  expect_report(shared::ErrorReason::kIsoTpProtocol, shared::can_id::kIsoTpRequest);
  // An unknown ISO-TP message type.
  h.send(raw_frame(shared::can_id::kIsoTpRequest, {0x02, 0x7E, 0x00}));
  expect_report(shared::ErrorReason::kUnknownMessage, shared::can_id::kIsoTpRequest);
  // An ISO-TP transfer that stops: N_Cr timeout after 1 s.
  h.send(raw_frame(shared::can_id::kIsoTpRequest, {0x10, 0x20, 1, 2, 3, 4, 5, 6}));
  h.run(10001);
  expect_report(shared::ErrorReason::kIsoTpTimeout, shared::can_id::kIsoTpRequest);
  // Frames outside the protocol block are other nodes' traffic: no response at all.
  h.send(raw_frame(0x7FF, {1}));
  h.send(raw_frame(0x0FF, {}));
  h.run(200);
  CHECK(h.last(shared::can_id::kErrorReport, from) == nullptr);

  // A flood of 10,000 malformed frames in 1 s: at most one report per 10 ms, counts aggregated.
  from = h.frame_count;
  for (int i = 0; i < 10000; ++i) {
    h.send(raw_frame(shared::can_id::kJointStateA, {1, 2, 3}));
    if (i % 10 == 9) h.run(10);
  }
  const std::size_t reports = h.count(shared::can_id::kErrorReport, from);
  CHECK(reports >= 95);
  CHECK(reports <= 101);
  const CanFrame* f = h.last(shared::can_id::kErrorReport, from);
  REQUIRE(f != nullptr);
  shared::ErrorReport e;
  REQUIRE(shared::decode(*f, e) == shared::DecodeStatus::kOk);
  CHECK(e.count >= 99);
  // Still correcting afterwards.
  from = h.frame_count;
  h.send(raw_frame(shared::can_id::kJointStateA, {0, 0, 0, 0, 0, 0, 0, 0x30}));
  h.send(raw_frame(shared::can_id::kJointStateB, {0, 0, 0, 0, 0, 0, 0, 0x30}));
  h.run(1);
  CHECK(h.count(shared::can_id::kCorrectedA, from) == 1);
  const shared::Heartbeat hb = h.heartbeat();
  CHECK((hb.error_flags & shared::error_flag::kMalformedFrame) != 0);
  h.mode(false, true, true);
  CHECK((h.heartbeat().error_flags & shared::error_flag::kMalformedFrame) == 0);
}

TEST_CASE("triggers: one report may wait for the bus; a trigger beyond that is answered with kBusy") {
  test::FakeStorage storage;
  Harness h(storage);
  h.mode(true, false);
  h.can.capacity = 0;  // the controller takes nothing: reports cannot leave
  CanFrame t;
  for (std::uint8_t seq = 1; seq <= 3; ++seq) {
    shared::encode(shared::MeasureTrigger{seq, shared::section::kRanges}, t);
    h.send(t);
    h.app.poll(h.now_us += 100);
  }
  h.can.capacity = 256;
  h.run(200);
  const CanFrame* f = h.last(shared::can_id::kErrorReport);
  REQUIRE(f != nullptr);
  shared::ErrorReport e;
  REQUIRE(shared::decode(*f, e) == shared::DecodeStatus::kOk);
  CHECK(e.reason == shared::ErrorReason::kBusy);
  CHECK(e.count == 1);
  shared::MeasurementReport r;
  REQUIRE(shared::decode(std::span<const std::uint8_t>(h.message).first(h.message_length), r) ==
          shared::DecodeStatus::kOk);
  CHECK(r.sequence == 2);  // 1 and 2 were delivered, 3 was refused
  CHECK(h.heartbeat().measurements == 2);
}
