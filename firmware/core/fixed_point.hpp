// Fixed-point numbers for the pixel path: the same bits on the Cortex-M4 and natively.
//
// A Fixed<Rep, F> holds the real value raw / 2^F in the integer `Rep`. The rules below are
// the whole contract; tests/firmware/core/fixed_point_test.cpp pins each one bit-exactly
// against an independent reference (fixed_point_reference.py, exact rational arithmetic),
// in the native test run and on the M4 under QEMU.
//
// Storage    Rep is a signed or unsigned integer of 8, 16 or 32 bits. Every intermediate is
//            computed in int64_t, where sums and products of two 32-bit operands are exact;
//            a format whose intermediate would not fit is rejected at compile time.
// Rounding   Whenever fraction bits are dropped (multiplication, division, casting to fewer
//            fraction bits, conversion from floating point, square root), the result is the
//            nearest representable value, ties away from zero. So round(-x) == -round(x):
//            symmetric data such as centroid offsets gets no drift toward -infinity.
// Overflow   Results outside [lowest(), highest()] saturate to the nearer end: never a wrap,
//            never undefined behaviour. Unsigned formats saturate negative results to 0.
// Division   by zero saturates: highest() for a dividend >= 0, lowest() for a negative one.
// Float in   NaN becomes 0; +-infinity and out-of-range values saturate.
// Float out  to_double() is exact; to_float() rounds to nearest-even (IEEE) when the raw
//            value has more than 24 significant bits.
// Mixing     Formats never mix implicitly: fixed_cast<To>(x), mul<To>(a, b), div<To>(a, b).
//
// Cost on the Cortex-M4 (no heap, no exceptions, constant time except division and sqrt):
// + and - a handful of instructions; * one SMULL plus rounding and saturation; / and sqrt
// a 64-bit division (__aeabi_ldivmod) or a 32-step loop: keep them off per-pixel paths.
#pragma once

#include <compare>
#include <cstdint>
#include <limits>
#include <type_traits>

namespace kincal::core {

namespace fixed_detail {

template <class Rep>
concept Storage =
    std::is_integral_v<Rep> && !std::is_same_v<Rep, bool> && (sizeof(Rep) == 1 || sizeof(Rep) == 2 || sizeof(Rep) == 4);

// Bits of magnitude an int64_t intermediate may use without overflow.
inline constexpr int kMagnitudeBits = 62;

template <class Rep>
inline constexpr int kWidth = std::numeric_limits<Rep>::digits;  // value bits, sign excluded

template <Storage Rep>
constexpr Rep saturate(std::int64_t v) noexcept {
  constexpr auto lo = static_cast<std::int64_t>(std::numeric_limits<Rep>::lowest());
  constexpr auto hi = static_cast<std::int64_t>(std::numeric_limits<Rep>::max());
  return static_cast<Rep>(v < lo ? lo : (v > hi ? hi : v));
}

// v / 2^shift rounded to nearest, ties away from zero. Requires 0 <= shift <= 62 and
// |v| < 2^62, which every caller guarantees by the static_asserts on its formats.
constexpr std::int64_t round_shift_right(std::int64_t v, int shift) noexcept {
  if (shift == 0) return v;
  const std::int64_t half = std::int64_t{1} << (shift - 1);
  return v >= 0 ? (v + half) >> shift : -((-v + half) >> shift);
}

// n / d rounded to nearest, ties away from zero; d == 0 saturates by the sign of n.
// Requires |n|, |d| < 2^62.
constexpr std::int64_t round_div(std::int64_t n, std::int64_t d) noexcept {
  if (d == 0) return n >= 0 ? std::numeric_limits<std::int64_t>::max() : std::numeric_limits<std::int64_t>::min();
  const bool negative = (n < 0) != (d < 0);
  const std::int64_t an = n < 0 ? -n : n;
  const std::int64_t ad = d < 0 ? -d : d;
  std::int64_t q = an / ad;
  if (2 * (an - q * ad) >= ad) ++q;
  return negative ? -q : q;
}

// v * 2^shift for shift of either sign, rounding when shift < 0.
constexpr std::int64_t rescale(std::int64_t v, int shift) noexcept {
  return shift >= 0 ? v * (std::int64_t{1} << shift) : round_shift_right(v, -shift);
}

}  // namespace fixed_detail

// round(sqrt(n)) for any 64-bit n, in at most 32 iterations (firmware/core/fixed_point.cpp).
std::uint64_t isqrt_round(std::uint64_t n) noexcept;

template <fixed_detail::Storage Rep, int F>
class Fixed {
  static_assert(F >= 0 && F <= 8 * static_cast<int>(sizeof(Rep)), "fraction bits must fit the storage");

