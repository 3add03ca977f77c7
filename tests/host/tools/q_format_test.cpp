// seqslam_tools/q_format.h: the host's conversions between the core's fixed-point formats and
// doubles, against exact values (the conversions are exact or round to nearest, ties away
// from zero, so every expected value here is exact).
#include "seqslam_tools/q_format.h"

#include <gtest/gtest.h>

namespace seqslam::tools {
namespace {

constexpr double kTwoPi = 6.283185307179586;  // the double nearest 2 pi

TEST(QFormat, UnsignedFormatsRoundToNearestTiesAwayFromZero) {
  // UQ8.8 (the heuristic's threshold, the slope search's velocities).
  EXPECT_EQ(from_double<UQ8_8>(0.8).raw(), 205u);      // 204.8
  EXPECT_EQ(from_double<UQ8_8>(1.2).raw(), 307u);      // 307.2
  EXPECT_EQ(from_double<UQ8_8>(0.5 / 256).raw(), 1u);  // a tie: away from zero
  EXPECT_EQ(from_double<UQ8_8>(1.5 / 256).raw(), 2u);
  EXPECT_EQ(to_double(UQ8_8::from_raw(205)), 0.80078125);
  EXPECT_EQ(to_double(UQ8_8::from_raw(65535)), 255.99609375);
  // UQ16.16 (the confidence threshold).
  EXPECT_EQ(from_double<UQ16_16>(0.85).raw(), 55706u);  // 55705.6
  EXPECT_EQ(to_double(UQ16_16::from_raw(55706)), 55706.0 / 65536);
  EXPECT_EQ(to_double(UQ16_16::from_raw(0xFFFFFFFFu)), 65535.9999847412109375);
}

TEST(QFormat, SignedFormatsRoundNegativeTiesAwayFromZero) {
  EXPECT_EQ(from_double<Q31_32>(-1.5).raw(), -(int64_t{3} << 31));
  EXPECT_EQ(from_double<Q15_16>(-0.5 / 65536).raw(), -1);  // a tie: away from zero
  EXPECT_EQ(from_double<Q15_16>(-0.4 / 65536).raw(), 0);
  EXPECT_EQ(from_double<Q15_16>(-2.6 / 65536).raw(), -3);
  EXPECT_EQ(to_double(Q15_16::from_raw(-1)), -1.0 / 65536);
  EXPECT_EQ(to_double(Q31_32::from_raw(-(int64_t{3} << 31))), -1.5);
}

TEST(QFormat, UnsignedTurnsReadTheTopBitAsHalfATurn) {
  EXPECT_EQ(unsigned_turns(Angle{0}), 0.0);
  EXPECT_EQ(unsigned_turns(Angle{1}), 1.0 / 4294967296.0);
  EXPECT_EQ(unsigned_turns(Angle{0x80000000u}), 0.5);
  EXPECT_EQ(signed_turns(Angle{0x80000000u}), -0.5);
  EXPECT_EQ(unsigned_turns(Angle{0xFFFFFFFFu}), 1.0 - 1.0 / 4294967296.0);
  // Above half a turn the two readings differ by exactly one turn.
  for (const uint32_t bam : {0x80000000u, 0xC0000000u, 0xFFFFFFFFu, 0x9E3779B9u})
    EXPECT_EQ(unsigned_turns(Angle{bam}) - signed_turns(Angle{bam}), 1.0) << bam;
  for (const uint32_t bam : {0u, 1u, 0x40000000u, 0x7FFFFFFFu})
    EXPECT_EQ(unsigned_turns(Angle{bam}), signed_turns(Angle{bam})) << bam;
}

TEST(QFormat, UnsignedRadiansLieInOneTurn) {
  EXPECT_EQ(to_unsigned_radians(Angle{0}), 0.0);
  EXPECT_EQ(to_unsigned_radians(Angle{0x40000000u}), kTwoPi / 4);  // pi / 2, exactly
  EXPECT_EQ(to_unsigned_radians(Angle{0x80000000u}), kTwoPi / 2);  // pi, not -pi
  EXPECT_EQ(to_radians(Angle{0x80000000u}), -kTwoPi / 2);
  EXPECT_NEAR(to_unsigned_radians(Angle{0xC0000000u}), 0.75 * kTwoPi, 1e-15);
  EXPECT_LT(to_unsigned_radians(Angle{0xFFFFFFFFu}), kTwoPi);
}

TEST(QFormat, Angle16RoundsDirectlyToSixteenBits) {
  EXPECT_EQ(angle16_from_radians(0.0), 0u);
  EXPECT_EQ(angle16_from_radians(kTwoPi / 4), 16384u);
  EXPECT_EQ(angle16_from_radians(-kTwoPi / 4), 49152u);  // negative: wrapped to one turn
  EXPECT_EQ(angle16_from_radians(kTwoPi * 5 + kTwoPi / 2), 32768u);
  // Half a step is a tie: away from zero.
  EXPECT_EQ(angle16_from_radians(kTwoPi / 131072), 1u);
  EXPECT_EQ(angle16_from_radians(kTwoPi / 65536 * 1.49), 1u);
  EXPECT_EQ(angle16_from_radians(-kTwoPi / 65536), 65535u);
  // Within half a step below a whole turn: wraps to 0, not 65536.
  EXPECT_EQ(angle16_from_radians(-kTwoPi / 131072), 0u);
  EXPECT_EQ(angle16_from_radians(-1e-9), 0u);
  // Just below half a step: 0, though the nearest 32-bit angle (32768 BAM) is half a step.
  const double just_below = 32767.75 / 4294967296.0 * kTwoPi;
  EXPECT_EQ(angle16_from_radians(just_below), 0u);
  EXPECT_EQ(angle_from_radians(just_below).bam, 32768u);
}

}  // namespace
}  // namespace seqslam::tools
