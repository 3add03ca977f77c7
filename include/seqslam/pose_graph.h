// A fixed-capacity 2-D pose graph and its optimiser, in fixed point (issue 7, "From
// localisation to SLAM", items 1 and 3; issue 35: limits, information, nonlinear finish).
//
// Nodes are places (an odometry pose each, plus the caller's place index); an odometry edge
// joins each node to the one before it, loop-closure edges join recognised places. Every edge
// holds the pose of its `to` node seen from its `from` node (dx along from's heading, dy to
// its left, dtheta) and its information, a symmetric 3x3 matrix in from's frame
// (PoseInformation: the data's own, e.g. a g2o file's; or the explorer's, a position weight
// made weaker across the route by closure_lateral and a heading weight).
//
// Method: the two-stage linear approximation of LAGO (Carlone et al., 2012), chosen because
// both stages are *linear* least-squares problems over the graph Laplacian, which suit fixed
// point and can be cut into slices of bounded work:
//  1. Headings: minimise sum_e w_e^h (theta_to - theta_from - dtheta_e)^2 over the node
//     headings, node 0 fixed. Each residual is taken modulo a full turn against the current
//     estimate (headings wrap by integer overflow), which unwraps a loop closure's measurement
//     against the odometry chain as corrected so far; this is right as long as no closure is
//     off by more than half a turn.
//  2. Positions given those headings: minimise sum_e r_e^T W_e r_e, r_e = p_to - p_from -
//     R(theta_from) d_e (node 0 fixed), W_e = R(theta_from) Omega_e R(theta_from)^T with
//     Omega_e the edge's position block. The explorer's odometry weighs all directions alike;
//     its closures weigh the direction across their `from` node's heading less than the one
//     along it (f = PoseGraphConfig::closure_lateral): image matching says where along the
//     route two passes meet, not how far apart side by side they ran. One coupled system for
//     x and y.
//  3. Optionally (refine_restarts > 0) the nonlinear finish: Gauss-Newton on the full problem
//     min sum_e e^T Omega_e e, e = (R(theta_from)^T (p_to - p_from) - d, theta_to -
//     theta_from - dtheta), x, y and heading together, from LAGO's solution: LAGO's objective
//     is 1-2 % above the optimum on most public graphs and 26-57 % on strongly nonlinear
//     ones (manhattanOlson3500, MIT; docs/mapping.md, "Public pose graphs").
// Each system is solved by preconditioned conjugate gradients warm-started from the current
// estimate. LAGO's preconditioner is the odometry chain itself (the graph's spanning path,
// solved exactly in two passes: suffix sums, then prefix sums, weighted by the chain's
// variances), so the preconditioned matrix is the identity plus one rank-one term per loop
// closure and component (and per anisotropic odometry edge in the position stage: the chain
// weighs every direction by the edge's smallest eigenvalue): in exact arithmetic CG ends after
// at most that many iterations plus one whatever the loop length, where Gauss-Seidel on a
// 450-node chain needs tens of thousands of sweeps. (On the 457-node test loop with 3
// closures: 3, 5 and 5 iterations, 26 081 work units in all.) The finish's preconditioner is
// the exact odometry chain of the linearised problem: the flow of forces and torques from the
// chain's end (each edge's lever turning forces into torque), each edge's 3x3 covariance, and
// the rigid motion of everything after a node back along the chain. Each relinearisation's CG
// run ends when its r.z is 2^-20 of the fresh one or a quarter of the stage's threshold (an
// inexact Gauss-Newton step), and a step
// that raises the objective (summed in the residual pass) is halved, up to 8 times.
//
// Error bound (LAGO). The chain variance of each node is 1 / the smallest eigenvalue of the
// odometry edge's position information (and 1 / its heading information), rounded up so that
// the preconditioner M <= L, the system matrix. For any estimate x with residual r and
// z = M^-1 r, the error against the exact least-squares solution x* is max_i |x_i - x*_i| <=
// sqrt(V r.z), V the sum of the chain variances (e^T M e <= r^T M^-1 r because M <= L;
// Cauchy-Schwarz along the chain). A stage ends when this bound, from a freshly recomputed
// residual, is at most its tolerance. So headings are within tolerance_heading of the exact
// solution of the stored problem, and positions within tolerance_xy + tolerance_heading *
// (the summed length of all edges) (a heading error e moves each measurement by at most e
// |d|, and by the maximum principle a unit change of one measurement moves no position by more
// than one unit). Defaults on the 91 m test loop: 3.7e-7 rad (2.1e-5 degrees) and 44
// micrometres; measured against a double-precision direct solve: 1.5e-7 degrees and 0.1
// micrometres. The bound grows with V: on a 5 km route (V = 5 000 m) a millimetre needs r.z
// below 2e-10 m^2, under the rounding floor, where the stall rule ends the stage (its actual
// error: 2 micrometres, test PoseGraph.TenThousandPosesOverAHundredMetres). The rounding floor
// comes from rounding the estimates at the closures' ends, amplified by the chain between
// them: about 1.5e-8 rad and 0.4 micrometres on the test loop, growing with the loop length
// and the square root of the number of closures. A stage whose freshly recomputed residual
// does not halve over a whole CG run ends there (a "stall" in the statistics: the tolerance
// was not certified; the estimate is the best the arithmetic reached). The finish ends when
// its fresh r.z meets the position test (or the objective's, below), when no halving of a step
// lowers the objective (a stall), or after refine_restarts relinearisations (a stall).
//
// Stopping (issue 35). The position and heading tests above need r.z below tolerance^2 / V,
// and V grows with the route: on graphs of thousands of poses that is under the rounding floor
// and every stage ended by the stall rule. A second, certified test the arithmetic reaches:
// for any M <= L, r.z = r^T M^-1 r >= r^T L^-1 r = e^T L e, the stage objective's excess over
// its exact minimum (the quadratic's, x = x* + e). So a stage ends once a freshly recomputed
// r.z is at most PoseGraphConfig::tolerance_objective (in the objective's units), and the
// position bound follows as sqrt(V r.z); in the finish r.z bounds the decrease the
// Gauss-Newton model still offers at the current estimate. Each stage records the r.z it ended
// with (PoseGraphStats::objective_bound: the certified bound, whichever rule ended it), and
// the statistics say which rule: tolerance_stops (certified within the tolerance), stalls
// (not: at the rounding floor by the halving rule, or the finish at the objective's floor, no
// halving of a step lowering it), of them `exhausted` (out of max_restarts / refine_restarts).
// The halving rule does not apply to the finish, whose fresh residuals belong to different
// linearisations. The objective's test lives with the finish (enable_refine()).
//
// The tree preconditioner (PoseGraphConfig::tree_preconditioner, issue 35). The chain's
// preconditioned matrix is the identity plus a term per closure, so CG needs about as many
// iterations as there are closures (12 630 on manhattanOlson3500). With the option, node k's
// preconditioner edge is the stiffest of its odometry edge and the loop closures from an older
// node to k (the smaller variance of the position information's smallest eigenvalue; ties to
// the closure), chosen as the edges arrive: a spanning tree whose every parent is older than
// its child, so the passes keep the chain's order and cost, children handing their flows to
// their parent through a per-node accumulator (PoseGraphTreeSlot, 40 bytes a node). It is a
// subgraph with each edge's own weights, so M <= L still holds and V is its variances summed.
// The finish carries the torque of each tree edge's lever, as the chain does. Closures from
// the newer node to the older one are not used (MIT's: its tree is its chain). Measured in
// docs/mapping.md ("Public pose graphs"): 7x less work on intel and manhattanOlson3500; on
// graphs whose closures are weaker than their odometry the tree is the chain.
//
// Limits (issue 35). What is proven, by construction: no overflow goes unseen. Every value
// stored in a CG vector, every edge term and every residual is checked against 2^53 (so each
// of the at most 3 x 65 535 products of an inner product is below 2^106 and the 128-bit sums
// cannot wrap; the saturating operations clip at 2^63, far beyond the check). A value beyond
// it abandons the CG run (no step is taken from a direction that overflowed; steps already
// taken were valid) and repeats it from a recomputed residual with the vectors scaled down by
// 2^scale, scale what the largest value seen needs plus two bits (stats: rescales, max_scale;
// each recomputation starts again at full resolution). A graph that needs more than
// max_scale bits (48 by default), or whose estimates would leave +-2^30 m, ends in kFailed:
// optimise_step returns kOutOfRange, never converged, and the estimates keep the last valid
// step. The inputs' own limits are checked when they are added: 65 535 nodes and edges, steps
// below 128 m along each axis (Q7.24), information UQ16.16 (up to 65 535, resolution 2^-16;
// odometry eigenvalues and heading at least 1/256). Within them, whether a graph needs more
// than 48 bits depends on the data, not on a size alone (the preconditioned residual grows
// with the chain's variance times the residual's sum); measured: the public graphs need at
// most 27 bits (MIT, 808 nodes; manhattanOlson3500 20, intel 17) and a 10 000-pose, 5 km
// route over 120 m 17 bits, so 21 bits or more are left. At scale s the residual is rounded
// to 2^(s-1) raw units per term, which the stopping bound inherits.
//
// Incremental use. add_node() places the new node at its predecessor's current estimate
// composed with the odometry step: for a leaf this is the exact optimum of every stage, so a
// converged graph stays converged while the robot drives. A node added while a stage is in
// progress stays a leaf outside the system being solved, and the end of each stage places
// such leaves again from their (moved) predecessors before the next stage starts with them,
// so the solve keeps its progress however often nodes arrive. add_loop_closure() restarts
// the solve at the heading stage, warm-started from the current estimates; if a CG step is
// half applied at that moment, the step is completed first (an abandoned step would leave the
// estimate torn between moved and unmoved nodes).
//
// Bounded work: optimise_step(budget) performs at most `budget` work units and returns. A unit
// is one node visited in a pass, one loop closure visited in a pass, or one scalar step of CG
// (step length, or direction and stopping test: a 64/32-bit division and a few 128-bit
// additions; the one that finishes a stage also starts the next: two 64-bit divisions more).
// Each unit's cost is bounded: node units of a residual recomputation in the position stage
// are the dearest (a sincos each, and x and y together); closure units of the position stage
// take a sincos more when closures are anisotropic; the finish's units do x, y and heading
// with a lever each. One CG iteration is 3 node passes, 2 closure passes and 2 scalar steps; a
// residual recomputation (at the start of a stage and to confirm convergence) 3 node passes,
// 1 closure pass and 1 scalar step (the finish: one node pass more, applying its update). The
// work of a stage is bounded by max_restarts x (iterations per run + 1) x (3 nodes + 2
// closures + 2) units, the run capped by max_iterations (0: what exact arithmetic needs,
// which grows with the closures) and ended early by the tolerance or the stall rule. The
// instruction counts on the RV32IMC target are in docs/performance.md (make bench).
//
// Number formats:
// - Estimates: x, y Q31.32 metres; heading Q0.64 turns (the node's binary angle and 32 more
//   bits in the solver slot), pose() returns it rounded to a binary angle.
// - Edge measurements: dx, dy Q7.24 metres (|d| < 128 m, rounding 3e-8 m), dtheta a binary
//   angle in (-half turn, half turn].
// - Information UQ16.16 (the off-diagonal terms Q15.16). The explorer's: relative to 1 m of
//   odometry travel: an odometry edge that moved d metres gets 1 m / max(d, min_travel) in
//   every part; a loop closure weighted 20 is as certain as 5 cm of odometry (only ratios
//   matter within each LAGO stage). The data's (PoseInformation): per square metre and square
//   radian times one common factor (the finish weighs position against heading). Chain
//   variances UQ8.24 (a step below 128 sqrt(2) m has information above 1/182).
// - Solver vectors int64 in 2^-32 m (positions), 2^-40 turn (LAGO's headings: 8 guard bits
//   below a binary angle) or 2^-32 rad (the finish's headings), divided by 2^scale (above);
//   residuals are weighted by info / 2^16; inner products are exact 128-bit sums; CG's step
//   and direction scalars carry 32 significant bits (relative error 2^-31). Products round to
//   nearest and saturate, and every stored value is checked ("Limits").
//
// Memory (caller-owned, see PoseGraphStorage): 24 bytes per node, 40 per edge, 64 per node of
// solver state (three int64 CG vectors for x and y, the heading stage using the x half; the
// chain variances, the heading's low bits); the finish another 80 per node
// (PoseGraphRefineStorage: the heading components, the update, the chain covariance). 512
// nodes and 600 edges: 69 056 bytes (+40 960 with the finish); the tree preconditioner 40 per
// node more (PoseGraphTreeStorage: its parent, variances and flow accumulator). Edges fill the
// edge array from both ends: odometry edge k-1 (node k-1 to k) at index k-1, loop closures
// from the last element downwards, so a closure never reshuffles the chain and both share one
// capacity.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/fixmath.h"
#include "seqslam/odometry.h"
#include "seqslam/span.h"
#include "seqslam/state_io.h"
#include "seqslam/status.h"

