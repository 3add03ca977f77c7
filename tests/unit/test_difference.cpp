// Image differences: SAD/MAD exact, the register-blocked batch kernel equal to the plain one,
// and the shift-tolerant variant against a double-precision formula.
#include "seqslam/difference.h"

#include "ref_math.h"
#include "synthetic.h"
#include "test.h"

namespace seqslam {
namespace {

void random_image(test::Rng& rng, uint8_t* px, uint32_t n) {
  for (uint32_t i = 0; i < n; ++i)
    px[i] = static_cast<uint8_t>(rng.below(256));
}

TEST(Difference, SadAndMadAreExact) {
  test::Rng rng(10);
  uint8_t a[512], b[512];
  const ImageSize s{32, 16};
  for (int trial = 0; trial < 50; ++trial) {
    random_image(rng, a, 512);
    random_image(rng, b, 512);
    uint32_t ref = 0;
    for (int i = 0; i < 512; ++i)
      ref += static_cast<uint32_t>(a[i] > b[i] ? a[i] - b[i] : b[i] - a[i]);
    const Result<uint32_t> r = sad(ImageView{a, s}, ImageView{b, s});
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r.value(), ref);
    const Result<UQ8_8> m = mad(ImageView{a, s}, ImageView{b, s});
    ASSERT_TRUE(m.ok());
    EXPECT_NEAR(m.value().raw() / 256.0, ref / 512.0, 0.5 / 256.0 + 1e-12);
  }
  EXPECT_EQ(sad(ImageView{a, s}, ImageView{a, s}).value(), 0u);
}

TEST(Difference, BatchKernelEqualsPairwise) {
  test::Rng rng(11);
  static uint8_t lib[40 * 512];
  uint8_t q[512];
  uint32_t sums[40], out[40];
  const uint32_t sizes[] = {512, 500, 120, 16, 17, 15, 1};
  for (uint32_t pixels : sizes) {
    random_image(rng, lib, 40 * pixels);
    random_image(rng, q, pixels);
    for (uint32_t j = 0; j < 40; ++j)
      sums[j] = pixel_sum(lib + j * pixels, pixels);
    sad_many(q, lib, sums, 40, pixels, out);
    for (uint32_t j = 0; j < 40; ++j) {
      const ImageSize s{static_cast<uint16_t>(pixels), 1};
      ASSERT_EQ(out[j], sad(ImageView{q, s}, ImageView{lib + j * pixels, s}).value())
          << "pixels " << pixels << " image " << j;
    }
  }
  // Extremes: all 0 against all 255.
  for (uint32_t i = 0; i < 512; ++i)
    q[i] = 0, lib[i] = 255;
  sums[0] = pixel_sum(lib, 512);
  sad_many(q, lib, sums, 1, 512, out);
  EXPECT_EQ(out[0], 512u * 255u);
}

// Double reference of the shift-tolerant MAD: min over dx of the overlap MAD.
double reference_shift_mad(const uint8_t* a, const uint8_t* b, int w, int h, int max_shift) {
  double best = 1e300;
  for (int dx = -max_shift; dx <= max_shift; ++dx) {
    double total = 0.0;
    int n = 0;
    for (int y = 0; y < h; ++y) {
      for (int x = 0; x < w; ++x) {
        const int xa = x + (dx > 0 ? dx : 0);
        const int xb = x + (dx < 0 ? -dx : 0);
        if (xa >= w || xb >= w) continue;
        total += test::ref_fabs(static_cast<double>(a[y * w + xa]) - b[y * w + xb]);
        ++n;
      }
    }
    const double m = total / n;
    if (m < best) best = m;
  }
  return best;
}

TEST(Difference, ShiftTolerantMatchesDoubleReference) {
  test::Rng rng(12);
  uint8_t a[512], b[512];
  const ImageSize s{32, 16};
  for (int trial = 0; trial < 40; ++trial) {
    random_image(rng, a, 512);
    // b is a shifted, noisy copy of a: the best offset should be found.
    const int shift = trial % 7 - 3;
    for (int y = 0; y < 16; ++y)
      for (int x = 0; x < 32; ++x) {
        const int sx = x + shift;
        b[y * 32 + x] = sx >= 0 && sx < 32 ? a[y * 32 + sx] : static_cast<uint8_t>(rng.below(256));
      }
    for (uint8_t m = 0; m <= 4; ++m) {
      const Result<uint32_t> r = shift_tolerant_sad(ImageView{a, s}, ImageView{b, s}, m);
      ASSERT_TRUE(r.ok());
      // SAD units of the full area, rounded: |value / A - MAD| <= 0.5 / A.
      EXPECT_NEAR(r.value() / 512.0, reference_shift_mad(a, b, 32, 16, m), 0.5 / 512.0 + 1e-9);
    }
  }
  EXPECT_EQ(shift_tolerant_sad(ImageView{a, s}, ImageView{b, s}, 0).value(),
            sad(ImageView{a, s}, ImageView{b, s}).value());
}

TEST(Difference, BadInput) {
  uint8_t a[16] = {}, b[16] = {};
  EXPECT_EQ(sad(ImageView{a, ImageSize{4, 4}}, ImageView{b, ImageSize{2, 8}}).status(),
            Status::kInvalidArgument);
  EXPECT_EQ(sad(ImageView{nullptr, ImageSize{4, 4}}, ImageView{b, ImageSize{4, 4}}).status(),
            Status::kInvalidArgument);
  EXPECT_EQ(mad(ImageView{a, ImageSize{0, 4}}, ImageView{b, ImageSize{0, 4}}).status(),
            Status::kInvalidArgument);
  EXPECT_EQ(
      shift_tolerant_sad(ImageView{a, ImageSize{4, 4}}, ImageView{b, ImageSize{4, 4}}, 4).status(),
      Status::kOutOfRange);
}

}  // namespace
}  // namespace seqslam
