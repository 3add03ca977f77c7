// The simulated robot (host_sim/include/seqslam_sim/robot.h): its encoder stream integrated
// by the core's Odometry against its true motion, the driver's deviations from the route,
// the snapshot stream, and the infrared sensors.
//
// Stated bounds:
// - perfect wheels (the firmware's constants), no slip, no deviation, a straight 10 m leg:
//   dead-reckoned end within 5 mm and 0.05 degrees of the truth (measured: printed);
// - the mis-calibrated default wheels with slip on the ~90 m loop: end error between 0.1 m
//   and 3 m (the 2025 thesis's realistic range), heading error below 15 degrees;
// - |lateral deviation| <= deviation_m + 0.1 m, |heading deviation| <= 30 degrees;
// - infrared: |reading - true distance| <= 4 sigma of the sensor model (sigma = 4 mm + 1.2 %
//   of the distance) on every reading, the mean error within 5 mm; 0 beyond the range.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include <gtest/gtest.h>

#include "seqslam/odometry.h"
#include "seqslam_sim/lab.h"
#include "seqslam_sim/robot.h"
#include "seqslam_sim/scenario.h"
#include "seqslam_sim/world.h"
#include "seqslam_tools/q_format.h"
#include "test_log.h"

namespace seqslam::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

// The firmware's OdometryConfig defaults as true wheels: odometry is then exact up to the
// encoders' quantisation and the integration rule.
WheelParams firmware_wheels() {
  WheelParams w;
  w.circumference_left = 0.532;
  w.circumference_right = 0.53227;
  w.track = 0.474;
  w.ticks_per_revolution = 4096;
  return w;
}

World empty_world() {
  World w(3.0);
  Box far;  // something far away so the world has bounds
  far.lo = Vec3{100.0, 100.0, 2.9};
  far.hi = Vec3{100.1, 100.1, 3.0};
  w.add(far);
  w.finalize(0.5);
  return w;
}

struct OdometryError {
  double position_m = 0.0;
  double heading_deg = 0.0;
};

// Integrates the ticks' encoder counts with the core's odometry (reset on the first snapshot,
// update on each) and compares the end pose with the truth, both relative to the first tick.
OdometryError dead_reckoning_error(const std::vector<DriveTick>& ticks) {
  Odometry odometry;
  EXPECT_EQ(odometry.configure(OdometryConfig{}), Status::kOk);
  odometry.reset(Pose2{}, ticks.front().snapshot.encoder_left,
                 ticks.front().snapshot.encoder_right);
  for (size_t i = 1; i < ticks.size(); ++i) {
    const Status s =
        odometry.update(ticks[i].snapshot.encoder_left, ticks[i].snapshot.encoder_right);
    if (s != Status::kOk) {
      ADD_FAILURE() << "odometry rejected snapshot " << i;
      break;
    }
  }
  const Pose2 p = odometry.pose();
  const double ox = tools::to_double(p.x);
  const double oy = tools::to_double(p.y);
  const double oh = tools::to_radians(p.heading);
  const TruePose& a = ticks.front().truth;
  const TruePose& b = ticks.back().truth;
  const double c = std::cos(a.heading);
  const double s = std::sin(a.heading);
  const double ex = c * (b.x - a.x) + s * (b.y - a.y);
  const double ey = -s * (b.x - a.x) + c * (b.y - a.y);
  OdometryError e;
  e.position_m = std::hypot(ox - ex, oy - ey);
  e.heading_deg = std::fabs(std::remainder(oh - (b.heading - a.heading), 2 * kPi)) * 180 / kPi;
  return e;
}

TEST(SimRobot, PerfectWheelsStraightLegOdometryIsExact) {
  DriveOptions o;
  o.wheels = firmware_wheels();
  o.slip_sigma = 0.0;
  o.deviation_m = 0.0;
  const std::vector<Leg> legs = {Leg{{{6.0, lab::kSouthLane}, {16.0, lab::kSouthLane}}, false}};
  Rng rng(11);
  const std::vector<DriveTick> ticks = drive(legs, o, empty_world(), rng);
  ASSERT_GT(ticks.size(), 1000u);
  const TruePose& end = ticks.back().truth;
  EXPECT_NEAR(end.x, 16.0, 0.1);  // drove the whole leg
  EXPECT_NEAR(end.y, lab::kSouthLane, 0.01);
  const OdometryError e = dead_reckoning_error(ticks);
  seqslam::test::log_figure("sim.robot.perfect_wheels_10m.end_error_mm", e.position_m * 1000);
  seqslam::test::log_figure("sim.robot.perfect_wheels_10m.heading_error_deg", e.heading_deg);
  EXPECT_LT(e.position_m, 0.005);
  EXPECT_LT(e.heading_deg, 0.05);
}

