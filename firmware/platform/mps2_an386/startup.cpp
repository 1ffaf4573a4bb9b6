// Reset and vectors for QEMU's mps2-an386 (Cortex-M4 with FPU), where the firmware-core
// test image runs. Newlib's rdimon crt0 (_start) then zeroes .bss, sets up semihosting
// (stdout, argv, exit status) and calls main.
#include <cerrno>
#include <cstddef>
#include <cstdint>

extern "C" {
extern std::uint32_t __stack_top;
extern std::uint32_t __data_load__, __data_start__, __data_end__;
[[noreturn]] void _start();
void Reset_Handler();
void Fault_Handler();
int getentropy(void* buffer, std::size_t length);
}

namespace {
using Vector = void (*)();
}

extern "C" void Reset_Handler() {
  // Full access to CP10/CP11 (the FPU) before any floating-point instruction runs.
  auto* const cpacr = reinterpret_cast<volatile std::uint32_t*>(0xE000ED88u);
  *cpacr = *cpacr | (0xFu << 20);
  __asm volatile("dsb\n\tisb" ::: "memory");
  // QEMU loads .data at its load address in flash; copy it to RAM as a real MCU must.
  const std::uint32_t* src = &__data_load__;
  for (std::uint32_t* dst = &__data_start__; dst < &__data_end__;) *dst++ = *src++;
  _start();
}

// A fault in a test image ends the run with a failure instead of hanging QEMU:
// semihosting SYS_EXIT with ADP_Stopped_RunTimeErrorUnknown.
extern "C" void Fault_Handler() {
  __asm volatile(
      "mov r0, #0x18\n\t"
      "ldr r1, =0x20023\n\t"
      "bkpt 0xAB" ::
          : "r0", "r1", "memory");
  for (;;) {
  }
}

// libstdc++'s std::random_device asks for entropy; this board has none to give.
extern "C" int getentropy(void*, std::size_t) {
  errno = ENOSYS;
  return -1;
}

// clang-format off
__attribute__((section(".vectors"), used)) const Vector kVectors[16] = {
    reinterpret_cast<Vector>(&__stack_top),  // initial stack pointer
    Reset_Handler, Fault_Handler, Fault_Handler, Fault_Handler, Fault_Handler, Fault_Handler,
    nullptr, nullptr, nullptr, nullptr,
    Fault_Handler, Fault_Handler, nullptr, Fault_Handler, Fault_Handler};
// clang-format on
