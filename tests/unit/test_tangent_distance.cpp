// Tangent distance: kernel, blur, tangents and the regularised two-sided distance against
// double-precision references written here from the definitions, edge cases (flat images,
// 0/255 checkerboards, tiny and maximal sizes, bad input) and the behaviour that justifies the
// metric (small for shifted / rotated / scaled copies, large for unrelated images).
#include "seqslam/tangent_distance.h"

#include "ref_math.h"
#include "seqslam/assert.h"
#include "synthetic.h"
#include "test.h"
#include "test_log.h"

namespace seqslam {
namespace {

using test::ref_fabs;

constexpr double kLambda = 1.0 / (1 << kTdLambdaShift);
// One in the raw units of the formats compared: UQ8.8 (blurred pixels, rms, sigma), Q8.7
// (tangents), Q47.16 (squared distances).
constexpr double kUQ8_8One = static_cast<double>(UQ8_8::from_int(1).raw());
constexpr double kQ8_7One = static_cast<double>(Q8_7::from_int(1).raw());
constexpr double kQ47_16One = static_cast<double>(Q47_16::from_int(1).raw());
// Stated bounds (tangent_distance.h).
constexpr double kBlurBound = 1.0 / 256.0;
constexpr double kTangentBound = 3.0 / 256.0;
constexpr double kTdRelBound = 1.0 / (1 << 30);  // of ||d||^2
constexpr double kTdAbsBound = 1.0 / (1 << 15);

double g_blur_err = 0.0;
double g_tangent_err = 0.0;
double g_td_abs = 0.0;  // worst |TD - TD_double| in grey^2
double g_td_rel = 0.0;  // worst |TD - TD_double| / ||d||^2

TangentImage g_a;
TangentImage g_b;
uint8_t g_px_a[kMaxPixels];
uint8_t g_px_b[kMaxPixels];
double g_ref[kMaxPixels];
double g_tmp[kMaxPixels];
double g_tan[kTangentCount][kMaxPixels];

BlurKernel kernel_for(uint32_t sigma_raw) {
  const Result<BlurKernel> k = make_blur_kernel(UQ8_8::from_raw(static_cast<uint16_t>(sigma_raw)));
  SEQSLAM_ASSERT(k.ok());
  return k.value();
}

int clampi(int v, int n) {
  return v < 0 ? 0 : (v >= n ? n - 1 : v);
}

// Exact separable blur with the kernel's integer weights / 4096 (no intermediate rounding).
void ref_blur(const uint8_t* px, ImageSize s, const BlurKernel& k, double* out) {
  const int w = s.width, h = s.height, r = k.radius;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double acc = 0.0;
      for (int o = -r; o <= r; ++o)
        acc += k.weight[o < 0 ? -o : o] / 4096.0 * px[y * w + clampi(x + o, w)];
      g_tmp[y * w + x] = acc;
    }
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      double acc = 0.0;
      for (int o = -r; o <= r; ++o)
        acc += k.weight[o < 0 ? -o : o] / 4096.0 * g_tmp[clampi(y + o, h) * w + x];
      out[y * w + x] = acc;
    }
}

// The four Lie operators of a (double) blurred image, straight from the definitions.
void ref_tangents(const double* b, ImageSize s) {
  const int w = s.width, h = s.height;
  const double dmax = w > h ? w : h;
  for (int y = 0; y < h; ++y)
    for (int x = 0; x < w; ++x) {
      const double dx = (b[y * w + clampi(x + 1, w)] - b[y * w + clampi(x - 1, w)]) / 2.0;
      const double dy = (b[clampi(y + 1, h) * w + x] - b[clampi(y - 1, h) * w + x]) / 2.0;
      const double u = (x - (w - 1) / 2.0) / (dmax / 2.0);
      const double v = (y - (h - 1) / 2.0) / (dmax / 2.0);
      const int i = y * w + x;
      g_tan[0][i] = dx;
      g_tan[1][i] = dy;
      g_tan[2][i] = v * dx - u * dy;
      g_tan[3][i] = u * dx + v * dy;
    }
}

