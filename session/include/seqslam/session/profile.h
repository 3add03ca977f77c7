// The firmware's capacity profile: the sizes its static state is made for and the optional
// features of this build. The firmware application (firmware/app) allocates its session with
// them, `seqslam config write` checks a configuration against them before it writes, and the
// PC tools run the head board's route search with the very same storage types, so a
// configuration the tools accept is one the robot runs (docs/firmware.md). Header only; the
// build selects the profile with the SEQSLAM_APP_* definitions of the seqslam_session target.
#pragma once

#include <stdint.h>

#include "seqslam/limits.h"
#include "seqslam/route_search.h"
#include "seqslam/session/features.h"
#include "seqslam/storage/run_config.h"

// Explore mode only (PC): places whose metadata and full-search state are kept in RAM.
#ifndef SEQSLAM_APP_MAX_PLACES
#define SEQSLAM_APP_MAX_PLACES 2000
#endif
// Grid tiles resident in RAM (1036 bytes each; the rest is paged to the card's `map` file).
// 3 is the least one ray needs (occupancy_grid.h); 6 keeps a whole scan resident.
#ifndef SEQSLAM_APP_GRID_SLOTS
#define SEQSLAM_APP_GRID_SLOTS 6
#endif
// Distinct map tiles the card store can index (8 bytes each in RAM): 1.6 m x 1.6 m each.
#ifndef SEQSLAM_APP_MAP_TILES
#define SEQSLAM_APP_MAP_TILES 512
#endif

namespace seqslam::profile {

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
// the default window, 27: 33 until issue 32 measured the same answers with 27, docs/accuracy.md).
inline constexpr uint16_t kWindowSlots = 25;
// Steps the query history keeps (a bit each in RAM, a 512-byte slot each on the card): the
// longest a relocalisation scan may take before its anchor's images are overwritten.
inline constexpr uint32_t kQuerySteps = 512;
// Library places of the route search's work (its replays, its scan) after each 10 ms snapshot
// (a slice): the longest slice stays inside the snapshot period (docs/performance.md, "The
// time between places"; 32 until the image cache went from 3 blocks to 2 in issue 32).
inline constexpr uint32_t kScanSlicePlaces = 24;
inline constexpr bool kHeuristicMatcher = SEQSLAM_APP_HEURISTIC != 0;
inline constexpr bool kMapping = SEQSLAM_APP_MAPPING != 0;

// Images up to this many pixels (the default 12x10) keep the relocalisation scan's query
// images in RAM (kMaxScanSeqLen of them, 1 200 bytes): read once a scan instead of once every
// chunk of library places, which made the card's requests most of a scan's time
// (docs/performance.md, "The time between places"). Larger images read them from the card.
inline constexpr uint32_t kScanRowPixels = storage::RunConfig{}.mapping.size().pixels();

// The route search's storage for these sizes.
using RouteStorage = RouteSearchStorage<kWindowSlots, kMaxSeqLen, kMaxScanSeqLen, kMaxNormWindow,
                                        kMaxExclusion, kScanRowPixels>;
// Its budget on the head board (docs/firmware.md, "Localising on a whole route"; images of at
// most 512 pixels, 17-bit differences): the window 25 x (2 S + 5), the band (25 + W) x 4, the
// scan 1 692 and its 10 query images of 120 pixels, the candidate 99.
static_assert(kMaxPixels != 512 || RouteStorage::kBytes == 25 * 65 + 75 * 4 + 1692 + 10 * 120 + 99,
              "the route search's RAM on the board: 4 916 bytes");

// Places the explore mode (PC only) holds: its full search keeps per-place state in RAM.
inline constexpr uint32_t kMaxPlaces = SEQSLAM_APP_MAX_PLACES;
// Explore: one graph node per place; edges: the odometry chain plus at most one closure per
// place; the grid's resident tiles and the card store's tile index; the final solve's bound
// (optimise_step slices after the last place).
inline constexpr uint32_t kGraphNodes = kMaxPlaces;
inline constexpr uint32_t kGraphEdges = 2 * kMaxPlaces;
inline constexpr uint32_t kGridSlots = SEQSLAM_APP_GRID_SLOTS;
inline constexpr uint32_t kMapTiles = SEQSLAM_APP_MAP_TILES;
inline constexpr uint32_t kMaxFinalSlices = 200000;
static_assert(kGridSlots >= 3, "a ray may touch 3 tiles: at least 3 grid slots");

// Cache for streaming library images from the card: 3 blocks, so 3 images of 512 pixels (2 of
// images that do not fill whole blocks: one block for the skew), 11 of the default 12x10. Its
// size is how many images one card request brings (each request costs the card's access time,
// ~0.5 ms: docs/card_model.md); RAM decided it (docs/firmware.md, "Memory on the board": 6
// blocks until issue 32 gave 1.5 KB to the scan's query images).
inline constexpr uint32_t kImageCacheBytes = 2 * 512;

// The run configurations this build runs.
inline constexpr storage::RunLimits kRunLimits{kMaxSeqLen,   kMaxNormWindow, kMaxExclusion,
                                               kWindowSlots, kMaxScanSeqLen, kHeuristicMatcher,
                                               kMapping};
static_assert(storage::check_run_config(storage::RunConfig{}, kRunLimits).ok(),
              "the firmware runs the default run configuration");

}  // namespace seqslam::profile
