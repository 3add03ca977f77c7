#include "seqslam/explorer.h"

#include "seqslam/difference.h"
#include "seqslam/messages.h"
#include "seqslam/spatial_trigger.h"

namespace seqslam {

const char* explorer_issue_text(ExplorerIssue issue) {
#if !SEQSLAM_MESSAGE_TEXTS
  return message_code("EI", static_cast<uint32_t>(issue));
#endif
  switch (issue) {
    case ExplorerIssue::kNone:
      return "ok";
    case ExplorerIssue::kGate:
      return "a loop-closure gate setting is out of range (loop_closure.h)";
    case ExplorerIssue::kGraph:
      return "the pose graph's settings or buffers are invalid (pose_graph.h)";
    case ExplorerIssue::kGrid:
      return "the map grid's settings or RAM tiles are invalid (occupancy_grid.h)";
    case ExplorerIssue::kAlign:
      return "closure alignment: length must be 0..64 and max_offset 0..8 (closure_align.h)";
    case ExplorerIssue::kHeading:
      return "closure heading: max_shift must be 0..16 and hfov above 0";
    case ExplorerIssue::kBudget:
      return "the optimiser budget per place must be at least 1";
    case ExplorerIssue::kSpacing:
      return "the capture spacing must be above 0 and at most 1000 m";
  }
  return "unknown";
}

namespace {

ExplorerCheck refuse(Status s, ExplorerIssue issue, GridIssue grid = GridIssue::kNone) {
  return ExplorerCheck{s, issue, grid};
}

// The settings the explorer's own code uses (the graph, gate and grid check theirs).
ExplorerCheck check_own(const ExplorerConfig& c) {
  if (c.align.length > kMaxAlignLength || c.align.max_offset > kMaxAlignOffset) {
    return refuse(Status::kOutOfRange, ExplorerIssue::kAlign);
  }
  if (c.max_shift > kMaxSubpixelShift || c.hfov.bam == 0) {
    return refuse(Status::kOutOfRange, ExplorerIssue::kHeading);
  }
  if (c.optimise_budget == 0) return refuse(Status::kInvalidArgument, ExplorerIssue::kBudget);
  if (c.spacing.raw() <= 0 || c.spacing > SpatialTrigger::kMaxSpacing) {
    return refuse(Status::kOutOfRange, ExplorerIssue::kSpacing);
  }
  return {};
}

}  // namespace

ExplorerCheck Explorer::configure(const ExplorerConfig& config, const ExplorerBuffers& buffers) {
  ExplorerCheck own = check_own(config);
  if (!own.ok()) return own;
  if (check_loop_closure_config(config.gate) != Status::kOk) {
    return refuse(Status::kOutOfRange, ExplorerIssue::kGate);
  }
  configured_ = false;
  Status s = graph_.configure(config.graph, buffers.graph);
  if (s != Status::kOk) return refuse(s, ExplorerIssue::kGraph);
  s = gate_.configure(config.gate);
  if (s != Status::kOk) return refuse(s, ExplorerIssue::kGate);
  if (buffers.tiles != nullptr) {
    GridIssue gi = GridIssue::kNone;
    s = grid_.configure(config.grid, buffers.grid, *buffers.tiles, &gi);
    if (s != Status::kOk) return refuse(s, ExplorerIssue::kGrid, gi);
  }
  config_ = config;
  tiles_ = buffers.tiles;
  sensors_ = buffers.sensors;
  scratch_ = buffers.scratch;
  reset_run_state();
  configured_ = true;
  return {};
}

// An empty run: what configure() leaves, and what a refused state() leaves.
void Explorer::reset_run_state() {
  graph_.reset();
  gate_.reset();
  stats_ = ExplorerStats{};
  hanging_ = false;
  rebased_ = false;
  last_fix_ = 0;
  untrusted_ranges_ = 0;
  rebuilding_ = false;
  next_rebuild_node_ = 0;
}

// A restored state refers only to nodes the restored graph has.
bool Explorer::state_valid() const {
  const uint32_t nodes = graph_.node_count();
  if (hanging_ && hang_node_ >= nodes) return false;
  if (last_fix_ > nodes || untrusted_ranges_ > kMaxUntrustedRanges) return false;
  for (uint32_t i = 0; i < untrusted_ranges_; ++i) {
    if (first_untrusted_[i] > last_untrusted_[i]) return false;
  }
  return gate_.state_fits(nodes);
}

void Explorer::begin_run() {
  rebased_ = false;
  last_fix_ = graph_.node_count();
}

Status Explorer::place(PlaceLibrary& library, Span<const uint32_t> differences, const Match& m,
                       const Pose2& odometry, uint32_t place, ExplorerStep* step) {
  if (!configured_) return Status::kFailedPrecondition;
  if (step == nullptr) return Status::kInvalidArgument;
  *step = ExplorerStep{};
  // The graph's frame: the odometry's, re-anchored after a relocalisation.
  const Pose2 pose =
      rebased_ ? compose(rebase_to_, relative_pose(rebase_from_, odometry)) : odometry;
  const Result<uint32_t> added = graph_.add_node(pose, place);
  if (!added.ok()) {
    // Library place i is node i no longer: no more closures (the gate needs that), but the
    // snapshots keep hanging from the last node.
    ++stats_.graph_full;
    return Status::kOk;
  }
  const uint32_t node = added.value();
  ++stats_.nodes;
  step->node = static_cast<int32_t>(node);
  hang_from(node, odometry);

  LoopClosureQuery q;
  q.match = m;
  q.node = node;
  q.matched_node = m.place >= 0 && static_cast<uint32_t>(m.place) < node && stats_.graph_full == 0
                       ? m.place
                       : -1;
  q.known_nodes = node > config_.recent_exclusion ? node - config_.recent_exclusion : 0;
  // The gate keeps its own odometry (distance driven, the pose at its last fix) in the raw
  // frame: a relocalisation re-anchors the graph's frame, not the gate's.
  q.odometry = odometry;
  if (q.matched_node >= 0) {
    q.closer_places = count_closer(differences, q.known_nodes, static_cast<uint32_t>(m.place));
  }
  SEQSLAM_TRY(gate_.decide(graph_, q, &step->decision));

  if (step->decision.kind == LoopClosureClass::kClosure) {
    closure_edge(library, node, q.known_nodes, static_cast<uint32_t>(q.matched_node), step);
    last_fix_ = node;
  } else if (step->decision.kind == LoopClosureClass::kRelocalised && q.matched_node >= 0) {
    // Odometry was broken since the last fix: from here on its poses are re-anchored at the
    // matched place (the next odometry edge takes the jump, weighted by its length), and the
    // places since the last fix are not trusted for the map.
    rebase_from_ = odometry;
    rebase_to_ = graph_.pose(static_cast<uint32_t>(q.matched_node)).value();
    rebased_ = true;
    distrust(last_fix_ + 1, node);
    last_fix_ = node;
    step->relocalised = true;
    ++stats_.relocalisations;
  }
  if (graph_.optimise_step(config_.optimise_budget, &step->progress) == Status::kOk &&
      step->progress.work > 0) {
    stats_.optimise_work += step->progress.work;
    ++stats_.slices;
  }
  return Status::kOk;
}

// The closure edge from `matched` to `node`: where along the matched pass the place lies (the
// edge joins the aligned place, dx the rest of a place), then the heading from the images.
// A failing card read falls back (the matched place; the same heading) and is counted.
void Explorer::closure_edge(PlaceLibrary& library, uint32_t node, uint32_t known, uint32_t matched,
                            ExplorerStep* step) {
  uint32_t target = matched;
  RelativePose2 rel{};
  if (config_.align.length > 0) {
    ClosureAlignment al;
    step->align_status = align_closure(library, node, matched, known, config_.align, scratch_, &al);
    if (step->align_status == Status::kOk) {
      if (al.place != matched) ++stats_.closures_realigned;
      target = al.place;
      rel.dx = along_route(al.fraction, config_.spacing);
    } else {
      ++stats_.align_failures;
    }
  }
  if (config_.max_shift > 0) {
    // The matched image is copied to the scratch: reading the current one may evict it from a
    // card-backed image cache.
    ImageView a{}, b{};
    Status s = library.image(target, &a);
    if (s == Status::kOk && a.size.pixels() > scratch_.size()) s = Status::kInvalidArgument;
    if (s == Status::kOk) {
      for (uint32_t i = 0; i < a.size.pixels(); ++i)
        scratch_[i] = a.pixels[i];
      a.pixels = scratch_.data();
      s = library.image(node, &b);
    }
    if (s == Status::kOk) {
      const Result<Q15_16> shift = subpixel_shift(a, b, config_.max_shift);
      s = shift.status();
      if (s == Status::kOk) {
        step->shift = shift.value();
        rel.dtheta = shift_to_heading(shift.value(), config_.hfov, a.size.width);
      }
    }
    step->heading_status = s;
    if (s != Status::kOk) ++stats_.heading_failures;
  }
  if (graph_.add_loop_closure(target, node, rel, config_.closure_information) == Status::kOk) {
    ++stats_.closures;
    step->closure_to = static_cast<int32_t>(target);
    step->gate_place = matched;
    step->closure = rel;
  }
}

void Explorer::distrust(uint32_t first, uint32_t last) {
  if (first > last) return;
  stats_.untrusted_places += last - first + 1;
  if (untrusted_ranges_ == kMaxUntrustedRanges) {
    last_untrusted_[kMaxUntrustedRanges - 1] = last;  // merged: everything between distrusted
    return;
  }
  first_untrusted_[untrusted_ranges_] = first;
  last_untrusted_[untrusted_ranges_] = last;
  ++untrusted_ranges_;
}

bool Explorer::trusted(uint32_t node) const {
  for (uint32_t k = 0; k < untrusted_ranges_; ++k) {
    if (node >= first_untrusted_[k] && node <= last_untrusted_[k]) return false;
  }
  return true;
}

void Explorer::hang_from(uint32_t node, const Pose2& odometry) {
  hanging_ = true;
  hang_node_ = node;
  hang_odometry_ = odometry;
}

Status Explorer::scan(const Pose2& odometry, Span<const uint16_t> readings) {
  if (!configured_) return Status::kFailedPrecondition;
  if (tiles_ == nullptr) return Status::kOk;
  if (rebuilding_ && hanging_ && !trusted(hang_node_)) return Status::kOk;
  Pose2 pose = odometry;
  if (hanging_) {
    pose = compose(graph_.pose(hang_node_).value(), relative_pose(hang_odometry_, odometry));
  }
  uint32_t rejected = 0;
  for (size_t k = 0; k < readings.size() && k < sensors_.size(); ++k) {
    if (grid_.insert_reading(pose, sensors_[k], readings[k]) != Status::kOk) ++rejected;
  }
  if (rebuilding_) {
    ++stats_.rebuild_scans;
    stats_.rebuild_rejected += rejected;
  } else {
    ++stats_.scans;
    stats_.rejected += rejected;
  }
  return Status::kOk;
}

Status Explorer::finish(uint32_t max_slices) {
  if (!configured_) return Status::kFailedPrecondition;
  for (uint32_t k = 0; k < max_slices; ++k) {
    PoseGraphProgress progress;
    SEQSLAM_TRY(graph_.optimise_step(config_.optimise_budget, &progress));
    stats_.optimise_work += progress.work;
    if (progress.converged) return Status::kOk;
    ++stats_.final_slices;
  }
  return graph_.converged() ? Status::kOk : Status::kResourceExhausted;
}

Status Explorer::begin_rebuild() {
  if (!configured_) return Status::kFailedPrecondition;
  if (tiles_ != nullptr) {
    SEQSLAM_TRY(grid_.clear());
  }
  rebuilding_ = true;
  hanging_ = false;
  next_rebuild_node_ = 0;
  stats_.rebuild_places = 0;
  stats_.rebuild_scans = 0;
  stats_.rebuild_rejected = 0;
  return Status::kOk;
}

void Explorer::rebuild_place(uint32_t place, const Pose2& odometry) {
  if (!rebuilding_ || next_rebuild_node_ >= graph_.node_count()) return;
  if (graph_.place(next_rebuild_node_).value() != place) return;  // it made no node
  hang_from(next_rebuild_node_++, odometry);
  ++stats_.rebuild_places;
}

Status Explorer::flush_map() {
  if (!configured_) return Status::kFailedPrecondition;
  return tiles_ != nullptr ? grid_.flush() : Status::kOk;
}

}  // namespace seqslam