// Checks blur and tangents of `px` against the double pipeline; updates the worst errors.
void check_prepared(const uint8_t* px, ImageSize s, const BlurKernel& k, const TangentImage& t) {
  ref_blur(px, s, k, g_ref);
  const uint32_t n = s.pixels();
  double worst_blur = 0.0, worst_tan = 0.0;
  for (uint32_t i = 0; i < n; ++i) {
    const double e = ref_fabs(t.blurred[i].raw() / kUQ8_8One - g_ref[i]);
    if (e > worst_blur) worst_blur = e;
  }
  ref_tangents(g_ref, s);
  for (int c = 0; c < kTangentCount; ++c)
    for (uint32_t i = 0; i < n; ++i) {
      const double e = ref_fabs(t.tangent[c][i].raw() / kQ8_7One - g_tan[c][i]);
      if (e > worst_tan) worst_tan = e;
    }
  EXPECT_LE(worst_blur, kBlurBound);
  EXPECT_LE(worst_tan, kTangentBound);
  if (worst_blur > g_blur_err) g_blur_err = worst_blur;
  if (worst_tan > g_tangent_err) g_tangent_err = worst_tan;
}

// Solves (G + lambda diag G) c = -g by Gaussian elimination with partial pivoting, then
// evaluates the regularised objective ||d + M c||^2 + lambda sum G_ii c_i^2 directly.
// Columns with a zero tangent are left out. Returns the squared distance in grey levels^2.
double ref_td(const TangentImage& a, const TangentImage& b) {
  const uint32_t n = a.size.pixels();
  constexpr int kN = 2 * kTangentCount;
  auto col = [&](int c, uint32_t i) {
    return c < kTangentCount ? a.tangent[c][i].raw() / kQ8_7One
                             : -b.tangent[c - kTangentCount][i].raw() / kQ8_7One;
  };
  double gm[kN][kN + 1] = {};
  for (uint32_t i = 0; i < n; ++i) {
    const double d = a.blurred[i].raw() / kUQ8_8One - b.blurred[i].raw() / kUQ8_8One;
    for (int p = 0; p < kN; ++p) {
      for (int q = 0; q < kN; ++q)
        gm[p][q] += col(p, i) * col(q, i);
      gm[p][kN] -= col(p, i) * d;
    }
  }
  double diag[kN];
  bool used[kN];
  for (int p = 0; p < kN; ++p) {
    diag[p] = gm[p][p];
    used[p] = diag[p] > 0.0;
    if (!used[p]) {
      for (int q = 0; q < kN; ++q)
        gm[p][q] = gm[q][p] = 0.0;
      gm[p][p] = 1.0;
      gm[p][kN] = 0.0;
    } else {
      gm[p][p] += kLambda * diag[p];
    }
  }
  for (int k = 0; k < kN; ++k) {
    int piv = k;
    for (int i = k + 1; i < kN; ++i)
      if (ref_fabs(gm[i][k]) > ref_fabs(gm[piv][k])) piv = i;
    for (int j = 0; j <= kN; ++j) {
      const double t = gm[k][j];
      gm[k][j] = gm[piv][j];
      gm[piv][j] = t;
    }
    for (int i = k + 1; i < kN; ++i) {
      const double m = gm[i][k] / gm[k][k];
      for (int j = k; j <= kN; ++j)
        gm[i][j] -= m * gm[k][j];
    }
  }
  double c[kN];
  for (int k = kN - 1; k >= 0; --k) {
    double acc = gm[k][kN];
    for (int j = k + 1; j < kN; ++j)
      acc -= gm[k][j] * c[j];
    c[k] = acc / gm[k][k];
  }
  double total = 0.0;
  for (uint32_t i = 0; i < n; ++i) {
    double r = a.blurred[i].raw() / kUQ8_8One - b.blurred[i].raw() / kUQ8_8One;
    for (int p = 0; p < kN; ++p)
      if (used[p]) r += col(p, i) * c[p];
    total += r * r;
  }
  for (int p = 0; p < kN; ++p)
    if (used[p]) total += kLambda * diag[p] * c[p] * c[p];
  return total;
}

