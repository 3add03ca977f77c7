// Local normalisation of a difference vector (2025 thesis eq. 4.6) with an online-valid
// positive offset.
//
// For a query, the raw differences d(j) to the library places j = 0..n-1 are normalised
// against a sliding window of library places around j:
//
//   window(j) = [j - h, j + h] clipped to [0, n-1],   h = floor(W / 2)
//   z(j)      = (d(j) - mean_window) / max(std_window, sigma_min)     (population std)
//   D+(j)     = z(j) + B,   B = sqrt(W) rounded down to 1/2048
//
// Why "+ B" (docs/normalisation.md has the full argument): the sequence costs must be positive
// for the confidence ratio (eq. 4.16) to mean anything. The batch tools shift the whole matrix
// by its global minimum, which a robot never sees. But a z-score of one sample within a window
// of m samples that contains it can never be below -sqrt(m - 1) (equality when all others are
// equal), and m - 1 <= W. So z + sqrt(W) is >= 0 for every row, every j, at every time, without
// looking at any other row: costs are positive by construction, bounded by S * 2 sqrt(W), and a
// constant offset per term leaves argmin unchanged. No clamping is ever active (except the
// rounding of the fixed-point value at exactly -B).
//
// W = 0 switches normalisation off (the thesis's "W = 0" baseline): D+(j) = MAD(j) / 8, the
// mean absolute difference in units of 8 grey levels, which is positive anyway.
//
// Number format: D+ is UQ5.11 (uint16, 1/2048 of a standard deviation). Inputs are SAD units
// (see difference.h) of images with `pixels` pixels.
//
// Arithmetic: window sums are exact integers (s1 < 2^30, s2 < 2^52 in uint64). The standard
// deviation is the exact integer square root of n^2 var, brought to 16 significant bits by an
// even shift; the z-score is one 32-bit rounded division. Against the double formula the
// error is below 2 LSB (tests/unit/test_normalise.cpp; measured 0.7 LSB).
#pragma once

#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/limits.h"
#include "seqslam/status.h"

namespace seqslam {

static_assert(kMaxWindow <= 255, "sqrt(W) must stay below 16 for UQ5.11 and int32 z-scores");

class LocalNormaliser {
 public:
  // window: W, 0 (off) or 2..kMaxWindow. sigma_min: grey levels (MAD), > 0 when W > 0.
  // pixels: image area A (1..kMaxPixels). Returns kOutOfRange for W == 1 or W > kMaxWindow or
  // pixels out of range, kInvalidArgument for sigma_min == 0 with W > 0.
  Status configure(uint16_t window, UQ8_8 sigma_min, uint32_t pixels);

  uint16_t window() const { return window_; }
  // B in UQ5.11.
  uint16_t offset_raw() const { return offset_; }

  // Calls f(j, D+(j)) for j = n-1 down to 0: the order in which the diagonal matcher updates
  // its costs in place. Inline so the matcher's loop keeps the window sums in registers.
  template <typename F>
  void for_each_descending(const uint32_t* d, uint32_t n, F&& f) const;

  // The same for j = hi down to lo only (lo <= hi < n): each D+(j) is exactly the value the
  // whole row would give, since place j's window [j - h, j + h] is clipped to [0, n - 1] as
  // there. Only d[max(0, lo - h) .. min(n - 1, hi + h)] is read, so a caller that knows the
  // differences of that band only may pass d offset so that the band's first place is index
  // 0 and n = the band's length, provided the band starts at place 0 or at lo - h and ends at
  // the row's last place or at hi + h (the windowed matcher's bands, window_matcher.h).
  template <typename F>
  void for_each_descending(const uint32_t* d, uint32_t n, uint32_t lo, uint32_t hi, F&& f) const;

  // Convenience for tools and tests: out[j] = D+(j) for the whole row.
  void normalise_row(const uint32_t* d, uint32_t n, uint16_t* out) const;

  // D+ of the difference dj whose (clipped) window holds `count` differences with sum s1 and
  // sum of squares s2: the streaming form (the relocalisation scan keeps the window sums of
  // each row itself, sequence_scan.h). Equal to what the row functions give for that window.
  uint16_t value_of(uint32_t dj, uint32_t count, uint32_t s1, uint64_t s2) const {
    if (window_ == 0) return static_cast<uint16_t>((dj * 256u + pixels_ / 2) / pixels_);
    const uint64_t fl = static_cast<uint64_t>(count * sigma_min_sad_);
    int32_t exponent = 0;
    uint32_t root = 1u << 15;
    return value(dj, count, s1, s2, fl * fl, exponent, root);
  }
  uint32_t half() const { return half_; }

 private:
  // D+ of value dj in a window of `count` values with sums s1, s2. `exponent` and `root` carry
  // the normalisation shift and square root from the neighbouring place as starting points;
  // the result does not depend on them.
  uint16_t value(uint32_t dj, uint32_t count, uint32_t s1, uint64_t s2, uint64_t floor_sq,
                 int32_t& exponent, uint32_t& root) const;

