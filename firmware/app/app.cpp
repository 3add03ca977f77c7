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

const char* signed_decimal(int32_t v, char (&buf)[12]) {
  if (v >= 0) return decimal(static_cast<uint32_t>(v), buf);
  uint32_t magnitude = static_cast<uint32_t>(-(v + 1)) + 1u;
  char* p = buf + sizeof buf - 1;
  *p = '\0';
  do {
    *--p = static_cast<char>('0' + magnitude % 10);
    magnitude /= 10;
  } while (magnitude != 0);
  *--p = '-';
  return p;
}

// A consecutive run of this many implausible encoder jumps is taken as real (e.g. the robot
// was carried) and becomes the new odometry baseline.
constexpr uint32_t kGlitchesBeforeResync = 3;

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

Status Application::start(storage::Volume& volume, hal::SpinalCord* bus, hal::PixelBuffer* camera,
                          Printer print) {
  print_ = print;
  stats_ = Stats{};
  odometry_started_ = false;
  have_last_ = false;
  consecutive_glitches_ = 0;

  // What to do.
  storage::Region config_file;
  if (volume.open(storage::kConfigFile, &config_file) == Status::kOk) {
    storage::LogProblem lp = storage::LogProblem::kNone;
    const Status s = storage::read_run_config(config_file, &config_, &lp);
    if (s != Status::kOk) {
      say_status(
          "reading the run configuration", s,
          lp != storage::LogProblem::kNone ? storage::log_problem_text(lp) : "invalid settings");
      return s;
    }
    say("app: run configuration read from the volume\n");
  } else {
    config_ = storage::RunConfig{};
    say("app: no config file: defaults (repeat)\n");
  }
  // What this build cannot run is refused before any file is opened (the same check as
  // `seqslam config write`'s).
  const storage::RunCheck check = storage::check_run_config(config_, kRunLimits);
  if (!check.ok()) {
    say_status("configuration", check.status, storage::run_issue_text(check.issue));
    return check.status;
  }
  if (config_.matcher == LocaliserMatcher::kHeuristic) say("app: sequence matcher: heuristic\n");

  // Sensors and camera: live devices, or the volume's replay recording.
  if (bus != nullptr && camera != nullptr) {
    bus_ = bus;
    camera_ = camera;
  } else {
    Status s = volume.open(storage::kReplayFile, &replay_file_);
    if (s != Status::kOk) {
      say_status("no sensors", s, "no live bus and camera, and no 'replay' file");
      return s;
    }
    storage::DreamProblem dp = storage::DreamProblem::kNone;
    s = replay_.open(replay_file_, Span<uint8_t>(replay_buffer_, sizeof replay_buffer_), &dp);
    if (s != Status::kOk) {
      say_status("opening the replay recording", s,
                 storage::dream_problem_reason(dp, replay_.reader().log_problem()));
      return s;
    }
    // A recording without odometry (reduced) never moves a distance trigger: refuse it here
    // instead of running through it with no capture.
    if (config_.trigger == storage::TriggerMode::kDistance &&
        replay_.header().variant == storage::DreamVariant::kReduced) {
      say("app: the replay has no odometry (reduced): use trigger every-frame\n");
      return Status::kFailedPrecondition;
    }
    bus_ = &replay_;
    camera_ = &replay_;
    say("app: sensors and camera replayed from the volume's recording\n");
  }
  Status s = camera_->configure(config_.mapping);
  if (s != Status::kOk) {
    say_status("configuring the pixel pipeline", s,
               "the camera or the replay cannot produce this mapping");
    return s;
  }
  // Cannot fail: read_run_config checked the odometry (the defaults are valid) and
  // check_run_config the spacing.
  s = odometry_.configure(config_.odometry);
  if (s == Status::kOk) s = trigger_.configure(config_.spacing);
  SEQSLAM_ASSERT(s == Status::kOk);
  s = open_library(volume);
  if (s != Status::kOk) return s;
  s = open_recording(volume);
  if (s != Status::kOk) return s;
#if SEQSLAM_APP_MAPPING
  s = open_mapping(volume);
  if (s == Status::kOk && (config_.modes & storage::kModeContinue) != 0) s = continue_run();
  if (s != Status::kOk) return s;
#endif
  return Status::kOk;
}

