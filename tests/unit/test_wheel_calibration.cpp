// Wheel calibration from loop closures (wheel_calibration.h): known constants recovered on a
// synthetic figure of eight, refused on a loop driven one way only, against a double-precision
// reference of the same estimator, and bad input.
#include "seqslam/wheel_calibration.h"

#include "ref_math.h"
#include "test.h"

namespace seqslam {
namespace {

using test::kPi;

constexpr double kQ32 = 4294967296.0;
double to_d(Q31_32 v) {
  return static_cast<double>(v.raw()) / kQ32;
}
Q31_32 from_d(double v) {
  return Q31_32::from_raw(static_cast<int64_t>(test::ref_round(v * kQ32)));
}

// The constants the odometry runs with, and the true wheels: the simulator's offsets (host_sim
// robot.h: left +0.08 %, right +0.05 %, track +0.5 %).
constexpr double kLeft = 0.532, kRight = 0.53227, kTrack = 0.474;
constexpr double kTrueLeft = kLeft * 1.0008, kTrueRight = kRight * 1.0005,
                 kTrueTrack = kTrack * 1.005;
constexpr double kTrueMean = (1.0008 + 1.0005) / 2;
constexpr double kTrueDifference = (1.0005 - 1.0008) / kTrueMean;
constexpr double kTrueTrackRel = 1.005 / kTrueMean - 1;

constexpr uint32_t kNodes = 1400;
constexpr uint32_t kEdges = 1700;
using Storage = PoseGraphStorage<kNodes, kEdges>;

// Deterministic noise in [-1, 1).
struct Noise {
  uint32_t state = 12345;
  double next() {
    state = state * 1664525u + 1013904223u;
    return static_cast<double>(state >> 8) / 8388608.0 - 1.0;
  }
};

// Drives `laps` laps of squares of 6 m sides with 1.2 m radius corners at 0.5 m/s (10 ms
// steps): with `both_ways` each lap is a figure of eight (a square turning left, then one
// turning right); else a square turning left. The encoders count with the true wheels, the
// odometry integrates with the configured ones, a node every 40 steps (0.2 m). Then every 4th
// node of the last lap closes with the same node of the first lap, its measurement the
// identity (the same place) plus the noise of real closures: up to +-`lateral` metres and
// +-`heading_deg` degrees.
void build(PoseGraph& g, Storage& storage, bool both_ways, double lateral, double heading_deg) {
  ASSERT_EQ(g.configure(PoseGraphConfig{}, storage.buffers()), Status::kOk);
  OdometryConfig oc;
  Odometry odo;
  ASSERT_EQ(odo.configure(oc), Status::kOk);
  odo.reset(Pose2{}, 0, 0);
  const int corners = both_ways ? 8 : 4;
  const double ds = 0.005, radius = 1.2, side = 6.0;
  const double arc = kPi / 2 * radius;
  double left = 0, right = 0;
  uint32_t step = 0, per_lap = 0;
  for (int lap = 0; lap < 2; ++lap) {
    step = 0;  // nodes at the same places of both laps
    for (int c = 0; c < corners; ++c) {
      const double curvature = (c < 4 ? 1.0 : -1.0) / radius;
      for (int part = 0; part < 2; ++part) {
        const double length = part == 0 ? side : arc;
        const double k = part == 0 ? 0.0 : curvature;
        const uint32_t n = static_cast<uint32_t>(test::ref_round(length / ds));
        for (uint32_t i = 0; i < n; ++i) {
          left += ds * (1 - k * kTrueTrack / 2) / kTrueLeft * 4096;
          right += ds * (1 + k * kTrueTrack / 2) / kTrueRight * 4096;
          ASSERT_EQ(odo.update(static_cast<uint32_t>(static_cast<int64_t>(left)),
                               static_cast<uint32_t>(static_cast<int64_t>(right))),
                    Status::kOk);
          if (++step % 40 == 0) {
            ASSERT_TRUE(g.add_node(odo.pose(), g.node_count()).ok());
          }
        }
      }
    }
    if (lap == 0) per_lap = g.node_count();
  }
  Noise noise;
  for (uint32_t j = per_lap + 1; j < 2 * per_lap; j += 4) {
    const RelativePose2 z{
        from_d(lateral * noise.next() / 2), from_d(lateral * noise.next()),
        Angle::from_turn_ratio(
            static_cast<int64_t>(test::ref_round(heading_deg * noise.next() * 1e6)),
            360 * 1000000)};
    ASSERT_EQ(g.add_loop_closure(j - per_lap, j, z, {UQ16_16::from_int(1), UQ16_16::from_int(1)}),
              Status::kOk);
  }
}

// ---- The double-precision reference: the same model (header) and cost, solved by
// Gauss-Newton with central-difference derivatives.
struct RefEdge {
  double dx, dy, turn;
};

void ref_replay(const PoseGraph& g, double delta, double tau, double* x, double* y, double* th) {
  x[0] = y[0] = th[0] = 0;
  for (uint32_t n = 0; n + 1 < g.node_count(); ++n) {
    const PoseGraphEdge e = g.edge(n).value();
    const double dx = static_cast<double>(e.dx.raw()) / 16777216.0;
    const double dy = static_cast<double>(e.dy.raw()) / 16777216.0;
    const double turn = signed_diff(e.dtheta, Angle{}) * (2 * kPi / kQ32);
    const double chord = test::ref_sqrt(dx * dx + dy * dy);
    const double path = chord * (1 + turn * turn / 24);
    const double path2 = path + delta * kTrack * turn / 4;
    const double turn2 = (turn + delta * path / kTrack) / (1 + tau);
    const double chord2 = path2 * (1 - turn2 * turn2 / 24);
    x[n + 1] = x[n] + chord2 * test::ref_cos(th[n] + turn2 / 2);
    y[n + 1] = y[n] + chord2 * test::ref_sin(th[n] + turn2 / 2);
    th[n + 1] = th[n] + turn2;
  }
}

double wrap(double a) {
  while (a > kPi)
    a -= 2 * kPi;
  while (a <= -kPi)
    a += 2 * kPi;
  return a;
}

// The residuals (3 per closure, heading scaled by sqrt(100)) at (delta, tau).
void ref_residuals(const PoseGraph& g, double delta, double tau, double* r) {
  static double x[kNodes], y[kNodes], th[kNodes];
  ref_replay(g, delta, tau, x, y, th);
  const uint32_t first = g.node_count() - 1;
  for (uint32_t i = 0; i < g.closure_count(); ++i) {
    const PoseGraphEdge e = g.edge(first + i).value();
    const double c = test::ref_cos(th[e.from]), s = test::ref_sin(th[e.from]);
    const double dx = x[e.to] - x[e.from], dy = y[e.to] - y[e.from];
    r[3 * i] = c * dx + s * dy - static_cast<double>(e.dx.raw()) / 16777216.0;
    r[3 * i + 1] = -s * dx + c * dy - static_cast<double>(e.dy.raw()) / 16777216.0;
    r[3 * i + 2] =
        10 * wrap(th[e.to] - th[e.from] - signed_diff(e.dtheta, Angle{}) * (2 * kPi / kQ32));
  }
}

// Per mille parameters, prior 0.01 per square per mille, as the defaults.
void ref_solve(const PoseGraph& g, double* delta, double* tau) {
  static double r0[3 * 400], rp[3 * 400], rm[3 * 400];
  const uint32_t m = 3 * g.closure_count();
  double p[2] = {0, 0};
  for (int it = 0; it < 8; ++it) {
    ref_residuals(g, p[0] / 1000, p[1] / 1000, r0);
    static double jac[2][3 * 400];
    for (int q = 0; q < 2; ++q) {
      const double h = 1e-4;
      double a[2] = {p[0], p[1]}, b[2] = {p[0], p[1]};
      a[q] += h;
      b[q] -= h;
      ref_residuals(g, a[0] / 1000, a[1] / 1000, rp);
      ref_residuals(g, b[0] / 1000, b[1] / 1000, rm);
      for (uint32_t k = 0; k < m; ++k)
        jac[q][k] = (rp[k] - rm[k]) / (2 * h);
    }
    double h00 = 0.01, h01 = 0, h11 = 0.01, g0 = 0.01 * p[0], g1 = 0.01 * p[1];
    for (uint32_t k = 0; k < m; ++k) {
      h00 += jac[0][k] * jac[0][k];
      h01 += jac[0][k] * jac[1][k];
      h11 += jac[1][k] * jac[1][k];
      g0 += jac[0][k] * r0[k];
      g1 += jac[1][k] * r0[k];
    }
    const double det = h00 * h11 - h01 * h01;
    p[0] -= (h11 * g0 - h01 * g1) / det;
    p[1] -= (h00 * g1 - h01 * g0) / det;
  }
  *delta = p[0] / 1000;
  *tau = p[1] / 1000;
}

// One graph for all tests (configure() empties it): the target's memory is small.
Storage g_storage;
PoseGraph g_graph;
WheelCalibrationSlot g_slots[400];
Span<WheelCalibrationSlot> slots() {
  return Span<WheelCalibrationSlot>(g_slots, 400);
}

TEST(WheelCalibration, RecoversKnownConstantsOnAFigureOfEight) {
  Storage& storage = g_storage;
  PoseGraph& g = g_graph;
  build(g, storage, true, 0.0, 0.0);
  WheelCalibrationResult r;
  ASSERT_EQ(calibrate_wheels(g, WheelCalibrationConfig{}, slots(), &r), Status::kOk);
  EXPECT_GE(r.closures_used, 20u);
  EXPECT_EQ(r.closures_skipped, 0u);
  // The model's approximation (each 0.2 m edge one arc, also where a corner begins inside it)
  // leaves 0.00001 % in the wheels and 0.016 % in the track (measured), an order of magnitude
  // inside the bounds (0.05 % and 0.2 %).
  EXPECT_NEAR(to_d(r.correction.difference), kTrueDifference, 1e-6);
  EXPECT_NEAR(to_d(r.correction.track), kTrueTrackRel, 3e-4);
  EXPECT_LT(to_d(r.rms_after), to_d(r.rms_before) / 10);
  // Applied: the corrected constants are the true ones up to the unobservable mean wheel.
  const OdometryConfig c = apply_wheel_correction(OdometryConfig{}, r.correction);
  EXPECT_NEAR(to_d(c.circumference_left) * kTrueMean / kTrueLeft, 1.0, 2e-5);
  EXPECT_NEAR(to_d(c.circumference_right) * kTrueMean / kTrueRight, 1.0, 2e-5);
  EXPECT_NEAR(to_d(c.track_width) * kTrueMean / kTrueTrack, 1.0, 3e-4);
  // The double-precision reference of the same estimator lands on the same point: the
  // fixed point's rounding and its first-order analytic derivatives (the reference
  // differentiates numerically) move it by less than 1e-7 in delta and 1e-6 in tau.
  double delta = 0, tau = 0;
  ref_solve(g, &delta, &tau);
  EXPECT_NEAR(to_d(r.correction.difference), delta, 1e-7);
  EXPECT_NEAR(to_d(r.correction.track), tau, 1e-6);
}

TEST(WheelCalibration, NoisyClosuresStillSeparateBothWays) {
  Storage& storage = g_storage;
  PoseGraph& g = g_graph;
  build(g, storage, true, 0.3, 1.5);
  WheelCalibrationResult r;
  // This noise is independent from closure to closure (real closures' is not).
  WheelCalibrationConfig independent;
  independent.correlated_closures = 1;
  ASSERT_EQ(calibrate_wheels(g, independent, slots(), &r), Status::kOk);
  EXPECT_NEAR(to_d(r.correction.difference), kTrueDifference, 5e-5);
  EXPECT_NEAR(to_d(r.correction.track), kTrueTrackRel, 1e-3);
  double delta = 0, tau = 0;
  ref_solve(g, &delta, &tau);
  EXPECT_NEAR(to_d(r.correction.difference), delta, 1e-7);
  EXPECT_NEAR(to_d(r.correction.track), tau, 1e-6);
}

TEST(WheelCalibration, RefusesALoopDrivenOneWay) {
  // Turning left only, a track error and unequal wheels bend the loop alike: with the same
  // closure noise the two cannot be told apart, and the estimate is not to be applied.
  Storage& storage = g_storage;
  PoseGraph& g = g_graph;
  build(g, storage, false, 0.3, 1.5);
  WheelCalibrationResult r;
  WheelCalibrationConfig independent;  // as above: even counting every closure as independent
  independent.correlated_closures = 1;
  EXPECT_EQ(calibrate_wheels(g, independent, slots(), &r), Status::kOutOfRange);
  EXPECT_GT(to_d(r.sigma_track), to_d(independent.max_sigma_track));
}

TEST(WheelCalibration, RefusesBadInputAndTooFewClosures) {
  Storage& storage = g_storage;
  PoseGraph& g = g_graph;
  build(g, storage, true, 0.0, 0.0);
  WheelCalibrationResult r;
  const WheelCalibrationConfig ok{};
  EXPECT_EQ(calibrate_wheels(g, ok, slots(), nullptr), Status::kInvalidArgument);
  EXPECT_EQ(calibrate_wheels(g, ok, Span<WheelCalibrationSlot>(g_slots, 3), &r),
            Status::kInvalidArgument);
  WheelCalibrationConfig bad = ok;
  bad.iterations = 0;
  EXPECT_EQ(calibrate_wheels(g, bad, slots(), &r), Status::kInvalidArgument);
  bad = ok;
  bad.track_width = Q31_32{};
  EXPECT_EQ(calibrate_wheels(g, bad, slots(), &r), Status::kInvalidArgument);
  bad = ok;
  bad.max_step = Q31_32::from_int(17);
  EXPECT_EQ(calibrate_wheels(g, bad, slots(), &r), Status::kInvalidArgument);
  bad = ok;
  bad.correlated_closures = 0;
  EXPECT_EQ(calibrate_wheels(g, bad, slots(), &r), Status::kInvalidArgument);
  bad = ok;
  bad.min_closures = static_cast<uint16_t>(g.closure_count() + 1);
  EXPECT_EQ(calibrate_wheels(g, bad, slots(), &r), Status::kFailedPrecondition);
  EXPECT_EQ(r.closures_used, g.closure_count());
  PoseGraph unconfigured;
  EXPECT_EQ(calibrate_wheels(unconfigured, ok, slots(), &r), Status::kInvalidArgument);
}

TEST(WheelCalibration, ClosuresAcrossABreakInTheChainAreNotUsed) {
  // A second run starting elsewhere (a jump of 5 m in the chain): closures spanning it are
  // skipped, the rest still calibrate.
  Storage& storage = g_storage;
  PoseGraph& g = g_graph;
  build(g, storage, true, 0.0, 0.0);
  const uint32_t last = g.node_count() - 1;
  const Pose2 end = g.pose(last).value();
  ASSERT_TRUE(g.add_node(Pose2{end.x + Q31_32::from_int(5), end.y, end.heading}, 0).ok());
  ASSERT_TRUE(g.add_node(Pose2{end.x + Q31_32::from_ratio(52, 10), end.y, end.heading}, 0).ok());
  ASSERT_EQ(g.add_loop_closure(3, g.node_count() - 1, RelativePose2{},
                               {UQ16_16::from_int(1), UQ16_16::from_int(1)}),
            Status::kOk);
  WheelCalibrationResult r;
  ASSERT_EQ(calibrate_wheels(g, WheelCalibrationConfig{}, slots(), &r), Status::kOk);
  EXPECT_EQ(r.breaks, 1u);
  EXPECT_EQ(r.closures_skipped, 1u);
  EXPECT_NEAR(to_d(r.correction.track), kTrueTrackRel, 3e-4);
}

}  // namespace
}  // namespace seqslam
