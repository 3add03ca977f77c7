// Shared arithmetic of the pose graph's two translation units (pose_graph.cpp: LAGO and the
// state machine; pose_graph_refine.cpp: the nonlinear finish, linked only by images that call
// PoseGraph::enable_refine()). Internal: not part of the public headers.
#pragma once

#include <stdint.h>

#include "seqslam/pose_graph.h"

namespace seqslam::pose_graph_detail {

constexpr int64_t kInt64Max = 9223372036854775807;
constexpr int64_t kInt64Min = -kInt64Max - 1;

inline int64_t add_sat(int64_t a, int64_t b) {
  int64_t r = 0;
  if (__builtin_add_overflow(a, b, &r)) return a < 0 ? kInt64Min : kInt64Max;
  return r;
}
inline int64_t sub_sat(int64_t a, int64_t b) {
  int64_t r = 0;
  if (__builtin_sub_overflow(a, b, &r)) return a < 0 ? kInt64Min : kInt64Max;
  return r;
}

// round(v * m / 2^shift), ties away from zero, saturating; shift 0..127. The inner operation
// of every pass, so it avoids the general 128-bit routines: |v| m is a 96-bit value formed
// from two 32x32-bit products (RV32's mul/mulhu pairs), kept as hi * 2^32 + lo32, and shifted
// in two 64-bit words.
inline int64_t mul_u32_shift(int64_t v, uint32_t m, int shift) {
  const bool negative = v < 0;
  const uint64_t a = negative ? 0 - static_cast<uint64_t>(v) : static_cast<uint64_t>(v);
  const uint64_t low = (a & 0xFFFFFFFFu) * m;
  const uint64_t hi = (a >> 32) * m + (low >> 32);  // (a >> 32) <= 2^31: no overflow
  const uint64_t lo32 = low & 0xFFFFFFFFu;
  uint64_t q = 0;
  uint64_t half = 0;     // bit shift - 1 of the product: round half away from zero
  if (m == 0) return 0;  // beta = 0 after a restart
  if (shift == 0) {
    if ((hi >> 31) != 0) return negative ? kInt64Min : kInt64Max;
    q = (hi << 32) | lo32;
  } else if (shift < 32) {
    if ((hi >> (31 + shift)) != 0) return negative ? kInt64Min : kInt64Max;  // >= 2^63
    q = (hi << (32 - shift)) | (lo32 >> shift);
    half = (lo32 >> (shift - 1)) & 1u;
  } else if (shift < 96) {
    q = shift == 32 ? hi : hi >> (shift - 32);
    half = shift == 32 ? (lo32 >> 31) & 1u : (hi >> (shift - 33)) & 1u;
  }
  q += half;
  if (q > static_cast<uint64_t>(kInt64Max)) return negative ? kInt64Min : kInt64Max;
  return negative ? -static_cast<int64_t>(q) : static_cast<int64_t>(q);
}

// acc += a * b, exact (the 64x64-bit product from four 32x32-bit ones).
inline void multiply_add(Int128* acc, int64_t a, int64_t b) {
  const uint64_t ua = a < 0 ? 0 - static_cast<uint64_t>(a) : static_cast<uint64_t>(a);
  const uint64_t ub = b < 0 ? 0 - static_cast<uint64_t>(b) : static_cast<uint64_t>(b);
  const Int128 p = Int128::mul_u64(ua, ub);
  *acc = (a < 0) != (b < 0) ? *acc - p : *acc + p;
}

// Weight (UQ16.16) times a vector element.
inline int64_t weigh(int64_t v, uint32_t w) {
  return mul_u32_shift(v, w, 16);
}

// A signed weight (Q15.16) times a vector element.
inline int64_t weigh_signed(int64_t v, int32_t w) {
  const int64_t m =
      mul_u32_shift(v, w < 0 ? 0u - static_cast<uint32_t>(w) : static_cast<uint32_t>(w), 16);
  return w < 0 ? -m : m;
}

// A vector element times a sine or cosine (Q1.30, |c| <= 2^30).
inline int64_t mul_q30(int64_t v, Q1_30 c) {
  const int32_t raw = c.raw();
  const int64_t m =
      mul_u32_shift(v, raw < 0 ? 0u - static_cast<uint32_t>(raw) : static_cast<uint32_t>(raw), 30);
  return raw < 0 ? -m : m;
}

inline int bit_length(Int128 v) {
  if (v.high64() != 0) return 128 - __builtin_clzll(v.high64());
  if (v.low64() == 0) return 0;
  return 64 - __builtin_clzll(v.low64());
}

// Rotation of an edge's Q7.24 step by a heading, into Q31.32: round((c dx - s dy) / 2^22) etc.
// Shared by add_node (placing a new node) and the residuals, so a freshly added leaf has a
// residual of exactly zero.
inline int64_t rotate_x(SinCos sc, const PoseGraphEdge& e) {
  const int64_t v = static_cast<int64_t>(sc.cos.raw()) * e.dx.raw() -
                    static_cast<int64_t>(sc.sin.raw()) * e.dy.raw();
  return (v + (int64_t{1} << 21)) >> 22;
}
inline int64_t rotate_y(SinCos sc, const PoseGraphEdge& e) {
  const int64_t v = static_cast<int64_t>(sc.sin.raw()) * e.dx.raw() +
                    static_cast<int64_t>(sc.cos.raw()) * e.dy.raw();
  return (v + (int64_t{1} << 21)) >> 22;
}

// round(v / 2^shift) (ties up), shift 1..62, without the overflow of adding the half first.
inline int64_t shift_round_i64(int64_t v, int shift) {
  return (v >> shift) + ((v >> (shift - 1)) & 1);
}

// Q31.32 to Q7.24 (rounded); false if it does not fit.
inline bool to_q7_24(Q31_32 v, Q7_24* out) {
  const Int128 r = detail::shift_round(Int128(v.raw()), 8);
  if (r < Int128(-2147483647 - 1) || r > Int128(2147483647)) return false;
  *out = Q7_24::from_raw(static_cast<int32_t>(r.low64_signed()));
  return true;
}

// A lower bound on the smallest eigenvalue of [[a, c], [c, l]] (UQ16.16 raw, c signed), raw
// units; <= 0 if the matrix is not positive definite. (a + l - sqrt((a - l)^2 + 4 c^2)) / 2
// with the square root rounded up.
inline int64_t smallest_eigenvalue(uint32_t a, uint32_t l, int32_t c) {
  if (c == 0) return a < l ? a : l;
  const int64_t d = static_cast<int64_t>(a) - static_cast<int64_t>(l);
  const uint64_t ud = static_cast<uint64_t>(d < 0 ? -d : d);
  const uint64_t uc = static_cast<uint64_t>(c < 0 ? -static_cast<int64_t>(c) : c);
  const Int128 disc = Int128::mul_u64(ud, ud) + Int128::mul_u64(2 * uc, 2 * uc);  // < 2^67
  // sqrt(disc) <= 4 sqrt(disc / 16 + 1) <= 4 (isqrt(disc / 16 + 1) + 1)
  const uint64_t q = disc.sar(4).low64() + 1;
  const uint64_t root = 4 * (static_cast<uint64_t>(isqrt64(q)) + 1);
  return (static_cast<int64_t>(a) + static_cast<int64_t>(l) - static_cast<int64_t>(root)) / 2;
}

// 1 / info in UQ8.24, rounded up, so that the chain preconditioner never exceeds the chain's
// part of the system matrix (the stopping bound needs M <= L). Odometry steps are below
// 128 * sqrt(2) m, so info >= 1/182 and the variance fits; 24 fraction bits keep the
// preconditioner within 2^-24 of the chain, where UQ16.16 cost an extra CG iteration per stage.
inline uint32_t variance_of(uint32_t info_raw) {
  const uint64_t one = uint64_t{1} << 40;
  return static_cast<uint32_t>((one + info_raw - 1) / info_raw);
}

// Variance (UQ8.24) times a vector element.
inline int64_t spread(int64_t v, uint32_t var) {
  return mul_u32_shift(v, var, 24);
}

// The CG vectors' limit: any stored value of larger magnitude is an overflow (overflow_). With
// every vector element and every edge term below 2^53, each of the at most 3 x 65535 products
// of an inner product is below 2^106, so the 128-bit sums cannot wrap; and the saturating
// operations (which clip at 2^63) are always caught, never taken for values.
constexpr int64_t kVectorLimit = int64_t{1} << 53;
// Coarsest scale (bits dropped from the CG vectors) before a graph is refused: beyond it a
// rounded residual step is 2^48 raw units, far above any tolerance.
constexpr uint32_t kMaxScale = 48;
// An estimate or edge residual of this magnitude (2^-32 m units: 2^30 m) is beyond the limits.
constexpr int64_t kEstimateLimit = int64_t{1} << 62;

// checked() inside a pass: the high words of the magnitudes OR-ed into the pass's own `peak`
// (a register), added to PoseGraph::peak_ once at the pass's end (peak_ |= peak << 32), so a
// value at or beyond 2^53 is caught at the same scalar step as before, for three instructions
// on RV32 instead of a call. (The low words only matter below 2^32, far under the limit; the
// rescale's choice of bits reads only bits above 51.)
inline int64_t mark(uint32_t* peak, int64_t v) {
  *peak |= static_cast<uint32_t>(static_cast<uint64_t>(v ^ (v >> 63)) >> 32);
  return v;
}

inline int64_t abs_i64(int64_t v) {
  return v < 0 ? -v : v;  // callers pass values above kInt64Min
}

// round(v / 2^shift), shift 0..62 (v above -2^63).
inline int64_t shift_down(int64_t v, uint32_t shift) {
  return shift == 0 ? v : shift_round_i64(v, static_cast<int>(shift));
}

// round(a * b / 2^32), saturating (the 128-bit product of two int64).
inline int64_t mul_q32(int64_t a, int64_t b) {
  const uint64_t ua = a < 0 ? 0 - static_cast<uint64_t>(a) : static_cast<uint64_t>(a);
  const uint64_t ub = b < 0 ? 0 - static_cast<uint64_t>(b) : static_cast<uint64_t>(b);
  const Int128 p = detail::shift_round(Int128::mul_u64(ua, ub), 32);
  if (p.high64() != 0 || (p.low64() >> 63) != 0) return (a < 0) != (b < 0) ? kInt64Min : kInt64Max;
  const int64_t m = static_cast<int64_t>(p.low64());
  return (a < 0) != (b < 0) ? -m : m;
}

// Radians in 2^-32 units to Q0.64 turns (x 2^32 / (2 pi)), modulo a turn: exact wrapping.
inline uint64_t radians_to_turns(int64_t v) {
  constexpr uint64_t kTurnsPerRadian = 683565276;  // round(2^32 / (2 pi))
  const uint64_t u = v < 0 ? 0 - static_cast<uint64_t>(v) : static_cast<uint64_t>(v);
  const uint64_t t = Int128::mul_u64(u, kTurnsPerRadian).low64();
  return v < 0 ? 0 - t : t;
}

// A Q0.64 turn difference (signed, the short way round) to radians in 2^-32 units: x 2 pi
// 2^-32, i.e. x round(2 pi 2^29) / 2^61. |result| <= pi 2^32.
inline int64_t turns_to_radians(int64_t v) {
  constexpr uint32_t kTwoPiQ29 = 3373259426u;
  return mul_u32_shift(v, kTwoPiQ29, 61);
}

// a <= b for values at scales sa and sb (true values a 2^(2 sa), b 2^(2 sb)).
inline bool scaled_le(Int128 a, uint32_t sa, Int128 b, uint32_t sb) {
  if (sa >= sb) return a <= b.sar(static_cast<int>(2 * (sa - sb)));
  return a.sar(static_cast<int>(2 * (sb - sa))) <= b;
}

}  // namespace seqslam::pose_graph_detail