#if SEQSLAM_APP_MAPPING
Status Application::open_mapping(storage::Volume& volume) {
  exploring_ = false;
  if ((config_.modes & storage::kModeExplore) == 0) return Status::kOk;
  // The grid is rebuilt at the end from the snapshots on the card: the replay, or on live
  // sensors this run's recording.
  if (bus_ != &replay_ && !recording_) {
    say_status("configuration", Status::kFailedPrecondition,
               "explore on live sensors needs record mode (the map is rebuilt from it)");
    return Status::kFailedPrecondition;
  }
  Status s = volume.open(storage::kMapFile, &map_file_);
  if (s == Status::kOk) s = volume.open(storage::kGraphFile, &graph_file_);
  if (s != Status::kOk) {
    say_status("opening the map files", s, "the volume needs 'map' and 'graph' files (explore)");
    return s;
  }
  // Where the run's state is saved for a later continuation (optional unless continuing).
  has_state_file_ = volume.open(storage::kStateFile, &state_file_) == Status::kOk;
  storage::MapProblem mp = storage::MapProblem::kNone;
  s = map_store_.create(map_file_, config_.grid(), Span<storage::MapTileIndexEntry>(map_index_),
                        &mp);
  if (s != Status::kOk) {
    say_status("creating the map file", s,
               mp == storage::MapProblem::kLog ? storage::log_problem_text(map_store_.log_problem())
                                               : storage::map_problem_text(mp));
    return s;
  }
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
  ExplorerConfig ec;  // the explorer's defaults, with the run's own settings
  ec.grid = config_.grid();
  ec.recent_exclusion = config_.recent_exclusion;
  ec.spacing = config_.spacing;
  ExplorerBuffers eb;
  eb.graph = graph_storage_.buffers();
  eb.grid = grid_ram_.buffers();
  eb.tiles = &map_store_;
  eb.sensors = Span<const RangeSensor>(sensors_, sensor_count_);
  eb.scratch = Span<uint8_t>(closure_image_);
  const ExplorerCheck check = explorer_.configure(ec, eb);
  if (!check.ok()) {
    say_status("configuring the explorer", check.status,
               check.issue == ExplorerIssue::kGrid ? grid_issue_text(check.grid_issue)
                                                   : explorer_issue_text(check.issue));
    return check.status;
  }
  exploring_ = true;
  say("app: explore: pose graph, loop closure and map\n");
  return Status::kOk;
}

// One place through the explorer (explorer.h: graph node, gate, closure edge, optimiser
// slice); its closures are printed.
void Application::explore_place(const Match& m, const Pose2& pose, uint32_t capture) {
  ExplorerStep step;
  const Status s = explorer_.place(library_, Span<const uint32_t>(differences_, kMaxPlaces), m,
                                   pose, capture, &step);
  if (s != Status::kOk) {
    say_status("explorer", s);
    return;
  }
  if (step.closure_to >= 0 && print_ != nullptr) {
    char a[12], b[12];
    say("closure node ", decimal(static_cast<uint32_t>(step.node), a));
    say(" with node ", decimal(static_cast<uint32_t>(step.closure_to), b));
    say("\n");
  }
}

// A snapshot's infrared readings into the grid (explorer.h: at the last place's estimate and
// the odometry since it).
void Application::map_snapshot(const hal::SensorSnapshot& snap) {
  if ((snap.flags & hal::SensorSnapshot::kHasInfrared) == 0) return;
  const uint32_t n =
      snap.infrared_count < hal::kMaxInfrared ? snap.infrared_count : hal::kMaxInfrared;
  (void)explorer_.scan(odometry_.pose(), Span<const uint16_t>(snap.infrared_mm, n));
}

