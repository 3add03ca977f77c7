// The explorer: the mapping step of one captured place, written once for everything that maps
// (the firmware's explore mode, `seqslam slam`, the mapping bench; docs/mapping.md, "The
// explorer").
//
// Per place, after the localiser has matched it against the run's own earlier places
// (Localiser::observe appended it to the library, so library place i is graph node i):
//   1. a pose-graph node at the odometry pose (re-anchored after a relocalisation, below);
//   2. the loop-closure gate on the localiser's answer (loop_closure.h), with the image-rank
//      rule over the localiser's difference row;
//   3. on a closure, the edge: aligned along the matched pass (align_closure: it joins the
//      aligned place, dx the rest of a place times the capture spacing), its heading from the
//      horizontal shift between the two places' library images (subpixel_shift,
//      shift_to_heading); a card that fails during either falls back to the matched place and
//      the same heading, counted, never fatal;
//   4. on a relocalisation (the gate's kRelocalised, off by default), the odometry is
//      re-anchored at the matched node from here on, and the places since the last fix are no
//      longer trusted for the map (their snapshots are left out of a rebuild);
//   5. one optimiser slice of `optimise_budget` units.
// Per 10 ms snapshot, scan() puts the infrared readings into the occupancy grid at the current
// estimate of the last place composed with the odometry since it. After the last place,
// finish() optimises to convergence; a rebuild (begin_rebuild(), then per captured frame
// rebuild_place() and per snapshot scan() again, fed from the recording) redraws the grid at
// the optimised poses.
//
// Memory is the caller's (ExplorerBuffers): the graph's node and edge arrays, the grid's RAM
// tiles and tile store, one image of scratch (docs/mapping.md, "The explorer").
#pragma once

#include <stdint.h>

#include "seqslam/closure_align.h"
#include "seqslam/fixed.h"
#include "seqslam/loop_closure.h"
#include "seqslam/occupancy_grid.h"
#include "seqslam/place_library.h"
#include "seqslam/pose_graph.h"
#include "seqslam/span.h"
#include "seqslam/status.h"

