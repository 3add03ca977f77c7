// Occupancy grid from the infrared distance sensors: log-odds cells in tiles, only a few of
// them in RAM, the rest behind a TileStore (the SD card on the robot).
//
// Cells. The world is a rectangle of width x height cells of cell_mm millimetres (default
// 50 mm, the resolution of the simulator's true map, so a grid and the true map compare cell
// for cell; the Sharp sensors' noise, 4 mm + 1.2 % of the distance, stays below one 5 cm cell
// up to their 1.5 m range). Cell (col, row) covers [origin_x + col * cell, origin_x + (col+1)
// * cell) x [same for y]: half-open, so every point belongs to exactly one cell. Each cell
// holds a log-odds value L = ln(p / (1 - p)) as an int8 in Q3.4 (raw / 16; 0 = p 0.5 =
// never seen). A miss adds config.miss (< 0), a hit config.hit (> 0), and the sum saturates
// at +-config.limit, so a cell that has been certain for a long time can still change within
// a bounded number of observations (limit - threshold over the increment).
//
// Classification: occupied iff L >= occupied_threshold, free iff L <= free_threshold,
// unknown otherwise. The defaults are the ROS map_server thresholds (occupied_thresh 0.65 ->
// L 0.62, free_thresh 0.196 -> L -1.41) rounded to Q3.4:
//
//   hit +14 (0.875, p 0.71)   miss -6 (-0.375, p 0.41)   limit 64 (4.0, p 0.982)
//   occupied >= 10 (0.625, p 0.65)   free <= -23 (-1.4375, p 0.19)
//
// so one hit makes a cell occupied and four misses make it free.
//
// Tiles. The cells are grouped into square tiles of kGridTileSide^2 = 32 x 32 cells (1024
// bytes, two SD sectors; 1.6 m at 5 cm). The simulated lab (54 m x 14 m with the side rooms)
// is 1080 x 280 cells = 34 x 9 tiles = 306 KB, far more than the board's 64 KB, so the grid
// keeps only N tiles in caller-owned RAM slots (OccupancyGridStorage<N>: N * 1036 bytes) and
// pages the others through a TileStore, least recently used first. A tile that was never
// saved reads as all zeros (unknown). One infrared ray (at most 1.5 m = 30 cells at 5 cm)
// spans at most 2 x 2 tiles and touches at most 3 of them, so N >= 3 is needed; a six-sensor
// scan reaches +-1.7 m around the robot, up to 3 x 2 tiles in a corridor, so N = 6 (6.2 KB)
// keeps a scan resident: tile loads per scan along a corridor 3.8 (N = 3), 2.7 (N = 4), 0.07
// (N = 6 or 8, i.e. each tile once per pass; tests/unit/test_occupancy_grid.cpp).
//
// Rays. insert_ray() walks the cells from the cell of the ray's start point to the cell of
// its end point with an integer Bresenham walk over the end points in 1/256 cell (not over
// the cell centres), see RayWalker: every visited cell is met by the segment, consecutive
// cells are 8-neighbours, the first and last cells are the cells of the end points. The cells
// before the last get a miss, the last a hit (or a miss for a free ray, e.g. a sensor's "no
// echo"). A ray is applied all or nothing: the tiles it touches are made resident first (a
// store error then leaves the map as it was), then every cell is updated.
//
// Number formats and error bounds. Positions come in as Q31.32 metres (Pose2) and become
// sub-cell coordinates in 1/2^8 cell (kGridSubcellBits), truncated towards minus infinity:
// error < 2^-8 cell (0.2 mm at 5 cm: far below the sensors' noise, and it keeps the walk in
// 32-bit arithmetic). The cell of a point is exact (a floor of a floor is the floor). A
// sensor ray computed from a pose, a mounting and a range in millimetres (sensor_ray()) uses
// sincos() (error <= 1.0e-9) and rounded Q31.32 products: its end points are within
// (|x| + |y| + range) * 1.0e-9 m + 2^-31 m of the exact values (tested against double
// precision: at most 1.2e-9 m for the Myon sensors). So an end cell differs from the exact
// double computation only where the exact point lies within about 1e-8 m of a cell boundary,
// and the walk follows the segment between the end points truncated to 1/256 cell.
//
// Graph changes ("re-entered when the graph changes"). The grid is a cache of the rays under
// the poses it was given; it does not keep the rays. When the pose graph is re-optimised the
// application clears the grid (clear(): RAM slots dropped, TileStore::clear()) and inserts the
// stored readings again with the optimised poses, e.g. per place: pose of the place from the
// graph, the snapshots since the previous place replayed through odometry relative to it.
// The rebuild driver belongs to the application; the grid only needs clear() and the same
// insert calls.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/fixmath.h"
#include "seqslam/odometry.h"
#include "seqslam/span.h"
#include "seqslam/status.h"

