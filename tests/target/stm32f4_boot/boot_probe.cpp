// The boot test's probe: linked into the STM32F407 image (the flash image's objects, main.cpp
// included) to boot it under QEMU 7.2's netduinoplus2, an STM32F405 model. It reports over
// semihosting, one line per fact ("PASS name: ..." or "FAIL name: ..."); check_boot.py runs QEMU
// with a time limit, judges these lines and what QEMU logged of the image's accesses to the
// peripherals the model leaves unimplemented (RCC, IWDG, CAN1, DCMI: reads 0, writes ignored).
//
// How this image differs from the flash image, each only where the model cannot do what the chip
// does, or to observe and end the run:
//   - memory map: netduinoplus2.ld, CCM (stack, application object) at 0x20020000 (no CCM RAM
//     in the model);
//   - wait_adc_end_of_conversion (adc_rangers.hpp) returns true at once: the model's ADC never sets
//     SR.EOC; its data register yields a conversion when read after SWSTART;
//   - firmware_main is wrapped (--wrap): the boot facts are checked on entry, before the real one
//     runs; watchdog::refresh is wrapped: it counts the main loop's passes (one refresh each),
//     checks the clock and the rangers on the first and ends the run on the kMainLoopPasses-th;
//   - HardFault_Handler reports the fault and ends the run (the flash image's is Default_Handler's
//     breakpoint loop), so that a broken boot fails fast with the fault registers.
#include <array>
#include <cstddef>
#include <cstdint>

#include "firmware/platform/stm32f4/adc_rangers.hpp"
#include "firmware/platform/stm32f4/clock.hpp"
#include "firmware/platform/stm32f4/mmio.hpp"
#include "firmware/platform/stm32f4/systick_clock.hpp"

extern "C" {
extern std::uint32_t __stack_top, __vectors_start;
extern std::uint32_t __data_load__, __data_start__, __data_end__, __bss_start__, __bss_end__;
void Reset_Handler();
void SysTick_Handler();
void HardFault_Handler();
[[noreturn]] void __real_firmware_main();
[[noreturn]] void __wrap_firmware_main();
// kincal::stm32f4::watchdog::refresh() and wait_adc_end_of_conversion(), by their mangled names.
void __real__ZN6kincal7stm32f48watchdog7refreshEv();
void __wrap__ZN6kincal7stm32f48watchdog7refreshEv();
bool __wrap__ZN6kincal7stm32f426wait_adc_end_of_conversionEv();
}

namespace {

namespace board = kincal::stm32f4;
using board::mmio::reg;

// Semihosting (Arm's "Semihosting for AArch32 and AArch64", SYS_WRITE0 and SYS_EXIT).
constexpr std::uint32_t kSysWrite0 = 0x04, kSysExit = 0x18;
constexpr std::uint32_t kApplicationExit = 0x20026, kRunTimeErrorUnknown = 0x20023;  // QEMU exits 0 / 1

void semihost(std::uint32_t operation, const void* argument) {
  __asm volatile("mov r0, %0\n\tmov r1, %1\n\tbkpt 0xAB" : : "r"(operation), "r"(argument) : "r0", "r1", "memory");
}

// One line of the report, built without printf (no heap) and written with SYS_WRITE0.
class Line {
 public:
  Line& text(const char* s) {
    while (*s != '\0') put(*s++);
    return *this;
  }
  Line& number(std::uint64_t value) {
    std::array<char, 20> digits{};
    std::size_t n = 0;
    do {
      digits[n++] = static_cast<char>('0' + value % 10u);
      value /= 10u;
    } while (value != 0);
    while (n != 0) put(digits[--n]);
    return *this;
  }
  Line& hex(std::uint32_t value) {
    text("0x");
    for (int shift = 28; shift >= 0; shift -= 4) put("0123456789abcdef"[(value >> shift) & 0xFu]);
    return *this;
  }
  void write() {
    buffer_[size_] = '\n';
    buffer_[size_ + 1] = '\0';
    semihost(kSysWrite0, buffer_.data());
  }

