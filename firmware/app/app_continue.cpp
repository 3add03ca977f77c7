// Continuing an explore run from the card (docs/firmware.md, "Continuing an explore run").
// Built with the explore mode only (SEQSLAM_APP_MAPPING: the PC).
//
// At the end of an explore run, before the final solve changes the graph, everything the
// next place depends on is saved to the card's `state` file (storage/state_file.h): the
// application's counters and snapshot bookkeeping, the odometry, the spatial trigger, the
// localiser's sequences and the explorer (graph with the optimiser's position, gate,
// re-anchoring, untrusted places). The library is on the card already. A run configured with
// mode `continue` loads the library for teaching, restores that state and skips the replay to
// where the saved run stopped; from there it is the same run: its graph, closures and map
// equal those of one run over the whole recording (checked by ctest firmware_host_continue).
// The map is redrawn from the final graph over the whole replay at the end, as always, so the
// grid drawn while exploring is not saved.
#include "app.h"

#include "seqslam/storage/bytes.h"

namespace seqslam::app {

namespace {

// Bumped whenever run_state() or a component's state() changes its fields.
constexpr uint32_t kStateVersion = 2;

// The CRC of every byte written: the layout key of a state (Application::state_key).
class CrcSink final : public StateSink {
 public:
  Status write(const uint8_t* data, uint32_t size) override {
    crc_ = storage::crc32_update(crc_, data, size);
    return Status::kOk;
  }
  uint32_t crc() const { return crc_; }

 private:
  uint32_t crc_ = 0;
};

template <class Io>
void persist_stats(Io& io, Stats& s) {
  io.field(s.snapshots);
  io.field(s.missed_snapshots);
  io.field(s.late_snapshots);
  io.field(s.damaged_snapshots);
  io.field(s.damaged_replay);
  io.field(s.captures);
  io.field(s.no_frame);
  io.field(s.taught);
  io.field(s.steps);
  io.field(s.localised);
  io.field(s.recorded_places);
  io.field(s.library_full);
  io.field(s.storage_errors);
  io.field(s.library_loaded);
  io.field(s.relocalisation_scans);
  io.field(s.scan_jumps);
  io.field(s.carried);
  io.field(s.scan_errors);
  io.field(s.rebuild_captures);
}

}  // namespace

template <class Io>
void Application::run_state(Io& io) {
  io.tag(state_tag("APPS"));
  persist_stats(io, stats_);
  io.field(last_sequence_);
  io.field(last_timestamp_);
  io.field(have_last_);
  uint32_t places = library_.size();  // the library on the card must be the saved run's
  io.field(places);
  if (Io::kReading && places != library_.size()) io.fail();
  session_.state(io);
}

// What a state depends on beyond its own fields: the build's capacities and the settings that
// shape the components' state. A state saved under another key is refused unread.
uint32_t Application::state_key() const {
  CrcSink crc;
  StateOut out(crc);
  uint32_t build[] = {kStateVersion, profile::kMaxPlaces, profile::kMaxSeqLen, profile::kGraphNodes, profile::kGraphEdges};
  out.array(Span<uint32_t>(build));
  storage::RunConfig c = config_;
  uint16_t size[] = {c.mapping.size().width, c.mapping.size().height, c.sequence.seq_len,
                     c.sequence.window, c.recent_exclusion};
  out.array(Span<uint16_t>(size));
  out.field(c.sequence.threshold);
  out.field(c.max_shift);
  out.field(c.spacing);
  out.field(c.odometry.ticks_per_revolution);
  out.field(c.odometry.circumference_left);
  out.field(c.odometry.circumference_right);
  out.field(c.odometry.track_width);
  out.field(c.grid_origin.x_mm);
  out.field(c.grid_origin.y_mm);
  uint16_t grid[] = {c.grid_cell_mm, c.grid_size.width, c.grid_size.height};
  out.array(Span<uint16_t>(grid));
  return crc.crc();
}

// Saves the run's state, if the card has a `state` file; a failure is counted as a storage
// error (the run then ends with DATA_LOSS) but does not stop the map and graph being saved.
void Application::save_run() {
  if (!has_state_file_) {
    say("app: explore: no 'state' file: this run cannot be continued\n");
    return;
  }
  storage::StateFileWriter writer;
  Status s = writer.create(state_file_, state_key());
  StateOut out(writer);
  if (s == Status::kOk) {
    run_state(out);
    s = out.status();
  }
  if (s == Status::kOk) s = writer.finish();
  if (s != Status::kOk) {
    ++stats_.storage_errors;
    say_status("saving the run's state", s, storage::log_problem_text(writer.log_problem()));
    return;
  }
  char buf[12];
  say("app: explore: run state saved (", decimal(static_cast<uint32_t>(out.bytes()), buf));
  say(" bytes): mode continue goes on from here\n");
}

// Restores the saved run and moves the replay to where it stopped. Reads only: it runs
// before the start-up writes anything, so a state that does not continue leaves the card as
// it was.
Status Application::restore_run() {
  storage::StateFileReader reader;
  storage::StateProblem sp = storage::StateProblem::kNone;
  Status s = reader.open(state_file_, state_key(), &sp);
  if (s != Status::kOk) {
    say_status("reading the saved run", s,
               sp == storage::StateProblem::kLog ? storage::log_problem_text(reader.log_problem())
                                                 : storage::state_problem_text(sp));
    return s;
  }
  StateIn in(reader);
  run_state(in);
  if (!in.ok() || !reader.at_end()) {
    say_status("restoring the saved run", Status::kDataLoss,
               session::firmware_issue_text(session::FirmwareIssue::kStateMismatch));
    return Status::kDataLoss;
  }
  // The replay up to the saved run's last snapshot: every record it took (damaged ones too).
  const uint32_t taken = stats_.snapshots + stats_.damaged_snapshots;
  uint32_t last = 0;
  for (uint32_t i = 0; i < taken; ++i) {
    hal::SensorSnapshot snap;
    s = replay_.next(&snap);
    if (s == Status::kOk) last = snap.sequence;
    if (s != Status::kOk && s != Status::kDataLoss) break;
  }
  if ((s != Status::kOk && s != Status::kDataLoss) || (have_last_ && last != last_sequence_)) {
    say_status("continuing", Status::kFailedPrecondition,
               session::firmware_issue_text(session::FirmwareIssue::kReplayMismatch));
    return Status::kFailedPrecondition;
  }
  char a[12], b[12];
  say("app: continuing the saved run after place ", decimal(library_.size(), a));
  say(" and snapshot ", decimal(taken, b));
  say("\n");
  return Status::kOk;
}

}  // namespace seqslam::app
