#include "seqslam/pose_graph.h"

#include "pose_graph_math.h"

namespace seqslam {

using namespace pose_graph_detail;

namespace {

// Positive semi-definite (PoseInformation): the position block exactly, the 3x3 determinant
// on values rounded down to 2^-8 (products of three of them need 72 bits).
bool positive_semidefinite(const PoseInformation& in) {
  const int64_t a = in.along.raw();
  const int64_t l = in.lateral.raw();
  const int64_t h = in.heading.raw();
  const int64_t c = in.cross.raw();
  const int64_t p = in.along_heading.raw();
  const int64_t q = in.lateral_heading.raw();
  if (static_cast<uint64_t>(c * c) > static_cast<uint64_t>(a) * static_cast<uint64_t>(l) ||
      static_cast<uint64_t>(p * p) > static_cast<uint64_t>(a) * static_cast<uint64_t>(h) ||
      static_cast<uint64_t>(q * q) > static_cast<uint64_t>(l) * static_cast<uint64_t>(h)) {
    return false;
  }
  if (p == 0 && q == 0) return true;
  const int64_t a8 = a >> 8, l8 = l >> 8, h8 = h >> 8, c8 = c >> 8, p8 = p >> 8, q8 = q >> 8;
  Int128 det(0);
  multiply_add(&det, a8, l8 * h8 - q8 * q8);
  multiply_add(&det, -c8, c8 * h8 - q8 * p8);
  multiply_add(&det, p8, c8 * q8 - l8 * p8);
  return !det.negative();
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
      b.solver.size() < b.nodes.size() || b.solver.data() == nullptr ||
      // The finish, the objective's tolerance and the tree: linked by enable_refine().
      (refine_ops_ == nullptr
           ? (c.refine_restarts > 0 || c.tree_preconditioner || c.tolerance_objective.raw() != 0)
           : !refine_ops_->valid(c, b))) {
    return Status::kInvalidArgument;
  }
  if (c.min_travel.raw() < (int64_t{1} << 16) || c.min_travel.raw() > (int64_t{1} << 32) ||
      c.tolerance_xy.raw() < 1 || c.tolerance_xy.raw() > (int64_t{1} << 24) ||
      c.tolerance_heading.bam < 1 || c.tolerance_heading.bam >= (uint32_t{1} << 24) ||
      c.extra_iterations < 1 || c.extra_iterations > 1000 || c.max_restarts < 1 ||
      c.max_restarts > 1000 || c.closure_lateral.raw() > UQ16_16::from_int(1).raw() ||
      c.max_iterations > 10000 || c.refine_restarts > 1000 || c.max_scale > kMaxScale) {
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
  var_sum_heading_ = 0;
  stats_ = PoseGraphStats{};
  scale_ = 0;
  peak_ = 0;
  fresh_scale_ = 0;
  rescaled_ = false;
  fatal_ = false;
  apply_shift_ = -1;
  pending_step_ = false;
  step_applied_ = false;
  backtracks_ = 0;
  run_complete_ = true;
  anisotropic_ = 0;
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
  if (solve_nodes_ > nodes_ || scale_ > kMaxScale) return false;
  if (stage_ == PoseGraphStage::kRefine && config_.refine_restarts == 0) return false;
  if (stage_ == PoseGraphStage::kConverged || stage_ == PoseGraphStage::kFailed) return true;
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
    case Phase::kApply:
      if (stage_ != PoseGraphStage::kRefine) return false;
      end = solve_nodes_;
      break;
    case Phase::kCheck:
    case Phase::kStepLength:
      return true;
  }
  return index_ <= end;
}

Result<uint32_t> PoseGraph::add_node(const Pose2& odometry, uint32_t place) {
  const Status s = add_odometry(odometry, place, nullptr, 0);
  if (s != Status::kOk) return s;
  return nodes_ - 1;
}

// The data's information is checked here, apart from add_odometry(), so that a caller of the
// other overload (the explorer) does not link the checks.
Result<uint32_t> PoseGraph::add_node(const Pose2& odometry, uint32_t place,
                                     const PoseInformation& info) {
  if (!configured_) return Status::kFailedPrecondition;
  if (nodes_ > 0) {
    // The chain preconditioner's variances: 1 / the smallest eigenvalue of the position
    // information (so that the chain's share of the system matrix, weighted alike in every
    // direction, stays below the edge's: M <= A), and 1 / the heading information; both at
    // least 1/256 so that the variances fit UQ8.24.
    const int64_t smallest =
        smallest_eigenvalue(info.along.raw(), info.lateral.raw(), info.cross.raw());
    if (smallest < 256 || info.heading.raw() < 256 || !positive_semidefinite(info)) {
      return Status::kInvalidArgument;
    }
    const Status s = add_odometry(odometry, place, &info, static_cast<uint32_t>(smallest));
    if (s != Status::kOk) return s;
  } else {
    const Status s = add_odometry(odometry, place, nullptr, 0);
    if (s != Status::kOk) return s;
  }
  return nodes_ - 1;
}

// `given`: the data's information, checked, and its position block's smallest eigenvalue; null:
// the explorer's 1 m / max(step, min_travel).
Status PoseGraph::add_odometry(const Pose2& odometry, uint32_t place, const PoseInformation* given,
                               uint32_t smallest_given) {
  if (!configured_) return Status::kFailedPrecondition;
  if (nodes_ >= node_capacity_) return Status::kResourceExhausted;
  PoseGraphSolverSlot& slot = buffers_.solver[nodes_];
  PoseGraphNode& node = buffers_.nodes[nodes_];
  if (nodes_ == 0) {
    node = PoseGraphNode{odometry.x, odometry.y, odometry.heading, place};
    slot = PoseGraphSolverSlot{};  // the anchor: never part of a system
    if (!buffers_.refine.empty()) buffers_.refine[0] = PoseGraphRefineSlot{};
    last_odometry_ = odometry;
    nodes_ = 1;
    return Status::kOk;
  }
  if (edge_count() >= edge_capacity_) return Status::kResourceExhausted;
  const RelativePose2 step = relative_pose(last_odometry_, odometry);
  PoseGraphEdge e{};
  if (!to_q7_24(step.dx, &e.dx) || !to_q7_24(step.dy, &e.dy)) return Status::kOutOfRange;
  e.from = static_cast<uint16_t>(nodes_ - 1);
  e.to = static_cast<uint16_t>(nodes_);
  e.dtheta = step.dtheta;
  uint32_t smallest = smallest_given;
  if (given != nullptr) {
    e.info_xy = given->along;
    e.info_lateral = given->lateral;
    e.info_cross = given->cross;
    e.info_heading = given->heading;
    e.info_along_heading = given->along_heading;
    e.info_lateral_heading = given->lateral_heading;
  } else {
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
    e.info_lateral = e.info_xy;
    smallest = static_cast<uint32_t>(info);
  }
  if (refine_ops_ != nullptr && !refine_ops_->add_node(*this, e)) return Status::kInvalidArgument;
  buffers_.edges[nodes_ - 1] = e;
  node.place = place;
  slot = PoseGraphSolverSlot{};
  slot.var = variance_of(smallest);
  slot.var_heading = variance_of(e.info_heading.raw());
  // The new leaf at its predecessor's estimate composed with the step: the optimum of every
  // stage for a leaf, so a converged graph stays converged.
  place_leaf(nodes_);
  var_sum_ += slot.var;
  var_sum_heading_ += slot.var_heading;
  if (e.info_xy.raw() != e.info_lateral.raw() || e.info_cross.raw() != 0) ++anisotropic_;
  last_odometry_ = odometry;
  ++nodes_;
  // A stage in progress goes on without it: the new node is a leaf outside the system being
  // solved, placed again from its predecessor when the stage ends (kLeaves), which is its
  // optimum. (Restarting the stage instead would throw its work away at every place: with a
  // node every slice and slices shorter than an iteration, the solve would never advance.)
  return Status::kOk;
}

Status PoseGraph::add_loop_closure(uint32_t a, uint32_t b, const RelativePose2& b_from_a,
                                   EdgeInformation info) {
  if (!configured_) return Status::kFailedPrecondition;
  if (a >= nodes_ || b >= nodes_) return Status::kOutOfRange;
  if (a == b || (info.xy.raw() == 0 && info.heading.raw() == 0)) return Status::kInvalidArgument;
  // Weaker across the route by closure_lateral (rounded as the position stage did when it
  // applied the fraction itself).
  const uint32_t across = static_cast<uint32_t>(
      (static_cast<uint64_t>(info.xy.raw()) * config_.closure_lateral.raw() + 0x8000u) >> 16);
  // Positive semi-definite by construction (diagonal, lateral <= along).
  return add_closure(a, b, b_from_a,
                     PoseInformation{info.xy, UQ16_16::from_raw(across), Q15_16{}, info.heading,
                                     Q15_16{}, Q15_16{}});
}

Status PoseGraph::add_loop_closure(uint32_t a, uint32_t b, const RelativePose2& b_from_a,
                                   const PoseInformation& info) {
  if (!configured_) return Status::kFailedPrecondition;
  if (a >= nodes_ || b >= nodes_) return Status::kOutOfRange;
  const int64_t cross = info.cross.raw();
  const bool no_position = info.along.raw() == 0 && info.lateral.raw() == 0 && cross == 0;
  if (a == b || (no_position && info.heading.raw() == 0)) return Status::kInvalidArgument;
  if (!positive_semidefinite(info)) return Status::kInvalidArgument;
  return add_closure(a, b, b_from_a, info);
}

// A checked closure into the edge array (from both add_loop_closure overloads).
Status PoseGraph::add_closure(uint32_t a, uint32_t b, const RelativePose2& b_from_a,
                              const PoseInformation& info) {
  PoseGraphEdge e{};
  if (!to_q7_24(b_from_a.dx, &e.dx) || !to_q7_24(b_from_a.dy, &e.dy)) {
    return Status::kOutOfRange;
  }
  if (edge_count() >= edge_capacity_) return Status::kResourceExhausted;
  e.from = static_cast<uint16_t>(a);
  e.to = static_cast<uint16_t>(b);
  e.dtheta = b_from_a.dtheta;
  e.info_xy = info.along;
  e.info_lateral = info.lateral;
  e.info_cross = info.cross;
  e.info_heading = info.heading;
  e.info_along_heading = info.along_heading;
  e.info_lateral_heading = info.lateral_heading;
  buffers_.edges[edge_capacity_ - 1 - closures_] = e;
  ++closures_;
  if (config_.tree_preconditioner) refine_ops_->tree_closure(*this, closures_ - 1);
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
  while (done < budget && stage_ != PoseGraphStage::kConverged &&
         stage_ != PoseGraphStage::kFailed) {
    done += run_phase(budget - done);
  }
  out->work = done;
  out->converged = stage_ == PoseGraphStage::kConverged;
  out->stage = stage_;
  return stage_ == PoseGraphStage::kFailed ? Status::kOutOfRange : Status::kOk;
}

// ---- Stage-dependent views ----------------------------------------------------------------

__attribute__((noinline)) int64_t PoseGraph::checked(int64_t v) {
  peak_ |= static_cast<uint64_t>(v ^ (v >> 63));
  return v;
}

// The edge's residual b - A x, scaled by 2^-scale_. Headings: the measured turn minus the
// estimated one modulo a full turn (the unwrapping against the current estimate), in the
// stage's units (2^-8 binary-angle units, or 2^-32 rad in the nonlinear finish). Positions:
// R(theta_from) d - (p_to - p_from), 2^-32 m.
PoseGraph::Vec PoseGraph::edge_residual(const PoseGraphEdge& e) {
  const PoseGraphNode& a = buffers_.nodes[e.from];
  const PoseGraphNode& b = buffers_.nodes[e.to];
  const uint64_t turn = (static_cast<uint64_t>(e.dtheta.bam) << 32) - (fine(e.to) - fine(e.from));
  if (stage_ == PoseGraphStage::kHeadings) {
    return Vec{{shift_down(shift_round_i64(static_cast<int64_t>(turn), 24), scale_), 0, 0}};
  }
  const SinCos sc = sincos(heading(e.from));
  const int64_t rx = sub_sat(rotate_x(sc, e), sub_sat(b.x.raw(), a.x.raw()));
  const int64_t ry = sub_sat(rotate_y(sc, e), sub_sat(b.y.raw(), a.y.raw()));
  if (abs_i64(rx) >= kEstimateLimit || abs_i64(ry) >= kEstimateLimit) fatal_ = true;
  Vec r{{shift_down(rx, scale_), shift_down(ry, scale_), 0}};
  if (refining()) {
    // The finish sums rho . t (its objective): rho within the limit too.
    checked(r.v[0]);
    checked(r.v[1]);
    r.v[2] = checked(refine_ops_->heading_residual(*this, turn));
  }
  return r;
}

// W_e v. Headings: the heading weight. Positions: W = R(theta_from) Omega R(theta_from)^T,
// Omega = [[along, cross], [cross, lateral]], written as m I plus the excess along (a) or
// across (b) and the cross term, m = min(along, lateral), so that an isotropic edge costs no
// rotation and a closure weak across (b = cross = 0) the one rotation it always cost. The
// nonlinear finish: both, the heading in 2^-32 rad.
PoseGraph::Vec PoseGraph::weigh_edge(const PoseGraphEdge& e, Vec v) const {
  if (stage_ == PoseGraphStage::kHeadings) {
    return Vec{{weigh(v.v[0], e.info_heading.raw()), 0, 0}};
  }
  if (refining()) return refine_ops_->weigh(*this, e, v);
  const uint32_t along = e.info_xy.raw();
  const uint32_t lateral = e.info_lateral.raw();
  const int32_t cross = e.info_cross.raw();
  const uint32_t m = along < lateral ? along : lateral;
  Vec t{{weigh(v.v[0], m), weigh(v.v[1], m), 0}};
  if (along == lateral && cross == 0) return t;
  const SinCos sc = sincos(heading(e.from));
  // u = (c, s) along the heading, w = (-s, c) across it.
  const int64_t va = add_sat(mul_q30(v.v[0], sc.cos), mul_q30(v.v[1], sc.sin));
  int64_t ka = along > m ? weigh(va, along - m) : 0;
  int64_t kw = 0;
  if (lateral > m || cross != 0) {
    const int64_t vw = sub_sat(mul_q30(v.v[1], sc.cos), mul_q30(v.v[0], sc.sin));
    kw = lateral > m ? weigh(vw, lateral - m) : 0;
    if (cross != 0) {
      ka = add_sat(ka, weigh_signed(vw, cross));
      kw = add_sat(kw, weigh_signed(va, cross));
    }
  }
  if (ka != 0) {
    t.v[0] = add_sat(t.v[0], mul_q30(ka, sc.cos));
    t.v[1] = add_sat(t.v[1], mul_q30(ka, sc.sin));
  }
  if (kw != 0) {
    t.v[0] = sub_sat(t.v[0], mul_q30(kw, sc.sin));
    t.v[1] = add_sat(t.v[1], mul_q30(kw, sc.cos));
  }
  return t;
}

// J_e p for the search direction p. LAGO: p_to - p_from. The nonlinear finish: the position
// part less the lever times the `from` node's heading component, and the heading difference.
PoseGraph::Vec PoseGraph::difference(const PoseGraphEdge& e) {
  if (refining()) return refine_ops_->difference(*this, e);
  Vec d{{0, 0, 0}};
  const uint32_t dim = dims();
  // |d| < 2^54 from the checks on p: products with terms below 2^53 stay below 2^107.
  for (uint32_t c = 0; c < dim; ++c)
    d.v[c] = sub_sat(vp_of(e.to, c), vp_of(e.from, c));
  return d;
}

// What the edge's term t takes from its `from` node: t itself, and in the nonlinear finish the
// lever's share in the heading component, (J a)^T t.
PoseGraph::Vec PoseGraph::from_share(const PoseGraphEdge& e, Vec t) const {
  return refining() ? refine_ops_->from_share(*this, e, t) : t;
}

void PoseGraph::move(uint32_t i, uint32_t c, int64_t delta) {
  PoseGraphNode& n = buffers_.nodes[i];
  if (stage_ == PoseGraphStage::kHeadings || c == 2) {
    // Q0.64 turns: wrapping is exact. LAGO's headings are 2^-40 turn; the finish's 2^-32 rad.
    const uint64_t step =
        c == 2 ? refine_ops_->heading_step(delta) : static_cast<uint64_t>(delta) << 24;
    const uint64_t h = fine(i) + step;
    n.heading.bam = static_cast<uint32_t>(h >> 32);
    buffers_.solver[i].heading_low = static_cast<uint32_t>(h);
  } else if (c == 0) {
    n.x = Q31_32::from_raw(add_sat(n.x.raw(), delta));
    if (abs_i64(n.x.raw()) >= kEstimateLimit) fatal_ = true;
  } else {
    n.y = Q31_32::from_raw(add_sat(n.y.raw(), delta));
    if (abs_i64(n.y.raw()) >= kEstimateLimit) fatal_ = true;
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
  fatal_ = false;
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
  // stage start (V changes only with the graph) with two 64-bit divisions. The nonlinear
  // finish uses the position test (its heading unit, 2^-32 rad, is the position's 2^-32 m).
  const uint64_t tol = stage_ == PoseGraphStage::kHeadings
                           ? uint64_t{config_.tolerance_heading.bam} << 8
                           : static_cast<uint64_t>(config_.tolerance_xy.raw());
  const uint64_t sum = stage_ == PoseGraphStage::kHeadings ? var_sum_heading_ : var_sum_;
  const uint64_t v = (sum + 255) >> 8;  // <= 2^40 (65535 chain variances below 2^32)
  const uint64_t t2 = tol * tol;        // tol < 2^32
  threshold_ = Int128::from_u64(t2 / v).shl(16) + Int128::from_u64(((t2 % v) << 16) / v);
  if (config_.tolerance_objective.raw() > 0) refine_ops_->objective_threshold(*this);
  // The system is the nodes there are now; later ones stay leaves until the stage ends (a
  // restart inside the stage keeps the system, so its residuals stay comparable).
  solve_nodes_ = nodes_;
  // The finish's first pass only clears the update vectors (left from an abandoned finish).
  apply_shift_ = -1;
  pending_step_ = false;
  step_applied_ = false;
  backtracks_ = 0;
  run_complete_ = true;
  scale_ = 0;
  peak_ = 0;
  rescaled_ = false;
  restart();
}

// Restarts `stage` now, or, while a CG step is half applied (kBackward has moved some nodes
// and not others), as soon as it is applied to all of them. Abandoning a step half way leaves
// the estimate torn between moved and unmoved nodes; when a node arrives after every slice
// (the robot's use) and a slice ends inside the step each time, the tears add up and the
// solve diverges instead of converging (seen with weak closures: headings off by a full
// turn). Nodes added in the meantime are leaves outside the system until the restart.
void PoseGraph::request_restart(PoseGraphStage stage) {
  const bool applying = stage_ != PoseGraphStage::kConverged && stage_ != PoseGraphStage::kFailed &&
                        phase_ == Phase::kBackward && updating_ && index_ > 0;
  if (!applying) {
    pending_ = PoseGraphStage::kConverged;
    start_stage(stage);
    return;
  }
  // The earliest stage asked for wins (a closure restarts at the headings).
  if (pending_ == PoseGraphStage::kConverged || stage < pending_) pending_ = stage;
}

// Headings, then positions (with the headings just solved), then the nonlinear finish if on.
void PoseGraph::finish_stage() {
  if (nodes_ > solve_nodes_) {
    // Leaves arrived during the stage: place them from their predecessors first.
    phase_ = Phase::kLeaves;
    index_ = solve_nodes_;
    return;
  }
  if (stage_ == PoseGraphStage::kHeadings) {
    start_stage(PoseGraphStage::kPositions);
  } else if (stage_ == PoseGraphStage::kPositions && config_.refine_restarts > 0) {
    start_stage(PoseGraphStage::kRefine);
  } else {
    stage_ = PoseGraphStage::kConverged;
    ++stats_.solves;
  }
}

// The graph is beyond the limits: the estimates stay where the last valid step left them.
void PoseGraph::fail() {
  stage_ = PoseGraphStage::kFailed;
  pending_ = PoseGraphStage::kConverged;
  ++stats_.failures;
}

// What exact arithmetic may need: the preconditioned system is the identity plus one rank-one
// term per closure and component, and in the position stage one or two per odometry edge
// whose information is not alike in every direction (the chain preconditioner weighs all
// directions by its smallest eigenvalue); the finish's chain preconditioner is exact.
uint32_t PoseGraph::iteration_cap() const {
  if (config_.max_iterations > 0) return config_.max_iterations;
  const uint32_t chain = stage_ == PoseGraphStage::kPositions ? 2 * anisotropic_ : 0;
  return closures_ * dims() + chain + 1u + config_.extra_iterations;
}

void PoseGraph::restart() {
  // The finish counts its relinearisations in check(), after the last update is applied.
  if (!refining() && stage_restarts_ >= config_.max_restarts) {
    // Out of recomputations: accept the estimate (the bound recorded at the last fresh
    // residual; CG's steps since only lowered the objective, to rounding).
    ++stats_.stalls;
    ++stats_.exhausted;
    finish_stage();
    return;
  }
  ++stage_restarts_;
  // Each recomputation starts at full resolution: the residual shrinks as the solve converges,
  // and a coarse scale kept from a large residual would put the rounding floor above the
  // tolerance. An overflow makes it coarser again (rescale()).
  scale_ = 0;
  peak_ = 0;
  if (refining() && apply_shift_ > 0) apply_shift_ = 0;
  phase_ = refining() ? Phase::kApply : Phase::kResidualChain;
  index_ = 1;
  updating_ = false;
  run_iterations_ = 0;
}

// An overflow: the run's vectors are not to be trusted. Begin the recomputation again two bits
// coarser (not counted as a restart: the scale's limit bounds how often this happens); the
// estimates hold only steps taken from vectors that were within the limit.
void PoseGraph::rescale() {
  ++stats_.rescales;
  // Coarser by what the largest value seen needs, two bits to spare (a clipped value, 2^63,
  // asks for 12).
  uint32_t bits = 0;
  while (bits < 64 && (peak_ >> bits) != 0)
    ++bits;
  scale_ += bits > 51 ? bits - 51 : 2;
  if (scale_ > stats_.max_scale) stats_.max_scale = scale_;
  if (scale_ > config_.max_scale) {
    fail();
    return;
  }
  peak_ = 0;
  rescaled_ = true;
  run_complete_ = false;
  // The finish's steps of this run are applied (they are the sum of valid steps).
  if (refining() && apply_shift_ > 0) apply_shift_ = 0;
  phase_ = refining() ? Phase::kApply : Phase::kResidualChain;
  index_ = 1;
  updating_ = false;
  run_iterations_ = 0;
}

uint32_t PoseGraph::run_phase(uint32_t budget) {
  if (fatal_) {
    fail();
    return 1;
  }
  const uint32_t chain = solve_nodes_ - 1;  // nodes 1..solve_nodes_-1 take part (node 0 fixed)
  switch (phase_) {
    case Phase::kApply: {
      const uint32_t n = pass_length(solve_nodes_, budget);
      apply_deltas(n);
      if (index_ == solve_nodes_) {
        if (apply_shift_ > 0 || (apply_shift_ == 0 && pending_step_)) step_applied_ = true;
        if (apply_shift_ < 0) apply_shift_ = 0;
        pending_step_ = false;
        ++stats_.relinearisations;
        phase_ = Phase::kResidualChain;
        index_ = 1;
      }
      return n;
    }
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
        flow_[0] = flow_[1] = flow_[2] = 0;
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

// Nodes 1..n-1 of the nonlinear finish: the update built by the last CG run (the sum of its
// steps, at the linearisation point it was built for) moves the estimates, or a backtrack
// takes half of what is left of it back (apply_shift_), or delta is cleared (a new stage).
void PoseGraph::apply_deltas(uint32_t count) {
  for (uint32_t i = 0; i < count; ++i, ++index_) {
    refine_ops_->apply(*this, index_);
    ++stats_.node_visits;
  }
}

// r = b - A x, chain part: the odometry edge into node k adds t = W rho to r_k and removes it
// (with the lever's share in the finish) from r_{k-1} (node 0 is fixed and has no equation).
void PoseGraph::residual_chain(uint32_t count) {
  uint32_t peak = 0;  // the pass's largest magnitudes, high words (mark())
  const uint32_t dim = dims();
  for (uint32_t i = 0; i < count; ++i, ++index_) {
    const uint32_t k = index_;
    const PoseGraphEdge& e = buffers_.edges[k - 1];
    const Vec rho = edge_residual(e);
    const Vec t = weigh_edge(e, rho);
    const Vec f = from_share(e, t);
    if (refining()) refine_ops_->objective_add(*this, rho, t, k == 1);
    // (f, which only enters the stored sums, needs no check of its own: a saturated f leaves
    // a stored value beyond the limit, caught there.)
    for (uint32_t c = 0; c < dim; ++c) {
      vr(k, c) = mark(&peak, t.v[c]);
      if (k >= 2) vr(k - 1, c) = mark(&peak, sub_sat(vr(k - 1, c), f.v[c]));
    }
    ++stats_.node_visits;
  }
  peak_ |= static_cast<uint64_t>(peak) << 32;
}

void PoseGraph::residual_closures(uint32_t count) {
  uint32_t peak = 0;  // the pass's largest magnitudes, high words (mark())
  const uint32_t dim = dims();
  for (uint32_t i = 0; i < count; ++i, ++index_) {
    const PoseGraphEdge& e = closure(index_);
    const Vec rho = edge_residual(e);
    const Vec t = weigh_edge(e, rho);
    const Vec f = from_share(e, t);
    if (refining()) refine_ops_->objective_add(*this, rho, t, false);
    // (t and f only enter the stored sums: a saturated one leaves a stored value beyond the
    // limit, the other summand being below it, so the stored values' checks catch it.)
    for (uint32_t c = 0; c < dim; ++c) {
      if (e.to != 0) vr(e.to, c) = mark(&peak, add_sat(vr(e.to, c), t.v[c]));
      if (e.from != 0) vr(e.from, c) = mark(&peak, sub_sat(vr(e.from, c), f.v[c]));
    }
    ++stats_.closure_visits;
  }
  peak_ |= static_cast<uint64_t>(peak) << 32;
}

// Nodes n-1 down to 1. When updating, first the CG step (x += alpha p, r -= alpha q, with q
// in the z slot; the finish adds alpha p to its update instead of moving the estimate, whose
// linearisation must hold for the whole run). Then the chain preconditioner's first half: the
// flow through the odometry edge into node k is the sum of r over nodes k.. (everything
// downstream of it on the path), and that edge's share of the correction is flow * variance.
void PoseGraph::backward(uint32_t count) {
  uint32_t peak = 0;  // the pass's largest magnitudes, high words (mark())
  const uint32_t dim = dims();
  // The finish's chain and the tree preconditioner are in pose_graph_refine.cpp.
  const bool hooked = refining() || config_.tree_preconditioner;
  for (uint32_t i = 0; i < count; ++i, ++index_) {
    const uint32_t k = solve_nodes_ - 1 - index_;
    for (uint32_t c = 0; c < dim; ++c) {
      if (updating_) {
        // The step in the estimate's units: alpha p 2^scale.
        const int32_t shift = alpha_.shift - static_cast<int32_t>(scale_);
        int64_t step = 0;
        if (shift >= 0) {
          step = mul_u32_shift(vp(k, c), alpha_.mant, shift);
        } else {
          step = mul_u32_shift(vp(k, c), alpha_.mant, 0);
          if (abs_i64(step) < (kEstimateLimit >> -shift)) {
            step *= int64_t{1} << -shift;
          } else {
            fatal_ = true;  // a step of 2^30 m: beyond the limits
            step = 0;
          }
        }
        if (refining()) {
          pending_step_ = true;
          int64_t& d = buffers_.refine[k].delta[c];
          d = add_sat(d, step);
          if (abs_i64(d) >= kEstimateLimit) fatal_ = true;
        } else {
          move(k, c, step);
        }
        vr(k, c) =
            mark(&peak, sub_sat(vr(k, c), mul_u32_shift(vz(k, c), alpha_.mant, alpha_.shift)));
      }
      if (hooked) continue;
      flow_[c] = mark(&peak, add_sat(flow_[c], vr(k, c)));
      vz(k, c) = mark(&peak, spread(flow_[c], var(k, c)));
    }
    if (hooked) refine_ops_->chain_backward(*this, k);
    ++stats_.node_visits;
  }
  peak_ |= static_cast<uint64_t>(peak) << 32;
}

// Nodes 1..n-1: the second half, z_k = z_{k-1} + share_k (z_0 = 0), and r.z.
void PoseGraph::forward(uint32_t count) {
  uint32_t peak = 0;  // the pass's largest magnitudes, high words (mark())
  const uint32_t dim = dims();
  const bool hooked = refining() || config_.tree_preconditioner;
  for (uint32_t i = 0; i < count; ++i, ++index_) {
    const uint32_t k = index_;
    if (hooked) refine_ops_->chain_forward(*this, k);
    for (uint32_t c = 0; c < dim; ++c) {
      if (!hooked && k >= 2) vz(k, c) = mark(&peak, add_sat(vz(k, c), vz(k - 1, c)));
      multiply_add(&rz_, vr(k, c), vz(k, c));
    }
    ++stats_.node_visits;
  }
  peak_ |= static_cast<uint64_t>(peak) << 32;
}

// Nodes 1..n-1: p = z + beta p, then q = A p for the chain edges, written over z (z_k is
// read before q_k is stored; q_{k-1} is complete except for this edge's share) and
// p.q = sum over edges of (J p)^T W (J p).
void PoseGraph::direction_chain(uint32_t count) {
  uint32_t peak = 0;  // the pass's largest magnitudes, high words (mark())
  const uint32_t dim = dims();
  for (uint32_t i = 0; i < count; ++i, ++index_) {
    const uint32_t k = index_;
    for (uint32_t c = 0; c < dim; ++c) {
      vp(k, c) = mark(&peak, add_sat(vz(k, c), mul_u32_shift(vp(k, c), beta_.mant, beta_.shift)));
    }
    if (refining() && run_iterations_ == 0) {
      // A new run builds a new update (the last one is applied, or taken back in part).
      for (uint32_t c = 0; c < 3; ++c)
        buffers_.refine[k].delta[c] = 0;
    }
    const PoseGraphEdge& e = buffers_.edges[k - 1];
    const Vec d = difference(e);
    const Vec t = weigh_edge(e, d);
    const Vec f = from_share(e, t);
    for (uint32_t c = 0; c < dim; ++c) {
      vz(k, c) = mark(&peak, t.v[c]);
      if (k >= 2) vz(k - 1, c) = mark(&peak, sub_sat(vz(k - 1, c), f.v[c]));
      multiply_add(&pq_, d.v[c], t.v[c]);
    }
    ++stats_.node_visits;
  }
  peak_ |= static_cast<uint64_t>(peak) << 32;
}

void PoseGraph::direction_closures(uint32_t count) {
  uint32_t peak = 0;  // the pass's largest magnitudes, high words (mark())
  const uint32_t dim = dims();
  for (uint32_t i = 0; i < count; ++i, ++index_) {
    const PoseGraphEdge& e = closure(index_);
    const Vec d = difference(e);
    const Vec t = weigh_edge(e, d);
    const Vec f = from_share(e, t);
    for (uint32_t c = 0; c < dim; ++c) {
      mark(&peak, t.v[c]);
      if (e.to != 0) vz(e.to, c) = mark(&peak, add_sat(vz(e.to, c), t.v[c]));
      if (e.from != 0) vz(e.from, c) = mark(&peak, sub_sat(vz(e.from, c), f.v[c]));
      multiply_add(&pq_, d.v[c], t.v[c]);
    }
    ++stats_.closure_visits;
  }
  peak_ |= static_cast<uint64_t>(peak) << 32;
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
  if (overflowed()) {
    rescale();
    return;
  }
  // The threshold at this scale: r.z holds the true value / 2^(2 scale).
  const bool small = rz_ <= threshold_.sar(static_cast<int>(2 * scale_));
  if (!updating_) {
    // r.z of a freshly recomputed residual: the bound is rigorous here.
    if (refine_ops_ != nullptr) refine_ops_->record_bound(*this);
    // The finish first judges the step it applied (pose_graph_refine.cpp).
    if (refining() && !refine_ops_->judge(*this, small)) return;
    ++stats_.restarts;
    if (small) {
      ++stats_.tolerance_stops;
      finish_stage();
      return;
    }
    // A fresh residual that did not even halve since the last one: the estimate is at the
    // rounding floor (the tolerance is below it), and more iterations only stir the rounding.
    // (Not after a rescale: that recomputes the residual of the same estimate.)
    if (stage_restarts_ >= 2 && !rescaled_ && run_complete_ && !refining() &&
        !scaled_le(rz_ + rz_, scale_, fresh_rz_, fresh_scale_)) {
      ++stats_.stalls;
      finish_stage();
      return;
    }
    fresh_rz_ = rz_;
    fresh_scale_ = scale_;
    rescaled_ = false;
    beta_ = Scalar{};
  } else {
    ++run_iterations_;
    ++stats_.iterations;
    // Converged by CG's own (recursive) residual, or out of iterations: confirm or continue
    // from a recomputed residual. The finish relinearises earlier, once the linearised system
    // is solved well enough (refine_enough).
    const bool enough = refining() && refine_ops_->enough(*this);
    const bool capped = run_iterations_ >= iteration_cap();
    if (small || enough || capped || !ratio(rz_, rz_old_, &beta_.mant, &beta_.shift)) {
      // A run that did not halve r.z over all its iterations is at the rounding floor or too
      // slow to be worth more (the stall rule); the finish's early end of a run is neither.
      run_complete_ = !enough;
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
  if (overflowed()) {
    rescale();  // the direction is not to be trusted: no step
    return;
  }
  if (!ratio(rz_, pq_, &alpha_.mant, &alpha_.shift)) {
    restart();
    return;
  }
  rz_old_ = rz_;
  updating_ = true;
  phase_ = Phase::kBackward;
  index_ = 0;
  flow_[0] = flow_[1] = flow_[2] = 0;
}

}  // namespace seqslam
