// Local normalisation (eq. 4.6) with the online offset sqrt(W): against double precision,
// positivity under adversarial rows, W = 0 and sigma_min.
#include "seqslam/normalise.h"

#include "ref_math.h"
#include "synthetic.h"
#include "test.h"
#include "test_log.h"

namespace seqslam {
namespace {

// Stated bound of the fixed-point normaliser against the double formula: 2 LSB of UQ5.11,
// i.e. 1/1024 of a standard deviation.
constexpr double kBoundLsb = 2.0;

// Double-precision D+(j) for SAD-unit input with images of `pixels` pixels.
double reference_value(const uint32_t* d, uint32_t n, uint32_t j, uint16_t window,
                       double sigma_min_grey, uint32_t pixels) {
  if (window == 0) return static_cast<double>(d[j]) / pixels / 8.0;
  const uint32_t h = window / 2u;
  const uint32_t lo = j >= h ? j - h : 0;
  const uint32_t hi = j + h < n ? j + h : n - 1;
  double sum = 0.0, m = 0.0;
  for (uint32_t k = lo; k <= hi; ++k)
    sum += d[k], m += 1.0;
  const double mean = sum / m;
  double var = 0.0;
  for (uint32_t k = lo; k <= hi; ++k)
    var += (d[k] - mean) * (d[k] - mean);
  double sd = test::ref_sqrt(var / m);
  const double sigma_min = sigma_min_grey * pixels;  // in SAD units
  if (sd < sigma_min) sd = sigma_min;
  const double offset =
      test::ref_floor(test::ref_sqrt(static_cast<double>(window)) * 2048.0) / 2048.0;
  return (d[j] - mean) / sd + offset;
}

TEST(LocalNormaliser, AgreesWithDoublePrecision) {
  test::Rng rng(20);
  static uint32_t d[1000];
  static uint16_t out[1000];
  const uint16_t windows[] = {2, 7, 10, 15, 30, 50, 63, 255};
  double worst = 0.0;
  for (uint16_t w : windows) {
    for (int trial = 0; trial < 6; ++trial) {
      const uint32_t n = 1 + rng.below(trial == 0 ? 5 : 1000);
      const uint32_t pixels = 512;
      // SAD-like values: a noisy level with dips (true matches) and bumps.
      const uint32_t level = 20000 + rng.below(30000);
      for (uint32_t j = 0; j < n; ++j) {
        d[j] = level + rng.below(6000);
        if (rng.below(20) == 0) d[j] = rng.below(level / 2);
        if (rng.below(30) == 0) d[j] = level * 2 + rng.below(10000);
      }
      LocalNormaliser norm;
      ASSERT_EQ(norm.configure(w, UQ8_8::from_ratio(1, 2), pixels), Status::kOk);
      norm.normalise_row(d, n, out);
      for (uint32_t j = 0; j < n; ++j) {
        const double ref = reference_value(d, n, j, w, 0.5, pixels);
        const double err = test::ref_fabs(out[j] / 2048.0 - ref);
        if (err > worst) worst = err;
        ASSERT_LE(err, kBoundLsb / 2048.0) << "W " << w << " n " << n << " j " << j;
      }
    }
  }
  test::log_figure("normaliser max error (sigma)", worst);
  EXPECT_LE(worst, kBoundLsb / 2048.0) << "max error (sigma): " << worst;
}

TEST(LocalNormaliser, NeverNegativeEvenForTheMostExtremeWindow) {
  // One low value among equal ones gives the most negative z-score possible,
  // -sqrt(m - 1); the offset sqrt(W) keeps it at >= 0.
  static uint32_t d[301];
  static uint16_t out[301];
  for (uint16_t w : {uint16_t{2}, uint16_t{10}, uint16_t{50}, uint16_t{255}}) {
    for (uint32_t j = 0; j < 301; ++j)
      d[j] = 100000;
    d[150] = 0;
    LocalNormaliser norm;
    ASSERT_EQ(norm.configure(w, UQ8_8::from_raw(1), 512), Status::kOk);
    norm.normalise_row(d, 301, out);
    // z = -sqrt(m - 1) with m = 2 * (W / 2) + 1: D+ = sqrt(W) - sqrt(m - 1), 0 for even W.
    const double expected = test::ref_sqrt(w) - test::ref_sqrt(2.0 * (w / 2));
    EXPECT_NEAR(out[150] / 2048.0, expected, 2.0 / 2048.0) << "W " << w;
    for (uint32_t j = 0; j < 301; ++j)
      EXPECT_LE(out[j], 2u * norm.offset_raw() + 2);
  }
}

TEST(LocalNormaliser, WindowZeroIsScaledMad) {
  uint32_t d[4] = {0, 512 * 8, 512 * 255, 512 * 100};
  uint16_t out[4];
  LocalNormaliser norm;
  ASSERT_EQ(norm.configure(0, UQ8_8::from_int(0), 512), Status::kOk);
  norm.normalise_row(d, 4, out);
  EXPECT_EQ(out[0], 0);
  EXPECT_EQ(out[1], 2048);  // MAD 8 -> 1.0
  EXPECT_EQ(out[2], 255 * 256);
  EXPECT_EQ(out[3], 100 * 256);
}

TEST(LocalNormaliser, FlatRowUsesSigmaMin) {
  uint32_t d[20];
  uint16_t out[20];
  for (uint32_t& v : d)
    v = 4242;
  LocalNormaliser norm;
  ASSERT_EQ(norm.configure(10, UQ8_8::from_int(1), 512), Status::kOk);
  norm.normalise_row(d, 20, out);
  for (uint16_t v : out)
    EXPECT_EQ(v, norm.offset_raw());  // z = 0
  d[5] = 4242 + 512;  // one grey level of MAD above: z = (5/6 * 512) / max(sd, 512) < 1
  norm.normalise_row(d, 20, out);
  EXPECT_GT(out[5], norm.offset_raw());
}

TEST(LocalNormaliser, ResultDoesNotDependOnHistory) {
  test::Rng rng(21);
  static uint32_t a[300], b[300];
  static uint16_t first[300], again[300];
  for (uint32_t j = 0; j < 300; ++j)
    a[j] = 1000 + rng.below(100000), b[j] = rng.below(500);
  LocalNormaliser norm;
  ASSERT_EQ(norm.configure(50, UQ8_8::from_int(1), 512), Status::kOk);
  norm.normalise_row(a, 300, first);
  norm.normalise_row(b, 300, again);  // moves the internal square-root seed far away
  norm.normalise_row(a, 300, again);
  for (uint32_t j = 0; j < 300; ++j)
    ASSERT_EQ(first[j], again[j]);
}

TEST(LocalNormaliser, RejectsBadParameters) {
  LocalNormaliser norm;
  EXPECT_EQ(norm.configure(1, UQ8_8::from_int(1), 512), Status::kOutOfRange);
  EXPECT_EQ(norm.configure(256, UQ8_8::from_int(1), 512), Status::kOutOfRange);
  EXPECT_EQ(norm.configure(50, UQ8_8::from_int(0), 512), Status::kInvalidArgument);
  EXPECT_EQ(norm.configure(50, UQ8_8::from_int(1), 0), Status::kOutOfRange);
  EXPECT_EQ(norm.configure(50, UQ8_8::from_int(1), kMaxPixels + 1), Status::kOutOfRange);
}

}  // namespace
}  // namespace seqslam