namespace seqslam {

// Relative positions of graph edges, metres: |value| < 128, resolution 2^-24 m (6e-8 m).
using Q7_24 = Fixed<int32_t, 24>;

// Node indices are 16-bit.
inline constexpr uint32_t kMaxPoseGraphNodes = 65535;
inline constexpr uint32_t kMaxPoseGraphEdges = 65535;

// The pose of one frame seen from another: `dx` along the first frame's heading, `dy` to its
// left (metres), `dtheta` the second heading minus the first.
struct RelativePose2 {
  Q31_32 dx;
  Q31_32 dy;
  Angle dtheta;
};

// from^-1 * to: where `to` is, seen from `from` (both in the same frame). Rotation by sincos()
// (error 1e-9), products rounded to Q31.32 and saturating.
RelativePose2 relative_pose(const Pose2& from, const Pose2& to);
// from * rel: the pose `rel` describes, in from's frame. The inverse of relative_pose() to
// within a few 2^-32 m times the distance in metres.
Pose2 compose(const Pose2& from, const RelativePose2& rel);

// One node: the current estimate of the place's pose and the caller's place index.
struct PoseGraphNode {
  Q31_32 x;
  Q31_32 y;
  Angle heading;
  uint32_t place;
};

// One edge: the measured pose of `to` in the frame of `from` and its information, a symmetric
// 3x3 matrix in `from`'s frame (along its heading, across it, heading):
// [[info_xy, info_cross, info_along_heading], [., info_lateral, info_lateral_heading],
//  [., ., info_heading]], positive semi-definite (add_node / add_loop_closure check it).
struct PoseGraphEdge {
  uint16_t from;
  uint16_t to;
  Q7_24 dx;
  Q7_24 dy;
  Angle dtheta;                 // signed_diff(dtheta, Angle{}) is the measured turn
  UQ16_16 info_xy;              // position information along from's heading (see PoseInformation)
  UQ16_16 info_heading;         // heading information
  UQ16_16 info_lateral;         // position information across from's heading
  Q15_16 info_cross;            // the off-diagonal term
  Q15_16 info_along_heading;    // position-heading terms of the full 3x3 information (used by
  Q15_16 info_lateral_heading;  // the nonlinear finish only; LAGO's stages are separable)
};

// Per-node solver state (opaque to callers; in the storage so the optimiser has no
// hidden memory): the conjugate-gradient vectors and the chain preconditioner's variances.
struct PoseGraphSolverSlot {
  int64_t r[2];          // residual (x, y; headings: [0])
  int64_t p[2];          // search direction
  int64_t z[2];          // preconditioned residual, or the product with the direction
  uint32_t var;          // position: 1 / (smallest eigenvalue of the odometry edge's
                         // position information), UQ8.24, rounded up
  uint32_t var_heading;  // heading: 1 / its heading information, UQ8.24, rounded up
  uint32_t heading_low;  // the heading's Q0.64 fraction below the node's binary angle
  uint32_t reserved;     // 0 (keeps the slot free of padding)
};

// Per-node state of the nonlinear finish (PoseGraphConfig::refine_restarts; optional buffer):
// the heading component of the CG vectors, the Gauss-Newton update being built, and the
// covariance of the odometry edge into the node (its 3x3 information inverted, in the edge's
// `from` frame: the finish's chain preconditioner), xx xy xt yy yt tt, value cov * 2^-cov_shift.
struct PoseGraphRefineSlot {
  int64_t r;
  int64_t p;
  int64_t z;
  int64_t delta[3];  // x, y (2^-32 m), heading (2^-32 rad)
  int32_t cov[6];
  int32_t cov_shift;
  int32_t reserved;  // 0 (keeps the slot free of padding)
};

// Per-node state of the tree preconditioner (PoseGraphConfig::tree_preconditioner; optional
// buffer): node k's edge in the preconditioner's spanning tree joins it to `parent` < k, the
// stiffest of the odometry edge into k and the loop closures from an older node to k (ties go
// to the closure); its variances (as PoseGraphSolverSlot's, of that edge); and the flow that
// k's children in the tree pass to it during a preconditioner pass.
struct PoseGraphTreeSlot {
  uint16_t parent;
  uint16_t reserved;     // 0 (keeps the slot free of padding)
  uint32_t var;          // 1 / the smallest eigenvalue of the edge's position information, UQ8.24
  uint32_t var_heading;  // 1 / its heading information, UQ8.24
  uint32_t pass;         // the preconditioner pass that wrote acc (node 0: the current pass)
  int64_t acc[3];        // x, y, heading (LAGO's headings: [0])
};

template <class Io>
void persist(Io& io, PoseGraphNode& n) {
  io.field(n.x);
  io.field(n.y);
  io.field(n.heading);
  io.field(n.place);
}
template <class Io>
void persist(Io& io, PoseGraphEdge& e) {
  io.field(e.from);
  io.field(e.to);
  io.field(e.dx);
  io.field(e.dy);
  io.field(e.dtheta);
  io.field(e.info_xy);
  io.field(e.info_heading);
  io.field(e.info_lateral);
  io.field(e.info_cross);
  io.field(e.info_along_heading);
  io.field(e.info_lateral_heading);
}
template <class Io>
void persist(Io& io, PoseGraphSolverSlot& s) {
  for (int c = 0; c < 2; ++c) {
    io.field(s.r[c]);
    io.field(s.p[c]);
    io.field(s.z[c]);
  }
  io.field(s.var);
  io.field(s.var_heading);
  io.field(s.heading_low);
  io.field(s.reserved);
}
template <class Io>
void persist(Io& io, PoseGraphRefineSlot& s) {
  io.field(s.r);
  io.field(s.p);
  io.field(s.z);
  for (int c = 0; c < 3; ++c)
    io.field(s.delta[c]);
  for (int c = 0; c < 6; ++c)
    io.field(s.cov[c]);
  io.field(s.cov_shift);
  io.field(s.reserved);
}

template <class Io>
void persist(Io& io, PoseGraphTreeSlot& s) {
  io.field(s.parent);
  io.field(s.reserved);
  io.field(s.var);
  io.field(s.var_heading);
  io.field(s.pass);
  for (int c = 0; c < 3; ++c)
    io.field(s.acc[c]);
}

static_assert(sizeof(PoseGraphNode) == 24, "pose graph node budget: 24 bytes");
static_assert(sizeof(PoseGraphTreeSlot) == 40, "pose graph tree slot budget: 40 bytes");
static_assert(sizeof(PoseGraphEdge) == 40, "pose graph edge budget: 40 bytes");
static_assert(sizeof(PoseGraphSolverSlot) == 64, "pose graph solver slot budget: 64 bytes");
static_assert(sizeof(PoseGraphRefineSlot) == 80, "pose graph refine slot budget: 80 bytes");

struct PoseGraphBuffers {
  Span<PoseGraphNode> nodes;           // node capacity N, 1..kMaxPoseGraphNodes
  Span<PoseGraphEdge> edges;           // edge capacity, 0..kMaxPoseGraphEdges (odometry + closures)
  Span<PoseGraphSolverSlot> solver;    // >= N
  Span<PoseGraphRefineSlot> refine{};  // >= N with refine_restarts > 0; may be left out
  Span<PoseGraphTreeSlot> tree{};      // >= N with tree_preconditioner; may be left out
};

// Storage for up to kNodes nodes and kEdges edges (odometry edges count: a chain of kNodes
// nodes needs kNodes - 1), for static allocation: `static PoseGraphStorage<512, 600> storage;`.
template <uint32_t kNodes, uint32_t kEdges>
struct PoseGraphStorage {
  static_assert(kNodes > 0 && kNodes <= kMaxPoseGraphNodes, "bad pose graph node capacity");
  static_assert(kEdges > 0 && kEdges <= kMaxPoseGraphEdges, "bad pose graph edge capacity");
  static constexpr size_t kBytes = (sizeof(PoseGraphNode) + sizeof(PoseGraphSolverSlot)) * kNodes +
                                   sizeof(PoseGraphEdge) * kEdges;
  PoseGraphNode nodes[kNodes];
  PoseGraphEdge edges[kEdges];
  PoseGraphSolverSlot solver[kNodes];