 public:
  using rep = Rep;
  static constexpr int frac_bits = F;

  constexpr Fixed() noexcept = default;

  static constexpr Fixed from_raw(Rep raw) noexcept {
    Fixed x;
    x.raw_ = raw;
    return x;
  }
  static constexpr Fixed from_int(std::int64_t v) noexcept {
    // Clamp first so that the scaling below cannot overflow; the result saturates anyway.
    constexpr std::int64_t limit = std::int64_t{1} << (fixed_detail::kMagnitudeBits - F);
    const std::int64_t clamped = v < -limit ? -limit : (v > limit ? limit : v);
    return from_raw(fixed_detail::saturate<Rep>(clamped * (std::int64_t{1} << F)));
  }
  static constexpr Fixed from_double(double v) noexcept {
    if (v != v) return from_raw(0);  // NaN
    const double scaled = v * static_cast<double>(std::int64_t{1} << F);
    constexpr double lo = static_cast<double>(std::numeric_limits<Rep>::lowest());
    constexpr double hi = static_cast<double>(std::numeric_limits<Rep>::max());
    if (scaled <= lo - 0.5) return lowest();
    if (scaled >= hi + 0.5) return highest();
    // |scaled| < 2^33 here, so the truncation is defined and scaled - whole is exact.
    auto whole = static_cast<std::int64_t>(scaled);
    const double fraction = scaled - static_cast<double>(whole);
    if (fraction >= 0.5) ++whole;
    if (fraction <= -0.5) --whole;
    return from_raw(fixed_detail::saturate<Rep>(whole));
  }
  static constexpr Fixed from_float(float v) noexcept { return from_double(static_cast<double>(v)); }

  static constexpr Fixed lowest() noexcept { return from_raw(std::numeric_limits<Rep>::lowest()); }
  static constexpr Fixed highest() noexcept { return from_raw(std::numeric_limits<Rep>::max()); }
  static constexpr Fixed epsilon() noexcept { return from_raw(1); }  // one LSB = 2^-F

  constexpr Rep raw() const noexcept { return raw_; }
  constexpr double to_double() const noexcept {
    return static_cast<double>(raw_) / static_cast<double>(std::int64_t{1} << F);
  }
  constexpr float to_float() const noexcept {
    return static_cast<float>(raw_) / static_cast<float>(std::int64_t{1} << F);
  }

  friend constexpr bool operator==(Fixed, Fixed) noexcept = default;
  friend constexpr auto operator<=>(Fixed, Fixed) noexcept = default;

  friend constexpr Fixed operator+(Fixed a, Fixed b) noexcept {
    return from_raw(fixed_detail::saturate<Rep>(std::int64_t{a.raw_} + b.raw_));
  }
  friend constexpr Fixed operator-(Fixed a, Fixed b) noexcept {
    return from_raw(fixed_detail::saturate<Rep>(std::int64_t{a.raw_} - b.raw_));
  }
  friend constexpr Fixed operator-(Fixed a) noexcept {
    return from_raw(fixed_detail::saturate<Rep>(-std::int64_t{a.raw_}));
  }
  friend constexpr Fixed operator*(Fixed a, Fixed b) noexcept {
    static_assert(2 * fixed_detail::kWidth<Rep> <= fixed_detail::kMagnitudeBits, "product would not fit int64_t");
    const std::int64_t product = std::int64_t{a.raw_} * b.raw_;
    return from_raw(fixed_detail::saturate<Rep>(fixed_detail::round_shift_right(product, F)));
  }
  friend constexpr Fixed operator/(Fixed a, Fixed b) noexcept {
    static_assert(fixed_detail::kWidth<Rep> + F <= fixed_detail::kMagnitudeBits);
    const std::int64_t n = std::int64_t{a.raw_} * (std::int64_t{1} << F);
    return from_raw(fixed_detail::saturate<Rep>(fixed_detail::round_div(n, b.raw_)));
  }
  constexpr Fixed& operator+=(Fixed b) noexcept { return *this = *this + b; }
  constexpr Fixed& operator-=(Fixed b) noexcept { return *this = *this - b; }
  constexpr Fixed& operator*=(Fixed b) noexcept { return *this = *this * b; }
  constexpr Fixed& operator/=(Fixed b) noexcept { return *this = *this / b; }

