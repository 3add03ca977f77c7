// Spatial sampling: a capture every 20 cm of straight-line travel since the last capture.
#include "seqslam/spatial_trigger.h"

#include "route.h"
#include "test.h"

namespace seqslam {
namespace {

Pose2 at(int64_t x_mm, int64_t y_mm) {
  return Pose2{Q31_32::from_ratio(x_mm, 1000), Q31_32::from_ratio(y_mm, 1000), Angle{}};
}

TEST(SpatialTrigger, FirstPoseCapturesThenEverySpacing) {
  SpatialTrigger t;
  EXPECT_TRUE(t.update(at(0, 0)));
  EXPECT_FALSE(t.update(at(100, 0)));
  EXPECT_FALSE(t.update(at(199, 0)));
  EXPECT_TRUE(t.update(at(200, 0)));
  EXPECT_FALSE(t.update(at(399, 0)));
  EXPECT_TRUE(t.update(at(401, 0)));  // measured from the capture at 200, not from 400
  EXPECT_EQ(t.captures(), 3u);
  EXPECT_EQ(t.last_capture().x.raw(), Q31_32::from_ratio(401, 1000).raw());
}

TEST(SpatialTrigger, UsesEuclideanDistance) {
  SpatialTrigger t;
  EXPECT_TRUE(t.update(at(0, 0)));
  EXPECT_FALSE(t.update(at(141, 141)));  // 199.4 mm
  EXPECT_TRUE(t.update(at(142, 142)));   // 200.8 mm
  EXPECT_FALSE(t.update(at(142 - 100, 142 - 100)));
  EXPECT_TRUE(t.update(at(-100, 142)));  // back and sideways
}

TEST(SpatialTrigger, ConfigurationAndReset) {
  SpatialTrigger t;
  EXPECT_EQ(t.configure(Q31_32::from_int(0)), Status::kInvalidArgument);
  EXPECT_EQ(t.configure(Q31_32::from_int(2000)), Status::kOutOfRange);
  EXPECT_EQ(t.spacing().raw(), SpatialTrigger::kDefaultSpacing.raw());
  ASSERT_EQ(t.configure(Q31_32::from_ratio(1, 2)), Status::kOk);
  EXPECT_TRUE(t.update(at(5000, 0)));
  EXPECT_FALSE(t.update(at(5400, 0)));
  t.reset();
  EXPECT_TRUE(t.update(at(5400, 0)));
}

TEST(SpatialTrigger, LoopOfNinetyTwoMetresGivesAboutFourHundredSixtyPlaces) {
  Odometry o;
  ASSERT_EQ(o.configure(OdometryConfig{}), Status::kOk);
  o.reset(Pose2{}, 0, 0);
  SpatialTrigger t;
  test::LoopDrive drive;
  test::WheelTicks ticks{0, 0};
  while (drive.step(&ticks)) {
    ASSERT_EQ(o.update(static_cast<uint32_t>(ticks.left), static_cast<uint32_t>(ticks.right)),
              Status::kOk);
    t.update(o.pose());
  }
  // Path length / 0.2 m, minus what the chord-vs-arc and per-step overshoot cost.
  const double ideal = drive.distance() / 0.2;
  EXPECT_LE(static_cast<double>(t.captures()), ideal + 1.0);
  EXPECT_GE(static_cast<double>(t.captures()), ideal * 0.98);
}

}  // namespace
}  // namespace seqslam
