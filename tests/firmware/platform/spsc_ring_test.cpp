// spsc_ring.hpp (the STM32F407's receive ring between the CAN ISR and the main loop), natively:
// order, empty and full, the drop count, wrap-around of the storage, and a producer thread against
// a consumer thread (the ISR against the main loop) with no item lost, duplicated or torn except
// those the ring counted as dropped. Not covered here: the wrap of the free-running 32-bit indices
// at 2^32 items (exact because 2^32 is a multiple of the power-of-two capacity; reaching it takes
// 4e9 operations).
#include "firmware/platform/stm32f4/spsc_ring.hpp"

#include <doctest.h>

#include <atomic>
#include <cstdint>
#include <thread>

using kincal::stm32f4::SpscRing;

namespace {

// A CAN-frame-sized item whose words all derive from its sequence number, so a torn copy shows.
struct Item {
  std::uint32_t sequence = 0;
  std::uint32_t words[4] = {};
};

Item make_item(std::uint32_t sequence) {
  Item item;
  item.sequence = sequence;
  for (std::uint32_t k = 0; k < 4; ++k) item.words[k] = sequence * 2654435761u + k;
  return item;
}

bool intact(const Item& item) {
  for (std::uint32_t k = 0; k < 4; ++k)
    if (item.words[k] != item.sequence * 2654435761u + k) return false;
  return true;
}

}  // namespace

TEST_CASE("spsc_ring: a new ring is empty and pop leaves the output alone") {
  SpscRing<Item, 4> ring;
  CHECK(ring.empty());
  CHECK(ring.overflows() == 0u);
  Item out = make_item(7);
  CHECK_FALSE(ring.pop(out));
  CHECK(out.sequence == 7u);
}

TEST_CASE("spsc_ring: items come out in the order they went in") {
  SpscRing<Item, 8> ring;
  for (std::uint32_t i = 0; i < 5; ++i) REQUIRE(ring.push(make_item(i)));
  CHECK_FALSE(ring.empty());
  for (std::uint32_t i = 0; i < 5; ++i) {
    Item out;
    REQUIRE(ring.pop(out));
    CHECK(out.sequence == i);
    CHECK(intact(out));
  }
  CHECK(ring.empty());
}

TEST_CASE("spsc_ring: a full ring drops the new item, keeps the queued ones and counts the drop") {
  SpscRing<Item, 4> ring;
  for (std::uint32_t i = 0; i < 4; ++i) REQUIRE(ring.push(make_item(i)));
  CHECK_FALSE(ring.push(make_item(100)));
  CHECK_FALSE(ring.push(make_item(101)));
  CHECK(ring.overflows() == 2u);

  Item out;
  REQUIRE(ring.pop(out));
  CHECK(out.sequence == 0u);
  CHECK(ring.push(make_item(4)));  // one slot free again
  CHECK_FALSE(ring.push(make_item(102)));
  CHECK(ring.overflows() == 3u);
  for (std::uint32_t expected = 1; expected <= 4; ++expected) {
    REQUIRE(ring.pop(out));
    CHECK(out.sequence == expected);
  }
  CHECK_FALSE(ring.pop(out));
  CHECK(ring.overflows() == 3u);
}

TEST_CASE("spsc_ring: the storage wraps around many times with the fill level varying") {
  SpscRing<Item, 4> ring;
  std::uint32_t pushed = 0, popped = 0;
  for (int round = 0; round < 1000; ++round) {
    const int fill = 1 + round % 4;  // 1..4 items in flight: every slot offset is visited
    for (int k = 0; k < fill; ++k) REQUIRE(ring.push(make_item(pushed++)));
    for (int k = 0; k < fill; ++k) {
      Item out;
      REQUIRE(ring.pop(out));
      REQUIRE(out.sequence == popped++);
    }
    REQUIRE(ring.empty());
  }
  CHECK(pushed == popped);
  CHECK(ring.overflows() == 0u);
}

TEST_CASE("spsc_ring: producer and consumer threads lose, repeat and tear nothing but the counted drops") {
  // The producer pushes bursts longer than the ring (CAN frames arriving back to back), then waits
  // until the consumer has taken every accepted item (the main loop catching up): each burst
  // races the consumer, and the test's length does not depend on how the threads are scheduled.
  constexpr std::uint32_t kBursts = 1000, kBurst = 20;
  static SpscRing<Item, 8> ring;  // static: one instance per process, like the driver's
  std::atomic<std::uint32_t> consumed{0};
  std::atomic<std::uint32_t> producer_drops{0};
  std::atomic<bool> producer_done{false};

  std::thread producer([&] {
    std::uint32_t accepted = 0, drops = 0, sequence = 0;
    for (std::uint32_t burst = 0; burst < kBursts; ++burst) {
      for (std::uint32_t k = 0; k < kBurst; ++k) {
        if (ring.push(make_item(sequence++))) {
          ++accepted;
        } else {
          ++drops;
        }
        // Frames a little apart: room for the consumer to pop in the middle of a burst. Spinning,
        // not sleeping, so that a loaded machine does not stretch the test.
        for (int pause = 0; pause < 2000; ++pause) std::atomic_signal_fence(std::memory_order_seq_cst);
      }
      while (consumed.load(std::memory_order_acquire) != accepted) std::this_thread::yield();
    }
    producer_drops.store(drops, std::memory_order_relaxed);
    producer_done.store(true, std::memory_order_release);
  });

  // The consumer starts only once the producer has overrun the ring, so drops happen on every
  // schedule; from then on both run freely.
  while (ring.overflows() == 0u) std::this_thread::yield();
  std::uint32_t received = 0, missing = 0, next_expected = 0;
  bool in_order = true, all_intact = true;
  std::uint32_t idle_polls = 0;
  for (;;) {
    const bool done = producer_done.load(std::memory_order_acquire);
    Item out;
    if (ring.pop(out)) {
      in_order = in_order && out.sequence >= next_expected;  // strictly increasing: no repeats
      all_intact = all_intact && intact(out);
      missing += out.sequence - next_expected;
      next_expected = out.sequence + 1u;
      consumed.store(++received, std::memory_order_release);
    } else if (done) {
      break;  // the producer finished before this empty pop: nothing more will come
    } else if (++idle_polls % 8192 == 0) {
      std::this_thread::yield();  // mostly spin, as the main loop polls: ready when a burst starts
    }
  }
  producer.join();
  constexpr std::uint32_t kItems = kBursts * kBurst;
  missing += kItems - next_expected;

  CHECK(in_order);
  CHECK(all_intact);
  CHECK(ring.overflows() > 0u);
  CHECK(ring.overflows() == producer_drops.load());
  CHECK(missing == ring.overflows());
  CHECK(received + ring.overflows() == kItems);
  MESSAGE("received ", received, " of ", kItems, " items, ", ring.overflows(), " dropped");
}
