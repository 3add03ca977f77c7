#include "bench_pose_graph.h"

#include "seqslam/board/board.h"
#include "seqslam/fixmath.h"
#include "seqslam/pose_graph.h"

namespace seqslam::bench {

namespace {

// The loop of tests/unit/test_pose_graph.cpp: 20 m straights of 100 steps of 0.2 m and
// quarter turns of 12 steps, 448 steps a lap, a node per step and 9 more; odometry 0.3 %
// long with a heading bias of 8e-4 rad/m (1.37 m off after the lap; stepped with compose(),
// so rounding differs from the test by nanometres); closures 0-448, 4-452,
// 8-456 measured from the truth.
constexpr uint32_t kLap = 448;
constexpr uint32_t kNodes = kLap + 9;
constexpr uint32_t kClosureA[3] = {0, 4, 8};

// All in external memory: the bench's RAM is nearly full. An all-zero PoseGraph is a valid
// unconfigured one, so the zero-filled (never loaded) region suits it.
SEQSLAM_BOARD_EXTMEM PoseGraphStorage<512, 600> g_storage;
SEQSLAM_BOARD_EXTMEM Pose2 g_truth[kNodes];
SEQSLAM_BOARD_EXTMEM Pose2 g_odometry[kNodes];
SEQSLAM_BOARD_EXTMEM PoseGraph g_graph;

// One step of arc length ds turning by dtheta (midpoint rule), as a relative pose: the
// heading half-way round times ds. Built with the core's compose() to keep the bench small.
RelativePose2 arc(Q31_32 ds, uint32_t dtheta) {
  const Pose2 p = compose(Pose2{Q31_32{}, Q31_32{}, Angle{dtheta / 2}},
                          RelativePose2{ds, Q31_32{}, Angle{dtheta - dtheta / 2}});
  return RelativePose2{p.x, p.y, p.heading};
}

void make_loop() {
  const Q31_32 ds = Q31_32::from_ratio(2, 10);
  const Q31_32 ds_odo = Q31_32::from_ratio(2006, 10000);
  const uint32_t turn = (uint32_t{1} << 30) / 12;
  const uint32_t bias = 109370;
  const RelativePose2 straight{ds, Q31_32{}, Angle{}};
  const RelativePose2 corner = arc(ds, turn);
  const RelativePose2 straight_odo = arc(ds_odo, bias);
  const RelativePose2 corner_odo = arc(ds_odo, turn + turn * 3 / 1000 + bias);
  g_truth[0] = Pose2{Q31_32::from_int(2), Q31_32::from_int(-1), Angle::from_degrees(10)};
  g_odometry[0] = g_truth[0];
  for (uint32_t k = 1; k < kNodes; ++k) {
    const bool turning = ((k - 1) % kLap % 112) >= 100;
    g_truth[k] = compose(g_truth[k - 1], turning ? corner : straight);
    g_odometry[k] = compose(g_odometry[k - 1], turning ? corner_odo : straight_odo);
  }
}

void print(const char* s) {
  board::console_print(s);
}
void print_u(uint64_t v) {
  board::console_print_u64(v);
}
void print_ratio(uint64_t v, uint64_t d) {  // v / d with one decimal
  const uint64_t q = (v * 10 + d / 2) / d;
  print_u(q / 10);
  print(".");
  print_u(q % 10);
}

}  // namespace

bool run_pose_graph(uint32_t slice_units, PoseGraphFigures* f) {
  make_loop();
  if (g_graph.configure(PoseGraphConfig{}, g_storage.buffers()) != Status::kOk) return false;
  f->nodes = kNodes;
  f->closures = 3;
  f->slice_units = slice_units;
  f->storage_bytes = static_cast<uint32_t>(decltype(g_storage)::kBytes);
  f->object_bytes = sizeof(PoseGraph);
  uint64_t node_total = 0;
  uint64_t closure_total = 0;
  for (uint32_t k = 0; k < kNodes; ++k) {
    uint64_t t0 = board::instructions_retired();
    if (!g_graph.add_node(g_odometry[k], k).ok()) return false;
    node_total += board::instructions_retired() - t0;
    for (uint32_t a : kClosureA) {
      if (a + kLap != k) continue;
      const RelativePose2 m = relative_pose(g_truth[a], g_truth[k]);
      const EdgeInformation info{UQ16_16::from_int(20), UQ16_16::from_int(20)};
      t0 = board::instructions_retired();
      if (g_graph.add_loop_closure(a, k, m, info) != Status::kOk) return false;
      closure_total += board::instructions_retired() - t0;
    }
  }
  f->add_node = node_total / kNodes;
  f->add_closure = closure_total / 3;
  f->slices = 0;
  f->slice_max = 0;
  f->total = 0;
  PoseGraphProgress p;
  do {
    const uint64_t t0 = board::instructions_retired();
    if (g_graph.optimise_step(slice_units, &p) != Status::kOk) return false;
    const uint64_t t = board::instructions_retired() - t0;
    f->total += t;
    f->slice_max = t > f->slice_max ? t : f->slice_max;
    ++f->slices;
  } while (!p.converged && f->slices < 100000);
  if (!p.converged) return false;
  f->slice_mean = f->total / f->slices;
  const PoseGraphStats& s = g_graph.stats();
  f->units = s.node_visits + s.closure_visits + s.scalar_steps;
  f->iterations = s.iterations;
  // RMSE against the truth in micrometres (the differences are below a metre: no overflow).
  uint64_t sum = 0;
  for (uint32_t k = 0; k < kNodes; ++k) {
    const Pose2 e = g_graph.pose(k).value();
    const int64_t dx = ((e.x.raw() - g_truth[k].x.raw()) * 1000000) >> 32;
    const int64_t dy = ((e.y.raw() - g_truth[k].y.raw()) * 1000000) >> 32;
    sum += static_cast<uint64_t>(dx * dx + dy * dy);
  }
  f->rmse_um = isqrt64(sum / kNodes);
  return true;
}

void print_pose_graph(const PoseGraphFigures& f) {
  print("pose graph, ");
  print_u(f.nodes);
  print("-node loop with ");
  print_u(f.closures);
  print(" closures: optimise_step slices of ");
  print_u(f.slice_units);
  print(" units ");
  print_u(f.slice_mean);
  print(" instructions (max ");
  print_u(f.slice_max);
  print(", ");
  print_ratio(f.total, f.units);
  print("/unit); converged after ");
  print_u(f.slices);
  print(" slices, ");
  print_u(f.units);
  print(" units, ");
  print_u(f.iterations);
  print(" CG iterations, ");
  print_u(f.total);
  print(" instructions; add_node ");
  print_u(f.add_node);
  print(", add_loop_closure ");
  print_u(f.add_closure);
  print("; RMSE to truth ");
  print_u(static_cast<uint64_t>(f.rmse_um));
  print(" um; storage 512 nodes / 600 edges ");
  print_u(f.storage_bytes);
  print(" bytes\n");
}

void print_pose_graph_json(const PoseGraphFigures& f) {
  print("{\"nodes\": ");
  print_u(f.nodes);
  print(", \"closures\": ");
  print_u(f.closures);
  print(", \"slice_units\": ");
  print_u(f.slice_units);
  print(", \"instructions_per_slice_mean\": ");
  print_u(f.slice_mean);
  print(", \"instructions_per_slice_max\": ");
  print_u(f.slice_max);
  print(", \"slices_to_converge\": ");
  print_u(f.slices);
  print(", \"units_to_converge\": ");
  print_u(f.units);
  print(", \"cg_iterations\": ");
  print_u(f.iterations);
  print(", \"instructions_to_converge\": ");
  print_u(f.total);
  print(", \"add_node_instructions\": ");
  print_u(f.add_node);
  print(", \"add_loop_closure_instructions\": ");
  print_u(f.add_closure);
  print(", \"rmse_um\": ");
  print_u(static_cast<uint64_t>(f.rmse_um));
  print(", \"storage_bytes_512_nodes_600_edges\": ");
  print_u(f.storage_bytes);
  print(", \"object_bytes\": ");
  print_u(f.object_bytes);
}

}  // namespace seqslam::bench