 private:
  void put(char c) {
    if (size_ + 2 < buffer_.size()) buffer_[size_++] = c;
  }
  std::array<char, 160> buffer_{};
  std::size_t size_ = 0;
};

std::uint32_t failures = 0;

Line verdict(bool ok, const char* name) {
  if (!ok) ++failures;
  Line line;
  line.text(ok ? "PASS " : "FAIL ").text(name).text(": ");
  return line;
}

[[noreturn]] void finish() {
  Line().text(failures == 0 ? "DONE all facts hold" : "DONE with failures").write();
  semihost(kSysExit, reinterpret_cast<const void*>(failures == 0 ? kApplicationExit : kRunTimeErrorUnknown));
  for (;;) {
  }
}

// An object's or a function's address (a function's with the Thumb bit, as the vector table has it).
template <typename T>
std::uint32_t address_of(T* p) {
  return static_cast<std::uint32_t>(reinterpret_cast<std::uintptr_t>(p));
}

// Initialised and zero-initialised objects of the image: volatile, so that they stay in .data and
// .bss (a never-written object could otherwise become a constant).
volatile std::uint32_t probe_data[4] = {0x600DCAFEu, 0x12345678u, 0xA5A55A5Au, 7u};
volatile std::uint32_t probe_bss[4];

// The chip's SRAM ends at 0x20020000; nothing of the image lies in its last word, so it still
// holds check_boot.py's fill (0xA5 bytes, written before reset): the proof that the .bss check
// below saw memory that was not zero before Reset_Handler ran.
constexpr std::uintptr_t kSramLastWord = 0x2001FFFCu;
constexpr std::uint32_t kFill = 0xA5A5A5A5u;

[[gnu::noinline]] void check_data() {
  // Every byte of .data equals its load image in flash, but clock_status (Reset_Handler sets it
  // after the copy).
  const auto* loaded = reinterpret_cast<const volatile std::uint8_t*>(&__data_load__);
  const auto* begin = reinterpret_cast<const volatile std::uint8_t*>(&__data_start__);
  const auto* end = reinterpret_cast<const volatile std::uint8_t*>(&__data_end__);
  const auto* clock_status = reinterpret_cast<const volatile std::uint8_t*>(&board::clock_status);
  std::uint32_t differing = 0;
  for (const volatile std::uint8_t* p = begin; p != end; ++p, ++loaded)
    if (p != clock_status && *p != *loaded) ++differing;
  const bool values = probe_data[0] == 0x600DCAFEu && probe_data[1] == 0x12345678u && probe_data[2] == 0xA5A55A5Au &&
                      probe_data[3] == 7u;
  verdict(differing == 0 && values, "data")
      .text(".data ")
      .hex(address_of(begin))
      .text(" bytes ")
      .number(static_cast<std::uint32_t>(end - begin))
      .text(" from ")
      .hex(address_of(&__data_load__))
      .text(", differing ")
      .number(differing)
      .text(values ? ", probe values initialised" : ", probe values WRONG")
      .write();
}

[[gnu::noinline]] void check_bss() {
  std::uint32_t nonzero = 0, words = 0;
  for (const volatile std::uint32_t* p = &__bss_start__; p != &__bss_end__; ++p, ++words)
    if (*p != 0) ++nonzero;
  const bool probe_zero = probe_bss[0] == 0 && probe_bss[1] == 0 && probe_bss[2] == 0 && probe_bss[3] == 0;
  const bool filled = reg(kSramLastWord) == kFill;
  verdict(nonzero == 0 && probe_zero, "bss")
      .text(".bss ")
      .hex(address_of(&__bss_start__))
      .text(" words ")
      .number(words)
      .text(", nonzero ")
      .number(nonzero)
      .write();
  verdict(filled, "fill")
      .text("SRAM beyond the image holds ")
      .hex(reg(kSramLastWord))
      .text(" (set before reset)")
      .write();
}

[[gnu::noinline]] void check_fpu() {
  const std::uint32_t cp10_cp11 = (reg(0xE000ED88u) >> 20) & 0xFu;  // SCB_CPACR
  volatile float a = 1.5f, b = 2.25f, c = 0.125f;
  const float product = a * b + c;  // 3.5 exactly: a fault here if the FPU were off
  verdict(cp10_cp11 == 0xFu && product == 3.5f, "fpu")
      .text("CPACR CP10/CP11 ")
      .hex(cp10_cp11)
      .text(", 1.5 * 2.25 + 0.125 = ")
      .number(static_cast<std::uint32_t>(product * 8.0f))
      .text("/8")
      .write();
}

[[gnu::noinline]] void check_vectors() {
  // The table the core took reset from (VTOR, 0 at reset: flash aliased at 0 with BOOT0 low) is
  // the image's, at the address its linker script gave .vectors: the STM32F4's boot address.
  constexpr std::uintptr_t kFlashBoot = 0x08000000u;
  constexpr std::size_t kWords = 16 + 82;
  const std::uint32_t vtor = reg(0xE000ED08u);
  const std::uint32_t table = address_of(&__vectors_start);
  bool same = true;
  for (std::size_t i = 0; i < kWords; ++i) same = same && reg(vtor + 4u * i) == reg(table + 4u * i);
  const bool entries = reg(table) == address_of(&__stack_top) && reg(table + 4u) == address_of(&Reset_Handler) &&
                       reg(table + 12u) == address_of(&HardFault_Handler) &&
                       reg(table + 60u) == address_of(&SysTick_Handler);
  verdict(table == kFlashBoot && (vtor == 0 || vtor == kFlashBoot) && same && entries, "vectors")
      .text(".vectors at ")
      .hex(table)
      .text(", VTOR ")
      .hex(vtor)
      .text(", initial SP ")
      .hex(reg(table))
      .text(", reset ")
      .hex(reg(table + 4u))
      .text(same && entries ? ", entries are the image's" : ", entries WRONG")
      .write();
}

const char* clock_name(board::ClockStatus status) {
  switch (status) {
    case board::ClockStatus::kPll168MHz:
      return "PLL 168 MHz";
    case board::ClockStatus::kHseFailedOnHsi:
      return "HSI 16 MHz, the crystal never became ready";
    case board::ClockStatus::kPllFailedOnHsi:
      return "HSI 16 MHz, the PLL never locked";
  }
  return "unknown";
}

[[gnu::noinline]] void check_clock() {
  // The model has no RCC: HSERDY never sets, so the set-up must have given up and stayed on the HSI.
  const board::ClockRates rates = board::clock_rates();
  verdict(board::clock_status == board::ClockStatus::kHseFailedOnHsi && rates.core_hz == 16000000 &&
              rates.apb1_hz == 16000000 && rates.apb2_hz == 16000000,
          "clock")
      .text(clock_name(board::clock_status))
      .text("; core ")
      .number(rates.core_hz)
      .text(" Hz, APB1 ")
      .number(rates.apb1_hz)
      .text(" Hz, APB2 ")
      .number(rates.apb2_hz)
      .text(" Hz")
      .write();
}

void check_systick() {
  // Three milliseconds of the firmware's clock: SysTick_Handler must have run at least twice.
  constexpr std::uint64_t kAdvanceUs = 3000;
  constexpr std::uint32_t kPollLimit = 20000000;
  const std::uint64_t start_us = board::systick::now_us();
  std::uint64_t now_us = start_us;
  std::uint32_t polls = 0;
  for (; polls < kPollLimit && now_us < start_us + kAdvanceUs; ++polls) now_us = board::systick::now_us();
  verdict(now_us >= start_us + kAdvanceUs, "systick")
      .text("now_us ")
      .number(start_us)
      .text(" -> ")
      .number(now_us)
      .text(" across a busy wait of ")
      .number(polls)
      .text(" polls")
      .write();
}

void check_rangers() {
  // The driver on its own ADC1 set-up, as firmware_main starts it; every scan's four ranges go
  // to check_boot.py, which knows the model's conversions (7 counts more each).
  constexpr std::uint32_t kScans = 150;
  board::AdcRangers rangers;
  const bool started = rangers.start(board::clock_rates().apb2_hz) == board::AdcStatus::kOk;
  std::uint32_t scans = 0;
  for (; started && scans < kScans; ++scans) {
    std::array<std::uint32_t, kincal::shared::kRangers> ranges_um{};
    std::uint64_t time_us = 0;
    if (rangers.read(ranges_um, time_us) != kincal::app::RangerStatus::kOk) break;
    Line line;
    line.text("RANGES ").number(scans);
    for (const std::uint32_t range_um : ranges_um) line.text(" ").number(range_um);
    line.write();
  }
  verdict(started && scans == kScans, "rangers").number(scans).text(" scans of 4 beams read").write();
}

constexpr std::uint32_t kMainLoopPasses = 1000;
std::uint32_t passes = 0;

}  // namespace

