// Stereo frames from two sources (issue #6): pairs each left frame with the right frame nearest
// in time, within a tolerance, and keeps a record of the frames that found no partner (a dropped
// or duplicated frame on one side must not shift every later pair).
//
// Pairing rule (both streams in non-decreasing time): look at the earliest unpaired frame of
// each side. If they are more than tolerance_s apart, the earlier one can have no partner later
// (the other side only moves forward in time) and is reported unpaired. Otherwise they pair,
// unless the next frame on the earlier side is strictly nearer to the other side's frame, in
// which case the earlier frame is unpaired. Each frame is used at most once; when one stream
// ends, the other's remaining frames are unpaired. Time going backwards within a stream throws
// CaptureError naming the source and frame.
//
// Cost: one frame of look-ahead per side; the unpaired record grows by one small entry per
// unpaired frame (no images kept). Errors of the underlying sources propagate unchanged.
#pragma once

#include <cstdint>
#include <deque>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "host/capture/frame_source.hpp"

namespace kincal::capture {

struct StereoFrame {
  Frame left, right;
};

enum class Side { kLeft, kRight };

struct UnpairedFrame {
  Side side = Side::kLeft;
  std::int64_t index = 0;
  double timestamp_s = 0;
  std::string origin;
};

class StereoSource {
 public:
  // tolerance_s >= 0: the largest time difference of a pair. Throws std::invalid_argument for a
  // negative or non-finite tolerance or a null source.
  StereoSource(std::unique_ptr<FrameSource> left, std::unique_ptr<FrameSource> right, double tolerance_s);

  // The next pair, or std::nullopt when either stream has ended (the rest is then unpaired).
  std::optional<StereoFrame> next();

  // Every frame skipped so far, in the order it was skipped.
  const std::vector<UnpairedFrame>& unpaired() const { return unpaired_; }

 private:
  struct Stream {
    std::unique_ptr<FrameSource> source;
    std::deque<Frame> ahead;  // at most two frames: the head and its successor
    double last_s = 0;
    bool started = false;
    bool ended = false;
  };
  // Makes `ahead` hold at least n frames if the stream has them.
  void fill(Stream& s, std::size_t n);
  void skip(Stream& s, Side side);
  void drain(Stream& s, Side side);

  Stream left_, right_;
  double tolerance_s_;
  std::vector<UnpairedFrame> unpaired_;
};

}  // namespace kincal::capture