  PoseGraphBuffers buffers() {
    return {Span<PoseGraphNode>(nodes, kNodes), Span<PoseGraphEdge>(edges, kEdges),
            Span<PoseGraphSolverSlot>(solver, kNodes), Span<PoseGraphRefineSlot>()};
  }
};

// The nonlinear finish's per-node state (PoseGraphConfig::refine_restarts): 80 bytes a node,
// set as PoseGraphBuffers::refine = slots().
template <uint32_t kNodes>
struct PoseGraphRefineStorage {
  static_assert(kNodes > 0 && kNodes <= kMaxPoseGraphNodes, "bad pose graph node capacity");
  static constexpr size_t kBytes = sizeof(PoseGraphRefineSlot) * kNodes;
  PoseGraphRefineSlot slot[kNodes];
  Span<PoseGraphRefineSlot> slots() { return Span<PoseGraphRefineSlot>(slot, kNodes); }
};

// The tree preconditioner's per-node state (PoseGraphConfig::tree_preconditioner): 40 bytes a
// node, set as PoseGraphBuffers::tree = slots().
template <uint32_t kNodes>
struct PoseGraphTreeStorage {
  static_assert(kNodes > 0 && kNodes <= kMaxPoseGraphNodes, "bad pose graph node capacity");
  static constexpr size_t kBytes = sizeof(PoseGraphTreeSlot) * kNodes;
  PoseGraphTreeSlot slot[kNodes];
  Span<PoseGraphTreeSlot> slots() { return Span<PoseGraphTreeSlot>(slot, kNodes); }
};

// The explorer's closure information: isotropic position weight (made weaker across the
// route by PoseGraphConfig::closure_lateral) and a heading weight.
struct EdgeInformation {
  UQ16_16 xy;       // position information relative to 1 m of odometry; 0: none
  UQ16_16 heading;  // heading information, same unit; 0: none
};

// An edge's information as the data give it (g2o's 3x3 information matrix): in the `from`
// node's frame, rows and columns along its heading, across it, heading. Units: per square
// metre, per metre radian and per square radian, all scaled by one common factor of the
// caller's choice (LAGO's two stages use only ratios within the position part and within the
// heading; the nonlinear finish weighs position against heading, so there the factor must be
// common). LAGO uses the position block and the heading; the position-heading terms only the
// nonlinear finish. The matrix must be positive semi-definite (checked on the position block
// exactly, on the whole to the check's rounding of 2^-8 of a unit); on an odometry edge the
// position block must be positive definite with eigenvalues, and the heading, of at least
// 1/256 (the chain preconditioner's variances are UQ8.24).
struct PoseInformation {
  UQ16_16 along;
  UQ16_16 lateral;
  Q15_16 cross;
  UQ16_16 heading;
  Q15_16 along_heading;
  Q15_16 lateral_heading;