// The map again from the start of the stream (the replay, or this run's recording) with the
// optimised poses: the same odometry, trigger and captures as the run, so every snapshot hangs
// from the place it hung from while exploring.
Status Application::rebuild_map() {
  storage::Region& source = bus_ == &replay_ ? replay_file_ : record_file_;
  storage::DreamProblem dp = storage::DreamProblem::kNone;
  Status s = explorer_.begin_rebuild();
  if (s == Status::kOk) {
    s = replay_.open(source, Span<uint8_t>(replay_buffer_, sizeof replay_buffer_), &dp);
  }
  if (s == Status::kOk) s = replay_.configure(config_.mapping);
  if (s == Status::kOk) s = trigger_.configure(config_.spacing);
  if (s != Status::kOk) {
    say_status("rebuilding the map", s,
               storage::dream_problem_reason(dp, replay_.reader().log_problem()));
    return s;
  }
  odometry_started_ = false;
  consecutive_glitches_ = 0;
  Stats counts;  // the run's counters are not the rebuild's
  for (;;) {
    hal::SensorSnapshot snap;
    s = replay_.next(&snap);
    if (s == Status::kOutOfRange) break;
    if (s == Status::kDataLoss) continue;
    if (s != Status::kOk) break;
    if (!advance_odometry(snap, &counts)) continue;
    map_snapshot(snap);
    if (!trigger_.update(odometry_.pose())) continue;
    s = replay_.capture();
    hal::Frame frame;
    if (s == Status::kOk) s = replay_.read(&frame);
    if (s == Status::kUnavailable) continue;
    if (s != Status::kOk) break;
    explorer_.rebuild_place(stats_.rebuild_captures++, odometry_.pose());
  }
  explorer_.end_rebuild();
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
  if (explorer_.finish(kMaxFinalSlices) != Status::kOk) {
    say("app: explore: the pose graph did not converge (slice bound)\n");
  }
  Status s = rebuild_map();
  if (s != Status::kOk) return s;
  if (explorer_.stats().rebuild_places != explorer_.graph().node_count()) {
    say("app: explore: the rebuild did not find every place\n");
  }
  s = explorer_.flush_map();
  if (s != Status::kOk) {
    say_status("saving the map", s, storage::log_problem_text(map_store_.log_problem()));
    return s;
  }
  storage::LogProblem lp = storage::LogProblem::kNone;
  s = storage::write_graph(graph_file_, explorer_.graph(), &lp);
  if (s != Status::kOk) {
    say_status("saving the graph", s, storage::log_problem_text(lp));
    return s;
  }
  say("app: explore: map and graph saved\n");
  return Status::kOk;
}
#endif

