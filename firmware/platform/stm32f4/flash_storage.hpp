// The parameter store's non-volatile slots (app::StoragePort) in the STM32F407's own flash, one
// flash sector per slot, so that erasing one slot never touches another (firmware/app/
// parameter_store.hpp relies on that: the other copy of a block must survive a power cut in the
// middle of an erase). Register level, RM0090 section 3.
//
// Flash map of the STM32F407VG (1 MiB, sectors 0-3: 16 KiB, 4: 64 KiB, 5-11: 128 KiB). The image
// never overlaps the parameter sectors: stm32f407vg.ld places the vector table alone in sector 0
// and the code from sector 9, and asserts that against the range this file exports.
//   sector  0  0x08000000  16 KiB   vector table (the reset address)
//   sector  1  0x08004000  16 KiB   slot 6  correction, copy A
//   sector  2  0x08008000  16 KiB   slot 7  correction, copy B
//   sector  3  0x0800C000  16 KiB   slot 4  platform geometry, copy A
//   sector  4  0x08010000  64 KiB   slot 5  platform geometry, copy B
//   sector  5  0x08020000  128 KiB  slot 0  camera intrinsics, copy A
//   sector  6  0x08040000  128 KiB  slot 1  camera intrinsics, copy B
//   sector  7  0x08060000  128 KiB  slot 2  colour lookup table, copy A
//   sector  8  0x08080000  128 KiB  slot 3  colour lookup table, copy B
//   sectors 9-11  0x080A0000  384 KiB  code, constants, .data initial values
// The correction parameters, written after every identification, get the small sectors that erase
// fastest; the camera blocks, written once per camera calibration, get the large ones. Each slot
// uses the first kSlotBytes of its sector. Re-flashing the image with openocd (the `flash` target)
// erases only the sectors the image occupies, so stored parameters survive a firmware update.
//
// Programming: word (x32) where the address is 4-byte aligned and 4 bytes remain, byte (x8) at the
// edges; erase with x32 parallelism. x32 needs VDD >= 2.7 V (RM0090 table 7; the Discovery board
// runs at 3.0 V, most boards at 3.3 V). The flash data cache is switched off during each operation
// and reset afterwards, so reads never return bytes from before an erase or program.
// Verification: erase() checks the slot's bytes read back as 0xFF; write() compares what it
// programmed.
//
// ISR safety: main loop only; no ISR touches the flash controller. Interrupts stay enabled, but
// the F407 has one flash bank: any instruction fetch or vector fetch from flash waits until an
// erase or program ends, so no interrupt handler runs meanwhile (bxCAN's 3-frame hardware FIFO
// overruns on a busy bus, and the SysTick clock stops: see bxcan.hpp and systick_clock.hpp). The
// application writes parameters only in its idle state, when no correction stream runs.
// Cost (datasheet, x32): sector erase 16 KiB 250 ms typical / 500 ms max, 64 KiB 550 / 1100 ms,
// 128 KiB 1 / 2 s; programming about 16 us per word or byte (100 us max), so a 2 KiB block takes
// about 8 ms. Reads are memory-mapped copies. Memory: none (the object is empty).
// Failure modes: kFailed for a slot out of range, an access past the slot, a controller that does
// not unlock, an error flag (write protection, alignment, parallelism, sequence), a bounded wait
// that ran out (> 4 s for an erase, > 3 ms for a word), or a verification mismatch. A power cut
// leaves the slot partly erased or programmed: the parameter store's CRC rejects it.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "firmware/app/parameter_store.hpp"
#include "firmware/app/ports.hpp"

namespace kincal::stm32f4 {

// The STM32F407's sector geometry (RM0090 table 5).
constexpr std::uint32_t flash_sector_address(std::uint8_t sector) {
  if (sector < 4) return 0x08000000u + 0x4000u * sector;
  if (sector == 4) return 0x08010000u;
  return 0x08020000u + 0x20000u * (sector - 5u);
}
constexpr std::uint32_t flash_sector_bytes(std::uint8_t sector) {
  return sector < 4 ? 0x4000u : sector == 4 ? 0x10000u : 0x20000u;
}

// The sectors reserved for parameters: 1..8. stm32f407vg.ld checks its image against these.
inline constexpr std::uint32_t kParameterSectorsStart = 0x08004000u;
inline constexpr std::uint32_t kParameterSectorsEnd = 0x080A0000u;

class FlashStorage {
 public:
  static constexpr std::size_t kSlotBytes = 4096;
  static constexpr std::size_t kSlots = app::slot_format::kSlotCount;
  // Sector of each slot (slot = (block - 1) * 2 + copy, parameter_store.hpp).
  static constexpr std::array<std::uint8_t, kSlots> kSlotSector{5, 6, 7, 8, 3, 4, 1, 2};

  static constexpr std::uint32_t slot_address(std::uint8_t slot) { return flash_sector_address(kSlotSector[slot]); }

  app::StorageStatus read(std::uint8_t slot, std::uint32_t offset, std::span<std::uint8_t> out) const;
  app::StorageStatus erase(std::uint8_t slot);
  app::StorageStatus write(std::uint8_t slot, std::uint32_t offset, std::span<const std::uint8_t> in);
};

static_assert(app::StoragePort<FlashStorage>);

}  // namespace kincal::stm32f4
