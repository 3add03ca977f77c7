// Odometry: configuration checks, wrap-around, glitch rejection, the 92 m loop against a
// double-precision integration of the same ticks (issue: within 1 mm and 0.05 degrees), and
// continuing from a saved state.
#include "seqslam/odometry.h"

#include "ram_state.h"
#include "ref_math.h"
#include "route.h"
#include "seqslam/spatial_trigger.h"
#include "test.h"
#include "test_log.h"

namespace seqslam {
namespace {

// One in raw units: a metre in Q31.32, a turn in binary-angle units.
constexpr double kMetre = static_cast<double>(Q31_32::from_int(1).raw());
constexpr double kBamPerTurn = static_cast<double>(uint64_t{1} << 32);

double metres(Q31_32 v) {
  return static_cast<double>(v.raw()) / kMetre;
}
double radians(Angle a) {
  return static_cast<double>(static_cast<int32_t>(a.bam)) * (2.0 * test::kPi / kBamPerTurn);
}

Odometry configured(const OdometryConfig& c = OdometryConfig{}) {
  Odometry o;
  EXPECT_EQ(o.configure(c), Status::kOk);
  o.reset(Pose2{}, 0, 0);
  return o;
}

TEST(Odometry, RejectsBadConfiguration) {
  Odometry o;
  OdometryConfig c;
  c.ticks_per_revolution = 0;
  EXPECT_EQ(o.configure(c), Status::kInvalidArgument);
  c = OdometryConfig{};
  c.track_width = Q31_32::from_int(0);
  EXPECT_EQ(o.configure(c), Status::kInvalidArgument);
  c = OdometryConfig{};
  c.circumference_left = Q31_32::from_int(-1);
  EXPECT_EQ(o.configure(c), Status::kInvalidArgument);
  c = OdometryConfig{};
  c.counter_bits = 33;
  EXPECT_EQ(o.configure(c), Status::kInvalidArgument);
  c = OdometryConfig{};
  c.counter_bits = 12;  // max_ticks 4096 >= 2^11: a wrap could not be told from a jump
  EXPECT_EQ(o.configure(c), Status::kOutOfRange);
  c = OdometryConfig{};
  c.circumference_right = Q31_32::from_int(17);
  EXPECT_EQ(o.configure(c), Status::kOutOfRange);
  c = OdometryConfig{};
  c.track_width = Q31_32::from_ratio(1, 100);  // 1 cm track: a full turn per update possible
  EXPECT_EQ(o.configure(c), Status::kOutOfRange);
  EXPECT_FALSE(o.ready());
  EXPECT_EQ(o.update(1, 1), Status::kFailedPrecondition);
}

TEST(Odometry, StraightLineAndSpinInPlace) {
  OdometryConfig c;
  c.circumference_right = c.circumference_left;
  Odometry o = configured(c);
  ASSERT_EQ(o.update(4096, 4096), Status::kOk);  // one revolution forward
  EXPECT_NEAR(metres(o.pose().x), 0.532, 1e-9);
  EXPECT_NEAR(metres(o.pose().y), 0.0, 1e-9);
  EXPECT_EQ(o.pose().heading.bam, 0u);
  // Spin: wheels opposite by pi * L / 2 of travel each = a half turn.
  const double ticks = test::kPi * 0.474 / 2.0 / 0.532 * 4096.0;
  const uint32_t t = static_cast<uint32_t>(test::ref_round(ticks));
  ASSERT_EQ(o.update(4096 - t / 2, 4096 + t / 2), Status::kOk);
  ASSERT_EQ(o.update(4096 - t, 4096 + t), Status::kOk);
  EXPECT_NEAR(metres(o.pose().x), 0.532, 1e-6);
  EXPECT_NEAR(test::ref_fabs(radians(o.pose().heading)), test::kPi, 2e-3);
  EXPECT_NEAR(metres(o.distance_travelled()), 0.532, 1e-6);
}

TEST(Odometry, SixteenBitCountersWrapLikeThirtyTwoBitOnes) {
  OdometryConfig narrow;
  narrow.counter_bits = 16;
  Odometry a = configured();
  Odometry b = configured(narrow);
  a.reset(Pose2{}, 0xFFFFFF00u, 0x00000010u);
  b.reset(Pose2{}, 0xFF00u, 0x0010u);
  uint32_t l = 0xFFFFFF00u;
  uint32_t r = 0x00000010u;
  for (int i = 0; i < 3000; ++i) {
    l += 37;
    r -= 29;  // right wheel backwards: counts wrap below zero
    ASSERT_EQ(a.update(l, r), Status::kOk);
    ASSERT_EQ(b.update(l & 0xFFFFu, r & 0xFFFFu), Status::kOk);
  }
  EXPECT_EQ(a.pose().x.raw(), b.pose().x.raw());
  EXPECT_EQ(a.pose().y.raw(), b.pose().y.raw());
  EXPECT_EQ(a.heading_turns_q64(), b.heading_turns_q64());
}

TEST(Odometry, GlitchIsSkippedAndResyncAcceptsJump) {
  Odometry o = configured();
  ASSERT_EQ(o.update(100, 100), Status::kOk);
  const Pose2 before = o.pose();
  EXPECT_EQ(o.update(100 + 5000, 100), Status::kOutOfRange);  // corrupted left count
  EXPECT_EQ(o.pose().x.raw(), before.x.raw());
  EXPECT_EQ(o.update(200, 200), Status::kOk);  // next good reading continues from 100
  EXPECT_NEAR(metres(o.pose().x), 200 * 0.532 / 4096 + 0.0 * 1, 2e-5);
  o.resync(1000000, 1000000);
  EXPECT_EQ(o.update(1000010, 1000010), Status::kOk);
}

TEST(Odometry, NinetyTwoMetreLoopMatchesDoublePrecision) {
  Odometry o = configured();
  const uint32_t start = 0xFFFF0000u;  // counters wrap during the run
  o.reset(Pose2{}, start, start);
  test::LoopDrive drive;
  test::ReferenceOdometry ref;
  test::WheelTicks t{0, 0};
  test::WheelTicks prev{0, 0};
  double worst_position = 0.0;
  double worst_heading = 0.0;
  while (drive.step(&t)) {
    ASSERT_EQ(
        o.update(start + static_cast<uint32_t>(t.left), start + static_cast<uint32_t>(t.right)),
        Status::kOk);
    ref.update(t.left - prev.left, t.right - prev.right);
    prev = t;
    const Pose2 p = o.pose();
    const double dx = metres(p.x) - ref.x;
    const double dy = metres(p.y) - ref.y;
    const double e = test::ref_sqrt(dx * dx + dy * dy);
    if (e > worst_position) worst_position = e;
    // Heading difference wrapped to (-pi, pi].
    const double turns = static_cast<double>(o.heading_turns_q64()) / 18446744073709551616.0;
    double dh = turns * 2.0 * test::kPi - ref.phi;
    dh -= 2.0 * test::kPi * test::ref_round(dh / (2.0 * test::kPi));
    if (test::ref_fabs(dh) > worst_heading) worst_heading = test::ref_fabs(dh);
  }
  EXPECT_GT(drive.distance(), 91.0);
  EXPECT_GT(drive.steps(), 25000u);
  const double worst_degrees = worst_heading * 180.0 / test::kPi;
  // Printed on every run (gtest and minitest) so the figures in docs/accuracy.md can be checked.
  test::log_figure("loop steps", drive.steps());
  test::log_figure("loop length (m)", drive.distance());
  test::log_figure("max position error (m)", worst_position);
  test::log_figure("max heading error (deg)", worst_degrees);
  EXPECT_LT(worst_position, 1e-3) << "max position error (m): " << worst_position;
  EXPECT_LT(worst_degrees, 0.05) << "max heading error (deg): " << worst_degrees;
  // The measured figures (about 3e-6 m and 4e-6 degrees after 92 m) are far inside the
  // issue's bound; a regression (e.g. a coarse sine) shows up here first. What remains is
  // the Q31.32 quantisation of the configured constants (0.53227 m is stored to 2.3e-10 m,
  // a relative 3e-10 on the per-tick heading increment), not arithmetic drift.
  EXPECT_LT(worst_position, 1e-5) << "max position error (m): " << worst_position;
  EXPECT_LT(worst_degrees, 2e-5) << "max heading error (deg): " << worst_degrees;
  EXPECT_NEAR(metres(o.distance_travelled()), drive.distance(), 0.01);
}

}  // namespace
}  // namespace seqslam