Status Application::open_library(storage::Volume& volume) {
  const bool teach = (config_.modes & storage::kModeTeach) != 0;
  const bool repeat = (config_.modes & storage::kModeRepeat) != 0;
  results_on_ = repeat;
  if (!teach && !repeat) return Status::kOk;
  Status s = volume.open(storage::kLibraryFile, &library_file_);
  if (s == Status::kOk) s = volume.open(storage::kLibraryImagesFile, &library_images_file_);
  if (s != Status::kOk) {
    say_status("opening the library files", s, "the volume needs 'library' and 'library.img'");
    return s;
  }
  storage::LibraryConfig lc;
  lc.image_size = config_.mapping.size();
  lc.preprocess = config_.preprocess;
  lc.mapping = config_.mapping;
  const Span<uint8_t> cache(image_cache_, sizeof image_cache_);
  // Only explore's full search keeps places in RAM; otherwise the card holds the library.
  PlaceLibraryBuffers buffers{};
#if SEQSLAM_APP_MAPPING
  if ((config_.modes & storage::kModeExplore) != 0) {
    buffers =
        PlaceLibraryBuffers{Span<PlaceInfo>(info_, kMaxPlaces), Span<uint32_t>(sums_, kMaxPlaces)};
  }
#endif
  storage::LibraryProblem lp = storage::LibraryProblem::kNone;
  // Continuing an explore run (PC: kMapping) teaches after the stored places.
  const bool continuing = kMapping && (config_.modes & storage::kModeContinue) != 0;
  if (continuing) {
    s = images_.load_for_teaching(library_file_, library_images_file_, lc, cache, buffers, library_,
                                  &lp);
  } else if (teach) {
    s = images_.create(library_file_, library_images_file_, lc, cache, &lp);
    if (s == Status::kOk) s = library_.configure(lc.image_size, images_, buffers);
  } else {
    s = images_.load(library_file_, library_images_file_, lc, cache, buffers, library_, &lp);
    stats_.library_loaded = library_.size();
  }
  if (s != Status::kOk) {
    say_status(continuing ? "loading the library to continue"
               : teach    ? "creating the library"
                          : "loading the library",
               s, storage::library_problem_reason(lp, images_.log_problem()));
    return s;
  }
  if (!teach) {
    char buf[12];
    say("app: library loaded: ", decimal(library_.size(), buf));
    say(images_.recovered_tail() ? " places (the last place, cut by a power loss, dropped)\n"
                                 : " places\n");
  }
  const ConfigCheck check = configure_localiser(volume, teach, repeat);
  if (!check.ok()) {
    if (check.issue != ConfigIssue::kNone) {
      say_status("configuring the localiser", check.status, config_issue_text(check.issue));
    }
    return check.status;
  }
  if (results_on_) {
    s = volume.open(storage::kResultsFile, &results_file_);
    storage::LogProblem rp = storage::LogProblem::kNone;
    if (s == Status::kOk)
      s = continuing ? results_.reopen(results_file_, &rp) : results_.create(results_file_, &rp);
    if (s != Status::kOk) {
      // A missing file, or one the card failed to write (a full or failing card): each its
      // own advice (issue 34: a full card was told it needed a 'results' file).
      say_status("creating the results file", s,
                 rp == storage::LogProblem::kNone ? "the volume needs a 'results' file"
                                                  : storage::log_problem_text(rp));
      return s;
    }
  }
  return Status::kOk;
}

// The search: explore's full search (PC), the heuristic where built in, or the route search
// with its query history on the card. Each overload links only its own matcher (localiser.h).
ConfigCheck Application::configure_localiser(storage::Volume& volume, bool teach, bool repeat) {
  LocaliserConfig lc = config_.localiser();
#if SEQSLAM_APP_MAPPING
  if ((config_.modes & storage::kModeExplore) != 0) {
    return localiser_.configure(lc, library_, matcher_.buffers(),
                                Span<uint32_t>(differences_, kMaxPlaces));
  }
#endif
  [[maybe_unused]] const bool heuristic = lc.matcher == LocaliserMatcher::kHeuristic;
#if SEQSLAM_APP_HEURISTIC
  if (heuristic && (!repeat || lc.heuristic.scan_places == 0)) {
    return localiser_.configure(lc, library_, heuristic_);
  }
#endif
  if (!repeat) {
    // Teaching alone never localises: the route search is configured (it validates the
    // settings) but never steps, so its query history needs no file; the RAM slot it gets
    // is the card history's buffer.
    const Status s = teach_history_.configure(lc.image_size.pixels(), Span<uint8_t>(query_buffer_),
                                              Span<uint32_t>(&teach_places_, 1));
    if (s != Status::kOk) return {s, ConfigIssue::kNone};
    return localiser_.configure(lc, library_, route_, route_storage_.buffers(), teach_history_);
  }
  Status s = volume.open(storage::kQueriesFile, &queries_file_);
  if (s == Status::kOk) {
    // One slot of the configured image, whatever the build's largest image: the PC build
    // (larger kMaxPixels, so a larger buffer) then reads the card exactly as the board does.
    const size_t slot =
        (lc.image_size.pixels() + hal::kBlockSize - 1u) / hal::kBlockSize * hal::kBlockSize;
    s = queries_.configure(
        queries_file_, lc.image_size.pixels(),
        Span<uint8_t>(query_buffer_, slot < sizeof query_buffer_ ? slot : sizeof query_buffer_),
        Span<uint32_t>(query_grew_));
  }
  if (s != Status::kOk) {
    say_status("opening the query history", s,
               "the volume needs a 'queries' file (docs/firmware.md)");
    return {s, ConfigIssue::kNone};
  }
#if SEQSLAM_APP_HEURISTIC
  // A budgeted heuristic reads its sequence's first image back from the card.
  if (heuristic) return localiser_.configure(lc, library_, heuristic_, &queries_);
#endif
  // Loop closure in one run (teach + repeat) has no known start: it scans.
  if (teach) lc.route.start = -1;
  return localiser_.configure(lc, library_, route_, route_storage_.buffers(), queries_);
}

