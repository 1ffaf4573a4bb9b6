#include "host/capture/stereo_source.hpp"

#include <cmath>
#include <stdexcept>
#include <utility>

namespace kincal::capture {

StereoSource::StereoSource(std::unique_ptr<FrameSource> left, std::unique_ptr<FrameSource> right, double tolerance_s)
    : tolerance_s_(tolerance_s) {
  if (!left || !right) throw std::invalid_argument("StereoSource: a source is null");
  if (!(tolerance_s >= 0) || !std::isfinite(tolerance_s)) {
    throw std::invalid_argument("StereoSource: tolerance_s must be finite and >= 0, not " +
                                std::to_string(tolerance_s));
  }
  left_.source = std::move(left);
  right_.source = std::move(right);
}

void StereoSource::fill(Stream& s, std::size_t n) {
  while (s.ahead.size() < n && !s.ended) {
    std::optional<Frame> f = s.source->next();
    if (!f) {
      s.ended = true;
      break;
    }
    if (s.started && f->timestamp_s < s.last_s) {
      throw CaptureError(s.source->name() + ": time goes backwards at " + f->origin + " (" +
                         std::to_string(f->timestamp_s) + " s after " + std::to_string(s.last_s) + " s)");
    }
    s.started = true;
    s.last_s = f->timestamp_s;
    s.ahead.push_back(std::move(*f));
  }
}

void StereoSource::skip(Stream& s, Side side) {
  const Frame& f = s.ahead.front();
  unpaired_.push_back({side, f.index, f.timestamp_s, f.origin});
  s.ahead.pop_front();
}

void StereoSource::drain(Stream& s, Side side) {
  for (fill(s, 1); !s.ahead.empty(); fill(s, 1)) skip(s, side);
}

std::optional<StereoFrame> StereoSource::next() {
  for (;;) {
    fill(left_, 1);
    fill(right_, 1);
    if (left_.ahead.empty() || right_.ahead.empty()) {
      drain(left_, Side::kLeft);
      drain(right_, Side::kRight);
      return std::nullopt;
    }
    const double tl = left_.ahead.front().timestamp_s;
    const double tr = right_.ahead.front().timestamp_s;
    const bool left_earlier = tl <= tr;
    Stream& early = left_earlier ? left_ : right_;
    const Side early_side = left_earlier ? Side::kLeft : Side::kRight;
    const double t_other = left_earlier ? tr : tl;
    const double gap = std::abs(tl - tr);
    if (gap > tolerance_s_) {
      skip(early, early_side);
      continue;
    }
    fill(early, 2);
    if (early.ahead.size() == 2 && std::abs(early.ahead[1].timestamp_s - t_other) < gap) {
      skip(early, early_side);
      continue;
    }
    StereoFrame pair{std::move(left_.ahead.front()), std::move(right_.ahead.front())};
    left_.ahead.pop_front();
    right_.ahead.pop_front();
    return pair;
  }
}

}  // namespace kincal::capture
