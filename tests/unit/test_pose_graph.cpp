// The pose graph: configuration, statuses, capacity and bad indices; the leaf rule (a chain
// reproduces odometry and stays converged); a 457-node square loop (89.6 m a lap) driven with
// mis-calibrated wheels and closed by three loop closures, whose optimised trajectory is far
// closer to the truth than dead reckoning; work per optimise_step never above the budget and
// results independent of the slicing; incremental building (nodes added after convergence
// and while optimising) equal to a solve from scratch; and, on the host, the fixed-point
// solution against the double-precision direct solve of the same least-squares problem
// (tools/reference) and a full nonlinear Gauss-Newton for comparison.
//
// Bounds, fixed point vs the double-precision direct solve of the same problem on the loop:
// stated for the issue, positions within 1 mm and headings within 0.01 degree; guaranteed by
// the stopping rule (pose_graph.h), headings within tolerance_heading (3.7e-7 rad) and
// positions within tolerance_xy + tolerance_heading * (summed edge lengths) = 44 um, both
// plus rounding; measured 4e-8 degree and 1e-7 m (the "[ figure ]" lines).
#include "seqslam/pose_graph.h"

#include "ref_math.h"
#include "test.h"
#include "test_log.h"
#include "ram_state.h"
#include "seqslam/state_io.h"

#if defined(SEQSLAM_TEST_GTEST) && __has_include("reference.h")
// Host builds that link seqslam_reference also check against tools/reference.
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "reference.h"
#define POSE_GRAPH_TEST_HAS_REFERENCE 1
#endif

namespace seqslam {
namespace {

// One in raw units: a metre in Q31.32, a turn in binary-angle units, an information weight
// in UQ16.16.
constexpr double kMetre = static_cast<double>(Q31_32::from_int(1).raw());
constexpr double kBamPerTurn = static_cast<double>(uint64_t{1} << 32);
constexpr double kInfoOne = static_cast<double>(UQ16_16::from_int(1).raw());

double metres(Q31_32 v) {
  return static_cast<double>(v.raw()) / kMetre;
}
double radians(Angle a) {
  return static_cast<double>(static_cast<int32_t>(a.bam)) * (2.0 * test::kPi / kBamPerTurn);
}
double abs_d(double v) {
  return v < 0 ? -v : v;
}

// ---- The square loop ---------------------------------------------------------------------
// Four 20 m straights (100 steps of 0.2 m) joined by quarter turns of 12 steps (radius
// 1.53 m): 448 steps a lap. The robot drives one lap and 9 steps more, a node per step, and
// recognises nodes 0, 4 and 8 at nodes 448, 452 and 456.
constexpr uint32_t kLap = 448;
constexpr uint32_t kLoopNodes = kLap + 9;
constexpr uint32_t kClosures = 3;
constexpr uint32_t kClosureA[kClosures] = {0, 4, 8};

// Odometry errors: the wheels' calibration reads 0.3 % long on average (distances and turns
// scale by 1.003), and a left-right mismatch turns the robot by 8e-4 rad per metre driven.
constexpr int64_t kScaleNum = 1003;
constexpr int64_t kScaleDen = 1000;
// 8e-4 rad/m * 0.2 m / (2 pi) * 2^32 binary-angle units per step.
constexpr int32_t kBiasPerStep = 109370;

struct Loop {
  Pose2 truth[kLoopNodes];
  Pose2 odometry[kLoopNodes];
};

// One step of arc length ds turning by dtheta, with the midpoint rule.
Pose2 advance(Pose2 p, Q31_32 ds, int32_t dtheta) {
  const SinCos sc = sincos(Angle{p.heading.bam + static_cast<uint32_t>(dtheta / 2)});
  p.x = p.x + mul_sat<Q31_32>(ds, sc.cos);
  p.y = p.y + mul_sat<Q31_32>(ds, sc.sin);
  p.heading = Angle{p.heading.bam + static_cast<uint32_t>(dtheta)};
  return p;
}

void make_loop(Loop* loop) {
  const Q31_32 ds = Q31_32::from_ratio(2, 10);
  const Q31_32 ds_odo = Q31_32::from_ratio(2 * kScaleNum, 10 * kScaleDen);
  const int32_t turn = static_cast<int32_t>((int64_t{1} << 30) / 12);  // a quarter in 12 steps
  Pose2 truth{Q31_32::from_int(2), Q31_32::from_int(-1), Angle::from_degrees(10)};
  Pose2 odo = truth;
  loop->truth[0] = truth;
  loop->odometry[0] = odo;
  for (uint32_t k = 1; k < kLoopNodes; ++k) {
    const uint32_t in_lap = (k - 1) % kLap;
    const int32_t dtheta = (in_lap % 112) >= 100 ? turn : 0;
    truth = advance(truth, ds, dtheta);
    odo = advance(odo, ds_odo, static_cast<int32_t>(dtheta * kScaleNum / kScaleDen) + kBiasPerStep);
    loop->truth[k] = truth;
    loop->odometry[k] = odo;
  }
}

const Loop& the_loop() {
  static Loop loop;
  static bool made = false;
  if (!made) {
    make_loop(&loop);
    made = true;
  }
  return loop;
}

// Closures as certain as 5 cm of odometry.
const EdgeInformation kClosureInfo{UQ16_16::from_int(20), UQ16_16::from_int(20)};

// Adds nodes [first, last) of the loop and the closures whose later node is among them.
void add_loop_nodes(PoseGraph& g, uint32_t first, uint32_t last) {
  const Loop& loop = the_loop();
  for (uint32_t k = first; k < last; ++k) {
    const Result<uint32_t> r = g.add_node(loop.odometry[k], 1000 + k);
    ASSERT_TRUE(r.ok()) << "node " << k;
    ASSERT_EQ(r.value(), k);
    for (uint32_t c = 0; c < kClosures; ++c) {
      if (kClosureA[c] + kLap != k) continue;
      const RelativePose2 m = relative_pose(loop.truth[kClosureA[c]], loop.truth[k]);
      ASSERT_EQ(g.add_loop_closure(kClosureA[c], k, m, kClosureInfo), Status::kOk);
    }
  }
}

struct Solve {
  uint32_t calls = 0;
  uint32_t max_work = 0;
  bool work_counted = true;  // every call's counted units equal its reported work
};

// Runs optimise_step(budget) until converged (at most `max_calls` calls).
Solve optimise(PoseGraph& g, uint32_t budget, uint32_t max_calls = 1000000) {
  Solve s;
  PoseGraphProgress p;
  do {
    const PoseGraphStats before = g.stats();
    EXPECT_EQ(g.optimise_step(budget, &p), Status::kOk);
    const PoseGraphStats& after = g.stats();
    const uint64_t counted = (after.node_visits - before.node_visits) +
                             (after.closure_visits - before.closure_visits) +
                             (after.scalar_steps - before.scalar_steps);
    if (counted != p.work) s.work_counted = false;
    if (p.work > s.max_work) s.max_work = p.work;
    ++s.calls;
  } while (!p.converged && s.calls < max_calls);
  return s;
}

// Root-mean-square position error against the truth over all nodes, metres.
double rmse(const PoseGraph& g) {
  const Loop& loop = the_loop();
  double sum = 0.0;
  for (uint32_t k = 0; k < g.node_count(); ++k) {
    const Pose2 p = g.pose(k).value();
    const double dx = metres(p.x) - metres(loop.truth[k].x);
    const double dy = metres(p.y) - metres(loop.truth[k].y);
    sum += dx * dx + dy * dy;
  }
  return test::ref_sqrt(sum / g.node_count());
}
double rmse_dead_reckoning() {
  const Loop& loop = the_loop();
  double sum = 0.0;
  for (uint32_t k = 0; k < kLoopNodes; ++k) {
    const double dx = metres(loop.odometry[k].x) - metres(loop.truth[k].x);
    const double dy = metres(loop.odometry[k].y) - metres(loop.truth[k].y);
    sum += dx * dx + dy * dy;
  }
  return test::ref_sqrt(sum / kLoopNodes);
}

struct Difference {
  double position = 0.0;  // metres, largest |dx| or |dy|
  double heading = 0.0;   // radians
};
Difference largest_difference(const PoseGraph& a, const PoseGraph& b) {
  Difference d;
  for (uint32_t k = 0; k < a.node_count(); ++k) {
    const Pose2 p = a.pose(k).value();
    const Pose2 q = b.pose(k).value();
    const double ex = abs_d(metres(p.x) - metres(q.x));
    const double ey = abs_d(metres(p.y) - metres(q.y));
    const double eh = abs_d(radians(Angle{p.heading.bam - q.heading.bam}));
    if (ex > d.position) d.position = ex;
    if (ey > d.position) d.position = ey;
    if (eh > d.heading) d.heading = eh;
  }
  return d;
}

// The a-priori bound on positions against the exact solution (pose_graph.h): tolerance_xy +
// tolerance_heading * the summed length of all edges, metres, plus 1e-6 m for rounding.
double position_bound(const PoseGraph& g) {
  double length = 0.0;
  for (uint32_t i = 0; i < g.edge_count(); ++i) {
    const PoseGraphEdge e = g.edge(i).value();
    const double dx = e.dx.raw() / 16777216.0;
    const double dy = e.dy.raw() / 16777216.0;
    length += test::ref_sqrt(dx * dx + dy * dy);
  }
  return metres(g.config().tolerance_xy) + radians(g.config().tolerance_heading) * length + 1e-6;
}
double heading_bound(const PoseGraph& g) {
  return radians(g.config().tolerance_heading) + 2e-9;  // plus rounding to a binary angle
}

using LoopStorage = PoseGraphStorage<512, 600>;
static_assert(LoopStorage::kBytes == 69056, "512 nodes and 600 edges: 69 056 bytes");
static_assert(sizeof(LoopStorage) == LoopStorage::kBytes, "no padding in the storage");

PoseGraph configured(LoopStorage& storage, const PoseGraphConfig& c = PoseGraphConfig{}) {
  PoseGraph g;
  EXPECT_EQ(g.configure(c, storage.buffers()), Status::kOk);
  return g;
}

// ---- Configuration, statuses, capacity ----------------------------------------------------

TEST(PoseGraph, RejectsBadConfiguration) {
  static PoseGraphStorage<8, 8> s;
  PoseGraph g;
  PoseGraphConfig c;
  PoseGraphBuffers b = s.buffers();
  b.nodes = Span<PoseGraphNode>();
  EXPECT_EQ(g.configure(c, b), Status::kInvalidArgument);
  b = s.buffers();
  b.solver = b.solver.subspan(0, 7);
  EXPECT_EQ(g.configure(c, b), Status::kInvalidArgument);
  EXPECT_FALSE(g.configured());
  c.min_travel = Q31_32::from_ratio(1, 1 << 17);
  EXPECT_EQ(g.configure(c, s.buffers()), Status::kInvalidArgument);
  c = PoseGraphConfig{};
  c.min_travel = Q31_32::from_ratio(101, 100);
  EXPECT_EQ(g.configure(c, s.buffers()), Status::kInvalidArgument);
  c = PoseGraphConfig{};
  c.tolerance_xy = Q31_32::from_int(0);
  EXPECT_EQ(g.configure(c, s.buffers()), Status::kInvalidArgument);
  c.tolerance_xy = Q31_32::from_ratio(1, 100);  // 1 cm > 2^-8 m
  EXPECT_EQ(g.configure(c, s.buffers()), Status::kInvalidArgument);
  c = PoseGraphConfig{};
  c.tolerance_heading = Angle{0};
  EXPECT_EQ(g.configure(c, s.buffers()), Status::kInvalidArgument);
  c.tolerance_heading = Angle::from_degrees(2);
  EXPECT_EQ(g.configure(c, s.buffers()), Status::kInvalidArgument);
  c = PoseGraphConfig{};
  c.extra_iterations = 0;
  EXPECT_EQ(g.configure(c, s.buffers()), Status::kInvalidArgument);
  c = PoseGraphConfig{};
  c.max_restarts = 0;
  EXPECT_EQ(g.configure(c, s.buffers()), Status::kInvalidArgument);
  c = PoseGraphConfig{};
  c.closure_lateral = UQ16_16::from_raw(UQ16_16::from_int(1).raw() + 1);  // above 1
  EXPECT_EQ(g.configure(c, s.buffers()), Status::kInvalidArgument);
  c = PoseGraphConfig{};
  c.tolerance_objective = Q31_32::from_ratio(1, 1000);  // needs enable_refine()
  EXPECT_EQ(g.configure(c, s.buffers()), Status::kInvalidArgument);
  c.tolerance_objective = Q31_32::from_raw(-1);
  EXPECT_EQ(g.configure(c, s.buffers()), Status::kInvalidArgument);
  EXPECT_FALSE(g.configured());
  EXPECT_EQ(g.configure(PoseGraphConfig{}, s.buffers()), Status::kOk);
  EXPECT_TRUE(g.configured());
  EXPECT_EQ(g.node_capacity(), 8u);
  EXPECT_EQ(g.edge_capacity(), 8u);
}

TEST(PoseGraph, UnconfiguredRefusesWork) {
  PoseGraph g;
  PoseGraphProgress p;
  EXPECT_EQ(g.add_node(Pose2{}, 0).status(), Status::kFailedPrecondition);
  EXPECT_EQ(g.add_loop_closure(0, 1, RelativePose2{}, kClosureInfo), Status::kFailedPrecondition);
  EXPECT_EQ(g.optimise_step(10, &p), Status::kFailedPrecondition);
  EXPECT_EQ(g.pose(0).status(), Status::kOutOfRange);
  EXPECT_EQ(g.node_count(), 0u);
}

Pose2 at(int64_t x_cm, int64_t y_cm, int64_t degrees) {
  return Pose2{Q31_32::from_ratio(x_cm, 100), Q31_32::from_ratio(y_cm, 100),
               Angle::from_degrees(degrees)};
}

TEST(PoseGraph, CapacityAndBadIndices) {
  static PoseGraphStorage<4, 4> s;
  PoseGraph g;
  ASSERT_EQ(g.configure(PoseGraphConfig{}, s.buffers()), Status::kOk);
  for (uint32_t k = 0; k < 4; ++k) {
    const Result<uint32_t> r = g.add_node(at(20 * k, 0, 0), 7 + k);
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r.value(), k);
  }
  EXPECT_EQ(g.add_node(at(80, 0, 0), 11).status(), Status::kResourceExhausted);
  EXPECT_EQ(g.node_count(), 4u);
  EXPECT_EQ(g.edge_count(), 3u);
  // Bad closures leave the graph as it was.
  EXPECT_EQ(g.add_loop_closure(0, 4, RelativePose2{}, kClosureInfo), Status::kOutOfRange);
  EXPECT_EQ(g.add_loop_closure(9, 1, RelativePose2{}, kClosureInfo), Status::kOutOfRange);
  EXPECT_EQ(g.add_loop_closure(2, 2, RelativePose2{}, kClosureInfo), Status::kInvalidArgument);
  EXPECT_EQ(g.add_loop_closure(0, 3, RelativePose2{}, EdgeInformation{}), Status::kInvalidArgument);
  RelativePose2 far{Q31_32::from_int(128), Q31_32::from_int(0), Angle{}};
  EXPECT_EQ(g.add_loop_closure(0, 3, far, kClosureInfo), Status::kOutOfRange);
  EXPECT_EQ(g.closure_count(), 0u);
  EXPECT_TRUE(g.converged());
  // The last edge slot takes one closure (heading information only is allowed).
  EXPECT_EQ(g.add_loop_closure(3, 0, RelativePose2{Q31_32::from_ratio(-6, 10), Q31_32{}, Angle{}},
                               EdgeInformation{UQ16_16{}, UQ16_16::from_int(4)}),
            Status::kOk);
  EXPECT_FALSE(g.converged());
  EXPECT_EQ(g.add_loop_closure(0, 2, RelativePose2{}, kClosureInfo), Status::kResourceExhausted);
  EXPECT_EQ(g.edge_count(), 4u);
  EXPECT_EQ(g.closure_count(), 1u);
  // Edges: the chain first, then the closure.
  for (uint32_t i = 0; i < 3; ++i) {
    const Result<PoseGraphEdge> e = g.edge(i);
    ASSERT_TRUE(e.ok());
    EXPECT_EQ(e.value().from, i);
    EXPECT_EQ(e.value().to, i + 1);
    EXPECT_EQ(e.value().dx.raw(), Q7_24::from_ratio(2, 10).raw());
    EXPECT_EQ(e.value().info_xy.raw(), UQ16_16::from_int(5).raw()) << "1 m / 0.2 m";
  }
  ASSERT_TRUE(g.edge(3).ok());
  EXPECT_EQ(g.edge(3).value().from, 3u);
  EXPECT_EQ(g.edge(3).value().to, 0u);
  EXPECT_EQ(g.edge(3).value().info_heading.raw(), UQ16_16::from_int(4).raw());
  EXPECT_EQ(g.edge(4).status(), Status::kOutOfRange);
  EXPECT_EQ(g.pose(4).status(), Status::kOutOfRange);
  EXPECT_EQ(g.place(3).value(), 10u);
  EXPECT_EQ(g.place(4).status(), Status::kOutOfRange);
  PoseGraphProgress p;
  EXPECT_EQ(g.optimise_step(0, &p), Status::kInvalidArgument);
  EXPECT_EQ(g.optimise_step(10, nullptr), Status::kInvalidArgument);
  const Solve solve = optimise(g, 10);
  EXPECT_TRUE(g.converged());
  EXPECT_LE(solve.max_work, 10u);
  // A straight chain with a consistent closure does not move (0.2 m is 3e-8 m off in Q7.24).
  for (uint32_t k = 0; k < 4; ++k) {
    EXPECT_NEAR(metres(g.pose(k).value().x), 0.2 * k, 1e-7);
    EXPECT_NEAR(metres(g.pose(k).value().y), 0.0, 1e-7);
  }

