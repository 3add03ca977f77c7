// Wheel calibration from loop closures: how far the left and right wheel circumferences and
// the track width that the odometry ran with are off, estimated from the pose graph after a
// run (issue 16 item 1; docs/mapping.md, "Odometry that calibrates itself").
//
// Model. Every odometry edge of the graph was integrated with the run's constants (left and
// right circumference U_L, U_R, track b). It is taken as an arc: path length s, turn dtheta,
// so the wheels travelled L = s - b dtheta / 2 and R = s + b dtheta / 2. With the true
// constants k_L U_L, k_R U_R, k_b b the same ticks give
//   s' = (k_L L + k_R R) / 2,     dtheta' = (k_R R - k_L L) / (k_b b).
// Two of the three factors are observable from loop closures, not all three: scaling every
// one of them by c scales the whole trajectory by c, and closures between places recognised
// by their images ("same place", the offset along the route in capture spacings, the heading
// from the image shift) hold at any scale. So the mean wheel scale is fixed at the run's,
//   k_L = 1 - delta / 2,   k_R = 1 + delta / 2,   k_b = 1 + tau,
// and (delta, tau) are estimated: delta is the wheels' difference (a curve on every straight),
// tau the track's error relative to the mean wheel (every turn a little too far or short).
//
// Method: Gauss-Newton over (delta, tau). Each iteration replays the odometry chain with the
// corrected edges (dead reckoning from node 0) and compares every loop closure with the
// replayed relative pose of its two nodes: position residual in metres, heading residual in
// radians times sqrt(heading_weight). The Jacobian is first order and analytic: a change of
// the heading at one edge rotates everything after it, so with per-node prefix sums of the
// heading derivatives (A, B) and of those times each edge's translation (G) one pass over the
// nodes gives every closure's derivatives. A small prior (prior_weight) keeps the normal
// equations regular. The result's formal standard deviations (from the normal matrix and the
// residual variance) say whether the run could tell the two apart: on a loop driven in one
// direction only, a track error and unequal wheels bend the loop alike (Borenstein's UMBmark
// drives a square both ways for this reason) and the estimate is refused (kOutOfRange)
// rather than applied; a route that turns both ways (a figure of eight) separates them.
//
// Closures whose chain of odometry edges crosses an edge that is not an odometry step (longer
// than max_step or turning by a quarter turn or more: a new run's start, a relocalisation's
// re-anchoring) are not used.
//
// Number formats: positions, residuals and derivatives Q31.32 metres or radians; delta and
// tau in the solver as Q31.32 per mille (so the normal matrix stays below 2^31 on a route of
// a few hundred metres), in the result as Q31.32 fractions; the 2x2 solve with 128-bit
// products.
//
// Memory: the caller's scratch, one WheelCalibrationSlot per loop closure (see the struct);
// nothing else. Work: `iterations` passes over the nodes (a sincos each) plus, per pass, one
// look at every closure; the closures are ordered once (insertion sort, linear when they come
// in node order as the explorer adds them).
#pragma once

#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/odometry.h"
#include "seqslam/pose_graph.h"
#include "seqslam/span.h"
#include "seqslam/status.h"

namespace seqslam {

// Corrections relative to the constants the odometry ran with (fractions, Q31.32):
// k_L = 1 - difference / 2, k_R = 1 + difference / 2, k_b = 1 + track.
struct WheelCorrection {
  Q31_32 difference;
  Q31_32 track;
};

struct WheelCalibrationConfig {
  // The track width the odometry ran with (OdometryConfig::track_width), metres.
  Q31_32 track_width = Q31_32::from_ratio(474, 1000);
  // Heading residuals weigh heading_weight per square radian against 1 per square metre of
  // position residual (100: one degree of heading counts as 1.7 cm).
  UQ16_16 heading_weight = UQ16_16::from_int(100);
  // Prior information on delta and tau (per square per mille): keeps the solve regular.
  UQ16_16 prior_weight = UQ16_16::from_ratio(1, 100);
  // Odometry edges longer than this, or turning by a quarter turn or more, break the chain.
  Q31_32 max_step = Q31_32::from_int(1);
  // Accepted only with at least this many usable closures ...
  uint16_t min_closures = 20;
  // Closures come in runs along the sequence matcher's sequences (S = 30 places), which share
  // their images and their odometry: not independent. The formal variances count this many
  // closures as one (on seed 1's calibrate runs the true errors were 5..11 times the
  // independent-closure sigma; sqrt(30) = 5.5). 1..1000.
  uint16_t correlated_closures = 30;
  // ... and formal standard deviations of delta and tau at most these (fractions).
  Q31_32 max_sigma_difference = Q31_32::from_ratio(1, 10000);  // 0.01 %
  Q31_32 max_sigma_track = Q31_32::from_ratio(1, 1000);        // 0.1 %
  // Bounds of a plausible estimate (fractions): a hand-measured robot is not further off.
  Q31_32 max_difference = Q31_32::from_ratio(1, 100);  // 1 %
  Q31_32 max_track = Q31_32::from_ratio(5, 100);       // 5 %
  // Gauss-Newton iterations (each a pass over the nodes), 1..20.
  uint8_t iterations = 6;
};

// Per loop closure, the solver's memory (caller-owned; one per closure of the graph).
struct WheelCalibrationSlot {
  uint16_t lo = 0;     // the closure's older node
  uint16_t hi = 0;     // ... and newer node (the chain runs lo -> hi)
  uint16_t by_lo = 0;  // the slots in the order of their `lo` (a permutation)
  uint16_t segment = 0;
  RelativePose2 z{};  // hi seen from lo, measured
  // Replayed at `lo` in the current iteration: heading (radians), position, the heading's
  // derivatives by delta and tau (radians per per mille) and the prefix sums G.
  int64_t at_lo[9] = {};
};

struct WheelCalibrationResult {
  WheelCorrection correction{};  // the estimate (also when refused, for the report)
  Q31_32 sigma_difference{};     // formal standard deviations (fractions)
  Q31_32 sigma_track{};
  Q31_32 rms_before{};  // closure residuals, metres (position part), at zero correction
  Q31_32 rms_after{};   // ... and at the estimate
  uint32_t closures_used = 0;
  uint32_t closures_skipped = 0;  // their chain crosses a break, or no slot
  uint32_t breaks = 0;            // odometry edges that break the chain
  uint32_t iterations = 0;
};

// Estimates the correction from `graph`'s odometry chain and loop closures. Returns:
//   kOk                 - estimated and plausible: apply it (apply_wheel_correction);
//   kInvalidArgument    - a setting out of range, a null `out`, or fewer scratch slots than
//                         closures (then nothing is estimated);
//   kFailedPrecondition - fewer than min_closures usable closures;
//   kOutOfRange         - the route cannot tell the two corrections apart (a formal
//                         standard deviation above its bound) or the estimate is outside
//                         the plausible bounds: not to be applied.
// `out` holds the figures in every case but kInvalidArgument.
Status calibrate_wheels(const PoseGraph& graph, const WheelCalibrationConfig& config,
                        Span<WheelCalibrationSlot> scratch, WheelCalibrationResult* out);

// The odometry constants corrected by `c` (circumferences times k_L, k_R, track times k_b).
// Corrections compose: a run with corrected constants estimates the remaining correction.
OdometryConfig apply_wheel_correction(const OdometryConfig& base, const WheelCorrection& c);

}  // namespace seqslam