// Prepares px_a / px_b, checks them and their distance against the references.
TangentDistance check_pair(ImageSize s, const BlurKernel& k) {
  EXPECT_EQ(prepare_tangent_image(ImageView{g_px_a, s}, k, &g_a), Status::kOk);
  EXPECT_EQ(prepare_tangent_image(ImageView{g_px_b, s}, k, &g_b), Status::kOk);
  check_prepared(g_px_a, s, k, g_a);
  check_prepared(g_px_b, s, k, g_b);
  const Result<TangentDistance> r = tangent_distance(g_a, g_b);
  EXPECT_TRUE(r.ok());
  const TangentDistance td = r.value();
  double plain = 0.0;
  for (uint32_t i = 0; i < s.pixels(); ++i) {
    const double d = g_a.blurred[i].raw() / kUQ8_8One - g_b.blurred[i].raw() / kUQ8_8One;
    plain += d * d;
  }
  EXPECT_EQ(static_cast<double>(td.plain_squared.raw()) / kQ47_16One, plain);  // exact
  const double ref = ref_td(g_a, g_b);
  const double got = static_cast<double>(td.squared.raw()) / kQ47_16One;
  const double err = ref_fabs(got - ref);
  EXPECT_LE(err, kTdRelBound * plain + kTdAbsBound) << "ref " << ref << " got " << got;
  EXPECT_LE(td.squared.raw(), td.plain_squared.raw());
  EXPECT_GE(td.squared.raw(), 0);
  if (err > g_td_abs) g_td_abs = err;
  if (plain > 0.0 && err / plain > g_td_rel) g_td_rel = err / plain;
  // rms: floor(sqrt(TD / A)) in UQ8.8, within 1/256 below the exact value (+ rounding of
  // the mean).
  const double rms = test::ref_sqrt(got / s.pixels());
  EXPECT_LE(td.rms.raw() / kUQ8_8One, rms + 1e-3);
  EXPECT_GE(td.rms.raw() / kUQ8_8One, rms - 1.0 / kUQ8_8One - 1e-3);
  return td;
}

// Prints and resets the worst errors seen by check_pair in the current test (ctest runs each
// test in its own process, so every test reports its own figures).
void log_worst(const char* test_name) {
  EXPECT_GT(g_blur_err + g_tangent_err, 0.0) << "no comparison ran in " << test_name;
  test::log_figure("  blur worst |error| (grey, bound 1/256)", g_blur_err);
  test::log_figure("  tangent worst |error| (grey, bound 3/256)", g_tangent_err);
  test::log_figure("  TD worst |error| (grey^2)", g_td_abs);
  test::log_figure("  TD worst |error| / ||d||^2 (bound 2^-30 + 2^-15 abs)", g_td_rel);
  g_blur_err = g_tangent_err = g_td_abs = g_td_rel = 0.0;
}

void random_image(test::Rng& rng, uint8_t* px, uint32_t n) {
  for (uint32_t i = 0; i < n; ++i)
    px[i] = static_cast<uint8_t>(rng.below(256));
}

TEST(TangentDistance, KernelMatchesGaussian) {
  const uint32_t sigmas[] = {64, 128, 179, 256, 384, 512, 1, 100};
  for (uint32_t s : sigmas) {
    const BlurKernel k = kernel_for(s);
    const double sigma = s / kUQ8_8One;
    EXPECT_EQ(k.radius, (s + 127) / 128);
    double g[kMaxBlurRadius + 1];
    double total = 0.0;
    for (int i = 0; i <= k.radius; ++i) {
      g[i] = test::ref_exp(-(i * i) / (2.0 * sigma * sigma));
      total += i == 0 ? g[i] : 2.0 * g[i];
    }
    uint32_t sum = k.weight[0];
    for (int i = 1; i <= k.radius; ++i) {
      sum += 2u * k.weight[i];
      EXPECT_LE(ref_fabs(k.weight[i] - 4096.0 * g[i] / total), 0.5 + 1e-9) << "sigma " << s;
    }
    EXPECT_EQ(sum, 4096u);
    EXPECT_LE(ref_fabs(k.weight[0] - 4096.0 * g[0] / total), k.radius + 1.0);
  }
  EXPECT_EQ(make_blur_kernel(UQ8_8::from_raw(0)).value().weight[0], 4096);
  EXPECT_EQ(make_blur_kernel(UQ8_8::from_raw(513)).status(), Status::kOutOfRange);
  // sigma 1: weights of exp(-k^2/2) normalised: 0.4026, 0.2442, 0.0545 (radius 2).
  const BlurKernel k1 = kernel_for(256);
  EXPECT_EQ(k1.radius, 2);
  EXPECT_NEAR(k1.weight[1], 1000, 2);
  EXPECT_NEAR(k1.weight[2], 223, 2);
}

