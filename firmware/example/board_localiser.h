// How another firmware runs the head board's localiser (README, "Using the library"): the
// route search (a window around the odometry's prediction, beside it a relocalisation scan and
// a candidate it found) over a place library on the robot's SD card, reached through the HAL's block device.
//
// The integrator supplies three HAL devices (hal/): the card (hal::BlockDevice, holding a
// volume made by `seqslam disk create` with the files `library`, `library.img` and, to
// repeat, `queries`), the sensor bus (hal::SensorSnapshot every 10 ms, e.g. from its own
// hal::SpinalCord driver) and the pixel buffer (hal::PixelBuffer). Everything else is the
// library's: the session (session/) wires the odometry, the 20 cm trigger and the localiser
// exactly as firmware/app does, so the integrator's answers are the head board's.
//
// Memory: all static (the object is meant to be a static variable), sized by the capacity
// profile (session/profile.h): sizeof(BoardLocaliser) is the localiser's RAM, nothing per
// place (the library and the query history are on the card).
#pragma once

#include <stdint.h>

#include "seqslam/hal/block_device.h"
#include "seqslam/hal/pixel_buffer.h"
#include "seqslam/hal/spinal_cord.h"
#include "seqslam/query_history.h"
#include "seqslam/route_search.h"
#include "seqslam/session/profile.h"
#include "seqslam/session/session.h"
#include "seqslam/storage/library_store.h"
#include "seqslam/storage/query_store.h"
#include "seqslam/storage/run_files.h"
#include "seqslam/storage/volume.h"

namespace seqslam::example {

// What start() refused, for the integrator's log.
enum class StartIssue : uint8_t {
  kNone = 0,
  kModes,      // config.modes is neither teach nor repeat alone, or the matcher not diagonal
  kSettings,   // the board cannot run the configuration (check_run_config, the localiser's)
  kVolume,     // the card holds no volume
  kFiles,      // a file the mode needs is missing (library, library.img; queries to repeat)
  kLibrary,    // the library cannot be created (teach) or loaded (repeat)
  kQueries,    // the query history does not fit the `queries` file
  kCamera,     // the pixel buffer cannot produce the configuration's mapping
  kLocaliser,  // the session refused the configuration (a SessionCheck)
};

class BoardLocaliser {
 public:
  // Teaches (config.modes == kModeTeach: a new library on the card) or repeats
  // (kModeRepeat: localises against the card's library) with `config` (the diagonal
  // matcher), which must outlive the run (the session keeps a reference). Programs the
  // camera's mapping. kOk, or the failing part's status with *issue (if given) saying which
  // part refused; every check runs before the card is written, so a refused start leaves the
  // card's library as it was.
  Status start(hal::BlockDevice& card, hal::PixelBuffer& camera, const storage::RunConfig& config,
               StartIssue* issue = nullptr);

  // One sensor snapshot (every 10 ms). When the trigger asks for a place, captures it from
  // the camera and teaches or localises it: *placed is true and *step says what the place did
  // (step->matched and step->match: the answer, step->match.localised: a fix to trust).
  // A capture without a frame is not an error (*placed false). Then, as the firmware does, one
  // slice of the localiser's work between places (the route search's scan: at most
  // profile::kScanSlicePlaces library places, ~8 ms on the head board; docs/performance.md,
  // "The time between places"). Statuses: the camera's and the localiser's (invalid image,
  // storage).
  Status on_snapshot(const hal::SensorSnapshot& snap, bool* placed, session::PlaceStep* step);

  uint32_t places() const { return library_.size(); }
  const session::Session& session() const { return session_; }

 private:
  Status handle(const hal::SensorSnapshot& snap, bool* placed, session::PlaceStep* step);
  Status open_library(bool teach);
  Status open_queries(bool repeat);

  const storage::RunConfig* config_ = nullptr;
  hal::PixelBuffer* camera_ = nullptr;
  uint32_t captures_ = 0;
  storage::Volume volume_{};
  storage::Region meta_{};
  storage::Region images_file_{};
  storage::Region queries_file_{};
  storage::StoredPlaceImages images_{};
  PlaceLibrary library_{};
  uint8_t image_cache_[profile::kImageCacheBytes] = {};
  storage::StoredQueryHistory queries_{};
  RamQueryHistory teach_history_{};  // teaching alone: the session needs one, it is not used
  uint32_t teach_places_ = 0;
  uint8_t query_buffer_[hal::kBlockSize] = {};  // one slot: images of up to 512 pixels
  uint32_t query_grew_[profile::kQuerySteps / 32] = {};
  RouteSearch route_{};
  profile::RouteStorage route_storage_{};
  session::Session session_{};
};

}  // namespace seqslam::example