 private:
  Rep raw_ = 0;
};

template <class T>
inline constexpr bool is_fixed_v = false;
template <class Rep, int F>
inline constexpr bool is_fixed_v<Fixed<Rep, F>> = true;
template <class T>
concept FixedPoint = is_fixed_v<T>;

// The formats the pixel path uses; the name says signedness, integer and fraction bits.
using q15 = Fixed<std::int16_t, 15>;     // [-1, 1): unit-range coefficients (colour weights)
using q31 = Fixed<std::int32_t, 31>;     // [-1, 1): unit-range coefficients, full precision
using uq8_8 = Fixed<std::uint16_t, 8>;   // [0, 256): pixel intensity with a fraction
using q24_8 = Fixed<std::int32_t, 8>;    // +-8.4e6: coordinates and sums with 1/256 resolution
using q16_16 = Fixed<std::int32_t, 16>;  // +-32768: sub-pixel positions, 1.5e-5 px resolution

// x in another format: rounded when fraction bits are dropped, saturated when out of range.
template <FixedPoint To, FixedPoint From>
constexpr To fixed_cast(From x) noexcept {
  constexpr int shift = To::frac_bits - From::frac_bits;
  static_assert(shift <= 0 || fixed_detail::kWidth<typename From::rep> + shift <= fixed_detail::kMagnitudeBits);
  return To::from_raw(fixed_detail::saturate<typename To::rep>(fixed_detail::rescale(x.raw(), shift)));
}

// a * b in format To, exact before the single rounding to To.
template <FixedPoint To, FixedPoint A, FixedPoint B>
constexpr To mul(A a, B b) noexcept {
  constexpr int shift = To::frac_bits - A::frac_bits - B::frac_bits;
  static_assert(
      fixed_detail::kWidth<typename A::rep> + fixed_detail::kWidth<typename B::rep> + (shift > 0 ? shift : 0) <=
          fixed_detail::kMagnitudeBits,
      "product would not fit int64_t");
  const std::int64_t product = std::int64_t{a.raw()} * b.raw();
  return To::from_raw(fixed_detail::saturate<typename To::rep>(fixed_detail::rescale(product, shift)));
}

// a / b in format To, with one rounding; b == 0 saturates by the sign of a.
template <FixedPoint To, FixedPoint A, FixedPoint B>
constexpr To div(A a, B b) noexcept {
  constexpr int shift = To::frac_bits + B::frac_bits - A::frac_bits;
  static_assert(shift >= 0 ? fixed_detail::kWidth<typename A::rep> + shift <= fixed_detail::kMagnitudeBits
                           : fixed_detail::kWidth<typename B::rep> - shift <= fixed_detail::kMagnitudeBits);
  const std::int64_t n = shift >= 0 ? std::int64_t{a.raw()} * (std::int64_t{1} << shift) : a.raw();
  const std::int64_t d = shift >= 0 ? b.raw() : std::int64_t{b.raw()} * (std::int64_t{1} << -shift);
  return To::from_raw(fixed_detail::saturate<typename To::rep>(fixed_detail::round_div(n, d)));
}

// sqrt(x) in x's format, rounded to nearest; negative x gives 0.
template <FixedPoint T>
T sqrt(T x) noexcept {
  static_assert(fixed_detail::kWidth<typename T::rep> + T::frac_bits <= 63);
  if (x.raw() <= 0) return T::from_raw(0);
  const auto n = static_cast<std::uint64_t>(x.raw()) << T::frac_bits;
  return T::from_raw(fixed_detail::saturate<typename T::rep>(static_cast<std::int64_t>(isqrt_round(n))));
}

}  // namespace kincal::core
