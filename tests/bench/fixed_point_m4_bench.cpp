// Instructions per fixed-point operation on the Cortex-M4 (QEMU, -icount shift=0):
// the cost model that the pixel path's budget (issue #3) is planned with.
#include <cstdint>
#include <cstdio>

#include "firmware/core/fixed_point.hpp"
#include "tests/bench/m4_instruction_counter.hpp"

using kincal::core::q16_16;

namespace {

constexpr int kRepetitions = 20000;

// Keeps the compiler from folding or hoisting the operation out of the timed loop.
template <class T>
void keep(T& value) {
  __asm volatile("" : "+r"(value));
}

template <class Op>
double instructions_per_op(kincal::bench::M4InstructionCounter& counter, Op op) {
  std::int32_t a = 0x00012345, b = 0x00003456;
  counter.start();
  for (int i = 0; i < kRepetitions; ++i) {
    keep(a);
    keep(b);
    a = op(q16_16::from_raw(a), q16_16::from_raw(b)).raw();
  }
  return static_cast<double>(counter.stop_instructions()) / kRepetitions;
}

}  // namespace

int main() {
  kincal::bench::M4InstructionCounter counter;
  const double loop = instructions_per_op(counter, [](q16_16 a, q16_16) { return a; });
  const double add = instructions_per_op(counter, [](q16_16 a, q16_16 b) { return a + b; }) - loop;
  const double mul = instructions_per_op(counter, [](q16_16 a, q16_16 b) { return a * b; }) - loop;
  const double div = instructions_per_op(counter, [](q16_16 a, q16_16 b) { return a / b; }) - loop;
  const double root = instructions_per_op(counter, [](q16_16 a, q16_16) { return sqrt(a); }) - loop;
  std::printf("FIGURE fixed_q16_16_add_m4_instructions %.1f instructions\n", add);
  std::printf("FIGURE fixed_q16_16_mul_m4_instructions %.1f instructions\n", mul);
  std::printf("FIGURE fixed_q16_16_div_m4_instructions %.1f instructions\n", div);
  std::printf("FIGURE fixed_q16_16_sqrt_m4_instructions %.1f instructions\n", root);
  return 0;
}
