// SIMD sums of absolute differences for the host evaluation (seqslam_tools/sad_simd.h).
//
// Highway compiles this file once per x86 target (foreach_target.h re-includes it) and
// HWY_DYNAMIC_DISPATCH picks the best the CPU supports at the first call. Per 8 bytes the
// kernel forms |a - b| with two saturating subtractions and an OR, and SumsOf8 adds them
// (psadbw against zero on x86): 64-bit lanes that cannot overflow for any image size.
//
// Blocking: four query rows share each library vector load, and the library is walked in
// chunks of kChunkImages so a chunk stays in L1/L2 while every block of rows passes over it.
// Measured on `make bench-eval` (docs/seqslam_eval.md).

// AVX-512 is left out: on the AMD EPYC (Zen 4) this was measured on, the AVX3 build ran at
// 175 M image pairs/s against AVX2's 214 M (docs/seqslam_eval.md), as a 512-byte image is
// only eight 64-byte vectors and the horizontal sums dominate. AVX-512 CPUs run AVX2.
#ifndef HWY_DISABLED_TARGETS
#define HWY_DISABLED_TARGETS (HWY_AVX3 | HWY_AVX3_DL)
#endif
#undef HWY_TARGET_INCLUDE
#define HWY_TARGET_INCLUDE "sad_simd.cpp"
#include <hwy/foreach_target.h>  // must precede highway.h
#include <hwy/highway.h>

#include <algorithm>
#if HWY_ARCH_X86_64
#include <emmintrin.h>  // SSE2, the x86-64 baseline (the fallback target's kernel)
#endif

#include "seqslam_tools/sad_simd.h"

