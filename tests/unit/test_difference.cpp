// Image differences: SAD/MAD exact, the register-blocked batch kernel equal to the plain one,
// and the shift-tolerant variant against a double-precision formula.
#include "seqslam/difference.h"

#include "ref_math.h"
#include "synthetic.h"
#include "test.h"

namespace seqslam {
namespace {

// One in the raw units of the results' formats: MAD in UQ8.8 grey levels, shifts in Q15.16
// pixels.
constexpr double kMadOne = static_cast<double>(UQ8_8::from_int(1).raw());
constexpr double kShiftOne = static_cast<double>(Q15_16::from_int(1).raw());

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
    EXPECT_NEAR(m.value().raw() / kMadOne, ref / 512.0, 0.5 / kMadOne + 1e-12);
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

// Double reference of subpixel_shift: exact means per shift, the same candidate order, the
// parabola's vertex.
double reference_subpixel_shift(const uint8_t* a, const uint8_t* b, int w, int h, int max_shift) {
  double mean[2 * kMaxSubpixelShift + 1];
  for (int dx = -max_shift; dx <= max_shift; ++dx) {
    double sum = 0;
    int n = 0;
    for (int y = 0; y < h; ++y)
      for (int x = 0; x < w; ++x) {
        const int xa = x + dx;
        if (xa < 0 || xa >= w) continue;
        sum += test::ref_fabs(static_cast<double>(a[y * w + xa]) - b[y * w + x]);
        ++n;
      }
    mean[dx + max_shift] = sum / n;
  }
  int best = 0;
  for (int k = 1; k <= max_shift; ++k)
    for (int sign = -1; sign <= 1; sign += 2)
      if (mean[sign * k + max_shift] < mean[best + max_shift]) best = sign * k;
  if (best == -max_shift || best == max_shift) return best;
  const double l = mean[best - 1 + max_shift], c = mean[best + max_shift],
               r = mean[best + 1 + max_shift];
  const double curvature = l - 2 * c + r;
  return curvature > 0 ? best + (l - r) / (2 * curvature) : best;
}

// A smooth pattern (two horizontal waves whose phase changes with the row), sampled with its
// origin moved by t pixels: content at column x of the unmoved image appears at x + t.
void smooth_pattern(uint8_t* px, int w, int h, double t) {
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double u = x - t;
      const double v =
          128 + 60 * test::ref_sin(0.45 * u + 0.7 * y) + 40 * test::ref_cos(0.23 * u - 0.3 * y);
      px[y * w + x] = static_cast<uint8_t>(test::ref_round(v));
    }
}

TEST(Difference, SubpixelShiftMatchesDoubleReference) {
  test::Rng rng(29);
  uint8_t a[512], b[512];
  const ImageSize s{32, 16};
  for (int trial = 0; trial < 40; ++trial) {
    random_image(rng, a, 512);
    // b: a noisy copy of a whose content sits `shift` columns to the left (a(x + shift) = b(x)).
    const int shift = trial % 9 - 4;
    for (int i = 0; i < 512; ++i) {
      const int x = i % 32, y = i / 32, sx = x + shift;
      const int v = sx >= 0 && sx < 32 ? a[y * 32 + sx] + static_cast<int>(rng.below(41)) - 20
                                       : static_cast<int>(rng.below(256));
      b[i] = static_cast<uint8_t>(v < 0 ? 0 : v > 255 ? 255 : v);
    }
    for (uint8_t m = 0; m <= 6; ++m) {
      const Result<Q15_16> r = subpixel_shift(ImageView{a, s}, ImageView{b, s}, m);
      ASSERT_TRUE(r.ok());
      const double got = r.value().raw() / kShiftOne;
      const double want = reference_subpixel_shift(a, b, 32, 16, m);
      // The means are rounded to 2^-16 grey levels; with curvatures of tens of grey levels
      // (random content) that moves the vertex by far less than 1e-4 pixel.
      EXPECT_NEAR(got, want, 1e-4);
      if (m >= 5) {
        EXPECT_NEAR(got, shift, 0.5);  // the integer shift is found
      }
    }
  }
}

TEST(Difference, SubpixelShiftRecoversFractionalShifts) {
  // Smooth content moved by a fraction of a pixel: the parabola through three means locates
  // it to within 0.15 pixel (its bias for such content; measured worst case 0.089).
  uint8_t a[512], b[512];
  const ImageSize s{32, 16};
  smooth_pattern(a, 32, 16, 0.0);
  double worst = 0;
  for (int k = -16; k <= 16; ++k) {
    const double t = k * 0.1875;  // -3 .. 3 pixels
    smooth_pattern(b, 32, 16, -t);
    const Result<Q15_16> r = subpixel_shift(ImageView{a, s}, ImageView{b, s}, 5);
    ASSERT_TRUE(r.ok());
    const double err = test::ref_fabs(r.value().raw() / kShiftOne - t);
    worst = err > worst ? err : worst;
    EXPECT_LE(err, 0.15);
  }
  EXPECT_GT(worst, 0.0);  // the bound is not vacuous: the estimate is not exact
}

TEST(Difference, SubpixelShiftBadInput) {
  uint8_t a[512] = {}, b[512] = {};
  const ImageSize s{32, 16};
  EXPECT_EQ(subpixel_shift(ImageView{nullptr, s}, ImageView{b, s}, 2).status(),
            Status::kInvalidArgument);
  EXPECT_EQ(subpixel_shift(ImageView{a, s}, ImageView{b, ImageSize{16, 32}}, 2).status(),
            Status::kInvalidArgument);
  EXPECT_EQ(
      subpixel_shift(ImageView{a, ImageSize{4, 4}}, ImageView{b, ImageSize{4, 4}}, 4).status(),
      Status::kOutOfRange);
  EXPECT_EQ(subpixel_shift(ImageView{a, s}, ImageView{b, s}, kMaxSubpixelShift + 1).status(),
            Status::kOutOfRange);
  // Identical flat images: every mean is 0, no refinement, shift 0.
  const Result<Q15_16> flat = subpixel_shift(ImageView{a, s}, ImageView{b, s}, 3);
  ASSERT_TRUE(flat.ok());
  EXPECT_EQ(flat.value().raw(), 0);
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
