// The firmware application's files on the volume: what to do (the run configuration) and
// what it found (the results). Both are record logs like every other seqslam file, so the PC
// tools read what the robot wrote and the robot reads what the PC prepared, with the same
// checks (docs/dream_format.md, "Run configuration" and "Results").
//
// Volume file names used by the application (firmware/app):
//   config       - RunConfig (a log header, no records); absent: defaults
//   replay       - a dream recording the board replays as its sensor bus and camera (QEMU,
//                  host): absent on a robot with live sensors
//   library      - place library metadata   } written by teach, read by repeat
//   library.img  - place library images     }
//   record       - the dream recording written in record mode
//   results      - one RunResult per localisation step (repeat, or teach + repeat)
//   queries      - the route search's query history (scratch, query_store.h)
//   map, graph   - explore mode: the occupancy grid's tiles and the pose graph (map_store.h)
#pragma once

#include <stdint.h>

#include "seqslam/hal/block_device.h"
#include "seqslam/hal/pixel_buffer.h"
#include "seqslam/localiser.h"
#include "seqslam/occupancy_grid.h"
#include "seqslam/odometry.h"
#include "seqslam/spatial_trigger.h"
#include "seqslam/storage/record_log.h"

namespace seqslam::storage {

// Version 2 added the sequence matcher and the heuristic's settings, version 3 the explore
// mode and the map's frame and bounds, version 4 the route search's settings
// (docs/firmware.md). An older configuration is refused
// like any other version (kFailedPrecondition, LogProblem::kVersion): it is rewritten with
// `seqslam config write`, and an older reader refuses a newer file instead of silently running
// without what it cannot read (a version-2 firmware would otherwise see the explore bit as a
// damaged file, not as a newer one).
inline constexpr LogKind kRunConfigKind{{'S', 'Q', 'C', 'O', 'N', 'F', 'G', '1'}, 4};
inline constexpr LogKind kResultsKind{{'S', 'Q', 'R', 'E', 'S', 'L', 'T', '1'}, 1};

inline constexpr const char* kConfigFile = "config";
inline constexpr const char* kReplayFile = "replay";
inline constexpr const char* kLibraryFile = "library";
inline constexpr const char* kLibraryImagesFile = "library.img";
inline constexpr const char* kRecordFile = "record";
inline constexpr const char* kResultsFile = "results";

enum RunMode : uint8_t {
  kModeTeach = 1u << 0,     // build the library from this run and store it
  kModeRepeat = 1u << 1,    // localise against the stored library (with kModeTeach: against this
                            // run's own earlier places - loop closure - while building it)
  kModeRecord = 1u << 2,    // write this run as a dream recording
  kModeExplore = 1u << 3,   // with kModeTeach and kModeRepeat (required): also build the pose
                            // graph, close loops and build the occupancy grid (map, graph files)
  kModeContinue = 1u << 4,  // with kModeExplore (required): continue the explore run saved on
                            // the card (library, `state` file) instead of starting a new one
};

enum class TriggerMode : uint8_t {
  kDistance = 0,    // a capture every `spacing` metres of odometry (the robot)
  kEveryFrame = 1,  // every recorded frame is a place (recordings without odometry)
};

// HeuristicConfig's defaults with the head board's scan budget.
constexpr HeuristicConfig robot_heuristic() {
  HeuristicConfig h;
  h.scan_places = 96;
  return h;
}

struct RunConfig {
  uint8_t modes = kModeRepeat;
  TriggerMode trigger = TriggerMode::kDistance;
  hal::PipelineMapping mapping{};  // also fixes the image size
  PreprocessConfig preprocess{};
  SequenceConfig sequence{};
  uint8_t max_shift = 0;
  uint16_t recent_exclusion = 50;
  OdometryConfig odometry{};
  Q31_32 spacing = Q31_32::from_ratio(1, 5);
  bool record_colour = false;
  LocaliserMatcher matcher = LocaliserMatcher::kDiagonal;
  // Candidates (k), candidate threshold, guard and the scan's budget are stored; seq_len and
  // exclusion are not (the heuristic uses sequence.seq_len and sequence.exclusion, see
  // LocaliserConfig). The robot's default budget: 96 library places a step for the first
  // image's greedy scan (about 29 ms of a step with the card, docs/firmware.md).
  HeuristicConfig heuristic = robot_heuristic();
  // Explore: the occupancy grid's frame (the odometry frame: the run starts at the origin,
  // heading along +x) and bounds. Default: 80 m x 80 m of 5 cm cells centred on the start.
  int32_t grid_origin_x_mm = -40000;
  int32_t grid_origin_y_mm = -40000;
  uint16_t grid_cell_mm = 50;
  uint16_t grid_width = 1600;   // cells
  uint16_t grid_height = 1600;  // cells
  // The route search (teach / repeat with the diagonal matcher; route_search.h). Its start
  // place is used in repeat mode; teach + repeat (loop closure) always starts unknown.
  RouteSearchConfig route{};

