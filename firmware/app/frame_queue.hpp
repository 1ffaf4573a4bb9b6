// A fixed-capacity FIFO of CAN frames (ring buffer), for frames the application has produced
// but the CAN controller has not taken yet.
// Memory: kCapacity * sizeof(CanFrame) (72 bytes each), inside the object. Cost: O(1) per call.
// Thread/ISR safety: one producer and one consumer in the same context; not ISR-safe.
// Failure modes: push() on a full queue returns false and drops nothing already queued.
#pragma once

#include <array>
#include <cstddef>

#include "shared/can_frame.hpp"

namespace kincal::app {

template <std::size_t kCapacity>
class FrameQueue {
  static_assert(kCapacity > 0 && kCapacity <= 255, "frame queue capacity out of range");

 public:
  bool push(const shared::CanFrame& frame) {
    if (size_ == kCapacity) return false;
    frames_[(head_ + size_) % kCapacity] = frame;
    ++size_;
    return true;
  }
  const shared::CanFrame& front() const { return frames_[head_]; }
  void pop() {
    if (size_ == 0) return;
    head_ = (head_ + 1) % kCapacity;
    --size_;
  }
  bool empty() const { return size_ == 0; }
  bool full() const { return size_ == kCapacity; }
  std::size_t size() const { return size_; }

 private:
  std::array<shared::CanFrame, kCapacity> frames_{};
  std::size_t head_ = 0;
  std::size_t size_ = 0;
};

}  // namespace kincal::app
