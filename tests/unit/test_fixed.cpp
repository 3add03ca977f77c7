// Fixed-point types: rounding, saturation and the 128-bit intermediate.
#include "seqslam/fixed.h"

#include "seqslam/fixmath.h"
#include "test.h"

namespace seqslam {
namespace {

TEST(Fixed, FromRatioRoundsToNearestTiesAwayFromZero) {
  using Q = Fixed<int32_t, 1>;                                 // steps of 0.5
  EXPECT_EQ(Q::from_ratio(1, 4).raw(), 1);                     // 0.25 -> 0.5 (tie away from zero)
  EXPECT_EQ(Q::from_ratio(-1, 4).raw(), -1);                   // -0.25 -> -0.5
  EXPECT_EQ(Q::from_ratio(1, 5).raw(), 0);                     // 0.2 -> 0
  EXPECT_EQ(Q::from_ratio(3, -4).raw(), -2);                   // -0.75 -> -1.0
  EXPECT_EQ(Q31_32::from_ratio(532, 1000).raw(), 2284922601);  // round(0.532 * 2^32)
}

TEST(Fixed, FromIntSaturates) {
  EXPECT_EQ(Q15_16::from_int(5).raw(), 5 * 65536);
  EXPECT_EQ(Q15_16::from_int(40000).raw(), Q15_16::max().raw());
  EXPECT_EQ(Q15_16::from_int(-40000).raw(), Q15_16::min().raw());
  EXPECT_EQ(UQ8_8::from_int(-1).raw(), 0);
}

TEST(Fixed, AdditionAndSubtractionSaturate) {
  const Q15_16 big = Q15_16::from_int(30000);
  EXPECT_EQ((big + big).raw(), Q15_16::max().raw());
  EXPECT_EQ((-big - big).raw(), Q15_16::min().raw());
  EXPECT_EQ((Q15_16::from_int(2) + Q15_16::from_int(3)).raw(), Q15_16::from_int(5).raw());
  EXPECT_EQ((UQ16_16::from_int(1) - UQ16_16::from_int(2)).raw(), 0u);
  EXPECT_EQ((-Q15_16::min()).raw(), Q15_16::max().raw());
}

TEST(Fixed, MultiplyRoundsAndSaturates) {
  const Q15_16 a = Q15_16::from_ratio(3, 2);
  const Q15_16 b = Q15_16::from_ratio(-5, 4);
  EXPECT_EQ(mul_sat<Q15_16>(a, b).raw(), Q15_16::from_ratio(-15, 8).raw());
  // 2^-16 * 0.5 = 2^-17: a tie at Q15.16, rounds away from zero.
  EXPECT_EQ(mul_sat<Q15_16>(Q15_16::from_raw(1), Q15_16::from_ratio(1, 2)).raw(), 1);
  EXPECT_EQ(mul_sat<Q15_16>(Q15_16::from_raw(-1), Q15_16::from_ratio(1, 2)).raw(), -1);
  EXPECT_EQ(mul_sat<Q15_16>(Q15_16::from_int(300), Q15_16::from_int(300)).raw(),
            Q15_16::max().raw());
  // Mixed formats: Q31.32 metres times Q1.30 cosine into Q31.32.
  const Q31_32 d = Q31_32::from_ratio(1, 8);
  const Q1_30 half = Q1_30::from_ratio(1, 2);
  EXPECT_EQ(mul_sat<Q31_32>(d, half).raw(), Q31_32::from_ratio(1, 16).raw());
}

TEST(Fixed, NarrowAndDivide) {
  EXPECT_EQ(narrow_sat<UQ8_8>(UQ16_16::from_ratio(3, 1024)).raw(), 1);  // 0.0029 -> 1/256
  EXPECT_EQ(narrow_sat<UQ8_8>(UQ16_16::from_int(300)).raw(), 65535);
  EXPECT_EQ(div_sat<UQ16_16>(UQ16_16::from_int(1), UQ16_16::from_int(3)).raw(), 21845u);
  EXPECT_EQ(div_sat<Q15_16>(Q15_16::from_int(-1), Q15_16::from_int(3)).raw(), -21845);
  EXPECT_EQ(div_sat<Q15_16>(Q15_16::from_int(1), Q15_16::from_raw(0)).raw(), Q15_16::max().raw());
  EXPECT_EQ(div_sat<Q15_16>(Q15_16::from_int(-1), Q15_16::from_raw(0)).raw(), Q15_16::min().raw());
  EXPECT_EQ(div_sat<Q15_16>(Q15_16::from_raw(0), Q15_16::from_raw(0)).raw(), 0);
}

TEST(Fixed, IntegerParts) {
  EXPECT_EQ(Q15_16::from_ratio(-3, 2).floor_int(), -2);
  EXPECT_EQ(Q15_16::from_ratio(-3, 2).round_int(), -2);
  EXPECT_EQ(Q15_16::from_ratio(5, 2).round_int(), 3);
  EXPECT_EQ(Q15_16::from_ratio(9, 4).round_int(), 2);
}

TEST(Int128, ArithmeticMatchesSchoolbook) {
  const Int128 a = Int128(0x123456789ABCDEF0LL);
  const Int128 b = Int128(-0x0FEDCBA987654321LL);
  const Int128 p = a * b;
  EXPECT_TRUE(p.negative());
  // (p / b) == a exactly, and shifting round trips.
  EXPECT_TRUE(p.div(b) == a);
  EXPECT_TRUE(a.shl(40).sar(40) == a);
  EXPECT_TRUE(b.shl(3).sar(3) == b);
  EXPECT_TRUE((-a).sar(64) == Int128(-1));
  EXPECT_TRUE(Int128(-1).sar(100) == Int128(-1));
  EXPECT_TRUE(Int128(7).div(Int128(-2)) == Int128(-3));  // truncation towards zero
  const Int128 m = Int128::mul_u64(0xFFFFFFFFFFFFFFFFull, 0xFFFFFFFFFFFFFFFFull);
  EXPECT_EQ(m.high64(), 0xFFFFFFFFFFFFFFFEull);
  EXPECT_EQ(m.low64(), 1ull);
}

#if defined(__SIZEOF_INT128__)
__extension__ typedef __int128 CompilerInt128;

TEST(Int128, RandomAgainstCompilerInt128) {
  uint64_t s = 12345;
  for (int i = 0; i < 20000; ++i) {
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    const int64_t x = static_cast<int64_t>(s);
    s = s * 6364136223846793005ull + 1442695040888963407ull;
    const int64_t y = static_cast<int64_t>(s >> (s & 31));
    const CompilerInt128 ref = static_cast<CompilerInt128>(x) * y;
    const Int128 got = Int128(x) * Int128(y);
    ASSERT_EQ(got.low64(), static_cast<uint64_t>(ref));
    ASSERT_EQ(got.high64(), static_cast<uint64_t>(ref >> 64));
    if (y != 0) {
      const CompilerInt128 q = ref / y;
      const Int128 gq = got.div(Int128(y));
      ASSERT_EQ(gq.low64(), static_cast<uint64_t>(q));
      ASSERT_EQ(gq.high64(), static_cast<uint64_t>(q >> 64));
    }
    const int sh = static_cast<int>(s % 127);
    ASSERT_EQ(got.sar(sh).low64(), static_cast<uint64_t>(ref >> sh));
  }
}
#endif

TEST(Angle, DegreesAndDifferences) {
  EXPECT_EQ(Angle::from_degrees(90).bam, 1u << 30);
  EXPECT_EQ(Angle::from_degrees(-90).bam, 3u << 30);
  EXPECT_EQ(Angle::from_degrees(360).bam, 0u);
  EXPECT_EQ(signed_diff(Angle::from_degrees(10), Angle::from_degrees(350)),
            static_cast<int32_t>(Angle::from_degrees(20).bam));
}

}  // namespace
}  // namespace seqslam