Status Application::open_recording(storage::Volume& volume) {
  recording_ = (config_.modes & storage::kModeRecord) != 0;
  if (!recording_) return Status::kOk;
  Status s = volume.open(storage::kRecordFile, &record_file_);
  if (s != Status::kOk) {
    say_status("opening the recording file", s, "the volume needs a 'record' file");
    return s;
  }
  storage::DreamHeader h;
  if (bus_ == &replay_) {
    h = replay_.header();  // camera and sensor layout of the source
    if (config_.record_colour && h.colour == storage::ColourFormat::kNone) {
      say("app: record-colour: the replay has no colour to record\n");
      return Status::kFailedPrecondition;
    }
  }
  h.variant = config_.trigger == storage::TriggerMode::kDistance ? storage::DreamVariant::kFull
                                                                 : storage::DreamVariant::kReduced;
  h.colour = config_.record_colour ? storage::ColourFormat::kYuv422 : storage::ColourFormat::kNone;
  h.mapping = config_.mapping;
  h.wheels = config_.odometry;
  h.spacing = config_.spacing;
  storage::DreamProblem dp = storage::DreamProblem::kNone;
  s = recorder_.create(record_file_, h, &dp);
  if (s != Status::kOk) {
    say_status("creating the recording", s,
               storage::dream_problem_reason(dp, recorder_.log_problem()));
    return s;
  }
  return Status::kOk;
}

