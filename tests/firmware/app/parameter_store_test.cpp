// Two-slot parameter storage: the newest valid copy wins, and a power cut at ANY byte of a
// save leaves either the previous copy or the new one, never a corrupt or missing block.
#include "firmware/app/parameter_store.hpp"

#include <doctest.h>

#include <algorithm>
#include <array>
#include <cstdint>

#include "tests/firmware/app/fake_ports.hpp"

using kincal::app::LoadResult;
using kincal::app::ParameterStore;
using kincal::app::StoreStatus;
using kincal::shared::ParameterBlock;
using kincal::test::FakeStorage;

namespace {

std::array<std::uint8_t, 300> payload_of(std::uint8_t seed) {
  std::array<std::uint8_t, 300> p{};
  for (std::size_t i = 0; i < p.size(); ++i) p[i] = static_cast<std::uint8_t>(seed + i * 13u);
  return p;
}

}  // namespace

TEST_CASE("empty storage: every block is missing") {
  FakeStorage storage;
  ParameterStore<FakeStorage> store(storage);
  std::array<std::uint8_t, 2048> out{};
  CHECK(store.load(ParameterBlock::kCorrection, out).status == StoreStatus::kMissing);
}

TEST_CASE("saves alternate slots and the newest copy is loaded") {
  FakeStorage storage;
  ParameterStore<FakeStorage> store(storage);
  std::array<std::uint8_t, 2048> out{};
  for (std::uint8_t round = 1; round <= 5; ++round) {
    const auto p = payload_of(round);
    std::uint32_t sequence = 0;
    REQUIRE(store.save(ParameterBlock::kGeometry, 1, p, sequence) == StoreStatus::kOk);
    CHECK(sequence == round);
    const LoadResult r = store.load(ParameterBlock::kGeometry, out);
    REQUIRE(r.status == StoreStatus::kOk);
    CHECK(r.sequence == round);
    CHECK(r.length == p.size());
    CHECK(r.version == 1);
    CHECK(std::equal(p.begin(), p.end(), out.begin()));
  }
  // Slots of another block are independent.
  CHECK(store.load(ParameterBlock::kIntrinsics, out).status == StoreStatus::kMissing);
  // A caller buffer too small for the block.
  CHECK(store.load(ParameterBlock::kGeometry, std::span<std::uint8_t>(out).first(10)).status == StoreStatus::kTooLarge);
}

TEST_CASE("a corrupted newest copy falls back to the older one") {
  FakeStorage storage;
  ParameterStore<FakeStorage> store(storage);
  std::uint32_t sequence = 0;
  REQUIRE(store.save(ParameterBlock::kCorrection, 1, payload_of(1), sequence) == StoreStatus::kOk);
  REQUIRE(store.save(ParameterBlock::kCorrection, 1, payload_of(2), sequence) == StoreStatus::kOk);
  // Copy 2 went to slot B of block 4 (slot 7); flip one payload bit there.
  storage.slots[7][kincal::app::slot_format::kHeaderBytes + 100] ^= 0x10;
  std::array<std::uint8_t, 2048> out{};
  const LoadResult r = store.load(ParameterBlock::kCorrection, out);
  REQUIRE(r.status == StoreStatus::kOk);
  CHECK(r.sequence == 1);
  const auto p1 = payload_of(1);
  CHECK(std::equal(p1.begin(), p1.end(), out.begin()));
}

TEST_CASE("sequence numbers compare across wrap-around") {
  using kincal::app::slot_format::newer;
  CHECK(newer(2, 1));
  CHECK_FALSE(newer(1, 2));
  CHECK(newer(0, 0xFFFFFFFFu));
  CHECK_FALSE(newer(5, 5));
}

TEST_CASE("power cut at every byte operation of a save: old or new copy, never neither") {
  // Measure one save's operations, then cut the power after each possible count.
  FakeStorage probe;
  ParameterStore<FakeStorage> probe_store(probe);
  std::uint32_t sequence = 0;
  REQUIRE(probe_store.save(ParameterBlock::kGeometry, 1, payload_of(1), sequence) == StoreStatus::kOk);
  const std::size_t before = probe.operations;
  REQUIRE(probe_store.save(ParameterBlock::kGeometry, 1, payload_of(2), sequence) == StoreStatus::kOk);
  const std::size_t per_save = probe.operations - before;
  REQUIRE(per_save == FakeStorage::kSlotBytes + 300 + kincal::app::slot_format::kHeaderBytes);

  const auto old_copy = payload_of(2);
  const auto new_copy = payload_of(3);
  int kept_old = 0, got_new = 0;
  // Every cut point in the erase tail, the payload and the header, and a stride through the erase.
  for (std::size_t cut = 0; cut <= per_save; cut += (cut < FakeStorage::kSlotBytes - 8 ? 37 : 1)) {
    FakeStorage storage = probe;  // holds copies 1 and 2
    storage.operations = 0;
    ParameterStore<FakeStorage> store(storage);
    storage.budget = static_cast<std::int64_t>(cut);
    std::uint32_t s = 0;
    const StoreStatus saved = store.save(ParameterBlock::kGeometry, 1, new_copy, s);
    storage.power_on();
    std::array<std::uint8_t, 2048> out{};
    ParameterStore<FakeStorage> after_reboot(storage);
    const LoadResult r = after_reboot.load(ParameterBlock::kGeometry, out);
    REQUIRE(r.status == StoreStatus::kOk);
    if (r.sequence == 3) {
      CHECK(std::equal(new_copy.begin(), new_copy.end(), out.begin()));
      ++got_new;
    } else {
      CHECK(r.sequence == 2);
      CHECK(std::equal(old_copy.begin(), old_copy.end(), out.begin()));
      CHECK(saved != StoreStatus::kOk);
      ++kept_old;
    }
  }
  CHECK(kept_old > 0);
  CHECK(got_new > 0);
}
