// Memory-mapped register access for the STM32F407's drivers, and the few core and RCC registers
// more than one driver touches (RM0090 section 2.3 memory map, section 7 RCC; ARMv7-M ARM B3.4
// NVIC). No vendor HAL and no CMSIS headers: each driver writes its own register table, as
// clock.cpp does; what they share lives here.
//
// Why a header of its own: bxCAN, flash, ADC and SysTick all enable peripheral clocks and
// interrupts; one definition of those addresses keeps the drivers from disagreeing.
// ISR safety: reg() is a plain volatile access. The read-modify-write helpers (set_bits) are not
// atomic: call them from the main loop during start-up, before the interrupts they configure are
// enabled. Cost: one load and one store each. Failure modes: none (a wrong address is a bus
// fault, caught by the stack of HardFault_Handler = Default_Handler).
#pragma once

#include <cstdint>

namespace kincal::stm32f4::mmio {

inline volatile std::uint32_t& reg(std::uintptr_t address) {
  return *reinterpret_cast<volatile std::uint32_t*>(address);
}
inline volatile std::uint8_t& reg8(std::uintptr_t address) {
  return *reinterpret_cast<volatile std::uint8_t*>(address);
}
inline void set_bits(std::uintptr_t address, std::uint32_t bits) { reg(address) = reg(address) | bits; }
inline void clear_bits(std::uintptr_t address, std::uint32_t bits) { reg(address) = reg(address) & ~bits; }
// Replaces the bits under `mask` with `value` (already shifted into place).
inline void modify(std::uintptr_t address, std::uint32_t mask, std::uint32_t value) {
  reg(address) = (reg(address) & ~mask) | (value & mask);
}

// RCC clock enables (RM0090 section 7.3.10-7.3.14). A peripheral is usable two AHB/APB cycles after
// its enable bit is set (errata sheet ES0182, "delay after an RCC peripheral clock enabling"):
// enable_clock() reads the register back, which provides it.
inline constexpr std::uintptr_t kRccAhb1enr = 0x40023830u;
inline constexpr std::uintptr_t kRccApb1enr = 0x40023840u;
inline constexpr std::uintptr_t kRccApb2enr = 0x40023844u;
inline constexpr std::uint32_t kAhb1GpioA = 1u << 0, kAhb1GpioB = 1u << 1;
inline constexpr std::uint32_t kApb1Can1 = 1u << 25;
inline constexpr std::uint32_t kApb2Adc1 = 1u << 8;
inline void enable_clock(std::uintptr_t enable_register, std::uint32_t bits) {
  set_bits(enable_register, bits);
  const std::uint32_t read_back = reg(enable_register);
  static_cast<void>(read_back);
}

// GPIO ports (RM0090 section 8.4): mode, output type, speed, pull and alternate function.
inline constexpr std::uintptr_t kGpioA = 0x40020000u;
inline constexpr std::uintptr_t kGpioB = 0x40020400u;
enum class PinMode : std::uint32_t { kInput = 0, kOutput = 1, kAlternate = 2, kAnalog = 3 };
enum class Pull : std::uint32_t { kNone = 0, kUp = 1, kDown = 2 };
// Configures one pin; `alternate` (AF0..AF15) matters only in kAlternate mode.
inline void configure_pin(std::uintptr_t port, unsigned pin, PinMode mode, Pull pull, std::uint32_t alternate = 0) {
  const unsigned two = pin * 2u;
  modify(port + 0x00u, 3u << two, static_cast<std::uint32_t>(mode) << two);  // MODER
  clear_bits(port + 0x04u, 1u << pin);                                       // OTYPER: push-pull
  modify(port + 0x08u, 3u << two, 2u << two);                                // OSPEEDR: fast (50 MHz)
  modify(port + 0x0Cu, 3u << two, static_cast<std::uint32_t>(pull) << two);  // PUPDR
  const std::uintptr_t afr = port + (pin < 8 ? 0x20u : 0x24u);               // AFRL / AFRH
  const unsigned four = (pin % 8u) * 4u;
  modify(afr, 0xFu << four, alternate << four);
}

// NVIC (ARMv7-M B3.4): enable and priority of a peripheral interrupt; the F407 implements the top
// 4 priority bits, so priorities are multiples of 16 (0 = most urgent).
inline constexpr std::uintptr_t kNvicIser0 = 0xE000E100u;
inline constexpr std::uintptr_t kNvicIpr0 = 0xE000E400u;
inline void enable_irq(unsigned irq, std::uint8_t priority) {
  reg8(kNvicIpr0 + irq) = priority;
  reg(kNvicIser0 + 4u * (irq / 32u)) = 1u << (irq % 32u);
}

// Peripheral interrupt numbers (RM0090 table 61; the order of startup.cpp's vector table).
inline constexpr unsigned kIrqCan1Rx0 = 20;
inline constexpr unsigned kIrqCan1Sce = 22;

// The one priority the board's interrupts share (CAN1 RX0, CAN1 SCE, SysTick): none preempts
// another, so the stack holds at most one of their frames at a time (stm32f407vg.ld's budget).
inline constexpr std::uint8_t kIrqPriority = 0x80;

inline void data_synchronization_barrier() { __asm volatile("dsb" ::: "memory"); }

}  // namespace kincal::stm32f4::mmio
