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

#if defined(SEQSLAM_TEST_GTEST) && __has_include("reference.h")
// Host builds that link seqslam_reference also check against tools/reference.
#include <algorithm>
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
static_assert(LoopStorage::kBytes == 55360, "512 nodes and 600 edges: 55 360 bytes");
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
#endif

}  // namespace
}  // namespace seqslam
