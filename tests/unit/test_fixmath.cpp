// Integer square roots (exact) and sine/cosine (stated maximum error 1e-9).
#include "seqslam/fixmath.h"

#include "ref_math.h"
#include "synthetic.h"
#include "test.h"
#include "test_log.h"

namespace seqslam {
namespace {

#if defined(SEQSLAM_TEST_GTEST)
constexpr uint32_t kSinCosSamples = 1u << 20;  // host: 2^20 + 1 angles
#else
constexpr uint32_t kSinCosSamples = 1u << 14;  // target: same spread, fewer points (soft float)
#endif

bool is_floor_sqrt32(uint32_t x, uint32_t r) {
  const uint64_t r2 = static_cast<uint64_t>(r) * r;
  const uint64_t r1 = static_cast<uint64_t>(r + 1) * (r + 1);
  return r2 <= x && x < r1;
}

TEST(Isqrt, ExactAroundEverySquareAndAtTheEnds) {
  for (uint32_t r = 0; r < 65536; r += 1) {
    const uint32_t sq = r * r;
    ASSERT_EQ(isqrt32(sq), r);
    if (sq > 0) {
      ASSERT_EQ(isqrt32(sq - 1), r - 1);
    }
    if (r < 65535) {
      ASSERT_EQ(isqrt32(sq + 1), r == 0 ? 1u : r);
    }
  }
  EXPECT_EQ(isqrt32(0xFFFFFFFFu), 65535u);
  EXPECT_EQ(isqrt64(0xFFFFFFFFFFFFFFFFull), 0xFFFFFFFFu);
  EXPECT_EQ(isqrt64(0), 0u);
}

TEST(Isqrt, RandomInputsAreFloorSqrt) {
  test::Rng rng(7);
  for (int i = 0; i < 20000; ++i) {
    const uint32_t x = rng.next32() >> (rng.next32() % 32);
    ASSERT_TRUE(is_floor_sqrt32(x, isqrt32(x))) << x;
    const uint64_t y = rng.next64() >> (rng.next32() % 64);
    const uint64_t r = isqrt64(y);
    ASSERT_TRUE(r * r <= y) << y;
    ASSERT_TRUE(r == 0xFFFFFFFFu || (r + 1) * (r + 1) > y) << y;
  }
}

// Binary angle units in a turn, and one in Q1.30 raw units (sine and cosine).
constexpr double kBamPerTurn = static_cast<double>(uint64_t{1} << 32);
constexpr double kSinCosOne = static_cast<double>(Q1_30::from_int(1).raw());

double max_sincos_error(uint32_t bam, double worst) {
  const SinCos sc = sincos(Angle{bam});
  const double angle = static_cast<double>(bam) * (2.0 * test::kPi / kBamPerTurn);
  const double es =
      test::ref_fabs(static_cast<double>(sc.sin.raw()) / kSinCosOne - test::ref_sin(angle));
  const double ec =
      test::ref_fabs(static_cast<double>(sc.cos.raw()) / kSinCosOne - test::ref_cos(angle));
  if (es > worst) worst = es;
  if (ec > worst) worst = ec;
  return worst;
}

TEST(SinCos, MaximumErrorIsBelowStatedBound) {
  constexpr double kStatedMaxError = 1.0e-9;
  double worst = 0.0;
  const uint32_t step = static_cast<uint32_t>((uint64_t{1} << 32) / kSinCosSamples);
  for (uint64_t k = 0; k <= kSinCosSamples; ++k) {
    worst = max_sincos_error(static_cast<uint32_t>(k * step), worst);
  }
  // Octant boundaries and their neighbours, where the reduction switches branches.
  for (uint32_t octant = 0; octant < 8; ++octant) {
    for (int32_t d = -3; d <= 3; ++d) {
      worst = max_sincos_error((octant << 29) + static_cast<uint32_t>(d), worst);
    }
  }
  test::Rng rng(99);
  for (int i = 0; i < 4096; ++i)
    worst = max_sincos_error(rng.next32(), worst);
  test::log_figure("sincos max error", worst);
  EXPECT_LT(worst, kStatedMaxError) << "max |error| = " << worst;
}

TEST(SinCos, QuarterTurnsAreExact) {
  const int32_t one = 1 << 30;
  const SinCos s0 = sincos(Angle::from_degrees(0));
  const SinCos s90 = sincos(Angle::from_degrees(90));
  const SinCos s180 = sincos(Angle::from_degrees(180));
  const SinCos s270 = sincos(Angle::from_degrees(270));
  EXPECT_EQ(s0.sin.raw(), 0);
  EXPECT_EQ(s0.cos.raw(), one);
  EXPECT_EQ(s90.sin.raw(), one);
  EXPECT_EQ(s90.cos.raw(), 0);
  EXPECT_EQ(s180.sin.raw(), 0);
  EXPECT_EQ(s180.cos.raw(), -one);
  EXPECT_EQ(s270.sin.raw(), -one);
  EXPECT_EQ(s270.cos.raw(), 0);
}

TEST(SinCos, SymmetriesHoldExactly) {
  test::Rng rng(3);
  for (int i = 0; i < 2000; ++i) {
    const uint32_t a = rng.next32();
    const SinCos p = sincos(Angle{a});
    const SinCos n = sincos(Angle{0u - a});
    EXPECT_EQ(p.cos.raw(), n.cos.raw());
    EXPECT_EQ(p.sin.raw(), -n.sin.raw());
  }
}

TEST(DivRound, MatchesRoundHalfAwayFromZero) {
  EXPECT_EQ(div_round(5, 2), 3);
  EXPECT_EQ(div_round(-5, 2), -3);
  EXPECT_EQ(div_round(4, 3), 1);
  EXPECT_EQ(div_round(-4, 3), -1);
  EXPECT_EQ(div_round_i32(7, 2), 4);
  EXPECT_EQ(div_round_i32(-7, 2), -4);
  EXPECT_EQ(div_round_u32(7, 2), 4u);
}

TEST(ParabolaVertex, MatchesDoubleReferenceAndHandlesDegenerateTriples) {
  // (l - r) / (2 (l - 2c + r)) in 2^-16 units, rounded to nearest: within half a unit (plus
  // the double's own rounding) of the exact value for minima of random triples.
  constexpr double kOne = static_cast<double>(Q15_16::from_int(1).raw());
  constexpr int32_t kHalf = Q15_16::from_ratio(1, 2).raw();
  test::Rng rng(42);
  for (int i = 0; i < 20000; ++i) {
    const int64_t c = static_cast<int64_t>(rng.next64() >> 24);  // up to 2^40
    const int64_t l = c + static_cast<int64_t>(rng.next64() >> (24 + rng.below(30)));
    const int64_t r = c + static_cast<int64_t>(rng.next64() >> (24 + rng.below(30)));
    if (l == c && r == c) continue;
    const double want = static_cast<double>(l - r) / (2.0 * static_cast<double>(l - 2 * c + r));
    const int32_t got = parabola_vertex_q16(l, c, r);
    ASSERT_NEAR(got / kOne, want, 0.5 / kOne + 1e-12);
    ASSERT_LE(got, kHalf);
    ASSERT_GE(got, -kHalf);
  }
  EXPECT_EQ(parabola_vertex_q16(5, 3, 1), 0);    // a straight line: no curvature
  EXPECT_EQ(parabola_vertex_q16(7, 7, 7), 0);    // flat
  EXPECT_EQ(parabola_vertex_q16(1, 5, 2), 0);    // a maximum, not a minimum
  EXPECT_EQ(parabola_vertex_q16(10, 0, 10), 0);  // symmetric
  EXPECT_EQ(parabola_vertex_q16(4, 1, 2), Q15_16::from_ratio(1, 4).raw());  // (4 - 2) / (2 * 4)
  EXPECT_EQ(parabola_vertex_q16(1, 1, 9), -kHalf);  // c == l: the vertex at -1/2
  EXPECT_EQ(parabola_vertex_q16(100, 50, 1), Q15_16::from_int(1).raw());  // c > r: clamped to +1
}

TEST(MulShiftRound, WideProductsRoundAndSaturate) {
  // 2^62 * 2^30 / 2^60 = 2^32: the product needs 93 bits.
  EXPECT_EQ(mul_shift_round(int64_t{1} << 62, int64_t{1} << 30, 60), int64_t{1} << 32);
  EXPECT_EQ(mul_shift_round(3, 1, 1), 2);    // 1.5 -> 2
  EXPECT_EQ(mul_shift_round(-3, 1, 1), -2);  // -1.5 -> -2
  EXPECT_EQ(mul_shift_round(int64_t{1} << 62, int64_t{1} << 62, 0),
            static_cast<int64_t>(0x7FFFFFFFFFFFFFFFull));
}

}  // namespace
}  // namespace seqslam