TEST(TangentDistance, RandomImagesMatchDouble) {
  test::Rng rng(61);
  const ImageSize sizes[] = {{32, 16}, {12, 10}, {7, 5}};
  const uint32_t sigmas[] = {0, 128, 256, 512};
  for (ImageSize s : sizes)
    for (uint32_t sg : sigmas)
      for (int trial = 0; trial < 3; ++trial) {
        random_image(rng, g_px_a, s.pixels());
        random_image(rng, g_px_b, s.pixels());
        check_pair(s, kernel_for(sg));
      }
  // Near-identical images: L_A ~ L_B makes the unregularised system singular.
  for (int trial = 0; trial < 4; ++trial) {
    random_image(rng, g_px_a, 512);
    for (uint32_t i = 0; i < 512; ++i)
      g_px_b[i] = static_cast<uint8_t>(g_px_a[i] ^ (rng.below(8) == 0 ? 1 : 0));
    check_pair(ImageSize{32, 16}, kernel_for(256));
  }
  // Identical images: exactly zero.
  random_image(rng, g_px_a, 512);
  for (uint32_t i = 0; i < 512; ++i)
    g_px_b[i] = g_px_a[i];
  EXPECT_EQ(check_pair(ImageSize{32, 16}, kernel_for(256)).squared.raw(), 0);
  log_worst("random and near-identical images");
}

TEST(TangentDistance, TangentSetsLeaveTangentsOut) {
  // A prepared image without some tangents: those are zero (and so their Gram entries), the
  // others and the blur are as in the full preparation, and the distance still matches the
  // double-precision solve of the smaller system within the same bound. With fewer
  // directions to move along it can only grow (up to rounding).
  test::Rng rng(97);
  const ImageSize s{32, 16};
  const BlurKernel k = kernel_for(256);
  static TangentImage full_a, full_b;
  const uint8_t sets[] = {kTangentsWithoutScaling, kTangentShiftX | kTangentShiftY,
                          kTangentRotation, 0};
  for (uint8_t set : sets) {
    for (int trial = 0; trial < 3; ++trial) {
      random_image(rng, g_px_a, s.pixels());
      for (uint32_t i = 0; i < s.pixels(); ++i)  // a related image: the distance is not trivial
        g_px_b[i] = static_cast<uint8_t>((g_px_a[i] + rng.below(40)) & 0xFF);
      ASSERT_EQ(prepare_tangent_image(ImageView{g_px_a, s}, k, &full_a), Status::kOk);
      ASSERT_EQ(prepare_tangent_image(ImageView{g_px_b, s}, k, &full_b), Status::kOk);
      ASSERT_EQ(prepare_tangent_image(ImageView{g_px_a, s}, k, &g_a, set), Status::kOk);
      ASSERT_EQ(prepare_tangent_image(ImageView{g_px_b, s}, k, &g_b, set), Status::kOk);
      for (int c = 0; c < kTangentCount; ++c) {
        const bool kept = (set & (1u << c)) != 0;
        for (uint32_t i = 0; i < s.pixels(); ++i) {
          EXPECT_EQ(g_a.tangent[c][i].raw(), kept ? full_a.tangent[c][i].raw() : 0);
          EXPECT_EQ(g_a.blurred[i].raw(), full_a.blurred[i].raw());
        }
      }
      int gi = 0;
      for (int a = 0; a < kTangentCount; ++a)
        for (int b = a; b < kTangentCount; ++b, ++gi) {
          const bool kept = (set & (1u << a)) != 0 && (set & (1u << b)) != 0;
          EXPECT_EQ(g_a.gram[gi], kept ? full_a.gram[gi] : 0);
        }
      const TangentDistance some = tangent_distance(g_a, g_b).value();
      const TangentDistance all = tangent_distance(full_a, full_b).value();
      const double plain = static_cast<double>(some.plain_squared.raw()) / kQ47_16One;
      const double ref = ref_td(g_a, g_b);
      const double got = static_cast<double>(some.squared.raw()) / kQ47_16One;
      EXPECT_LE(ref_fabs(got - ref), kTdRelBound * plain + kTdAbsBound) << int{set};
      EXPECT_GE(got + kTdRelBound * plain + kTdAbsBound,
                static_cast<double>(all.squared.raw()) / kQ47_16One);
      if (set == 0) {  // no tangents: the plain distance
        EXPECT_EQ(some.squared.raw(), some.plain_squared.raw());
      }
    }
  }
  EXPECT_EQ(prepare_tangent_image(ImageView{g_px_a, s}, k, &g_a, 0x10), Status::kInvalidArgument);
}