namespace seqslam {

// The explorer's graph: its loop closures come from images, which place two passes along the
// route but cannot see how far apart side by side they ran, so a closure's position
// information across the route is 3 % of along it (chosen on seed 1's explore runs,
// docs/mapping.md "Closures weak across the route").
constexpr PoseGraphConfig explorer_graph_config() {
  PoseGraphConfig c{};
  c.closure_lateral = UQ16_16::from_ratio(3, 100);
  return c;
}

// The settings; these defaults are the only ones (the firmware, `seqslam slam` and the bench
// start from them; docs/mapping.md says where each was measured).
struct ExplorerConfig {
  LoopClosureConfig gate{};
  PoseGraphConfig graph = explorer_graph_config();
  GridConfig grid{};
  // Closure edges: information relative to 1 m of odometry.
  EdgeInformation closure_information{UQ16_16::from_int(1), UQ16_16::from_int(1)};
  // Alignment along the matched pass; align.length 0: off (the matched place, same position).
  ClosureAlignConfig align{15, 5, 2};
  // The closure's heading from the image shift over +-max_shift columns and an effective field
  // of view `hfov` (fitted on the simulator's camera); max_shift 0: off (the same heading).
  uint8_t max_shift = 6;
  Angle hfov = Angle::from_degrees(50);
  // Optimiser work units per place (the mapping step's time bound; docs/performance.md).
  uint32_t optimise_budget = 2000;
  // The localiser's recent exclusion (LocaliserConfig::recent_exclusion): the newest places,
  // not yet known ground for the gate's aliasing test.
  uint16_t recent_exclusion = 50;
  // The capture spacing (metres): turns the alignment's fraction of a place into metres.
  Q31_32 spacing = Q31_32::from_ratio(1, 5);
};

// Why configure() refused (with kInvalidArgument / kOutOfRange / kResourceExhausted).
enum class ExplorerIssue : uint8_t {
  kNone = 0,
  kGate,     // a LoopClosureConfig setting out of range
  kGraph,    // the pose graph's settings or buffers
  kGrid,     // the grid's settings or RAM slots (grid_issue in the check)
  kAlign,    // align.length or max_offset out of range
  kHeading,  // max_shift above kMaxSubpixelShift, or hfov 0
  kBudget,   // optimise_budget 0
  kSpacing,  // spacing <= 0 or above SpatialTrigger::kMaxSpacing
};
const char* explorer_issue_text(ExplorerIssue issue);

struct ExplorerCheck {
  Status status = Status::kOk;
  ExplorerIssue issue = ExplorerIssue::kNone;
  GridIssue grid_issue = GridIssue::kNone;
  bool ok() const { return status == Status::kOk; }
};

struct ExplorerBuffers {
  PoseGraphBuffers graph;
  OccupancyGridBuffers grid;
  TileStore* tiles = nullptr;       // null: no map (scan() does nothing)
  Span<const RangeSensor> sensors;  // the robot's range sensors, in reading order
  Span<uint8_t> scratch;            // one image: the closure's alignment and matched image
};

// What one place did.
struct ExplorerStep {
  LoopClosureDecision decision;
  int32_t node = -1;        // the place's graph node; -1: not added (graph full, step too long)
  int32_t closure_to = -1;  // a closure: the node it joined (after the alignment); else -1
  uint32_t gate_place = 0;  // a closure: the matcher's place the gate accepted
  RelativePose2 closure{};  // a closure: the edge's measurement (dx along, dtheta)
  Q15_16 shift{};           // a closure: the image shift behind dtheta, columns
  Status align_status = Status::kOk;    // a closure: kOk or why it joined the matched place
  Status heading_status = Status::kOk;  // a closure: kOk or why it kept the same heading
  bool relocalised = false;             // the odometry was re-anchored at this place
  PoseGraphProgress progress;
};

struct ExplorerStats {
  uint32_t nodes = 0;               // places added to the graph
  uint32_t graph_full = 0;          // places not added (full, or a step out of range)
  uint32_t closures = 0;            // closure edges added
  uint32_t closures_realigned = 0;  // ... joined to a neighbour of the matched place
  uint32_t align_failures = 0;      // ... whose alignment could not read an image
  uint32_t heading_failures = 0;    // ... whose heading could not be measured (same heading)
  uint32_t relocalisations = 0;     // re-anchorings of the odometry
  uint32_t untrusted_places = 0;    // places left out of the map by relocalisations
  uint64_t optimise_work = 0;       // optimiser units, per place and final
  uint32_t slices = 0;              // per-place optimiser slices that did work
  uint32_t final_slices = 0;        // finish()'s slices
  uint32_t scans = 0;               // snapshots put into the grid while exploring
  uint32_t rejected = 0;            // ... readings the grid refused (range, bounds, store)
  uint32_t rebuild_places = 0;      // nodes found again by rebuild_place()
  uint32_t rebuild_scans = 0;       // snapshots put into the rebuilt grid
  uint32_t rebuild_rejected = 0;    // ... readings refused
};
template <class Io>
void persist(Io& io, ExplorerStats& s) {
  io.field(s.nodes);
  io.field(s.graph_full);
  io.field(s.closures);
  io.field(s.closures_realigned);
  io.field(s.align_failures);
  io.field(s.heading_failures);
  io.field(s.relocalisations);
  io.field(s.untrusted_places);
  io.field(s.optimise_work);
  io.field(s.slices);
  io.field(s.final_slices);
  io.field(s.scans);
  io.field(s.rejected);
  io.field(s.rebuild_places);
  io.field(s.rebuild_scans);
  io.field(s.rebuild_rejected);
}

// Relocalisations remembered for the map (each a range of untrusted places); more merge into
// the last range, which then distrusts everything between them (conservative).
inline constexpr uint32_t kMaxUntrustedRanges = 8;

class Explorer {
 public:
  // Checks every setting, then configures the graph, the gate and (with a tile store) the
  // grid, and resets. Nothing is kept on failure.
  ExplorerCheck configure(const ExplorerConfig& config, const ExplorerBuffers& buffers);

  // A new run of the same library, graph and map (a robot that explored before): its odometry
  // starts again (a relocalisation's re-anchoring ends). The localiser's sequence is the
  // caller's to reset.
  void begin_run();

  // The mapping step of one place (see the top of this file). `library` holds the place as
  // its newest one (library.size() - 1 must be the next node), `differences` the localiser's
  // difference row for it, `match` its answer, `odometry` the odometry pose at the capture
  // and `place` the caller's index of it (kept by the graph). Returns kOk (also when the
  // graph is full: step->node -1, counted), kFailedPrecondition before configure(),
  // kInvalidArgument for a null `step`, the gate's errors otherwise.
  Status place(PlaceLibrary& library, Span<const uint32_t> differences, const Match& match,
               const Pose2& odometry, uint32_t place, ExplorerStep* step);

