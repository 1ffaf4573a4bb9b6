// The sensor platform's firmware on the STM32F407. Today it boots, brings the clock to
// 168 MHz and sleeps between interrupts: the application (CAN protocol, camera and rangers,
// measurement scheduling) arrives with issue #5 in firmware/app.
extern "C" [[noreturn]] void firmware_main() {
  for (;;) __asm volatile("wfi");
}