namespace seqslam {

inline constexpr uint32_t kGridTileShift = 5;
inline constexpr uint32_t kGridTileSide = 1u << kGridTileShift;            // cells
inline constexpr uint32_t kGridTileCells = kGridTileSide * kGridTileSide;  // bytes per tile
inline constexpr uint32_t kGridSubcellBits = 8;                            // Q.8 cells
inline constexpr int64_t kGridSubcell = int64_t{1} << kGridSubcellBits;    // one cell
// World size limit per side, in cells (tile coordinates then fit 10 bits).
inline constexpr uint32_t kMaxGridSide = 32768;
// Longest ray: |dx| and |dy| at most this many cells (keeps the walk's remainders in int32:
// 2^8 * 2^12 * 2^8 = 2^28).
inline constexpr uint32_t kMaxRayCells = 4096;
// Most tiles one ray may touch (the walk's tile list lives on the stack).
inline constexpr uint32_t kMaxRayTiles = 8;
// Most RAM slots (tile lookups scan the slots linearly).
inline constexpr uint32_t kMaxGridSlots = 64;

// Log-odds in Q3.4: raw / 16 = ln(p / (1 - p)).
inline constexpr int32_t kLogOddsOne = 16;

struct GridCell {
  int32_t col = 0;
  int32_t row = 0;
};
inline constexpr bool operator==(GridCell a, GridCell b) {
  return a.col == b.col && a.row == b.row;
}
inline constexpr bool operator!=(GridCell a, GridCell b) {
  return !(a == b);
}

// A tile coordinate: tile (x, y) holds the cells col = 32 x .. 32 x + 31, row = 32 y ..
// 32 y + 31; inside a tile the cells are stored row by row, cell (col, row) at byte
// (row % 32) * 32 + col % 32.
struct GridTile {
  uint16_t x = 0;
  uint16_t y = 0;
};

// The integer walk from one point to another, in sub-cell coordinates (1/2^8 cell, cell
// (c, r) = [c, c+1) x [r, r+1) after dividing by 2^8). The axis along which the segment is
// longer (major axis; x on a tie) is sampled at the start point and then at every whole cell
// step along it, start + k (one cell along the major axis, |d minor| / |d major| cells along
// the other), k = 0..floor(|d major|); the minor coordinate's fraction is kept exactly as a
// remainder over |d major| (Bresenham's error term, with the sub-cell start offset folded in),
// so no rounding happens. The cells of those samples, then the end point's cell if it differs
// from the last, are the walk. Therefore:
//  - every cell contains a point of the segment (the samples lie on it): the walk is a subset
//    of the cells the exact segment passes through or touches;
//  - consecutive cells differ by exactly 1 along the major axis (the end cell: by 0 or 1) and
//    by at most 1 along the other: 8-connected, no cell twice;
//  - the first cell is the start point's, the last the end point's; a zero-length ray (or
//    start and end in one cell) is one cell;
//  - floor(|d major|) + 1 or + 2 cells, i.e. |end cell - start cell| along the major axis
//    + 1, plus one when the last step changes only the minor axis.
// Cost per cell: one 32-bit add and compare (no multiply or divide in the loop).
class RayWalker {
 public:
  // Starts a walk. kOutOfRange if |x1 - x0| or |y1 - y0| exceeds kMaxRayCells cells or a
  // coordinate's cell index does not fit int32 (nothing changes then).
  Status reset(int64_t x0, int64_t y0, int64_t x1, int64_t y1);
  // The next cell of the walk into *cell; false when the walk is over (or never started).
  bool next(GridCell* cell);
  // True when the cell next() returned last is the end point's cell.
  bool at_end() const { return done_; }
  GridCell start_cell() const { return start_; }
  GridCell end_cell() const { return end_; }

 private:
  friend class OccupancyGrid;  // its insert loop inlines next()

