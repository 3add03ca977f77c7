#include "app.h"

#include "seqslam/assert.h"

namespace seqslam::app {

// Decimal text of v into buf (no libc on the board).
const char* decimal(uint32_t v, char (&buf)[12]) {
  char* p = buf + sizeof buf - 1;
  *p = '\0';
  do {
    *--p = static_cast<char>('0' + v % 10);
    v /= 10;
  } while (v != 0);
  return p;
}

namespace {

// A firmware issue's sentence, or its code on the board.
#define FI(issue) session::firmware_issue_text(session::FirmwareIssue::issue)

// At most 11 characters ("-2147483648") and the terminator: buf always has room for the sign.
const char* signed_decimal(int32_t v, char (&buf)[12]) {
  if (v >= 0) return decimal(static_cast<uint32_t>(v), buf);
  char* p = const_cast<char*>(decimal(static_cast<uint32_t>(-(v + 1)) + 1u, buf));
  *--p = '-';
  return p;
}

// What the route search did at a step, as the results file stores it.
uint8_t route_result_bits(const RouteStepInfo& info) {
  uint8_t bits = 0;
  if (info.carried) bits |= storage::kRouteCarried;
  if (info.scan_running) bits |= storage::kRouteScanRunning;
  if (info.scan_completed) bits |= storage::kRouteScanCompleted;
  if (info.scan_jumped) bits |= storage::kRouteJumped;
  if (info.probation) bits |= storage::kRouteProbation;
  if (info.tracking) bits |= storage::kRouteTracking;
  return bits;
}

}  // namespace

void Application::say(const char* a, const char* b) const {
  if (print_ == nullptr) return;
  print_(a);
  if (b != nullptr) print_(b);
}

void Application::say_status(const char* what, Status s, const char* why) const {
  say("app: ", what);
  say(": ", status_name(s));
  if (why != nullptr) say(" - ", why);
  say("\n");
}

// ---------------------------------------------------------------------------------------
// Start-up. Everything that can refuse the run comes first and reads only; the card is
// written (a library, results, recording or map created, a continued run's files reopened)
// only once the run is sure to start.

Status Application::start(storage::Volume& volume, hal::SpinalCord* bus, hal::PixelBuffer* camera,
                          Printer print) {
  print_ = print;
  stats_ = Stats{};
  have_last_ = false;
  SEQSLAM_TRY(read_config(volume));
  SEQSLAM_TRY(open_sensors(volume, bus, camera));
  SEQSLAM_TRY(find_files(volume));
  SEQSLAM_TRY(check_sources());
  SEQSLAM_TRY(open_queries());
  const bool continuing = profile::kMapping && mode(storage::kModeContinue);
  if (!mode(storage::kModeTeach) || continuing) {
    // The library is read (repeat) or taught further (continue): loaded, then the session.
    SEQSLAM_TRY(open_library(false));
    SEQSLAM_TRY(configure_session());
#if SEQSLAM_APP_MAPPING
    if (continuing) SEQSLAM_TRY(restore_run());
#endif
  }
  SEQSLAM_TRY(check_scan_reach());
  // From here on the card is written.
  if (mode(storage::kModeTeach) && !continuing) {
    SEQSLAM_TRY(open_library(true));
    SEQSLAM_TRY(configure_session());
  }
  SEQSLAM_TRY(open_results());
  SEQSLAM_TRY(open_recording());
#if SEQSLAM_APP_MAPPING
  SEQSLAM_TRY(open_map());
#endif
  return Status::kOk;
}

// What to do: the card's configuration or the defaults, and whether this build runs it.
Status Application::read_config(storage::Volume& volume) {
  config_ = storage::RunConfig{};  // the settings the card does not carry: their defaults
  storage::Region config_file;
  if (volume.open(storage::kConfigFile, &config_file) == Status::kOk) {
    storage::LogProblem lp = storage::LogProblem::kNone;
    const Status s = storage::read_run_config(config_file, &config_, &lp);
    if (s != Status::kOk) {
      say_status(
          "run configuration", s,
          lp != storage::LogProblem::kNone ? storage::log_problem_text(lp)
                                           : FI(kInvalidSettings));
      return s;
    }
    say("app: run configuration read from the volume\n");
  } else {
    say("app: no config file: defaults (repeat)\n");
  }
  // What this build cannot run is refused before any file is opened (the same check as
  // `seqslam config write`'s).
  const storage::RunCheck check = storage::check_run_config(config_, profile::kRunLimits);
  if (!check.ok()) {
    say_status("configuration", check.status, storage::run_issue_text(check.issue));
    return check.status;
  }
  if (config_.matcher == LocaliserMatcher::kHeuristic) say("app: sequence matcher: heuristic\n");
  return Status::kOk;
}

// Sensors and camera: live devices, or the volume's replay recording (read only).
Status Application::open_sensors(storage::Volume& volume, hal::SpinalCord* bus,
                                 hal::PixelBuffer* camera) {
  if (bus != nullptr && camera != nullptr) {
    bus_ = bus;
    camera_ = camera;
  } else {
    Status s = volume.open(storage::kReplayFile, &replay_file_);
    if (s != Status::kOk) {
      say_status("no sensors", s, FI(kNoSensors));
      return s;
    }
    storage::DreamProblem dp = storage::DreamProblem::kNone;
    s = replay_.open(replay_file_, Span<uint8_t>(replay_buffer_, sizeof replay_buffer_), &dp);
    if (s != Status::kOk) {
      say_status("replay", s, storage::dream_problem_reason(dp, replay_.reader().log_problem()));
      return s;
    }
    // A recording without odometry (reduced) never moves a distance trigger: refuse it here
    // instead of running through it with no capture.
    if (config_.trigger == storage::TriggerMode::kDistance &&
        replay_.header().variant == storage::DreamVariant::kReduced) {
      say_status("configuration", Status::kFailedPrecondition, FI(kReducedReplay));
      return Status::kFailedPrecondition;
    }
    bus_ = &replay_;
    camera_ = &replay_;
    say("app: sensors and camera replayed from the volume's recording\n");
  }
  const Status s = camera_->configure(config_.mapping);
  if (s != Status::kOk) {
    say_status("pixel pipeline", s, FI(kMappingRefused));
  }
  return s;
}

// Every file the modes need, found before any is written.
Status Application::find_files(storage::Volume& volume) {
  const bool teach = mode(storage::kModeTeach);
  const bool repeat = mode(storage::kModeRepeat);
  results_on_ = repeat;
  recording_ = mode(storage::kModeRecord);
  if (teach || repeat) {
    Status s = volume.open(storage::kLibraryFile, &library_file_);
    if (s == Status::kOk) s = volume.open(storage::kLibraryImagesFile, &library_images_file_);
    if (s != Status::kOk) {
      say_status("library files", s, FI(kNeedsLibrary));
      return s;
    }
  }
  if (repeat) {
    Status s = volume.open(storage::kResultsFile, &results_file_);
    if (s != Status::kOk) {
      say_status("results file", s, FI(kNeedsResults));
      return s;
    }
  }
  // The query history: the route search's, or a budgeted heuristic's (explore's full search
  // keeps none).
  if (repeat && !mode(storage::kModeExplore)) {
    const Status s = volume.open(storage::kQueriesFile, &queries_file_);
    if (s != Status::kOk) {
      say_status("query history", s, FI(kNeedsQueries));
      return s;
    }
  }
  if (recording_) {
    const Status s = volume.open(storage::kRecordFile, &record_file_);
    if (s != Status::kOk) {
      say_status("record file", s, FI(kNeedsRecord));
      return s;
    }
  }
#if SEQSLAM_APP_MAPPING
  return find_map_files(volume);
#else
  return Status::kOk;
#endif
}

// What the configuration and the sources must agree on.
Status Application::check_sources() {
  if (recording_ && bus_ == &replay_ && config_.record_colour &&
      replay_.header().colour == storage::ColourFormat::kNone) {
    say_status("configuration", Status::kFailedPrecondition, FI(kNoColour));
    return Status::kFailedPrecondition;
  }
#if SEQSLAM_APP_MAPPING
  if (mode(storage::kModeExplore)) {
    // The grid is rebuilt at the end from the snapshots on the card: the replay, or on live
    // sensors this run's recording.
    if (bus_ != &replay_ && !recording_) {
      say_status("configuration", Status::kFailedPrecondition, FI(kExploreLive));
      return Status::kFailedPrecondition;
    }
    GridIssue gi = GridIssue::kNone;
    const Status s = check_grid_config(config_.grid(), &gi);
    if (s != Status::kOk) {
      say_status("configuring the explorer", s, grid_issue_text(gi));
      return s;
    }
  }
  if (mode(storage::kModeContinue) && (bus_ != &replay_ || recording_)) {
    say_status("configuration", Status::kFailedPrecondition, FI(kContinueSource));
    return Status::kFailedPrecondition;
  }
#endif
  return Status::kOk;
}

// The query history: on the card in repeat mode (read when a scan needs its images; nothing
// is written until the first step), a RAM stand-in that is never used when teaching alone.
Status Application::open_queries() {
  const uint32_t pixels = config_.mapping.size().pixels();
  if (!mode(storage::kModeRepeat)) {
    return teach_history_.configure(pixels, Span<uint8_t>(query_buffer_),
                                    Span<uint32_t>(&teach_places_, 1));
  }
  if (mode(storage::kModeExplore)) return Status::kOk;
  // One slot of the configured image, whatever the build's largest image: the PC build
  // (larger kMaxPixels, so a larger buffer) then reads the card exactly as the board does.
  const size_t slot = (pixels + hal::kBlockSize - 1u) / hal::kBlockSize * hal::kBlockSize;
  const Status s = queries_.configure(
      queries_file_, pixels,
      Span<uint8_t>(query_buffer_, slot < sizeof query_buffer_ ? slot : sizeof query_buffer_),
      Span<uint32_t>(query_grew_));
  if (s != Status::kOk) say_status("query history", s, FI(kQueriesTooSmall));
  return s;
}

// The route search's relocalisation scan against its query history (the library loaded, or
// empty when this run teaches it): fewer steps than the scan's images, and no scan could ever
// run; too few for a scan over the stored library, and from an unknown start nothing would
// ever be localised. Both refused (a known start tracks without a scan).
Status Application::check_scan_reach() {
  if (!mode(storage::kModeRepeat) || mode(storage::kModeExplore) ||
      config_.matcher != LocaliserMatcher::kDiagonal) {
    return Status::kOk;
  }
  const storage::QueryFit fit =
      storage::query_history_fit(queries_.capacity(), scan_seq_len(config_.route, config_.sequence),
                                 library_.size(), config_.route.scan_places);
  if (fit == storage::QueryFit::kFits ||
      (fit == storage::QueryFit::kTooFewForLibrary && config_.route.start >= 0)) {
    return Status::kOk;
  }
  say_status("query history", Status::kOutOfRange,
             fit == storage::QueryFit::kTooFewForImages ? FI(kQueriesTooSmall)
                                                        : FI(kScanCannotComplete));
  return Status::kOutOfRange;
}

namespace {

storage::LibraryConfig library_config(const storage::RunConfig& c) {
  storage::LibraryConfig lc;
  lc.image_size = c.mapping.size();
  lc.preprocess = c.preprocess;
  lc.mapping = c.mapping;
  return lc;
}

}  // namespace

// The library: the stored one (repeat; continue, to teach after its places), which only reads
// the card, or a new one (teach), which writes it.
Status Application::open_library(bool create) {
  const storage::LibraryConfig lc = library_config(config_);
  const Span<uint8_t> cache(image_cache_, sizeof image_cache_);
  // Only explore's full search keeps places in RAM; otherwise the card holds the library.
  PlaceLibraryBuffers buffers{};
#if SEQSLAM_APP_MAPPING
  if (mode(storage::kModeExplore)) {
    buffers = PlaceLibraryBuffers{Span<PlaceInfo>(info_, profile::kMaxPlaces),
                                  Span<uint32_t>(sums_, profile::kMaxPlaces)};
  }
#endif
  storage::LibraryProblem lp = storage::LibraryProblem::kNone;
  const bool continuing = profile::kMapping && mode(storage::kModeContinue);
  Status s;
  if (create) {
    s = images_.create(library_file_, library_images_file_, lc, cache, &lp);
    if (s == Status::kOk) s = library_.configure(lc.image_size, images_, buffers);
  } else if (continuing) {
    s = images_.load_for_teaching(library_file_, library_images_file_, lc, cache, buffers,
                                  library_, &lp);
  } else {
    s = images_.load(library_file_, library_images_file_, lc, cache, buffers, library_, &lp);
  }
  if (s != Status::kOk) {
    say_status("library", s, storage::library_problem_reason(lp, images_.log_problem()));
    return s;
  }
  if (!create && !continuing) {
    stats_.library_loaded = library_.size();
    char buf[12];
    say("app: library loaded: ", decimal(library_.size(), buf));
    say(images_.recovered_tail() ? " places (the last place, cut by a power loss, dropped)\n"
                                 : " places\n");
  }
  return Status::kOk;
}

// The pipeline on this run's storage: the session wires the matcher the configuration names
// (the route search, the heuristic, or explore's full search) and, exploring, the explorer.
Status Application::configure_session() {
  session::SessionParts parts;
  parts.library = &library_;
  session::MatcherParts& m = parts.matcher;
  m.route = &route_;
  m.route_buffers = route_storage_.buffers();
  m.history = mode(storage::kModeRepeat) ? static_cast<QueryHistory*>(&queries_)
                                         : static_cast<QueryHistory*>(&teach_history_);
#if SEQSLAM_APP_HEURISTIC
  m.heuristic = &heuristic_;
#endif
#if SEQSLAM_APP_MAPPING
  m.full = matcher_.buffers();
  m.differences = Span<uint32_t>(differences_, profile::kMaxPlaces);
  // The range sensors as the replay's header describes them; Myon's on live sensors.
  sensor_count_ = 0;
  if (bus_ == &replay_) {
    const storage::DreamHeader& h = replay_.header();
    for (; sensor_count_ < h.infrared_count && sensor_count_ < hal::kMaxInfrared; ++sensor_count_)
      sensors_[sensor_count_] = storage::range_sensor_of(h.infrared[sensor_count_]);
  } else {
    for (; sensor_count_ < kMyonInfraredCount; ++sensor_count_)
      sensors_[sensor_count_] = kMyonInfrared[sensor_count_];
  }
  parts.explorer.graph = graph_storage_.buffers();
  parts.explorer.grid = grid_ram_.buffers();
  parts.explorer.tiles = &map_store_;
  parts.explorer.sensors = Span<const RangeSensor>(sensors_, sensor_count_);
  parts.explorer.scratch = Span<uint8_t>(closure_image_);
#endif
  const session::SessionCheck check =
      session_.configure(config_, session::Search::kRoute, parts);
  if (!check.ok()) {
    say_status("localiser", check.status,
               check.issue == session::SessionIssue::kLocaliser
                   ? config_issue_text(check.localiser_issue)
                   : session::session_issue_text(check.issue));
    return check.status;
  }
#if SEQSLAM_APP_MAPPING
  if (session_.exploring()) say("app: explore: pose graph, loop closure and map\n");
#endif
  return Status::kOk;
}

// Repeat: the results, new or (a continued run) after the saved run's.
Status Application::open_results() {
  if (!results_on_) return Status::kOk;
  // A card that fails the write (full or failing) is told so, not that it lacks the file.
  storage::LogProblem rp = storage::LogProblem::kNone;
  const Status s = profile::kMapping && mode(storage::kModeContinue)
                       ? results_.reopen(results_file_, &rp)
                       : results_.create(results_file_, &rp);
  if (s != Status::kOk) say_status("results file", s, storage::log_problem_text(rp));
  return s;
}

Status Application::open_recording() {
  if (!recording_) return Status::kOk;
  storage::DreamHeader h;
  if (bus_ == &replay_) h = replay_.header();  // camera and sensor layout of the source
  h.variant = config_.trigger == storage::TriggerMode::kDistance ? storage::DreamVariant::kFull
                                                                 : storage::DreamVariant::kReduced;
  h.colour = config_.record_colour ? storage::ColourFormat::kYuv422 : storage::ColourFormat::kNone;
  h.mapping = config_.mapping;
  h.wheels = config_.odometry;
  h.spacing = config_.spacing;
  storage::DreamProblem dp = storage::DreamProblem::kNone;
  const Status s = recorder_.create(record_file_, h, &dp);
  if (s != Status::kOk) {
    say_status("recording", s, storage::dream_problem_reason(dp, recorder_.log_problem()));
  }
  return s;
}

#if SEQSLAM_APP_MAPPING
Status Application::find_map_files(storage::Volume& volume) {
  if (!mode(storage::kModeExplore)) return Status::kOk;
  Status s = volume.open(storage::kMapFile, &map_file_);
  if (s == Status::kOk) s = volume.open(storage::kGraphFile, &graph_file_);
  if (s != Status::kOk) {
    say_status("opening the map files", s, FI(kNeedsMapFiles));
    return s;
  }
  // Where the run's state is saved for a later continuation (optional unless continuing).
  has_state_file_ = volume.open(storage::kStateFile, &state_file_) == Status::kOk;
  if (mode(storage::kModeContinue) && !has_state_file_) {
    say_status("continuing", Status::kNotFound, FI(kNoState));
    return Status::kNotFound;
  }
  return Status::kOk;
}

// Explore: a new map session in the `map` file (written).
Status Application::open_map() {
  if (!session_.exploring()) return Status::kOk;
  storage::MapProblem mp = storage::MapProblem::kNone;
  const Status s = map_store_.create(map_file_, config_.grid(),
                                     Span<storage::MapTileIndexEntry>(map_index_), &mp);
  if (s != Status::kOk) {
    say_status("creating the map file", s,
               mp == storage::MapProblem::kLog ? storage::log_problem_text(map_store_.log_problem())
                                               : storage::map_problem_text(mp));
  }
  return s;
}

// A place's closure, printed.
void Application::print_closure(const session::PlaceStep& step) {
  if (step.explore_status != Status::kOk) {
    say_status("explorer", step.explore_status);
    return;
  }
  if (step.explore.closure_to >= 0 && print_ != nullptr) {
    char a[12], b[12];
    say("closure node ", decimal(static_cast<uint32_t>(step.explore.node), a));
    say(" with node ", decimal(static_cast<uint32_t>(step.explore.closure_to), b));
    say("\n");
  }
}

// The map again from the start of the stream (the replay, or this run's recording) with the
// optimised poses: the session replays the same odometry, trigger and captures as the run,
// so every snapshot hangs from the place it hung from while exploring.
Status Application::rebuild_map() {
  storage::Region& source = bus_ == &replay_ ? replay_file_ : record_file_;
  storage::DreamProblem dp = storage::DreamProblem::kNone;
  Status s = session_.begin_rebuild();
  if (s == Status::kOk) {
    s = replay_.open(source, Span<uint8_t>(replay_buffer_, sizeof replay_buffer_), &dp);
  }
  if (s == Status::kOk) s = replay_.configure(config_.mapping);
  if (s != Status::kOk) {
    say_status("rebuilding the map", s,
               storage::dream_problem_reason(dp, replay_.reader().log_problem()));
    return s;
  }
  for (;;) {
    hal::SensorSnapshot snap;
    s = replay_.next(&snap);
    if (s == Status::kOutOfRange) break;
    if (s == Status::kDataLoss) continue;
    if (s != Status::kOk) break;
    if (!session_.rebuild_snapshot(snap)) continue;
    s = replay_.capture();
    hal::Frame frame;
    if (s == Status::kOk) s = replay_.read(&frame);
    if (s == Status::kUnavailable) continue;
    if (s != Status::kOk) break;
    session_.rebuild_place(stats_.rebuild_captures++);
  }
  session_.end_rebuild();
  if (s != Status::kOutOfRange) {
    say_status("rebuilding the map", s);
    return s;
  }
  return Status::kOk;
}

// After the last place: the run's state saved (it can be continued), the graph to
// convergence, the map rebuilt, both saved.
Status Application::finish_explore() {
  save_run();
  if (session_.finish(profile::kMaxFinalSlices) != Status::kOk) {
    say("app: explore: the pose graph did not converge (slice bound)\n");
  }
  SEQSLAM_TRY(rebuild_map());
  const Explorer& explorer = session_.explorer();
  if (explorer.stats().rebuild_places != explorer.graph().node_count()) {
    say("app: explore: the rebuild did not find every place\n");
  }
  Status s = session_.explorer().flush_map();
  if (s != Status::kOk) {
    say_status("saving the map", s, storage::log_problem_text(map_store_.log_problem()));
    return s;
  }
  storage::LogProblem lp = storage::LogProblem::kNone;
  s = storage::write_graph(graph_file_, explorer.graph(), &lp);
  if (s != Status::kOk) {
    say_status("saving the graph", s, storage::log_problem_text(lp));
    return s;
  }
  say("app: explore: map and graph saved\n");
  return Status::kOk;
}
#endif

// ---------------------------------------------------------------------------------------
// The run.

Status Application::run() {
  for (;;) {
    hal::SensorSnapshot snap;
    const Status s = bus_->next(&snap);
    if (s == Status::kOutOfRange) {  // the stream has ended
      if (bus_ == &replay_) stats_.damaged_replay = replay_.bad_records();
      Status end = Status::kOk;
#if SEQSLAM_APP_MAPPING
      if (session_.exploring()) end = finish_explore();
#endif
      if (end == Status::kOk && (stats_.damaged_replay | stats_.storage_errors) != 0) {
        // Everything readable was used and everything writable saved; the run still fails:
        // data was lost on the way in (a damaged replay) or out (results, recording).
        end = Status::kDataLoss;
        say_status("run", end, FI(kDataLost));
      }
      return end;
    }
    if (s == Status::kUnavailable) return s;  // live bus: nothing yet
    if (s == Status::kDataLoss) {
      ++stats_.damaged_snapshots;
      continue;
    }
    if (s != Status::kOk) {
      say_status("sensor bus", s);
      return s;
    }
    SEQSLAM_TRY(step(snap));
    // A slice of the localiser's work between places (the route search's scan).
    session_.work(profile::kScanSlicePlaces);
  }
}

Status Application::step(const hal::SensorSnapshot& snap) {
  ++stats_.snapshots;
  if (have_last_) {
    if (snap.sequence > last_sequence_ + 1)
      stats_.missed_snapshots += snap.sequence - last_sequence_ - 1;
    if (snap.timestamp_us - last_timestamp_ > hal::kLateSnapshotUs) ++stats_.late_snapshots;
  }
  have_last_ = true;
  last_sequence_ = snap.sequence;
  last_timestamp_ = snap.timestamp_us;

  if (recording_ && config_.trigger == storage::TriggerMode::kDistance) {
    if (recorder_.snapshot(snap) != Status::kOk) {
      ++stats_.storage_errors;
      recording_ = false;  // keep localising; the recording stops here
      say("app: recording stopped: ", storage::log_problem_text(recorder_.log_problem()));
      say("\n");
    }
  }
  // The odometry, the map's scan and the trigger (the session).
  if (!session_.snapshot(snap)) return Status::kOk;
  Status s = camera_->capture();
  hal::Frame frame;
  if (s == Status::kOk) s = camera_->read(&frame);
  if (s == Status::kUnavailable) {
    ++stats_.no_frame;
    return Status::kOk;
  }
  if (s != Status::kOk) {
    say_status("camera", s);
    return s;
  }
  return process(frame, snap, session_.pose());
}

void Application::record_place(const hal::Frame& frame, const hal::SensorSnapshot& snap,
                               const Pose2& pose) {
  storage::DreamPlace p;
  p.index = stats_.recorded_places;
  p.bus_sequence = snap.sequence;
  p.timestamp_us = snap.timestamp_us;
  p.encoder_left = snap.encoder_left;
  p.encoder_right = snap.encoder_right;
  p.pose = pose;
  p.head_pan = snap.head_pan;
  p.head_tilt = snap.head_tilt;
  p.infrared_count = snap.infrared_count;
  for (uint32_t i = 0; i < snap.infrared_count && i < hal::kMaxInfrared; ++i) {
    p.infrared_mm[i] = snap.infrared_mm[i];
  }
  p.size = frame.size;
  p.gray = frame.gray;
  p.yuv = frame.yuv;
  if (recorder_.place(p) == Status::kOk) {
    ++stats_.recorded_places;
  } else {
    ++stats_.storage_errors;
    recording_ = false;
    say_status("recording", Status::kResourceExhausted, FI(kRecordingStopped));
  }
}

Status Application::process(const hal::Frame& frame, const hal::SensorSnapshot& snap,
                            const Pose2& pose) {
  const uint32_t index = stats_.captures++;
  if (recording_) record_place(frame, snap, pose);
  session::PlaceStep step;
  const Status s = session_.place(ImageView{frame.gray, frame.size}, pose, index, &step);
  if (step.taught) ++stats_.taught;
  if (step.library_full) ++stats_.library_full;  // RAM metadata or the card is full
  if (s != Status::kOk) {
    say_status("localiser", s);
    return s;
  }
  if (!step.matched) return Status::kOk;
#if SEQSLAM_APP_MAPPING
  if (step.explored || step.explore_status != Status::kOk) print_closure(step);
#endif
  write_result(step, index, snap, pose);
  return Status::kOk;
}

// One localisation step: counted, stored in the results file, printed.
void Application::write_result(const session::PlaceStep& step, uint32_t capture,
                               const hal::SensorSnapshot& snap, const Pose2& pose) {
  const Match& m = step.match;
  ++stats_.steps;
  if (m.localised) ++stats_.localised;
  uint8_t route_bits = 0;
  if (step.routed) {
    const RouteStepInfo& info = step.route;
    route_bits = route_result_bits(info);
    if (info.scan_completed) ++stats_.relocalisation_scans;
    if (info.scan_jumped) ++stats_.scan_jumps;
    if (info.carried) ++stats_.carried;
    if (info.scan_status != Status::kOk) ++stats_.scan_errors;
  }
  // Every field given: no default-initialised copy first (the board's code is counted).
  const storage::RunResult r{m.query,    capture,          snap.timestamp_us, pose,
                             m.place,    m.runner_up,      m.cost,            m.runner_up_cost,
                             m.confidence, m.localised,    route_bits};
  if (results_on_ && results_.append(r) != Status::kOk) {
    ++stats_.storage_errors;
    results_on_ = false;
    say_status("results", Status::kResourceExhausted, FI(kResultsStopped));
  }
  if (m.place >= 0 && print_ != nullptr) {
    char a[12], b[12], c[12];
    say("step ", decimal(m.query, a));
    say(" place ", signed_decimal(m.place, b));
    say(" confidence_q16 ", decimal(m.confidence.raw(), c));
    say(m.localised ? " localised\n" : " not localised\n");
  }
}

void Application::report() const {
  // Stats's counters in its order, the session's odometry counters after damaged_replay; the
  // labels in the same order (one table and a loop: the head board's code is counted).
  static const char* const kLabels[] = {
      "snapshots",           "missed snapshots",
      "late snapshots",      "damaged snapshots",
      "damaged replay records",
      "no encoders",         "odometry glitches",
      "odometry resyncs",    "captures",
      "trigger without frame", "places taught",
      "library loaded",      "relocalisation scans",
      "scan jumps",          "carried answers",
      "scan card errors",    "steps",
      "localised",           "recorded places",
      "library full",        "storage errors",
  };
  constexpr uint32_t kBefore = 5;  // counters before the odometry's
  constexpr uint32_t kStats = sizeof(Stats) / sizeof(uint32_t) - 1;  // rebuild_captures aside
  static_assert(kStats + 3 == sizeof kLabels / sizeof kLabels[0], "a label per counter");
  uint32_t stats[kStats + 1];
  static_assert(sizeof stats == sizeof(Stats), "Stats is uint32_t counters");
  __builtin_memcpy(stats, &stats_, sizeof stats);
  const session::SessionStats& o = session_.stats();
  const uint32_t odometry[3] = {o.no_encoders, o.odometry_glitches, o.odometry_resyncs};
  char buf[12];
  for (uint32_t i = 0; i < kStats + 3; ++i) {
    const uint32_t v = i < kBefore ? stats[i] : i < kBefore + 3 ? odometry[i - kBefore]
                                                                : stats[i - 3];
    say("app: ", kLabels[i]);
    say(" ", decimal(v, buf));
    say("\n");
  }
#if SEQSLAM_APP_MAPPING
  if (!session_.exploring() && !profile::kMapping) return;
  const ExplorerStats& e = session_.explorer().stats();
  struct Line {
    const char* label;
    uint32_t value;
  };
  const Line lines[] = {
      {"graph nodes", e.nodes},
      {"graph full", e.graph_full},
      {"closures", e.closures},
      {"closures realigned", e.closures_realigned},
      {"closure alignments failed", e.align_failures},
      {"closure headings failed", e.heading_failures},
      {"relocalisations", e.relocalisations},
      {"optimiser work", static_cast<uint32_t>(e.optimise_work)},
      {"final optimiser slices", e.final_slices},
      {"map scans", e.scans},
      {"map readings rejected", e.rejected},
      {"rebuild places", e.rebuild_places},
      {"rebuild scans", e.rebuild_scans},
      {"rebuild readings rejected", e.rebuild_rejected},
  };
  for (const Line& l : lines) {
    say("app: ", l.label);
    say(" ", decimal(l.value, buf));
    say("\n");
  }
#endif
}

}  // namespace seqslam::app