  // Constructed from at least four values, so that a braced pair still means EdgeInformation
  // in add_loop_closure(a, b, m, {xy, heading}).
  PoseInformation() = default;
  constexpr PoseInformation(UQ16_16 along_, UQ16_16 lateral_, Q15_16 cross_, UQ16_16 heading_,
                            Q15_16 along_heading_ = Q15_16{}, Q15_16 lateral_heading_ = Q15_16{})
      : along(along_),
        lateral(lateral_),
        cross(cross_),
        heading(heading_),
        along_heading(along_heading_),
        lateral_heading(lateral_heading_) {}
};

struct PoseGraphConfig {
  // Odometry edges get information 1 m / max(straight-line step, min_travel), so two nodes at
  // the same spot do not pin each other infinitely hard. 2^-16 m .. 1 m.
  Q31_32 min_travel = Q31_32::from_ratio(1, 100);
  // A position stage ends when its error bound (see above) is at most this. 2^-32 m .. 2^-8 m.
  Q31_32 tolerance_xy = Q31_32::from_ratio(1, 100000);  // 10 micrometres
  // The same for the heading stage: 1 .. 2^24 - 1 binary-angle units (2^-32 turn .. 1.4
  // degrees).
  Angle tolerance_heading = Angle{1u << 8};  // 3.7e-7 rad, 2.1e-5 degrees
  // CG iterations per residual recomputation beyond closures + 1 (what exact arithmetic
  // needs; rounding may need a few more), 1..1000.
  uint16_t extra_iterations = 8;
  // Residual recomputations per stage before the stage is ended anyway (a stall; the halving
  // rule above normally ends a hopeless stage first), 1..1000.
  uint16_t max_restarts = 6;
  // A loop closure's position information across its `from` node's heading, as a fraction of
  // its information along it (0..1; 1: the same in every direction, 0: none across). Applies
  // to closures added with EdgeInformation (the explorer's), not to PoseInformation ones.
  UQ16_16 closure_lateral = UQ16_16::from_int(1);
  // CG iterations per residual recomputation at most (0: closures x components + 1 +
  // extra_iterations, what exact arithmetic may need). A fixed cap makes the work per
  // recomputation linear in the graph; restarted CG still converges. 0..10000.
  uint16_t max_iterations = 0;
  // The nonlinear finish: after LAGO's two stages, Gauss-Newton on the full problem (x, y and
  // heading together; PoseInformation's units), each relinearisation followed by CG on the
  // linearised system; at most this many relinearisations (0: off, LAGO only; 0..1000). Needs
  // PoseGraphBuffers::refine.
  uint16_t refine_restarts = 0;
  // A stage also ends, certified, when its objective is within this of the exact minimum of
  // the stage's problem (LAGO's stages: their linear least-squares objective; the finish: the
  // Gauss-Newton model at the current estimate, i.e. no step could lower the objective's model
  // by more): the bound is r.z of a freshly recomputed residual ("Stopping" above). In the
  // objective's units (sum e^T Omega e with the information as stored: headings in radians,
  // positions in metres), Q31.32, 0 .. 2^30; 0: off (only the position and heading tolerances,
  // the explorer's setting).
  Q31_32 tolerance_objective = Q31_32{};
  // The preconditioner: false, the odometry chain ("Method"); true, a spanning tree of the
  // odometry chain and the loop closures stiffer than it (PoseGraphTreeSlot; "The tree
  // preconditioner" above). Needs PoseGraphBuffers::tree and enable_refine().
  bool tree_preconditioner = false;
  // Bits the CG vectors may be scaled down by to stay within their range (an overflow makes
  // the scale coarser, "Limits"); a graph that needs more fails (kFailed), 0..48. 48 keeps
  // every graph within the documented limits solvable; less refuses rather than loses
  // resolution (and lets a test force the failure).
  uint16_t max_scale = 48;
};

// Which system the optimiser works on.
enum class PoseGraphStage : uint8_t {
  kConverged = 0,  // nothing to do: the estimates solve the current graph
  kHeadings = 1,
  kPositions = 2,  // x and y together
  kRefine = 3,     // the nonlinear finish (Gauss-Newton), x, y and heading together
  kFailed = 4,     // the graph is beyond the arithmetic's limits (see "Limits"); no solution
};

struct PoseGraphProgress {
  uint32_t work = 0;       // units performed by this call, <= budget
  bool converged = false;  // the estimates solve the current graph (stage kConverged)
  PoseGraphStage stage = PoseGraphStage::kConverged;  // the stage after this call
};

// Counters since configure() or reset(); every unit is counted where its work is done.
struct PoseGraphStats {
  uint64_t node_visits = 0;      // node units
  uint64_t closure_visits = 0;   // closure units
  uint64_t scalar_steps = 0;     // scalar units
  uint32_t iterations = 0;       // CG iterations (all stages)
  uint32_t restarts = 0;         // residual recomputations completed (all stages)
  uint32_t stalls = 0;           // stages ended without certifying a tolerance: at the rounding
                                 // floor (the halving rule) or out of restarts (`exhausted`)
  uint32_t exhausted = 0;        // of the stalls, those ended by max_restarts / refine_restarts
  uint32_t tolerance_stops = 0;  // stages ended certified by a tolerance
  // Per stage (0 headings, 1 positions, 2 the finish), at its last end: the certified bound on
  // its objective's excess over the exact minimum of the stage's problem, r.z of the last
  // freshly recomputed residual, in the objective's units (tolerance_objective), UQ32.32,
  // saturating. With V the chain variances' sum (chain_variance_sum()), every heading (stage
  // 0) or position (stage 1) is within sqrt(V bound) of the stage's exact solution.
  uint64_t objective_bound[3] = {0, 0, 0};
  uint32_t solves = 0;            // times the optimiser reached kConverged
  uint32_t rescales = 0;          // CG runs abandoned and repeated at a coarser scale (overflow)
  uint32_t max_scale = 0;         // the coarsest scale used (bits dropped from the CG vectors)
  uint32_t relinearisations = 0;  // residual recomputations of the nonlinear finish
  uint32_t failures = 0;          // times the optimiser ended in kFailed
};
template <class Io>
void persist(Io& io, PoseGraphStats& s) {
  io.field(s.node_visits);
  io.field(s.closure_visits);
  io.field(s.scalar_steps);
  io.field(s.iterations);
  io.field(s.restarts);
  io.field(s.stalls);
  io.field(s.solves);
  io.field(s.rescales);
  io.field(s.max_scale);
  io.field(s.relinearisations);
  io.field(s.failures);
  io.field(s.exhausted);
  io.field(s.tolerance_stops);
  for (int i = 0; i < 3; ++i)
    io.field(s.objective_bound[i]);
}

class PoseGraph {
 public:
  // Validates `config` and adopts it with `buffers` (caller-owned, must outlive the graph),
  // then resets. Returns kInvalidArgument for a node span that is empty or larger than
  // kMaxPoseGraphNodes, an edge span larger than kMaxPoseGraphEdges, a solver span shorter
  // than the node span, a setting outside the documented range, or refine_restarts > 0
  // without a refine buffer of the node span's length or before enable_refine() (nothing
  // changes then).
  Status configure(const PoseGraphConfig& config, const PoseGraphBuffers& buffers);