  int32_t rem_ = 0;   // minor fraction * |d major|, in [0, den_)
  int32_t step_ = 0;  // d minor * 2^8 per major step (|step_| <= den_)
  int32_t den_ = 1;   // 2^8 * |d major| <= 2^28
  int32_t major_ = 0;
  int32_t minor_ = 0;
  int32_t major_dir_ = 1;
  uint32_t steps_left_ = 0;  // whole major steps still to take
  GridCell start_{};
  GridCell end_{};
  bool x_major_ = true;
  bool started_ = false;  // the first sample has not been emitted yet
  bool active_ = false;
  bool done_ = false;
};

// Where the grid keeps tiles it cannot hold in RAM. Tiles are 1024 bytes of int8 log-odds in
// the layout described at GridTile. Implementations: a region of the SD card (storage), a RAM
// table (tests, host tools).
class TileStore {
 public:
  // Reads tile `tile` into `cells` (kGridTileCells bytes). Returns kNotFound for a tile that
  // was never saved since the last clear() (the grid then treats it as all unknown), or the
  // implementation's error (e.g. kDataLoss, kUnavailable); kInvalidArgument for a wrong
  // buffer size.
  Status load(GridTile tile, Span<int8_t> cells) {
    if (cells.data() == nullptr || cells.size() != kGridTileCells) return Status::kInvalidArgument;
    return do_load(tile, cells);
  }
  // Writes tile `tile` from `cells` (kGridTileCells bytes).
  Status save(GridTile tile, Span<const int8_t> cells) {
    if (cells.data() == nullptr || cells.size() != kGridTileCells) return Status::kInvalidArgument;
    return do_save(tile, cells);
  }
  // Forgets every tile (afterwards every load returns kNotFound). A store on the card can do
  // this lazily, e.g. with a generation number in each tile record.
  Status clear() { return do_clear(); }

 protected:
  TileStore() = default;
  ~TileStore() = default;
  TileStore(const TileStore&) = default;
  TileStore& operator=(const TileStore&) = default;

 private:
  virtual Status do_load(GridTile tile, Span<int8_t> cells) = 0;
  virtual Status do_save(GridTile tile, Span<const int8_t> cells) = 0;
  virtual Status do_clear() = 0;
};

struct GridConfig {
  // World position of cell (0, 0)'s lower-left corner, metres.
  Q31_32 origin_x = Q31_32::from_int(0);
  Q31_32 origin_y = Q31_32::from_int(0);
  uint16_t cell_mm = 50;  // cell side, 10..1000 mm
  uint16_t width = 0;     // cells along x, 1..kMaxGridSide: the world bounds
  uint16_t height = 0;    // cells along y, 1..kMaxGridSide
  // Q3.4 log-odds (see the top of this file).
  int8_t hit = 14;                 // > 0, <= limit
  int8_t miss = -6;                // < 0, >= -limit
  int8_t limit = 64;               // saturation, 1..127
  int8_t occupied_threshold = 10;  // 0 < occupied_threshold <= limit
  int8_t free_threshold = -23;     // -limit <= free_threshold < 0
};

enum class GridIssue : uint8_t {
  kNone = 0,
  kCellSizeOutOfRange,   // cell_mm outside 10..1000
  kSizeOutOfRange,       // width or height 0 or > kMaxGridSide
  kLimitOutOfRange,      // limit outside 1..127
  kIncrementOutOfRange,  // hit <= 0 or > limit, miss >= 0 or < -limit
  kThresholdOutOfRange,  // thresholds not in [-limit, 0) and (0, limit]
  kNoSlots,              // no RAM slot, more than kMaxGridSlots, or too few cell bytes
};
// Short stable text, e.g. "grid.cell_mm must be 10..1000".
const char* grid_issue_text(GridIssue issue);
// kOutOfRange for every issue but kNoSlots (checked by configure); *issue names it.
Status check_grid_config(const GridConfig& config, GridIssue* issue = nullptr);

enum class CellState : uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };

// Metadata of one RAM slot (public so OccupancyGridStorage can size it).
struct GridSlot {
  uint32_t last_use = 0;  // the grid's use counter when the slot was last touched
  GridTile tile{};
  uint8_t state = 0;  // 0 empty, 1 clean, 2 dirty (differs from the store)
};

struct OccupancyGridBuffers {
  Span<int8_t> cells;    // >= slots.size() * kGridTileCells
  Span<GridSlot> slots;  // 1..kMaxGridSlots
};

// RAM for kSlots resident tiles, for static allocation:
// `static OccupancyGridStorage<4> grid_ram;` (4 x 1036 bytes).
template <uint32_t kSlots>
struct OccupancyGridStorage {
  static_assert(kSlots >= 1 && kSlots <= kMaxGridSlots, "bad slot count");
  static constexpr size_t kBytes = kSlots * (kGridTileCells + sizeof(GridSlot));
  int8_t cells[kSlots * kGridTileCells];
  GridSlot slots[kSlots];

