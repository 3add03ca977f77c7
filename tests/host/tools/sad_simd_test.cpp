// The host SIMD SAD kernel (tools/common/src/sad_simd.cpp) against the core's sad_many and a
// double-precision reference, on every instruction set compiled in that this CPU supports.
// Error bound: 0 (the sums are exact integers, so every target must agree bit for bit).
#include "seqslam_tools/sad_simd.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <string>
#include <vector>

#include "seqslam/difference.h"

namespace seqslam::tools {
namespace {

// Restores the automatic choice even when an assertion fails mid-loop.
struct ForcedTarget {
  explicit ForcedTarget(int64_t t) { sad_force_target(t); }
  ~ForcedTarget() { sad_force_target(0); }
  ForcedTarget(const ForcedTarget&) = delete;
  ForcedTarget& operator=(const ForcedTarget&) = delete;
};

std::vector<uint8_t> random_bytes(size_t n, uint32_t seed) {
  std::mt19937 rng(seed);
  std::uniform_int_distribution<int> px(0, 255);
  std::vector<uint8_t> v(n);
  for (uint8_t& b : v)
    b = static_cast<uint8_t>(px(rng));
  return v;
}

double reference_sad(const uint8_t* a, const uint8_t* b, uint32_t pixels) {
  double s = 0.0;
  for (uint32_t k = 0; k < pixels; ++k)
    s += std::fabs(static_cast<double>(a[k]) - static_cast<double>(b[k]));
  return s;
}

// rows x count SADs through sad_rows, with a wider output stride whose padding must stay
// untouched; compared with the core kernel and the double reference.
void check_case(uint32_t pixels, uint32_t rows, uint32_t count, uint32_t seed) {
  SCOPED_TRACE("pixels " + std::to_string(pixels) + ", rows " + std::to_string(rows) + ", count " +
               std::to_string(count) + ", target " + sad_target_name());
  const auto queries = random_bytes(static_cast<size_t>(rows) * pixels, seed);
  const auto library = random_bytes(static_cast<size_t>(count) * pixels, seed + 1);
  const size_t stride = count + 3;
  constexpr uint32_t kPad = 0xDEADBEEFu;
  std::vector<uint32_t> out(rows * stride, kPad);
  sad_rows(queries.data(), rows, library.data(), count, pixels, out.data(), stride);

  std::vector<uint32_t> sums(count);
  for (uint32_t j = 0; j < count; ++j)
    sums[j] = pixel_sum(&library[static_cast<size_t>(j) * pixels], pixels);
  std::vector<uint32_t> core(count);
  for (uint32_t r = 0; r < rows; ++r) {
    const uint8_t* q = &queries[static_cast<size_t>(r) * pixels];
    sad_many(q, library.data(), sums.data(), count, pixels, core.data());
    for (uint32_t j = 0; j < count; ++j) {
      const uint32_t got = out[r * stride + j];
      ASSERT_EQ(got, core[j]) << "row " << r << " image " << j;
      ASSERT_EQ(static_cast<double>(got),
                reference_sad(q, &library[static_cast<size_t>(j) * pixels], pixels))
          << "row " << r << " image " << j;
    }
    for (size_t j = count; j < stride; ++j)
      ASSERT_EQ(out[r * stride + j], kPad) << "row " << r << " wrote past its " << count;
  }
}

TEST(SadSimd, EveryTargetEqualsTheCoreKernel) {
  const std::vector<int64_t> targets = sad_available_targets();
  ASSERT_FALSE(targets.empty());
  for (const int64_t t : targets) {
    const ForcedTarget forced(t);
    ASSERT_STREQ(sad_target_name(), sad_target_name(t));
    // 32x16, 25x20 (not a multiple of any vector), 12x10, 7x3 (under one 16-byte vector),
    // one pixel; 1-9 rows (blocks of four and the rest); 1-300 images (crosses the
    // 128-image library chunk).
    uint32_t seed = 1;
    for (const uint32_t pixels : {512u, 500u, 120u, 21u, 1u}) {
      for (const uint32_t rows : {1u, 4u, 5u, 9u}) {
        for (const uint32_t count : {1u, 127u, 129u, 300u})
          check_case(pixels, rows, count, seed++);
      }
    }
  }
}

TEST(SadSimd, LargestDifferencesDoNotOverflow) {
  // 255 per pixel over 128x128 = 4 177 920: beyond 16 and 24 bits, far inside 32.
  constexpr uint32_t kPixels = 128 * 128;
  const std::vector<uint8_t> black(4 * kPixels, 0);
  const std::vector<uint8_t> white(3 * kPixels, 255);
  for (const int64_t t : sad_available_targets()) {
    const ForcedTarget forced(t);
    std::vector<uint32_t> out(4 * 3, 0);
    sad_rows(black.data(), 4, white.data(), 3, kPixels, out.data(), 3);
    for (const uint32_t v : out)
      ASSERT_EQ(v, 255u * kPixels) << sad_target_name();
  }
}

TEST(SadSimd, AutomaticChoiceIsTheBestAvailable) {
  // Highway's target bits: lower is better, and the list is in increasing bit order.
  const std::vector<int64_t> targets = sad_available_targets();
  ASSERT_FALSE(targets.empty());
  EXPECT_STREQ(sad_target_name(), sad_target_name(targets.front()));
}

}  // namespace
}  // namespace seqslam::tools
