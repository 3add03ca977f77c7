// What the firmware application can run: the sizes its static state is made for and the
// optional features of this build. The application checks a run configuration against them
// at start (storage::check_run_config) and `seqslam config write` checks with the same ones
// before it writes, so a configuration the tool writes is one the application runs
// (docs/firmware.md). Header only, no code: the host tools include it without linking the
// application (compiled with seqslam_app's definitions, SEQSLAM_APP_*).
#pragma once

#include <stdint.h>

#include "seqslam/storage/run_files.h"

// Whether the application can run the heuristic sequence matcher (run configuration
// `matcher`). Without it (0) a configuration that asks for it is refused at start, and none
// of the heuristic matcher's code or state is in the image (docs/firmware.md).
#ifndef SEQSLAM_APP_HEURISTIC
#define SEQSLAM_APP_HEURISTIC 1
#endif
// Whether the application can explore (run configuration mode `explore`: pose graph, loop
// closure, occupancy grid). Without it (0) an explore configuration is refused at start and
// none of the mapping code or state is in the image.
#ifndef SEQSLAM_APP_MAPPING
#define SEQSLAM_APP_MAPPING 1
#endif

namespace seqslam::app {

// Teach and repeat keep nothing per place in RAM: the library's images and metadata stay on
// the card and the route search's state is sized by these constants, not by the route
// (docs/firmware.md, "Localising on a whole route"). A configuration above them is refused at
// start, naming the setting (storage::check_run_config with kRunLimits).
// Longest sequence S the diagonal matcher's state is sized for (the heuristic's state does
// not grow with S: up to the core's kMaxSeqLen).
inline constexpr uint16_t kMaxSeqLen = 30;
// Longest sequence the relocalisation scan is sized for (route.scan_seq_len, at most S, <= it).
inline constexpr uint16_t kMaxScanSeqLen = 10;
// Widest local normalisation window W and largest exclusion R the route search is sized for.
inline constexpr uint16_t kMaxNormWindow = 50;
inline constexpr uint16_t kMaxExclusion = 10;
// Diagonals the route search's window can keep (the run configuration's route.window <= it;
// the default window, 33).
inline constexpr uint16_t kWindowSlots = 33;
// Steps the query history keeps (a bit each in RAM, a 512-byte slot each on the card): the
// longest a relocalisation scan may take before its anchor's images are overwritten.
inline constexpr uint32_t kQuerySteps = 512;
inline constexpr bool kHeuristicMatcher = SEQSLAM_APP_HEURISTIC != 0;
inline constexpr bool kMapping = SEQSLAM_APP_MAPPING != 0;

// The run configurations this build runs.
inline constexpr storage::RunLimits kRunLimits{kMaxSeqLen,   kMaxNormWindow, kMaxExclusion,
                                               kWindowSlots, kMaxScanSeqLen, kHeuristicMatcher,
                                               kMapping};
static_assert(storage::check_run_config(storage::RunConfig{}, kRunLimits).ok(),
              "the application runs the default run configuration");

}  // namespace seqslam::app