  // One snapshot's range readings (readings[k] from sensors[k]; extra readings are ignored)
  // at the current estimate of the last place composed with the odometry since it; before
  // the first place, at the odometry. Readings the grid refuses are counted. Returns kOk, or
  // kFailedPrecondition before configure().
  Status scan(const Pose2& odometry, Span<const uint16_t> readings);

  // After the last place: optimiser slices until the graph converges or `max_slices` have
  // run. kOk when converged, kResourceExhausted when the bound stopped it first,
  // kFailedPrecondition before configure().
  Status finish(uint32_t max_slices);

  // Redraws the map: clears the grid and rewinds to the first node. Then, replaying the same
  // snapshots and captures in order: rebuild_place() for every captured frame (`place` as
  // given to place()), scan() for every snapshot. The grid's store errors come back.
  Status begin_rebuild();
  void rebuild_place(uint32_t place, const Pose2& odometry);
  void end_rebuild() { rebuilding_ = false; }

  // Saves the grid's resident tiles to the store.
  Status flush_map();

  const PoseGraph& graph() const { return graph_; }
  const LoopClosureGate& gate() const { return gate_; }
  const OccupancyGrid& grid() const { return grid_; }
  bool has_map() const { return tiles_ != nullptr; }
  const ExplorerConfig& config() const { return config_; }
  const ExplorerStats& stats() const { return stats_; }
  // Whether node i's snapshots go into a rebuilt map (false after a relocalisation made it
  // untrusted).
  bool trusted(uint32_t node) const;

  // Everything a later place depends on, to continue a stopped run exactly (state_io.h): the
  // graph with the optimiser's position, the gate, the node the snapshots hang from, the
  // relocalisation's re-anchoring, the untrusted places and the counters. Not the grid: the
  // map is redrawn from the final graph at the end of a run (begin_rebuild), so the grid
  // drawn while exploring never reaches it. Between two places, never while rebuilding
  // (kFailedPrecondition). Configure with the same settings and capacities first; a
  // restored state that does not fit them fails the io (kDataLoss) and the explorer resets.
  template <class Io>
  void state(Io& io) {
    if (!configured_ || rebuilding_) {
      io.fail_with(Status::kFailedPrecondition);
      return;
    }
    io.tag(state_tag("EXPL"));
    io.field(stats_);
    graph_.state(io);
    gate_.state(io);
    io.field(hang_odometry_);
    io.field(hang_node_);
    io.field(hanging_);
    io.field(rebase_from_);
    io.field(rebase_to_);
    io.field(rebased_);
    io.field(last_fix_);
    io.array(Span<uint32_t>(first_untrusted_));
    io.array(Span<uint32_t>(last_untrusted_));
    io.field(untrusted_ranges_);
    if (Io::kReading && io.ok() && !state_valid()) io.fail();
    if (Io::kReading && !io.ok()) reset_run_state();
  }

 private:
  void closure_edge(PlaceLibrary& library, uint32_t node, uint32_t known, uint32_t matched,
                    ExplorerStep* step);
  void distrust(uint32_t first, uint32_t last);
  void hang_from(uint32_t node, const Pose2& odometry);
  bool state_valid() const;
  void reset_run_state();

  ExplorerConfig config_{};
  PoseGraph graph_{};
  LoopClosureGate gate_{};
  OccupancyGrid grid_{};
  TileStore* tiles_ = nullptr;
  Span<const RangeSensor> sensors_{};
  Span<uint8_t> scratch_{};
  ExplorerStats stats_{};
  // The node the snapshots hang from, and its odometry pose (the run's own frame).
  Pose2 hang_odometry_{};
  uint32_t hang_node_ = 0;
  bool hanging_ = false;
  // After a relocalisation: the raw odometry pose and the graph pose it was re-anchored at.
  Pose2 rebase_from_{};
  Pose2 rebase_to_{};
  bool rebased_ = false;
  uint32_t last_fix_ = 0;  // the node of the last closure or relocalisation, or the run's first
  uint32_t first_untrusted_[kMaxUntrustedRanges] = {};
  uint32_t last_untrusted_[kMaxUntrustedRanges] = {};
  uint32_t untrusted_ranges_ = 0;
  uint32_t next_rebuild_node_ = 0;
  bool rebuilding_ = false;
  bool configured_ = false;
};

}  // namespace seqslam
