// Pins every rule of firmware/core/fixed_point.hpp bit-exactly, natively and on the M4:
// golden vectors and digests come from fixed_point_reference.py (exact rationals).
#include "firmware/core/fixed_point.hpp"

#include <doctest.h>

#include <cstddef>
#include <cstdint>
#include <cstring>

#include "fixed_point_vectors.inc"
#include "shared/crc32.hpp"

using namespace kincal::core;

namespace {

template <class T>
T raw_of(std::int64_t v) {
  return T::from_raw(static_cast<typename T::rep>(v));
}

// Counts mismatches so that a broken rule reports a few cases, not thousands of lines.
class Mismatches {
 public:
  explicit Mismatches(const char* table) : table_(table) {}
  void expect(std::int64_t got, std::int64_t expected, std::int64_t a, std::int64_t b = 0) {
    if (got == expected) return;
    if (++count_ <= 3) MESSAGE(doctest::String(table_), ": a=", a, " b=", b, " got ", got, " expected ", expected);
  }
  ~Mismatches() { CHECK_MESSAGE(count_ == 0, doctest::String(table_), ": ", count_, " mismatches"); }
  Mismatches(const Mismatches&) = delete;
  Mismatches& operator=(const Mismatches&) = delete;

 private:
  const char* table_;
  int count_ = 0;
};

template <class T, std::size_t N, class Op>
void check_binary(const char* table, const vectors::Binary (&cases)[N], Op op) {
  Mismatches m(table);
  for (const auto& c : cases) m.expect(op(raw_of<T>(c.a), raw_of<T>(c.b)).raw(), c.expected, c.a, c.b);
}

template <class To, class A, class B, std::size_t N, class Op>
void check_mixed(const char* table, const vectors::Binary (&cases)[N], Op op) {
  Mismatches m(table);
  for (const auto& c : cases) m.expect(op(raw_of<A>(c.a), raw_of<B>(c.b)).raw(), c.expected, c.a, c.b);
}

template <class From, class To, std::size_t N>
void check_cast(const char* table, const vectors::Unary (&cases)[N]) {
  Mismatches m(table);
  for (const auto& c : cases) m.expect(fixed_cast<To>(raw_of<From>(c.a)).raw(), c.expected, c.a);
}

std::uint32_t float_bits(float f) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &f, sizeof bits);
  return bits;
}

// CRC-32 (zlib's polynomial) over little-endian 32-bit words, as the reference computes it.
std::uint32_t crc32_word(std::uint32_t crc, std::uint32_t word) {
  const std::uint8_t bytes[] = {static_cast<std::uint8_t>(word), static_cast<std::uint8_t>(word >> 8),
                                static_cast<std::uint8_t>(word >> 16), static_cast<std::uint8_t>(word >> 24)};
  return ~kincal::shared::crc32_update(~crc, bytes);
}

template <class T>
std::uint32_t crc_same_format_ops(std::uint32_t crc, T a, T b) {
  const T results[] = {a + b, a - b, a * b, a / b, -a, sqrt(a)};
  for (const T r : results) crc = crc32_word(crc, static_cast<std::uint32_t>(r.raw()));
  return crc;
}

std::uint64_t splitmix64(std::uint64_t& state) {
  state += 0x9E3779B97F4A7C15u;
  std::uint64_t z = state;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9u;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBu;
  return z ^ (z >> 31);
}

q16_16 random_q16_16(std::uint64_t z) {
  const auto raw = static_cast<std::int32_t>(static_cast<std::uint32_t>(z & 0xFFFFFFFFu));
  return q16_16::from_raw(raw >> ((z >> 58) % 32));
}

}  // namespace