TEST(SimRobot, PerfectWheelsOnTheLoopStayClose) {
  // The same on the loop's corners: only quantisation and the 10 ms midpoint rule (the
  // physics runs at 1 ms) separate dead reckoning from the truth.
  DriveOptions o;
  o.wheels = firmware_wheels();
  o.slip_sigma = 0.0;
  Rng rng(12);
  const std::vector<DriveTick> ticks = drive(routes::loop(), o, empty_world(), rng);
  ASSERT_GT(ticks.size(), 10000u);
  const OdometryError e = dead_reckoning_error(ticks);
  seqslam::test::log_figure("sim.robot.perfect_wheels_loop.end_error_mm", e.position_m * 1000);
  seqslam::test::log_figure("sim.robot.perfect_wheels_loop.heading_error_deg", e.heading_deg);
  EXPECT_LT(e.position_m, 0.05);
  EXPECT_LT(e.heading_deg, 0.5);
}

TEST(SimRobot, DefaultWheelsOnTheLoop) {
  const World lab = build_lab(3);
  const DriveOptions o;  // mis-calibrated wheels, slip, 0.5 m deviation
  Rng rng(2025);
  const std::vector<DriveTick> ticks = drive(routes::loop(), o, lab, rng);
  ASSERT_GT(ticks.size(), 10000u);
  ASSERT_LT(ticks.size(), 4000000u);

  // Dead reckoning: realistically wrong.
  const OdometryError e = dead_reckoning_error(ticks);
  seqslam::test::log_figure("sim.robot.default_wheels_loop.end_error_m", e.position_m);
  seqslam::test::log_figure("sim.robot.default_wheels_loop.heading_error_deg", e.heading_deg);
  EXPECT_GT(e.position_m, 0.1);
  EXPECT_LT(e.position_m, 3.0);
  EXPECT_LT(e.heading_deg, 15.0);

  // The loop ends where it started (0.4 m further along the lane).
  const TruePose& end = ticks.back().truth;
  EXPECT_NEAR(end.x, 6.4, o.deviation_m + 0.1);
  EXPECT_NEAR(end.y, lab::kSouthLane, o.deviation_m + 0.1);

  // Deviations from the route.
  double max_lateral = 0.0, max_heading = 0.0, length = 0.0;
  for (size_t i = 0; i < ticks.size(); ++i) {
    max_lateral = std::max(max_lateral, std::fabs(ticks[i].lateral_deviation));
    max_heading = std::max(max_heading, std::fabs(ticks[i].heading_deviation) * 180 / kPi);
    if (i > 0) {
      length += std::hypot(ticks[i].truth.x - ticks[i - 1].truth.x,
                           ticks[i].truth.y - ticks[i - 1].truth.y);
    }
  }
  seqslam::test::log_figure("sim.robot.default_wheels_loop.max_lateral_m", max_lateral);
  seqslam::test::log_figure("sim.robot.default_wheels_loop.max_heading_dev_deg", max_heading);
  seqslam::test::log_figure("sim.robot.default_wheels_loop.length_m", length);
  EXPECT_LE(max_lateral, o.deviation_m + 0.1);
  EXPECT_LE(max_heading, 30.0);
  EXPECT_GT(max_lateral, 0.1);  // the driver does wander
  EXPECT_NEAR(length, route_length(routes::loop(), o.corner_radius), 5.0);

  // The snapshot stream: sequence +1, time +10 ms, encoders wrap.
  const hal::SensorSnapshot& first = ticks.front().snapshot;
  EXPECT_GT(first.encoder_left, 0xFFFFFFFFu - (1u << 20));
  EXPECT_GT(first.encoder_right, 0xFFFFFFFFu - (1u << 20));
  bool left_wrapped = false, right_wrapped = false;
  for (size_t i = 1; i < ticks.size(); ++i) {
    const hal::SensorSnapshot& a = ticks[i - 1].snapshot;
    const hal::SensorSnapshot& b = ticks[i].snapshot;
    ASSERT_EQ(b.sequence, a.sequence + 1) << "at " << i;
    ASSERT_EQ(b.timestamp_us, a.timestamp_us + 10000u) << "at " << i;
    ASSERT_EQ(b.flags, hal::SensorSnapshot::kHasEncoders | hal::SensorSnapshot::kHasInfrared |
                           hal::SensorSnapshot::kHasHead);
    // At most 0.35 m/s: a few dozen ticks per 10 ms, in either direction (mod 2^32).
    const auto dl = static_cast<int32_t>(b.encoder_left - a.encoder_left);
    const auto dr = static_cast<int32_t>(b.encoder_right - a.encoder_right);
    ASSERT_LT(std::abs(dl), 100) << "at " << i;
    ASSERT_LT(std::abs(dr), 100) << "at " << i;
    if (b.encoder_left < a.encoder_left && dl > 0) left_wrapped = true;
    if (b.encoder_right < a.encoder_right && dr > 0) right_wrapped = true;
  }
  EXPECT_TRUE(left_wrapped);
  EXPECT_TRUE(right_wrapped);
}

