// Integer and fixed-point maths without floating point or libm.
#pragma once

#include <stdint.h>

#include "seqslam/fixed.h"

namespace seqslam {

// floor(sqrt(x)), exact for every input. Bitwise (digit-by-digit) method: 16 / 32 iterations
// of shifts, adds and compares; no multiply or divide.
uint32_t isqrt32(uint32_t x);
uint32_t isqrt64(uint64_t x);

// round(n / d) with ties away from zero, d > 0 (the caller guarantees it). Integer division
// in C++ truncates towards zero; image and statistics code needs the rounding of the double
// reference (std::round) to agree with it exactly. The magnitudes are divided unsigned: on
// RV32 a signed 64-bit division is a second libgcc routine (__divdi3, 1.1 KB of the head
// board's RAM) beside the unsigned one the matcher needs anyway.
constexpr int64_t div_round(int64_t n, int64_t d) {
  const uint64_t ud = static_cast<uint64_t>(d);
  const uint64_t magnitude = n >= 0 ? static_cast<uint64_t>(n) : 0u - static_cast<uint64_t>(n);
  const uint64_t q = (magnitude + ud / 2) / ud;
  return n >= 0 ? static_cast<int64_t>(q) : -static_cast<int64_t>(q);
}
constexpr uint32_t div_round_u32(uint32_t n, uint32_t d) {
  return (n + d / 2) / d;
}
// The 32-bit signed version (one divide instruction on RV32M, where the 64-bit one is a
// libgcc call). The caller keeps |n| + d / 2 below 2^31.
constexpr int32_t div_round_i32(int32_t n, int32_t d) {
  return n >= 0 ? (n + d / 2) / d : -((-n + d / 2) / d);
}

// An angle as a binary angle measure (BAM): a full turn is 2^32, so wrap-around at 360
// degrees is free and exact. 0 points along +x, angles grow counter-clockwise.
struct Angle {
  uint32_t bam = 0;

  // The angle num/den of a full turn (e.g. from_turn_ratio(1, 4) is 90 degrees), rounded.
  static constexpr Angle from_turn_ratio(int64_t num, int64_t den) {
    const Int128 v = Int128(num).shl(32);
    const Int128 half = Int128(den / 2);
    const Int128 q = v.negative() ? -((-v + half).div(Int128(den))) : (v + half).div(Int128(den));
    return Angle{static_cast<uint32_t>(q.low64())};
  }
  static constexpr Angle from_degrees(int64_t num, int64_t den = 1) {
    return from_turn_ratio(num, den * 360);
  }
  // Signed difference a - b in (-2^31, 2^31] BAM, i.e. the shorter way round.
  friend constexpr int32_t signed_diff(Angle a, Angle b) {
    return static_cast<int32_t>(a.bam - b.bam);
  }
  friend constexpr bool operator==(Angle a, Angle b) { return a.bam == b.bam; }
  friend constexpr bool operator!=(Angle a, Angle b) { return a.bam != b.bam; }
};

struct SinCos {
  Q1_30 sin;
  Q1_30 cos;
};

// Sine and cosine of a binary angle in Q1.30.
// Method: octant reduction to |theta| <= pi/4, then Taylor polynomials to theta^11 (sin) and
// theta^12 (cos) evaluated in unsigned Q0.32 (truncation term < 1e-11).
// Maximum error against the exact value: 1.0e-9 (about 2 LSB of Q1.30), verified over
// 2^20 + 1 angles spread over the full turn, the octant boundaries and their neighbours, by
// tests/unit/test_fixmath.cpp. sin and cos of multiples of 90 degrees are exact.
SinCos sincos(Angle a);

// Where the parabola through three equally spaced samples (l, c, r at -1, 0, +1) has its
// vertex, in Q15.16 raw units (2^-16 of a sample spacing): (l - r) / (2 (l - 2c + r)), rounded
// to nearest. For a minimum (c <= l and c <= r, not all equal) the result lies in
// [-1/2, 1/2]; a flat or non-convex triple (l - 2c + r <= 0) gives 0. The caller keeps
// |l - r| below 2^46 so the scaled numerator fits 64 bits. Used to refine a sampled minimum
// to a fraction of a step (subpixel_shift(), align_closure()).
int32_t parabola_vertex_q16(int64_t l, int64_t c, int64_t r);

// Product helpers for 64-bit fixed point on 32-bit cores: round(a * b / 2^shift), ties away
// from zero, saturating to int64, with a 128-bit intermediate so nothing overflows silently.
int64_t mul_shift_round(int64_t a, int64_t b, int shift);

}  // namespace seqslam
