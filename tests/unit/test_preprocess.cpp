// Preprocessing against double-precision formulas: HE and iGK exactly, PN within one grey
// level (and exact on >= 99 % of pixels).
#include "seqslam/preprocess.h"

#include "ref_math.h"
#include "synthetic.h"
#include "test.h"

namespace seqslam {
namespace {

constexpr uint32_t kMaxTestPixels = kMaxPixels;

void random_image(test::Rng& rng, uint8_t* px, uint32_t n, int lo, int hi) {
  for (uint32_t i = 0; i < n; ++i)
    px[i] = static_cast<uint8_t>(rng.range(lo, hi));
}

// Double-precision HE, eq. 4.3.
void reference_he(const uint8_t* in, uint32_t n, uint8_t* out) {
  // cdf(r) = sum of pmf up to r = (pixels <= r) / n; counting first keeps exact ties exact.
  double hist[256] = {};
  for (uint32_t i = 0; i < n; ++i)
    hist[in[i]] += 1.0;
  double cdf[256];
  double cum = 0.0;
  for (int r = 0; r < 256; ++r) {
    cum += hist[r];
    cdf[r] = cum / static_cast<double>(n);
  }
  for (uint32_t i = 0; i < n; ++i)
    out[i] = static_cast<uint8_t>(test::ref_round(255.0 * cdf[in[i]]));
}

// Double-precision PN, eq. 4.1 with the library's partition and scaling.
void reference_pn(const PatchNormConfig& c, const uint8_t* in, ImageSize size, uint8_t* out) {
  const uint32_t w = size.width;
  const uint32_t h = size.height;
  const uint32_t cols = w / c.patch_width > 0 ? w / c.patch_width : 1;
  const uint32_t rows = h / c.patch_height > 0 ? h / c.patch_height : 1;
  const double eps = static_cast<double>(c.epsilon.raw()) / 256.0;
  const double gain = static_cast<double>(c.gain.raw()) / 256.0;
  for (uint32_t r = 0; r < rows; ++r) {
    for (uint32_t q = 0; q < cols; ++q) {
      const uint32_t x0 = q * w / cols, x1 = (q + 1) * w / cols;
      const uint32_t y0 = r * h / rows, y1 = (r + 1) * h / rows;
      double sum = 0.0, n = 0.0;
      for (uint32_t y = y0; y < y1; ++y)
        for (uint32_t x = x0; x < x1; ++x)
          sum += in[y * w + x], n += 1.0;
      const double mean = sum / n;
      double var = 0.0;
      for (uint32_t y = y0; y < y1; ++y)
        for (uint32_t x = x0; x < x1; ++x)
          var += (in[y * w + x] - mean) * (in[y * w + x] - mean);
      const double sd = test::ref_sqrt(var / n);
      for (uint32_t y = y0; y < y1; ++y) {
        for (uint32_t x = x0; x < x1; ++x) {
          double v = 128.0;
          if (sd + eps > 0.0)
            v = test::ref_round(128.0 + gain * (in[y * w + x] - mean) / (sd + eps));
          out[y * w + x] = static_cast<uint8_t>(v < 0.0 ? 0.0 : (v > 255.0 ? 255.0 : v));
        }
      }
    }
  }
}

TEST(Preprocess, HistogramEqualisationIsExact) {
  test::Rng rng(1);
  uint8_t in[kMaxTestPixels], out[kMaxTestPixels], ref[kMaxTestPixels];
  const ImageSize sizes[] = {{32, 16}, {25, 20}, {12, 10}, {1, 1}, {7, 3}};
  for (const ImageSize s : sizes) {
    for (int trial = 0; trial < 20; ++trial) {
      random_image(rng, in, s.pixels(), trial, 255 - 3 * trial);
      ASSERT_EQ(equalise_histogram(ImageView{in, s}, MutableImageView{out, s}), Status::kOk);
      reference_he(in, s.pixels(), ref);
      for (uint32_t i = 0; i < s.pixels(); ++i)
        ASSERT_EQ(out[i], ref[i]) << "pixel " << i;
    }
  }
}

TEST(Preprocess, HistogramEqualisationOfAFlatImageIsWhite) {
  uint8_t px[16];
  for (uint8_t& p : px)
    p = 77;
  const ImageSize s{4, 4};
  ASSERT_EQ(equalise_histogram(ImageView{px, s}, MutableImageView{px, s}), Status::kOk);
  for (uint8_t p : px)
    EXPECT_EQ(p, 255);  // cdf(77) = 1
}

TEST(Preprocess, InverseGammaTableMatchesFormula) {
  uint8_t in[256], out[256];
  for (int i = 0; i < 256; ++i)
    in[i] = static_cast<uint8_t>(i);
  const ImageSize s{16, 16};
  ASSERT_EQ(inverse_gamma(ImageView{in, s}, MutableImageView{out, s}), Status::kOk);
  for (int i = 0; i < 256; ++i) {
    const double ref = test::ref_round(255.0 * test::ref_pow(i / 255.0, 1.0 / 0.45));
    EXPECT_EQ(static_cast<double>(out[i]), ref) << "level " << i;
  }
}

TEST(Preprocess, PatchNormalisationWithinOneGreyLevel) {
  test::Rng rng(2);
  uint8_t in[kMaxTestPixels], out[kMaxTestPixels], ref[kMaxTestPixels];
  const ImageSize sizes[] = {{32, 16}, {25, 20}, {12, 10}, {5, 3}};
  uint32_t total = 0, exact = 0;
  for (const ImageSize s : sizes) {
    for (int trial = 0; trial < 30; ++trial) {
      PatchNormConfig c;
      c.patch_width = static_cast<uint8_t>(2 + trial % 5);
      c.patch_height = static_cast<uint8_t>(2 + trial % 3);
      c.epsilon = UQ8_8::from_raw(static_cast<uint16_t>(trial * 20));
      c.gain = UQ8_8::from_raw(static_cast<uint16_t>(2048 + trial * 300));
      random_image(rng, in, s.pixels(), trial * 3, 255 - trial * 4);
      ASSERT_EQ(patch_normalise(c, ImageView{in, s}, MutableImageView{out, s}), Status::kOk);
      reference_pn(c, in, s, ref);
      for (uint32_t i = 0; i < s.pixels(); ++i) {
        const int d = out[i] - ref[i];
        ASSERT_LE(d < 0 ? -d : d, 1) << "pixel " << i;
        exact += d == 0 ? 1u : 0u;
        ++total;
      }
    }
  }
  EXPECT_GE(static_cast<double>(exact), 0.99 * total) << exact << " of " << total << " exact";
}

TEST(Preprocess, PatchNormalisationHandlesFlatPatches) {
  uint8_t px[32 * 16];
  for (uint32_t i = 0; i < 32 * 16; ++i)
    px[i] = 200;
  px[0] = 0;  // one non-flat patch
  const ImageSize s{32, 16};
  PatchNormConfig c;
  ASSERT_EQ(patch_normalise(c, ImageView{px, s}, MutableImageView{px, s}), Status::kOk);
  EXPECT_EQ(px[100], 128);  // flat patch -> mid-grey
  EXPECT_LT(px[0], 128);
  c.epsilon = UQ8_8::from_int(0);  // even with epsilon 0 a flat patch is not a division by 0
  for (uint32_t i = 0; i < 32 * 16; ++i)
    px[i] = 9;
  ASSERT_EQ(patch_normalise(c, ImageView{px, s}, MutableImageView{px, s}), Status::kOk);
  EXPECT_EQ(px[7], 128);
}

TEST(Preprocess, CombinationsAreCompositions) {
  test::Rng rng(3);
  const ImageSize s{25, 20};
  uint8_t in[500], a[500], b[500];
  random_image(rng, in, 500, 10, 240);
  PreprocessConfig c;
  c.method = Preprocessing::kInvGammaHistEq;
  ASSERT_EQ(preprocess(c, ImageView{in, s}, MutableImageView{a, s}), Status::kOk);
  ASSERT_EQ(inverse_gamma(ImageView{in, s}, MutableImageView{b, s}), Status::kOk);
  ASSERT_EQ(equalise_histogram(ImageView{b, s}, MutableImageView{b, s}), Status::kOk);
  for (int i = 0; i < 500; ++i)
    ASSERT_EQ(a[i], b[i]);
  c.method = Preprocessing::kHistEqPatchNorm;
  ASSERT_EQ(preprocess(c, ImageView{in, s}, MutableImageView{a, s}), Status::kOk);
  ASSERT_EQ(equalise_histogram(ImageView{in, s}, MutableImageView{b, s}), Status::kOk);
  ASSERT_EQ(patch_normalise(c.patch, ImageView{b, s}, MutableImageView{b, s}), Status::kOk);
  for (int i = 0; i < 500; ++i)
    ASSERT_EQ(a[i], b[i]);
  c.method = Preprocessing::kNone;
  ASSERT_EQ(preprocess(c, ImageView{in, s}, MutableImageView{a, s}), Status::kOk);
  for (int i = 0; i < 500; ++i)
    ASSERT_EQ(a[i], in[i]);
  // In place equals out of place.
  c.method = Preprocessing::kInvGammaPatchNorm;
  ASSERT_EQ(preprocess(c, ImageView{in, s}, MutableImageView{a, s}), Status::kOk);
  for (int i = 0; i < 500; ++i)
    b[i] = in[i];
  ASSERT_EQ(preprocess(c, ImageView{b, s}, MutableImageView{b, s}), Status::kOk);
  for (int i = 0; i < 500; ++i)
    ASSERT_EQ(a[i], b[i]);
}

TEST(Preprocess, LargestImageOfTheBuild) {
  // The host build takes 64x32; the target's 512-pixel buffer 32x16.
  const ImageSize s = kMaxPixels >= 2048 ? ImageSize{64, 32} : ImageSize{32, 16};
  static uint8_t px[kMaxPixels];
  test::Rng rng(4);
  random_image(rng, px, s.pixels(), 0, 255);
  PreprocessConfig c;
  for (int m = 0; m <= 6; ++m) {
    c.method = static_cast<Preprocessing>(m);
    EXPECT_EQ(preprocess(c, ImageView{px, s}, MutableImageView{px, s}), Status::kOk);
  }
}

TEST(Preprocess, BadInputReturnsStatusAndLeavesOutputAlone) {
  uint8_t in[16] = {}, out[16];
  for (uint8_t& p : out)
    p = 42;
  const ImageSize s{4, 4};
  PreprocessConfig c;
  EXPECT_EQ(preprocess(c, ImageView{nullptr, s}, MutableImageView{out, s}),
            Status::kInvalidArgument);
  EXPECT_EQ(preprocess(c, ImageView{in, s}, MutableImageView{out, ImageSize{2, 8}}),
            Status::kInvalidArgument);
  EXPECT_EQ(preprocess(c, ImageView{in, ImageSize{0, 4}}, MutableImageView{out, ImageSize{0, 4}}),
            Status::kInvalidArgument);
  const ImageSize huge{static_cast<uint16_t>(kMaxPixels + 1), 1};
  EXPECT_EQ(preprocess(c, ImageView{in, huge}, MutableImageView{out, huge}), Status::kOutOfRange);
  c.method = Preprocessing::kPatchNorm;
  c.patch.patch_width = 0;
  EXPECT_EQ(preprocess(c, ImageView{in, s}, MutableImageView{out, s}), Status::kInvalidArgument);
  c.patch.patch_width = 1;
  c.patch.patch_height = 1;
  EXPECT_EQ(check_preprocess_config(c), Status::kInvalidArgument);
  c.patch = PatchNormConfig{};
  c.patch.gain = UQ8_8::from_int(0);
  EXPECT_EQ(check_preprocess_config(c), Status::kInvalidArgument);
  c.method = static_cast<Preprocessing>(99);
  EXPECT_EQ(check_preprocess_config(c), Status::kInvalidArgument);
  for (uint8_t p : out)
    EXPECT_EQ(p, 42);
  EXPECT_EQ(preprocessing_name(Preprocessing::kInvGammaHistEq)[0], 'i');
}

}  // namespace
}  // namespace seqslam
