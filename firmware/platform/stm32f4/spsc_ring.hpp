// A lock-free single-producer/single-consumer ring of fixed capacity: an interrupt handler pushes,
// the main loop pops (bxCAN's received frames).
//
// Why lock-free: the producer is an ISR, which cannot wait for the main loop; masking interrupts
// around every pop would delay the CAN ISR for no gain. On a single-core Cortex-M4 the 32-bit
// indices are written by one side each, with release stores after the payload and acquire loads
// before reading it (GCC emits DMB), so neither side ever sees a half-written item.
// Contract: exactly one producer context calls push() and exactly one consumer context calls
// pop()/empty(); overflows() may be read from anywhere.
// Memory: kCapacity items inside the object, plus three 32-bit counters; constexpr-constructible,
// so a namespace-scope instance is zero-initialised in .bss (no static constructor).
// Cost: O(1): push and pop copy one item and do one acquire load and one release store.
// Failure modes: push() on a full ring drops the NEW item (what is queued stays, in order),
// counts it in overflows() and returns false. The free-running indices wrap at 2^32, which is a
// multiple of the power-of-two capacity, so wrap-around is exact.
#pragma once

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

namespace kincal::stm32f4 {

template <class T, std::size_t kCapacity>
class SpscRing {
  static_assert(kCapacity >= 2 && kCapacity <= (std::size_t{1} << 16) && (kCapacity & (kCapacity - 1)) == 0,
                "ring capacity must be a power of two in [2, 65536]");
  static_assert(std::atomic<std::uint32_t>::is_always_lock_free, "the ring needs lock-free 32-bit atomics");

 public:
  static constexpr std::size_t capacity() { return kCapacity; }

  // Producer side. False (and the item dropped and counted) when the ring is full.
  bool push(const T& item) {
    const std::uint32_t head = head_.load(std::memory_order_relaxed);
    const std::uint32_t tail = tail_.load(std::memory_order_acquire);
    if (head - tail >= kCapacity) {
      overflows_.store(overflows_.load(std::memory_order_relaxed) + 1u, std::memory_order_relaxed);
      return false;
    }
    items_[head & kMask] = item;
    head_.store(head + 1u, std::memory_order_release);
    return true;
  }

  // Consumer side. False when the ring is empty.
  bool pop(T& out) {
    const std::uint32_t tail = tail_.load(std::memory_order_relaxed);
    const std::uint32_t head = head_.load(std::memory_order_acquire);
    if (head == tail) return false;
    out = items_[tail & kMask];
    tail_.store(tail + 1u, std::memory_order_release);
    return true;
  }

  // Consumer side: whether pop() would return false now.
  bool empty() const { return head_.load(std::memory_order_acquire) == tail_.load(std::memory_order_relaxed); }

  // Items push() had to drop since start-up (wraps at 2^32).
  std::uint32_t overflows() const { return overflows_.load(std::memory_order_relaxed); }

 private:
  static constexpr std::uint32_t kMask = static_cast<std::uint32_t>(kCapacity - 1);

  std::array<T, kCapacity> items_{};
  std::atomic<std::uint32_t> head_{0};       // written by the producer only
  std::atomic<std::uint32_t> tail_{0};       // written by the consumer only
  std::atomic<std::uint32_t> overflows_{0};  // written by the producer only
};

}  // namespace kincal::stm32f4