  // Empties the graph (keeps configuration and buffers). Statistics restart at zero.
  void reset();

  // Appends a node at the odometry pose `odometry` (the odometry's own frame, not corrected)
  // for the caller's place index `place`, and, from the second node on, the odometry edge from
  // the previous node: the step between the two odometry poses, information 1 m / max(step,
  // min_travel). The node's estimate is its predecessor's estimate composed with that step
  // (the first node is the anchor: its estimate is `odometry` and never moves). Returns the new
  // node's index, or:
  //   kFailedPrecondition - not configured;
  //   kResourceExhausted  - the node or edge capacity is full;
  //   kOutOfRange         - the step is 128 m or more along an axis (Q7.24).
  Result<uint32_t> add_node(const Pose2& odometry, uint32_t place);
  // The same with the odometry edge's information as the data give it (PoseInformation; the
  // first node has no edge and ignores it). Also kInvalidArgument for information that is not
  // positive definite with eigenvalues and heading of at least 1/256.
  Result<uint32_t> add_node(const Pose2& odometry, uint32_t place, const PoseInformation& info);

  // Adds a loop closure: node `b` is measured at `b_from_a` seen from node `a` (the identity
  // when the two places were recognised as the same), with information `info` (relative to
  // 1 m of odometry). Returns kOk, or:
  //   kFailedPrecondition - not configured;
  //   kOutOfRange         - a or b is not a node index (>= node_count());
  //   kInvalidArgument    - a == b, or both information weights are 0;
  //   kOutOfRange         - the measured step is 128 m or more along an axis;
  //   kResourceExhausted  - the edge capacity is full.
  // On success the optimiser restarts at the heading stage (from the current estimates).
  Status add_loop_closure(uint32_t a, uint32_t b, const RelativePose2& b_from_a,
                          EdgeInformation info);
  // The same with the information as the data give it: kInvalidArgument also when the position
  // matrix is not positive semi-definite, or it and the heading are both 0.
  Status add_loop_closure(uint32_t a, uint32_t b, const RelativePose2& b_from_a,
                          const PoseInformation& info);

