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
//                      others).
// The same source builds for the target (main_board.cpp: the QEMU board's virtio disk) and
// for the PC (main_host.cpp: a disk-image file); on both the sensors and the camera are
// either live HAL devices or a dream recording on the volume replayed through the same
// interfaces. All memory is static and sized at compile time (budget below).
#pragma once

#include <stdint.h>

#include "seqslam/hal/pixel_buffer.h"
#include "seqslam/hal/spinal_cord.h"
#include "seqslam/localiser.h"
#include "seqslam/spatial_trigger.h"
#include "seqslam/storage/dream.h"
#include "seqslam/storage/dream_replay.h"
#include "seqslam/storage/library_store.h"
#include "seqslam/storage/run_files.h"
#include "seqslam/storage/volume.h"

#ifndef SEQSLAM_APP_MAX_PLACES
#define SEQSLAM_APP_MAX_PLACES 80
#endif

// Whether the application can run the heuristic sequence matcher (run configuration
// `matcher`). Without it (0) a configuration that asks for it is refused at start, and none
// of the heuristic matcher's code or state is in the image: the head board's build, whose
// 65 456 bytes it does not fit (docs/firmware.md).
#ifndef SEQSLAM_APP_HEURISTIC
#define SEQSLAM_APP_HEURISTIC 1
#endif

namespace seqslam::app {

// Places whose metadata and matcher state fit the head board's RAM (images stay on the card).
inline constexpr uint32_t kMaxPlaces = SEQSLAM_APP_MAX_PLACES;
// Longest sequence the diagonal matcher's state is sized for (the heuristic's state does not
// grow with S: up to the core's kMaxSeqLen).
inline constexpr uint16_t kMaxSeqLen = 30;
inline constexpr bool kHeuristicMatcher = SEQSLAM_APP_HEURISTIC != 0;
// Cache for streaming library images from the card: 2 images of 512 pixels and the skew.
inline constexpr uint32_t kImageCacheBytes = 3 * 512;

struct Stats {
  uint32_t snapshots = 0;          // snapshots received
  uint32_t missed_snapshots = 0;   // gaps in the bus sequence
  uint32_t late_snapshots = 0;     // more than hal::kLateSnapshotUs after the previous one
  uint32_t damaged_snapshots = 0;  // reported damaged by the bus (skipped)
  uint32_t no_encoders = 0;        // snapshots without encoder data (distance trigger)
  uint32_t odometry_glitches = 0;  // implausible encoder jumps skipped
  uint32_t odometry_resyncs = 0;   // ... that persisted and were accepted as the new baseline
  uint32_t captures = 0;           // images captured and processed
  uint32_t no_frame = 0;           // trigger fired but the camera had no frame
  uint32_t taught = 0;             // places added to the library
  uint32_t steps = 0;              // localisation steps
  uint32_t localised = 0;          // steps whose confidence passed the threshold
  uint32_t recorded_places = 0;    // places written to the recording
  uint32_t library_full = 0;       // places not taught because the library was full
  uint32_t storage_errors = 0;     // recording/results/library writes that failed
  uint32_t library_loaded = 0;     // places loaded from the card (repeat)
};

// Lines of text for the console (board UART, stdout).
using Printer = void (*)(const char* text);

class Application {
 public:
  // Prepares a run from the volume: reads `config` (defaults when absent), opens the sensor
  // source (`bus`/`camera` if given, else the volume's `replay` recording), loads or creates
  // the library, opens the recording and results files as the modes require. Prints what it
  // does and, on failure, why; returns the failing status.
  Status start(storage::Volume& volume, hal::SpinalCord* bus, hal::PixelBuffer* camera,
               Printer print);

  // Processes snapshots until the stream ends (kOk) or a fatal error (its status). A live bus
  // that has no snapshot yet makes it return kUnavailable (call again).
  Status run();

  // Prints the statistics.
  void report() const;

  const Stats& stats() const { return stats_; }
  const storage::RunConfig& config() const { return config_; }
  const Localiser& localiser() const { return localiser_; }

 private:
  Status open_library(storage::Volume& volume);
  Status open_recording(storage::Volume& volume);
  Status step(const hal::SensorSnapshot& snap);
  Status process(const hal::Frame& frame, const hal::SensorSnapshot& snap, const Pose2& pose);
  void say(const char* a, const char* b = nullptr) const;
  void say_status(const char* what, Status s, const char* why = nullptr) const;

  Printer print_ = nullptr;
  storage::RunConfig config_{};
  Stats stats_{};
  hal::SpinalCord* bus_ = nullptr;
  hal::PixelBuffer* camera_ = nullptr;
  bool recording_ = false;
  bool results_on_ = false;
  bool odometry_started_ = false;
  uint32_t consecutive_glitches_ = 0;
  uint32_t last_sequence_ = 0;
  uint32_t last_timestamp_ = 0;
  bool have_last_ = false;

  Odometry odometry_{};
  SpatialTrigger trigger_{};
  Localiser localiser_{};
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

  PlaceInfo info_[kMaxPlaces] = {};
  uint32_t sums_[kMaxPlaces] = {};
  uint32_t differences_[kMaxPlaces] = {};
  DiagonalMatcherStorage<kMaxPlaces, kMaxSeqLen> matcher_{};
#if SEQSLAM_APP_HEURISTIC
  HeuristicMatcher heuristic_{};
#endif
  uint8_t image_cache_[kImageCacheBytes] = {};
  uint8_t replay_buffer_[storage::kDreamRecordMax] = {};
};

}  // namespace seqslam::app