Status Application::run() {
  for (;;) {
    hal::SensorSnapshot snap;
    const Status s = bus_->next(&snap);
    if (s == Status::kOutOfRange) {  // the stream has ended
      if (bus_ == &replay_) stats_.damaged_replay = replay_.bad_records();
      Status end = Status::kOk;
#if SEQSLAM_APP_MAPPING
      if (exploring_) end = finish_explore();
#endif
      if (end == Status::kOk && (stats_.damaged_replay | stats_.storage_errors) != 0) {
        // Everything readable was used and everything writable saved; the run still fails:
        // data was lost on the way in (a damaged replay) or out (results, recording).
        say("app: data lost: damaged replay records or storage errors (counts below)\n");
        end = Status::kDataLoss;
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
    const Status t = step(snap);
    if (t != Status::kOk) return t;
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

  bool capture = true;
  if (config_.trigger == storage::TriggerMode::kDistance) {
    if (!advance_odometry(snap, &stats_)) return Status::kOk;
#if SEQSLAM_APP_MAPPING
    if (exploring_) map_snapshot(snap);
#endif
    capture = trigger_.update(odometry_.pose());
  }
  if (!capture) return Status::kOk;
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
  return process(frame, snap, odometry_.pose());
}

// The odometry from one snapshot (distance trigger). False when the snapshot moves nothing: no
// encoders, or an implausible jump (kGlitchesBeforeResync in a row become the new baseline).
bool Application::advance_odometry(const hal::SensorSnapshot& snap, Stats* counts) {
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

Status Application::process(const hal::Frame& frame, const hal::SensorSnapshot& snap,
                            const Pose2& pose) {
  const uint32_t index = stats_.captures++;
  const ImageView raw{frame.gray, frame.size};
  if (recording_) {
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
      say("app: recording stopped (a place could not be written)\n");
    }
  }
  const bool teach = (config_.modes & storage::kModeTeach) != 0;
  const bool repeat = (config_.modes & storage::kModeRepeat) != 0;
  Match m;
  Status s = Status::kOk;
  if (teach && repeat) {
    s = localiser_.observe(raw, pose, index, &m);
  } else if (repeat) {
    s = localiser_.localise(raw, &m);
  } else if (teach) {
    s = localiser_.teach(raw, pose, index);
  }
  [[maybe_unused]] const bool taken = teach && s == Status::kOk;  // now in the library
  if (teach) {
    if (s == Status::kOk) {
      ++stats_.taught;
    } else if (s == Status::kResourceExhausted) {
      ++stats_.library_full;  // RAM metadata or the card is full: localising goes on
      s = Status::kOk;
    }
  }
  if (s != Status::kOk) {
    say_status("localiser", s);
    return s;
  }
  if (!repeat) return Status::kOk;
#if SEQSLAM_APP_MAPPING
  // Only places the localiser took in (observe appended them) become nodes: library place i
  // is then node i.
  if (exploring_ && taken) explore_place(m, pose, index);
#endif
  ++stats_.steps;
  if (m.localised) ++stats_.localised;
  uint8_t route_bits = 0;
  if (localiser_.route() != nullptr) {
    const RouteStepInfo& info = localiser_.route_step();
    route_bits = route_result_bits(info);
    if (info.scan_completed) ++stats_.relocalisation_scans;
    if (info.scan_jumped) ++stats_.scan_jumps;
    if (info.carried) ++stats_.carried;
    if (info.scan_status != Status::kOk) ++stats_.scan_errors;
  }
  storage::RunResult r;
  r.step = m.query;
  r.capture = index;
  r.timestamp_us = snap.timestamp_us;
  r.pose = pose;
  r.place = m.place;
  r.runner_up = m.runner_up;
  r.cost = m.cost;
  r.runner_up_cost = m.runner_up_cost;
  r.confidence = m.confidence;
  r.localised = m.localised;
  r.route = route_bits;
  if (results_on_ && results_.append(r) != Status::kOk) {
    ++stats_.storage_errors;
    results_on_ = false;
    say("app: results file full or failing: results stop here\n");
  }
  if (m.place >= 0 && print_ != nullptr) {
    char a[12], b[12], c[12];
    say("step ", decimal(m.query, a));
    say(" place ", signed_decimal(m.place, b));
    say(" confidence_q16 ", decimal(m.confidence.raw(), c));
    say(m.localised ? " localised\n" : " not localised\n");
  }
  return Status::kOk;
}

void Application::report() const {
  struct Line {
    const char* label;
    uint32_t value;
  };
#if SEQSLAM_APP_MAPPING
  const ExplorerStats& e = explorer_.stats();
#endif
  const Line lines[] = {
    {"snapshots", stats_.snapshots},
    {"missed snapshots", stats_.missed_snapshots},
    {"late snapshots", stats_.late_snapshots},
    {"damaged snapshots", stats_.damaged_snapshots},
    {"damaged replay records", stats_.damaged_replay},
    {"no encoders", stats_.no_encoders},
    {"odometry glitches", stats_.odometry_glitches},
    {"odometry resyncs", stats_.odometry_resyncs},
    {"captures", stats_.captures},
    {"trigger without frame", stats_.no_frame},
    {"places taught", stats_.taught},
    {"library loaded", stats_.library_loaded},
    {"relocalisation scans", stats_.relocalisation_scans},
    {"scan jumps", stats_.scan_jumps},
    {"carried answers", stats_.carried},
    {"scan card errors", stats_.scan_errors},
    {"steps", stats_.steps},
    {"localised", stats_.localised},
    {"recorded places", stats_.recorded_places},
    {"library full", stats_.library_full},
    {"storage errors", stats_.storage_errors},
#if SEQSLAM_APP_MAPPING
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
#endif
  };
  for (const Line& l : lines) {
    char buf[12];
    say("app: ", l.label);
    say(" ", decimal(l.value, buf));
    say("\n");
  }
}

}  // namespace seqslam::app