TEST(SimRobot, InfraredReadsTheWallDistance) {
  // A wall across the robot's path at x = 7 (face), another along its left at y = 1.9
  // (beyond the 1.5 m range of the left sensor, 0.2 m off the centre line: 1.7 m).
  World w(3.0);
  Box front;
  front.lo = Vec3{7.0, -3.0, 0.0};
  front.hi = Vec3{7.2, 3.0, 3.0};
  w.add(front);
  Box left;
  left.lo = Vec3{0.0, 1.9, 0.0};
  left.hi = Vec3{7.0, 2.1, 3.0};
  w.add(left);
  Box low;  // an obstacle above the sensors' 12 cm plane, on the right: not seen
  low.lo = Vec3{5.0, -1.5, 0.2};
  low.hi = Vec3{7.0, -0.5, 0.8};
  w.add(low);
  w.finalize(0.5);

  DriveOptions o;
  o.wheels = firmware_wheels();
  o.slip_sigma = 0.0;
  o.deviation_m = 0.0;
  // From x = 5.8 (front sensor at 6.0: 1.0 m from the wall) to 6.4 (0.4 m).
  const std::vector<Leg> legs = {Leg{{{5.8, 0.0}, {6.4, 0.0}}, false}};
  Rng rng(99);
  const std::vector<DriveTick> ticks = drive(legs, o, w, rng);
  ASSERT_GT(ticks.size(), 100u);
  const std::vector<InfraredSensor> ir = default_infrared();
  ASSERT_EQ(ir.size(), 6u);
  double sum_error_mm = 0.0, worst_sigmas = 0.0;
  int readings = 0;
  for (const DriveTick& t : ticks) {
    ASSERT_EQ(t.snapshot.infrared_count, 6);
    const double c = std::cos(t.truth.heading);
    // Front sensor 0.2 m ahead of the base, pointing along the heading (~0).
    const double sensor_x = t.truth.x + 0.2 * c;
    const double d = (7.0 - sensor_x) / c;
    const double sigma_mm = 4.0 + 12.0 * d;
    const double error_mm = t.snapshot.infrared_mm[0] - 1000.0 * d;
    EXPECT_LE(std::fabs(error_mm), 4.0 * sigma_mm + 0.5)
        << "reading " << t.snapshot.infrared_mm[0] << " mm at " << d << " m";
    worst_sigmas = std::max(worst_sigmas, std::fabs(error_mm) / sigma_mm);
    sum_error_mm += error_mm;
    ++readings;
    EXPECT_EQ(t.snapshot.infrared_mm[3], 0) << "left wall at 1.7 m is beyond 1.5 m";
    EXPECT_EQ(t.snapshot.infrared_mm[4], 0) << "nothing on the right at 12 cm";
    EXPECT_EQ(t.snapshot.infrared_mm[5], 0) << "nothing behind";
  }
  const double mean_error_mm = sum_error_mm / readings;
  seqslam::test::log_figure("sim.robot.infrared.mean_error_mm", mean_error_mm);
  seqslam::test::log_figure("sim.robot.infrared.worst_error_sigmas", worst_sigmas);
  EXPECT_LT(std::fabs(mean_error_mm), 5.0);
  EXPECT_GT(worst_sigmas, 0.5);  // the readings are noisy, not exact
  // The run went from 1.0 m to about 0.45 m (it stops 5 cm short of the leg's end).
  EXPECT_NEAR(ticks.front().snapshot.infrared_mm[0], 1000, 70);
  EXPECT_GT(ticks.back().truth.x, 6.3);
  EXPECT_LT(ticks.back().snapshot.infrared_mm[0], 520);
}

}  // namespace
}  // namespace seqslam::sim
