#include "seqslam/pose_graph.h"

namespace seqslam {

namespace {

constexpr int64_t kInt64Max = 9223372036854775807;
constexpr int64_t kInt64Min = -kInt64Max - 1;

int64_t add_sat(int64_t a, int64_t b) {
  int64_t r = 0;
  if (__builtin_add_overflow(a, b, &r)) return a < 0 ? kInt64Min : kInt64Max;
  return r;
}
int64_t sub_sat(int64_t a, int64_t b) {
  int64_t r = 0;
  if (__builtin_sub_overflow(a, b, &r)) return a < 0 ? kInt64Min : kInt64Max;
  return r;
}

// round(v * m / 2^shift), ties away from zero, saturating; shift 0..127. The inner operation
// of every pass, so it avoids the general 128-bit routines: |v| m is a 96-bit value formed
// from two 32x32-bit products (RV32's mul/mulhu pairs), kept as hi * 2^32 + lo32, and shifted
// in two 64-bit words.
int64_t mul_u32_shift(int64_t v, uint32_t m, int shift) {
  const bool negative = v < 0;
  const uint64_t a = negative ? 0 - static_cast<uint64_t>(v) : static_cast<uint64_t>(v);
  const uint64_t low = (a & 0xFFFFFFFFu) * m;
  const uint64_t hi = (a >> 32) * m + (low >> 32);  // (a >> 32) <= 2^31: no overflow
  const uint64_t lo32 = low & 0xFFFFFFFFu;
  uint64_t q = 0;
  uint64_t half = 0;     // bit shift - 1 of the product: round half away from zero
  if (m == 0) return 0;  // beta = 0 after a restart
  if (shift == 0) {
    if ((hi >> 31) != 0) return negative ? kInt64Min : kInt64Max;
    q = (hi << 32) | lo32;
  } else if (shift < 32) {
    if ((hi >> (31 + shift)) != 0) return negative ? kInt64Min : kInt64Max;  // >= 2^63
    q = (hi << (32 - shift)) | (lo32 >> shift);
    half = (lo32 >> (shift - 1)) & 1u;
  } else if (shift < 96) {
    q = shift == 32 ? hi : hi >> (shift - 32);
    half = shift == 32 ? (lo32 >> 31) & 1u : (hi >> (shift - 33)) & 1u;
  }
  q += half;
  if (q > static_cast<uint64_t>(kInt64Max)) return negative ? kInt64Min : kInt64Max;
  return negative ? -static_cast<int64_t>(q) : static_cast<int64_t>(q);
}

// acc += a * b, exact (the 64x64-bit product from four 32x32-bit ones).
void multiply_add(Int128* acc, int64_t a, int64_t b) {
  const uint64_t ua = a < 0 ? 0 - static_cast<uint64_t>(a) : static_cast<uint64_t>(a);
  const uint64_t ub = b < 0 ? 0 - static_cast<uint64_t>(b) : static_cast<uint64_t>(b);
  const Int128 p = Int128::mul_u64(ua, ub);
  *acc = (a < 0) != (b < 0) ? *acc - p : *acc + p;
}

// Weight (UQ16.16) times a vector element.
int64_t weigh(int64_t v, uint32_t w) {
  return mul_u32_shift(v, w, 16);
}

// A vector element times a sine or cosine (Q1.30, |c| <= 2^30).
int64_t mul_q30(int64_t v, Q1_30 c) {
  const int32_t raw = c.raw();
  const int64_t m =
      mul_u32_shift(v, raw < 0 ? 0u - static_cast<uint32_t>(raw) : static_cast<uint32_t>(raw), 30);
  return raw < 0 ? -m : m;
}

int bit_length(Int128 v) {
  if (v.high64() != 0) return 128 - __builtin_clzll(v.high64());
  if (v.low64() == 0) return 0;
  return 64 - __builtin_clzll(v.low64());
}

// Rotation of an edge's Q7.24 step by a heading, into Q31.32: round((c dx - s dy) / 2^22) etc.
// Shared by add_node (placing a new node) and the residuals, so a freshly added leaf has a
// residual of exactly zero.
int64_t rotate_x(SinCos sc, const PoseGraphEdge& e) {
  const int64_t v = static_cast<int64_t>(sc.cos.raw()) * e.dx.raw() -
                    static_cast<int64_t>(sc.sin.raw()) * e.dy.raw();
  return (v + (int64_t{1} << 21)) >> 22;
}
int64_t rotate_y(SinCos sc, const PoseGraphEdge& e) {
  const int64_t v = static_cast<int64_t>(sc.sin.raw()) * e.dx.raw() +
                    static_cast<int64_t>(sc.cos.raw()) * e.dy.raw();
  return (v + (int64_t{1} << 21)) >> 22;
}

// round(v / 2^shift) (ties up), shift 1..62, without the overflow of adding the half first.
int64_t shift_round_i64(int64_t v, int shift) {
  return (v >> shift) + ((v >> (shift - 1)) & 1);
}

// Q31.32 to Q7.24 (rounded); false if it does not fit.
bool to_q7_24(Q31_32 v, Q7_24* out) {
  const Int128 r = detail::shift_round(Int128(v.raw()), 8);
  if (r < Int128(-2147483647 - 1) || r > Int128(2147483647)) return false;
  *out = Q7_24::from_raw(static_cast<int32_t>(r.low64_signed()));
  return true;
}

// 1 / info in UQ8.24, rounded up, so that the chain preconditioner never exceeds the chain's
// part of the system matrix (the stopping bound needs M <= L). Odometry steps are below
// 128 * sqrt(2) m, so info >= 1/182 and the variance fits; 24 fraction bits keep the
// preconditioner within 2^-24 of the chain, where UQ16.16 cost an extra CG iteration per stage.
uint32_t variance_of(uint32_t info_raw) {
  const uint64_t one = uint64_t{1} << 40;
  return static_cast<uint32_t>((one + info_raw - 1) / info_raw);
}

// Variance (UQ8.24) times a vector element.
int64_t spread(int64_t v, uint32_t var) {
  return mul_u32_shift(v, var, 24);
}

}  // namespace

RelativePose2 relative_pose(const Pose2& from, const Pose2& to) {
  const Q31_32 wx = to.x - from.x;
  const Q31_32 wy = to.y - from.y;
  const SinCos sc = sincos(from.heading);
  RelativePose2 r;
  r.dx = mul_sat<Q31_32>(wx, sc.cos) + mul_sat<Q31_32>(wy, sc.sin);
  r.dy = mul_sat<Q31_32>(wy, sc.cos) - mul_sat<Q31_32>(wx, sc.sin);
  r.dtheta = Angle{to.heading.bam - from.heading.bam};
  return r;
}

Pose2 compose(const Pose2& from, const RelativePose2& rel) {
  const SinCos sc = sincos(from.heading);
  Pose2 p;
  p.x = from.x + mul_sat<Q31_32>(rel.dx, sc.cos) - mul_sat<Q31_32>(rel.dy, sc.sin);
  p.y = from.y + mul_sat<Q31_32>(rel.dx, sc.sin) + mul_sat<Q31_32>(rel.dy, sc.cos);
  p.heading = Angle{from.heading.bam + rel.dtheta.bam};
  return p;
}

Status PoseGraph::configure(const PoseGraphConfig& c, const PoseGraphBuffers& b) {
  if (b.nodes.empty() || b.nodes.data() == nullptr || b.nodes.size() > kMaxPoseGraphNodes ||
      b.edges.size() > kMaxPoseGraphEdges || (!b.edges.empty() && b.edges.data() == nullptr) ||
      b.solver.size() < b.nodes.size() || b.solver.data() == nullptr) {
    return Status::kInvalidArgument;
  }
  if (c.min_travel.raw() < (int64_t{1} << 16) || c.min_travel.raw() > (int64_t{1} << 32) ||
      c.tolerance_xy.raw() < 1 || c.tolerance_xy.raw() > (int64_t{1} << 24) ||
      c.tolerance_heading.bam < 1 || c.tolerance_heading.bam >= (uint32_t{1} << 24) ||
      c.extra_iterations < 1 || c.extra_iterations > 1000 || c.max_restarts < 1 ||
      c.max_restarts > 1000 || c.closure_lateral.raw() > UQ16_16::from_int(1).raw()) {
    return Status::kInvalidArgument;
  }
  config_ = c;
  buffers_ = b;
  node_capacity_ = static_cast<uint32_t>(b.nodes.size());
  edge_capacity_ = static_cast<uint32_t>(b.edges.size());
  configured_ = true;
  reset();
  return Status::kOk;
}

void PoseGraph::reset() {
  nodes_ = 0;
  closures_ = 0;
  last_odometry_ = Pose2{};
  var_sum_ = 0;
  stats_ = PoseGraphStats{};
  stage_ = PoseGraphStage::kConverged;
  phase_ = Phase::kResidualChain;
  index_ = 0;
  updating_ = false;
  solve_nodes_ = 0;
  pending_ = PoseGraphStage::kConverged;
}

// A restored state (state()): its counts fit the buffers ...
bool PoseGraph::counts_fit() const {
  if (!configured_ || nodes_ > node_capacity_) return false;
  const uint32_t chain = nodes_ > 0 ? nodes_ - 1 : 0;
  return chain <= edge_capacity_ && closures_ <= edge_capacity_ - chain;
}

// ... its edges join its nodes, and the optimiser's position lies inside the current pass
// (run_phase() counts down from the pass's end).
bool PoseGraph::state_valid() const {
  for (uint32_t i = 0; i < edge_count(); ++i) {
    const PoseGraphEdge e = edge(i).value();
    if (e.from >= nodes_ || e.to >= nodes_) return false;
  }
  if (solve_nodes_ > nodes_) return false;
  if (stage_ == PoseGraphStage::kConverged) return true;
  if (solve_nodes_ == 0) return false;
  uint32_t end = 0;
  switch (phase_) {
    case Phase::kResidualChain:
    case Phase::kForward:
    case Phase::kDirectionChain:
      end = solve_nodes_;
      break;
    case Phase::kBackward:
      end = solve_nodes_ - 1;
      break;
    case Phase::kResidualClosures:
    case Phase::kDirectionClosures:
      end = closures_;
      break;
    case Phase::kLeaves:
      end = nodes_;
      break;
    case Phase::kCheck:
    case Phase::kStepLength:
      return true;
  }
  return index_ <= end;
}

Result<uint32_t> PoseGraph::add_node(const Pose2& odometry, uint32_t place) {
  if (!configured_) return Status::kFailedPrecondition;
  if (nodes_ >= node_capacity_) return Status::kResourceExhausted;
  PoseGraphSolverSlot& slot = buffers_.solver[nodes_];
  PoseGraphNode& node = buffers_.nodes[nodes_];
  if (nodes_ == 0) {
    node = PoseGraphNode{odometry.x, odometry.y, odometry.heading, place};
    slot = PoseGraphSolverSlot{};  // the anchor: never part of a system
    last_odometry_ = odometry;
    nodes_ = 1;
    return uint32_t{0};
  }
  if (edge_count() >= edge_capacity_) return Status::kResourceExhausted;
  const RelativePose2 step = relative_pose(last_odometry_, odometry);
  PoseGraphEdge e{};
  if (!to_q7_24(step.dx, &e.dx) || !to_q7_24(step.dy, &e.dy)) return Status::kOutOfRange;
  e.from = static_cast<uint16_t>(nodes_ - 1);
  e.to = static_cast<uint16_t>(nodes_);
  e.dtheta = step.dtheta;
  // Information 1 m / max(step, min_travel): variance grows with the distance driven.
  const int64_t dx = e.dx.raw();
  const int64_t dy = e.dy.raw();
  // The straight-line step, Q7.24 metres.
  uint64_t travel = isqrt64(static_cast<uint64_t>(dx * dx) + static_cast<uint64_t>(dy * dy));
  const uint64_t floor = (static_cast<uint64_t>(config_.min_travel.raw()) + 128) >> 8;
  if (travel < floor) travel = floor;
  uint64_t info = ((uint64_t{1} << 40) + travel / 2) / travel;  // UQ16.16 of 1 m / travel
  if (info > 0xFFFFFFFFu) info = 0xFFFFFFFFu;
  e.info_xy = UQ16_16::from_raw(static_cast<uint32_t>(info));
  e.info_heading = e.info_xy;
  buffers_.edges[nodes_ - 1] = e;

  node.place = place;
  // One chain variance serves both stages: odometry edges have equal information in both.
  slot = PoseGraphSolverSlot{};
  slot.var = variance_of(e.info_xy.raw());
  // The new leaf at its predecessor's estimate composed with the step: the optimum of both
  // stages for a leaf, so a converged graph stays converged.
  place_leaf(nodes_);
  var_sum_ += slot.var;
  last_odometry_ = odometry;
  const uint32_t index = nodes_++;
  // A stage in progress goes on without it: the new node is a leaf outside the system being
  // solved, placed again from its predecessor when the stage ends (kLeaves), which is its
  // optimum. (Restarting the stage instead would throw its work away at every place: with a
  // node every slice and slices shorter than an iteration, the solve would never advance.)
  return index;
}

Status PoseGraph::add_loop_closure(uint32_t a, uint32_t b, const RelativePose2& b_from_a,
                                   EdgeInformation info) {
  if (!configured_) return Status::kFailedPrecondition;
  if (a >= nodes_ || b >= nodes_) return Status::kOutOfRange;
  if (a == b || (info.xy.raw() == 0 && info.heading.raw() == 0)) return Status::kInvalidArgument;
  PoseGraphEdge e{};
  if (!to_q7_24(b_from_a.dx, &e.dx) || !to_q7_24(b_from_a.dy, &e.dy)) {
    return Status::kOutOfRange;
  }
  if (edge_count() >= edge_capacity_) return Status::kResourceExhausted;
  e.from = static_cast<uint16_t>(a);
  e.to = static_cast<uint16_t>(b);
  e.dtheta = b_from_a.dtheta;
  e.info_xy = info.xy;
  e.info_heading = info.heading;
  buffers_.edges[edge_capacity_ - 1 - closures_] = e;
  ++closures_;
  request_restart(PoseGraphStage::kHeadings);
  return Status::kOk;
}

Result<Pose2> PoseGraph::pose(uint32_t i) const {
  if (i >= nodes_) return Status::kOutOfRange;
  const PoseGraphNode& n = buffers_.nodes[i];
  return Pose2{n.x, n.y, heading(i)};
}

Result<uint32_t> PoseGraph::place(uint32_t i) const {
  if (i >= nodes_) return Status::kOutOfRange;
  return buffers_.nodes[i].place;
}

Result<PoseGraphEdge> PoseGraph::edge(uint32_t i) const {
  const uint32_t chain = nodes_ > 0 ? nodes_ - 1 : 0;
  if (i < chain) return buffers_.edges[i];
  if (i - chain < closures_) return closure(i - chain);
  return Status::kOutOfRange;
}

Status PoseGraph::optimise_step(uint32_t budget, PoseGraphProgress* out) {
  if (!configured_) return Status::kFailedPrecondition;
  if (budget == 0 || out == nullptr) return Status::kInvalidArgument;
  uint32_t done = 0;
  while (done < budget && stage_ != PoseGraphStage::kConverged) {
    done += run_phase(budget - done);
  }
  out->work = done;
  out->converged = stage_ == PoseGraphStage::kConverged;
  out->stage = stage_;
  return Status::kOk;
}

// ---- Stage-dependent views ----------------------------------------------------------------

PoseGraph::Vec PoseGraph::edge_residual(const PoseGraphEdge& e) const {
  const PoseGraphNode& a = buffers_.nodes[e.from];
  const PoseGraphNode& b = buffers_.nodes[e.to];
  if (stage_ == PoseGraphStage::kHeadings) {
    // Modulo a full turn (the unwrapping against the current estimate), in Q0.64 turns, then
    // into the stage's units of 2^-8 binary-angle units.
    const uint64_t r = (static_cast<uint64_t>(e.dtheta.bam) << 32) - (fine(e.to) - fine(e.from));
    return Vec{{shift_round_i64(static_cast<int64_t>(r), 24), 0}};
  }
  const SinCos sc = sincos(heading(e.from));
  return Vec{{sub_sat(rotate_x(sc, e), sub_sat(b.x.raw(), a.x.raw())),
              sub_sat(rotate_y(sc, e), sub_sat(b.y.raw(), a.y.raw()))}};
}

// W_e v. Headings and odometry edges: the edge's weight times each component. A loop closure
// in the position stage: W = f w I + (1 - f) w u u^T with u the unit vector along its `from`
// node's heading (R diag(w, f w) R^T written so that f = 1 costs no rotation).
PoseGraph::Vec PoseGraph::weigh_edge(const PoseGraphEdge& e, bool closure, Vec v) const {
  if (stage_ == PoseGraphStage::kHeadings) return Vec{{weigh(v.v[0], e.info_heading.raw()), 0}};
  const uint32_t w = e.info_xy.raw();
  if (!closure || config_.closure_lateral.raw() == UQ16_16::from_int(1).raw()) {
    return Vec{{weigh(v.v[0], w), weigh(v.v[1], w)}};
  }
  const uint32_t across = static_cast<uint32_t>(
      (static_cast<uint64_t>(w) * config_.closure_lateral.raw() + 0x8000u) >> 16);
  Vec t{{weigh(v.v[0], across), weigh(v.v[1], across)}};
  const SinCos sc = sincos(heading(e.from));
  const int64_t along = add_sat(mul_q30(v.v[0], sc.cos), mul_q30(v.v[1], sc.sin));
  const int64_t k = weigh(along, w - across);
  t.v[0] = add_sat(t.v[0], mul_q30(k, sc.cos));
  t.v[1] = add_sat(t.v[1], mul_q30(k, sc.sin));
  return t;
}

PoseGraph::Vec PoseGraph::difference(uint32_t to, uint32_t from) const {
  const PoseGraphSolverSlot& a = buffers_.solver[to];
  const PoseGraphSolverSlot& b = buffers_.solver[from];
  return Vec{{sub_sat(a.p[0], b.p[0]), sub_sat(a.p[1], b.p[1])}};
}

void PoseGraph::move(uint32_t i, uint32_t c, int64_t delta) {
  PoseGraphNode& n = buffers_.nodes[i];
  if (stage_ == PoseGraphStage::kHeadings) {
    // Q0.64 turns: wrapping is exact.
    const uint64_t h = fine(i) + (static_cast<uint64_t>(delta) << 24);
    n.heading.bam = static_cast<uint32_t>(h >> 32);
    buffers_.solver[i].heading_low = static_cast<uint32_t>(h);
  } else if (c == 0) {
    n.x = Q31_32::from_raw(add_sat(n.x.raw(), delta));
  } else {
    n.y = Q31_32::from_raw(add_sat(n.y.raw(), delta));
  }
}

uint64_t PoseGraph::fine(uint32_t i) const {
  return (static_cast<uint64_t>(buffers_.nodes[i].heading.bam) << 32) |
         buffers_.solver[i].heading_low;
}

Angle PoseGraph::heading(uint32_t i) const {
  return Angle{buffers_.nodes[i].heading.bam + (buffers_.solver[i].heading_low >> 31)};
}

// ---- The state machine --------------------------------------------------------------------

void PoseGraph::start_stage(PoseGraphStage stage) {
  stage_ = stage;
  stage_restarts_ = 0;
  if (nodes_ <= 1) {
    // A single node is the anchor: nothing to solve.
    stage_ = PoseGraphStage::kConverged;
    ++stats_.solves;
    return;
  }
  // Stop when V r.z <= tolerance^2. Raw units: r.z is in value units squared times info with
  // info's 16 fraction bits removed, V has 24 fraction bits, so the test is
  // r.z <= tol^2 2^24 / V = tol^2 2^16 / (V / 2^8), V / 2^8 rounded up (the threshold can only
  // get stricter). The heading stage's values carry 8 more fraction bits. Computed once per
  // stage start (V changes only with the graph) with two 64-bit divisions.
  const uint64_t tol = stage_ == PoseGraphStage::kHeadings
                           ? uint64_t{config_.tolerance_heading.bam} << 8
                           : static_cast<uint64_t>(config_.tolerance_xy.raw());
  const uint64_t v = (var_sum_ + 255) >> 8;  // <= 2^40 (65535 chain variances below 2^32)
  const uint64_t t2 = tol * tol;             // tol < 2^32
  threshold_ = Int128::from_u64(t2 / v).shl(16) + Int128::from_u64(((t2 % v) << 16) / v);
  // The system is the nodes there are now; later ones stay leaves until the stage ends (a
  // restart inside the stage keeps the system, so its residuals stay comparable).
  solve_nodes_ = nodes_;
  restart();
}

// Restarts `stage` now, or, while a CG step is half applied (kBackward has moved some nodes
// and not others), as soon as it is applied to all of them. Abandoning a step half way leaves
// the estimate torn between moved and unmoved nodes; when a node arrives after every slice
// (the robot's use) and a slice ends inside the step each time, the tears add up and the
// solve diverges instead of converging (seen with weak closures: headings off by a full
// turn). Nodes added in the meantime are leaves outside the system until the restart.
void PoseGraph::request_restart(PoseGraphStage stage) {
  const bool applying =
      stage_ != PoseGraphStage::kConverged && phase_ == Phase::kBackward && updating_ && index_ > 0;
  if (!applying) {
    pending_ = PoseGraphStage::kConverged;
    start_stage(stage);
    return;
  }
  // The earliest stage asked for wins (a closure restarts at the headings).
  if (pending_ == PoseGraphStage::kConverged || stage < pending_) pending_ = stage;
}

// Headings, then positions (with the headings just solved).
void PoseGraph::finish_stage() {
  if (nodes_ > solve_nodes_) {
    // Leaves arrived during the stage: place them from their predecessors first.
    phase_ = Phase::kLeaves;
    index_ = solve_nodes_;
    return;
  }
  if (stage_ == PoseGraphStage::kHeadings) {
    start_stage(PoseGraphStage::kPositions);
  } else {
    stage_ = PoseGraphStage::kConverged;
    ++stats_.solves;
  }
}

void PoseGraph::restart() {
  if (stage_restarts_ >= config_.max_restarts) {
    // The tolerance is below what rounding lets the residual reach: accept the estimate.
    ++stats_.stalls;
    finish_stage();
    return;
  }
  ++stage_restarts_;
  phase_ = Phase::kResidualChain;
  index_ = 1;
  updating_ = false;
  run_iterations_ = 0;
}

uint32_t PoseGraph::run_phase(uint32_t budget) {
  const uint32_t chain = solve_nodes_ - 1;  // nodes 1..solve_nodes_-1 take part (node 0 fixed)
  switch (phase_) {
    case Phase::kResidualChain: {
      const uint32_t n = pass_length(solve_nodes_, budget);
      residual_chain(n);
      if (index_ == solve_nodes_) {
        phase_ = Phase::kResidualClosures;
        index_ = 0;
      }
      return n;
    }
    case Phase::kResidualClosures: {
      const uint32_t n = pass_length(closures_, budget);
      residual_closures(n);
      if (index_ == closures_) {
        phase_ = Phase::kBackward;
        index_ = 0;
        flow_[0] = flow_[1] = 0;
      }
      return n;
    }
    case Phase::kBackward: {
      const uint32_t n = pass_length(chain, budget);
      backward(n);
      if (index_ == chain && pending_ != PoseGraphStage::kConverged) {
        // The step is applied everywhere: now the restart that was asked for meanwhile.
        const PoseGraphStage stage = pending_;
        pending_ = PoseGraphStage::kConverged;
        start_stage(stage);
      } else if (index_ == chain) {
        phase_ = Phase::kForward;
        index_ = 1;
        rz_ = Int128(0);
      }
      return n;
    }
    case Phase::kForward: {
      const uint32_t n = pass_length(solve_nodes_, budget);
      forward(n);
      if (index_ == solve_nodes_) phase_ = Phase::kCheck;
      return n;
    }
    case Phase::kCheck:
      check();
      return 1;
    case Phase::kDirectionChain: {
      const uint32_t n = pass_length(solve_nodes_, budget);
      direction_chain(n);
      if (index_ == solve_nodes_) {
        phase_ = Phase::kDirectionClosures;
        index_ = 0;
      }
      return n;
    }
    case Phase::kDirectionClosures: {
      const uint32_t n = pass_length(closures_, budget);
      direction_closures(n);
      if (index_ == closures_) phase_ = Phase::kStepLength;
      return n;
    }
    case Phase::kStepLength:
      step_length();
      return 1;
    case Phase::kLeaves: {
      // nodes_ may grow meanwhile: a node added here is placed from a predecessor that is
      // either already placed again or reached later by this pass.
      const uint32_t n = pass_length(nodes_, budget);
      place_leaves(n);
      if (index_ == nodes_) {
        solve_nodes_ = nodes_;
        finish_stage();
      }
      return n;
    }
  }
  return 1;
}

// Node k (>= 1) at its predecessor's estimate composed with the odometry edge into it: where
// add_node() puts a new node, and where the end of a stage puts the leaves added during it.
void PoseGraph::place_leaf(uint32_t k) {
  const PoseGraphEdge& e = buffers_.edges[k - 1];
  const PoseGraphNode& prev = buffers_.nodes[k - 1];
  PoseGraphNode& node = buffers_.nodes[k];
  const SinCos sc = sincos(heading(k - 1));
  node.x = Q31_32::from_raw(add_sat(prev.x.raw(), rotate_x(sc, e)));
  node.y = Q31_32::from_raw(add_sat(prev.y.raw(), rotate_y(sc, e)));
  node.heading = Angle{prev.heading.bam + e.dtheta.bam};
  buffers_.solver[k].heading_low = buffers_.solver[k - 1].heading_low;
}

// Leaves solve_nodes_.. in order (kLeaves).
void PoseGraph::place_leaves(uint32_t count) {
  for (uint32_t i = 0; i < count; ++i, ++index_) {
    place_leaf(index_);
    ++stats_.node_visits;
  }
}

// r = b - A x, chain part: the odometry edge into node k adds t = W rho to r_k and removes it
// from r_{k-1} (node 0 is fixed and has no equation).
void PoseGraph::residual_chain(uint32_t count) {
  const uint32_t dim = dims();
  for (uint32_t i = 0; i < count; ++i, ++index_) {
    const uint32_t k = index_;
    const PoseGraphEdge& e = buffers_.edges[k - 1];
    const Vec t = weigh_edge(e, false, edge_residual(e));
    for (uint32_t c = 0; c < dim; ++c) {
      buffers_.solver[k].r[c] = t.v[c];
      if (k >= 2) buffers_.solver[k - 1].r[c] = sub_sat(buffers_.solver[k - 1].r[c], t.v[c]);
    }
    ++stats_.node_visits;
  }
}

void PoseGraph::residual_closures(uint32_t count) {
  const uint32_t dim = dims();
  for (uint32_t i = 0; i < count; ++i, ++index_) {
    const PoseGraphEdge& e = closure(index_);
    const Vec t = weigh_edge(e, true, edge_residual(e));
    for (uint32_t c = 0; c < dim; ++c) {
      if (e.to != 0) buffers_.solver[e.to].r[c] = add_sat(buffers_.solver[e.to].r[c], t.v[c]);
      if (e.from != 0) {
        buffers_.solver[e.from].r[c] = sub_sat(buffers_.solver[e.from].r[c], t.v[c]);
      }
    }
    ++stats_.closure_visits;
  }
}

// Nodes n-1 down to 1. When updating, first the CG step (x += alpha p, r -= alpha q, with q
// in the z slot). Then the chain preconditioner's first half: the flow through the odometry
// edge into node k is the sum of r over nodes k.. (everything downstream of it on the path),
// and that edge's share of the correction is flow * variance (x and y alike).
void PoseGraph::backward(uint32_t count) {
  const uint32_t dim = dims();
  for (uint32_t i = 0; i < count; ++i, ++index_) {
    const uint32_t k = solve_nodes_ - 1 - index_;
    PoseGraphSolverSlot& s = buffers_.solver[k];
    for (uint32_t c = 0; c < dim; ++c) {
      if (updating_) {
        move(k, c, mul_u32_shift(s.p[c], alpha_.mant, alpha_.shift));
        s.r[c] = sub_sat(s.r[c], mul_u32_shift(s.z[c], alpha_.mant, alpha_.shift));
      }
      flow_[c] = add_sat(flow_[c], s.r[c]);
      s.z[c] = spread(flow_[c], var(k));
    }
    ++stats_.node_visits;
  }
}

// Nodes 1..n-1: the second half, z_k = z_{k-1} + share_k (z_0 = 0), and r.z.
void PoseGraph::forward(uint32_t count) {
  const uint32_t dim = dims();
  for (uint32_t i = 0; i < count; ++i, ++index_) {
    const uint32_t k = index_;
    PoseGraphSolverSlot& s = buffers_.solver[k];
    for (uint32_t c = 0; c < dim; ++c) {
      if (k >= 2) s.z[c] = add_sat(s.z[c], buffers_.solver[k - 1].z[c]);
      multiply_add(&rz_, s.r[c], s.z[c]);
    }
    ++stats_.node_visits;
  }
}

// Nodes 1..n-1: p = z + beta p, then q = A p for the chain edges, written over z (z_k is
// read before q_k is stored; q_{k-1} is complete except for this edge's share) and
// p.q = sum over edges of (p_to - p_from)^T W (p_to - p_from).
void PoseGraph::direction_chain(uint32_t count) {
  const uint32_t dim = dims();
  for (uint32_t i = 0; i < count; ++i, ++index_) {
    const uint32_t k = index_;
    PoseGraphSolverSlot& s = buffers_.solver[k];
    for (uint32_t c = 0; c < dim; ++c) {
      s.p[c] = add_sat(s.z[c], mul_u32_shift(s.p[c], beta_.mant, beta_.shift));
    }
    const Vec d = difference(k, k - 1);
    const Vec t = weigh_edge(buffers_.edges[k - 1], false, d);
    for (uint32_t c = 0; c < dim; ++c) {
      s.z[c] = t.v[c];
      if (k >= 2) buffers_.solver[k - 1].z[c] = sub_sat(buffers_.solver[k - 1].z[c], t.v[c]);
      multiply_add(&pq_, d.v[c], t.v[c]);
    }
    ++stats_.node_visits;
  }
}

void PoseGraph::direction_closures(uint32_t count) {
  const uint32_t dim = dims();
  for (uint32_t i = 0; i < count; ++i, ++index_) {
    const PoseGraphEdge& e = closure(index_);
    const Vec d = difference(e.to, e.from);
    const Vec t = weigh_edge(e, true, d);
    for (uint32_t c = 0; c < dim; ++c) {
      if (e.to != 0) buffers_.solver[e.to].z[c] = add_sat(buffers_.solver[e.to].z[c], t.v[c]);
      if (e.from != 0) {
        buffers_.solver[e.from].z[c] = sub_sat(buffers_.solver[e.from].z[c], t.v[c]);
      }
      multiply_add(&pq_, d.v[c], t.v[c]);
    }
    ++stats_.closure_visits;
  }
}

namespace {

// num / den as mant * 2^-shift with a 32-bit mantissa (relative error < 2^-31); false unless
// both are positive and the ratio is below 2^32. One 64/32-bit division.
bool ratio(Int128 num, Int128 den, uint32_t* mant, int32_t* shift) {
  if (num <= Int128(0) || den <= Int128(0)) return false;
  const int en = bit_length(num);
  const int ed = bit_length(den);
  const uint64_t n64 = en > 64 ? num.sar(en - 64).low64() : num.low64() << (64 - en);
  const uint64_t d32 = ed > 32 ? den.sar(ed - 32).low64() : den.low64() << (32 - ed);
  uint64_t q = n64 / d32;  // in (2^31, 2^33)
  int s = ed + 32 - en;
  if ((q >> 32) != 0) {
    q >>= 1;
    --s;
  }
  if (s < 1) return false;  // 2^31 or more: no sensible CG scalar
  *mant = static_cast<uint32_t>(q);
  *shift = s > 127 ? 127 : s;
  return true;
}

}  // namespace

void PoseGraph::check() {
  ++stats_.scalar_steps;
  const bool small = rz_ <= threshold_;
  if (!updating_) {
    // r.z of a freshly recomputed residual: the bound is rigorous here.
    ++stats_.restarts;
    if (small) {
      finish_stage();
      return;
    }
    // A fresh residual that did not even halve since the last one: the estimate is at the
    // rounding floor (the tolerance is below it), and more iterations only stir the rounding.
    if (stage_restarts_ >= 2 && rz_ + rz_ > fresh_rz_) {
      ++stats_.stalls;
      finish_stage();
      return;
    }
    fresh_rz_ = rz_;
    beta_ = Scalar{};
  } else {
    ++run_iterations_;
    ++stats_.iterations;
    // Converged by CG's own (recursive) residual, or out of iterations: confirm or continue
    // from a recomputed residual.
    if (small || run_iterations_ >= closures_ * dims() + 1u + config_.extra_iterations ||
        !ratio(rz_, rz_old_, &beta_.mant, &beta_.shift)) {
      restart();
      return;
    }
  }
  phase_ = Phase::kDirectionChain;
  index_ = 1;
  pq_ = Int128(0);
}

void PoseGraph::step_length() {
  ++stats_.scalar_steps;
  if (!ratio(rz_, pq_, &alpha_.mant, &alpha_.shift)) {
    restart();
    return;
  }
  rz_old_ = rz_;
  updating_ = true;
  phase_ = Phase::kBackward;
  index_ = 0;
  flow_[0] = flow_[1] = 0;
}

}  // namespace seqslam
