// The reference maths (ref_math.h) on both sides: known values (computed with 200-bit
// arithmetic) and identities. On the target this exercises libgcc's soft-float, which must
// reproduce the host's IEEE results; test_ref_math.cpp checks the host against <cmath>.
#include "test.h"

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

double relative(double actual, double expected) {
  return ref_fabs(actual - expected) / ref_fabs(expected);
}

TEST(RefMathIdentities, KnownValues) {
  EXPECT_NEAR(ref_sin(1.0), 0.84147098480789650665, 1e-15);
  EXPECT_NEAR(ref_cos(1.0), 0.5403023058681397174, 1e-15);
  EXPECT_NEAR(ref_sin(1000.0), 0.82687954053200256026, 1e-15);
  EXPECT_NEAR(ref_cos(9999.5), -0.98211429039236216133, 1e-15);
  EXPECT_NEAR(ref_atan2(1.0, -2.0), 2.6779450445889871222, 1e-15);
  EXPECT_LE(relative(ref_exp(1.0), 2.7182818284590452354), 1e-15);
  EXPECT_LE(relative(ref_exp(-10.5), 0.000027536449349747157857), 1e-15);
  EXPECT_LE(relative(ref_log(10.0), 2.302585092994045684), 1e-15);
  EXPECT_LE(relative(ref_log(1e-5), -11.512925464970228338), 1e-15);
  EXPECT_LE(relative(ref_sqrt(2.0), 1.4142135623730950488), 1e-15);
  EXPECT_LE(relative(ref_pow(0.5, 2.2), 0.21763764082403100799), 1e-15);
  EXPECT_LE(relative(ref_pow(0.3, 0.45), 0.58170736792793830916), 1e-15);
}

TEST(RefMathIdentities, ExactOperations) {
  EXPECT_EQ(ref_floor(-2.5), -3.0);
  EXPECT_EQ(ref_floor(2.5), 2.0);
  EXPECT_EQ(ref_round(-2.5), -3.0);
  EXPECT_EQ(ref_round(2.5), 3.0);
  EXPECT_EQ(ref_round(0.49999999999999994), 0.0);
  EXPECT_EQ(ref_fabs(-3.25), 3.25);
  EXPECT_EQ(ref_sqrt(144.0), 12.0);
  EXPECT_EQ(ref_pow(2.0, 10.0), 1024.0);
  EXPECT_EQ(ref_exp(0.0), 1.0);
  EXPECT_EQ(ref_log(1.0), 0.0);
}

TEST(RefMathIdentities, Identities) {
  for (int i = -200; i <= 200; ++i) {
    const double x = 0.37 * i;
    const double s = ref_sin(x);
    const double c = ref_cos(x);
    ASSERT_NEAR(s * s + c * c, 1.0, 4e-16) << "x=" << x;
    const double e = ref_exp(0.05 * i);
    ASSERT_NEAR(ref_log(e), 0.05 * i, 1e-15 * (1.0 + ref_fabs(0.05 * i))) << "i=" << i;
  }
  for (int i = -200; i <= 200; ++i) {
    const double x = 0.0157 * i;  // within (-pi, pi), where atan2(sin x, cos x) = x
    ASSERT_NEAR(ref_atan2(ref_sin(x), ref_cos(x)), x, 1e-15) << "x=" << x;
  }
  for (int i = 1; i <= 100; ++i) {
    const double x = 0.01 * i;
    ASSERT_LE(relative(ref_pow(x, 2.0), x * x), 4.5e-16) << "x=" << x;
    ASSERT_LE(relative(ref_pow(x, 0.5), ref_sqrt(x)), 4.5e-16) << "x=" << x;
  }
}

}  // namespace