  uint16_t window_ = 50;
  uint16_t half_ = 25;
  uint16_t offset_ = 0;
  uint32_t pixels_ = 1;
  uint32_t sigma_min_sad_ = 1;
};

// ---- Inline implementation (hot path) ----

namespace detail {

// Brings v (> 0) into [2^30, 2^32) by an even shift: returns v * 2^-e and updates e, which
// comes in as the neighbouring place's exponent. The common case (the same e in 2..30) is a
// few 32-bit operations; anything else takes the general loop.
inline uint32_t normalise_variance(uint64_t v, int32_t& e) {
  const uint32_t hi = static_cast<uint32_t>(v >> 32);
  const uint32_t lo = static_cast<uint32_t>(v);
  if (e >= 2 && e <= 30 && (hi >> e) == 0) {
    const uint32_t s = (lo >> e) | (hi << (32 - e));
    if (s >= (1u << 30)) return s;
  }
  uint64_t scaled = e >= 0 ? (v >> e) : (v << -e);
  while (scaled >= (uint64_t{1} << 32)) {
    e += 2;
    scaled = e >= 0 ? (v >> e) : (v << -e);
  }
  while (scaled < (uint64_t{1} << 30)) {
    e -= 2;
    scaled = e >= 0 ? (v >> e) : (v << -e);
  }
  return static_cast<uint32_t>(scaled);
}

}  // namespace detail

inline uint16_t LocalNormaliser::value(uint32_t dj, uint32_t count, uint32_t s1, uint64_t s2,
                                       uint64_t floor_sq, int32_t& exponent, uint32_t& root) const {
  // n^2 var and n (d - mean), exact: count <= 256, s2 < 2^52, s1 < 2^30.
  uint64_t v = static_cast<uint64_t>(count) * s2 - static_cast<uint64_t>(s1) * s1;
  if (v < floor_sq) v = floor_sq;
  const int32_t num = static_cast<int32_t>(count * dj) - static_cast<int32_t>(s1);
  // sqrt(v / 2^e) then has 16 significant bits; the numerator is scaled by the same 2^(e/2).
  const uint32_t vs = detail::normalise_variance(v, exponent);
  const int32_t e = exponent;
  // floor(sqrt(vs)) by integer Newton: one step from any positive start lands at or above
  // the root, then the iterates fall strictly until they reach it. root is in [2^15, 2^16).
  uint32_t s = (root + vs / root) >> 1;
  for (;;) {
    const uint32_t t = (s + vs / s) >> 1;
    if (t >= s) break;
    s = t;
  }
  root = s;
  // |num| <= sqrt(m - 1) * sd <= sqrt(255) * sd < 15.97 * 2^16 after scaling, so
  // num * 2^11 (+ sd / 2 for rounding) stays below 2^31.
  const int32_t num_scaled = e >= 0 ? (num >> (e / 2)) : (num * (1 << (-e / 2)));
  const int32_t n2048 = num_scaled * 2048;
  const int32_t half = static_cast<int32_t>(s >> 1);
  const int32_t sd = static_cast<int32_t>(s);
  const int32_t z = n2048 >= 0 ? (n2048 + half) / sd : -((half - n2048) / sd);
  const int32_t out = z + offset_;
  return static_cast<uint16_t>(out < 0 ? 0 : (out > 65535 ? 65535 : out));
}

template <typename F>
void LocalNormaliser::for_each_descending(const uint32_t* d, uint32_t n, F&& f) const {
  if (n == 0) return;
  for_each_descending(d, n, 0, n - 1, static_cast<F&&>(f));
}

template <typename F>
void LocalNormaliser::for_each_descending(const uint32_t* d, uint32_t n, uint32_t lo, uint32_t hi,
                                          F&& f) const {
  if (n == 0 || lo > hi || hi >= n) return;
  if (window_ == 0) {
    // MAD / 8 in UQ5.11 = SAD * 2^11 / (8 A) = SAD * 256 / A; SAD * 256 < 2^30.
    for (uint32_t j = hi + 1; j-- > lo;) {
      f(j, static_cast<uint16_t>((d[j] * 256u + pixels_ / 2) / pixels_));
    }
    return;
  }
  const uint32_t h = half_;
  const uint32_t last = n - 1;
  uint32_t s1 = 0;
  uint64_t s2 = 0;
  const uint32_t first_in = hi >= h ? hi - h : 0;
  const uint32_t last_in = last - hi >= h ? hi + h : last;
  for (uint32_t k = first_in; k <= last_in; ++k) {
    s1 += d[k];
    s2 += static_cast<uint64_t>(d[k]) * d[k];
  }
  uint32_t count = last_in - first_in + 1;
  // (n sigma_min)^2 for the usual full window; recomputed only where the window is clipped.
  const uint32_t full = 2 * h + 1;
  const uint64_t full_floor = static_cast<uint64_t>(full * sigma_min_sad_);
  const uint64_t full_floor_sq = full_floor * full_floor;
  int32_t exponent = 0;
  uint32_t root = 1u << 15;
  for (uint32_t j = hi;; --j) {
    uint64_t floor_sq = full_floor_sq;
    if (count != full) {
      const uint64_t fl = static_cast<uint64_t>(count * sigma_min_sad_);
      floor_sq = fl * fl;
    }
    f(j, value(d[j], count, s1, s2, floor_sq, exponent, root));
    if (j == lo) break;
    // Slide the window from place j to place j - 1: place j - 1 - h enters, j + h leaves.
    const bool enters = j - 1 >= h;
    const bool leaves = j + h <= last;
    if (enters && leaves) {
      // in^2 - out^2 = (in - out)(in + out): one widening multiply instead of two.
      const uint32_t in = d[j - 1 - h];
      const uint32_t out = d[j + h];
      s1 += in - out;
      s2 += static_cast<uint64_t>(static_cast<int64_t>(static_cast<int32_t>(in - out)) *
                                  static_cast<int64_t>(in + out));
    } else if (enters) {
      const uint32_t in = d[j - 1 - h];
      s1 += in;
      s2 += static_cast<uint64_t>(in) * in;
      ++count;
    } else if (leaves) {
      const uint32_t out = d[j + h];
      s1 -= out;
      s2 -= static_cast<uint64_t>(out) * out;
      --count;
    }
  }
}

}  // namespace seqslam
