// The head board's application: teach, repeat and record, on a volume (SD card).
//
// Every 10 ms SpinalCord snapshot updates the odometry; the spatial trigger (or, for
// recordings without odometry, every frame) captures an image from the pixel buffer, which is
// then, depending on the run configuration (storage/run_files.h):
//   teach            - added to the place library on the card;
//   repeat           - localised against the stored library; one result per step;
//   teach + repeat   - localised against this run's own earlier places (loop closure) while
//                      the library is built;
//   record           - written, with every snapshot, to a dream recording (combines with the
//                      others);
//   explore          - teach + repeat, and mapping: a pose-graph node per place, the
//                      loop-closure gate on the localiser's answer, closure edges, a bounded
//                      optimiser slice per place, every snapshot's infrared readings into an
//                      occupancy grid paged to the card; at the end the graph is optimised to
//                      convergence, the grid rebuilt from the optimised poses, and map and
//                      graph saved on the volume (docs/firmware.md, "Explore").
// The same source builds for the target (main_board.cpp: the QEMU board's virtio disk) and
// for the PC (main_host.cpp: a disk-image file); on both the sensors and the camera are
// either live HAL devices or a dream recording on the volume replayed through the same
// interfaces. All memory is static and sized at compile time (budget below).
#pragma once

#include <stdint.h>

#include "seqslam/hal/pixel_buffer.h"
#include "seqslam/hal/spinal_cord.h"
#include "seqslam/localiser.h"
#include "seqslam/route_search.h"
#include "seqslam/session/profile.h"
#include "seqslam/session/session.h"
#include "seqslam/spatial_trigger.h"
#include "seqslam/storage/dream.h"
#include "seqslam/storage/dream_replay.h"
#include "seqslam/storage/library_store.h"
#include "seqslam/storage/query_store.h"
#include "seqslam/storage/run_files.h"
#include "seqslam/storage/volume.h"

// SEQSLAM_APP_MAPPING and SEQSLAM_APP_HEURISTIC (the optional features) and the sizes of the
// static state: the firmware's capacity profile (session/profile.h).
#if SEQSLAM_APP_MAPPING
#include "seqslam/explorer.h"
#include "seqslam/storage/map_store.h"
#include "seqslam/storage/state_file.h"
#endif

namespace seqslam::app {

// The counters, in the order report() prints them (the odometry's, the session's, come after
// damaged_replay; the explorer's after these).
struct Stats {
  uint32_t snapshots = 0;          // snapshots received
  uint32_t missed_snapshots = 0;   // gaps in the bus sequence
  uint32_t late_snapshots = 0;     // more than hal::kLateSnapshotUs after the previous one
  uint32_t damaged_snapshots = 0;  // reported damaged by the bus (skipped)
  uint32_t damaged_replay = 0;     // replay records damaged or lost (skipped; the run fails)
  uint32_t captures = 0;           // images captured and processed
  uint32_t no_frame = 0;           // trigger fired but the camera had no frame
  uint32_t taught = 0;             // places added to the library
  uint32_t library_loaded = 0;     // places loaded from the card (repeat)
  // The route search (route_search.h).
  uint32_t relocalisation_scans = 0;  // relocalisation scans completed
  uint32_t scan_jumps = 0;            // ... confident away from the prediction (a candidate)
  uint32_t carried = 0;               // steps answered with a scan's place carried along
  uint32_t scan_errors = 0;           // card errors the scan met (it retries or restarts)
  uint32_t steps = 0;                 // localisation steps
  uint32_t localised = 0;             // steps whose confidence passed the threshold
  uint32_t recorded_places = 0;       // places written to the recording
  uint32_t library_full = 0;          // places not taught because the library was full
  uint32_t storage_errors = 0;        // recording/results/library writes that failed
  // Explore: the explorer's own counters (ExplorerStats) are printed beside these.
  uint32_t rebuild_captures = 0;  // captures replayed while rebuilding the map
};

// Lines of text for the console (board UART, stdout).
using Printer = void (*)(const char* text);
// Decimal text of v, written into the end of buf (no libc on the board).
const char* decimal(uint32_t v, char (&buf)[12]);

class Application {
 public:
  // Prepares a run from the volume: reads `config` (defaults when absent), opens the sensor
  // source (`bus`/`camera` if given, else the volume's `replay` recording), loads or creates
  // the library, opens the recording and results files as the modes require, and wires the
  // session. Everything that can refuse the run (the configuration, a missing or unsuitable
  // file, a state that does not continue) is checked before any file is created, truncated
  // or started anew: a refused start leaves the card as it was. Prints what it does and, on
  // failure, why; returns the failing status.
  Status start(storage::Volume& volume, hal::SpinalCord* bus, hal::PixelBuffer* camera,
               Printer print);

  // Processes snapshots until the stream ends (kOk) or a fatal error (its status). A live bus
  // that has no snapshot yet makes it return kUnavailable (call again).
  Status run();

  // Prints the statistics.
  void report() const;