  // Links the nonlinear finish (pose_graph_refine.cpp) into this graph: call it before
  // configure() with refine_restarts > 0 (configure() refuses that setting without it). Kept
  // apart so that an image that never calls it (the explorer's) carries none of its code.
  void enable_refine();

  // Performs at most `budget` work units (see above) of the optimisation and reports where it
  // is. kFailedPrecondition before configure(), kInvalidArgument for a zero budget or a null
  // `out`. With nothing to do it returns at once (work 0, converged). kOutOfRange (with `out`
  // filled: stage kFailed, not converged) when the graph is beyond the limits ("Limits"
  // above): the estimates are then the last valid ones, not a solution; the graph stays failed
  // until a loop closure is added (which tries again) or reset().
  Status optimise_step(uint32_t budget, PoseGraphProgress* out);

  // The current estimate of node i (odometry-composed until optimised); kOutOfRange for
  // i >= node_count().
  Result<Pose2> pose(uint32_t i) const;
  // The place index given to add_node for node i; kOutOfRange for i >= node_count().
  Result<uint32_t> place(uint32_t i) const;
  // Edge i in 0..edge_count()-1: odometry edges first (edge k-1 joins node k-1 to k), then the
  // loop closures in the order added; kOutOfRange otherwise.
  Result<PoseGraphEdge> edge(uint32_t i) const;

  uint32_t node_count() const { return nodes_; }
  uint32_t edge_count() const { return nodes_ > 0 ? nodes_ - 1 + closures_ : closures_; }
  uint32_t closure_count() const { return closures_; }
  uint32_t node_capacity() const { return node_capacity_; }
  uint32_t edge_capacity() const { return edge_capacity_; }
  bool configured() const { return configured_; }
  bool converged() const { return stage_ == PoseGraphStage::kConverged; }
  bool failed() const { return stage_ == PoseGraphStage::kFailed; }
  PoseGraphStage stage() const { return stage_; }
  const PoseGraphConfig& config() const { return config_; }
  const PoseGraphStats& stats() const { return stats_; }
  // V of the error bounds: the chain variances summed, UQ40.24 (1 / information units):
  // positions (1 / the smallest eigenvalue of each odometry edge's position information) or
  // headings.
  uint64_t chain_variance_sum(bool headings) const {
    return headings ? var_sum_heading_ : var_sum_;
  }

  // The nodes, edges, estimates and the optimiser's place inside its stage, to continue a
  // stopped run exactly (state_io.h): only the filled part of the buffers is saved. Configure
  // with the same settings and capacities first; a restored state that does not fit them
  // (counts, edge ends, the optimiser's position) fails the io (kDataLoss) and the graph is
  // reset.
  template <class Io>
  void state(Io& io) {
    io.tag(state_tag("PGR4"));  // PGR3: no objective bounds; PGR2: 24-byte edges, 56-byte
                                // solver slots, no scale
    io.field(stats_);
    io.field(nodes_);
    io.field(closures_);
    if (Io::kReading && !counts_fit()) io.fail();
    if (io.ok()) {
      io.array(buffers_.nodes.subspan(0, nodes_));
      io.array(buffers_.solver.subspan(0, nodes_));
      io.array(buffers_.edges.subspan(0, nodes_ > 0 ? nodes_ - 1 : 0));
      io.array(buffers_.edges.subspan(edge_capacity_ - closures_, closures_));
      if (config_.refine_restarts > 0) io.array(buffers_.refine.subspan(0, nodes_));
      if (config_.tree_preconditioner) io.array(buffers_.tree.subspan(0, nodes_));
    }
    io.field(last_odometry_);
    io.field(var_sum_);
    io.field(var_sum_heading_);
    io.enumeration(stage_, PoseGraphStage::kFailed);
    io.enumeration(phase_, Phase::kLeaves);
    io.field(index_);
    io.field(solve_nodes_);
    io.enumeration(pending_, PoseGraphStage::kRefine);
    io.field(updating_);
    io.field(run_iterations_);
    io.field(stage_restarts_);
    io.field(flow_[0]);
    io.field(flow_[1]);
    io.field(flow_[2]);
    io.field(threshold_);
    io.field(fresh_rz_);
    io.field(rz_);
    io.field(rz_old_);
    io.field(pq_);
    io.field(alpha_.mant);
    io.field(alpha_.shift);
    io.field(beta_.mant);
    io.field(beta_.shift);
    io.field(scale_);
    io.field(peak_);
    io.field(fresh_scale_);
    io.field(rescaled_);
    io.field(apply_shift_);
    io.field(pending_step_);
    io.field(step_applied_);
    io.field(backtracks_);
    io.field(objective_);
    io.field(accepted_objective_);
    io.field(accepted_scale_);
    io.field(run_complete_);
    io.field(anisotropic_);
    if (Io::kReading && io.ok() && !state_valid()) io.fail();
    if (Io::kReading && !io.ok()) reset();
  }