TEST(TangentDistance, FlatImagesGivePlainDistance) {
  const ImageSize s{32, 16};
  for (uint32_t i = 0; i < 512; ++i)
    g_px_a[i] = 100, g_px_b[i] = 130;
  const TangentDistance td = check_pair(s, kernel_for(256));
  for (int c = 0; c < kTangentCount; ++c)
    for (uint32_t i = 0; i < 512; ++i)
      ASSERT_EQ(g_a.tangent[c][i].raw(), 0);
  EXPECT_EQ(td.squared.raw(), td.plain_squared.raw());
  EXPECT_EQ(td.squared.raw(), Q47_16::from_int(900 * 512).raw());
  EXPECT_EQ(td.rms.raw(), UQ8_8::from_int(30).raw());
  // One flat side: only the other image's tangents are used.
  test::Rng rng(62);
  random_image(rng, g_px_b, 512);
  const TangentDistance one = check_pair(s, kernel_for(256));
  EXPECT_LT(one.squared.raw(), one.plain_squared.raw());
  log_worst("flat images");
}

TEST(TangentDistance, CheckerboardExtremes) {
  const ImageSize s{32, 16};
  const uint32_t sigmas[] = {0, 128, 256, 512};
  for (uint32_t sg : sigmas) {
    for (uint32_t y = 0; y < 16; ++y)
      for (uint32_t x = 0; x < 32; ++x) {
        g_px_a[y * 32 + x] = ((x + y) & 1) != 0 ? 255 : 0;
        g_px_b[y * 32 + x] = ((x / 2 + y / 3) & 1) != 0 ? 0 : 255;
      }
    check_pair(s, kernel_for(sg));
    // Largest tangents: a single 0/255 step, unblurred, in the corners.
    for (uint32_t y = 0; y < 16; ++y)
      for (uint32_t x = 0; x < 32; ++x)
        g_px_b[y * 32 + x] = (x < 1 || y < 1 || x >= 31 || y >= 15) ? 255 : 0;
    check_pair(s, kernel_for(sg));
  }
  log_worst("0/255 checkerboards and steps");
}

TEST(TangentDistance, TinyAndMaximalSizes) {
  test::Rng rng(63);
  const ImageSize sizes[] = {{1, 1},
                             {2, 1},
                             {1, 2},
                             {3, 2},
                             {static_cast<uint16_t>(kMaxPixels), 1},
                             {1, static_cast<uint16_t>(kMaxPixels)},
                             {static_cast<uint16_t>(kMaxPixels / 16), 16}};
  for (ImageSize s : sizes) {
    random_image(rng, g_px_a, s.pixels());
    random_image(rng, g_px_b, s.pixels());
    const TangentDistance td = check_pair(s, kernel_for(256));
    if (s.pixels() == 1) {
      EXPECT_EQ(td.squared.raw(), td.plain_squared.raw());
    }
  }
  // Bad input.
  const BlurKernel k = kernel_for(256);
  const ImageSize too_big{static_cast<uint16_t>(kMaxPixels + 1), 1};
  EXPECT_EQ(prepare_tangent_image(ImageView{g_px_a, too_big}, k, &g_a), Status::kOutOfRange);
  EXPECT_EQ(prepare_tangent_image(ImageView{g_px_a, ImageSize{0, 4}}, k, &g_a),
            Status::kInvalidArgument);
  EXPECT_EQ(prepare_tangent_image(ImageView{nullptr, ImageSize{4, 4}}, k, &g_a),
            Status::kInvalidArgument);
  BlurKernel bad = k;
  bad.weight[0] = static_cast<uint16_t>(bad.weight[0] + 1);
  EXPECT_EQ(prepare_tangent_image(ImageView{g_px_a, ImageSize{4, 4}}, bad, &g_a),
            Status::kInvalidArgument);
  EXPECT_EQ(gaussian_blur(ImageView{g_px_a, ImageSize{4, 4}}, bad, g_a.blurred),
            Status::kInvalidArgument);
  ASSERT_EQ(prepare_tangent_image(ImageView{g_px_a, ImageSize{4, 4}}, k, &g_a), Status::kOk);
  ASSERT_EQ(prepare_tangent_image(ImageView{g_px_a, ImageSize{8, 2}}, k, &g_b), Status::kOk);
  EXPECT_EQ(tangent_distance(g_a, g_b).status(), Status::kInvalidArgument);
  // gaussian_blur alone equals the prepared image's blur.
  UQ8_8 out[16];
  ASSERT_EQ(gaussian_blur(ImageView{g_px_a, ImageSize{4, 4}}, k, out), Status::kOk);
  for (int i = 0; i < 16; ++i)
    EXPECT_EQ(out[i].raw(), g_a.blurred[i].raw());
  log_worst("tiny and maximal sizes");
}