  const Stats& stats() const { return stats_; }
  const storage::RunConfig& config() const { return config_; }
  const session::Session& session() const { return session_; }
  const Localiser& localiser() const { return session_.localiser(); }
#if SEQSLAM_APP_MAPPING
  const Explorer& explorer() const {
    return session_.explorer();
  }
  bool exploring() const {
    return session_.exploring();
  }
#endif

 private:
  // Start-up, in order: what can refuse first (read-only), then what writes.
  Status read_config(storage::Volume& volume);
  Status open_sensors(storage::Volume& volume, hal::SpinalCord* bus, hal::PixelBuffer* camera);
  Status find_files(storage::Volume& volume);
  Status check_sources();
  Status open_queries();
  Status check_scan_reach();
  Status open_library(bool create);
  Status configure_session();
  Status open_results();
  Status open_recording();
  Status step(const hal::SensorSnapshot& snap);
  Status process(const hal::Frame& frame, const hal::SensorSnapshot& snap, const Pose2& pose);
  void record_place(const hal::Frame& frame, const hal::SensorSnapshot& snap, const Pose2& pose);
  void write_result(const session::PlaceStep& step, uint32_t capture,
                    const hal::SensorSnapshot& snap, const Pose2& pose);
#if SEQSLAM_APP_MAPPING
  Status find_map_files(storage::Volume& volume);
  Status open_map();
  void print_closure(const session::PlaceStep& step);
  Status rebuild_map();
  Status finish_explore();
  // Continuing a stopped explore run (app_continue.cpp): the run's state on the card's
  // `state` file, saved before the final solve and restored at start.
  template <class Io>
  void run_state(Io& io);
  uint32_t state_key() const;
  void save_run();
  Status restore_run();
#endif
  void say(const char* a, const char* b = nullptr) const;
  void say_status(const char* what, Status s, const char* why = nullptr) const;
  bool mode(uint8_t m) const { return (config_.modes & m) != 0; }

  Printer print_ = nullptr;
  storage::RunConfig config_{};
  Stats stats_{};
  hal::SpinalCord* bus_ = nullptr;
  hal::PixelBuffer* camera_ = nullptr;
  bool recording_ = false;
  bool results_on_ = false;
  uint32_t last_sequence_ = 0;
  uint32_t last_timestamp_ = 0;
  bool have_last_ = false;

  session::Session session_{};
  PlaceLibrary library_{};
  storage::StoredPlaceImages images_{};
  storage::DreamReplay replay_{};
  storage::DreamWriter recorder_{};
  storage::ResultsWriter results_{};
  storage::Region replay_file_{};
  storage::Region record_file_{};
  storage::Region results_file_{};
  storage::Region library_file_{};
  storage::Region library_images_file_{};

  // The matchers' state and storage (the session wires the one the configuration names).
  RouteSearch route_{};
  profile::RouteStorage route_storage_{};
  storage::StoredQueryHistory queries_{};
  storage::Region queries_file_{};
  uint32_t query_grew_[profile::kQuerySteps / 32] = {};
  RamQueryHistory teach_history_{};  // teach alone: a stand-in that is never used
  uint32_t teach_places_ = 0;
  uint8_t query_buffer_[(kMaxPixels + hal::kBlockSize - 1) / hal::kBlockSize * hal::kBlockSize] =
      {};
#if SEQSLAM_APP_HEURISTIC
  HeuristicMatcher heuristic_{};
#endif
#if SEQSLAM_APP_MAPPING
  // Explore's full search: per-place metadata, the difference row and the matcher in RAM.
  PlaceInfo info_[profile::kMaxPlaces] = {};
  uint32_t sums_[profile::kMaxPlaces] = {};
  uint32_t differences_[profile::kMaxPlaces] = {};
  DiagonalMatcherStorage<profile::kMaxPlaces, profile::kMaxSeqLen> matcher_{};
  // The range sensors' mounts: the replay's header, or Myon's on live sensors.
  RangeSensor sensors_[hal::kMaxInfrared] = {};
  uint32_t sensor_count_ = 0;
  storage::MapStore map_store_{};
  storage::Region map_file_{};
  storage::Region graph_file_{};
  storage::Region state_file_{};
  bool has_state_file_ = false;
  PoseGraphStorage<profile::kGraphNodes, profile::kGraphEdges> graph_storage_{};
  OccupancyGridStorage<profile::kGridSlots> grid_ram_{};
  storage::MapTileIndexEntry map_index_[profile::kMapTiles] = {};
  // The explorer's scratch image: a closure's alignment, and the matched place's image while
  // the current one is read (the library's image cache may reuse its slot).
  uint8_t closure_image_[kMaxPixels] = {};
  static_assert(PoseGraphStorage<profile::kGraphNodes, profile::kGraphEdges>::kBytes ==
                    168 * profile::kMaxPlaces,
                "pose graph budget: 168 bytes a place");
  static_assert(OccupancyGridStorage<profile::kGridSlots>::kBytes == 1036 * profile::kGridSlots,
                "grid budget: 1036 bytes a resident tile");
#endif
  uint8_t image_cache_[profile::kImageCacheBytes] = {};
  uint8_t replay_buffer_[storage::kDreamRecordMax] = {};
};

}  // namespace seqslam::app