 private:
  enum class Phase : uint8_t {
    kResidualChain,      // restart: r = b - A x from the odometry edges (nodes ascending)
    kResidualClosures,   // restart: the loop closures' part of r
    kBackward,           // (x += alpha p, r -= alpha q,) chain flows F, z = F var (descending)
    kForward,            // z = prefix sums, r.z (ascending)
    kCheck,              // scalar: stop, restart or beta
    kDirectionChain,     // p = z + beta p, q = A p (chain part), p.q (ascending)
    kDirectionClosures,  // q += closures' part, p.q
    kStepLength,         // scalar: alpha = r.z / p.q
    kLeaves,             // stage end: nodes added during it placed from their predecessors
    kApply,              // nonlinear finish, before each residual: x += delta, delta = 0
  };
  // value = mant * 2^-shift (mant 0 or in [2^31, 2^32)).
  struct Scalar {
    uint32_t mant = 0;
    int32_t shift = 0;
  };

  Status add_odometry(const Pose2& odometry, uint32_t place, const PoseInformation* given,
                      uint32_t smallest_given);
  Status add_closure(uint32_t a, uint32_t b, const RelativePose2& b_from_a,
                     const PoseInformation& info);
  bool counts_fit() const;
  bool state_valid() const;
  void start_stage(PoseGraphStage stage);
  void request_restart(PoseGraphStage stage);
  void finish_stage();
  void restart();
  void rescale();
  void fail();
  uint32_t iteration_cap() const;
  uint32_t run_phase(uint32_t budget);
  void apply_deltas(uint32_t count);
  void residual_chain(uint32_t count);
  void residual_closures(uint32_t count);
  void backward(uint32_t count);
  void forward(uint32_t count);
  void direction_chain(uint32_t count);
  void direction_closures(uint32_t count);
  void check();
  void step_length();
  void place_leaf(uint32_t k);
  void place_leaves(uint32_t count);
  // Units of the current pass that fit `budget`: the pass runs index_ .. end - 1.
  uint32_t pass_length(uint32_t end, uint32_t budget) const {
    const uint32_t left = end - index_;
    return left < budget ? left : budget;
  }

  // Stage-dependent views of the data; a vector has dims() components (headings 1, x and y 2,
  // the nonlinear finish 3: x, y, heading).
  struct Vec {
    int64_t v[3];
  };
  uint32_t dims() const {
    return stage_ == PoseGraphStage::kHeadings ? 1u : stage_ == PoseGraphStage::kRefine ? 3u : 2u;
  }
  bool refining() const { return stage_ == PoseGraphStage::kRefine; }
  // Component c of node i's vectors (the third lives in the refine slot).
  int64_t& vr(uint32_t i, uint32_t c) {
    return c < 2 ? buffers_.solver[i].r[c] : buffers_.refine[i].r;
  }
  int64_t& vp(uint32_t i, uint32_t c) {
    return c < 2 ? buffers_.solver[i].p[c] : buffers_.refine[i].p;
  }
  int64_t& vz(uint32_t i, uint32_t c) {
    return c < 2 ? buffers_.solver[i].z[c] : buffers_.refine[i].z;
  }
  int64_t vp_of(uint32_t i, uint32_t c) const {
    return c < 2 ? buffers_.solver[i].p[c] : buffers_.refine[i].p;
  }
  Vec edge_residual(const PoseGraphEdge& e);
  Vec weigh_edge(const PoseGraphEdge& e, Vec v) const;  // W_e v
  Vec difference(const PoseGraphEdge& e);               // J_e p (LAGO: p_to - p_from)
  Vec from_share(const PoseGraphEdge& e, Vec t) const;  // what the `from` node loses