// A smooth scene sampled at arbitrary points: the same continuous image can be shifted,
// rotated or scaled exactly.
double scene(double x, double y, int variant) {
  const double p = variant * 1.7;
  double v = 128.0 + 50.0 * test::ref_sin(0.31 * x + 0.23 * y + p) +
             35.0 * test::ref_sin(0.19 * x - 0.41 * y + 2.0 * p + 1.0) +
             25.0 * test::ref_cos(0.07 * x * (1 + variant) + 0.5 * y - p);
  return v < 0.0 ? 0.0 : (v > 255.0 ? 255.0 : v);
}

// Renders the scene at sample points transformed about the image centre: rotate by `deg`
// degrees, scale by `scale`, then translate by (tx, ty).
void render(uint8_t* px, ImageSize s, int variant, double deg, double scale, double tx, double ty) {
  const double a = deg * test::kPi / 180.0;
  const double cs = test::ref_cos(a) * scale, sn = test::ref_sin(a) * scale;
  const double cx = (s.width - 1) / 2.0, cy = (s.height - 1) / 2.0;
  for (int y = 0; y < s.height; ++y)
    for (int x = 0; x < s.width; ++x) {
      const double u = x - cx, v = y - cy;
      const double sx = cx + cs * u - sn * v + tx, sy = cy + sn * u + cs * v + ty;
      px[y * s.width + x] = static_cast<uint8_t>(test::ref_round(scene(sx, sy, variant)));
    }
}

TEST(TangentDistance, InvariantToSmallTransformsNotToContent) {
  const ImageSize s{32, 16};
  const BlurKernel k = kernel_for(default_td_sigma(s).raw());
  EXPECT_EQ(default_td_sigma(s).raw(), 256);
  struct Case {
    const char* name;
    double deg, scale, tx, ty;
  };
  const Case cases[] = {{"shift x 1 px", 0, 1, 1, 0},
                        {"shift y 1 px", 0, 1, 0, 1},
                        {"rotate 4 deg", 4, 1, 0, 0},
                        {"scale 1.06", 0, 1.06, 0, 0}};
  double worst_ratio = 0.0, best_unrelated = 1.0;
  int64_t worst_near_td = 0, best_far_td = INT64_MAX;
  for (int variant = 0; variant < 3; ++variant) {
    render(g_px_a, s, variant, 0, 1, 0, 0);
    for (const Case& c : cases) {
      render(g_px_b, s, variant, c.deg, c.scale, c.tx, c.ty);
      const TangentDistance td = check_pair(s, k);
      const double ratio =
          static_cast<double>(td.squared.raw()) / static_cast<double>(td.plain_squared.raw());
      EXPECT_LT(ratio, 0.2) << c.name << " variant " << variant;
      if (ratio > worst_ratio) worst_ratio = ratio;
      if (td.squared.raw() > worst_near_td) worst_near_td = td.squared.raw();
    }
    render(g_px_b, s, (variant + 1) % 3, 0, 1, 0, 0);
    const TangentDistance far = check_pair(s, k);
    const double ratio =
        static_cast<double>(far.squared.raw()) / static_cast<double>(far.plain_squared.raw());
    EXPECT_GT(ratio, 0.3) << "unrelated, variant " << variant;
    if (ratio < best_unrelated) best_unrelated = ratio;
    if (far.squared.raw() < best_far_td) best_far_td = far.squared.raw();
  }
  // Every unrelated pair stays well above every transformed pair.
  EXPECT_GT(best_far_td, 3 * worst_near_td);
  test::log_figure("smallest unrelated TD / largest transformed TD",
                   static_cast<double>(best_far_td) / static_cast<double>(worst_near_td));
  test::log_figure("td/plain, worst small transform", worst_ratio);
  test::log_figure("td/plain, most similar unrelated", best_unrelated);
  log_worst("smooth scenes");
}

}  // namespace
}  // namespace seqslam