  OccupancyGridBuffers buffers() {
    return {Span<int8_t>(cells, kSlots * kGridTileCells), Span<GridSlot>(slots, kSlots)};
  }
};
static_assert(sizeof(GridSlot) == 12, "slot metadata grew");
static_assert(OccupancyGridStorage<4>::kBytes == 4144, "4 resident tiles: 4 KB + metadata");
static_assert(OccupancyGridStorage<6>::kBytes == 6216, "6 resident tiles (one scan): 6.1 KB");

// A range sensor on the robot: mounting point in the robot frame (x forward, y left, metres),
// pointing direction relative to the robot's heading, and its range.
struct RangeSensor {
  Q31_32 x = Q31_32::from_int(0);
  Q31_32 y = Q31_32::from_int(0);
  Angle angle{};
  uint16_t min_mm = 200;   // readings 1..min_mm-1 are rejected
  uint16_t max_mm = 1500;  // readings above are rejected
  // A reading of 0 (no echo): free up to this distance (max minus a margin for the noise near
  // the range end, where a real echo may fall out of range), no hit; 0: ignore such readings.
  // A limitation: the sensors also read 0 for an obstacle closer than min_mm.
  uint16_t no_echo_mm = 1400;
};

// Myon's six infrared sensors as the simulator mounts them (host_sim default_infrared(),
// docs/simulator.md): front, front-left and front-right at +-45 degrees, left, right, rear;
// Sharp GP2Y0A02-like range 0.2..1.5 m.
inline constexpr uint32_t kMyonInfraredCount = 6;
inline constexpr RangeSensor kMyonInfrared[kMyonInfraredCount] = {
    {Q31_32::from_ratio(20, 100), Q31_32::from_int(0), Angle::from_degrees(0), 200, 1500, 1400},
    {Q31_32::from_ratio(17, 100), Q31_32::from_ratio(12, 100), Angle::from_degrees(45), 200, 1500,
     1400},
    {Q31_32::from_ratio(17, 100), Q31_32::from_ratio(-12, 100), Angle::from_degrees(-45), 200, 1500,
     1400},
    {Q31_32::from_int(0), Q31_32::from_ratio(20, 100), Angle::from_degrees(90), 200, 1500, 1400},
    {Q31_32::from_int(0), Q31_32::from_ratio(-20, 100), Angle::from_degrees(-90), 200, 1500, 1400},
    {Q31_32::from_ratio(-20, 100), Q31_32::from_int(0), Angle::from_degrees(180), 200, 1500, 1400},
};

// A ray in world coordinates (metres).
struct SensorRay {
  Q31_32 x0;
  Q31_32 y0;
  Q31_32 x1;
  Q31_32 y1;
  bool hit = false;  // the end is an echo (else the whole ray is free)
  bool use = false;  // false: nothing to insert (a no-echo reading with no_echo_mm 0)
};

// The ray of one reading: sensor origin = pose + R(heading) (x, y); direction heading + angle;
// length range_mm (hit) or no_echo_mm for a reading of 0 (free). kOutOfRange for a non-zero
// reading outside min_mm..max_mm or a mounting offset of 256 m or more, kInvalidArgument for a
// null `out` (nothing written then). Positions saturate at the Q31.32 range.
Status sensor_ray(const Pose2& pose, const RangeSensor& sensor, uint16_t range_mm, SensorRay* out);

// What one insert did (optional).
struct RayReport {
  uint32_t cells = 0;    // cells updated
  bool clipped = false;  // the ray left the world bounds: cells up to the boundary got misses,
                         // the end (outside) no hit
};

// Paging counters since configure().
struct GridStats {
  uint32_t rays = 0;        // rays applied
  uint32_t cells = 0;       // cell updates
  uint32_t tile_loads = 0;  // TileStore::load calls (including kNotFound)
  uint32_t tile_saves = 0;  // TileStore::save calls
};

class OccupancyGrid {
 public:
  // Adopts the configuration, the RAM slots and the store; every slot starts empty (what was
  // resident before is dropped without saving: flush() first to keep it). Returns the
  // statuses of check_grid_config, or kResourceExhausted (issue kNoSlots) for no slot, more
  // than kMaxGridSlots or fewer than slots * 1024 cell bytes; nothing changes on failure.
  Status configure(const GridConfig& config, const OccupancyGridBuffers& buffers, TileStore& store,
                   GridIssue* issue = nullptr);