  // Edge capacity runs out before node capacity: kNodes - 1 odometry edges need room.
  static PoseGraphStorage<5, 3> t;
  ASSERT_EQ(g.configure(PoseGraphConfig{}, t.buffers()), Status::kOk);
  for (uint32_t k = 0; k < 4; ++k)
    ASSERT_TRUE(g.add_node(at(20 * k, 0, 0), k).ok());
  EXPECT_EQ(g.add_node(at(80, 0, 0), 4).status(), Status::kResourceExhausted);
  EXPECT_EQ(g.node_count(), 4u);
  // A step of 128 m cannot be an edge.
  static PoseGraphStorage<4, 4> u;
  ASSERT_EQ(g.configure(PoseGraphConfig{}, u.buffers()), Status::kOk);
  ASSERT_TRUE(g.add_node(at(0, 0, 0), 0).ok());
  EXPECT_EQ(g.add_node(at(12800, 0, 0), 1).status(), Status::kOutOfRange);
  EXPECT_TRUE(g.add_node(at(12799, 0, 0), 1).ok());
  g.reset();
  EXPECT_EQ(g.node_count(), 0u);
  EXPECT_EQ(g.edge_count(), 0u);
  EXPECT_TRUE(g.configured());
}

TEST(PoseGraph, OdometryInformationFollowsTheStep) {
  static PoseGraphStorage<4, 4> s;
  PoseGraph g;
  ASSERT_EQ(g.configure(PoseGraphConfig{}, s.buffers()), Status::kOk);
  ASSERT_TRUE(g.add_node(at(0, 0, 90), 0).ok());
  ASSERT_TRUE(g.add_node(at(0, 50, 90), 1).ok());   // 0.5 m ahead (the heading is +y)
  ASSERT_TRUE(g.add_node(at(0, 50, 180), 2).ok());  // turning on the spot: min_travel
  const PoseGraphEdge a = g.edge(0).value();
  EXPECT_EQ(a.info_xy.raw(), UQ16_16::from_int(2).raw());
  EXPECT_NEAR(a.dx.raw() / 16777216.0, 0.5, 1e-7);
  EXPECT_NEAR(a.dy.raw() / 16777216.0, 0.0, 1e-7);
  const PoseGraphEdge b = g.edge(1).value();
  EXPECT_NEAR(b.info_xy.raw() / kInfoOne, 100.0, 1e-3) << "1 m / 1 cm (1 cm in Q7.24)";
  EXPECT_EQ(b.dtheta.bam, Angle::from_degrees(90).bam);
}

// ---- The leaf rule -------------------------------------------------------------------------

TEST(PoseGraph, ChainReproducesOdometryAndStaysConverged) {
  static LoopStorage storage;
  PoseGraph g = configured(storage);
  const Loop& loop = the_loop();
  double worst = 0.0;
  for (uint32_t k = 0; k < kLoopNodes; ++k) {
    ASSERT_TRUE(g.add_node(loop.odometry[k], k).ok());
    EXPECT_TRUE(g.converged());
    const Pose2 p = g.pose(k).value();
    const double e = abs_d(metres(p.x) - metres(loop.odometry[k].x)) +
                     abs_d(metres(p.y) - metres(loop.odometry[k].y));
    if (e > worst) worst = e;
    EXPECT_EQ(p.heading.bam, loop.odometry[k].heading.bam);
  }
  test::log_figure("pose_graph chain vs odometry poses, worst |dx|+|dy| (m):", worst);
  EXPECT_LT(worst, 1e-5) << "Q7.24 steps and the rotation rounding over 456 steps";
  PoseGraphProgress p;
  EXPECT_EQ(g.optimise_step(100, &p), Status::kOk);
  EXPECT_TRUE(p.converged);
  EXPECT_EQ(p.work, 0u);
}

// ---- The loop -----------------------------------------------------------------------------

TEST(PoseGraph, LoopClosuresCorrectTheDrift) {
  static LoopStorage storage;
  PoseGraph g = configured(storage);
  add_loop_nodes(g, 0, kLoopNodes);
  ASSERT_EQ(g.closure_count(), kClosures);
  const Loop& loop = the_loop();
  const double drift =
      test::ref_sqrt((metres(loop.odometry[kLap].x) - metres(loop.truth[kLap].x)) *
                         (metres(loop.odometry[kLap].x) - metres(loop.truth[kLap].x)) +
                     (metres(loop.odometry[kLap].y) - metres(loop.truth[kLap].y)) *
                         (metres(loop.odometry[kLap].y) - metres(loop.truth[kLap].y)));
  test::log_figure("pose_graph loop: odometry drift after one lap (m):", drift);
  EXPECT_GT(drift, 1.0);
  EXPECT_LT(drift, 2.5);
  const double before = rmse(g);
  const uint32_t kBudget = 64;
  const Solve solve = optimise(g, kBudget);
  ASSERT_TRUE(g.converged());
  const double after = rmse(g);
  test::log_figure("pose_graph loop: dead-reckoning RMSE (m):", before);
  test::log_figure("pose_graph loop: optimised RMSE (m):", after);
  test::log_figure("pose_graph loop: slices of 64 units to converge:", solve.calls);
  test::log_figure("pose_graph loop: CG iterations:", g.stats().iterations);
  test::log_figure("pose_graph loop: residual recomputations:", g.stats().restarts);
  EXPECT_NEAR(before, rmse_dead_reckoning(), 1e-5);
  EXPECT_LT(after * 8, before) << "dead reckoning " << before << " m, optimised " << after << " m";
  // What remains is mostly the 0.3 % scale error, which no closure sees (a uniformly scaled
  // loop still closes): 0.3 % of the ~20 m mean distance from the start is 6 cm.
  EXPECT_LT(after, 0.15);
  EXPECT_TRUE(solve.work_counted);
  EXPECT_LE(solve.max_work, kBudget);
  EXPECT_EQ(g.stats().stalls, 0u);
  EXPECT_EQ(g.stats().solves, 1u);
  // Three stages, each at most closures + 1 iterations in exact arithmetic: rounding may add a
  // few, never many.
  EXPECT_LE(g.stats().iterations, 3u * (kClosures + 1) + 6);
  // The closed places now agree with their closures to a few centimetres.
  for (uint32_t c = 0; c < kClosures; ++c) {
    const RelativePose2 r =
        relative_pose(g.pose(kClosureA[c]).value(), g.pose(kClosureA[c] + kLap).value());
    EXPECT_LT(abs_d(metres(r.dx)), 0.05) << "closure " << c;
    EXPECT_LT(abs_d(metres(r.dy)), 0.05) << "closure " << c;
    EXPECT_LT(abs_d(radians(r.dtheta)), 0.01) << "closure " << c;
  }
  // The anchor never moves.
  EXPECT_EQ(g.pose(0).value().x, loop.odometry[0].x);
  EXPECT_EQ(g.pose(0).value().heading.bam, loop.odometry[0].heading.bam);
}

TEST(PoseGraph, WorkPerStepNeverExceedsTheBudget) {
  static LoopStorage reference_storage;
  PoseGraph reference = configured(reference_storage);
  add_loop_nodes(reference, 0, kLoopNodes);
  const Solve whole = optimise(reference, 0xFFFFFFFFu);
  EXPECT_EQ(whole.calls, 1u);
  static LoopStorage storage;
  for (uint32_t budget : {1u, 7u, 64u, 500u}) {
    PoseGraph g = configured(storage);
    add_loop_nodes(g, 0, kLoopNodes);
    const Solve s = optimise(g, budget);
    EXPECT_TRUE(g.converged()) << "budget " << budget;
    EXPECT_TRUE(s.work_counted) << "budget " << budget;
    EXPECT_LE(s.max_work, budget);
    EXPECT_EQ(s.max_work, budget) << "slices are used fully";
    // Slicing only decides where the work pauses: the same operations, the same result.
    EXPECT_EQ(g.stats().node_visits, reference.stats().node_visits) << "budget " << budget;
    const Difference d = largest_difference(g, reference);
    EXPECT_EQ(d.position, 0.0) << "budget " << budget;
    EXPECT_EQ(d.heading, 0.0) << "budget " << budget;
    if (budget == 64) {
      test::log_figure("pose_graph loop: units to converge:",
                       static_cast<double>(g.stats().node_visits + g.stats().closure_visits +
                                           g.stats().scalar_steps));
    }
  }
}

TEST(PoseGraph, IncrementalEqualsFromScratch) {
  static LoopStorage scratch_storage;
  PoseGraph scratch = configured(scratch_storage);
  add_loop_nodes(scratch, 0, kLoopNodes);
  optimise(scratch, 1000);
  ASSERT_TRUE(scratch.converged());

  // Closure by closure, optimising to convergence in between; the nodes after a converged
  // solve keep it converged (leaves).
  static LoopStorage storage;
  PoseGraph g = configured(storage);
  add_loop_nodes(g, 0, kLap + 1);
  optimise(g, 1000);
  ASSERT_TRUE(g.converged());
  add_loop_nodes(g, kLap + 1, kLap + 4);
  EXPECT_TRUE(g.converged()) << "leaves keep a solved graph solved";
  add_loop_nodes(g, kLap + 4, kLap + 5);  // the second closure
  EXPECT_FALSE(g.converged());
  optimise(g, 1000);
  // The rest while optimising: a node after every slice.
  uint32_t next = kLap + 5;
  PoseGraphProgress p;
  while (next < kLoopNodes) {
    ASSERT_EQ(g.optimise_step(300, &p), Status::kOk);
    add_loop_nodes(g, next, next + 1);
    ++next;
  }
  optimise(g, 1000);
  ASSERT_TRUE(g.converged());
  EXPECT_EQ(g.stats().stalls, 0u);
  const Difference d = largest_difference(g, scratch);
  test::log_figure("pose_graph incremental vs scratch, position (m):", d.position);
  test::log_figure("pose_graph incremental vs scratch, heading (rad):", d.heading);
  // Both are within the bounds of the same exact solution.
  test::log_figure("pose_graph loop: a-priori position bound (m):", position_bound(g));
  EXPECT_LT(d.position, 2 * position_bound(g));
  EXPECT_LT(d.heading, 2 * heading_bound(g));
}

// The robot's use: a node after every slice while a solve is under way, with slices that end
// while a CG step is being applied to the nodes (a budget just above one iteration's passes
// over ~450 nodes) and weak closures. A restart that abandoned the half-applied step tore the
// estimate between moved and unmoved nodes at every place, and the tears grew until headings
// were a full turn off (seen on a simulated explore run: RMSE 19 m instead of 0.55 m). The
// step is now finished first: estimates stay near the odometry's headings on the way, and the
// final solve equals the one from scratch.
TEST(PoseGraph, NodesArrivingDuringAStepNeverTearTheEstimate) {
  // The loop driven on for 52 more places after its last closure (the same turns rule).
  constexpr uint32_t kNodes = 509;
  static Pose2 truth[kNodes];
  static Pose2 odometry[kNodes];
  const Loop& loop = the_loop();
  for (uint32_t k = 0; k < kNodes; ++k) {
    if (k < kLoopNodes) {
      truth[k] = loop.truth[k];
      odometry[k] = loop.odometry[k];
      continue;
    }
    const int32_t turn = static_cast<int32_t>((int64_t{1} << 30) / 12);
    const int32_t dtheta = ((k - 1) % kLap % 112) >= 100 ? turn : 0;
    truth[k] = advance(truth[k - 1], Q31_32::from_ratio(2, 10), dtheta);
    odometry[k] = advance(odometry[k - 1], Q31_32::from_ratio(2 * kScaleNum, 10 * kScaleDen),
                          static_cast<int32_t>(dtheta * kScaleNum / kScaleDen) + kBiasPerStep);
  }
  const EdgeInformation weak{UQ16_16::from_ratio(3, 10), UQ16_16::from_ratio(3, 10)};
  for (const uint32_t budget : {2000u, 1300u, 3000u}) {
    static LoopStorage storage;
    PoseGraph g = configured(storage);
    static LoopStorage scratch_storage;
    PoseGraph scratch = configured(scratch_storage);
    double worst = 0.0;  // largest heading change of the newest node against its odometry
    PoseGraphProgress p;
    for (uint32_t k = 0; k < kNodes; ++k) {
      for (PoseGraph* graph : {&g, &scratch}) {
        ASSERT_TRUE(graph->add_node(odometry[k], k).ok());
        for (uint32_t c = 0; c < kClosures; ++c) {
          if (kClosureA[c] + kLap != k) continue;
          const RelativePose2 m = relative_pose(truth[kClosureA[c]], truth[k]);
          ASSERT_EQ(graph->add_loop_closure(kClosureA[c], k, m, weak), Status::kOk);
        }
      }
      ASSERT_EQ(g.optimise_step(budget, &p), Status::kOk);
      const double dev =
          abs_d(radians(Angle{g.pose(k).value().heading.bam - odometry[k].heading.bam}));
      if (dev > worst) worst = dev;
    }
    // The odometry's heading error over the lap is under 6 degrees (its drift plus the 0.3 %
    // turn error), and the corrections are of that size; the solve has progressed (a solve
    // that never applies a step leaves the newest node at its odometry heading).
    test::log_figure("pose_graph sliced with nodes arriving: worst online heading change (deg):",
                     worst * 180.0 / test::kPi);
    EXPECT_LT(worst, 10.0 * test::kPi / 180.0);
    EXPECT_GT(worst, 1.0 * test::kPi / 180.0);
    optimise(g, budget);
    optimise(scratch, 100000);
    ASSERT_TRUE(g.converged());
    ASSERT_TRUE(scratch.converged());
    const Difference d = largest_difference(g, scratch);
    EXPECT_LT(d.position, 2 * position_bound(g));
    EXPECT_LT(d.heading, 2 * heading_bound(g));
  }
}

// A grossly wrong closure (3 m and 170 degrees off a straight 50-node chain, and one at
// -170 degrees, i.e. 190): still a least-squares problem; the heading residual is unwrapped
// the short way round, the solve converges without stalls.
constexpr uint32_t kChainNodes = 50;

void add_false_closure_graph(PoseGraph& g, int64_t degrees) {
  for (uint32_t k = 0; k < kChainNodes; ++k)
    ASSERT_TRUE(g.add_node(at(20 * k, 0, 0), k).ok());
  const RelativePose2 wrong{Q31_32::from_ratio(128, 10), Q31_32::from_int(1),
                            Angle::from_degrees(degrees)};
  ASSERT_EQ(g.add_loop_closure(0, kChainNodes - 1, wrong, kClosureInfo), Status::kOk);
}

TEST(PoseGraph, GrossClosureStillConverges) {
  static PoseGraphStorage<kChainNodes, kChainNodes> storage;
  for (int64_t degrees : {170, -170, 190}) {
    PoseGraph g;
    ASSERT_EQ(g.configure(PoseGraphConfig{}, storage.buffers()), Status::kOk);
    add_false_closure_graph(g, degrees);
    const Solve s = optimise(g, 100);
    ASSERT_TRUE(g.converged());
    EXPECT_EQ(g.stats().stalls, 0u);
    EXPECT_LE(g.stats().iterations, 3u * 2 + 6);
    // The closure pulls the last heading most of the way (the chain's variance is 9.8 m of
    // odometry, the closure's 0.05): 170 * 9.8 / 9.85 degrees, the short way round.
    const double last = radians(g.pose(kChainNodes - 1).value().heading) * 180.0 / test::kPi;
    const double expected = (degrees == 170 ? 170.0 : -170.0) * 9.8 / 9.85;
    EXPECT_NEAR(last, expected, 0.01) << degrees;
    EXPECT_LE(s.max_work, 100u);
  }
}

// ---- Closures weak across the route -------------------------------------------------------
// A racetrack driven one and a half times with exact odometry: 30 nodes along +x at y = 0, a
// U-turn (radius 1 m), back along y = 2 m, a tighter U-turn (0.8 m) that brings the second
// pass along +x at y = 0.4 m. Its nodes are recognised as the first pass's nodes at the same
// x with the identity (what an image match says: "the same place"), which is right along the
// route and 0.4 m wrong across it.
constexpr uint32_t kStraight = 30;
constexpr uint32_t kTurnSteps = 12;

void add_pose(PoseGraph& g, Pose2* last, double x, double y, double heading_deg) {
  const Pose2 p{
      Q31_32::from_raw(static_cast<int64_t>(x * kMetre)),
      Q31_32::from_raw(static_cast<int64_t>(y * kMetre)),
      Angle{static_cast<uint32_t>(static_cast<int64_t>(heading_deg / 360.0 * kBamPerTurn))}};
  ASSERT_TRUE(g.add_node(p, g.node_count()).ok());
  *last = p;
}

// Returns the mean y of the second pass minus the first over the recognised nodes, after the
// solve with `lateral` (PoseGraphConfig::closure_lateral).
double racetrack_gap(UQ16_16 lateral, double* along_error) {
  static PoseGraphStorage<3 * kStraight + 2 * kTurnSteps, 4 * kStraight + 2 * kTurnSteps> storage;
  PoseGraphConfig c;
  c.closure_lateral = lateral;
  PoseGraph g;
  EXPECT_EQ(g.configure(c, storage.buffers()), Status::kOk);
  Pose2 last{};
  const double step = 0.2;
  for (uint32_t k = 0; k < kStraight; ++k)
    add_pose(g, &last, step * k, 0.0, 0.0);
  const double x_end = step * (kStraight - 1);
  for (uint32_t k = 1; k <= kTurnSteps; ++k) {  // centre (x_end, 1), radius 1, -90 .. 90 deg
    const double a = (-90.0 + 180.0 * k / kTurnSteps) * test::kPi / 180.0;
    add_pose(g, &last, x_end + test::ref_cos(a), 1.0 + test::ref_sin(a), 180.0 * k / kTurnSteps);
  }
  for (uint32_t k = 1; k < kStraight; ++k)
    add_pose(g, &last, x_end - step * k, 2.0, 180.0);
  for (uint32_t k = 1; k <= kTurnSteps; ++k) {  // centre (0, 1.2), radius 0.8, 90 .. 270 deg
    const double a = (90.0 + 180.0 * k / kTurnSteps) * test::kPi / 180.0;
    add_pose(g, &last, 0.8 * test::ref_cos(a), 1.2 + 0.8 * test::ref_sin(a),
             180.0 + 180.0 * k / kTurnSteps);
  }
  const uint32_t second = g.node_count() - 1;  // (0, 0.4), heading a full turn
  for (uint32_t k = 1; k < kStraight; ++k)
    add_pose(g, &last, step * k, 0.4, 360.0);
  const EdgeInformation info{UQ16_16::from_int(20), UQ16_16::from_int(20)};
  for (uint32_t k = 2; k < kStraight; k += 3) {
    EXPECT_EQ(g.add_loop_closure(k, second + k, RelativePose2{}, info), Status::kOk);
  }
  optimise(g, 1000);
  EXPECT_TRUE(g.converged());
  double gap = 0.0;
  double along = 0.0;
  uint32_t n = 0;
  for (uint32_t k = 2; k < kStraight; k += 3) {
    const Pose2 a = g.pose(k).value();
    const Pose2 b = g.pose(second + k).value();
    gap += metres(b.y) - metres(a.y);
    const double d = abs_d(metres(b.x) - metres(a.x));
    if (d > along) along = d;
    ++n;
  }
  *along_error = along;
  return gap / n;
}

TEST(PoseGraph, ClosuresWeakAcrossKeepPassesApartSideBySide) {
  double along = 0.0;
  const double iso = racetrack_gap(UQ16_16::from_int(1), &along);
  test::log_figure("racetrack: gap between the passes, closures alike in all directions (m):", iso);
  EXPECT_LT(iso, 0.01) << "identity closures pull the passes together";
  const double none = racetrack_gap(UQ16_16{}, &along);
  test::log_figure("racetrack: gap between the passes, no information across (m):", none);
  EXPECT_NEAR(none, 0.4, 0.002) << "the odometry's 0.4 m across is kept";
  EXPECT_LT(along, 1e-3) << "and the passes still meet along the route";
  // A little information across pulls a little: in the linear position stage the chain of
  // ~17 m between the passes resists a sideways shift no more than 17 m of odometry does.
  const double weak = racetrack_gap(UQ16_16::from_ratio(1, 1000), &along);
  test::log_figure("racetrack: gap between the passes, closures 1/1000 as sure across (m):", weak);
  EXPECT_GT(weak, iso + 0.05);
  EXPECT_LT(weak, none - 0.05);
  EXPECT_LT(along, 1e-3);
}

// ---- Information as the data give it (issue 35) --------------------------------------------

PoseInformation information(int64_t along, int64_t lateral, int64_t cross, int64_t heading,
                            int64_t along_heading = 0, int64_t lateral_heading = 0,
                            int64_t den = 1) {
  return PoseInformation{UQ16_16::from_ratio(along, den), UQ16_16::from_ratio(lateral, den),
                         Q15_16::from_ratio(cross, den), UQ16_16::from_ratio(heading, den),
                         Q15_16::from_ratio(along_heading, den),
                         Q15_16::from_ratio(lateral_heading, den)};
}

TEST(PoseGraph, InformationAsTheDataGiveIt) {
  static PoseGraphStorage<8, 8> s;
  PoseGraph g;
  ASSERT_EQ(g.configure(PoseGraphConfig{}, s.buffers()), Status::kOk);
  ASSERT_TRUE(g.add_node(at(0, 0, 0), 0).ok());
  // Anisotropic with a cross term and position-heading terms: stored as given.
  ASSERT_TRUE(g.add_node(at(50, 0, 0), 1, information(4, 16, 2, 8, 1, -3)).ok());
  const PoseGraphEdge e = g.edge(0).value();
  EXPECT_EQ(e.info_xy.raw(), UQ16_16::from_int(4).raw());
  EXPECT_EQ(e.info_lateral.raw(), UQ16_16::from_int(16).raw());
  EXPECT_EQ(e.info_cross.raw(), Q15_16::from_int(2).raw());
  EXPECT_EQ(e.info_heading.raw(), UQ16_16::from_int(8).raw());
  EXPECT_EQ(e.info_along_heading.raw(), Q15_16::from_int(1).raw());
  EXPECT_EQ(e.info_lateral_heading.raw(), Q15_16::from_int(-3).raw());
  // Odometry information must be positive definite with eigenvalues and heading >= 1/256.
  EXPECT_EQ(g.add_node(at(100, 0, 0), 2, information(4, 4, 4, 8)).status(),
            Status::kInvalidArgument);  // singular
  EXPECT_EQ(g.add_node(at(100, 0, 0), 2, information(4, 1, 0, 8, 0, 0, 512)).status(),
            Status::kInvalidArgument);  // lateral 1/512
  EXPECT_EQ(g.add_node(at(100, 0, 0), 2, information(4, 4, 0, 1, 0, 0, 512)).status(),
            Status::kInvalidArgument);  // heading 1/512
  EXPECT_EQ(g.add_node(at(100, 0, 0), 2, information(4, 4, 0, 1, 3)).status(),
            Status::kInvalidArgument);  // along-heading term beyond sqrt(4 * 1)
  EXPECT_EQ(g.add_node(at(100, 0, 0), 2, information(4, 4, 3, 4, 3, -3)).status(),
            Status::kInvalidArgument);  // 2x2 minors fine, determinant negative
  EXPECT_EQ(g.node_count(), 2u);
  EXPECT_TRUE(g.add_node(at(100, 0, 0), 2, information(4, 4, 0, 1, 1, 1)).ok());
  // Closures: positive semi-definite (a rank-one position block is allowed), not all zero.
  EXPECT_EQ(g.add_loop_closure(0, 2, RelativePose2{}, information(4, 1, 3, 1)),
            Status::kInvalidArgument);
  EXPECT_EQ(g.add_loop_closure(0, 2, RelativePose2{}, information(0, 0, 0, 0)),
            Status::kInvalidArgument);
  EXPECT_EQ(g.add_loop_closure(0, 2, RelativePose2{}, information(4, 1, 2, 0)), Status::kOk);
  EXPECT_EQ(g.closure_count(), 1u);
  // The explorer's closures keep their meaning: weaker across by closure_lateral.
  PoseGraphConfig weak;
  weak.closure_lateral = UQ16_16::from_ratio(1, 4);
  ASSERT_EQ(g.configure(weak, s.buffers()), Status::kOk);
  ASSERT_TRUE(g.add_node(at(0, 0, 0), 0).ok());
  ASSERT_TRUE(g.add_node(at(20, 0, 0), 1).ok());
  ASSERT_EQ(g.add_loop_closure(0, 1, RelativePose2{}, kClosureInfo), Status::kOk);
  EXPECT_EQ(g.edge(1).value().info_xy.raw(), UQ16_16::from_int(20).raw());
  EXPECT_EQ(g.edge(1).value().info_lateral.raw(), UQ16_16::from_int(5).raw());
  EXPECT_EQ(g.edge(0).value().info_lateral.raw(), g.edge(0).value().info_xy.raw());
  // Settings of the new knobs.
  PoseGraphConfig c;
  c.refine_restarts = 1;
  EXPECT_EQ(g.configure(c, s.buffers()), Status::kInvalidArgument) << "no refine buffer";
  c = PoseGraphConfig{};
  c.max_scale = 49;
  EXPECT_EQ(g.configure(c, s.buffers()), Status::kInvalidArgument);
  c = PoseGraphConfig{};
  c.max_iterations = 10001;
  EXPECT_EQ(g.configure(c, s.buffers()), Status::kInvalidArgument);
}

// ---- Overflow: rescaled, or refused with a status (issue 35) --------------------------------
// A straight chain of very certain steps (information 30 000) closed by a measurement 150
// degrees and 2 m off: the heading stage's first residual, 30 000 x 0.42 turn in 2^-40 turn,
// is 2^53.6, beyond the CG vectors' limit. The same graph with every information divided by
// 1024 is the same least-squares problem (only ratios matter) and stays within it.
constexpr uint32_t kStiffNodes = 300;

void add_stiff_graph(PoseGraph& g, int64_t den) {
  for (uint32_t k = 0; k < kStiffNodes; ++k) {
    const Result<uint32_t> r = k == 0 ? g.add_node(at(0, 0, 0), 0)
                                      : g.add_node(at(20 * k, 0, 0), k,
                                                   information(30000, 30000, 0, 30000, 0, 0, den));
    ASSERT_TRUE(r.ok()) << k;
  }
  const RelativePose2 off{Q31_32::from_ratio(20 * (kStiffNodes - 1) + 200, 100), Q31_32{},
                          Angle::from_degrees(150)};
  ASSERT_EQ(g.add_loop_closure(0, kStiffNodes - 1, off,
                               information(30000, 30000, 0, 30000, 0, 0, den)),
            Status::kOk);
}

TEST(PoseGraph, OverflowIsRescaledNeverSilent) {
  static PoseGraphStorage<kStiffNodes, kStiffNodes> strong_storage;
  static PoseGraphStorage<kStiffNodes, kStiffNodes> weak_storage;
  PoseGraph strong;
  PoseGraph weak;
  ASSERT_EQ(strong.configure(PoseGraphConfig{}, strong_storage.buffers()), Status::kOk);
  ASSERT_EQ(weak.configure(PoseGraphConfig{}, weak_storage.buffers()), Status::kOk);
  add_stiff_graph(strong, 1);
  add_stiff_graph(weak, 1024);
  optimise(strong, 500);
  optimise(weak, 500);
  ASSERT_TRUE(strong.converged());
  ASSERT_TRUE(weak.converged());
  test::log_figure("pose_graph stiff chain: rescales (information 30 000):",
                   strong.stats().rescales);
  test::log_figure("pose_graph stiff chain: coarsest scale (bits):", strong.stats().max_scale);
  EXPECT_GE(strong.stats().rescales, 1u) << "the overflow path was taken";
  EXPECT_GE(strong.stats().max_scale, 1u);
  EXPECT_EQ(weak.stats().rescales, 0u);
  EXPECT_EQ(strong.stats().failures, 0u);
  // The same problem, the same solution (each within the stopping rule's bound of it).
  const Difference d = largest_difference(strong, weak);
  test::log_figure("pose_graph stiff chain: rescaled vs unscaled, position (m):", d.position);
  test::log_figure("pose_graph stiff chain: rescaled vs unscaled, heading (rad):", d.heading);
  EXPECT_LT(d.position, 2 * position_bound(weak));
  EXPECT_LT(d.heading, 2 * heading_bound(weak));
  // And the closure (as certain as one step of the 299) turned the last node 299/300 of the
  // way.
  const double last = radians(strong.pose(kStiffNodes - 1).value().heading) * 180.0 / test::kPi;
  EXPECT_NEAR(last, 150.0 * 299 / 300, 0.01);
}

// With no room to rescale (max_scale 0) the same graph is refused: kOutOfRange, stage
// kFailed, never converged; the estimates are the last valid ones.
TEST(PoseGraph, OverflowBeyondTheLimitIsAnErrorNeverConverged) {
  static PoseGraphStorage<kStiffNodes, kStiffNodes + 1> storage;
  PoseGraphConfig c;
  c.max_scale = 0;
  PoseGraph g;
  ASSERT_EQ(g.configure(c, storage.buffers()), Status::kOk);
  add_stiff_graph(g, 1);
  PoseGraphProgress p;
  Status s = Status::kOk;
  uint32_t calls = 0;
  do {
    s = g.optimise_step(100, &p);
    ++calls;
  } while (s == Status::kOk && !p.converged && calls < 100000);
  EXPECT_EQ(s, Status::kOutOfRange);
  EXPECT_FALSE(p.converged);
  EXPECT_EQ(p.stage, PoseGraphStage::kFailed);
  EXPECT_TRUE(g.failed());
  EXPECT_FALSE(g.converged());
  EXPECT_EQ(g.stats().failures, 1u);
  EXPECT_EQ(g.stats().solves, 0u);
  // It stays failed: no work, the same status.
  EXPECT_EQ(g.optimise_step(100, &p), Status::kOutOfRange);
  EXPECT_EQ(p.work, 0u);
  EXPECT_FALSE(p.converged);
  // The estimates were never moved by an overflowed step: the chain is still odometry.
  EXPECT_EQ(g.pose(kStiffNodes - 1).value().heading.bam, 0u);
  // A new closure tries again (and fails again); reset() empties the graph.
  ASSERT_EQ(g.add_loop_closure(1, kStiffNodes - 2, RelativePose2{}, kClosureInfo), Status::kOk);
  do {
    s = g.optimise_step(100, &p);
  } while (s == Status::kOk && !p.converged);
  EXPECT_EQ(s, Status::kOutOfRange);
  EXPECT_EQ(g.stats().failures, 2u);
  g.reset();
  EXPECT_TRUE(g.converged());
  EXPECT_EQ(g.optimise_step(100, &p), Status::kOk);
}

// A state saved under the old layout (tag PGR2) is refused, and the graph is reset.
TEST(PoseGraph, RefusesAStateOfTheOldLayout) {
  static PoseGraphStorage<kStiffNodes, kStiffNodes> storage;
  static test::RamState<64 * 1024> saved;
  PoseGraph g;
  ASSERT_EQ(g.configure(PoseGraphConfig{}, storage.buffers()), Status::kOk);
  add_stiff_graph(g, 1024);
  PoseGraphProgress p;
  ASSERT_EQ(g.optimise_step(777, &p), Status::kOk);
  StateOut out(saved);
  g.state(out);
  ASSERT_EQ(out.status(), Status::kOk);
  PoseGraph h;
  ASSERT_EQ(h.configure(PoseGraphConfig{}, storage.buffers()), Status::kOk);
  StateIn in(saved);
  h.state(in);
  ASSERT_EQ(in.status(), Status::kOk);
  EXPECT_EQ(h.node_count(), kStiffNodes);
  uint32_t at_tag = 0;
  while (at_tag + 4 <= saved.size() &&
         !(saved.bytes[at_tag] == 'P' && saved.bytes[at_tag + 1] == 'G' &&
           saved.bytes[at_tag + 2] == 'R' && saved.bytes[at_tag + 3] == '4'))
    ++at_tag;
  ASSERT_LT(at_tag + 4, saved.size());
  saved.bytes[at_tag + 3] = '3';
  saved.rewind();
  StateIn old(saved);
  h.state(old);
  EXPECT_EQ(old.status(), Status::kDataLoss);
  EXPECT_EQ(h.node_count(), 0u);
}

#if defined(POSE_GRAPH_TEST_HAS_REFERENCE)
// ---- Against the double-precision reference (host) -----------------------------------------

double wrap(double a) {
  while (a > test::kPi)
    a -= 2 * test::kPi;
  while (a <= -test::kPi)
    a += 2 * test::kPi;
  return a;
}

double rmse(const std::vector<reference::PoseRef>& poses) {
  const Loop& loop = the_loop();
  double sum = 0.0;
  for (size_t k = 0; k < poses.size(); ++k) {
    const double dx = poses[k].x - metres(loop.truth[k].x);
    const double dy = poses[k].y - metres(loop.truth[k].y);
    sum += dx * dx + dy * dy;
  }
  return test::ref_sqrt(sum / static_cast<double>(poses.size()));
}

TEST(PoseGraph, MatchesDoublePrecisionDirectSolve) {
  static LoopStorage storage;
  PoseGraph g = configured(storage);
  add_loop_nodes(g, 0, kLoopNodes);
  const std::vector<reference::PoseEdgeRef> edges = reference::pose_edges_of(g);
  const Pose2 anchor = g.pose(0).value();
  const reference::PoseRef a{metres(anchor.x), metres(anchor.y), radians(anchor.heading)};
  std::vector<reference::PoseRef> initial;
  for (uint32_t k = 0; k < g.node_count(); ++k) {
    const Pose2 p = g.pose(k).value();
    initial.push_back({metres(p.x), metres(p.y), radians(p.heading)});
  }
  optimise(g, 1000);
  ASSERT_TRUE(g.converged());
  const std::vector<reference::PoseRef> ref =
      reference::pose_graph_linear(static_cast<int>(g.node_count()), edges, a);
  double position = 0.0;
  double heading = 0.0;
  for (uint32_t k = 0; k < g.node_count(); ++k) {
    const Pose2 p = g.pose(k).value();
    position = std::max(position, abs_d(metres(p.x) - ref[k].x));
    position = std::max(position, abs_d(metres(p.y) - ref[k].y));
    heading = std::max(heading, abs_d(wrap(radians(p.heading) - ref[k].theta)));
  }
  test::log_figure("pose_graph vs double direct solve, largest position error (m):", position);
  test::log_figure("pose_graph vs double direct solve, largest heading error (deg):",
                   heading * 180.0 / test::kPi);
  EXPECT_LT(position, 1e-3) << "stated bound: 1 mm";
  EXPECT_LT(heading * 180.0 / test::kPi, 0.01) << "stated bound: 0.01 degree";
  EXPECT_LT(position, position_bound(g)) << "the stopping rule's guarantee";
  EXPECT_LT(heading, heading_bound(g)) << "the stopping rule's guarantee";
  test::log_figure("pose_graph loop: double linear (LAGO) RMSE (m):", rmse(ref));

  // The full nonlinear problem from dead reckoning, for comparison (variances per metre of
  // odometry: (1 cm)^2 and (0.5 degree)^2).
  const std::vector<reference::PoseRef> gn =
      reference::pose_graph_gauss_newton(edges, initial, 1e-4, 7.6e-5);
  test::log_figure("pose_graph loop: double Gauss-Newton RMSE (m):", rmse(gn));
  double gn_gap = 0.0;
  for (size_t k = 0; k < gn.size(); ++k) {
    gn_gap = std::max(gn_gap, test::ref_sqrt((gn[k].x - ref[k].x) * (gn[k].x - ref[k].x) +
                                             (gn[k].y - ref[k].y) * (gn[k].y - ref[k].y)));
  }
  test::log_figure("pose_graph loop: largest linear vs Gauss-Newton distance (m):", gn_gap);
  EXPECT_LT(rmse(gn), 0.15);
}

// Closures weak across the route (PoseGraphConfig::closure_lateral): the coupled x-y solve.
TEST(PoseGraph, WeakAcrossClosuresMatchDoublePrecisionDirectSolve) {
  static LoopStorage storage;
  for (const UQ16_16 f : {UQ16_16{}, UQ16_16::from_ratio(1, 20), UQ16_16::from_ratio(1, 2)}) {
    PoseGraphConfig c;
    c.closure_lateral = f;
    PoseGraph g = configured(storage, c);
    add_loop_nodes(g, 0, kLoopNodes);
    const Pose2 anchor = g.pose(0).value();
    optimise(g, 1000);
    ASSERT_TRUE(g.converged());
    const std::vector<reference::PoseRef> ref = reference::pose_graph_linear(
        static_cast<int>(g.node_count()), reference::pose_edges_of(g),
        reference::PoseRef{metres(anchor.x), metres(anchor.y), radians(anchor.heading)});
    double position = 0.0;
    for (uint32_t k = 0; k < g.node_count(); ++k) {
      const Pose2 p = g.pose(k).value();
      position = std::max(position, abs_d(metres(p.x) - ref[k].x));
      position = std::max(position, abs_d(metres(p.y) - ref[k].y));
    }
    test::log_figure("pose_graph weak across vs double direct solve, largest position error (m):",
                     position);
    EXPECT_LT(position, 1e-3) << "stated bound: 1 mm, f " << f.raw();
    EXPECT_LT(position, position_bound(g)) << "the stopping rule's guarantee, f " << f.raw();
  }
}

TEST(PoseGraph, GrossClosureMatchesDoublePrecisionDirectSolve) {
  static PoseGraphStorage<kChainNodes, kChainNodes> storage;
  for (int64_t degrees : {170, -170}) {
    PoseGraph g;
    ASSERT_EQ(g.configure(PoseGraphConfig{}, storage.buffers()), Status::kOk);
    add_false_closure_graph(g, degrees);
    optimise(g, 100);
    ASSERT_TRUE(g.converged());
    const std::vector<reference::PoseRef> ref = reference::pose_graph_linear(
        static_cast<int>(g.node_count()), reference::pose_edges_of(g), reference::PoseRef{});
    for (uint32_t k = 0; k < g.node_count(); ++k) {
      const Pose2 p = g.pose(k).value();
      EXPECT_NEAR(metres(p.x), ref[k].x, position_bound(g)) << degrees << " node " << k;
      EXPECT_NEAR(metres(p.y), ref[k].y, position_bound(g)) << degrees << " node " << k;
      EXPECT_LT(abs_d(wrap(radians(p.heading) - ref[k].theta)), heading_bound(g)) << k;
    }
  }
}

// ---- Information as the data give it, against the reference (issue 35) ----------------------

// The loop with anisotropic information on every edge (odometry 4:1 along:across with a cross
// term, closures the other way round): LAGO against the dense double solve.
void add_anisotropic_loop(PoseGraph& g, const PoseInformation& odometry,
                          const PoseInformation& closure) {
  const Loop& loop = the_loop();
  for (uint32_t k = 0; k < kLoopNodes; ++k) {
    const Result<uint32_t> r =
        k == 0 ? g.add_node(loop.odometry[0], 0) : g.add_node(loop.odometry[k], k, odometry);
    ASSERT_TRUE(r.ok()) << k;
    for (uint32_t c = 0; c < kClosures; ++c) {
      if (kClosureA[c] + kLap != k) continue;
      ASSERT_EQ(g.add_loop_closure(kClosureA[c], k,
                                   relative_pose(loop.truth[kClosureA[c]], loop.truth[k]), closure),
                Status::kOk);
    }
  }
}

std::vector<reference::PoseRef> poses_of(const PoseGraph& g) {
  std::vector<reference::PoseRef> out;
  for (uint32_t k = 0; k < g.node_count(); ++k) {
    const Pose2 p = g.pose(k).value();
    out.push_back({metres(p.x), metres(p.y), radians(p.heading)});
  }
  return out;
}

Difference largest_difference(const PoseGraph& g, const std::vector<reference::PoseRef>& ref) {
  Difference d;
  for (uint32_t k = 0; k < g.node_count(); ++k) {
    const Pose2 p = g.pose(k).value();
    d.position = std::max(d.position, abs_d(metres(p.x) - ref[k].x));
    d.position = std::max(d.position, abs_d(metres(p.y) - ref[k].y));
    d.heading = std::max(d.heading, abs_d(wrap(radians(p.heading) - ref[k].theta)));
  }
  return d;
}

TEST(PoseGraph, AnisotropicInformationMatchesDoublePrecisionDirectSolve) {
  static LoopStorage storage;
  PoseGraph g = configured(storage);
  add_anisotropic_loop(g, information(20, 5, 3, 10), information(5, 20, -4, 20));
  ASSERT_GT(g.edge(0).value().info_cross.raw(), 0);
  optimise(g, 1000);
  ASSERT_TRUE(g.converged());
  EXPECT_EQ(g.stats().stalls, 0u);
  const Pose2 anchor = g.pose(0).value();
  const reference::PoseRef a{metres(anchor.x), metres(anchor.y), radians(anchor.heading)};
  const std::vector<reference::PoseEdgeRef> edges = reference::pose_edges_of(g);
  const std::vector<reference::PoseRef> ref =
      reference::pose_graph_linear(static_cast<int>(g.node_count()), edges, a);
  const Difference d = largest_difference(g, ref);
  test::log_figure("pose_graph anisotropic vs double direct solve, position (m):", d.position);
  test::log_figure("pose_graph anisotropic vs double direct solve, heading (rad):", d.heading);
  EXPECT_LT(d.position, position_bound(g)) << "the stopping rule's guarantee";
  EXPECT_LT(d.heading, heading_bound(g)) << "the stopping rule's guarantee";
  // The iterative reference (for graphs too large for the dense one) is the same solve.
  const std::vector<reference::PoseRef> it =
      reference::pose_graph_linear_iterative(static_cast<int>(g.node_count()), edges, a);
  double gap = 0.0;
  for (size_t k = 0; k < it.size(); ++k) {
    gap = std::max(gap, std::max(abs_d(it[k].x - ref[k].x), abs_d(it[k].y - ref[k].y)));
    gap = std::max(gap, abs_d(it[k].theta - ref[k].theta));
  }
  EXPECT_LT(gap, 1e-9);
}

// The objective's tolerance (issue 35): with position and heading tolerances no solve can reach
// (2^-32 m, 1 binary-angle unit) each LAGO stage ends certified by the objective's test, and
// the bounds it records hold against the dense double solve of the same problem: headings
// within sqrt(V_h b_0), positions within sqrt(V b_1) + that heading bound x the summed edge
// lengths (pose_graph.h, "Stopping"), plus rounding.
TEST(PoseGraph, ObjectiveToleranceIsCertified) {
  static LoopStorage storage;
  PoseGraphConfig c;
  c.tolerance_xy = Q31_32::from_raw(1);
  c.tolerance_heading = Angle{1};
  c.tolerance_objective = Q31_32::from_ratio(1, 1000000);
  PoseGraph g;
  g.enable_refine();
  ASSERT_EQ(g.configure(c, storage.buffers()), Status::kOk);
  add_anisotropic_loop(g, information(20, 5, 3, 10), information(5, 20, -4, 20));
  optimise(g, 1000);
  ASSERT_TRUE(g.converged());
  EXPECT_EQ(g.stats().stalls, 0u);
  EXPECT_EQ(g.stats().tolerance_stops, 2u);
  const double b0 = std::ldexp(static_cast<double>(g.stats().objective_bound[0]), -32);
  const double b1 = std::ldexp(static_cast<double>(g.stats().objective_bound[1]), -32);
  EXPECT_LE(b0, 1e-6);
  EXPECT_LE(b1, 1e-6);
  const double vh = std::ldexp(static_cast<double>(g.chain_variance_sum(true)), -24);
  const double v = std::ldexp(static_cast<double>(g.chain_variance_sum(false)), -24);
  double length = 0.0;
  for (uint32_t i = 0; i < g.edge_count(); ++i) {
    const PoseGraphEdge e = g.edge(i).value();
    length += std::hypot(e.dx.raw() / 16777216.0, e.dy.raw() / 16777216.0);
  }
  const double heading_certified = std::sqrt(vh * b0);
  const double position_certified = std::sqrt(v * b1) + heading_certified * length;
  const Pose2 anchor = g.pose(0).value();
  const std::vector<reference::PoseRef> ref = reference::pose_graph_linear(
      static_cast<int>(g.node_count()), reference::pose_edges_of(g),
      reference::PoseRef{metres(anchor.x), metres(anchor.y), radians(anchor.heading)});
  const Difference d = largest_difference(g, ref);
  test::log_figure("pose_graph objective tolerance 1e-6: certified heading bound (rad):",
                   heading_certified);
  test::log_figure("pose_graph objective tolerance 1e-6: heading vs double (rad):", d.heading);
  test::log_figure("pose_graph objective tolerance 1e-6: certified position bound (m):",
                   position_certified);
  test::log_figure("pose_graph objective tolerance 1e-6: position vs double (m):", d.position);
  EXPECT_LT(d.heading, heading_certified + 2e-9);
  EXPECT_LT(d.position, position_certified + 1e-6);
}

// The tree preconditioner (issue 35): closures stiffer than the odometry become their newer
// node's tree edge (the closure from node 0 hangs node 448 from the anchor), and LAGO with it
// meets the same stopping guarantee against the dense double solve as with the chain.
TEST(PoseGraph, TreePreconditionerMatchesDoublePrecisionDirectSolve) {
  static LoopStorage storage;
  static PoseGraphTreeStorage<512> tree;
  static_assert(PoseGraphTreeStorage<512>::kBytes == 512 * 40, "40 bytes a node");
  PoseGraphConfig c;
  c.tree_preconditioner = true;
  PoseGraphBuffers b = storage.buffers();
  b.tree = tree.slots();
  PoseGraph g;
  EXPECT_EQ(g.configure(c, b), Status::kInvalidArgument) << "the tree is not linked yet";
  g.enable_refine();
  b.tree = tree.slots().subspan(0, 511);
  EXPECT_EQ(g.configure(c, b), Status::kInvalidArgument) << "shorter than the nodes";
  b.tree = tree.slots();
  ASSERT_EQ(g.configure(c, b), Status::kOk);
  const PoseInformation odometry = information(20, 5, 3, 10);
  const PoseInformation closure = information(50, 40, 2, 30);
  add_anisotropic_loop(g, odometry, closure);
  EXPECT_EQ(tree.slot[100].parent, 99u);
  EXPECT_EQ(tree.slot[448].parent, 0u);
  EXPECT_EQ(tree.slot[452].parent, 4u);
  EXPECT_EQ(tree.slot[456].parent, 8u);
  EXPECT_LT(tree.slot[456].var, tree.slot[455].var);
  optimise(g, 1000);
  ASSERT_TRUE(g.converged());
  EXPECT_EQ(g.stats().stalls, 0u);
  const Pose2 anchor = g.pose(0).value();
  const std::vector<reference::PoseRef> ref = reference::pose_graph_linear(
      static_cast<int>(g.node_count()), reference::pose_edges_of(g),
      reference::PoseRef{metres(anchor.x), metres(anchor.y), radians(anchor.heading)});
  const Difference d = largest_difference(g, ref);
  test::log_figure("pose_graph tree vs double direct solve, position (m):", d.position);
  test::log_figure("pose_graph tree vs double direct solve, heading (rad):", d.heading);
  EXPECT_LT(d.position, position_bound(g)) << "the stopping rule's guarantee";
  EXPECT_LT(d.heading, heading_bound(g)) << "the stopping rule's guarantee";
  static LoopStorage chain_storage;
  PoseGraph chain = configured(chain_storage);
  add_anisotropic_loop(chain, odometry, closure);
  optimise(chain, 1000);
  test::log_figure("pose_graph CG iterations, chain preconditioner:", chain.stats().iterations);
  test::log_figure("pose_graph CG iterations, tree preconditioner:", g.stats().iterations);
  // (Not fewer here: three closures on a loop whose every odometry edge is anisotropic; the
  // public graphs' figures are in docs/mapping.md.) The same solution either way:
  const Difference dc = largest_difference(g, chain);
  EXPECT_LT(dc.position, 2 * position_bound(g));
  EXPECT_LT(dc.heading, 2 * heading_bound(g));
}

// g2o's objective in the core's convention: e = (R_from^T (p_to - p_from) - d, wrapped
// theta_to - theta_from - dtheta), sum e^T Omega e with the full 3x3 information.
double objective(const std::vector<reference::PoseEdgeRef>& edges,
                 const std::vector<reference::PoseRef>& x) {
  double sum = 0.0;
  for (const reference::PoseEdgeRef& e : edges) {
    const reference::PoseRef& a = x[static_cast<size_t>(e.from)];
    const reference::PoseRef& b = x[static_cast<size_t>(e.to)];
    const double c = test::ref_cos(a.theta);
    const double s = test::ref_sin(a.theta);
    const double v[3] = {c * (b.x - a.x) + s * (b.y - a.y) - e.dx,
                         -s * (b.x - a.x) + c * (b.y - a.y) - e.dy,
                         wrap(b.theta - a.theta - e.dtheta)};
    const double lateral = e.info_lateral < 0 ? e.info_xy : e.info_lateral;
    sum += e.info_xy * v[0] * v[0] + lateral * v[1] * v[1] + e.info_heading * v[2] * v[2] +
           2 * (e.info_cross * v[0] * v[1] + e.info_along_heading * v[0] * v[2] +
                e.info_lateral_heading * v[1] * v[2]);
  }
  return sum;
}

// The nonlinear finish on the loop (odometry sure to 2 cm and 1 degree a step, with
// position-heading terms; closures to 5 cm and 2 degrees): Gauss-Newton in fixed point
// against Gauss-Newton in double of the same stored problem.
TEST(PoseGraph, RefineReachesTheDoublePrecisionOptimum) {
  static LoopStorage storage;
  static PoseGraphRefineStorage<512> refine;
  PoseGraphConfig c;
  c.refine_restarts = 20;
  c.tolerance_xy = Q31_32::from_ratio(1, 1000000);
  PoseGraphBuffers b = storage.buffers();
  b.refine = refine.slots();
  PoseGraph g;
  EXPECT_EQ(g.configure(c, b), Status::kInvalidArgument) << "the finish is not linked yet";
  g.enable_refine();
  ASSERT_EQ(g.configure(c, b), Status::kOk);
  add_anisotropic_loop(g, information(2500, 2500, 0, 3283, 300, -200),
                       information(400, 400, 0, 820));
  const std::vector<reference::PoseEdgeRef> edges = reference::pose_edges_of(g);
  const std::vector<reference::PoseRef> odometry = poses_of(g);
  const Solve s = optimise(g, 700);
  ASSERT_TRUE(g.converged());
  EXPECT_TRUE(s.work_counted);
  EXPECT_LE(s.max_work, 700u);
  EXPECT_GT(g.stats().relinearisations, 1u);
  const std::vector<reference::PoseRef> gn =
      reference::pose_graph_gauss_newton(edges, odometry, 1.0, 1.0, 50);
  const Difference d = largest_difference(g, gn);
  const double mine = objective(edges, poses_of(g));
  const double best = objective(edges, gn);
  test::log_figure("pose_graph refine vs double Gauss-Newton, position (m):", d.position);
  test::log_figure("pose_graph refine vs double Gauss-Newton, heading (rad):", d.heading);
  test::log_figure("pose_graph refine: objective fixed point / double:", mine / best);
  test::log_figure("pose_graph refine: relinearisations:", g.stats().relinearisations);
  EXPECT_LT(d.position, 1e-5) << "stated bound: 10 micrometres";
  EXPECT_LT(d.heading, 1e-6) << "stated bound: 1e-6 rad";
  EXPECT_LT(mine, best * (1 + 1e-6));
  // LAGO alone is measurably worse on the same problem (the finish does something).
  static LoopStorage lago_storage;
  PoseGraph lago = configured(lago_storage);
  add_anisotropic_loop(lago, information(2500, 2500, 0, 3283, 300, -200),
                       information(400, 400, 0, 820));
  optimise(lago, 1000);
  EXPECT_GT(objective(edges, poses_of(lago)), best * (1 + 1e-4));
}

// The nonlinear finish with the tree preconditioner (its levers across the closures' tree
// edges): Gauss-Newton in fixed point against Gauss-Newton in double, to the bounds of the
// chain's test below.
TEST(PoseGraph, TreePreconditionedRefineReachesTheDoublePrecisionOptimum) {
  static LoopStorage storage;
  static PoseGraphRefineStorage<512> refine;
  static PoseGraphTreeStorage<512> tree;
  PoseGraphConfig c;
  c.refine_restarts = 20;
  c.tolerance_xy = Q31_32::from_ratio(1, 1000000);
  c.tree_preconditioner = true;
  PoseGraphBuffers b = storage.buffers();
  b.refine = refine.slots();
  b.tree = tree.slots();
  PoseGraph g;
  g.enable_refine();
  ASSERT_EQ(g.configure(c, b), Status::kOk);
  add_anisotropic_loop(g, information(2500, 2500, 0, 3283, 300, -200),
                       information(4000, 4000, 0, 5000, -100, 200));
  ASSERT_EQ(tree.slot[456].parent, 8u);
  const std::vector<reference::PoseEdgeRef> edges = reference::pose_edges_of(g);
  const std::vector<reference::PoseRef> odometry = poses_of(g);
  optimise(g, 700);
  ASSERT_TRUE(g.converged());
  const std::vector<reference::PoseRef> gn =
      reference::pose_graph_gauss_newton(edges, odometry, 1.0, 1.0, 50);
  const Difference d = largest_difference(g, gn);
  test::log_figure("pose_graph tree refine vs double Gauss-Newton, position (m):", d.position);
  test::log_figure("pose_graph tree refine vs double Gauss-Newton, heading (rad):", d.heading);
  EXPECT_LT(d.position, 1e-5) << "stated bound: 10 micrometres";
  EXPECT_LT(d.heading, 1e-6) << "stated bound: 1e-6 rad";
  EXPECT_LT(objective(edges, poses_of(g)), objective(edges, gn) * (1 + 1e-6));
}

// ---- 10 000 poses over more than 100 m (issue 35) ------------------------------------------
// A robot on a grid of streets 120 m square (blocks of 20 m, steps of 0.5 m, a random turn at
// each crossing) for 10 000 poses, 5 km; its odometry 1 % long on average with 0.3 degrees of
// heading noise a step (drift of tens of metres). Every tenth pose that passes within 0.5 m of
// a pose more than 100 poses older, heading within 30 degrees, closes to it with the true
// relative pose. Fed as the outside user feeds it (add_node with the odometry, the
// closures, optimise_step to convergence; and place by place at the explorer's 2 000 units a
// place); the result against the double-precision LAGO of the same stored problem and against
// the truth. Host only (1.4 MB of graph).
constexpr uint32_t kCityNodes = 10000;

struct City {
  std::vector<Pose2> truth;
  std::vector<Pose2> odometry;
  std::vector<std::pair<uint32_t, uint32_t>> closures;  // (older, newer)
};

uint64_t city_random(uint64_t* state) {
  *state = *state * 6364136223846793005ull + 1442695040888963407ull;
  return *state >> 33;
}
double city_gauss(uint64_t* state) {  // sum of 12 uniforms - 6
  double s = 0.0;
  for (int i = 0; i < 12; ++i) s += static_cast<double>(city_random(state) % 1000000) / 1e6;
  return s - 6.0;
}
Pose2 pose_of(double x, double y, double theta) {
  return Pose2{Q31_32::from_raw(static_cast<int64_t>(x * kMetre)),
               Q31_32::from_raw(static_cast<int64_t>(y * kMetre)),
               Angle{static_cast<uint32_t>(static_cast<int64_t>(
                   wrap(theta) / (2 * test::kPi) * kBamPerTurn))}};
}

const City& the_city() {
  static City city;
  if (!city.truth.empty()) return city;
  uint64_t rng = 35;
  double x = 0, y = 0, th = 0;         // truth: on the grid, heading a multiple of 90 deg
  double ox = 0, oy = 0, oth = 0;      // odometry
  int dir = 0;                         // 0 +x, 1 +y, 2 -x, 3 -y
  for (uint32_t k = 0; k < kCityNodes; ++k) {
    city.truth.push_back(pose_of(x, y, th));
    city.odometry.push_back(pose_of(ox, oy, oth));
    // At a crossing, turn left, right or go on, staying inside [0, 120]^2.
    const double gx = x / 20.0, gy = y / 20.0;
    if (std::fabs(gx - std::round(gx)) < 1e-6 && std::fabs(gy - std::round(gy)) < 1e-6) {
      for (int tries = 0; tries < 8; ++tries) {
        const int turn = static_cast<int>(city_random(&rng) % 3) - 1;
        const int nd = (dir + turn + 4) % 4;
        const double nx = x + (nd == 0 ? 20 : nd == 2 ? -20 : 0);
        const double ny = y + (nd == 1 ? 20 : nd == 3 ? -20 : 0);
        if (nx >= -1e-6 && nx <= 120 + 1e-6 && ny >= -1e-6 && ny <= 120 + 1e-6) {
          dir = nd;
          break;
        }
        if (tries == 7) dir = (dir + 2) % 4;
      }
    }
    const double new_th = dir * test::kPi / 2;
    double dth = wrap(new_th - th);
    const double step = 0.5;
    x += step * test::ref_cos(new_th);
    y += step * test::ref_sin(new_th);
    x = std::round(x * 2) / 2;
    y = std::round(y * 2) / 2;
    th = new_th;
    // Odometry of the same motion: 1 % long, heading noise 0.3 degrees.
    const double o_step = step * 1.01 * (1 + 0.002 * city_gauss(&rng));
    const double o_dth = dth + 0.3 * test::kPi / 180 * city_gauss(&rng);
    oth += o_dth;
    ox += o_step * test::ref_cos(oth);
    oy += o_step * test::ref_sin(oth);
  }
  for (uint32_t j = 100; j < kCityNodes; j += 10) {
    const double jx = metres(city.truth[j].x), jy = metres(city.truth[j].y);
    uint32_t best = kCityNodes;
    double best_d = 0.5;
    for (uint32_t i = 0; i + 100 < j; ++i) {
      const double d = std::hypot(metres(city.truth[i].x) - jx, metres(city.truth[i].y) - jy);
      const double dh = abs_d(radians(Angle{city.truth[j].heading.bam - city.truth[i].heading.bam}));
      if (d < best_d && dh < 30 * test::kPi / 180) {
        best_d = d;
        best = i;
      }
    }
    if (best < kCityNodes) city.closures.push_back({best, j});
  }
  return city;
}

// Position RMSE against the truth after the best rigid 2-D alignment.
double aligned_rmse(const std::vector<reference::PoseRef>& est, const std::vector<Pose2>& truth) {
  const size_t n = est.size();
  const double count = static_cast<double>(n);
  double ex = 0, ey = 0, tx = 0, ty = 0;
  for (size_t i = 0; i < n; ++i) {
    ex += est[i].x;
    ey += est[i].y;
    tx += metres(truth[i].x);
    ty += metres(truth[i].y);
  }
  ex /= count, ey /= count, tx /= count, ty /= count;
  double sc = 0, ss = 0;
  for (size_t i = 0; i < n; ++i) {
    const double ax = est[i].x - ex, ay = est[i].y - ey;
    const double bx = metres(truth[i].x) - tx, by = metres(truth[i].y) - ty;
    sc += ax * bx + ay * by;
    ss += ax * by - ay * bx;
  }
  const double phi = std::atan2(ss, sc), c = std::cos(phi), s = std::sin(phi);
  double sum = 0;
  for (size_t i = 0; i < n; ++i) {
    const double ax = est[i].x - ex, ay = est[i].y - ey;
    const double dx = c * ax - s * ay - (metres(truth[i].x) - tx);
    const double dy = s * ax + c * ay - (metres(truth[i].y) - ty);
    sum += dx * dx + dy * dy;
  }
  return std::sqrt(sum / count);
}

using CityStorage = PoseGraphStorage<kCityNodes, kCityNodes + 2000>;

void feed_city(PoseGraph& g, uint32_t budget_per_place) {
  const City& city = the_city();
  size_t next = 0;
  PoseGraphProgress p;
  for (uint32_t k = 0; k < kCityNodes; ++k) {
    ASSERT_TRUE(g.add_node(city.odometry[k], k).ok()) << k;
    while (next < city.closures.size() && city.closures[next].second == k) {
      const auto [i, j] = city.closures[next++];
      ASSERT_EQ(g.add_loop_closure(i, j, relative_pose(city.truth[i], city.truth[j]),
                                   kClosureInfo),
                Status::kOk);
    }
    if (budget_per_place > 0) {
      ASSERT_EQ(g.optimise_step(budget_per_place, &p), Status::kOk);
    }
  }
}

TEST(PoseGraph, TenThousandPosesOverAHundredMetres) {
#if defined(__SANITIZE_ADDRESS__)
  // ~90 s of CPU under ASan for code paths the smaller tests above take too (the rescale,
  // the chain passes, the stall rule); the plain host build runs it (~8 s).
  GTEST_SKIP() << "too slow under the sanitizers";
#endif
  const City& city = the_city();
  ASSERT_GE(city.closures.size(), 100u);
  double extent = 0.0;
  for (const Pose2& t : city.truth) extent = std::max(extent, std::max(metres(t.x), metres(t.y)));
  test::log_figure("pose_graph city: extent (m):", extent);
  test::log_figure("pose_graph city: closures:", static_cast<double>(city.closures.size()));
  EXPECT_GE(extent, 100.0);
  PoseGraphConfig c;
  c.tolerance_xy = Q31_32::from_ratio(1, 1000);  // 1 mm
  c.tolerance_heading = Angle{1u << 12};          // 6e-6 rad
  c.max_iterations = 1000;
  c.max_restarts = 30;
  static CityStorage storage;
  for (const uint32_t per_place : {0u, 2000u}) {
    PoseGraph g;
    ASSERT_EQ(g.configure(c, storage.buffers()), Status::kOk);
    feed_city(g, per_place);
    std::vector<reference::PoseRef> dead = poses_of(g);
    const Solve s = optimise(g, 100000);
    ASSERT_TRUE(g.converged()) << per_place;
    ASSERT_FALSE(g.failed());
    EXPECT_TRUE(s.work_counted);
    const Pose2 anchor = g.pose(0).value();
    const std::vector<reference::PoseRef> ref = reference::pose_graph_linear_iterative(
        static_cast<int>(g.node_count()), reference::pose_edges_of(g),
        reference::PoseRef{metres(anchor.x), metres(anchor.y), radians(anchor.heading)});
    const double ate_dead = aligned_rmse(dead, city.truth);
    const double ate_core = aligned_rmse(poses_of(g), city.truth);
    const double ate_ref = aligned_rmse(ref, city.truth);
    const Difference d = largest_difference(g, ref);
    const double units = static_cast<double>(g.stats().node_visits + g.stats().closure_visits +
                                             g.stats().scalar_steps);
    test::log_figure(per_place == 0 ? "pose_graph city batch: ATE dead reckoning (m):"
                                    : "pose_graph city 2000/place: ATE dead reckoning (m):",
                     ate_dead);
    test::log_figure(per_place == 0 ? "pose_graph city batch: ATE fixed point (m):"
                                    : "pose_graph city 2000/place: ATE fixed point (m):",
                     ate_core);
    test::log_figure("pose_graph city: ATE double LAGO (m):", ate_ref);
    test::log_figure("pose_graph city: fixed point vs double LAGO, position (m):", d.position);
    test::log_figure("pose_graph city: fixed point vs double LAGO, heading (rad):", d.heading);
    test::log_figure("pose_graph city: rescales:", g.stats().rescales);
    test::log_figure("pose_graph city: coarsest scale (bits):", g.stats().max_scale);
    test::log_figure("pose_graph city: work units:", units);
    test::log_figure("pose_graph city: stalls:", g.stats().stalls);
    EXPECT_GT(ate_dead, 1.0);
    EXPECT_LT(ate_core, ate_ref + 0.01) << "the issue's check: within the exact LAGO's + 1 cm";
    EXPECT_LT(d.position, 0.01);
  }
}
#endif

}  // namespace
}  // namespace seqslam
