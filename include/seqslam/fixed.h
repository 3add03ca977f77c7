// Strong fixed-point types: the Q format is part of the type.
//
// Fixed<Rep, F> stores value * 2^F in the integer Rep. Names follow the usual Q notation:
// Q15_16 is a signed 32-bit value with 15 integer bits, 16 fraction bits and a sign bit;
// UQ16_16 is its unsigned cousin. There is no conversion from or to floating point: constants
// are written as exact ratios (from_ratio(532, 1000)) and evaluated at compile time.
//
// Scaling and overflow behaviour (every routine here):
// - operator+ / operator- saturate to the range of Rep (never wrap, never UB).
// - from_int / from_ratio saturate; from_ratio rounds to nearest, ties away from zero.
// - mul_sat<R>(a, b) forms the exact product in 64 bits (128 for 64-bit reps), rounds to the
//   fraction bits of R to nearest (ties away from zero) and saturates to R.
// - narrow_sat<R>(a) re-scales to R's fraction bits with the same rounding and saturation.
#pragma once

#include <stdint.h>

#include "seqslam/wide_int.h"

namespace seqslam {

namespace detail {

template <typename T>
struct IntTraits;
template <>
struct IntTraits<int16_t> {
  static constexpr bool kSigned = true;
  static constexpr int64_t kMin = -32768;
  static constexpr int64_t kMax = 32767;
};
template <>
struct IntTraits<uint16_t> {
  static constexpr bool kSigned = false;
  static constexpr int64_t kMin = 0;
  static constexpr int64_t kMax = 65535;
};
template <>
struct IntTraits<int32_t> {
  static constexpr bool kSigned = true;
  static constexpr int64_t kMin = -2147483647 - 1;
  static constexpr int64_t kMax = 2147483647;
};
template <>
struct IntTraits<uint32_t> {
  static constexpr bool kSigned = false;
  static constexpr int64_t kMin = 0;
  static constexpr int64_t kMax = 4294967295;
};
template <>
struct IntTraits<int64_t> {
  static constexpr bool kSigned = true;
  static constexpr int64_t kMin = -9223372036854775807 - 1;
  static constexpr int64_t kMax = 9223372036854775807;
};

// Saturate a 128-bit value into Rep's range.
template <typename Rep>
constexpr Rep saturate(Int128 v) {
  if (v < Int128(IntTraits<Rep>::kMin)) return static_cast<Rep>(IntTraits<Rep>::kMin);
  if (v > Int128(IntTraits<Rep>::kMax)) return static_cast<Rep>(IntTraits<Rep>::kMax);
  return static_cast<Rep>(v.low64());
}

// round(v / 2^shift), ties away from zero; shift may be negative (then a left shift).
constexpr Int128 shift_round(Int128 v, int shift) {
  if (shift <= 0) return v.shl(-shift);
  const Int128 half = Int128(1).shl(shift - 1);
  if (v.negative()) return -((-v + half).sar(shift));
  return (v + half).sar(shift);
}

}  // namespace detail

template <typename Rep, int F>
class Fixed {
 public:
  using rep = Rep;
  static constexpr int kFracBits = F;
  static_assert(F >= 0 && F < 64, "fraction bits out of range");

  constexpr Fixed() = default;

  // The raw integer holds value * 2^F.
  static constexpr Fixed from_raw(Rep raw) {
    Fixed f;
    f.raw_ = raw;
    return f;
  }
  // value = v (saturating).
  static constexpr Fixed from_int(int64_t v) {
    return from_raw(detail::saturate<Rep>(Int128(v).shl(F)));
  }
  // value = num / den, rounded to nearest (ties away from zero), saturating. den != 0.
  static constexpr Fixed from_ratio(int64_t num, int64_t den) {
    Int128 n = Int128(num).shl(F);
    Int128 d(den);
    if (d.negative()) {
      n = -n;
      d = -d;
    }
    const Int128 half = d.sar(1);
    const Int128 q = n.negative() ? -((-n + half).div(d)) : (n + half).div(d);
    return from_raw(detail::saturate<Rep>(q));
  }
  static constexpr Fixed max() { return from_raw(static_cast<Rep>(detail::IntTraits<Rep>::kMax)); }
  static constexpr Fixed min() { return from_raw(static_cast<Rep>(detail::IntTraits<Rep>::kMin)); }

