// The loop-closure decision of issue 7 ("From localisation to SLAM", [R 7]): what to do with
// the localiser's answer for the place just observed (Localiser::observe, one run matched
// against its own older places) given the pose graph's estimates.
//
//   no full sequence yet (match.place < 0)              -> kNoSequence
//   confident (match.localised), consistent with odometry:
//     the confirm-th consecutive such match whose matched places advance along the library
//     (0..max_advance places per step), and every one after it   -> kClosure (add an edge)
//     before that                                                 -> kPending
//   confident but inconsistent with odometry            -> kRejectedInconsistent (reason says
//                                                          position or heading)
//     ... relocalise (> 0) such matches in a row that advance along the library
//                                                        -> kRelocalised (see below)
//   not confident, a known place near the estimate      -> kAliasing (discard: the place is
//                                                          known but looks different: an
//                                                          occlusion, people, light)
//   not confident, nothing known near                   -> kNovelty (a new place)
//
// The odometry rule. Since the last accepted fix (a closure or a relocalisation; before
// that: the start) the robot has driven D metres by odometry. The current pose is predicted
// from the fix: the estimate of the place it was fixed to, composed with the odometry since
// then (before any fix: the graph's own estimate of the current node, i.e. dead reckoning in
// the graph's frame). A match is consistent when the matched place's estimate lies within
//     drift_base + drift_rate * D            (straight-line distance, metres)
// of that prediction and its heading within
//     heading_base + heading_rate * D        (per metre)
// of the predicted heading. drift_base covers that the same place is passed on different
// lines (the simulator's driver keeps +-0.5 m from the centre line) and the matcher's +-1
// place; drift_rate the odometry's drift per metre (the simulator's default mis-calibration:
// 1.0..1.9 m after the 90 m loop, i.e. under 2.1 %; the default 5 % leaves room for slip).
// Using the prediction from the fix rather than the graph's current estimate of the current
// node makes the rule independent of how far the optimiser has got: after a closure the graph
// needs several places' worth of optimise_step slices to move the current node, while the
// prediction is right at once.
//
// Confirmation: one confident match can be an aliased place (the lab repeats its desks and
// doors); a run of `confirm` consistent matches whose matched places advance with the robot is
// far less likely to be one. docs/mapping.md has the measurements behind the default.
//
// Relocalisation (kidnapping, a jump of the route that odometry did not see): after the
// odometry has been broken, every correct match is inconsistent and would be rejected forever.
// When `relocalise` confident matches in a row are mutually consistent (advancing along the
// library) but inconsistent with odometry, the gate reports kRelocalised and takes the
// matched place as its new fix: the caller should re-anchor its odometry there and not add
// the match as a closure edge (the graph's odometry chain across the break is wrong, and a
// closure would bend the whole map to fit it). 0 disables it.
//
// Aliasing vs novelty: a known place is "near" when a node among the first known_nodes of the
// graph (the places the localiser compared against) lies within near_radius + the drift bound
// of the prediction, with a heading within the heading bound (a place seen the other way
// round looks new to the camera).
//
// All fixed point, no heap; the gate keeps only its fix, its streaks and its counters.
#pragma once

#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/fixmath.h"
#include "seqslam/odometry.h"
#include "seqslam/pose_graph.h"
#include "seqslam/sequence_matcher.h"
#include "seqslam/status.h"