#define KINCAL_SAME_FORMAT_TABLES(F)                                                                            \
  TEST_CASE("fixed " #F ": negation, sqrt and float conversions match the reference") {                         \
    using T = vectors::F;                                                                                       \
    {                                                                                                           \
      Mismatches m(#F "_neg");                                                                                  \
      for (const auto& c : vectors::F##_neg) m.expect((-raw_of<T>(c.a)).raw(), c.expected, c.a);                \
    }                                                                                                           \
    {                                                                                                           \
      Mismatches m(#F "_sqrt");                                                                                 \
      for (const auto& c : vectors::F##_sqrt) m.expect(sqrt(raw_of<T>(c.a)).raw(), c.expected, c.a);            \
    }                                                                                                           \
    {                                                                                                           \
      Mismatches m(#F "_to_float");                                                                             \
      for (const auto& c : vectors::F##_to_float) m.expect(float_bits(raw_of<T>(c.a).to_float()), c.bits, c.a); \
    }                                                                                                           \
    {                                                                                                           \
      Mismatches m(#F "_from_double");                                                                          \
      for (const auto& c : vectors::F##_from_double) m.expect(T::from_double(c.in).raw(), c.expected, 0);       \
    }                                                                                                           \
  }                                                                                                             \
  TEST_CASE("fixed " #F ": + and - match the reference") {                                                      \
    check_binary<vectors::F>(#F "_add", vectors::F##_add, [](auto a, auto b) { return a + b; });                \
    check_binary<vectors::F>(#F "_sub", vectors::F##_sub, [](auto a, auto b) { return a - b; });                \
  }

#define KINCAL_MUL_DIV_TABLES(F)                                                                 \
  TEST_CASE("fixed " #F ": * and / match the reference") {                                       \
    check_binary<vectors::F>(#F "_mul", vectors::F##_mul, [](auto a, auto b) { return a * b; }); \
    check_binary<vectors::F>(#F "_div", vectors::F##_div, [](auto a, auto b) { return a / b; }); \
  }

KINCAL_SAME_FORMAT_TABLES(q3_4)
KINCAL_SAME_FORMAT_TABLES(q15)
KINCAL_SAME_FORMAT_TABLES(uq8_8)
KINCAL_SAME_FORMAT_TABLES(q24_8)
KINCAL_SAME_FORMAT_TABLES(q16_16)
KINCAL_SAME_FORMAT_TABLES(q31)
KINCAL_SAME_FORMAT_TABLES(q32_0)
KINCAL_MUL_DIV_TABLES(q3_4)
KINCAL_MUL_DIV_TABLES(q15)
KINCAL_MUL_DIV_TABLES(uq8_8)
KINCAL_MUL_DIV_TABLES(q24_8)
KINCAL_MUL_DIV_TABLES(q16_16)
KINCAL_MUL_DIV_TABLES(q31)
KINCAL_MUL_DIV_TABLES(q32_0)

TEST_CASE("fixed_cast rounds and saturates as the reference does") {
  using namespace vectors;
  check_cast<vectors::q16_16, vectors::q24_8>("q16_16->q24_8", cast_q16_16_to_q24_8);
  check_cast<vectors::q24_8, vectors::q16_16>("q24_8->q16_16", cast_q24_8_to_q16_16);
  check_cast<vectors::q16_16, vectors::q15>("q16_16->q15", cast_q16_16_to_q15);
  check_cast<vectors::q15, vectors::q16_16>("q15->q16_16", cast_q15_to_q16_16);
  check_cast<vectors::q15, vectors::uq8_8>("q15->uq8_8", cast_q15_to_uq8_8);
  check_cast<vectors::uq8_8, vectors::q16_16>("uq8_8->q16_16", cast_uq8_8_to_q16_16);
  check_cast<vectors::q31, vectors::q15>("q31->q15", cast_q31_to_q15);
  check_cast<vectors::q16_16, vectors::q31>("q16_16->q31", cast_q16_16_to_q31);
  check_cast<vectors::q3_4, vectors::q32_0>("q3_4->q32_0", cast_q3_4_to_q32_0);
}

TEST_CASE("mixed-format mul and div round once, as the reference does") {
  using V = vectors::q16_16;
  check_mixed<V, vectors::q15, vectors::q24_8>("mul q15*q24_8->q16_16", vectors::mul_q15_q24_8_to_q16_16,
                                               [](auto a, auto b) { return mul<vectors::q16_16>(a, b); });
  check_mixed<vectors::uq8_8, vectors::uq8_8, vectors::q15>("mul uq8_8*q15->uq8_8", vectors::mul_uq8_8_q15_to_uq8_8,
                                                            [](auto a, auto b) { return mul<vectors::uq8_8>(a, b); });
  check_mixed<vectors::q31, vectors::q15, vectors::q15>("mul q15*q15->q31", vectors::mul_q15_q15_to_q31,
                                                        [](auto a, auto b) { return mul<vectors::q31>(a, b); });
  check_mixed<vectors::q32_0, V, V>("mul q16_16*q16_16->q32_0", vectors::mul_q16_16_q16_16_to_q32_0,
                                    [](auto a, auto b) { return mul<vectors::q32_0>(a, b); });
  check_mixed<V, vectors::q24_8, vectors::q24_8>("div q24_8/q24_8->q16_16", vectors::div_q24_8_q24_8_to_q16_16,
                                                 [](auto a, auto b) { return div<vectors::q16_16>(a, b); });
  check_mixed<vectors::q15, V, V>("div q16_16/q16_16->q15", vectors::div_q16_16_q16_16_to_q15,
                                  [](auto a, auto b) { return div<vectors::q15>(a, b); });
  check_mixed<vectors::q24_8, vectors::q15, V>("div q15/q16_16->q24_8", vectors::div_q15_q16_16_to_q24_8,
                                               [](auto a, auto b) { return div<vectors::q24_8>(a, b); });
  check_mixed<vectors::q32_0, V, vectors::q3_4>("div q16_16/q3_4->q32_0", vectors::div_q16_16_q3_4_to_q32_0,
                                                [](auto a, auto b) { return div<vectors::q32_0>(a, b); });
}

TEST_CASE("every q3_4 operation over all operand pairs matches the reference digest") {
  using T = vectors::q3_4;
  std::uint32_t crc = 0;
  for (int a = -128; a <= 127; ++a)
    for (int b = -128; b <= 127; ++b) crc = crc_same_format_ops(crc, raw_of<T>(a), raw_of<T>(b));
  CHECK(crc == vectors::kExhaustiveQ3_4Crc);
}

TEST_CASE("random q16_16 operations match the reference digest") {
  std::uint64_t state = vectors::kRandomSeed;
  std::uint32_t crc = 0;
  for (int i = 0; i < vectors::kRandomCount; ++i) {
    const q16_16 a = random_q16_16(splitmix64(state));
    const q16_16 b = random_q16_16(splitmix64(state));
    crc = crc_same_format_ops(crc, a, b);
  }
  CHECK(crc == vectors::kRandomQ16_16Crc);
}

TEST_CASE("the rules hold at compile time too") {
  static_assert(q16_16::from_double(1.5).raw() == 0x18000);
  static_assert(q16_16::from_double(-0.5 / 65536.0).raw() == -1);  // tie away from zero
  static_assert((q16_16::highest() + q16_16::epsilon()) == q16_16::highest());
  static_assert(-q15::lowest() == q15::highest());
  static_assert(uq8_8::from_int(3) - uq8_8::from_int(4) == uq8_8::from_raw(0));
  static_assert(q16_16::from_int(1) / q16_16::from_int(0) == q16_16::highest());
  static_assert(q16_16::from_int(-1) / q16_16::from_int(0) == q16_16::lowest());
  static_assert(q24_8::from_int(1) < q24_8::from_int(2));
  static_assert(q16_16::from_int(40000) == q16_16::highest());
  static_assert(q16_16::from_int(-(std::int64_t{1} << 62)) == q16_16::lowest());
  CHECK(isqrt_round(0) == 0);
  CHECK(isqrt_round(2) == 1);
  CHECK(isqrt_round(3) == 2);
  CHECK(isqrt_round(~std::uint64_t{0}) == (std::uint64_t{1} << 32));
  CHECK(isqrt_round(std::uint64_t{1} << 62) == (std::uint64_t{1} << 31));
}
