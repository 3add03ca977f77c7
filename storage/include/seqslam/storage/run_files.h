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
#include "seqslam/storage/run_config.h"

namespace seqslam::storage {

// The run configuration's card format: version 2 added the sequence matcher and the
// heuristic's settings, version 3 the explore mode and the map's frame and bounds, version 4
// the route search's settings (docs/firmware.md; run_config.h's table says which setting
// came with which). An older configuration is refused like any
// other version (kFailedPrecondition, LogProblem::kVersion): it is rewritten with `seqslam
// config write`, and an older reader refuses a newer file instead of silently running
// without what it cannot read.
inline constexpr LogKind kRunConfigKind{{'S', 'Q', 'C', 'O', 'N', 'F', 'G', '1'},
                                        kRunConfigVersion};
inline constexpr LogKind kResultsKind{{'S', 'Q', 'R', 'E', 'S', 'L', 'T', '1'}, 1};

inline constexpr const char* kConfigFile = "config";
inline constexpr const char* kReplayFile = "replay";
inline constexpr const char* kLibraryFile = "library";
inline constexpr const char* kLibraryImagesFile = "library.img";
inline constexpr const char* kRecordFile = "record";
inline constexpr const char* kResultsFile = "results";

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

// Writes `config` as the header of a run-configuration log on `device`. kInvalidArgument if
// the localiser or odometry part is invalid; log and device statuses.
Status write_run_config(hal::BlockDevice& device, const RunConfig& config);
// Reads it back into *config, whose settings the card does not carry (kPcOnly) keep their
// values: pass the defaults (RunConfig{}) or the PC tool's. kDataLoss for a damaged or invalid
// configuration, kFailedPrecondition for another version; log and device statuses (a device
// without one: kDataLoss / kWrongKind); *config is unchanged on failure.
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
