// The session: the one component that turns a checked run configuration
// (storage/run_config.h) into a running pipeline and drives it, place by place and snapshot by
// snapshot - the odometry and the spatial trigger, the localiser with its matcher, and in
// explore mode the explorer (graph node, loop-closure gate, closure edge, optimiser slice,
// the infrared scans into the map). The firmware (firmware/app) runs it with static storage
// on the card's files; the PC tools run the very same code with heap storage on recordings
// and image sets (`seqslam run`, `eval`, `slam`, the simulator's evaluation): the PC is the
// board's simulator, not a second implementation (ArduPilot's SITL principle).
//
// The matcher is chosen from one table (session.cpp, kMatchers): each entry is a matcher and,
// for the diagonal matcher, how it searches, with the function that configures the localiser
// for it on the session's storage. Entries are compiled in by the build's features (the
// firmware's profile: the heuristic where SEQSLAM_APP_HEURISTIC, the full search and explore
// where SEQSLAM_APP_MAPPING; the slope matcher on the PC), so an image links only what it
// can run (tinyusb's driver table).
//
// All memory is the caller's (SessionParts); SessionStorage sizes it at compile time.
#pragma once

#include <stdint.h>

#include "seqslam/hal/spinal_cord.h"
#include "seqslam/localiser.h"
#include "seqslam/odometry.h"
#include "seqslam/query_history.h"
#include "seqslam/route_search.h"
#include "seqslam/session/features.h"
#include "seqslam/spatial_trigger.h"
#include "seqslam/storage/run_config.h"

#if SEQSLAM_APP_MAPPING
#include "seqslam/explorer.h"
#endif

namespace seqslam::session {

// How the diagonal matcher searches the library: the route search (a window around the
// odometry's prediction and a relocalisation scan: what the head board runs in teach and
// repeat) or the whole library every step (explore, and the PC's reference).
enum class Search : uint8_t { kRoute = 0, kFull = 1 };

// The storage the matchers work in; each matcher needs only its own part (the others may
// stay empty).
struct MatcherParts {
  DiagonalMatcherBuffers full{};  // the full search's state
  Span<uint32_t> differences{};   // a difference row: the full search and the slope matcher
  RouteSearch* route = nullptr;   // the route search and its storage
  RouteSearchBuffers route_buffers{};
  // The query history: the route search's (required), a budgeted heuristic's (its scan's
  // first image; required when heuristic.scan_places > 0).
  QueryHistory* history = nullptr;
  HeuristicMatcher* heuristic = nullptr;
  SlopeMatcher* slope = nullptr;
  SlopeMatcherBuffers slope_buffers{};
};

// What a session runs on: the library (configured for the run's image size, on the card or
// in RAM) and the matchers' and the explorer's storage.
struct SessionParts {
  PlaceLibrary* library = nullptr;
  MatcherParts matcher{};
#if SEQSLAM_APP_MAPPING
  ExplorerBuffers explorer{};  // explore mode only
#endif
};

// The odometry's counters (the snapshots the session was given).
struct SessionStats {
  uint32_t no_encoders = 0;        // snapshots without encoder data (distance trigger)
  uint32_t odometry_glitches = 0;  // implausible encoder jumps skipped
  uint32_t odometry_resyncs = 0;   // ... that persisted and were accepted as the new baseline
};

// What one place did.
struct PlaceStep {
  bool matched = false;  // a localisation step ran (repeat modes): `match` is its answer
  Match match{};
  bool taught = false;        // the place went into the library
  bool library_full = false;  // ... or was refused because the library is full
  bool routed = false;        // the route search ran: `route` says what it did
  RouteStepInfo route{};
#if SEQSLAM_APP_MAPPING
  bool explored = false;  // explore: `explore` is the explorer's step for this place
  ExplorerStep explore{};
  Status explore_status = Status::kOk;  // the explorer's status (the run goes on after one)
#endif
};

// Why configure() refused: the localiser's issue, or one of the session's own.
enum class SessionIssue : uint8_t {
  kNone = 0,
  kLocaliser,        // the localiser refused (ConfigCheck::issue says why)
  kNoLibrary,        // SessionParts::library is null
  kMatcherNotBuilt,  // no entry of the matcher table runs this matcher and search
  kOdometry,         // the odometry or the trigger refused the configuration
  kExplorer,         // the explorer refused (explorer_issue / grid_issue say why)
};
const char* session_issue_text(SessionIssue issue);

struct SessionCheck {
  Status status = Status::kOk;
  SessionIssue issue = SessionIssue::kNone;
  ConfigIssue localiser_issue = ConfigIssue::kNone;
#if SEQSLAM_APP_MAPPING
  ExplorerIssue explorer_issue = ExplorerIssue::kNone;
  GridIssue grid_issue = GridIssue::kNone;
#endif
  bool ok() const {
    return status == Status::kOk;
  }
};

// Why the firmware refused to start or stopped recording and results (firmware/app): a
// sentence on the PC, a code "FW<n>" on the head board (messages.h; `seqslam explain FW3`).
enum class FirmwareIssue : uint8_t {
  kNone = 0,
  kNoSensors,           // no live bus and camera, and no replay file
  kMappingRefused,      // the camera or the replay cannot produce the configured mapping
  kReducedReplay,       // a distance trigger on a replay without odometry
  kNeedsLibrary,        // teach or repeat without the library files
  kNeedsResults,        // repeat without a results file
  kNeedsQueries,        // the route search without a query history file
  kQueriesTooSmall,     // ... one too small for the scan's images (or one image)
  kNeedsRecord,         // record mode without a record file
  kNoColour,            // record-colour with a grey replay
  kExploreLive,         // explore on live sensors without record mode
  kNeedsMapFiles,       // explore without the map and graph files
  kContinueSource,      // continue without the replay, or with record mode
  kNoState,             // continue without a state file
  kStateMismatch,       // a saved state that does not fit the library on the card
  kReplayMismatch,      // a replay that does not begin with the saved run
  kInvalidSettings,     // a run configuration its check refuses
  kDataLost,            // damaged replay records or storage errors during the run
  kResultsStopped,      // the results file full or failing: results stop
  kRecordingStopped,    // the recording full or failing: the recording stops
  kScanCannotComplete,  // a query history too small for a scan over the library
};
const char* firmware_issue_text(FirmwareIssue issue);

class Session {
 public:
  // Wires the pipeline for `config` (a configuration check_run_settings accepts): the
  // odometry and trigger, the localiser with the matcher of config.matcher (the diagonal
  // matcher searching as `search` says; explore always searches the whole library), and in
  // explore mode the explorer (config.explorer() with the storage of parts.explorer). The
  // session keeps a reference to `config` (it must outlive the session's use: the firmware's
  // RAM holds one copy). On failure the session is unconfigured and the check says why.
  SessionCheck configure(const storage::RunConfig& config, Search search,
                         const SessionParts& parts);