namespace seqslam {

enum class LoopClosureClass : uint8_t {
  kNoSequence = 0,
  kClosure = 1,
  kPending = 2,
  kRejectedInconsistent = 3,
  kAliasing = 4,
  kNovelty = 5,
  kRelocalised = 6,
};
inline constexpr uint32_t kLoopClosureClasses = 7;
// Short stable names: "no_sequence", "closure", "pending", "rejected_inconsistent",
// "aliasing", "novelty", "relocalised".
const char* loop_closure_class_name(LoopClosureClass c);

enum class LoopClosureReject : uint8_t {
  kNone = 0,
  kPosition = 1,  // the matched place is farther than the drift bound
  kHeading = 2,   // within it, but its heading differs by more than the heading bound
};

struct LoopClosureConfig {
  Q31_32 drift_base = Q31_32::from_int(1);           // metres, 0..1000
  UQ16_16 drift_rate = UQ16_16::from_ratio(5, 100);  // metres per metre driven, 0..1
  Angle heading_base = Angle::from_degrees(30);      // 0..180 degrees
  Angle heading_rate = Angle::from_degrees(1, 10);   // per metre driven, 0..10 degrees
  Q31_32 near_radius = Q31_32::from_ratio(3, 2);     // metres, 0..1000
  uint16_t confirm = 3;      // consecutive consistent matches for a closure, 1..1000
  uint16_t max_advance = 3;  // matched place steps between consecutive matches, 0..1000
  uint16_t relocalise = 0;   // consistent-but-odometry-inconsistent run to relocalise; 0 off
};

// kOk or kOutOfRange (a setting outside its documented range).
Status check_loop_closure_config(const LoopClosureConfig& config);

struct LoopClosureQuery {
  Match match;                // the localiser's answer for the current place
  uint32_t node = 0;          // the current place's graph node (already added)
  int32_t matched_node = -1;  // the node of match.place; -1 when none or not in the graph
  uint32_t known_nodes = 0;   // nodes 0..known_nodes-1 are the known places (aliasing test)
  Pose2 odometry{};           // the current odometry pose (as given to add_node)
};

struct LoopClosureDecision {
  LoopClosureClass kind = LoopClosureClass::kNoSequence;
  LoopClosureReject reject = LoopClosureReject::kNone;
  uint32_t node = 0;          // the current node
  int32_t matched_node = -1;  // as queried
  Pose2 predicted{};          // the current pose predicted from the last fix
  Q31_32 travelled{};         // odometry distance since the last fix (this place included)
  Q31_32 bound{};             // the drift bound at this place
  Q31_32 distance{};          // |matched estimate - prediction| (confident matches), metres
  int32_t heading_error = 0;  // matched heading - predicted heading, binary angle
  uint16_t streak = 0;        // consecutive consistent matches including this one
};

struct LoopClosureStats {
  uint32_t decisions[kLoopClosureClasses] = {};  // per LoopClosureClass
  uint32_t rejected_position = 0;
  uint32_t rejected_heading = 0;
  uint32_t streaks_broken = 0;  // a pending run that ended before it was confirmed
};

class LoopClosureGate {
 public:
  // Adopts `config` (kOutOfRange: nothing changes) and resets.
  Status configure(const LoopClosureConfig& config);
  // Forgets the fix, the streaks and the counters (keeps the configuration).
  void reset();

  // Classifies one place (see the top of this file) and updates the fix, streaks and counters.
  // kFailedPrecondition before configure(); kInvalidArgument for a null `out`; kOutOfRange
  // when query.node, query.matched_node or the fix's node is not a node of `graph`, or
  // known_nodes exceeds node_count() (nothing changes then).
  Status decide(const PoseGraph& graph, const LoopClosureQuery& query, LoopClosureDecision* out);

  bool configured() const { return configured_; }
  const LoopClosureConfig& config() const { return config_; }
  const LoopClosureStats& stats() const { return stats_; }
  bool has_fix() const { return has_fix_; }
  uint32_t fix_node() const { return fix_node_; }
  Q31_32 travelled() const { return travelled_; }

 private:
  Q31_32 drift_bound(Q31_32 travelled) const;
  uint32_t heading_bound(Q31_32 travelled) const;
  bool near_known(const PoseGraph& graph, uint32_t known, const Pose2& at, Q31_32 radius,
                  uint32_t heading) const;
  void take_fix(uint32_t node, const Pose2& odometry);

  LoopClosureConfig config_{};
  LoopClosureStats stats_{};
  Pose2 last_odometry_{};  // the previous query's odometry (travelled distance)
  Pose2 fix_odometry_{};   // the odometry pose at the last fix
  Q31_32 travelled_{};
  uint32_t fix_node_ = 0;          // the node the robot was fixed to
  int32_t last_place_ = -1;        // matched place of the previous confident match
  int32_t last_reloc_place_ = -1;  // ... of the previous inconsistent confident match
  uint16_t streak_ = 0;
  uint16_t reloc_streak_ = 0;
  bool has_fix_ = false;
  bool started_ = false;  // last_odometry_ is valid
  bool configured_ = false;
};

// A closure's heading offset from the horizontal shift between the two places' images
// (subpixel_shift(matched, current), difference.h): a camera with horizontal field of view
// `hfov` over `width` columns that has turned left by h sees the scene h * width / hfov
// columns further right, so the current place's heading relative to the matched one is
// -shift * hfov / width (pinhole small-angle approximation; rounded to nearest, saturating at
// +-half a turn). A lateral offset between the two passes also shifts near objects (parallax),
// which this cannot tell from a turn (docs/mapping.md). `width` 0 gives 0.
Angle shift_to_heading(Q15_16 shift_px, Angle hfov, uint32_t width);

}  // namespace seqslam
