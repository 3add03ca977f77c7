// Host check of the reference maths (ref_math.h) against the C library. The tolerances are
// the documented accuracy of the oracle that target-side tests may rely on.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <limits>

#include "ref_math.h"

namespace {

using seqslam::test::kPi;
using seqslam::test::ref_atan2;
using seqslam::test::ref_cos;
using seqslam::test::ref_exp;
using seqslam::test::ref_fabs;
using seqslam::test::ref_floor;
using seqslam::test::ref_log;
using seqslam::test::ref_pow;
using seqslam::test::ref_round;
using seqslam::test::ref_sin;
using seqslam::test::ref_sqrt;

constexpr int kSamples = 200000;
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNan = std::numeric_limits<double>::quiet_NaN();

// Deterministic xorshift64* so failures reproduce.
class Random {
 public:
  explicit Random(uint64_t seed) : state_(seed) {}
  uint64_t next() {
    state_ ^= state_ >> 12;
    state_ ^= state_ << 25;
    state_ ^= state_ >> 27;
    return state_ * 0x2545F4914F6CDD1Du;
  }
  // Uniform in [lo, hi).
  double uniform(double lo, double hi) {
    const double unit = static_cast<double>(next() >> 11) * 0x1p-53;
    return lo + (hi - lo) * unit;
  }
  // Log-uniform in [lo, hi), lo > 0.
  double log_uniform(double lo, double hi) { return std::exp(uniform(std::log(lo), std::log(hi))); }