  // The nonlinear finish's own code (pose_graph_refine.cpp), reached through this table so
  // that an image that never calls enable_refine() does not link it (the explorer's).
  struct RefineOps {
    bool (*valid)(const PoseGraphConfig& c, const PoseGraphBuffers& b);  // configure()'s part
    bool (*add_node)(PoseGraph& g, const PoseGraphEdge& e);  // node nodes_'s refine, tree slots
    Vec (*weigh)(const PoseGraph& g, const PoseGraphEdge& e, Vec v);
    Vec (*difference)(PoseGraph& g, const PoseGraphEdge& e);
    Vec (*from_share)(const PoseGraph& g, const PoseGraphEdge& e, Vec t);
    // The finish's chain preconditioner, or the tree's (LAGO and the finish).
    void (*chain_backward)(PoseGraph& g, uint32_t k);  // flow, lever, covariance share
    void (*chain_forward)(PoseGraph& g, uint32_t k);   // node k moves with node k-1 (parent)
    void (*apply)(PoseGraph& g, uint32_t k);           // kApply for node k
    int64_t (*heading_residual)(const PoseGraph& g, uint64_t turn);  // scaled 2^-32 rad
    uint64_t (*heading_step)(int64_t radians);                       // 2^-32 rad to Q0.64 turns
    bool (*judge)(PoseGraph& g, bool small);         // a fresh residual: go on with it?
    bool (*enough)(PoseGraph& g);                    // the finish's CG run may end
    void (*record_bound)(PoseGraph& g);              // stats_.objective_bound of a fresh r.z
    void (*objective_threshold)(PoseGraph& g);       // tolerance_objective into threshold_
    void (*tree_closure)(PoseGraph& g, uint32_t j);  // closure j, stiffer: the tree edge
    void (*objective_add)(PoseGraph& g, const Vec& rho, const Vec& t, bool first);  // e^T W e
  };
  static const RefineOps kRefineOps;
  static bool refine_covariance(const PoseGraphEdge& e, PoseGraphRefineSlot* out);
  static Vec refine_weigh(const PoseGraph& g, const PoseGraphEdge& e, Vec v);
  static Vec refine_difference(PoseGraph& g, const PoseGraphEdge& e);
  static Vec refine_from_share(const PoseGraph& g, const PoseGraphEdge& e, Vec t);
  static void refine_chain_backward(PoseGraph& g, uint32_t k);
  static void refine_chain_forward(PoseGraph& g, uint32_t k);
  static void refine_apply(PoseGraph& g, uint32_t k);
  static bool refine_judge(PoseGraph& g, bool small);
  static bool refine_enough(PoseGraph& g);
  static void refine_record_bound(PoseGraph& g);
  static void refine_objective_threshold(PoseGraph& g);
  static bool refine_valid(const PoseGraphConfig& c, const PoseGraphBuffers& b);
  static bool refine_add_node(PoseGraph& g, const PoseGraphEdge& e);
  static void refine_objective_add(PoseGraph& g, const Vec& rho, const Vec& t, bool first);
  static void tree_closure(PoseGraph& g, uint32_t j);
  static void tree_backward(PoseGraph& g, uint32_t k);
  static void tree_forward(PoseGraph& g, uint32_t k);
  static void refine_spread(PoseGraph& g, uint32_t k, uint32_t parent, const int64_t flow[3]);
  static int64_t lever_between(const PoseGraph& g, uint32_t a, uint32_t b, uint32_t c);
  static int64_t refine_heading_residual(const PoseGraph& g, uint64_t turn);
  static int64_t refine_lever(const PoseGraph& g, const PoseGraphEdge& e, uint32_t c);
  const RefineOps* refine_ops_ = nullptr;
  uint64_t fine(uint32_t i) const;  // node i's heading, Q0.64 turns
  Angle heading(uint32_t i) const;  // rounded to a binary angle
  void move(uint32_t i, uint32_t c, int64_t delta);
  // Every value stored in a CG vector (and every edge term) passes here: the magnitudes are
  // OR-ed into peak_, whose highest bit is the largest value's, so a value at or beyond 2^53
  // is an overflow, caught at the next scalar step (the saturating operations clip at 2^63:
  // nothing wraps unseen). No branch; out of line, as the image's RAM is short of code room.
  int64_t checked(int64_t v);
  bool overflowed() const { return (peak_ >> 53) != 0; }
  uint32_t var(uint32_t i, uint32_t c) const {
    return (stage_ == PoseGraphStage::kHeadings || c == 2) ? buffers_.solver[i].var_heading
                                                           : buffers_.solver[i].var;
  }
  const PoseGraphEdge& closure(uint32_t j) const { return buffers_.edges[edge_capacity_ - 1 - j]; }

  PoseGraphConfig config_{};
  PoseGraphBuffers buffers_{};
  PoseGraphStats stats_{};
  uint32_t node_capacity_ = 0;
  uint32_t edge_capacity_ = 0;
  uint32_t nodes_ = 0;
  uint32_t closures_ = 0;
  Pose2 last_odometry_{};         // the odometry pose of the last node (for the next step)
  uint64_t var_sum_ = 0;          // V: the position chain variances summed, UQ8.24
  uint64_t var_sum_heading_ = 0;  // the same for the heading chain
  // Optimiser state.
  PoseGraphStage stage_ = PoseGraphStage::kConverged;
  Phase phase_ = Phase::kResidualChain;
  uint32_t index_ = 0;        // position inside the current pass
  uint32_t solve_nodes_ = 0;  // nodes in the system being solved (nodes_ at the restart)
  // A restart asked for while a CG step was half applied (the stage to restart, kConverged:
  // none); it happens when kBackward has applied the step to every node.
  PoseGraphStage pending_ = PoseGraphStage::kConverged;
  bool updating_ = false;        // kBackward also applies the step (false right after restart)
  uint32_t run_iterations_ = 0;  // CG iterations since the last restart
  uint32_t stage_restarts_ = 0;  // restarts in this stage since the graph last changed
  int64_t flow_[3] = {0, 0, 0};  // running suffix sums of kBackward
  Int128 threshold_;             // r.z at or below which the stage's bound is met
  Int128 fresh_rz_;              // r.z of the last recomputed residual (progress check)
  Int128 rz_;                    // r.z of the current preconditioned residual
  Int128 rz_old_;                // r.z of the previous iteration (for beta)
  Int128 pq_;                    // p.q accumulated by the direction passes
  Scalar alpha_{};
  Scalar beta_{};
  // Overflow control: the CG vectors hold their values divided by 2^scale_ (chosen per
  // residual recomputation, coarser after an overflow); peak_ is the OR of the magnitudes of
  // every value stored since the run began (checked()).
  uint32_t scale_ = 0;
  uint64_t peak_ = 0;
  uint32_t fresh_scale_ = 0;  // the scale of fresh_rz_
  bool rescaled_ = false;     // the next fresh residual repeats one at a coarser scale
  bool fatal_ = false;        // an estimate left the representable range (not persisted: it
                              // ends the stage at once)
  // The nonlinear finish's step control: kApply moves the estimates by +delta (0), takes back
  // delta >> apply_shift_ (> 0: a backtrack halving the step) or only clears delta (-1).
  int32_t apply_shift_ = -1;
  bool pending_step_ = false;  // delta holds this run's steps, not yet applied
  bool step_applied_ = false;  // the next fresh residual judges an applied step
  uint32_t backtracks_ = 0;
  Int128 objective_;           // sum e^T Omega e of the residual pass (the finish)
  Int128 accepted_objective_;  // of the last accepted estimate, at accepted_scale_
  uint32_t accepted_scale_ = 0;
  bool run_complete_ = true;  // the last CG run had the iterations exact arithmetic needs
  uint32_t anisotropic_ = 0;  // odometry edges whose position information is anisotropic
  bool configured_ = false;
};

}  // namespace seqslam
