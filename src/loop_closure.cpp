#include "seqslam/loop_closure.h"

namespace seqslam {

namespace {

// Lengths are compared in micrometres: a Q31.32 difference clamped to +-2^31 um (2.1 km,
// far beyond any indoor map) squares into uint64 without overflow, and a micrometre is far
// below every bound the gate uses.
constexpr int64_t kMaxMicrometres = int64_t{1} << 31;

int64_t to_micrometres(Q31_32 v) {
  const int64_t um = mul_shift_round(v.raw(), 1000000, 32);
  if (um > kMaxMicrometres) return kMaxMicrometres;
  if (um < -kMaxMicrometres) return -kMaxMicrometres;
  return um;
}

uint64_t squared_um(const Pose2& a, const Pose2& b) {
  const int64_t dx = to_micrometres(a.x - b.x);
  const int64_t dy = to_micrometres(a.y - b.y);
  return static_cast<uint64_t>(dx * dx) + static_cast<uint64_t>(dy * dy);
}

uint64_t squared_bound_um(Q31_32 bound) {
  const int64_t um = to_micrometres(bound);
  return static_cast<uint64_t>(um) * static_cast<uint64_t>(um);
}

uint32_t abs_angle(int32_t bam) {
  return bam < 0 ? 0u - static_cast<uint32_t>(bam) : static_cast<uint32_t>(bam);
}

constexpr uint32_t kHalfTurn = 1u << 31;

// A relocalisation hypothesis no match has agreed with for this far (or relocalise_verify,
// if longer) is dropped: 10 places at 20 cm, as a trail survives kRelocaliseGap.
constexpr int64_t kHypothesisGapMetres = 2;

}  // namespace

const char* loop_closure_class_name(LoopClosureClass c) {
  switch (c) {
    case LoopClosureClass::kNoSequence:
      return "no_sequence";
    case LoopClosureClass::kClosure:
      return "closure";
    case LoopClosureClass::kPending:
      return "pending";
    case LoopClosureClass::kRejectedInconsistent:
      return "rejected_inconsistent";
    case LoopClosureClass::kAliasing:
      return "aliasing";
    case LoopClosureClass::kNovelty:
      return "novelty";
    case LoopClosureClass::kRelocalised:
      return "relocalised";
  }
  return "unknown";
}

Status check_loop_closure_config(const LoopClosureConfig& c) {
  const Q31_32 max_metres = Q31_32::from_int(1000);
  if (c.drift_base < Q31_32::from_int(0) || c.drift_base > max_metres) return Status::kOutOfRange;
  if (c.near_radius < Q31_32::from_int(0) || c.near_radius > max_metres) {
    return Status::kOutOfRange;
  }
  if (c.drift_rate > UQ16_16::from_int(1)) return Status::kOutOfRange;
  if (c.heading_base.bam > Angle::from_degrees(180).bam) return Status::kOutOfRange;
  if (c.heading_rate.bam > Angle::from_degrees(10).bam) return Status::kOutOfRange;
  if (c.confirm < 1 || c.confirm > 1000 || c.max_advance > 1000 || c.relocalise > 1000) {
    return Status::kOutOfRange;
  }
  if (c.relocalise_turn.bam > Angle::from_degrees(180).bam) return Status::kOutOfRange;
  if (c.relocalise_verify < Q31_32::from_int(0) || c.relocalise_verify > max_metres ||
      c.relocalise_support < 1 || c.relocalise_support > 1000) {
    return Status::kOutOfRange;
  }
  if (c.max_image_rank > UQ16_16::from_int(1)) return Status::kOutOfRange;
  if (c.turn_tolerance.bam > Angle::from_degrees(180).bam) return Status::kOutOfRange;
  return Status::kOk;
}

Status LoopClosureGate::configure(const LoopClosureConfig& config) {
  SEQSLAM_TRY(check_loop_closure_config(config));
  config_ = config;
  configured_ = true;
  reset();
  return Status::kOk;
}

void LoopClosureGate::reset() {
  stats_ = LoopClosureStats{};
  last_odometry_ = Pose2{};
  fix_odometry_ = Pose2{};
  travelled_ = Q31_32::from_int(0);
  fix_node_ = 0;
  last_place_ = -1;
  streak_ = 0;
  last_matched_node_ = -1;
  run_matched_turn_ = 0;
  reloc_streak_ = 0;
  trail_place_ = -1;
  trail_gap_ = 0;
  trail_turned_ = false;
  hyp_odometry_ = Pose2{};
  hyp_travelled_ = Q31_32::from_int(0);
  hyp_since_ = Q31_32::from_int(0);
  hyp_node_ = 0;
  hyp_support_ = 0;
  hyp_active_ = false;
  has_fix_ = false;
  started_ = false;
}

Q31_32 LoopClosureGate::drift_bound(Q31_32 travelled) const {
  return config_.drift_base + mul_sat<Q31_32>(config_.drift_rate, travelled);
}

uint32_t LoopClosureGate::heading_bound(Q31_32 travelled) const {
  // heading_rate (< 2^27 BAM per metre) times metres; saturates at half a turn, which
  // accepts every heading.
  const int64_t metres = travelled.raw() >> 16;  // Q47.16, >= 0
  const uint64_t rate = config_.heading_rate.bam;
  const uint64_t limit = uint64_t{kHalfTurn} << 16;
  const uint64_t grow = metres > 0 && static_cast<uint64_t>(metres) > limit / (rate + 1)
                            ? limit
                            : (static_cast<uint64_t>(metres) * rate);
  const uint64_t total = uint64_t{config_.heading_base.bam} + (grow >> 16);
  return total >= kHalfTurn ? kHalfTurn : static_cast<uint32_t>(total);
}

bool LoopClosureGate::near_known(const PoseGraph& graph, uint32_t known, const Pose2& at,
                                 Q31_32 radius, uint32_t heading) const {
  const uint64_t r2 = squared_bound_um(radius);
  for (uint32_t i = 0; i < known; ++i) {
    const Result<Pose2> p = graph.pose(i);
    if (!p.ok()) return false;
    if (squared_um(p.value(), at) > r2) continue;
    if (abs_angle(signed_diff(p.value().heading, at.heading)) <= heading) return true;
  }
  return false;
}

// The trail: consecutive matches (confident or not) whose matched places advance with the
// robot - by up to max_advance per place, places without a match included (at most
// kRelocaliseGap of them) - and whose turn since the trail began agrees between the odometry
// and the matched places' estimates (within heading_base). A match that does not continue it
// starts a new one, and the count of confident, odometry-inconsistent matches (reloc_streak_)
// starts again with it.
void LoopClosureGate::follow_trail(const LoopClosureQuery& q, const Pose2& matched) {
  const int32_t reach =
      static_cast<int32_t>(config_.max_advance) * static_cast<int32_t>(trail_gap_ + 1u);
  bool continues =
      trail_place_ >= 0 && q.match.place >= trail_place_ && q.match.place - trail_place_ <= reach;
  if (continues) {
    const int32_t odometry_turn = signed_diff(q.odometry.heading, trail_odometry_heading_);
    const int32_t matched_turn = signed_diff(matched.heading, trail_matched_heading_);
    const int32_t disagreement = static_cast<int32_t>(static_cast<uint32_t>(odometry_turn) -
                                                      static_cast<uint32_t>(matched_turn));
    if (abs_angle(disagreement) > config_.heading_base.bam) {
      continues = false;
    } else if (abs_angle(odometry_turn) >= config_.relocalise_turn.bam) {
      trail_turned_ = true;
    }
  }
  if (!continues) {
    trail_odometry_heading_ = q.odometry.heading;
    trail_matched_heading_ = matched.heading;
    trail_turned_ = config_.relocalise_turn.bam == 0;
    reloc_streak_ = 0;
  }
  trail_place_ = q.match.place;
  trail_gap_ = 0;
}

void LoopClosureGate::drop_hypothesis() {
  hyp_active_ = false;
  ++stats_.hypotheses_dropped;
  // A new hypothesis needs a new trail, with its own turn.
  reloc_streak_ = 0;
  trail_place_ = -1;
}

// A confident match the odometry cannot explain (and the image rule did not reject), with
// relocalisation on. Without a hypothesis it counts along the trail, and a trail that
// relocalises proposes one: the matched place at this odometry pose. With one, the match
// either agrees with it (its matched place lies where the hypothesis puts the robot, within
// the drift and heading bounds grown since its latest agreeing match) or drops it. A
// hypothesis verified over relocalise_verify metres by relocalise_support matches is
// accepted here: kRelocalised and the fix taken.
void LoopClosureGate::relocalise_step(const PoseGraph& graph, const LoopClosureQuery& q,
                                      const Pose2& matched, LoopClosureDecision* d) {
  const uint32_t node = static_cast<uint32_t>(q.matched_node);
  if (hyp_active_) {
    const Pose2 predicted =
        compose(graph.pose(hyp_node_).value(), relative_pose(hyp_odometry_, q.odometry));
    const bool agrees =
        squared_um(matched, predicted) <= squared_bound_um(drift_bound(hyp_since_)) &&
        abs_angle(signed_diff(matched.heading, predicted.heading)) <= heading_bound(hyp_since_);
    if (!agrees) {
      drop_hypothesis();
      return;
    }
    if (hyp_support_ < config_.relocalise_support) ++hyp_support_;  // no overflow
  } else {
    ++reloc_streak_;  // in the current trail (follow_trail restarts it with the trail)
    d->streak = reloc_streak_;
    if (reloc_streak_ < config_.relocalise || !trail_turned_) return;
    ++stats_.hypotheses;
    hyp_active_ = true;
    hyp_travelled_ = Q31_32::from_int(0);
    hyp_support_ = 1;
    reloc_streak_ = 0;
  }
  hyp_node_ = node;
  hyp_odometry_ = q.odometry;
  hyp_since_ = Q31_32::from_int(0);
  d->streak = hyp_support_;
  if (hyp_travelled_ < config_.relocalise_verify || hyp_support_ < config_.relocalise_support) {
    return;
  }
  hyp_active_ = false;
  d->kind = LoopClosureClass::kRelocalised;
  reloc_streak_ = 0;
  trail_place_ = -1;
  // The matches that relocalised confirm the place: the next consistent match closes.
  streak_ = static_cast<uint16_t>(config_.confirm > 1 ? config_.confirm - 1 : 1);
  last_place_ = q.match.place;
  last_matched_node_ = q.matched_node;
  run_odometry_heading_ = q.odometry.heading;
  run_matched_turn_ = 0;
  take_fix(node, q.odometry);
  // The fix's own place: predictions from here on start at the matched place.
  d->predicted = matched;
}

void LoopClosureGate::take_fix(uint32_t node, const Pose2& odometry) {
  has_fix_ = true;
  fix_node_ = node;
  fix_odometry_ = odometry;
  travelled_ = Q31_32::from_int(0);
}

Status LoopClosureGate::decide(const PoseGraph& graph, const LoopClosureQuery& q,
                               LoopClosureDecision* out) {
  if (!configured_) return Status::kFailedPrecondition;
  if (out == nullptr) return Status::kInvalidArgument;
  const uint32_t nodes = graph.node_count();
  if (q.node >= nodes || q.known_nodes > nodes ||
      (q.matched_node >= 0 && static_cast<uint32_t>(q.matched_node) >= nodes) ||
      (has_fix_ && fix_node_ >= nodes)) {
    return Status::kOutOfRange;
  }

  // Distance driven: straight-line steps between consecutive places (20 cm apart on the
  // robot, so this is the path length at that resolution).
  if (started_) {
    const uint64_t step2 = squared_um(q.odometry, last_odometry_);
    const uint32_t step_um = isqrt64(step2);
    const Q31_32 step = Q31_32::from_ratio(static_cast<int64_t>(step_um), 1000000);
    travelled_ = travelled_ + step;
    if (hyp_active_) {
      hyp_travelled_ = hyp_travelled_ + step;
      hyp_since_ = hyp_since_ + step;
    }
  }
  const Q31_32 stale = config_.relocalise_verify > Q31_32::from_int(kHypothesisGapMetres)
                           ? config_.relocalise_verify
                           : Q31_32::from_int(kHypothesisGapMetres);
  if (hyp_active_ && hyp_since_ > stale) drop_hypothesis();
  started_ = true;
  last_odometry_ = q.odometry;

  LoopClosureDecision d;
  d.node = q.node;
  d.matched_node = q.matched_node;
  d.travelled = travelled_;
  d.bound = drift_bound(travelled_);
  if (has_fix_) {
    d.predicted = compose(graph.pose(fix_node_).value(), relative_pose(fix_odometry_, q.odometry));
  } else {
    d.predicted = graph.pose(q.node).value();
  }
  const uint32_t heading_limit = heading_bound(travelled_);

  const bool confident = q.match.place >= 0 && q.match.localised && q.matched_node >= 0;
  if (q.match.place < 0) {
    d.kind = LoopClosureClass::kNoSequence;
    if (trail_place_ >= 0 && ++trail_gap_ > kRelocaliseGap) trail_place_ = -1;
  } else if (confident) {
    const Pose2 matched = graph.pose(static_cast<uint32_t>(q.matched_node)).value();
    if (config_.relocalise > 0) follow_trail(q, matched);
    const uint64_t dist2 = squared_um(matched, d.predicted);
    d.distance = Q31_32::from_ratio(static_cast<int64_t>(isqrt64(dist2)), 1000000);
    d.heading_error = signed_diff(matched.heading, d.predicted.heading);
    if (dist2 > squared_bound_um(d.bound)) {
      d.reject = LoopClosureReject::kPosition;
    } else if (abs_angle(d.heading_error) > heading_limit) {
      d.reject = LoopClosureReject::kHeading;
    } else if (static_cast<uint64_t>(q.closer_places) << 16 >
               static_cast<uint64_t>(config_.max_image_rank.raw()) * q.known_nodes) {
      d.reject = LoopClosureReject::kImage;
    }
    // Does the matched place follow the previous match along the library?
    const auto advances = [&](int32_t previous) {
      return previous >= 0 && q.match.place >= previous &&
             q.match.place - previous <= static_cast<int32_t>(config_.max_advance);
    };
    // Along a run of consistent matches the robot and the matched places must turn alike: the
    // odometry's turn since the run began against the matched places' own odometry turn (the
    // graph's chain measurements, which closures do not bend). Where two routes part (one
    // turns off, the other goes straight on) the images stay alike for a few places and the
    // estimates, dragged by the closures being made, would follow.
    const bool continues = d.reject == LoopClosureReject::kNone && streak_ > 0 &&
                           advances(last_place_) && last_matched_node_ >= 0;
    int64_t matched_turn = 0;
    if (continues) {
      matched_turn =
          run_matched_turn_ + chain_turn(graph, static_cast<uint32_t>(last_matched_node_),
                                         static_cast<uint32_t>(q.matched_node));
      const int64_t odometry_turn = signed_diff(q.odometry.heading, run_odometry_heading_);
      const int64_t disagreement = odometry_turn - matched_turn;
      if ((disagreement < 0 ? -disagreement : disagreement) >
          static_cast<int64_t>(config_.turn_tolerance.bam)) {
        d.reject = LoopClosureReject::kHeading;
      }
    }
    if (d.reject == LoopClosureReject::kNone) {
      streak_ = continues ? static_cast<uint16_t>(streak_ + 1) : 1;
      if (streak_ >= config_.confirm) streak_ = config_.confirm;  // no overflow, still closing
      if (continues) {
        run_matched_turn_ = matched_turn;
      } else {
        run_odometry_heading_ = q.odometry.heading;
        run_matched_turn_ = 0;
      }
      last_matched_node_ = q.matched_node;
      last_place_ = q.match.place;
      reloc_streak_ = 0;  // odometry explains the robot: nothing to relocalise
      if (hyp_active_) drop_hypothesis();
      d.streak = streak_;
      if (streak_ >= config_.confirm) {
        d.kind = LoopClosureClass::kClosure;
        take_fix(static_cast<uint32_t>(q.matched_node), q.odometry);
      } else {
        d.kind = LoopClosureClass::kPending;
      }
    } else {
      if (streak_ > 0 && streak_ < config_.confirm) ++stats_.streaks_broken;
      streak_ = 0;
      last_place_ = -1;
      d.kind = LoopClosureClass::kRejectedInconsistent;
      if (d.reject == LoopClosureReject::kPosition) {
        ++stats_.rejected_position;
      } else if (d.reject == LoopClosureReject::kHeading) {
        ++stats_.rejected_heading;
      } else {
        ++stats_.rejected_image;
      }
      // Only odometry can be wrong for a relocalisation: an image that disagrees is no
      // evidence for one.
      if (config_.relocalise > 0 && d.reject != LoopClosureReject::kImage) {
        relocalise_step(graph, q, matched, &d);
      }
    }
  } else {
    if (streak_ > 0 && streak_ < config_.confirm) ++stats_.streaks_broken;
    streak_ = 0;
    last_place_ = -1;
    if (config_.relocalise > 0 && q.matched_node >= 0) {
      follow_trail(q, graph.pose(static_cast<uint32_t>(q.matched_node)).value());
    }
    const Q31_32 radius = config_.near_radius + d.bound;
    d.kind = near_known(graph, q.known_nodes, d.predicted, radius, heading_limit)
                 ? LoopClosureClass::kAliasing
                 : LoopClosureClass::kNovelty;
  }
  ++stats_.decisions[static_cast<uint32_t>(d.kind)];
  *out = d;
  return Status::kOk;
}

// The turn the odometry measured from node `from` to node `to` (the chain edges' dtheta,
// signed binary-angle units summed); 0 unless from < to < node count.
int64_t LoopClosureGate::chain_turn(const PoseGraph& graph, uint32_t from, uint32_t to) {
  int64_t turn = 0;
  if (to >= graph.node_count()) return 0;
  for (uint32_t k = from + 1; k <= to; ++k) {
    const Result<PoseGraphEdge> e = graph.edge(k - 1);  // the odometry edge into node k
    if (e.ok()) turn += signed_diff(e.value().dtheta, Angle{});
  }
  return turn;
}

uint32_t count_closer(Span<const uint32_t> differences, uint32_t known, uint32_t place) {
  if (place >= known || known > differences.size()) return 0;
  const uint32_t at = differences[place];
  uint32_t closer = 0;
  for (uint32_t k = 0; k < known; ++k)
    closer += differences[k] < at ? 1u : 0u;
  return closer;
}

Angle shift_to_heading(Q15_16 shift_px, Angle hfov, uint32_t width) {
  if (width == 0) return Angle{};
  // |shift| < 2^31 (Q15.16 raw) times hfov < 2^32 needs up to 2^63: split hfov in halves so
  // each product stays within int64, then divide by width * 2^16.
  const int64_t s = shift_px.raw();
  const int64_t hi = static_cast<int64_t>(hfov.bam >> 16);
  const int64_t lo = static_cast<int64_t>(hfov.bam & 0xFFFFu);
  const int64_t den = static_cast<int64_t>(width);
  // -(s * hfov) / (width * 2^16) = -(s * hi + s * lo / 2^16) / width
  const int64_t num = s * hi + (s * lo) / 65536;
  int64_t q = -div_round(num, den);
  const int64_t half = int64_t{1} << 31;
  if (q >= half) q = half - 1;
  if (q < -half) q = -half;
  return Angle{static_cast<uint32_t>(q)};
}

}  // namespace seqslam
