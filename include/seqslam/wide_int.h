// A small two's-complement 128-bit integer for intermediate products.
//
// RV32 has no 128-bit (nor native 64x64) arithmetic and the freestanding core cannot rely on
// __int128, so products of 64-bit fixed-point values and compile-time constant folding go
// through this type. Everything is constexpr. Division is bitwise long division (128 steps):
// use it for configuration and constants, never per pixel.
#pragma once

#include <stdint.h>

namespace seqslam {

class Int128 {
 public:
  constexpr Int128() = default;
  constexpr Int128(int64_t v)  // NOLINT: implicit widening is the point
      : hi_(v < 0 ? ~uint64_t{0} : 0), lo_(static_cast<uint64_t>(v)) {}
  static constexpr Int128 from_parts(uint64_t hi, uint64_t lo) {
    Int128 r;
    r.hi_ = hi;
    r.lo_ = lo;
    return r;
  }
  static constexpr Int128 from_u64(uint64_t v) { return from_parts(0, v); }

  constexpr bool negative() const { return (hi_ >> 63) != 0; }
  constexpr uint64_t high64() const { return hi_; }
  constexpr uint64_t low64() const { return lo_; }
  constexpr int64_t low64_signed() const { return static_cast<int64_t>(lo_); }

  friend constexpr Int128 operator+(Int128 a, Int128 b) {
    const uint64_t lo = a.lo_ + b.lo_;
    return from_parts(a.hi_ + b.hi_ + (lo < a.lo_ ? 1 : 0), lo);
  }
  constexpr Int128 operator-() const { return from_parts(~hi_, ~lo_) + Int128(1); }
  friend constexpr Int128 operator-(Int128 a, Int128 b) { return a + (-b); }

  friend constexpr bool operator==(Int128 a, Int128 b) { return a.hi_ == b.hi_ && a.lo_ == b.lo_; }
  friend constexpr bool operator!=(Int128 a, Int128 b) { return !(a == b); }
  friend constexpr bool operator<(Int128 a, Int128 b) {
    const int64_t ah = static_cast<int64_t>(a.hi_);
    const int64_t bh = static_cast<int64_t>(b.hi_);
    return ah < bh || (ah == bh && a.lo_ < b.lo_);
  }
  friend constexpr bool operator>(Int128 a, Int128 b) { return b < a; }
  friend constexpr bool operator<=(Int128 a, Int128 b) { return !(b < a); }
  friend constexpr bool operator>=(Int128 a, Int128 b) { return !(a < b); }

  // Left shift by 0..127 (bits shifted out are lost).
  constexpr Int128 shl(int n) const {
    if (n <= 0) return *this;
    if (n >= 128) return Int128();
    if (n >= 64) return from_parts(lo_ << (n - 64), 0);
    return from_parts((hi_ << n) | (lo_ >> (64 - n)), lo_ << n);
  }
  // Arithmetic right shift by 0..127 (rounds towards minus infinity).
  constexpr Int128 sar(int n) const {
    if (n <= 0) return *this;
    const uint64_t sign = negative() ? ~uint64_t{0} : 0;
    if (n >= 128) return from_parts(sign, sign);
    if (n >= 64) {
      const uint64_t lo = n == 64 ? hi_ : ((hi_ >> (n - 64)) | (sign << (128 - n)));
      return from_parts(sign, lo);
    }
    const uint64_t hi = (hi_ >> n) | (sign << (64 - n));
    return from_parts(hi, (lo_ >> n) | (hi_ << (64 - n)));
  }

  // Full signed product; the caller keeps the magnitudes below 2^127.
  friend constexpr Int128 operator*(Int128 a, Int128 b) {
    const bool neg = a.negative() != b.negative();
    const Int128 ua = a.negative() ? -a : a;
    const Int128 ub = b.negative() ? -b : b;
    // (ah*2^64 + al) * (bh*2^64 + bl) mod 2^128 = al*bl + (ah*bl + al*bh) * 2^64.
    const Int128 low = mul_u64(ua.lo_, ub.lo_);
    const uint64_t cross = ua.hi_ * ub.lo_ + ua.lo_ * ub.hi_;
    const Int128 r = from_parts(low.hi_ + cross, low.lo_);
    return neg ? -r : r;
  }

  // Quotient truncated towards zero; d must not be zero.
  constexpr Int128 div(Int128 d) const {
    const bool neg = negative() != d.negative();
    Int128 n = negative() ? -*this : *this;
    const Int128 den = d.negative() ? -d : d;
    Int128 q;
    Int128 r;
    for (int bit = 127; bit >= 0; --bit) {
      r = r.shl(1);
      if (n.bit(bit)) r = r + Int128(1);
      if (r >= den) {
        r = r - den;
        q = q + Int128(1).shl(bit);
      }
    }
    return neg ? -q : q;
  }

  // Unsigned 64 x 64 -> 128 product from 32-bit halves (what RV32's mul/mulhu provide).
  static constexpr Int128 mul_u64(uint64_t a, uint64_t b) {
    const uint64_t a0 = a & 0xFFFFFFFFu;
    const uint64_t a1 = a >> 32;
    const uint64_t b0 = b & 0xFFFFFFFFu;
    const uint64_t b1 = b >> 32;
    const uint64_t p00 = a0 * b0;
    const uint64_t p01 = a0 * b1;
    const uint64_t p10 = a1 * b0;
    const uint64_t p11 = a1 * b1;
    const uint64_t mid = (p00 >> 32) + (p01 & 0xFFFFFFFFu) + (p10 & 0xFFFFFFFFu);
    const uint64_t lo = (p00 & 0xFFFFFFFFu) | (mid << 32);
    const uint64_t hi = p11 + (p01 >> 32) + (p10 >> 32) + (mid >> 32);
    return from_parts(hi, lo);
  }

 private:
  constexpr bool bit(int i) const {
    return i >= 64 ? ((hi_ >> (i - 64)) & 1u) != 0 : ((lo_ >> i) & 1u) != 0;
  }

  uint64_t hi_ = 0;
  uint64_t lo_ = 0;
};

}  // namespace seqslam
