// Reset, vector table and clock tree for the STM32F407 (RM0090): the sensor platform's MCU.
// Reset_Handler copies .data, zeroes .bss, enables the FPU, runs the clock set-up, then
// calls firmware_main() (main.cpp; C++ forbids calling main()). The firmware has no static
// constructors (the linker script asserts it), so the stack analysis sees no indirect call.
// Every interrupt handler is a weak alias of Default_Handler, so a driver defines e.g.
// CAN1_RX0_IRQHandler() to take its interrupt.
#include <cstdint>

#include "firmware/platform/stm32f4/clock.hpp"

extern "C" {
extern std::uint32_t __stack_top;
extern std::uint32_t __data_load__, __data_start__, __data_end__, __bss_start__, __bss_end__;
[[noreturn]] void firmware_main();
[[noreturn]] void Reset_Handler();
void Default_Handler();
}

// Unhandled interrupt or fault: stop here, where a debugger finds it.
extern "C" void Default_Handler() {
  for (;;) __asm volatile("bkpt 0");
}

// One table row per line reads better than any reflow.
// clang-format off
#define KINCAL_STM32F4_EXCEPTIONS(X) \
  X(NMI_Handler) X(HardFault_Handler) X(MemManage_Handler) X(BusFault_Handler) X(UsageFault_Handler) \
  X(SVC_Handler) X(DebugMon_Handler) X(PendSV_Handler) X(SysTick_Handler)

// The 82 peripheral interrupts of the STM32F405/407, in vector order (RM0090 table 61).
#define KINCAL_STM32F4_IRQS(X)                                                                          \
  X(WWDG) X(PVD) X(TAMP_STAMP) X(RTC_WKUP) X(FLASH) X(RCC) X(EXTI0) X(EXTI1) X(EXTI2) X(EXTI3) X(EXTI4)  \
  X(DMA1_Stream0) X(DMA1_Stream1) X(DMA1_Stream2) X(DMA1_Stream3) X(DMA1_Stream4) X(DMA1_Stream5)      \
  X(DMA1_Stream6) X(ADC) X(CAN1_TX) X(CAN1_RX0) X(CAN1_RX1) X(CAN1_SCE) X(EXTI9_5) X(TIM1_BRK_TIM9)    \
  X(TIM1_UP_TIM10) X(TIM1_TRG_COM_TIM11) X(TIM1_CC) X(TIM2) X(TIM3) X(TIM4) X(I2C1_EV) X(I2C1_ER)      \
  X(I2C2_EV) X(I2C2_ER) X(SPI1) X(SPI2) X(USART1) X(USART2) X(USART3) X(EXTI15_10) X(RTC_Alarm)       \
  X(OTG_FS_WKUP) X(TIM8_BRK_TIM12) X(TIM8_UP_TIM13) X(TIM8_TRG_COM_TIM14) X(TIM8_CC) X(DMA1_Stream7)  \
  X(FSMC) X(SDIO) X(TIM5) X(SPI3) X(UART4) X(UART5) X(TIM6_DAC) X(TIM7) X(DMA2_Stream0)                \
  X(DMA2_Stream1) X(DMA2_Stream2) X(DMA2_Stream3) X(DMA2_Stream4) X(ETH) X(ETH_WKUP) X(CAN2_TX)        \
  X(CAN2_RX0) X(CAN2_RX1) X(CAN2_SCE) X(OTG_FS) X(DMA2_Stream5) X(DMA2_Stream6) X(DMA2_Stream7)        \
  X(USART6) X(I2C3_EV) X(I2C3_ER) X(OTG_HS_EP1_OUT) X(OTG_HS_EP1_IN) X(OTG_HS_WKUP) X(OTG_HS) X(DCMI) \
  X(CRYP) X(HASH_RNG) X(FPU)

#define KINCAL_WEAK_EXCEPTION(name) extern "C" void name() __attribute__((weak, alias("Default_Handler")));
#define KINCAL_WEAK_IRQ(name) \
  extern "C" void name##_IRQHandler() __attribute__((weak, alias("Default_Handler")));
KINCAL_STM32F4_EXCEPTIONS(KINCAL_WEAK_EXCEPTION)
KINCAL_STM32F4_IRQS(KINCAL_WEAK_IRQ)
// clang-format on

namespace {

using Vector = void (*)();
#define KINCAL_IRQ_ENTRY(name) name##_IRQHandler,

struct VectorTable {
  Vector initial_stack;
  Vector reset;
  Vector nmi, hard_fault, mem_manage, bus_fault, usage_fault;
  Vector reserved_7_10[4];
  Vector svc, debug_monitor;
  Vector reserved_13;
  Vector pend_sv, systick;
  Vector irq[82];
};
static_assert(sizeof(VectorTable) == (16 + 82) * sizeof(Vector));

}  // namespace

// clang-format off
__attribute__((section(".vectors"), used)) const VectorTable kVectors = {
    reinterpret_cast<Vector>(&__stack_top),
    Reset_Handler,
    NMI_Handler, HardFault_Handler, MemManage_Handler, BusFault_Handler, UsageFault_Handler,
    {nullptr, nullptr, nullptr, nullptr},
    SVC_Handler, DebugMon_Handler,
    nullptr,
    PendSV_Handler, SysTick_Handler,
    {KINCAL_STM32F4_IRQS(KINCAL_IRQ_ENTRY)}};
// clang-format on

extern "C" void Reset_Handler() {
  const std::uint32_t* src = &__data_load__;
  for (std::uint32_t* dst = &__data_start__; dst < &__data_end__;) *dst++ = *src++;
  for (std::uint32_t* dst = &__bss_start__; dst < &__bss_end__;) *dst++ = 0;
  kincal::stm32f4::enable_fpu();
  kincal::stm32f4::clock_status = kincal::stm32f4::configure_clock_168mhz();
  firmware_main();
}
