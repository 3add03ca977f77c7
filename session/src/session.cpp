#include "seqslam/session/session.h"

#include "seqslam/messages.h"

namespace seqslam::session {

namespace {

// A consecutive run of this many implausible encoder jumps is taken as real (e.g. the robot
// was carried) and becomes the new odometry baseline.
constexpr uint32_t kGlitchesBeforeResync = 3;

SessionCheck refuse(Status s, SessionIssue issue) {
  SessionCheck c;
  c.status = s;
  c.issue = issue;
  return c;
}

SessionCheck from_localiser(const ConfigCheck& check) {
  SessionCheck c;
  if (check.ok()) return c;
  c.status = check.status;
  c.issue = SessionIssue::kLocaliser;
  c.localiser_issue = check.issue;
  return c;
}

// ---------------------------------------------------------------------------------------
// The matcher table: how each matcher (and search) configures the localiser on the parts.

using Wire = ConfigCheck (*)(Localiser&, const LocaliserConfig&, PlaceLibrary&,
                             const MatcherParts&);

constexpr ConfigCheck kNoStorage{Status::kResourceExhausted, ConfigIssue::kStorageTooSmall};

ConfigCheck wire_route(Localiser& l, const LocaliserConfig& c, PlaceLibrary& library,
                       const MatcherParts& p) {
  if (p.route == nullptr || p.history == nullptr) return kNoStorage;
  return l.configure(c, library, *p.route, p.route_buffers, *p.history);
}

#if SEQSLAM_SESSION_FULL_SEARCH
ConfigCheck wire_full(Localiser& l, const LocaliserConfig& c, PlaceLibrary& library,
                      const MatcherParts& p) {
  return l.configure(c, library, p.full, p.differences);
}
#endif

#if SEQSLAM_APP_HEURISTIC
// A budgeted heuristic (scan_places > 0) reads its sequence's first image back from the
// query history, when there is one.
ConfigCheck wire_heuristic(Localiser& l, const LocaliserConfig& c, PlaceLibrary& library,
                           const MatcherParts& p) {
  if (p.heuristic == nullptr) return kNoStorage;
  return l.configure(c, library, *p.heuristic, c.heuristic.scan_places > 0 ? p.history : nullptr);
}
#endif

#if SEQSLAM_SESSION_SLOPE
ConfigCheck wire_slope(Localiser& l, const LocaliserConfig& c, PlaceLibrary& library,
                       const MatcherParts& p) {
  if (p.slope == nullptr) return kNoStorage;
  return l.configure(c, library, *p.slope, p.slope_buffers, p.differences);
}
#endif

// Each matcher the build runs and how it is wired; a missing part of its storage is
// kStorageTooSmall (the localiser's own buffer checks name the rest).
struct MatcherEntry {
  LocaliserMatcher matcher;
  Search search;    // the diagonal matcher's; the others run alike either way
  bool any_search;
  Wire wire;
};

constexpr MatcherEntry kMatchers[] = {
    {LocaliserMatcher::kDiagonal, Search::kRoute, false, &wire_route},
#if SEQSLAM_SESSION_FULL_SEARCH
    {LocaliserMatcher::kDiagonal, Search::kFull, false, &wire_full},
#endif
#if SEQSLAM_APP_HEURISTIC
    {LocaliserMatcher::kHeuristic, Search::kFull, true, &wire_heuristic},
#endif
#if SEQSLAM_SESSION_SLOPE
    {LocaliserMatcher::kSlope, Search::kFull, true, &wire_slope},
#endif
};

}  // namespace

const char* session_issue_text(SessionIssue issue) {
#if !SEQSLAM_MESSAGE_TEXTS
  return message_code("SE", static_cast<uint32_t>(issue));
#endif
  switch (issue) {
    case SessionIssue::kNone:
      return "the session runs this configuration";
    case SessionIssue::kLocaliser:
      return "the localiser refused the configuration";
    case SessionIssue::kNoLibrary:
      return "no place library given";
    case SessionIssue::kMatcherNotBuilt:
      return "this build does not run the configured matcher with this search";
    case SessionIssue::kOdometry:
      return "the odometry or the trigger refused the configuration";
    case SessionIssue::kExplorer:
      return "the explorer refused the configuration";
  }
  return "unknown session issue";
}

const char* firmware_issue_text(FirmwareIssue issue) {
#if !SEQSLAM_MESSAGE_TEXTS
  return message_code("FW", static_cast<uint32_t>(issue));
#endif
  switch (issue) {
    case FirmwareIssue::kNone:
      return "the firmware runs";
    case FirmwareIssue::kNoSensors:
      return "no live bus and camera, and no 'replay' file";
    case FirmwareIssue::kMappingRefused:
      return "the camera or the replay cannot produce this mapping";
    case FirmwareIssue::kReducedReplay:
      return "the replay has no odometry (reduced): use trigger every-frame";
    case FirmwareIssue::kNeedsLibrary:
      return "the volume needs 'library' and 'library.img'";
    case FirmwareIssue::kNeedsResults:
      return "the volume needs a 'results' file";
    case FirmwareIssue::kNeedsQueries:
      return "the volume needs a 'queries' file (docs/firmware.md)";
    case FirmwareIssue::kQueriesTooSmall:
      return "the 'queries' file is too small: it must hold the relocalisation scan's images "
             "(docs/firmware.md)";
    case FirmwareIssue::kNeedsRecord:
      return "the volume needs a 'record' file";
    case FirmwareIssue::kNoColour:
      return "record-colour: the replay has no colour to record";
    case FirmwareIssue::kExploreLive:
      return "explore on live sensors needs record mode (the map is rebuilt from it)";
    case FirmwareIssue::kNeedsMapFiles:
      return "the volume needs 'map' and 'graph' files (explore)";
    case FirmwareIssue::kContinueSource:
      return "continue needs the replay and no record mode (a recording is not continued)";
    case FirmwareIssue::kNoState:
      return "the volume has no 'state' file";
    case FirmwareIssue::kStateMismatch:
      return "the state does not fit the library on the card";
    case FirmwareIssue::kReplayMismatch:
      return "the replay does not begin with the saved run";
    case FirmwareIssue::kInvalidSettings:
      return "invalid settings";
    case FirmwareIssue::kDataLost:
      return "data lost: damaged replay records or storage errors (counts below)";
    case FirmwareIssue::kResultsStopped:
      return "results file full or failing: results stop here";
    case FirmwareIssue::kRecordingStopped:
      return "a place could not be written: the recording stops here";
    case FirmwareIssue::kScanCannotComplete:
      return "the 'queries' file is too small for a relocalisation scan over this library "
             "(docs/firmware.md): only tracking from a known start";
  }
  return "unknown firmware issue";
}

SessionCheck Session::configure(const storage::RunConfig& config, Search search,
                                const SessionParts& parts) {
  configured_ = false;
  library_ = parts.library;
  if (library_ == nullptr) return refuse(Status::kInvalidArgument, SessionIssue::kNoLibrary);
  if (odometry_.configure(config.odometry) != Status::kOk ||
      trigger_.configure(config.spacing) != Status::kOk) {
    return refuse(Status::kInvalidArgument, SessionIssue::kOdometry);
  }
  config_ = &config;
  // Explore matches against the run's own places over the whole library.
  const bool explore = (config.modes & storage::kModeExplore) != 0;
  search_ = explore ? Search::kFull : search;
  stats_ = SessionStats{};
  odometry_started_ = false;
  consecutive_glitches_ = 0;
  SessionCheck check = wire_matcher(parts);
  if (!check.ok()) return check;
#if SEQSLAM_APP_MAPPING
  exploring_ = false;
  if (explore) {
    check = wire_explorer(parts);
    if (!check.ok()) return check;
    exploring_ = true;
  }
#endif
  configured_ = true;
  return check;
}

SessionCheck Session::wire_matcher(const SessionParts& parts) {
  LocaliserConfig lc = config_->localiser();
  // Loop closure in one run (teach + repeat) has no known start: the route search scans.
  const uint8_t loop = storage::kModeTeach | storage::kModeRepeat;
  if ((config_->modes & loop) == loop) lc.route.start = -1;
  for (const MatcherEntry& e : kMatchers) {
    if (e.matcher != lc.matcher || (!e.any_search && e.search != search_)) continue;
    return from_localiser(e.wire(localiser_, lc, *library_, parts.matcher));
  }
  return refuse(Status::kFailedPrecondition, SessionIssue::kMatcherNotBuilt);
}

#if SEQSLAM_APP_MAPPING
SessionCheck Session::wire_explorer(const SessionParts& parts) {
  const ExplorerCheck ex = explorer_.configure(config_->explorer(), parts.explorer);
  if (ex.ok()) return {};
  SessionCheck c = refuse(ex.status, SessionIssue::kExplorer);
  c.explorer_issue = ex.issue;
  c.grid_issue = ex.grid_issue;
  return c;
}
#endif

Status Session::teach(ImageView raw, const Pose2& pose, uint32_t capture) {
  if (!configured_) return Status::kFailedPrecondition;
  return localiser_.teach(raw, pose, capture);
}

void Session::begin_run() {
  localiser_.reset_sequence();
  odometry_started_ = false;
  consecutive_glitches_ = 0;
  (void)trigger_.configure(config_->spacing);  // re-arms; the spacing was checked
#if SEQSLAM_APP_MAPPING
  if (exploring_) explorer_.begin_run();
#endif
}

bool Session::advance_odometry(const hal::SensorSnapshot& snap, SessionStats* counts) {
  if ((snap.flags & hal::SensorSnapshot::kHasEncoders) == 0) {
    ++counts->no_encoders;
    return false;
  }
  if (!odometry_started_) {
    odometry_.reset(Pose2{}, snap.encoder_left, snap.encoder_right);
    odometry_started_ = true;
  } else if (odometry_.update(snap.encoder_left, snap.encoder_right) != Status::kOk) {
    ++counts->odometry_glitches;
    if (++consecutive_glitches_ >= kGlitchesBeforeResync) {
      odometry_.resync(snap.encoder_left, snap.encoder_right);
      ++counts->odometry_resyncs;
      consecutive_glitches_ = 0;
    }
    return false;
  }
  consecutive_glitches_ = 0;
  return true;
}

bool Session::snapshot(const hal::SensorSnapshot& snap) {
  if (config_->trigger != storage::TriggerMode::kDistance) return true;
  if (!advance_odometry(snap, &stats_)) return false;
#if SEQSLAM_APP_MAPPING
  if (exploring_) scan(snap);
#endif
  return trigger_.update(odometry_.pose());
}

Status Session::place(ImageView raw, const Pose2& pose, uint32_t capture, PlaceStep* out) {
  if (!configured_) return Status::kFailedPrecondition;
  PlaceStep step;
  const bool teach = (config_->modes & storage::kModeTeach) != 0;
  const bool repeat = (config_->modes & storage::kModeRepeat) != 0;
  Status s = Status::kOk;
  if (teach && repeat) {
    s = localiser_.observe(raw, pose, capture, &step.match);
  } else if (repeat) {
    s = localiser_.localise(raw, &step.match);
  } else if (teach) {
    s = localiser_.teach(raw, pose, capture);
  }
  if (teach) {
    step.taught = s == Status::kOk;
    // The library (RAM metadata or the card) is full: localising goes on.
    if (s == Status::kResourceExhausted) {
      step.library_full = true;
      s = Status::kOk;
    }
  }
  if (s == Status::kOk && repeat) {
    step.matched = true;
    if (localiser_.route() != nullptr) {
      step.routed = true;
      step.route = localiser_.route_step();
    }
  }
#if SEQSLAM_APP_MAPPING
  // Only places the localiser took in (observe appended them) become nodes: library place i
  // is then node i.
  if (s == Status::kOk && exploring_ && step.taught) {
    const uint32_t* row = localiser_.last_differences();
    step.explore_status =
        explorer_.place(*library_, Span<const uint32_t>(row, row != nullptr ? library_->size() : 0),
                        step.match, pose, capture, &step.explore);
    step.explored = step.explore_status == Status::kOk;
  }
#endif
  if (out != nullptr) *out = step;
  return s;
}

#if SEQSLAM_APP_MAPPING
// A snapshot's infrared readings into the grid (explorer.h: at the last place's estimate and
// the odometry since it).
void Session::scan(const hal::SensorSnapshot& snap) {
  if ((snap.flags & hal::SensorSnapshot::kHasInfrared) == 0) return;
  const uint32_t n =
      snap.infrared_count < hal::kMaxInfrared ? snap.infrared_count : hal::kMaxInfrared;
  (void)explorer_.scan(odometry_.pose(), Span<const uint16_t>(snap.infrared_mm, n));
}

Status Session::finish(uint32_t max_slices) {
  if (!exploring_) return Status::kFailedPrecondition;
  return explorer_.finish(max_slices);
}

Status Session::begin_rebuild() {
  if (!exploring_) return Status::kFailedPrecondition;
  Status s = explorer_.begin_rebuild();
  if (s == Status::kOk) s = trigger_.configure(config_->spacing);
  odometry_started_ = false;
  consecutive_glitches_ = 0;
  return s;
}

bool Session::rebuild_snapshot(const hal::SensorSnapshot& snap) {
  SessionStats ignored;  // the run's counters are not the rebuild's
  if (!advance_odometry(snap, &ignored)) return false;
  scan(snap);
  return trigger_.update(odometry_.pose());
}

void Session::rebuild_place(uint32_t capture) {
  explorer_.rebuild_place(capture, odometry_.pose());
}

void Session::end_rebuild() {
  explorer_.end_rebuild();
}
#endif

}  // namespace seqslam::session