namespace seqslam {
namespace {

// Continuing a stopped run (state_io.h): odometry saved half-way round the 92 m loop and
// restored into another configured odometry (never reset) ends the loop at exactly the pose
// of the one that never stopped; so does the spatial trigger driven by it.
TEST(Odometry, ContinuesExactlyFromASavedState) {
  static test::RamState<256> saved;
  test::LoopDrive drive;
  test::WheelTicks t{0, 0};
  Odometry a = configured();
  SpatialTrigger trigger_a;
  ASSERT_EQ(trigger_a.configure(SpatialTrigger::kDefaultSpacing), Status::kOk);
  Odometry b;
  SpatialTrigger trigger_b;
  bool resumed = false;
  uint32_t steps = 0, captures_after = 0;
  while (drive.step(&t)) {
    const uint32_t l = static_cast<uint32_t>(t.left), r = static_cast<uint32_t>(t.right);
    ASSERT_EQ(a.update(l, r), Status::kOk);
    const bool ca = trigger_a.update(a.pose());
    if (resumed) {
      ASSERT_EQ(b.update(l, r), Status::kOk);
      EXPECT_EQ(trigger_b.update(b.pose()), ca) << "step " << steps;
      captures_after += ca ? 1 : 0;
    }
    if (++steps == 4567) {  // mid-way, between two captures
      StateOut out(saved);
      a.state(out);
      trigger_a.state(out);
      ASSERT_EQ(out.status(), Status::kOk);
      ASSERT_EQ(b.configure(OdometryConfig{}), Status::kOk);
      ASSERT_EQ(trigger_b.configure(SpatialTrigger::kDefaultSpacing), Status::kOk);
      StateIn in(saved);
      b.state(in);
      trigger_b.state(in);
      ASSERT_EQ(in.status(), Status::kOk);
      resumed = true;
    }
  }
  ASSERT_TRUE(resumed);
  EXPECT_GT(captures_after, 100u);
  EXPECT_EQ(b.pose().x.raw(), a.pose().x.raw());
  EXPECT_EQ(b.pose().y.raw(), a.pose().y.raw());
  EXPECT_EQ(b.heading_turns_q64(), a.heading_turns_q64());
  EXPECT_EQ(b.distance_travelled().raw(), a.distance_travelled().raw());
  EXPECT_EQ(trigger_b.captures(), trigger_a.captures());
  // A state cut short inside the odometry's section leaves it waiting for reset() and the
  // trigger re-armed, with the status.
  saved.truncate(20);
  Odometry c;
  ASSERT_EQ(c.configure(OdometryConfig{}), Status::kOk);
  StateIn short_in(saved);
  c.state(short_in);
  SpatialTrigger trigger_c;
  trigger_c.state(short_in);
  EXPECT_EQ(short_in.status(), Status::kDataLoss);
  EXPECT_FALSE(c.ready());
  EXPECT_EQ(trigger_c.captures(), 0u);
}

}  // namespace
}  // namespace seqslam
