#include "firmware/app/platform_app.hpp"

namespace kincal::app {

shared::ErrorReason reason_for(shared::DecodeStatus status) {
  switch (status) {
    case shared::DecodeStatus::kWrongLength:
      return shared::ErrorReason::kWrongLength;
    case shared::DecodeStatus::kWrongFormat:
      return shared::ErrorReason::kWrongFormat;
    case shared::DecodeStatus::kWrongId:
      return shared::ErrorReason::kUnknownId;
    case shared::DecodeStatus::kOk:
    case shared::DecodeStatus::kBadValue:
      break;
  }
  return shared::ErrorReason::kBadValue;
}

shared::ErrorReason reason_for(CorrectStatus status) {
  return status == CorrectStatus::kNotCorrectable ? shared::ErrorReason::kBadValue : shared::ErrorReason::kNoParameters;
}

std::uint8_t reason_for(core::IsoTpEvent event) {
  switch (event) {
    case core::IsoTpEvent::kBadFrame:
    case core::IsoTpEvent::kSequenceError:
    case core::IsoTpEvent::kRemoteOverflow:
    case core::IsoTpEvent::kWaitLimit:
      return static_cast<std::uint8_t>(shared::ErrorReason::kIsoTpProtocol);
    case core::IsoTpEvent::kRxOverflow:
      return static_cast<std::uint8_t>(shared::ErrorReason::kIsoTpOverflow);
    case core::IsoTpEvent::kRxTimeout:
    case core::IsoTpEvent::kTxTimeout:
      return static_cast<std::uint8_t>(shared::ErrorReason::kIsoTpTimeout);
    case core::IsoTpEvent::kNone:
    case core::IsoTpEvent::kRxComplete:
    case core::IsoTpEvent::kIgnored:
      break;
  }
  return 0;
}

core::IsoTpConfig isotp_config(const AppConfig& config) {
  core::IsoTpConfig c;
  c.tx_id = shared::can_id::kIsoTpResponse;
  c.rx_id = shared::can_id::kIsoTpRequest;
  c.fd = config.fd;
  c.brs = config.fd;
  c.tx_dl = config.fd ? 64 : 8;
  c.padding = config.isotp_padding;
  c.block_size = config.isotp_block_size;
  c.st_min_raw = config.isotp_st_min_raw;
  c.n_bs_timeout_us = config.isotp_timeout_us;
  c.n_cr_timeout_us = config.isotp_timeout_us;
  return c;
}

void RejectionTracker::reject(shared::ErrorReason reason, std::uint32_t id) {
  reason_ = reason;
  id_ = static_cast<std::uint16_t>(id & 0x7FFu);
  if (pending_ != 0xFF) ++pending_;
  total_ = static_cast<std::uint8_t>(total_ + 1u);
}

bool RejectionTracker::take_report(std::uint64_t now_us, std::uint32_t interval_us, shared::ErrorReport& out) {
  if (pending_ == 0) return false;
  if (sent_once_ && now_us - last_report_us_ < interval_us) return false;
  out.reason = reason_;
  out.offending_id = id_;
  out.count = pending_;
  pending_ = 0;
  sent_once_ = true;
  last_report_us_ = now_us;
  return true;
}

}  // namespace kincal::app
