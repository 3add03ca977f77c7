#include "seqslam/fixmath.h"

namespace seqslam {

namespace {

// Digit-by-digit square root: one result bit per iteration, shifts, adds and compares only.
template <typename T>
T isqrt_digits(T x) {
  T result = 0;
  T bit = T{1} << (sizeof(T) * 8 - 2);
  while (bit > x)
    bit >>= 2;
  while (bit != 0) {
    if (x >= result + bit) {
      x -= result + bit;
      result = (result >> 1) + bit;
    } else {
      result >>= 1;
    }
    bit >>= 2;
  }
  return result;
}

}  // namespace

uint32_t isqrt32(uint32_t x) {
  return isqrt_digits<uint32_t>(x);
}

int32_t parabola_vertex_q16(int64_t l, int64_t c, int64_t r) {
  const int64_t curvature = l - 2 * c + r;
  if (curvature <= 0) return 0;
  const int64_t q = div_round((l - r) * 65536, 2 * curvature);
  // Only a triple that is not a minimum can put the vertex beyond half a step; clamp so the
  // result always fits and stays between the neighbours.
  return static_cast<int32_t>(q > 65536 ? 65536 : (q < -65536 ? -65536 : q));
}

uint32_t isqrt64(uint64_t x) {
  // The 32-bit routine is much cheaper on RV32; use it whenever the value fits.
  if (x <= 0xFFFFFFFFu) return isqrt32(static_cast<uint32_t>(x));
  return static_cast<uint32_t>(isqrt_digits<uint64_t>(x));
}

namespace {

constexpr uint64_t kOneQ32 = uint64_t{1} << 32;
// round(pi / 4 * 2^32).
constexpr uint64_t kPiOver4Q32 = 3373259426u;

// round(a * b / 2^32) for Q0.32 operands no larger than 1.0 (a * b < 2^64 because the
// polynomial arguments below stay under 0.62 whenever the other factor can reach 1.0).
inline uint64_t mul_q32(uint64_t a, uint64_t b) {
  return (a * b + (uint64_t{1} << 31)) >> 32;
}

// One Horner level: 1 - t2 * inner / k, all Q0.32. k is a small constant so the division by
// it is a 32-bit division by a constant (a multiply-high on RV32IM).
inline uint64_t horner(uint64_t t2, uint64_t inner, uint32_t k) {
  const uint32_t p = static_cast<uint32_t>(mul_q32(t2, inner));
  return kOneQ32 - (p + k / 2) / k;
}

// Q0.32 to Q1.30 with rounding.
inline int32_t to_q30(uint64_t v) {
  return static_cast<int32_t>((v + 2) >> 2);
}

}  // namespace

SinCos sincos(Angle a) {
  const uint32_t octant = a.bam >> 29;
  uint32_t r = a.bam & ((1u << 29) - 1);
  if ((octant & 1u) != 0) r = (1u << 29) - r;  // odd octants: reflect, then swap below
  // t = r / 2^29 * pi/4, in Q0.32 (t <= pi/4 < 1).
  const uint64_t t = (static_cast<uint64_t>(r) * kPiOver4Q32 + (uint64_t{1} << 28)) >> 29;
  const uint64_t t2 = mul_q32(t, t);

  // sin t = t (1 - t^2/6 (1 - t^2/20 (1 - t^2/42 (1 - t^2/72 (1 - t^2/110))))).
  uint64_t s = horner(t2, kOneQ32, 110);
  s = horner(t2, s, 72);
  s = horner(t2, s, 42);
  s = horner(t2, s, 20);
  s = horner(t2, s, 6);
  s = mul_q32(t, s);
  // cos t = 1 - t^2/2 (1 - t^2/12 (1 - t^2/30 (1 - t^2/56 (1 - t^2/90 (1 - t^2/132))))).
  uint64_t c = horner(t2, kOneQ32, 132);
  c = horner(t2, c, 90);
  c = horner(t2, c, 56);
  c = horner(t2, c, 30);
  c = horner(t2, c, 12);
  c = horner(t2, c, 2);

  int32_t sin_v = to_q30(s);
  int32_t cos_v = to_q30(c);
  if ((octant & 1u) != 0) {
    const int32_t tmp = sin_v;
    sin_v = cos_v;
    cos_v = tmp;
  }
  SinCos out;
  switch (octant >> 1) {
    case 0:
      out = {Q1_30::from_raw(sin_v), Q1_30::from_raw(cos_v)};
      break;
    case 1:
      out = {Q1_30::from_raw(cos_v), Q1_30::from_raw(-sin_v)};
      break;
    case 2:
      out = {Q1_30::from_raw(-sin_v), Q1_30::from_raw(-cos_v)};
      break;
    default:
      out = {Q1_30::from_raw(-cos_v), Q1_30::from_raw(sin_v)};
      break;
  }
  return out;
}

int64_t mul_shift_round(int64_t a, int64_t b, int shift) {
  return detail::saturate<int64_t>(detail::shift_round(Int128(a) * Int128(b), shift));
}

}  // namespace seqslam
