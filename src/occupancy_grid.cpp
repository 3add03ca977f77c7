#include "seqslam/occupancy_grid.h"

#include "seqslam/assert.h"
#include "seqslam/messages.h"

namespace seqslam {

namespace {

// |v| for |v| < 2^63 (callers bound v first).
constexpr int64_t abs64(int64_t v) {
  return v < 0 ? -v : v;
}

// -bound < v < bound, safe for every int64 (no negation).
constexpr bool inside(int64_t v, int64_t bound) {
  return v > -bound && v < bound;
}

// floor(v / 2^8): the cell index of a sub-cell coordinate. GCC and Clang shift signed values
// arithmetically (C++20 requires it), which is the floor.
constexpr int64_t cell_index(int64_t v) {
  return v >> kGridSubcellBits;
}

// |sub-cell coordinates| stay below 2^39 so cell indices fit int32 and differences int64.
constexpr int64_t kMaxSubcell = int64_t{1} << (31 + kGridSubcellBits);

constexpr int64_t kMaxRaySubcells = static_cast<int64_t>(kMaxRayCells) * kGridSubcell;

// Positions further than 2^20 m from the grid origin are rejected before scaling, so the
// product with 1000 stays below 2^62 (raw Q31.32 = metres * 2^32).
constexpr int64_t kMaxOffsetRaw = int64_t{1} << 52;

GridTile tile_of(GridCell c) {
  return GridTile{static_cast<uint16_t>(static_cast<uint32_t>(c.col) >> kGridTileShift),
                  static_cast<uint16_t>(static_cast<uint32_t>(c.row) >> kGridTileShift)};
}

bool same_tile(GridTile a, GridTile b) {
  return a.x == b.x && a.y == b.y;
}

size_t cell_offset(GridCell c) {
  const uint32_t mask = kGridTileSide - 1;
  return static_cast<size_t>(((static_cast<uint32_t>(c.row) & mask) << kGridTileShift) |
                             (static_cast<uint32_t>(c.col) & mask));
}

int8_t saturating_update(int8_t value, int8_t increment, int8_t limit) {
  int32_t v = static_cast<int32_t>(value) + static_cast<int32_t>(increment);
  if (v > limit) v = limit;
  if (v < -limit) v = -limit;
  return static_cast<int8_t>(v);
}

void fill_zero(Span<int8_t> cells) {
  for (int8_t& c : cells)
    c = 0;
}

enum SlotState : uint8_t { kEmpty = 0, kClean = 1, kDirty = 2 };

}  // namespace

// ---- RayWalker ----

Status RayWalker::reset(int64_t x0, int64_t y0, int64_t x1, int64_t y1) {
  if (!inside(x0, kMaxSubcell) || !inside(y0, kMaxSubcell) || !inside(x1, kMaxSubcell) ||
      !inside(y1, kMaxSubcell)) {
    return Status::kOutOfRange;
  }
  const int64_t dx = x1 - x0;
  const int64_t dy = y1 - y0;
  if (abs64(dx) > kMaxRaySubcells || abs64(dy) > kMaxRaySubcells) return Status::kOutOfRange;
  x_major_ = abs64(dx) >= abs64(dy);
  const int64_t a0 = x_major_ ? x0 : y0;
  const int64_t b0 = x_major_ ? y0 : x0;
  const int64_t da = x_major_ ? dx : dy;
  const int64_t db = x_major_ ? dy : dx;
  const int64_t abs_da = abs64(da);
  major_ = static_cast<int32_t>(cell_index(a0));
  minor_ = static_cast<int32_t>(cell_index(b0));
  major_dir_ = da < 0 ? -1 : 1;
  steps_left_ = static_cast<uint32_t>(abs_da >> kGridSubcellBits);
  if (abs_da == 0) {
    // Then db == 0 too (|db| <= |da|): a single cell.
    den_ = 1;
    rem_ = 0;
    step_ = 0;
  } else {
    // Minor position of sample k: b0 + db k 2^8 / |da| (sub-cell units). Scaled by |da|, the
    // fraction within the current cell is rem_ / den_ with den_ = 2^8 |da|; each major step
    // adds db 2^8. |db| <= |da| keeps |step_| <= den_, so one carry per step suffices, and
    // |da| <= 2^20 keeps den_ <= 2^28 and rem_ + step_ < 2^29: int32.
    den_ = static_cast<int32_t>(abs_da * kGridSubcell);
    rem_ = static_cast<int32_t>((b0 - static_cast<int64_t>(minor_) * kGridSubcell) * abs_da);
    step_ = static_cast<int32_t>(db * kGridSubcell);
  }
  start_ = x_major_ ? GridCell{major_, minor_} : GridCell{minor_, major_};
  end_ = GridCell{static_cast<int32_t>(cell_index(x1)), static_cast<int32_t>(cell_index(y1))};
  started_ = false;
  active_ = true;
  done_ = false;
  return Status::kOk;
}

bool RayWalker::next(GridCell* cell) {
  if (!active_ || cell == nullptr) return false;
  if (!started_) {
    started_ = true;
  } else if (steps_left_ > 0) {
    --steps_left_;
    major_ += major_dir_;
    rem_ += step_;
    if (rem_ >= den_) {
      rem_ -= den_;
      ++minor_;
    } else if (rem_ < 0) {
      rem_ += den_;
      --minor_;
    }
  } else {
    // The samples are done and the end point lies in the neighbouring cell.
    *cell = end_;
    done_ = true;
    active_ = false;
    return true;
  }
  *cell = x_major_ ? GridCell{major_, minor_} : GridCell{minor_, major_};
  if (steps_left_ == 0 && *cell == end_) {
    done_ = true;
    active_ = false;
  }
  return true;
}

// ---- Configuration ----

const char* grid_issue_text(GridIssue issue) {
#if !SEQSLAM_MESSAGE_TEXTS
  return message_code("GI", static_cast<uint32_t>(issue));
#endif
  switch (issue) {
    case GridIssue::kNone:
      return "ok";
    case GridIssue::kCellSizeOutOfRange:
      return "grid.cell_mm must be 10..1000";
    case GridIssue::kSizeOutOfRange:
      return "grid.width and grid.height must be 1..32768 cells (kMaxGridSide)";
    case GridIssue::kLimitOutOfRange:
      return "grid.limit must be 1..127";
    case GridIssue::kIncrementOutOfRange:
      return "grid.hit must be 1..limit and grid.miss -limit..-1";
    case GridIssue::kThresholdOutOfRange:
      return "grid.occupied_threshold must be 1..limit and grid.free_threshold -limit..-1";
    case GridIssue::kNoSlots:
      return "grid buffers must hold 1..64 slots (kMaxGridSlots) of 1024 cell bytes each";
  }
  return "unknown";
}

Status check_grid_config(const GridConfig& c, GridIssue* issue) {
  GridIssue found = GridIssue::kNone;
  if (c.cell_mm < 10 || c.cell_mm > 1000) {
    found = GridIssue::kCellSizeOutOfRange;
  } else if (c.width == 0 || c.height == 0 || c.width > kMaxGridSide || c.height > kMaxGridSide) {
    found = GridIssue::kSizeOutOfRange;
  } else if (c.limit < 1) {
    found = GridIssue::kLimitOutOfRange;
  } else if (c.hit < 1 || c.hit > c.limit || c.miss > -1 || c.miss < -c.limit) {
    found = GridIssue::kIncrementOutOfRange;
  } else if (c.occupied_threshold < 1 || c.occupied_threshold > c.limit || c.free_threshold > -1 ||
             c.free_threshold < -c.limit) {
    found = GridIssue::kThresholdOutOfRange;
  }
  if (issue != nullptr) *issue = found;
  return found == GridIssue::kNone ? Status::kOk : Status::kOutOfRange;
}

Status OccupancyGrid::configure(const GridConfig& config, const OccupancyGridBuffers& buffers,
                                TileStore& store, GridIssue* issue) {
  GridIssue found = GridIssue::kNone;
  const Status s = check_grid_config(config, &found);
  if (s != Status::kOk) {
    if (issue != nullptr) *issue = found;
    return s;
  }
  const size_t slots = buffers.slots.size();
  if (buffers.slots.data() == nullptr || buffers.cells.data() == nullptr || slots == 0 ||
      slots > kMaxGridSlots || buffers.cells.size() / kGridTileCells < slots) {
    if (issue != nullptr) *issue = GridIssue::kNoSlots;
    return Status::kResourceExhausted;
  }
  if (issue != nullptr) *issue = GridIssue::kNone;
  config_ = config;
  buffers_ = buffers;
  store_ = &store;
  stats_ = GridStats{};
  clock_ = 0;
  cells_per_metre_ =
      1000 % config.cell_mm == 0 ? static_cast<uint16_t>(1000 / config.cell_mm) : uint16_t{0};
  tiles_x_ = static_cast<uint16_t>((config.width + kGridTileSide - 1) >> kGridTileShift);
  tiles_y_ = static_cast<uint16_t>((config.height + kGridTileSide - 1) >> kGridTileShift);
  for (GridSlot& slot : buffers_.slots)
    slot = GridSlot{};
  configured_ = true;
  return Status::kOk;
}

// ---- Coordinates ----

Status OccupancyGrid::to_subcell(Q31_32 v, Q31_32 origin, int64_t* out) const {
  // metres * 2^32 -> cells * 2^8: * 1000 / (cell_mm * 2^24), rounded towards minus infinity.
  // A 64-bit division is a ~700-instruction libgcc call on RV32, so cell sizes that divide a
  // metre (10, 20, 25, 40, 50, 100, 125, 200, 250, 500, 1000 mm) multiply instead, exactly.
  int64_t d = 0;
  if (__builtin_sub_overflow(v.raw(), origin.raw(), &d) || !inside(d, kMaxOffsetRaw)) {
    return Status::kOutOfRange;
  }
  if (cells_per_metre_ != 0) {
    *out = (d * cells_per_metre_) >> (32 - kGridSubcellBits);  // arithmetic shift: floor
    return Status::kOk;
  }
  const int64_t n = d * 1000;
  const int64_t den = static_cast<int64_t>(config_.cell_mm) << (32 - kGridSubcellBits);
  int64_t q = n / den;
  if (q * den > n) --q;  // truncation went up for a negative n
  *out = q;
  return Status::kOk;
}

Status OccupancyGrid::cell_at(Q31_32 x, Q31_32 y, GridCell* out) const {
  if (out == nullptr) return Status::kInvalidArgument;
  if (!configured_) return Status::kFailedPrecondition;
  int64_t sx = 0;
  int64_t sy = 0;
  if (to_subcell(x, config_.origin_x, &sx) != Status::kOk ||
      to_subcell(y, config_.origin_y, &sy) != Status::kOk) {
    return Status::kOutOfRange;
  }
  const int64_t col = cell_index(sx);
  const int64_t row = cell_index(sy);
  if (col < 0 || row < 0 || col >= config_.width || row >= config_.height) {
    return Status::kOutOfRange;
  }
  *out = GridCell{static_cast<int32_t>(col), static_cast<int32_t>(row)};
  return Status::kOk;
}

// ---- Paging ----

int32_t OccupancyGrid::find_slot(GridTile tile) const {
  for (size_t i = 0; i < buffers_.slots.size(); ++i) {
    const GridSlot& s = buffers_.slots[i];
    if (s.state != kEmpty && same_tile(s.tile, tile)) return static_cast<int32_t>(i);
  }
  return -1;
}

void OccupancyGrid::tick() {
  if (++clock_ == 0) {
    // The counter wrapped (after 2^32 uses): restart the ages.
    for (GridSlot& s : buffers_.slots)
      s.last_use = 0;
    clock_ = 1;
  }
}

// Makes tiles[0..count) resident, slots[i] = the slot of tiles[i]. The tiles of this call are
// stamped with the current use count first, so a victim is never one of them. Map content is
// never lost: a dirty victim is saved before its slot is reused, and a failed save keeps it.
Status OccupancyGrid::make_resident(const GridTile* tiles, uint32_t count, int32_t* slots) {
  tick();
  for (uint32_t i = 0; i < count; ++i) {
    slots[i] = find_slot(tiles[i]);
    if (slots[i] >= 0) buffers_.slots[static_cast<size_t>(slots[i])].last_use = clock_;
  }
  for (uint32_t i = 0; i < count; ++i) {
    if (slots[i] >= 0) continue;
    int32_t victim = -1;
    for (size_t k = 0; k < buffers_.slots.size(); ++k) {
      const GridSlot& s = buffers_.slots[k];
      if (s.state == kEmpty) {
        victim = static_cast<int32_t>(k);
        break;
      }
      if (s.last_use != clock_ &&
          (victim < 0 || s.last_use < buffers_.slots[static_cast<size_t>(victim)].last_use)) {
        victim = static_cast<int32_t>(k);
      }
    }
    if (victim < 0) return Status::kResourceExhausted;
    GridSlot& slot = buffers_.slots[static_cast<size_t>(victim)];
    const Span<int8_t> cells(slot_cells(victim), kGridTileCells);
    if (slot.state == kDirty) {
      ++stats_.tile_saves;
      SEQSLAM_TRY(store_->save(slot.tile, cells));
    }
    slot.state = kEmpty;
    ++stats_.tile_loads;
    const Status s = store_->load(tiles[i], cells);
    if (s == Status::kNotFound) {
      fill_zero(cells);
    } else if (s != Status::kOk) {
      return s;
    }
    slot.tile = tiles[i];
    slot.state = kClean;
    slot.last_use = clock_;
    slots[i] = victim;
  }
  return Status::kOk;
}

Status OccupancyGrid::flush() {
  if (!configured_) return Status::kFailedPrecondition;
  for (size_t k = 0; k < buffers_.slots.size(); ++k) {
    GridSlot& slot = buffers_.slots[k];
    if (slot.state != kDirty) continue;
    ++stats_.tile_saves;
    const Status s =
        store_->save(slot.tile, Span<int8_t>(slot_cells(static_cast<int32_t>(k)), kGridTileCells));
    if (s != Status::kOk) return s;
    slot.state = kClean;
  }
  return Status::kOk;
}

Status OccupancyGrid::clear() {
  if (!configured_) return Status::kFailedPrecondition;
  SEQSLAM_TRY(store_->clear());
  for (GridSlot& slot : buffers_.slots)
    slot = GridSlot{};
  clock_ = 0;
  return Status::kOk;
}

Status OccupancyGrid::copy_tile(GridTile tile, Span<int8_t> out) const {
  if (!configured_) return Status::kFailedPrecondition;
  if (out.data() == nullptr || out.size() != kGridTileCells) return Status::kInvalidArgument;
  if (tile.x >= tiles_x_ || tile.y >= tiles_y_) return Status::kOutOfRange;
  const int32_t slot = find_slot(tile);
  if (slot >= 0) {
    const int8_t* cells = slot_cells(slot);
    for (size_t i = 0; i < kGridTileCells; ++i)
      out[i] = cells[i];
    return Status::kOk;
  }
  const Status s = store_->load(tile, out);
  if (s == Status::kNotFound) {
    fill_zero(out);
    return Status::kOk;
  }
  return s;
}

// ---- Rays ----

// Applies the walk; every tile it visits inside the bounds is resident. The walk is inlined
// here (same steps as RayWalker::next, the state in registers): this loop is the grid's hot
// path. `clip`: the end lies outside the bounds, so each cell is checked (the walk leaves the
// bounds once and for all: its samples lie on the segment, whose part inside the convex
// bounds is one piece).
void OccupancyGrid::apply(const RayWalker& w, bool clip, bool hit, RayReport* report) {
  const int8_t limit = config_.limit;
  const int8_t miss = config_.miss;
  const int8_t last = hit ? config_.hit : config_.miss;
  const int32_t den = w.den_;
  const int32_t step = w.step_;
  const int32_t dir = w.major_dir_;
  const bool x_major = w.x_major_;
  int32_t major = w.major_;
  int32_t minor = w.minor_;
  int32_t rem = w.rem_;
  uint32_t steps = w.steps_left_;
  GridCell c = w.start_;
  uint32_t tile_x = 0xFFFFFFFFu;  // no tile yet
  uint32_t tile_y = 0xFFFFFFFFu;
  int8_t* cells = nullptr;
  uint32_t updated = 0;
  bool clipped = false;
  for (;;) {
    // The end cell: the last sample, or its neighbour after the samples.
    const bool at_end = steps == 0 && c == w.end_;
    if (clip && !in_bounds(c)) {
      clipped = true;
      break;
    }
    const uint32_t tx = static_cast<uint32_t>(c.col) >> kGridTileShift;
    const uint32_t ty = static_cast<uint32_t>(c.row) >> kGridTileShift;
    if (tx != tile_x || ty != tile_y) {
      tile_x = tx;
      tile_y = ty;
      const int32_t slot =
          find_slot(GridTile{static_cast<uint16_t>(tx), static_cast<uint16_t>(ty)});
      SEQSLAM_ASSERT(slot >= 0);
      cells = slot_cells(slot);
      buffers_.slots[static_cast<size_t>(slot)].state = kDirty;
    }
    int8_t& cell = cells[cell_offset(c)];
    cell = saturating_update(cell, at_end ? last : miss, limit);
    ++updated;
    if (at_end) break;
    if (steps == 0) {
      c = w.end_;
      continue;
    }
    --steps;
    major += dir;
    rem += step;
    if (rem >= den) {
      rem -= den;
      ++minor;
    } else if (rem < 0) {
      rem += den;
      --minor;
    }
    c = x_major ? GridCell{major, minor} : GridCell{minor, major};
  }
  ++stats_.rays;
  stats_.cells += updated;
  if (report != nullptr) *report = RayReport{updated, clipped};
}

Status OccupancyGrid::insert_ray(Q31_32 x0, Q31_32 y0, Q31_32 x1, Q31_32 y1, bool hit,
                                 RayReport* report) {
  if (!configured_) return Status::kFailedPrecondition;
  int64_t sx0 = 0;
  int64_t sy0 = 0;
  int64_t sx1 = 0;
  int64_t sy1 = 0;
  if (to_subcell(x0, config_.origin_x, &sx0) != Status::kOk ||
      to_subcell(y0, config_.origin_y, &sy0) != Status::kOk ||
      to_subcell(x1, config_.origin_x, &sx1) != Status::kOk ||
      to_subcell(y1, config_.origin_y, &sy1) != Status::kOk) {
    return Status::kOutOfRange;
  }
  RayWalker walker;
  SEQSLAM_TRY(walker.reset(sx0, sy0, sx1, sy1));
  const GridCell start = walker.start_cell();
  if (!in_bounds(start)) return Status::kOutOfRange;
  const GridCell end = walker.end_cell();
  const bool clip = !in_bounds(end);

  // The walk is monotone in both axes, so the cells it visits inside the bounds lie in the
  // box spanned by the start cell and the end cell clamped to the bounds. If that box covers
  // at most 2 x 2 tiles and all are resident (the usual case), they are simply marked used.
  // Otherwise a first pass lists the tiles the walk really visits (each once, in order) and
  // pages them in, so no tile is loaded for nothing.
  const GridCell last{end.col < 0 ? 0 : (end.col >= config_.width ? config_.width - 1 : end.col),
                      end.row < 0 ? 0 : (end.row >= config_.height ? config_.height - 1 : end.row)};
  const GridTile a = tile_of(start);
  const GridTile b = tile_of(last);
  const GridTile lo{a.x < b.x ? a.x : b.x, a.y < b.y ? a.y : b.y};
  const GridTile hi{a.x < b.x ? b.x : a.x, a.y < b.y ? b.y : a.y};
  bool resident_box = hi.x - lo.x <= 1 && hi.y - lo.y <= 1;
  int32_t box_slots[4];
  uint32_t box_count = 0;
  for (uint16_t ty = lo.y; resident_box && ty <= hi.y; ++ty) {
    for (uint16_t tx = lo.x; resident_box && tx <= hi.x; ++tx) {
      box_slots[box_count] = find_slot(GridTile{tx, ty});
      resident_box = box_slots[box_count++] >= 0;
    }
  }
  if (resident_box) {
    tick();
    for (uint32_t i = 0; i < box_count; ++i)
      buffers_.slots[static_cast<size_t>(box_slots[i])].last_use = clock_;
  } else {
    GridTile tiles[kMaxRayTiles];
    uint32_t count = 1;
    tiles[0] = a;
    RayWalker scout = walker;
    GridCell c;
    while (scout.next(&c) && (!clip || in_bounds(c))) {
      const GridTile t = tile_of(c);
      if (same_tile(t, tiles[count - 1])) continue;
      if (count == kMaxRayTiles) return Status::kResourceExhausted;
      tiles[count++] = t;
    }
    if (count > slot_count()) return Status::kResourceExhausted;
    int32_t slots[kMaxRayTiles];
    SEQSLAM_TRY(make_resident(tiles, count, slots));
  }
  apply(walker, clip, hit, report);
  return Status::kOk;
}

Status OccupancyGrid::insert_ray(const SensorRay& ray, RayReport* report) {
  if (!ray.use) {
    if (report != nullptr) *report = RayReport{};
    return configured_ ? Status::kOk : Status::kFailedPrecondition;
  }
  return insert_ray(ray.x0, ray.y0, ray.x1, ray.y1, ray.hit, report);
}

namespace {

// round(a c / 2^30) for a Q31.32 value |a| < 2^40 (256 m: the callers check mount offsets,
// ranges are below 66 m) and a Q1.30 c. a is split into 32-bit halves so all products fit
// int64: a few multiply instructions instead of mul_shift_round's 128-bit arithmetic (~440
// instructions on RV32). Exact ties round up instead of away from zero; either way the error
// is at most half an LSB.
constexpr int64_t kMaxMountRaw = int64_t{1} << 40;
int64_t mul_q30(int64_t a, int32_t c) {
  const int64_t hi = a >> 32;                                         // |hi| < 2^8
  const int64_t lo = static_cast<int64_t>(static_cast<uint32_t>(a));  // a = hi 2^32 + lo
  return hi * c * 4 + ((lo * c + (int64_t{1} << 29)) >> 30);
}

// a + b, saturated to the int64 range (like Q31_32's operator+, without 128-bit arithmetic).
int64_t add_sat(int64_t a, int64_t b) {
  int64_t r = 0;
  if (__builtin_add_overflow(a, b, &r)) return b > 0 ? INT64_MAX : INT64_MIN;  // stdint.h limits
  return r;
}

// round(mm 2^32 / 1000) without a 64-bit division: 2^32 = 4294967 * 1000 + 296, and
// mm 296 mod 1000 is never 500, so the 32-bit rounding below has no ties.
int64_t mm_to_q32(uint16_t mm) {
  return static_cast<int64_t>(mm) * 4294967 +
         static_cast<int64_t>((static_cast<uint32_t>(mm) * 296u + 500u) / 1000u);
}

// A non-zero reading inside the sensor's range, and a mounting offset below 256 m.
bool reading_ok(const RangeSensor& sensor, uint16_t range_mm) {
  if (range_mm != 0 && (range_mm < sensor.min_mm || range_mm > sensor.max_mm)) return false;
  return inside(sensor.x.raw(), kMaxMountRaw) && inside(sensor.y.raw(), kMaxMountRaw);
}

// sensor_ray with the heading's sine and cosine given (insert_scan shares them).
Status sensor_ray_with(const Pose2& pose, SinCos h, const RangeSensor& sensor, uint16_t range_mm,
                       SensorRay* out) {
  if (!reading_ok(sensor, range_mm)) return Status::kOutOfRange;
  const uint16_t length_mm = range_mm != 0 ? range_mm : sensor.no_echo_mm;
  SensorRay ray;
  ray.hit = range_mm != 0;
  ray.use = length_mm != 0;
  // Mounting point: pose + R(heading) (x, y); Q31.32 x Q1.30 products rounded to Q31.32.
  const int32_t c = h.cos.raw();
  const int32_t s = h.sin.raw();
  const int64_t mx = sensor.x.raw();
  const int64_t my = sensor.y.raw();
  const int64_t x0 = add_sat(pose.x.raw(), mul_q30(mx, c) - mul_q30(my, s));
  const int64_t y0 = add_sat(pose.y.raw(), mul_q30(mx, s) + mul_q30(my, c));
  // Direction: heading + mounting angle (binary angles wrap exactly).
  const SinCos d = sincos(Angle{pose.heading.bam + sensor.angle.bam});
  const int64_t length = mm_to_q32(length_mm);
  ray.x0 = Q31_32::from_raw(x0);
  ray.y0 = Q31_32::from_raw(y0);
  ray.x1 = Q31_32::from_raw(add_sat(x0, mul_q30(length, d.cos.raw())));
  ray.y1 = Q31_32::from_raw(add_sat(y0, mul_q30(length, d.sin.raw())));
  *out = ray;
  return Status::kOk;
}

}  // namespace

Status sensor_ray(const Pose2& pose, const RangeSensor& sensor, uint16_t range_mm, SensorRay* out) {
  if (out == nullptr) return Status::kInvalidArgument;
  return sensor_ray_with(pose, sincos(pose.heading), sensor, range_mm, out);
}

Status OccupancyGrid::insert_reading(const Pose2& pose, const RangeSensor& sensor,
                                     uint16_t range_mm, RayReport* report) {
  if (!configured_) return Status::kFailedPrecondition;
  SensorRay ray;
  SEQSLAM_TRY(sensor_ray(pose, sensor, range_mm, &ray));
  return insert_ray(ray, report);
}

Status OccupancyGrid::insert_scan(const Pose2& pose, Span<const RangeSensor> sensors,
                                  Span<const uint16_t> readings_mm) {
  if (!configured_) return Status::kFailedPrecondition;
  if (sensors.size() != readings_mm.size()) return Status::kInvalidArgument;
  for (size_t i = 0; i < sensors.size(); ++i) {
    if (!reading_ok(sensors[i], readings_mm[i])) return Status::kOutOfRange;
  }
  const SinCos h = sincos(pose.heading);
  for (size_t i = 0; i < sensors.size(); ++i) {
    SensorRay ray;
    Status s = sensor_ray_with(pose, h, sensors[i], readings_mm[i], &ray);
    if (s == Status::kOk) s = insert_ray(ray);
    if (s != Status::kOk) return s;
  }
  return Status::kOk;
}

// ---- Queries ----

Status OccupancyGrid::log_odds(GridCell cell, int8_t* out) {
  if (out == nullptr) return Status::kInvalidArgument;
  if (!configured_) return Status::kFailedPrecondition;
  if (!in_bounds(cell)) return Status::kOutOfRange;
  const GridTile tile = tile_of(cell);
  int32_t slot = -1;
  SEQSLAM_TRY(make_resident(&tile, 1, &slot));
  *out = slot_cells(slot)[cell_offset(cell)];
  return Status::kOk;
}

Status OccupancyGrid::state(GridCell cell, CellState* out) {
  if (out == nullptr) return Status::kInvalidArgument;
  int8_t v = 0;
  SEQSLAM_TRY(log_odds(cell, &v));
  *out = classify(v);
  return Status::kOk;
}

}  // namespace seqslam