  // The occupancy grid these settings amount to (log-odds settings: GridConfig's defaults).
  GridConfig grid() const {
    GridConfig g;
    g.origin_x = Q31_32::from_ratio(grid_origin_x_mm, 1000);
    g.origin_y = Q31_32::from_ratio(grid_origin_y_mm, 1000);
    g.cell_mm = grid_cell_mm;
    g.width = grid_width;
    g.height = grid_height;
    return g;
  }

  // The localiser configuration these settings amount to.
  LocaliserConfig localiser() const {
    LocaliserConfig c;
    c.image_size = mapping.size();
    c.preprocess = preprocess;
    c.max_shift = max_shift;
    c.sequence = sequence;
    c.recent_exclusion = recent_exclusion;
    c.matcher = matcher;
    c.heuristic = heuristic;
    c.route = route;
    return c;
  }
};

// One localisation step of the application.
struct RunResult {
  uint32_t step = 0;     // localisation step (0, 1, ...)
  uint32_t capture = 0;  // capture (place) index in this run
  uint32_t timestamp_us = 0;
  Pose2 pose{};        // odometry pose at the capture
  int32_t place = -1;  // best library place, -1 while no full sequence
  int32_t runner_up = -1;
  uint32_t cost = 0;
  uint32_t runner_up_cost = 0;
  UQ16_16 confidence = UQ16_16::from_int(1);
  bool localised = false;
  uint8_t route = 0;  // what the route search did: RouteResultBits (0 for the other searches)
};

// RunResult::route (stored in a byte that earlier writers left 0).
enum RouteResultBits : uint8_t {
  kRouteCarried = 1u << 0,        // the place is a scan's answer carried along its diagonal
  kRouteScanRunning = 1u << 1,    // the relocalisation scan ran during the step
  kRouteScanCompleted = 1u << 2,  // ... and completed
  kRouteJumped = 1u << 3,         // ... confidently elsewhere: the window moved there
  kRouteProbation = 1u << 4,      // the prediction came from a jump not yet confirmed
  kRouteTracking = 1u << 5,       // a prediction existed (known start, or found by a scan)
};

// What a build of the firmware application can run beyond what the format holds: the sizes
// its static state was made for and its optional features (firmware/app/app_limits.h has the
// application's; `seqslam config write` checks with the same ones before writing).
struct RunLimits {
  uint16_t seq_len = 0;       // S of the diagonal matcher (route search, explore's full search)
  uint16_t norm_window = 0;   // W (route search)
  uint16_t exclusion = 0;     // R (route search)
  uint16_t route_window = 0;  // route.window: the route search's diagonals
  uint16_t scan_seq_len = 0;  // the relocalisation scan's sequence (route.scan_seq_len, at most S)
  bool heuristic = false;     // the heuristic matcher is built in
  bool mapping = false;       // explore is built in
};

// Which setting check_run_config refused, grouped by the status it returns with it.
enum class RunIssue : uint8_t {
  kNone = 0,
  kHeuristicNotBuilt,      // kFailedPrecondition: matcher heuristic, not built in
  kMappingNotBuilt,        // kFailedPrecondition: explore, mapping not built in
  kExploreHeuristic,       // kInvalidArgument: explore with the heuristic matcher
  kRouteMaxShift,          // kInvalidArgument: route search with max_shift not 0
  kSpacingOutOfRange,      // kOutOfRange: spacing <= 0 or above SpatialTrigger::kMaxSpacing
  kSeqLenAboveLimit,       // kOutOfRange: diagonal matcher, sequence.seq_len > seq_len
  kWindowAboveLimit,       // kOutOfRange: route search, sequence.window > norm_window
  kExclusionAboveLimit,    // kOutOfRange: route search, sequence.exclusion > exclusion
  kRouteWindowAboveLimit,  // kOutOfRange: route search, route.window > route_window
  kScanSeqLenAboveLimit,   // kOutOfRange: route search, the scan's sequence > scan_seq_len
};
// A sentence naming the setting and the limit's name (a code "RC<n>" on the board).
const char* run_issue_text(RunIssue issue);

struct RunCheck {
  Status status = Status::kOk;
  RunIssue issue = RunIssue::kNone;
  constexpr bool ok() const { return status == Status::kOk; }
};

// Whether an application with `limits` runs `config` (one that read_run_config accepts):
// the firmware checks this at start, before it opens any file, and `seqslam config write`
// before it writes. The trigger's spacing, the matcher's and explore's features, S for the
// diagonal matcher (the route search and explore's full search) and, where the route search
// runs (the diagonal matcher in teach or repeat mode, not explore), its sizes and plain SAD.
// Inline: the firmware's limits are constants, folded into its copy (the head board's RAM).
constexpr RunCheck check_run_config(const RunConfig& c, const RunLimits& limits) {
  const bool explore = (c.modes & kModeExplore) != 0;
  if (c.spacing.raw() <= 0 || c.spacing > SpatialTrigger::kMaxSpacing) {
    return {Status::kOutOfRange, RunIssue::kSpacingOutOfRange};
  }
  if (explore && !limits.mapping) return {Status::kFailedPrecondition, RunIssue::kMappingNotBuilt};
  if (c.matcher == LocaliserMatcher::kHeuristic) {
    if (!limits.heuristic) return {Status::kFailedPrecondition, RunIssue::kHeuristicNotBuilt};
    if (explore) return {Status::kInvalidArgument, RunIssue::kExploreHeuristic};
    return {};
  }
  if (c.sequence.seq_len > limits.seq_len) {
    return {Status::kOutOfRange, RunIssue::kSeqLenAboveLimit};
  }
  // The route search runs with the diagonal matcher in teach and repeat mode (teach alone
  // configures it too), not in explore (its full search).
  if (explore || (c.modes & (kModeTeach | kModeRepeat)) == 0) return {};
  if (c.sequence.window > limits.norm_window) {
    return {Status::kOutOfRange, RunIssue::kWindowAboveLimit};
  }
  if (c.sequence.exclusion > limits.exclusion) {
    return {Status::kOutOfRange, RunIssue::kExclusionAboveLimit};
  }
  if (c.route.window > limits.route_window) {
    return {Status::kOutOfRange, RunIssue::kRouteWindowAboveLimit};
  }
  // The scan's sequence: the shorter of route.scan_seq_len and S.
  if (c.route.scan_seq_len > limits.scan_seq_len && c.sequence.seq_len > limits.scan_seq_len) {
    return {Status::kOutOfRange, RunIssue::kScanSeqLenAboveLimit};
  }
  if (c.max_shift != 0) return {Status::kInvalidArgument, RunIssue::kRouteMaxShift};
  return {};
}

// Writes `config` as the header of a run-configuration log on `device`. kInvalidArgument if
// the localiser or odometry part is invalid; log and device statuses.
Status write_run_config(hal::BlockDevice& device, const RunConfig& config);
// Reads it back. kDataLoss for a damaged or invalid configuration, kFailedPrecondition for
// another version; log and device statuses (a device without one: kDataLoss / kWrongKind).
Status read_run_config(hal::BlockDevice& device, RunConfig* config, LogProblem* problem = nullptr);

class ResultsWriter {
 public:
  Status create(hal::BlockDevice& device, LogProblem* problem = nullptr);
  // Continues the results stored on `device` (a run continued from the card): statuses of
  // LogWriter::reopen.
  Status reopen(hal::BlockDevice& device, LogProblem* problem = nullptr);
  Status append(const RunResult& r, LogProblem* problem = nullptr);
  uint32_t count() const { return log_.records(); }

 private:
  LogWriter log_{};
};

class ResultsReader {
 public:
  Status open(hal::BlockDevice& device, LogProblem* problem = nullptr);
  // kOk, kOutOfRange at the end, kDataLoss for a damaged or malformed record (skipped).
  Status next(RunResult* out);
  LogProblem end_problem() const { return log_.end_problem(); }
  uint32_t lost_records() const { return log_.lost_records(); }

 private:
  LogReader log_{};
  uint8_t buffer_[kRecordOverhead + 64] = {};
};

}  // namespace seqslam::storage