 private:
  uint64_t state_;
};

double relative_error(double actual, double expected) {
  if (actual == expected) {
    return 0.0;
  }
  return std::fabs(actual - expected) / std::fabs(expected);
}

TEST(RefMath, PiIsTheNearestDouble) {
  EXPECT_EQ(kPi, M_PI);
}

TEST(RefMath, FabsFloorRoundAreExact) {
  Random rng(1);
  const double specials[] = {0.0,
                             -0.0,
                             0.5,
                             -0.5,
                             1.5,
                             -1.5,
                             2.5,
                             -2.5,
                             0.49999999999999994,
                             -0.49999999999999994,
                             4503599627370495.5,
                             -4503599627370495.5,
                             1e300,
                             -1e300,
                             0x1p52,
                             -0x1p52,
                             5e-324,
                             -5e-324,
                             7.0,
                             -7.0};
  for (const double x : specials) {
    EXPECT_EQ(ref_fabs(x), std::fabs(x)) << x;
    EXPECT_EQ(ref_floor(x), std::floor(x)) << x;
    EXPECT_EQ(ref_round(x), std::round(x)) << x;
    EXPECT_EQ(std::signbit(ref_floor(x)), std::signbit(std::floor(x))) << x;
    EXPECT_EQ(std::signbit(ref_round(x)), std::signbit(std::round(x))) << x;
  }
  for (int i = 0; i < kSamples; ++i) {
    const double x = rng.uniform(-1e6, 1e6);
    const double halves = std::floor(x) + 0.5;  // exact ties
    ASSERT_EQ(ref_fabs(x), std::fabs(x)) << x;
    ASSERT_EQ(ref_floor(x), std::floor(x)) << x;
    ASSERT_EQ(ref_round(x), std::round(x)) << x;
    ASSERT_EQ(ref_round(halves), std::round(halves)) << halves;
  }
  EXPECT_TRUE(std::isnan(ref_floor(kNan)));
  EXPECT_EQ(ref_floor(-kInf), -kInf);
  EXPECT_EQ(ref_round(kInf), kInf);
}

TEST(RefMath, SqrtWithinOneUlp) {
  Random rng(2);
  for (int i = 0; i < kSamples; ++i) {
    const double x = rng.log_uniform(1e-300, 1e300);
    ASSERT_LE(relative_error(ref_sqrt(x), std::sqrt(x)), 1e-15) << "x=" << x;
  }
  for (int i = 0; i < 1000; ++i) {
    const double x = rng.uniform(0.0, 1.0) * 0x1p-1040;  // subnormal
    ASSERT_LE(relative_error(ref_sqrt(x), std::sqrt(x)), 1e-15) << "x=" << x;
  }
  for (int i = 1; i <= 10000; ++i) {
    const double square = static_cast<double>(i) * static_cast<double>(i);
    ASSERT_EQ(ref_sqrt(square), static_cast<double>(i));
  }
  EXPECT_EQ(ref_sqrt(0.0), 0.0);
  EXPECT_EQ(ref_sqrt(kInf), kInf);
  EXPECT_TRUE(std::isnan(ref_sqrt(-1.0)));
  EXPECT_TRUE(std::isnan(ref_sqrt(kNan)));
}

void check_sin_cos(double x, double tolerance) {
  ASSERT_LE(std::fabs(ref_sin(x) - std::sin(x)), tolerance) << "sin x=" << x;
  ASSERT_LE(std::fabs(ref_cos(x) - std::cos(x)), tolerance) << "cos x=" << x;
}

TEST(RefMath, SinCosAbsoluteErrorUpTo1000) {
  Random rng(3);
  for (int i = 0; i < kSamples; ++i) {
    ASSERT_NO_FATAL_FAILURE(check_sin_cos(rng.uniform(-1000.0, 1000.0), 2e-15));
  }
  for (int i = 0; i < kSamples / 4; ++i) {
    ASSERT_NO_FATAL_FAILURE(check_sin_cos(rng.uniform(-4.0, 4.0), 2e-15));
  }
  // Near multiples of pi/4, where the reduction switches quadrant or cancels.
  for (int k = -1300; k <= 1300; ++k) {
    const double x = k * (kPi / 4.0);
    ASSERT_NO_FATAL_FAILURE(check_sin_cos(x, 2e-15));
    ASSERT_NO_FATAL_FAILURE(check_sin_cos(std::nextafter(x, kInf), 2e-15));
    ASSERT_NO_FATAL_FAILURE(check_sin_cos(std::nextafter(x, -kInf), 2e-15));
  }
  EXPECT_EQ(ref_sin(0.0), 0.0);
  EXPECT_EQ(ref_cos(0.0), 1.0);
  EXPECT_TRUE(std::isnan(ref_sin(kInf)));
  EXPECT_TRUE(std::isnan(ref_cos(kNan)));
}

TEST(RefMath, SinCosAbsoluteErrorUpTo1e4) {
  Random rng(4);
  for (int i = 0; i < kSamples; ++i) {
    ASSERT_NO_FATAL_FAILURE(check_sin_cos(rng.uniform(-1e4, 1e4), 2e-15));
  }
}

TEST(RefMath, Atan2AbsoluteError) {
  Random rng(5);
  for (int i = 0; i < kSamples; ++i) {
    const double scale = rng.log_uniform(1e-10, 1e10);
    const double y = rng.uniform(-1.0, 1.0) * scale;
    const double x = rng.uniform(-1.0, 1.0) * rng.log_uniform(1e-10, 1e10);
    ASSERT_LE(std::fabs(ref_atan2(y, x) - std::atan2(y, x)), 1e-15) << "y=" << y << " x=" << x;
  }
  for (int i = 0; i < kSamples / 4; ++i) {  // around the breakpoints 0.25, 0.75, 1
    const double x = rng.uniform(0.1, 2.0);
    ASSERT_LE(std::fabs(ref_atan2(x, 1.0) - std::atan2(x, 1.0)), 1e-15) << "x=" << x;
    ASSERT_LE(std::fabs(ref_atan2(-1.0, -x) - std::atan2(-1.0, -x)), 1e-15) << "x=" << x;
  }
  const double specials[] = {0.0, -0.0, 1.0, -1.0, kInf, -kInf};
  for (const double y : specials) {
    for (const double x : specials) {
      const double expected = std::atan2(y, x);
      const double actual = ref_atan2(y, x);
      EXPECT_LE(std::fabs(actual - expected), 1e-15) << "y=" << y << " x=" << x;
      EXPECT_EQ(std::signbit(actual), std::signbit(expected)) << "y=" << y << " x=" << x;
    }
  }
  EXPECT_TRUE(std::isnan(ref_atan2(kNan, 1.0)));
}

TEST(RefMath, ExpRelativeError) {
  Random rng(6);
  for (int i = 0; i < kSamples; ++i) {
    const double x = rng.uniform(-708.0, 709.0);
    ASSERT_LE(relative_error(ref_exp(x), std::exp(x)), 1e-15) << "x=" << x;
  }
  for (int i = 0; i < kSamples / 4; ++i) {
    const double x = rng.uniform(-1.0, 1.0);
    ASSERT_LE(relative_error(ref_exp(x), std::exp(x)), 1e-15) << "x=" << x;
  }
  for (int i = 0; i < 1000; ++i) {  // subnormal results: absolute, in units of the smallest
    const double x = rng.uniform(-744.0, -709.0);
    ASSERT_LE(std::fabs(ref_exp(x) - std::exp(x)), 5e-324 + 1e-15 * std::exp(x)) << "x=" << x;
  }
  EXPECT_EQ(ref_exp(0.0), 1.0);
  EXPECT_EQ(ref_exp(-kInf), 0.0);
  EXPECT_EQ(ref_exp(kInf), kInf);
  EXPECT_EQ(ref_exp(710.0), kInf);
  EXPECT_EQ(ref_exp(-800.0), 0.0);
  EXPECT_TRUE(std::isnan(ref_exp(kNan)));
}

TEST(RefMath, LogRelativeError) {
  Random rng(7);
  for (int i = 0; i < kSamples; ++i) {
    const double x = rng.log_uniform(1e-300, 1e300);
    ASSERT_LE(relative_error(ref_log(x), std::log(x)), 1e-15) << "x=" << x;
  }
  for (int i = 0; i < kSamples / 4; ++i) {  // near 1, where log(x) is small
    const double x = 1.0 + rng.uniform(-0.01, 0.01);
    ASSERT_LE(relative_error(ref_log(x), std::log(x)), 1e-15) << "x=" << x;
  }
  EXPECT_LE(relative_error(ref_log(5e-324), std::log(5e-324)), 1e-15);
  EXPECT_EQ(ref_log(1.0), 0.0);
  EXPECT_EQ(ref_log(0.0), -kInf);
  EXPECT_EQ(ref_log(kInf), kInf);
  EXPECT_TRUE(std::isnan(ref_log(-1.0)));
}

TEST(RefMath, PowRelativeErrorForTheRangesUsed) {
  Random rng(8);
  for (int i = 0; i < kSamples; ++i) {
    const double x = rng.uniform(0.0, 1.0);
    const double y = rng.uniform(0.4, 2.5);
    ASSERT_LE(relative_error(ref_pow(x, y), std::pow(x, y)), 1e-13) << x << "^" << y;
  }
  for (int i = 0; i < kSamples / 4; ++i) {  // small pixels, e.g. 1/255 and below
    const double x = rng.log_uniform(1e-30, 1.0);
    const double y = rng.uniform(0.4, 2.5);
    ASSERT_LE(relative_error(ref_pow(x, y), std::pow(x, y)), 1e-13) << x << "^" << y;
  }
}

TEST(RefMath, PowRelativeErrorWide) {
  Random rng(9);
  for (int i = 0; i < kSamples; ++i) {
    const double x = rng.log_uniform(1e-100, 1e100);
    const double y = rng.uniform(-3.0, 3.0);
    ASSERT_LE(relative_error(ref_pow(x, y), std::pow(x, y)), 2e-15) << x << "^" << y;
  }
  EXPECT_EQ(ref_pow(0.0, 2.0), 0.0);
  EXPECT_EQ(ref_pow(0.0, -1.0), kInf);
  EXPECT_EQ(ref_pow(0.0, 0.0), 1.0);
  EXPECT_EQ(ref_pow(1.0, 1e300), 1.0);
  EXPECT_EQ(ref_pow(2.0, 10.0), 1024.0);
  EXPECT_EQ(ref_pow(0.5, kInf), 0.0);
  EXPECT_EQ(ref_pow(2.0, kInf), kInf);
  EXPECT_EQ(ref_pow(kInf, -1.0), 0.0);
  EXPECT_TRUE(std::isnan(ref_pow(-2.0, 0.5)));
}

}  // namespace