  constexpr Rep raw() const { return raw_; }
  // The integer part, rounded towards minus infinity.
  constexpr int64_t floor_int() const { return Int128(raw_).sar(F).low64_signed(); }
  // The nearest integer, ties away from zero.
  constexpr int64_t round_int() const {
    return detail::shift_round(Int128(raw_), F).low64_signed();
  }

  friend constexpr bool operator==(Fixed a, Fixed b) { return a.raw_ == b.raw_; }
  friend constexpr bool operator!=(Fixed a, Fixed b) { return a.raw_ != b.raw_; }
  friend constexpr bool operator<(Fixed a, Fixed b) { return a.raw_ < b.raw_; }
  friend constexpr bool operator<=(Fixed a, Fixed b) { return a.raw_ <= b.raw_; }
  friend constexpr bool operator>(Fixed a, Fixed b) { return a.raw_ > b.raw_; }
  friend constexpr bool operator>=(Fixed a, Fixed b) { return a.raw_ >= b.raw_; }

  // Saturating addition and subtraction.
  friend constexpr Fixed operator+(Fixed a, Fixed b) {
    return from_raw(detail::saturate<Rep>(Int128(a.raw_) + Int128(b.raw_)));
  }
  friend constexpr Fixed operator-(Fixed a, Fixed b) {
    return from_raw(detail::saturate<Rep>(Int128(a.raw_) - Int128(b.raw_)));
  }
  // Saturating negation (the most negative value maps to the most positive).
  constexpr Fixed operator-() const { return from_raw(detail::saturate<Rep>(-Int128(raw_))); }

 private:
  Rep raw_ = 0;
};

// Multiply two fixed-point values into the format R: exact product, round to nearest (ties
// away from zero), saturate.
template <typename R, typename RepA, int FA, typename RepB, int FB>
constexpr R mul_sat(Fixed<RepA, FA> a, Fixed<RepB, FB> b) {
  const Int128 p = Int128(a.raw()) * Int128(b.raw());
  return R::from_raw(
      detail::saturate<typename R::rep>(detail::shift_round(p, FA + FB - R::kFracBits)));
}

// Re-scale into the format R, rounding to nearest (ties away from zero) and saturating.
template <typename R, typename Rep, int F>
constexpr R narrow_sat(Fixed<Rep, F> a) {
  return R::from_raw(
      detail::saturate<typename R::rep>(detail::shift_round(Int128(a.raw()), F - R::kFracBits)));
}

// a / b into the format R, rounded to nearest (ties away from zero), saturating. b must not
// be zero; a zero divisor saturates towards the sign of a (0 / 0 gives 0).
template <typename R, typename RepA, int FA, typename RepB, int FB>
constexpr R div_sat(Fixed<RepA, FA> a, Fixed<RepB, FB> b) {
  if (b.raw() == 0) {
    if (a.raw() == 0) return R::from_raw(0);
    return a.raw() > 0 ? R::max() : R::min();
  }
  // value = (a.raw / 2^FA) / (b.raw / 2^FB) = a.raw * 2^(FB - FA) / b.raw; in R: * 2^FR.
  const int shift = R::kFracBits + FB - FA;
  Int128 n = Int128(a.raw());
  Int128 d = Int128(b.raw());
  if (shift >= 0) {
    n = n.shl(shift);
  } else {
    d = d.shl(-shift);
  }
  if (d.negative()) {
    n = -n;
    d = -d;
  }
  const Int128 half = d.sar(1);
  const Int128 q = n.negative() ? -((-n + half).div(d)) : (n + half).div(d);
  return R::from_raw(detail::saturate<typename R::rep>(q));
}

// The formats used across the library. Each alias says what it is for.
using Q15_16 = Fixed<int32_t, 16>;    // general signed values, e.g. metres for reports
using UQ16_16 = Fixed<uint32_t, 16>;  // confidence scores and thresholds, ratios >= 0
using Q1_30 = Fixed<int32_t, 30>;     // sine and cosine, in [-1, 1]
using Q31_32 = Fixed<int64_t, 32>;    // lengths in metres: poses and wheel constants
using UQ8_8 = Fixed<uint16_t, 8>;     // grey levels with fraction (PN epsilon and gain, sigma_min)
using UQ5_11 = Fixed<uint16_t, 11>;   // normalised differences (z-scores shifted positive)

}  // namespace seqslam