  // A library place, taught outside a run (the PC tools build a library from a recording or
  // an image set): the localiser's teach() statuses.
  Status teach(ImageView raw, const Pose2& pose, uint32_t capture);

  // One sensor snapshot: the odometry (distance trigger), the map's scan in explore mode,
  // then the trigger. True when an image should be captured (every snapshot with the
  // every-frame trigger). Snapshots that move nothing (no encoders, an implausible jump) are
  // counted (stats()) and never capture.
  bool snapshot(const hal::SensorSnapshot& snap);
  // The odometry's pose (the place's pose when snapshot() asked for a capture).
  Pose2 pose() const { return odometry_.pose(); }

  // One captured image as a place of the run, at `pose`: teach, localise or observe (teach +
  // repeat: loop closure) as config.modes say, then explore's step for a place the library
  // took. A full library is counted in the step, not an error, and so is the explorer's
  // status (PlaceStep::explore_status). Statuses: the localiser's (invalid image, storage).
  Status place(ImageView raw, const Pose2& pose, uint32_t capture, PlaceStep* out);

  // Work between places, in slices between snapshots: up to `budget` library places of the
  // route search's scan (Localiser::work); the places streamed. What a caller leaves, the
  // next place streams first, so the answers do not depend on the slicing.
  uint32_t work(uint32_t budget) { return configured_ ? localiser_.work(budget) : 0u; }

  // A new run against the same library (and graph): the sequence, the odometry and the
  // trigger start afresh (the next snapshot is the odometry's origin).
  void begin_run();

#if SEQSLAM_APP_MAPPING
  // Explore's end: the graph to convergence in at most `max_slices` optimiser slices.
  Status finish(uint32_t max_slices);
  // The map again from the start of the run's stream at the optimised poses: begin_rebuild(),
  // then every snapshot to rebuild_snapshot() and, when it asks for a capture that produced a
  // frame, rebuild_place(); end_rebuild(). The odometry and the trigger replay the run's own
  // (so every snapshot hangs from the place it hung from while exploring); their counters
  // are not the run's.
  Status begin_rebuild();
  bool rebuild_snapshot(const hal::SensorSnapshot& snap);
  void rebuild_place(uint32_t capture);
  void end_rebuild();
  Explorer& explorer() {
    return explorer_;
  }
  const Explorer& explorer() const {
    return explorer_;
  }
  bool exploring() const {
    return exploring_;
  }
#endif

  // The run's state for continuing it later (state_io.h): the odometry, the trigger, the
  // localiser's sequence and, exploring, the explorer.
  template <class Io>
  void state(Io& io) {
    io.tag(state_tag("SESS"));
    io.field(stats_.no_encoders);
    io.field(stats_.odometry_glitches);
    io.field(stats_.odometry_resyncs);
    io.field(odometry_started_);
    io.field(consecutive_glitches_);
    odometry_.state(io);
    trigger_.state(io);
    localiser_.state(io);
#if SEQSLAM_APP_MAPPING
    if (exploring_) explorer_.state(io);
#endif
  }

  const Localiser& localiser() const {
    return localiser_;
  }
  Localiser& localiser() {
    return localiser_;
  }
  const storage::RunConfig& config() const {
    return *config_;
  }
  const SessionStats& stats() const {
    return stats_;
  }
  Search search() const {
    return search_;
  }

 private:
  SessionCheck wire_matcher(const SessionParts& parts);
  // The odometry from one snapshot; false when it moves nothing.
  bool advance_odometry(const hal::SensorSnapshot& snap, SessionStats* counts);
#if SEQSLAM_APP_MAPPING
  SessionCheck wire_explorer(const SessionParts& parts);
  void scan(const hal::SensorSnapshot& snap);
#endif

  const storage::RunConfig* config_ = nullptr;
  Search search_ = Search::kRoute;
  bool configured_ = false;
  SessionStats stats_{};
  Odometry odometry_{};
  SpatialTrigger trigger_{};
  bool odometry_started_ = false;
  uint32_t consecutive_glitches_ = 0;
  Localiser localiser_{};
  PlaceLibrary* library_ = nullptr;
#if SEQSLAM_APP_MAPPING
  Explorer explorer_{};
  bool exploring_ = false;
#endif
};

}  // namespace seqslam::session
