// The nonlinear finish of the pose graph (pose_graph.h, "Method" item 3): Gauss-Newton on x,
// y and heading together, in the same passes as LAGO's stages but with the linearised
// problem's terms (the levers of the position residuals about their from node's heading, the
// full 3x3 information) and the exact odometry chain of that problem as the preconditioner.
// Its own translation unit, reached through PoseGraph::kRefineOps once enable_refine() has
// been called: an image that never calls it does not link this code.
#include "seqslam/pose_graph.h"

#include "pose_graph_math.h"

namespace seqslam {

using namespace pose_graph_detail;

namespace {

int bit_length_abs(Int128 v) {
  return bit_length(v.negative() ? -v : v);
}

}  // namespace

const PoseGraph::RefineOps PoseGraph::kRefineOps = {
    &PoseGraph::refine_valid,
    &PoseGraph::refine_add_node,
    &PoseGraph::refine_weigh,
    &PoseGraph::refine_difference,
    &PoseGraph::refine_from_share,
    &PoseGraph::refine_chain_backward,
    &PoseGraph::refine_chain_forward,
    &PoseGraph::refine_apply,
    &PoseGraph::refine_heading_residual,
    &radians_to_turns,
    &PoseGraph::refine_judge,
    &PoseGraph::refine_enough,
    &PoseGraph::refine_record_bound,
    &PoseGraph::refine_objective_threshold,
    &PoseGraph::tree_closure,
    &PoseGraph::refine_objective_add,
};

void PoseGraph::enable_refine() {
  refine_ops_ = &kRefineOps;
}

// The certified bound of the current stage (stats_.objective_bound): r.z of the freshly
// recomputed residual in check() (true value rz_ 2^(2 scale_)) in the objective's units, UQ32.32
// rounded up, saturating: positions and the finish rz 2^-64 (2^-32 m or rad squared), headings
// rz 4 pi^2 2^-80 (2^-40 turn squared).
void PoseGraph::refine_record_bound(PoseGraph& g) {
  constexpr uint64_t kRad2PerTurn2 = 2649351758;  // ceil(4 pi^2 2^26)
  const bool headings = g.stage_ == PoseGraphStage::kHeadings;
  Int128 v = g.rz_.negative() ? Int128(0) : g.rz_;
  int shift = 2 * static_cast<int>(g.scale_) - 32;  // Q32.32 of rz 2^(2 scale) 2^-64
  uint64_t out = ~uint64_t{0};
  if (headings) {
    shift -= 42;                         // x 2^26 more in the constant, and 2^-16 more in the unit
    if (bit_length(v) > 94) shift = 64;  // saturates below
    v = v * Int128::from_u64(kRad2PerTurn2);
  }
  if (shift < 0) {
    const Int128 q = v.sar(-shift);
    const Int128 up = q.shl(-shift) == v ? q : q + Int128(1);
    if (up.high64() == 0) out = up.low64();
  } else if (bit_length(v) + shift <= 64) {
    out = v.shl(shift).low64();
  }
  g.stats_.objective_bound[headings ? 0 : g.refining() ? 2 : 1] = out;
}

// The objective's tolerance ("Stopping", PoseGraphConfig::tolerance_objective): r.z of a fresh
// residual bounds the stage objective's excess over its minimum; in raw units at scale 0 the
// excess times 2^64 (2^-32 m or rad squared), the headings' (2^-40 turn squared) the excess in
// rad^2 times 2^80 / (4 pi^2), rounded down. The stage's threshold is the larger of it and the
// position or heading test's.
void PoseGraph::refine_objective_threshold(PoseGraph& g) {
  constexpr uint64_t kTurn2PerRad2 = 7129844451505;  // floor(2^48 / (4 pi^2))
  const int64_t d = g.config_.tolerance_objective.raw();
  const Int128 objective = g.stage_ == PoseGraphStage::kHeadings
                               ? Int128::mul_u64(static_cast<uint64_t>(d), kTurn2PerRad2)
                               : Int128(d).shl(32);
  if (objective > g.threshold_) g.threshold_ = objective;
}

// A CG run of the finish ends early (an inexact Gauss-Newton step: solving further a system
// that is itself an approximation gains nothing) once r.z is 2^-20 of the fresh one, or a
// quarter of the stage's threshold (the remaining decrease of the linearised objective is then
// below what the next fresh residual is tested against).
bool PoseGraph::refine_enough(PoseGraph& g) {
  return scaled_le(g.rz_, g.scale_, g.fresh_rz_.sar(20), g.fresh_scale_) ||
         g.rz_ <= g.threshold_.sar(static_cast<int>(2 * g.scale_) + 2);
}

// The inverse of the 3x3 information (the odometry edge's covariance, for the nonlinear
// finish's chain preconditioner) as cov * 2^-cov_shift with the largest |cov| in [2^29, 2^31):
// the adjugate over the determinant (raw UQ16.16 entries: adj / det = covariance / 2^16).
// False unless positive definite.
bool PoseGraph::refine_covariance(const PoseGraphEdge& e, PoseGraphRefineSlot* out) {
  const Int128 a(static_cast<int64_t>(e.info_xy.raw()));
  const Int128 l(static_cast<int64_t>(e.info_lateral.raw()));
  const Int128 h(static_cast<int64_t>(e.info_heading.raw()));
  const Int128 c(static_cast<int64_t>(e.info_cross.raw()));
  const Int128 p(static_cast<int64_t>(e.info_along_heading.raw()));
  const Int128 q(static_cast<int64_t>(e.info_lateral_heading.raw()));
  const Int128 adj[6] = {l * h - q * q, p * q - c * h, c * q - l * p,
                         a * h - p * p, c * p - a * q, a * l - c * c};
  const Int128 det = a * adj[0] + c * adj[1] + p * adj[2];  // < 2^98
  if (det <= Int128(0)) return false;
  int largest = 0;
  for (const Int128& v : adj) {
    const int b = bit_length_abs(v);
    if (b > largest) largest = b;
  }
  // |adj| < 2^largest, det >= 2^(bit_length(det) - 1): |adj| 2^k / det < 2^30 for this k.
  const int k = 29 - largest + bit_length(det);
  if (k < 0 || k + largest > 125) return false;
  for (int i = 0; i < 6; ++i)
    out->cov[i] = static_cast<int32_t>(adj[i].shl(k).div(det).low64_signed());
  out->cov_shift = k - 16;  // covariance = cov 2^(16 - k)
  return true;
}

// The nonlinear finish's lever J a: the derivative of the edge's global position residual
// with respect to its `from` node's heading is -J (p_to - p_from), J the quarter turn; c 0: x,
// 1: y (Q31.32 metres).
int64_t PoseGraph::refine_lever(const PoseGraph& g, const PoseGraphEdge& e, uint32_t c) {
  const PoseGraphNode& a = g.buffers_.nodes[e.from];
  const PoseGraphNode& b = g.buffers_.nodes[e.to];
  return c == 0 ? sub_sat(a.y.raw(), b.y.raw()) : sub_sat(b.x.raw(), a.x.raw());
}

// The heading residual (the measured turn minus the estimated one, Q0.64 turns, the short way)
// in the finish's unit, 2^-32 rad, at the current scale.
int64_t PoseGraph::refine_heading_residual(const PoseGraph& g, uint64_t turn) {
  return shift_down(turns_to_radians(static_cast<int64_t>(turn)), g.scale_);
}

// The finish's W_e v: the edge's 3x3 information (its position block turned into the global
// frame by the from node's heading, LAGO's weigh_edge; the heading weight; the
// position-heading terms) times (x, y, heading).
PoseGraph::Vec PoseGraph::refine_weigh(const PoseGraph& g, const PoseGraphEdge& e, Vec v) {
  const uint32_t along = e.info_xy.raw();
  const uint32_t lateral = e.info_lateral.raw();
  const int32_t cross = e.info_cross.raw();
  const int32_t ph = e.info_along_heading.raw();
  const int32_t qh = e.info_lateral_heading.raw();
  const uint32_t m = along < lateral ? along : lateral;
  Vec t{{weigh(v.v[0], m), weigh(v.v[1], m), weigh(v.v[2], e.info_heading.raw())}};
  if (along == lateral && cross == 0 && ph == 0 && qh == 0) return t;
  const SinCos sc = sincos(g.heading(e.from));
  // u = (c, s) along the heading, w = (-s, c) across it.
  const int64_t va = add_sat(mul_q30(v.v[0], sc.cos), mul_q30(v.v[1], sc.sin));
  const int64_t vw = sub_sat(mul_q30(v.v[1], sc.cos), mul_q30(v.v[0], sc.sin));
  int64_t ka = along > m ? weigh(va, along - m) : 0;
  int64_t kw = lateral > m ? weigh(vw, lateral - m) : 0;
  ka = add_sat(ka, add_sat(weigh_signed(vw, cross), weigh_signed(v.v[2], ph)));
  kw = add_sat(kw, add_sat(weigh_signed(va, cross), weigh_signed(v.v[2], qh)));
  t.v[2] = add_sat(t.v[2], add_sat(weigh_signed(va, ph), weigh_signed(vw, qh)));
  t.v[0] = add_sat(t.v[0], sub_sat(mul_q30(ka, sc.cos), mul_q30(kw, sc.sin)));
  t.v[1] = add_sat(t.v[1], add_sat(mul_q30(ka, sc.sin), mul_q30(kw, sc.cos)));
  return t;
}

// J_e p: the position difference less the lever times the from node's heading component, and
// the heading difference.
PoseGraph::Vec PoseGraph::refine_difference(PoseGraph& g, const PoseGraphEdge& e) {
  Vec d{{0, 0, 0}};
  for (uint32_t c = 0; c < 3; ++c)
    d.v[c] = g.checked(sub_sat(g.vp_of(e.to, c), g.vp_of(e.from, c)));
  const int64_t h = g.vp_of(e.from, 2);
  for (uint32_t c = 0; c < 2; ++c)
    d.v[c] = g.checked(sub_sat(d.v[c], mul_q32(refine_lever(g, e, c), h)));
  return d;
}

// What the edge's term t takes from its `from` node: t, and the lever's share of it in the
// heading component, (J a)^T t.
PoseGraph::Vec PoseGraph::refine_from_share(const PoseGraph& g, const PoseGraphEdge& e, Vec t) {
  t.v[2] = add_sat(t.v[2], add_sat(mul_q32(refine_lever(g, e, 0), t.v[0]),
                                   mul_q32(refine_lever(g, e, 1), t.v[1])));
  return t;
}

// The chain preconditioner's first half at node k (kBackward, nodes descending): the flow
// (force and torque) from the nodes beyond k is carried across the edge k -> k+1 (its lever
// adds a torque), node k's residual joins it, and the edge into k takes the share its
// covariance gives: z_k = C_k flow, C_k = diag(R, 1) Sigma diag(R^T, 1), the covariance of the
// odometry edge into k (in its from frame) turned into the global frame.
void PoseGraph::refine_chain_backward(PoseGraph& g, uint32_t k) {
  if (g.config_.tree_preconditioner) {
    tree_backward(g, k);
    return;
  }
  int64_t* flow = g.flow_;
  if (k + 1 < g.solve_nodes_) {
    const PoseGraphEdge& next = g.buffers_.edges[k];
    flow[2] = add_sat(flow[2], add_sat(mul_q32(refine_lever(g, next, 0), flow[0]),
                                       mul_q32(refine_lever(g, next, 1), flow[1])));
  }
  for (uint32_t c = 0; c < 3; ++c)
    flow[c] = g.checked(add_sat(flow[c], g.vr(k, c)));
  refine_spread(g, k, k - 1, flow);
}

// z_k = C_k flow: the covariance of node k's preconditioner edge (from `parent`, in its frame)
// turned into the global frame by the parent's heading.
void PoseGraph::refine_spread(PoseGraph& g, uint32_t k, uint32_t parent, const int64_t flow[3]) {
  const PoseGraphRefineSlot& s = g.buffers_.refine[k];
  const SinCos sc = sincos(g.heading(parent));
  const int64_t f[3] = {add_sat(mul_q30(flow[0], sc.cos), mul_q30(flow[1], sc.sin)),
                        sub_sat(mul_q30(flow[1], sc.cos), mul_q30(flow[0], sc.sin)), flow[2]};
  static constexpr int kIndex[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  int64_t y[3];
  for (int i = 0; i < 3; ++i) {
    Int128 acc(0);
    for (int j = 0; j < 3; ++j)
      multiply_add(&acc, s.cov[kIndex[i][j]], f[j]);
    y[i] = detail::saturate<int64_t>(detail::shift_round(acc, s.cov_shift));
  }
  g.vz(k, 0) = g.checked(sub_sat(mul_q30(y[0], sc.cos), mul_q30(y[1], sc.sin)));
  g.vz(k, 1) = g.checked(add_sat(mul_q30(y[0], sc.sin), mul_q30(y[1], sc.cos)));
  g.vz(k, 2) = g.checked(y[2]);
}

// ---- The tree preconditioner (PoseGraphConfig::tree_preconditioner) ------------------------
//
// Node k's edge in the spanning tree joins it to parent < k: the odometry edge into k, or a
// loop closure from an older node to k whose position information is at least as stiff
// (variance no larger; ties to the closure). Every parent is older than its children, so the
// chain's passes keep their order: kBackward (descending) gathers each node's flow (its
// residual and its children's flows, which they left in its accumulator) and passes it to its
// parent, kForward (ascending) adds the parent's correction. The tree is a subgraph of the
// graph with each edge's own weights (the position weight its smallest eigenvalue), so M <= L
// and the stopping bounds hold with V the tree's variances summed (var_sum_, kept up to date
// here): each node's path to node 0 sums some of them.

// The lever of an edge from a to b (refine_lever with from a, to b).
int64_t PoseGraph::lever_between(const PoseGraph& g, uint32_t a, uint32_t b, uint32_t c) {
  const PoseGraphNode& na = g.buffers_.nodes[a];
  const PoseGraphNode& nb = g.buffers_.nodes[b];
  return c == 0 ? sub_sat(na.y.raw(), nb.y.raw()) : sub_sat(nb.x.raw(), na.x.raw());
}

// The finish's objective, summed by the residual passes (first: the pass's first edge):
// rho^T W rho with the edge term t = W rho checked, as it is not stored.
void PoseGraph::refine_objective_add(PoseGraph& g, const Vec& rho, const Vec& t, bool first) {
  if (first) g.objective_ = Int128(0);
  for (uint32_t c = 0; c < 3; ++c)
    multiply_add(&g.objective_, rho.v[c], g.checked(t.v[c]));
}

// configure()'s checks of what this file adds: the finish's and the tree's buffers, the
// objective's tolerance 0 .. 2^30.
bool PoseGraph::refine_valid(const PoseGraphConfig& c, const PoseGraphBuffers& b) {
  if (c.refine_restarts > 0 && (b.refine.size() < b.nodes.size() || b.refine.data() == nullptr)) {
    return false;
  }
  if (c.tree_preconditioner && (b.tree.size() < b.nodes.size() || b.tree.data() == nullptr)) {
    return false;
  }
  return c.tolerance_objective.raw() >= 0 && c.tolerance_objective.raw() <= (int64_t{1} << 62);
}

// add_node()'s part for node nodes_ >= 1 (odometry edge e into it), before the edge is stored:
// the finish's covariance of the edge (false: the information does not invert), and the
// node's tree edge, the odometry edge (its variances are the solver slot's, set later: they
// are copied here from the edge's information the same way).
bool PoseGraph::refine_add_node(PoseGraph& g, const PoseGraphEdge& e) {
  const uint32_t k = g.nodes_;
  if (!g.buffers_.refine.empty()) {
    PoseGraphRefineSlot& fine = g.buffers_.refine[k];
    fine = PoseGraphRefineSlot{};
    if (!refine_covariance(e, &fine)) return false;
  }
  if (g.config_.tree_preconditioner) {
    PoseGraphTreeSlot& t = g.buffers_.tree[k];
    t = PoseGraphTreeSlot{};
    t.parent = static_cast<uint16_t>(k - 1);
    const int64_t smallest =
        smallest_eigenvalue(e.info_xy.raw(), e.info_lateral.raw(), e.info_cross.raw());
    t.var = variance_of(static_cast<uint32_t>(smallest));
    t.var_heading = variance_of(e.info_heading.raw());
  }
  return true;
}

// Closure j becomes its newer node's tree edge if it joins an older node and is at least as
// stiff as the node's tree edge so far (and, with the finish, its 3x3 information inverts).
void PoseGraph::tree_closure(PoseGraph& g, uint32_t j) {
  const PoseGraphEdge& e = g.closure(j);
  if (e.from >= e.to) return;
  const int64_t smallest =
      smallest_eigenvalue(e.info_xy.raw(), e.info_lateral.raw(), e.info_cross.raw());
  if (smallest < 256 || e.info_heading.raw() < 256) return;
  const uint32_t var = variance_of(static_cast<uint32_t>(smallest));
  PoseGraphTreeSlot& t = g.buffers_.tree[e.to];
  if (var > t.var) return;
  if (!g.buffers_.refine.empty()) {
    PoseGraphRefineSlot fine = g.buffers_.refine[e.to];
    if (!refine_covariance(e, &fine)) return;
    g.buffers_.refine[e.to] = fine;
  }
  const uint32_t var_heading = variance_of(e.info_heading.raw());
  g.var_sum_ = g.var_sum_ - t.var + var;
  g.var_sum_heading_ = g.var_sum_heading_ - t.var_heading + var_heading;
  t.parent = e.from;
  t.var = var;
  t.var_heading = var_heading;
}

// kBackward at node k (after the CG step): its flow, handed on to its parent (in the finish
// with the torque of its lever), and its share z_k = the tree edge's covariance times it.
void PoseGraph::tree_backward(PoseGraph& g, uint32_t k) {
  // An accumulator holds flows of the current pass only: each pass has a number (node 0's
  // `pass`, the anchor having no tree edge), a slot stamped with another pass's number is
  // empty, and a consumed one is emptied. So a pass abandoned half way (a closure added, a
  // failure) leaves nothing behind (unless the same 32-bit number comes round again).
  uint32_t& pass = g.buffers_.tree[0].pass;
  if (k + 1 == g.solve_nodes_) ++pass;
  PoseGraphTreeSlot& t = g.buffers_.tree[k];
  const uint32_t parent = t.parent;
  const uint32_t dim = g.dims();
  const bool mine = t.pass == pass;
  int64_t flow[3] = {0, 0, 0};
  for (uint32_t c = 0; c < dim; ++c) {
    flow[c] = g.checked(mine ? add_sat(t.acc[c], g.vr(k, c)) : g.vr(k, c));
    t.acc[c] = 0;
  }
  if (parent != 0) {
    PoseGraphTreeSlot& p = g.buffers_.tree[parent];
    int64_t* up = p.acc;
    if (p.pass != pass) {
      p.pass = pass;
      up[0] = up[1] = up[2] = 0;
    }
    for (uint32_t c = 0; c < dim; ++c)
      up[c] = g.checked(add_sat(up[c], flow[c]));
    if (g.refining()) {
      up[2] = g.checked(add_sat(up[2], add_sat(mul_q32(lever_between(g, parent, k, 0), flow[0]),
                                               mul_q32(lever_between(g, parent, k, 1), flow[1]))));
    }
  }
  if (g.refining()) {
    refine_spread(g, k, parent, flow);
    return;
  }
  const uint32_t var = g.stage_ == PoseGraphStage::kHeadings ? t.var_heading : t.var;
  for (uint32_t c = 0; c < dim; ++c)
    g.vz(k, c) = g.checked(spread(flow[c], var));
}

// kForward at node k: it moves with its parent (in the finish as a rigid body, its heading
// change swinging k about the parent by the lever).
void PoseGraph::tree_forward(PoseGraph& g, uint32_t k) {
  const uint32_t parent = g.buffers_.tree[k].parent;
  if (parent == 0) return;
  if (!g.refining()) {
    for (uint32_t c = 0; c < g.dims(); ++c)
      g.vz(k, c) = g.checked(add_sat(g.vz(k, c), g.vz(parent, c)));
    return;
  }
  const int64_t h = g.vz(parent, 2);
  for (uint32_t c = 0; c < 2; ++c) {
    g.vz(k, c) = g.checked(
        add_sat(g.vz(k, c), add_sat(g.vz(parent, c), mul_q32(lever_between(g, parent, k, c), h))));
  }
  g.vz(k, 2) = g.checked(add_sat(g.vz(k, 2), h));
}

// The second half at node k >= 2 (kForward, ascending): node k moves with node k-1 as a rigid
// body (its heading change swings k about k-1 by the lever).
void PoseGraph::refine_chain_forward(PoseGraph& g, uint32_t k) {
  if (g.config_.tree_preconditioner) {
    tree_forward(g, k);
    return;
  }
  if (k < 2) return;
  const PoseGraphEdge& e = g.buffers_.edges[k - 1];
  const int64_t h = g.vz(k - 1, 2);
  for (uint32_t c = 0; c < 2; ++c) {
    g.vz(k, c) =
        g.checked(add_sat(g.vz(k, c), add_sat(g.vz(k - 1, c), mul_q32(refine_lever(g, e, c), h))));
  }
  g.vz(k, 2) = g.checked(add_sat(g.vz(k, 2), h));
}

// kApply at node k: the update built by the last CG run (the sum of its steps, at the
// linearisation point it was built for) moves the estimate, or a backtrack takes half of what
// is left of it back (apply_shift_), or delta is cleared (a new stage).
void PoseGraph::refine_apply(PoseGraph& g, uint32_t k) {
  PoseGraphRefineSlot& s = g.buffers_.refine[k];
  for (uint32_t c = 0; c < 3; ++c) {
    if (g.apply_shift_ < 0) {
      s.delta[c] = 0;
    } else if (g.apply_shift_ == 0) {
      if (g.pending_step_ && s.delta[c] != 0) g.move(k, c, s.delta[c]);
    } else {
      g.move(k, c, -(s.delta[c] >> g.apply_shift_));
    }
  }
}

// check() on a fresh residual in the finish: the step it applied is judged by the objective
// (worse, and half of it is taken back, up to 8 times; no better after that, and the estimate
// is at the floor: the stage ends). False when check() is to stop there.
bool PoseGraph::refine_judge(PoseGraph& g, bool small) {
  if (g.step_applied_) {
    const bool worse = !scaled_le(g.objective_, g.scale_, g.accepted_objective_, g.accepted_scale_);
    if (worse && g.backtracks_ < 8) {
      ++g.backtracks_;
      g.apply_shift_ = static_cast<int32_t>(g.backtracks_);
      g.phase_ = Phase::kApply;
      g.index_ = 1;
      return false;
    }
    g.step_applied_ = false;
    if (worse) {
      ++g.stats_.stalls;
      g.finish_stage();
      return false;
    }
  }
  g.accepted_objective_ = g.objective_;
  g.accepted_scale_ = g.scale_;
  g.backtracks_ = 0;
  if (!small && g.stage_restarts_ > g.config_.refine_restarts) {
    ++g.stats_.stalls;  // out of relinearisations
    ++g.stats_.exhausted;
    g.finish_stage();
    return false;
  }
  // The finish's CG vectors grow over a run (the levers of long closures turn forces into
  // large torques): start it with 7 bits to spare rather than lose it half way.
  if (g.peak_ > (static_cast<uint64_t>(kVectorLimit) >> 7) && !small) {
    g.rescale();
    return false;
  }
  return true;
}

}  // namespace seqslam
