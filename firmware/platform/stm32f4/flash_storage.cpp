#include "firmware/platform/stm32f4/flash_storage.hpp"

#include "firmware/platform/stm32f4/mmio.hpp"

// The parameter sectors as absolute symbols, so that stm32f407vg.ld can assert that the image
// stays out of them (a linker script cannot read C++ constants).
__asm(
    ".global __kincal_parameter_sectors_start\n"
    ".set __kincal_parameter_sectors_start, 0x08004000\n"
    ".global __kincal_parameter_sectors_end\n"
    ".set __kincal_parameter_sectors_end, 0x080A0000\n");

namespace kincal::stm32f4 {

namespace {

using app::StorageStatus;
using mmio::reg;

// Every slot: a distinct parameter sector, large enough, inside the reserved range.
constexpr bool slot_map_is_sound() {
  for (std::size_t a = 0; a < FlashStorage::kSlots; ++a) {
    const std::uint8_t sector = FlashStorage::kSlotSector[a];
    if (sector < 1 || sector > 8 || flash_sector_bytes(sector) < FlashStorage::kSlotBytes) return false;
    if (flash_sector_address(sector) < kParameterSectorsStart ||
        flash_sector_address(sector) + flash_sector_bytes(sector) > kParameterSectorsEnd)
      return false;
    for (std::size_t b = a + 1; b < FlashStorage::kSlots; ++b)
      if (FlashStorage::kSlotSector[b] == sector) return false;
  }
  return true;
}
static_assert(slot_map_is_sound());
static_assert(flash_sector_address(9) == kParameterSectorsEnd && flash_sector_address(1) == kParameterSectorsStart);
static_assert(
    flash_sector_bytes(FlashStorage::kSlotSector[app::slot_format::slot_of(shared::ParameterBlock::kCorrection, 0)]) ==
            0x4000u &&
        flash_sector_bytes(
            FlashStorage::kSlotSector[app::slot_format::slot_of(shared::ParameterBlock::kCorrection, 1)]) == 0x4000u,
    "the correction block is meant to live in the fast-erasing 16 KiB sectors");

// Flash interface registers (RM0090 3.9).
constexpr std::uintptr_t kAcr = 0x40023C00u, kKeyr = 0x40023C04u, kSr = 0x40023C0Cu, kCr = 0x40023C10u;
constexpr std::uint32_t kKey1 = 0x45670123u, kKey2 = 0xCDEF89ABu;
constexpr std::uint32_t kSrErrors =
    (1u << 1) | (1u << 4) | (1u << 5) | (1u << 6) | (1u << 7);  // OPERR, WRP, PGA, PGP, PGS
constexpr std::uint32_t kSrBsy = 1u << 16;
constexpr std::uint32_t kCrPg = 1u << 0, kCrSer = 1u << 1, kCrStrt = 1u << 16, kCrLock = 1u << 31;
constexpr std::uint32_t kCrPsizeX8 = 0u << 8, kCrPsizeX32 = 2u << 8;
constexpr std::uint32_t kAcrDcen = 1u << 10, kAcrDcrst = 1u << 12;

// Bounds on BSY, in polls of at least 5 cycles each at up to 168 MHz: >= 4.4 s for an erase
// (128 KiB: 2 s max), >= 3 ms for one program (100 us max). Longer on the 16 MHz fall-back clock.
constexpr std::uint32_t kEraseWaitLimit = 150000000;
constexpr std::uint32_t kProgramWaitLimit = 100000;

bool wait_idle(std::uint32_t limit) {
  for (std::uint32_t i = 0; i < limit; ++i)
    if ((reg(kSr) & kSrBsy) == 0) return true;
  return false;
}

bool in_slot(std::uint8_t slot, std::uint32_t offset, std::size_t bytes) {
  return slot < FlashStorage::kSlots && offset <= FlashStorage::kSlotBytes &&
         bytes <= FlashStorage::kSlotBytes - offset;
}

// Opens the controller for one operation: idle, unlocked, error flags cleared, data cache off.
// Returns whether the data cache was on (for end()); `ok` says whether the controller opened.
bool begin(bool& ok) {
  const bool data_cache = (reg(kAcr) & kAcrDcen) != 0;
  mmio::clear_bits(kAcr, kAcrDcen);
  ok = wait_idle(kProgramWaitLimit);
  if (ok && (reg(kCr) & kCrLock) != 0) {
    // The key sequence, once: a wrong one would lock the controller until reset.
    reg(kKeyr) = kKey1;
    reg(kKeyr) = kKey2;
  }
  ok = ok && (reg(kCr) & kCrLock) == 0;
  reg(kSr) = kSrErrors;  // write 1 to clear
  return data_cache;
}

// Closes it again: operation bits cleared, locked, data cache reset (stale lines) and restored.
void end(bool data_cache) {
  reg(kCr) = kCrLock;
  mmio::set_bits(kAcr, kAcrDcrst);
  mmio::clear_bits(kAcr, kAcrDcrst);
  if (data_cache) mmio::set_bits(kAcr, kAcrDcen);
}

bool done_without_error(std::uint32_t limit) {
  mmio::data_synchronization_barrier();  // the write that starts the operation has left the core
  return wait_idle(limit) && (reg(kSr) & kSrErrors) == 0;
}

const volatile std::uint8_t* flash_bytes(std::uint32_t address) {
  return reinterpret_cast<const volatile std::uint8_t*>(static_cast<std::uintptr_t>(address));
}

}  // namespace

StorageStatus FlashStorage::read(std::uint8_t slot, std::uint32_t offset, std::span<std::uint8_t> out) const {
  if (!in_slot(slot, offset, out.size())) return StorageStatus::kFailed;
  const volatile std::uint8_t* from = flash_bytes(slot_address(slot) + offset);
  for (std::size_t i = 0; i < out.size(); ++i) out[i] = from[i];
  return StorageStatus::kOk;
}

StorageStatus FlashStorage::erase(std::uint8_t slot) {
  if (slot >= kSlots) return StorageStatus::kFailed;
  bool ok = false;
  const bool data_cache = begin(ok);
  if (ok) {
    reg(kCr) = kCrSer | (std::uint32_t{kSlotSector[slot]} << 3) | kCrPsizeX32;
    reg(kCr) = reg(kCr) | kCrStrt;
    ok = done_without_error(kEraseWaitLimit);
  }
  end(data_cache);
  const volatile std::uint8_t* bytes = flash_bytes(slot_address(slot));
  for (std::size_t i = 0; ok && i < kSlotBytes; ++i) ok = bytes[i] == 0xFFu;
  return ok ? StorageStatus::kOk : StorageStatus::kFailed;
}

StorageStatus FlashStorage::write(std::uint8_t slot, std::uint32_t offset, std::span<const std::uint8_t> in) {
  if (!in_slot(slot, offset, in.size())) return StorageStatus::kFailed;
  const std::uint32_t base = slot_address(slot) + offset;
  bool ok = false;
  const bool data_cache = begin(ok);
  for (std::size_t i = 0; ok && i < in.size();) {
    const std::uint32_t address = base + static_cast<std::uint32_t>(i);
    if (address % 4u == 0 && in.size() - i >= 4) {
      reg(kCr) = kCrPg | kCrPsizeX32;
      reg(address) = std::uint32_t{in[i]} | std::uint32_t{in[i + 1]} << 8 | std::uint32_t{in[i + 2]} << 16 |
                     std::uint32_t{in[i + 3]} << 24;
      i += 4;
    } else {
      reg(kCr) = kCrPg | kCrPsizeX8;
      mmio::reg8(address) = in[i];
      i += 1;
    }
    ok = done_without_error(kProgramWaitLimit);
  }
  end(data_cache);
  const volatile std::uint8_t* bytes = flash_bytes(base);
  for (std::size_t i = 0; ok && i < in.size(); ++i) ok = bytes[i] == in[i];
  return ok ? StorageStatus::kOk : StorageStatus::kFailed;
}

}  // namespace kincal::stm32f4