// The checks are not inlined here: their report lines would stay on the stack under the real
// firmware_main (this frame lives on below it), beyond the image's stack budget.
// .bss first: a failed check counts itself in `failures`, which lives there.
extern "C" void __wrap_firmware_main() {
  check_bss();
  check_data();
  check_fpu();
  check_vectors();
  check_clock();
  __real_firmware_main();
}

extern "C" void __wrap__ZN6kincal7stm32f48watchdog7refreshEv() {
  __real__ZN6kincal7stm32f48watchdog7refreshEv();
  ++passes;
  if (passes == 1) {
    check_systick();
    check_rangers();
  }
  if (passes == kMainLoopPasses) {
    verdict(true, "main_loop")
        .number(passes)
        .text(" passes of firmware_main's loop, each refreshing the watchdog; now_us ")
        .number(board::systick::now_us())
        .write();
    finish();
  }
}

extern "C" bool __wrap__ZN6kincal7stm32f426wait_adc_end_of_conversionEv() { return true; }

extern "C" void HardFault_Handler() {
  verdict(false, "fault")
      .text("HardFault: HFSR ")
      .hex(reg(0xE000ED2Cu))
      .text(" CFSR ")
      .hex(reg(0xE000ED28u))
      .text(" BFAR ")
      .hex(reg(0xE000ED38u))
      .write();
  finish();
}