  // One ray from (x0, y0) to (x1, y1), metres: misses on the cells before the end cell, then
  // a hit (hit == true) or a miss on the end cell. Returns
  //   kFailedPrecondition - not configured;
  //   kOutOfRange         - the start is outside the world bounds, or the ray is longer than
  //                         kMaxRayCells cells along x or y;
  //   kResourceExhausted  - the ray touches more tiles than there are RAM slots (or than
  //                         kMaxRayTiles);
  //   a TileStore error   - paging a tile in or out failed.
  // On any of these the map is unchanged (the slots may hold other tiles). A ray that leaves
  // the bounds is clipped (kOk, report->clipped): its cells up to the boundary get misses.
  Status insert_ray(Q31_32 x0, Q31_32 y0, Q31_32 x1, Q31_32 y1, bool hit,
                    RayReport* report = nullptr);
  Status insert_ray(const SensorRay& ray, RayReport* report = nullptr);

  // sensor_ray() then insert_ray() (a reading that yields no ray: kOk, nothing changes).
  Status insert_reading(const Pose2& pose, const RangeSensor& sensor, uint16_t range_mm,
                        RayReport* report = nullptr);
  // One snapshot: readings[i] of sensors[i]. Every reading is checked first (kInvalidArgument
  // for different sizes, sensor_ray's kOutOfRange: nothing inserted); then the rays are
  // inserted in order, and the first insert error is returned (the rays before it stay).
  Status insert_scan(const Pose2& pose, Span<const RangeSensor> sensors,
                     Span<const uint16_t> readings_mm);

  // The cell containing world point (x, y). kOutOfRange outside the bounds,
  // kFailedPrecondition before configure(), kInvalidArgument for a null `out`.
  Status cell_at(Q31_32 x, Q31_32 y, GridCell* out) const;
  // A cell's log-odds / state; pages its tile in like an insert (statuses of insert_ray,
  // kOutOfRange outside the bounds, kInvalidArgument for a null `out`).
  Status log_odds(GridCell cell, int8_t* out);
  Status state(GridCell cell, CellState* out);
  CellState classify(int8_t log_odds) const {
    if (log_odds >= config_.occupied_threshold) return CellState::kOccupied;
    if (log_odds <= config_.free_threshold) return CellState::kFree;
    return CellState::kUnknown;
  }

  // Export: tiles_x() x tiles_y() tiles cover the bounds (cells beyond width / height in the
  // last column and row are never written and read 0). copy_tile() copies a tile's current
  // content from RAM or the store (a never-saved tile as zeros) without changing the slots.
  // kOutOfRange for a tile outside, kInvalidArgument for a wrong buffer, kFailedPrecondition
  // before configure(), store errors.
  uint16_t tiles_x() const { return tiles_x_; }
  uint16_t tiles_y() const { return tiles_y_; }
  Status copy_tile(GridTile tile, Span<int8_t> out) const;

  // Saves every dirty slot (they stay resident, clean). The first store error is returned;
  // slots not yet saved stay dirty.
  Status flush();
  // Forgets the whole map: TileStore::clear(), then every slot dropped. On a store error
  // nothing changes.
  Status clear();

  bool configured() const { return configured_; }
  const GridConfig& config() const { return config_; }
  const GridStats& stats() const { return stats_; }
  uint32_t slot_count() const { return static_cast<uint32_t>(buffers_.slots.size()); }
  // Whether tile `tile` is resident (tests).
  bool resident(GridTile tile) const { return find_slot(tile) >= 0; }

 private:
  Status to_subcell(Q31_32 v, Q31_32 origin, int64_t* out) const;
  int32_t find_slot(GridTile tile) const;
  Status make_resident(const GridTile* tiles, uint32_t count, int32_t* slots);
  void apply(const RayWalker& walker, bool clip, bool hit, RayReport* report);
  void tick();
  bool in_bounds(GridCell c) const {
    return static_cast<uint32_t>(c.col) < config_.width &&
           static_cast<uint32_t>(c.row) < config_.height;
  }
  int8_t* slot_cells(int32_t slot) const {
    return buffers_.cells.data() + static_cast<size_t>(slot) * kGridTileCells;
  }

  GridConfig config_{};
  OccupancyGridBuffers buffers_{};
  TileStore* store_ = nullptr;
  GridStats stats_{};
  uint32_t clock_ = 0;            // use counter for the LRU choice
  uint16_t cells_per_metre_ = 0;  // 1000 / cell_mm when that is whole, else 0
  uint16_t tiles_x_ = 0;
  uint16_t tiles_y_ = 0;
  bool configured_ = false;
};

// The grid object itself is small; the tiles are caller-owned (OccupancyGridStorage).
static_assert(sizeof(OccupancyGrid) <= 128, "OccupancyGrid object budget");

}  // namespace seqslam