HWY_BEFORE_NAMESPACE();
namespace seqslam::tools::HWY_NAMESPACE {
namespace hn = hwy::HWY_NAMESPACE;

// Sums of |a - b| over each group of 8 bytes, in 64-bit lanes. Highway 1.0.3 (Debian 12)
// has no SumsOf8AbsDiff yet, so the portable form costs two saturating subtractions, an OR
// and psadbw against zero; on x86 psadbw takes the two operands directly (3x fewer
// operations), so the x86 vector types get it through Highway's raw registers.
template <class V>
HWY_INLINE auto SadPairs(V a, V b) {
  return hn::SumsOf8(hn::Or(hn::SaturatedSub(a, b), hn::SaturatedSub(b, a)));
}
#if HWY_ARCH_X86 && HWY_TARGET != HWY_SCALAR
HWY_INLINE hn::Vec128<uint64_t> SadPairs(hn::Vec128<uint8_t> a, hn::Vec128<uint8_t> b) {
  return hn::Vec128<uint64_t>{_mm_sad_epu8(a.raw, b.raw)};
}
#if HWY_TARGET <= HWY_AVX2
HWY_INLINE hn::Vec256<uint64_t> SadPairs(hn::Vec256<uint8_t> a, hn::Vec256<uint8_t> b) {
  return hn::Vec256<uint64_t>{_mm256_sad_epu8(a.raw, b.raw)};
}
#endif
#if HWY_TARGET <= HWY_AVX3
HWY_INLINE hn::Vec512<uint64_t> SadPairs(hn::Vec512<uint8_t> a, hn::Vec512<uint8_t> b) {
  return hn::Vec512<uint64_t>{_mm512_sad_epu8(a.raw, b.raw)};
}
#endif
#endif

template <class D64>
HWY_INLINE uint64_t Total(D64 d64, hn::Vec<D64> v) {
  return hn::GetLane(hn::SumOfLanes(d64, v));
}

// Adds the SADs of pixels [k, end) rounded down to whole vectors of D to sum[0..3] (the four
// query rows q[0..3] against img); returns the first pixel not done.
template <class D>
HWY_INLINE size_t Accumulate4(D d, size_t k, size_t end, const uint8_t* const* q,
                              const uint8_t* img, uint64_t* sum) {
  const hn::Repartition<uint64_t, D> d64;
  const size_t n = hn::Lanes(d);
  auto a0 = hn::Zero(d64);
  auto a1 = hn::Zero(d64);
  auto a2 = hn::Zero(d64);
  auto a3 = hn::Zero(d64);
  for (; k + n <= end; k += n) {
    const auto l = hn::LoadU(d, img + k);
    a0 = hn::Add(a0, SadPairs(hn::LoadU(d, q[0] + k), l));
    a1 = hn::Add(a1, SadPairs(hn::LoadU(d, q[1] + k), l));
    a2 = hn::Add(a2, SadPairs(hn::LoadU(d, q[2] + k), l));
    a3 = hn::Add(a3, SadPairs(hn::LoadU(d, q[3] + k), l));
  }
  // Each lane holds less than 2^32 (255 x 8 per vector x at most 2^21 vectors), so two rows
  // share one horizontal sum: row a in the low half of a 64-bit lane, row b in the high half.
  const uint64_t s01 = Total(d64, hn::Or(a0, hn::ShiftLeft<32>(a1)));
  const uint64_t s23 = Total(d64, hn::Or(a2, hn::ShiftLeft<32>(a3)));
  sum[0] += s01 & 0xFFFFFFFFu;
  sum[1] += s01 >> 32;
  sum[2] += s23 & 0xFFFFFFFFu;
  sum[3] += s23 >> 32;
  return k;
}

template <class D>
HWY_INLINE size_t Accumulate1(D d, size_t k, size_t end, const uint8_t* q, const uint8_t* img,
                              uint64_t* sum) {
  const hn::Repartition<uint64_t, D> d64;
  const size_t n = hn::Lanes(d);
  auto a = hn::Zero(d64);
  for (; k + n <= end; k += n)
    a = hn::Add(a, SadPairs(hn::LoadU(d, q + k), hn::LoadU(d, img + k)));
  *sum += Total(d64, a);
  return k;
}

inline uint32_t ScalarAbsDiff(uint8_t a, uint8_t b) {
  return a > b ? static_cast<uint32_t>(a - b) : static_cast<uint32_t>(b - a);
}

#if HWY_TARGET == HWY_SCALAR && HWY_ARCH_X86_64
// The fallback below SSSE3. Highway 1.0.3 has no SSE2 target, only a one-lane scalar one
// (measured 16x slower than the core's kernel), but SSE2 is part of x86-64 itself, so its
// psadbw is there on every CPU this target can be chosen on.
template <uint32_t kRows>
HWY_INLINE size_t Sse2Accumulate(size_t k, size_t end, const uint8_t* const* q, const uint8_t* img,
                                 uint64_t* sum) {
  __m128i acc[kRows];
#pragma GCC unroll 4
  for (uint32_t r = 0; r < kRows; ++r)
    acc[r] = _mm_setzero_si128();
  for (; k + 16 <= end; k += 16) {
    const __m128i l = _mm_loadu_si128(reinterpret_cast<const __m128i*>(img + k));
#pragma GCC unroll 4
    for (uint32_t r = 0; r < kRows; ++r) {
      const __m128i a = _mm_loadu_si128(reinterpret_cast<const __m128i*>(q[r] + k));
      acc[r] = _mm_add_epi64(acc[r], _mm_sad_epu8(a, l));
    }
  }
  for (uint32_t r = 0; r < kRows; ++r) {
    sum[r] += static_cast<uint64_t>(_mm_cvtsi128_si64(acc[r])) +
              static_cast<uint64_t>(_mm_cvtsi128_si64(_mm_unpackhi_epi64(acc[r], acc[r])));
  }
  return k;
}
#endif

// Rows may be 1 or 4 (4 shares each library load between four queries).
template <uint32_t kRows>
void SadBlock(const uint8_t* const* q, const uint8_t* library, uint32_t count, uint32_t pixels,
              uint32_t* const* out) {
  const hn::ScalableTag<uint8_t> full;
  const hn::CappedTag<uint8_t, 16> narrow;  // the tail after the last whole wide vector
  for (uint32_t j = 0; j < count; ++j) {
    const uint8_t* img = library + static_cast<size_t>(j) * pixels;
    uint64_t sum[kRows] = {};
    size_t k = 0;
#if HWY_TARGET == HWY_SCALAR && HWY_ARCH_X86_64
    k = Sse2Accumulate<kRows>(k, pixels, q, img, sum);
    (void)full;
    (void)narrow;
#else
    if constexpr (kRows == 4) {
      k = Accumulate4(full, k, pixels, q, img, sum);
      if (pixels - k >= 16) k = Accumulate4(narrow, k, pixels, q, img, sum);
    } else {
      k = Accumulate1(full, k, pixels, q[0], img, sum);
      if (pixels - k >= 16) k = Accumulate1(narrow, k, pixels, q[0], img, sum);
    }
#endif
    for (; k < pixels; ++k) {
      for (uint32_t r = 0; r < kRows; ++r)
        sum[r] += ScalarAbsDiff(q[r][k], img[k]);
    }
    for (uint32_t r = 0; r < kRows; ++r)
      out[r][j] = static_cast<uint32_t>(sum[r]);
  }
}

// Images per library chunk: 128 x 512 B = 64 KB at 32x16, inside every x86 L2.
constexpr uint32_t kChunkImages = 128;

static void SadRows(const uint8_t* queries, uint32_t rows, const uint8_t* library, uint32_t count,
                    uint32_t pixels, uint32_t* out, size_t out_stride) {
  for (uint32_t c0 = 0; c0 < count; c0 += kChunkImages) {
    const uint32_t n = std::min(kChunkImages, count - c0);
    const uint8_t* chunk = library + static_cast<size_t>(c0) * pixels;
    uint32_t r = 0;
    for (; r + 4 <= rows; r += 4) {
      const uint8_t* q[4];
      uint32_t* o[4];
      for (uint32_t i = 0; i < 4; ++i) {
        q[i] = queries + static_cast<size_t>(r + i) * pixels;
        o[i] = out + (r + i) * out_stride + c0;
      }
      SadBlock<4>(q, chunk, n, pixels, o);
    }
    for (; r < rows; ++r) {
      const uint8_t* q = queries + static_cast<size_t>(r) * pixels;
      uint32_t* o = out + r * out_stride + c0;
      SadBlock<1>(&q, chunk, n, pixels, &o);
    }
  }
}

static int64_t ThisTarget() {
  return HWY_TARGET;
}

}  // namespace seqslam::tools::HWY_NAMESPACE
HWY_AFTER_NAMESPACE();

#if HWY_ONCE
namespace seqslam::tools {

HWY_EXPORT(SadRows);
HWY_EXPORT(ThisTarget);

void sad_rows(const uint8_t* queries, uint32_t rows, const uint8_t* library, uint32_t count,
              uint32_t pixels, uint32_t* out, size_t out_stride) {
  HWY_DYNAMIC_DISPATCH(SadRows)(queries, rows, library, count, pixels, out, out_stride);
}

const char* sad_target_name(int64_t target) {
  return hwy::TargetName(target);
}

const char* sad_target_name() {
  return sad_target_name(HWY_DYNAMIC_DISPATCH(ThisTarget)());
}

std::vector<int64_t> sad_available_targets() {
  return hwy::SupportedAndGeneratedTargets();
}

void sad_force_target(int64_t target) {
  hwy::SetSupportedTargetsForTest(target);
}

}  // namespace seqslam::tools
#endif  // HWY_ONCE
