// The occupancy grid: the integer ray walk against the exact segment (an exact integer
// segment/cell test on both platforms; on the host also the Amanatides-Woo traversal in double
// from tools/reference), log-odds saturation and classification, tile paging through a
// counting RAM store (more tiles than slots, content exact after eviction and reload, store
// failures leave the map unchanged), rays leaving the bounds, the sensor ray against double
// precision, a synthetic room scan, and paging figures along a corridor.
//
// Agreement rule of the walk (RayWalker in occupancy_grid.h) with the exact segment:
//  - the first cell is the start point's cell and the last the end point's (floor);
//  - every cell of the walk meets the closed segment (the exact traversal, touching included):
//    a subset of the exact traversal, in the same order;
//  - consecutive cells are distinct 8-neighbours; along the major axis every step moves one
//    cell, except that the last step may move along the minor axis only.
#include "seqslam/occupancy_grid.h"

#include "ram_tile_store.h"
#include "ref_math.h"
#include "synthetic.h"
#include "test.h"
#include "test_log.h"

#if defined(SEQSLAM_TEST_GTEST) && __has_include("reference.h")
// Host builds that link seqslam_reference also check against tools/reference.
#include <vector>

#include "reference.h"
#define GRID_TEST_HAS_REFERENCE 1
#endif

namespace seqslam {
namespace {

constexpr int64_t kS = kGridSubcell;  // one cell in sub-cell units

int64_t max64(int64_t a, int64_t b) {
  return a > b ? a : b;
}
int64_t min64(int64_t a, int64_t b) {
  return a < b ? a : b;
}
int64_t abs64(int64_t a) {
  return a < 0 ? -a : a;
}
int64_t floor_cell(int64_t v) {
  return v >= 0 ? v / kS : -((-v + kS - 1) / kS);
}

// Exact test: does the closed segment (x0, y0)-(x1, y1) meet the closed cell? Separating axes
// of a segment and a box: x, y, and the segment's normal (all four corners strictly on one
// side). Products stay far below 2^63 for rays of up to kMaxRayCells cells.
bool segment_meets_cell(int64_t x0, int64_t y0, int64_t x1, int64_t y1, GridCell c) {
  const int64_t cx0 = static_cast<int64_t>(c.col) * kS;
  const int64_t cy0 = static_cast<int64_t>(c.row) * kS;
  const int64_t cx1 = cx0 + kS;
  const int64_t cy1 = cy0 + kS;
  if (max64(x0, x1) < cx0 || min64(x0, x1) > cx1) return false;
  if (max64(y0, y1) < cy0 || min64(y0, y1) > cy1) return false;
  const int64_t dx = x1 - x0;
  const int64_t dy = y1 - y0;
  int positive = 0;
  int negative = 0;
  const int64_t xs[4] = {cx0, cx1, cx0, cx1};
  const int64_t ys[4] = {cy0, cy0, cy1, cy1};
  for (int i = 0; i < 4; ++i) {
    const int64_t cross = (xs[i] - x0) * dy - (ys[i] - y0) * dx;
    if (cross > 0) ++positive;
    if (cross < 0) ++negative;
  }
  return positive != 4 && negative != 4;
}

constexpr uint32_t kMaxWalk = 2 * kMaxRayCells + 4;
GridCell g_walk[kMaxWalk];

// Runs the walk into g_walk; returns the number of cells (0 if reset failed).
uint32_t walk(int64_t x0, int64_t y0, int64_t x1, int64_t y1, bool* end_flag_ok) {
  RayWalker w;
  if (w.reset(x0, y0, x1, y1) != Status::kOk) return 0;
  uint32_t n = 0;
  GridCell c;
  bool flags_ok = true;
  while (n < kMaxWalk && w.next(&c)) {
    g_walk[n++] = c;
    if (w.at_end() != (c == w.end_cell())) flags_ok = false;
  }
  if (!w.at_end()) flags_ok = false;
  GridCell extra;
  if (w.next(&extra)) flags_ok = false;  // nothing after the end
  *end_flag_ok = flags_ok;
  return n;
}

// Checks the agreement rule for one ray; returns false (with a gtest/minitest failure) on the
// first violation.
bool check_walk(int64_t x0, int64_t y0, int64_t x1, int64_t y1) {
  bool flags_ok = false;
  const uint32_t n = walk(x0, y0, x1, y1, &flags_ok);
  EXPECT_GT(n, 0u) << x0 << " " << y0 << " " << x1 << " " << y1;
  if (n == 0) return false;
  EXPECT_TRUE(flags_ok) << x0 << " " << y0 << " " << x1 << " " << y1;
  const GridCell first{static_cast<int32_t>(floor_cell(x0)), static_cast<int32_t>(floor_cell(y0))};
  const GridCell last{static_cast<int32_t>(floor_cell(x1)), static_cast<int32_t>(floor_cell(y1))};
  bool ok = flags_ok && g_walk[0] == first && g_walk[n - 1] == last;
  const bool x_major = abs64(x1 - x0) >= abs64(y1 - y0);
  for (uint32_t i = 0; i < n && ok; ++i) {
    if (!segment_meets_cell(x0, y0, x1, y1, g_walk[i])) ok = false;
    if (i == 0) continue;
    const int32_t dc = g_walk[i].col - g_walk[i - 1].col;
    const int32_t dr = g_walk[i].row - g_walk[i - 1].row;
    const int32_t major = x_major ? dc : dr;
    const int32_t minor = x_major ? dr : dc;
    if (minor < -1 || minor > 1) ok = false;
    if (i + 1 < n) {
      if (major != 1 && major != -1) ok = false;
    } else if (major < -1 || major > 1 || (major == 0 && minor == 0)) {
      ok = false;
    }
  }
  EXPECT_TRUE(ok) << "ray " << x0 << "," << y0 << " -> " << x1 << "," << y1 << " (sub-cells), " << n
                  << " cells";
  return ok;
}

// Random rays of seven kinds, in sub-cell units.
struct RandomRay {
  int64_t x0, y0, x1, y1;
};
RandomRay random_ray(test::Rng& rng, uint32_t i) {
  const auto coord = [&](int32_t cells) {
    return static_cast<int64_t>(rng.range(-cells, cells)) * kS +
           static_cast<int64_t>(rng.below(static_cast<uint32_t>(kS)));
  };
  RandomRay r{coord(40), coord(40), 0, 0};
  const int64_t len = static_cast<int64_t>(rng.range(-40, 40)) * kS + coord(1);
  switch (i % 8) {
    case 0:  // anywhere
    default:
      r.x1 = r.x0 + coord(40);
      r.y1 = r.y0 + coord(40);
      break;
    case 1:  // horizontal
      r.x1 = r.x0 + len;
      r.y1 = r.y0;
      break;
    case 2:  // vertical
      r.x1 = r.x0;
      r.y1 = r.y0 + len;
      break;
    case 3:  // exact diagonal, any of the four directions
      r.x1 = r.x0 + len;
      r.y1 = r.y0 + ((rng.below(2) != 0) ? len : -len);
      break;
    case 4:  // zero length
      r.x1 = r.x0;
      r.y1 = r.y0;
      break;
    case 5: {  // end points on the quarter-cell lattice: rays through cell corners
      const auto lattice = [&](int32_t cells) {
        return static_cast<int64_t>(rng.range(-4 * cells, 4 * cells)) * (kS / 4);
      };
      r = RandomRay{lattice(20), lattice(20), lattice(20), lattice(20)};
      break;
    }
    case 6:  // long
      r.x1 = r.x0 + static_cast<int64_t>(rng.range(-1000, 1000)) * kS + coord(1);
      r.y1 = r.y0 + static_cast<int64_t>(rng.range(-1000, 1000)) * kS + coord(1);
      break;
    case 7:  // within a cell or two
      r.x1 = r.x0 + coord(1);
      r.y1 = r.y0 + coord(1);
      break;
  }
  return r;
}

TEST(OccupancyGridWalk, RandomRaysFollowTheExactSegment) {
  test::Rng rng(71);
  uint32_t failures = 0;
  for (uint32_t i = 0; i < 4000 && failures < 5; ++i) {
    const RandomRay r = random_ray(rng, i);
    if (!check_walk(r.x0, r.y0, r.x1, r.y1)) ++failures;
    // The same ray backwards follows the same rule.
    if (!check_walk(r.x1, r.y1, r.x0, r.y0)) ++failures;
  }
  EXPECT_EQ(failures, 0u);
}

TEST(OccupancyGridWalk, AxisAlignedDiagonalAndZeroLengthCells) {
  bool flags = false;
  // Horizontal, from the middle of cell (2, 3) to the middle of (6, 3): 2..6.
  ASSERT_EQ(walk(2 * kS + kS / 2, 3 * kS + kS / 2, 6 * kS + kS / 2, 3 * kS + kS / 2, &flags), 5u);
  for (int32_t i = 0; i < 5; ++i)
    EXPECT_EQ(g_walk[i], (GridCell{2 + i, 3}));
  // Vertical downwards across zero: rows 1, 0, -1, -2.
  ASSERT_EQ(walk(kS / 2, kS + kS / 2, kS / 2, -2 * kS + kS / 2, &flags), 4u);
  for (int32_t i = 0; i < 4; ++i)
    EXPECT_EQ(g_walk[i], (GridCell{0, 1 - i}));
  // An exact diagonal through cell corners (-x, +y): the diagonal cells only.
  ASSERT_EQ(walk(0, 0, -3 * kS, 3 * kS, &flags), 4u);
  EXPECT_EQ(g_walk[0], (GridCell{0, 0}));
  EXPECT_EQ(g_walk[1], (GridCell{-3 + 2, 1}));
  EXPECT_EQ(g_walk[3], (GridCell{-3, 3}));
  // Zero length, and both points in one cell: one cell, which is the end.
  ASSERT_EQ(walk(-5, -5, -5, -5, &flags), 1u);
  EXPECT_EQ(g_walk[0], (GridCell{-1, -1}));
  EXPECT_TRUE(flags);
  ASSERT_EQ(walk(10, 10, kS - 1, kS - 1, &flags), 1u);
  EXPECT_TRUE(flags);
  // A short ray that only crosses into the neighbour: two cells.
  ASSERT_EQ(walk(kS - 10, 5, kS + 10, 6, &flags), 2u);
  EXPECT_EQ(g_walk[1], (GridCell{1, 0}));
  // The minor-only last step: from (0.05, 0.95) to (0.95, 1.85) cells.
  ASSERT_EQ(walk(kS / 20, kS * 19 / 20, kS * 19 / 20, kS * 37 / 20, &flags), 2u);
  EXPECT_EQ(g_walk[0], (GridCell{0, 0}));
  EXPECT_EQ(g_walk[1], (GridCell{0, 1}));
}

TEST(OccupancyGridWalk, RejectsRaysTooLongOrTooFarOut) {
  RayWalker w;
  const int64_t max = static_cast<int64_t>(kMaxRayCells) * kS;
  EXPECT_EQ(w.reset(0, 0, max, -max), Status::kOk);
  // The longest rays keep the walk's 32-bit remainders in range.
  EXPECT_TRUE(check_walk(0, 0, max, -max));
  EXPECT_TRUE(check_walk(kS - 1, 3, kS - 1 - max, max - 5));
  EXPECT_TRUE(check_walk(17, -200, max / 3 + 11, max - 201));
  EXPECT_TRUE(check_walk(-kS * 1000 + 1, kS * 500 - 1, -kS * 1000 + 1 - max, kS * 500 - 1 + 7));
  EXPECT_EQ(w.reset(0, 0, max + 1, 0), Status::kOutOfRange);
  EXPECT_EQ(w.reset(0, 0, 0, -max - 1), Status::kOutOfRange);
  const int64_t far = int64_t{1} << (31 + kGridSubcellBits);  // cell index beyond int32
  EXPECT_EQ(w.reset(far, 0, far, 0), Status::kOutOfRange);
  EXPECT_EQ(w.reset(-9223372036854775807LL - 1, 0, 0, 0), Status::kOutOfRange);
  GridCell c;
  RayWalker fresh;
  EXPECT_FALSE(fresh.next(&c));  // never started
}

#if defined(GRID_TEST_HAS_REFERENCE)
// The walk against the double-precision Amanatides-Woo supercover of the same segment: the
// walk's cells appear in the reference list, in the same order, and the end cells agree.
TEST(OccupancyGridWalk, SubsequenceOfTheAmanatidesWooReference) {
  test::Rng rng(72);
  uint32_t failures = 0;
  uint64_t walk_cells = 0;
  uint64_t reference_cells = 0;
  for (uint32_t i = 0; i < 20000 && failures < 5; ++i) {
    const RandomRay r = random_ray(rng, i);
    bool flags = false;
    const uint32_t n = walk(r.x0, r.y0, r.x1, r.y1, &flags);
    const double s = static_cast<double>(kS);
    const std::vector<reference::GridCellRef> ref =
        reference::grid_supercover(static_cast<double>(r.x0) / s, static_cast<double>(r.y0) / s,
                                   static_cast<double>(r.x1) / s, static_cast<double>(r.y1) / s);
    walk_cells += n;
    reference_cells += ref.size();
    bool ok = n > 0 && ref.front().col == g_walk[0].col && ref.front().row == g_walk[0].row &&
              ref.back().col == g_walk[n - 1].col && ref.back().row == g_walk[n - 1].row;
    size_t j = 0;
    for (uint32_t k = 0; k < n && ok; ++k) {
      while (j < ref.size() && !(ref[j].col == g_walk[k].col && ref[j].row == g_walk[k].row))
        ++j;
      if (j == ref.size()) ok = false;
      ++j;
    }
    if (!ok) {
      ++failures;
      ADD_FAILURE() << "ray " << r.x0 << "," << r.y0 << " -> " << r.x1 << "," << r.y1
                    << ": walk of " << n << " cells is not a subsequence of the " << ref.size()
                    << " reference cells";
    }
  }
  EXPECT_EQ(failures, 0u);
  // The walk is the thin (8-connected) line, the reference the thick (4-connected) one.
  test::log_figure("walk cells per reference cell",
                   static_cast<double>(walk_cells) / static_cast<double>(reference_cells));
}
#endif

// ---- The grid ----

using RamTileStore = test::RamTileStore<48>;

RamTileStore g_store;
RamTileStore g_store_b;
OccupancyGridStorage<3> g_ram3;
OccupancyGridStorage<2> g_ram2;
OccupancyGridStorage<32> g_ram32;
int8_t g_tile_a[kGridTileCells];
int8_t g_tile_b[kGridTileCells];

Q31_32 metres_mm(int64_t mm) {
  return Q31_32::from_ratio(mm, 1000);
}

GridConfig config_cells(uint16_t width, uint16_t height) {
  GridConfig c;
  c.width = width;
  c.height = height;
  return c;
}

int8_t cell_value(OccupancyGrid& grid, int32_t col, int32_t row) {
  int8_t v = 99;
  EXPECT_EQ(grid.log_odds(GridCell{col, row}, &v), Status::kOk);
  return v;
}

TEST(OccupancyGrid, ConfigurationIsChecked) {
  g_store.reset();
  OccupancyGrid grid;
  GridIssue issue = GridIssue::kNone;
  GridConfig c = config_cells(100, 50);
  EXPECT_EQ(check_grid_config(c, &issue), Status::kOk);
  EXPECT_EQ(issue, GridIssue::kNone);
  GridConfig bad[7] = {c, c, c, c, c, c, c};
  bad[0].cell_mm = 9;
  bad[1].width = 0;
  bad[2].height = 40000;
  bad[3].limit = 0;
  bad[4].hit = 0;
  bad[5].miss = -65;  // beyond -limit
  bad[6].free_threshold = 0;
  const GridIssue expected[7] = {GridIssue::kCellSizeOutOfRange,  GridIssue::kSizeOutOfRange,
                                 GridIssue::kSizeOutOfRange,      GridIssue::kLimitOutOfRange,
                                 GridIssue::kIncrementOutOfRange, GridIssue::kIncrementOutOfRange,
                                 GridIssue::kThresholdOutOfRange};
  for (uint32_t i = 0; i < 7; ++i) {
    EXPECT_EQ(grid.configure(bad[i], g_ram3.buffers(), g_store, &issue), Status::kOutOfRange) << i;
    EXPECT_EQ(issue, expected[i]) << i;
    EXPECT_FALSE(grid.configured());
  }
  // A sentence on the PC, a code on the board (seqslam/messages.h).
  EXPECT_EQ(grid_issue_text(GridIssue::kCellSizeOutOfRange)[0], SEQSLAM_MESSAGE_TEXTS ? 'g' : 'G');
  OccupancyGridBuffers none{};
  EXPECT_EQ(grid.configure(c, none, g_store, &issue), Status::kResourceExhausted);
  EXPECT_EQ(issue, GridIssue::kNoSlots);
  OccupancyGridBuffers short_cells = g_ram3.buffers();
  short_cells.cells = Span<int8_t>(g_ram3.cells, 2 * kGridTileCells);
  EXPECT_EQ(grid.configure(c, short_cells, g_store, &issue), Status::kResourceExhausted);
  EXPECT_FALSE(grid.configured());
  // Not configured: every call says so.
  EXPECT_EQ(grid.insert_ray(metres_mm(0), metres_mm(0), metres_mm(100), metres_mm(0), true),
            Status::kFailedPrecondition);
  int8_t v = 0;
  EXPECT_EQ(grid.log_odds(GridCell{0, 0}, &v), Status::kFailedPrecondition);
  EXPECT_EQ(grid.flush(), Status::kFailedPrecondition);
  EXPECT_EQ(grid.clear(), Status::kFailedPrecondition);
  GridCell cell;
  EXPECT_EQ(grid.cell_at(metres_mm(0), metres_mm(0), &cell), Status::kFailedPrecondition);
  EXPECT_EQ(grid.copy_tile(GridTile{0, 0}, Span<int8_t>(g_tile_a)), Status::kFailedPrecondition);
  const uint16_t none_read[1] = {0};
  EXPECT_EQ(grid.insert_scan(Pose2{}, Span<const RangeSensor>(kMyonInfrared, 1),
                             Span<const uint16_t>(none_read)),
            Status::kFailedPrecondition);
  ASSERT_EQ(grid.configure(c, g_ram3.buffers(), g_store, &issue), Status::kOk);
  EXPECT_EQ(grid.tiles_x(), 4);  // 100 cells = 3 whole tiles + 4 cells
  EXPECT_EQ(grid.tiles_y(), 2);
  EXPECT_EQ(grid.slot_count(), 3u);
}

TEST(OccupancyGrid, CellOfAPointIsHalfOpenAndBounded) {
  g_store.reset();
  OccupancyGrid grid;
  GridConfig c = config_cells(40, 20);
  c.origin_x = metres_mm(-1000);  // cells cover x -1.0 .. 1.0 m, y 0.5 .. 1.5 m
  c.origin_y = metres_mm(500);
  ASSERT_EQ(grid.configure(c, g_ram3.buffers(), g_store), Status::kOk);
  GridCell cell;
  ASSERT_EQ(grid.cell_at(metres_mm(-1000), metres_mm(500), &cell), Status::kOk);
  EXPECT_EQ(cell, (GridCell{0, 0}));
  ASSERT_EQ(grid.cell_at(metres_mm(-950), metres_mm(549), &cell), Status::kOk);
  EXPECT_EQ(cell, (GridCell{1, 0}));  // a boundary belongs to the cell above it
  ASSERT_EQ(grid.cell_at(metres_mm(0), metres_mm(1000), &cell), Status::kOk);
  EXPECT_EQ(cell, (GridCell{20, 10}));
  // One Q31.32 step below a boundary is still the cell below.
  ASSERT_EQ(grid.cell_at(metres_mm(0) - Q31_32::from_raw(1), metres_mm(1000), &cell), Status::kOk);
  EXPECT_EQ(cell, (GridCell{19, 10}));
  ASSERT_EQ(grid.cell_at(metres_mm(999), metres_mm(1499), &cell), Status::kOk);
  EXPECT_EQ(cell, (GridCell{39, 19}));
  EXPECT_EQ(grid.cell_at(metres_mm(1000), metres_mm(1000), &cell), Status::kOutOfRange);
  EXPECT_EQ(grid.cell_at(metres_mm(-1001), metres_mm(1000), &cell), Status::kOutOfRange);
  EXPECT_EQ(grid.cell_at(metres_mm(0), metres_mm(499), &cell), Status::kOutOfRange);
  EXPECT_EQ(grid.cell_at(Q31_32::max(), Q31_32::min(), &cell), Status::kOutOfRange);
  EXPECT_EQ(grid.cell_at(metres_mm(0), metres_mm(1000), nullptr), Status::kInvalidArgument);
}

TEST(OccupancyGrid, RayMissesBeforeTheEndAndHitsTheEnd) {
  g_store.reset();
  OccupancyGrid grid;
  const GridConfig c = config_cells(64, 64);
  ASSERT_EQ(grid.configure(c, g_ram3.buffers(), g_store), Status::kOk);
  // From the middle of cell (0, 1) to the middle of cell (10, 1).
  RayReport report;
  ASSERT_EQ(
      grid.insert_ray(metres_mm(25), metres_mm(75), metres_mm(525), metres_mm(75), true, &report),
      Status::kOk);
  EXPECT_EQ(report.cells, 11u);
  EXPECT_FALSE(report.clipped);
  for (int32_t col = 0; col < 10; ++col)
    EXPECT_EQ(cell_value(grid, col, 1), c.miss) << col;
  EXPECT_EQ(cell_value(grid, 10, 1), c.hit);
  EXPECT_EQ(cell_value(grid, 11, 1), 0);
  EXPECT_EQ(cell_value(grid, 5, 0), 0);
  EXPECT_EQ(cell_value(grid, 5, 2), 0);
  // A free ray: the end cell gets a miss too.
  ASSERT_EQ(grid.insert_ray(metres_mm(25), metres_mm(175), metres_mm(525), metres_mm(175), false,
                            &report),
            Status::kOk);
  EXPECT_EQ(cell_value(grid, 10, 3), c.miss);
  // A zero-length hit: just that cell.
  ASSERT_EQ(grid.insert_ray(metres_mm(1010), metres_mm(1010), metres_mm(1010), metres_mm(1010),
                            true, &report),
            Status::kOk);
  EXPECT_EQ(report.cells, 1u);
  EXPECT_EQ(cell_value(grid, 20, 20), c.hit);
  EXPECT_EQ(grid.stats().rays, 3u);
  EXPECT_EQ(grid.stats().cells, 23u);
  // Across a tile boundary (col 31 -> 32) and diagonally into the next tile row.
  ASSERT_EQ(grid.insert_ray(metres_mm(1525), metres_mm(1525), metres_mm(1725), metres_mm(1725),
                            true, &report),
            Status::kOk);
  EXPECT_EQ(report.cells, 5u);  // (30,30) .. (34,34)
  EXPECT_EQ(cell_value(grid, 31, 31), c.miss);
  EXPECT_EQ(cell_value(grid, 32, 32), c.miss);
  EXPECT_EQ(cell_value(grid, 34, 34), c.hit);
}

TEST(OccupancyGrid, LogOddsSaturateAndClassify) {
  g_store.reset();
  OccupancyGrid grid;
  GridConfig c = config_cells(32, 32);
  c.hit = 20;
  c.miss = -7;
  c.limit = 50;
  c.occupied_threshold = 12;
  c.free_threshold = -20;
  ASSERT_EQ(grid.configure(c, g_ram3.buffers(), g_store), Status::kOk);
  const Q31_32 x = metres_mm(125);  // cell (2, 2)
  const Q31_32 y = metres_mm(125);
  CellState st = CellState::kFree;
  ASSERT_EQ(grid.state(GridCell{2, 2}, &st), Status::kOk);
  EXPECT_EQ(st, CellState::kUnknown);
  // Hits: 20, 40, 50 (saturated), 50 ...
  const int8_t after_hits[4] = {20, 40, 50, 50};
  for (int8_t expected : after_hits) {
    ASSERT_EQ(grid.insert_ray(x, y, x, y, true), Status::kOk);
    EXPECT_EQ(cell_value(grid, 2, 2), expected);
  }
  ASSERT_EQ(grid.state(GridCell{2, 2}, &st), Status::kOk);
  EXPECT_EQ(st, CellState::kOccupied);
  // Misses from the saturated value: 43, 36, ... down to -50; occupied while >= 12, unknown
  // in between, free from <= -20.
  int32_t v = 50;
  for (int i = 0; i < 20; ++i) {
    ASSERT_EQ(grid.insert_ray(x, y, x, y, false), Status::kOk);
    v = v - 7 < -50 ? -50 : v - 7;
    EXPECT_EQ(cell_value(grid, 2, 2), v);
    ASSERT_EQ(grid.state(GridCell{2, 2}, &st), Status::kOk);
    const CellState want =
        v >= 12 ? CellState::kOccupied : (v <= -20 ? CellState::kFree : CellState::kUnknown);
    EXPECT_EQ(st, want) << v;
  }
  EXPECT_EQ(v, -50);
  // classify() on raw values: the thresholds are inclusive.
  EXPECT_EQ(grid.classify(12), CellState::kOccupied);
  EXPECT_EQ(grid.classify(11), CellState::kUnknown);
  EXPECT_EQ(grid.classify(-19), CellState::kUnknown);
  EXPECT_EQ(grid.classify(-20), CellState::kFree);
  EXPECT_EQ(grid.classify(0), CellState::kUnknown);
  // Stored values beyond the limit (a store written under another configuration) are pulled
  // back inside by the next update.
  GridConfig wide = c;
  wide.limit = 127;
  wide.hit = 100;
  ASSERT_EQ(grid.configure(wide, g_ram3.buffers(), g_store), Status::kOk);
  ASSERT_EQ(grid.insert_ray(x, y, x, y, true), Status::kOk);
  ASSERT_EQ(grid.insert_ray(x, y, x, y, true), Status::kOk);
  EXPECT_EQ(cell_value(grid, 2, 2), 127);
  ASSERT_EQ(grid.flush(), Status::kOk);
  ASSERT_EQ(grid.configure(c, g_ram3.buffers(), g_store), Status::kOk);
  EXPECT_EQ(cell_value(grid, 2, 2), 127);
  ASSERT_EQ(grid.insert_ray(x, y, x, y, false), Status::kOk);
  EXPECT_EQ(cell_value(grid, 2, 2), 50);
}

// Random rays of up to 1.5 m in a world of 8 x 4 tiles (256 x 128 cells at 5 cm).
struct MetreRay {
  Q31_32 x0, y0, x1, y1;
  bool hit;
};
MetreRay random_metre_ray(test::Rng& rng) {
  MetreRay r;
  const int32_t x0 = rng.range(0, 12799);  // mm
  const int32_t y0 = rng.range(0, 6399);
  r.x0 = metres_mm(x0);
  r.y0 = metres_mm(y0);
  r.x1 = metres_mm(x0 + rng.range(-1060, 1060));  // at most 1.5 m along the diagonal
  r.y1 = metres_mm(y0 + rng.range(-1060, 1060));
  r.hit = rng.below(3) != 0;
  return r;
}

// Compares every tile of two grids exactly.
bool same_map(const OccupancyGrid& a, const OccupancyGrid& b) {
  for (uint16_t ty = 0; ty < a.tiles_y(); ++ty) {
    for (uint16_t tx = 0; tx < a.tiles_x(); ++tx) {
      if (a.copy_tile(GridTile{tx, ty}, Span<int8_t>(g_tile_a)) != Status::kOk) return false;
      if (b.copy_tile(GridTile{tx, ty}, Span<int8_t>(g_tile_b)) != Status::kOk) return false;
      for (uint32_t i = 0; i < kGridTileCells; ++i) {
        if (g_tile_a[i] != g_tile_b[i]) return false;
      }
    }
  }
  return true;
}

TEST(OccupancyGrid, PagingKeepsContentExactWithMoreTilesThanSlots) {
  g_store.reset();
  g_store_b.reset();
  const GridConfig c = config_cells(256, 128);  // 8 x 4 = 32 tiles
  OccupancyGrid paged;                          // 3 slots
  OccupancyGrid whole;                          // 32 slots: never evicts
  ASSERT_EQ(paged.configure(c, g_ram3.buffers(), g_store), Status::kOk);
  ASSERT_EQ(whole.configure(c, g_ram32.buffers(), g_store_b), Status::kOk);
  test::Rng rng(73);
  uint32_t clipped = 0;
  for (uint32_t i = 0; i < 3000; ++i) {
    const MetreRay r = random_metre_ray(rng);
    RayReport ra;
    RayReport rb;
    ASSERT_EQ(paged.insert_ray(r.x0, r.y0, r.x1, r.y1, r.hit, &ra), Status::kOk) << i;
    ASSERT_EQ(whole.insert_ray(r.x0, r.y0, r.x1, r.y1, r.hit, &rb), Status::kOk) << i;
    EXPECT_EQ(ra.cells, rb.cells);
    EXPECT_EQ(ra.clipped, rb.clipped);
    if (ra.clipped) ++clipped;
  }
  EXPECT_GT(clipped, 0u);
  // The paged grid evicted and reloaded tiles many times; its map is the same, exactly.
  EXPECT_GT(paged.stats().tile_loads, 1000u);
  EXPECT_GT(paged.stats().tile_saves, 1000u);
  EXPECT_LE(whole.stats().tile_loads, 32u);
  EXPECT_EQ(whole.stats().tile_saves, 0u);
  EXPECT_EQ(g_store.loads, paged.stats().tile_loads);
  EXPECT_EQ(g_store.saves, paged.stats().tile_saves);
  EXPECT_TRUE(same_map(paged, whole));
  // After flush() the store alone holds the map: a fresh grid over it reads the same.
  ASSERT_EQ(paged.flush(), Status::kOk);
  EXPECT_EQ(paged.flush(), Status::kOk);  // nothing dirty any more
  OccupancyGrid reread;
  ASSERT_EQ(reread.configure(c, g_ram2.buffers(), g_store), Status::kOk);
  EXPECT_TRUE(same_map(reread, whole));
  int8_t v = 0;
  for (int32_t i = 0; i < 200; ++i) {
    const GridCell cell{(i * 37) % 256, (i * 53) % 128};
    ASSERT_EQ(reread.log_odds(cell, &v), Status::kOk);
    int8_t w = 0;
    ASSERT_EQ(whole.log_odds(cell, &w), Status::kOk);
    EXPECT_EQ(v, w);
  }
  test::log_figure("paging test: tile loads per ray (3 slots, random 1.5 m rays)",
                   static_cast<double>(paged.stats().tile_loads) / 3000.0);
}

// The grid's insert loop (which inlines the walk) updates exactly the cells RayWalker lists,
// up to the bounds: a plain model array updated from RayWalker with the same saturation rule
// must equal the grid after thousands of random rays (many clipped at the bounds).
int8_t g_model[128][256];

TEST(OccupancyGrid, UpdatesExactlyTheWalkCells) {
  g_store.reset();
  const GridConfig c = config_cells(256, 128);
  OccupancyGrid grid;
  ASSERT_EQ(grid.configure(c, g_ram32.buffers(), g_store), Status::kOk);
  for (auto& row : g_model) {
    for (int8_t& v : row)
      v = 0;
  }
  test::Rng rng(76);
  uint32_t clipped = 0;
  for (uint32_t i = 0; i < 4000; ++i) {
    const MetreRay r = random_metre_ray(rng);
    RayReport report;
    ASSERT_EQ(grid.insert_ray(r.x0, r.y0, r.x1, r.y1, r.hit, &report), Status::kOk);
    // The model: metres to 1/256 cells exactly as the grid does (5 cm: x 20 cells per metre).
    RayWalker w;
    ASSERT_EQ(w.reset((r.x0.raw() * 20) >> 24, (r.y0.raw() * 20) >> 24, (r.x1.raw() * 20) >> 24,
                      (r.y1.raw() * 20) >> 24),
              Status::kOk);
    GridCell cell;
    uint32_t n = 0;
    bool out = false;
    while (w.next(&cell)) {
      if (cell.col < 0 || cell.row < 0 || cell.col >= 256 || cell.row >= 128) {
        out = true;
        break;
      }
      int32_t v = g_model[cell.row][cell.col] + ((r.hit && w.at_end()) ? c.hit : c.miss);
      v = v > c.limit ? c.limit : (v < -c.limit ? -c.limit : v);
      g_model[cell.row][cell.col] = static_cast<int8_t>(v);
      ++n;
    }
    EXPECT_EQ(report.cells, n) << i;
    EXPECT_EQ(report.clipped, out) << i;
    if (out) ++clipped;
  }
  EXPECT_GT(clipped, 50u);
  uint32_t differ = 0;
  for (uint16_t ty = 0; ty < grid.tiles_y(); ++ty) {
    for (uint16_t tx = 0; tx < grid.tiles_x(); ++tx) {
      ASSERT_EQ(grid.copy_tile(GridTile{tx, ty}, Span<int8_t>(g_tile_a)), Status::kOk);
      for (uint32_t k = 0; k < kGridTileCells; ++k) {
        const uint32_t row = ty * kGridTileSide + k / kGridTileSide;
        const uint32_t col = tx * kGridTileSide + k % kGridTileSide;
        if (g_tile_a[k] != g_model[row][col]) ++differ;
      }
    }
  }
  EXPECT_EQ(differ, 0u);
}

TEST(OccupancyGrid, TooFewSlotsForARayIsRejectedUnchanged) {
  g_store.reset();
  g_store_b.reset();
  OccupancyGrid grid;
  OccupancyGrid untouched;
  const GridConfig c = config_cells(128, 128);
  ASSERT_EQ(grid.configure(c, g_ram2.buffers(), g_store), Status::kOk);
  ASSERT_EQ(untouched.configure(c, g_ram32.buffers(), g_store_b), Status::kOk);
  // Cells (30, 20) -> (34, 35): tiles (0,0), (1,0), (1,1).
  const Q31_32 x0 = metres_mm(1525);
  const Q31_32 y0 = metres_mm(1025);
  const Q31_32 x1 = metres_mm(1725);
  const Q31_32 y1 = metres_mm(1775);
  ASSERT_EQ(grid.insert_ray(x0, y0, x1, y1, true), Status::kResourceExhausted);
  EXPECT_EQ(grid.stats().rays, 0u);
  EXPECT_TRUE(same_map(grid, untouched));
  OccupancyGrid three;
  ASSERT_EQ(three.configure(c, g_ram3.buffers(), g_store), Status::kOk);
  RayReport report;
  ASSERT_EQ(three.insert_ray(x0, y0, x1, y1, true, &report), Status::kOk);
  EXPECT_EQ(report.cells, 16u);
}

TEST(OccupancyGrid, StoreFailuresLeaveTheMapUnchanged) {
  g_store.reset();
  g_store_b.reset();
  const GridConfig c = config_cells(256, 128);
  OccupancyGrid grid;
  OccupancyGrid model;
  ASSERT_EQ(grid.configure(c, g_ram3.buffers(), g_store), Status::kOk);
  ASSERT_EQ(model.configure(c, g_ram32.buffers(), g_store_b), Status::kOk);
  test::Rng rng(74);
  for (uint32_t i = 0; i < 200; ++i) {
    const MetreRay r = random_metre_ray(rng);
    ASSERT_EQ(grid.insert_ray(r.x0, r.y0, r.x1, r.y1, r.hit), Status::kOk);
    ASSERT_EQ(model.insert_ray(r.x0, r.y0, r.x1, r.y1, r.hit), Status::kOk);
  }
  ASSERT_TRUE(same_map(grid, model));
  uint32_t load_failures = 0;
  uint32_t save_failures = 0;
  for (uint32_t i = 0; i < 300; ++i) {
    const MetreRay r = random_metre_ray(rng);
    // Every third ray: the next load fails; every third: the next save.
    if (i % 3 == 0) g_store.fail_load_at = g_store.loads;
    if (i % 3 == 1) g_store.fail_save_at = g_store.saves;
    const Status s = grid.insert_ray(r.x0, r.y0, r.x1, r.y1, r.hit);
    g_store.fail_load_at = 0xFFFFFFFFu;
    g_store.fail_save_at = 0xFFFFFFFFu;
    if (s == Status::kUnavailable) ++load_failures;
    if (s == Status::kDataLoss) ++save_failures;
    if (s != Status::kOk) {
      EXPECT_TRUE(s == Status::kUnavailable || s == Status::kDataLoss) << status_name(s);
      EXPECT_TRUE(same_map(grid, model)) << i;  // nothing of the failed ray
      // Retried without the failure, the ray goes in.
      ASSERT_EQ(grid.insert_ray(r.x0, r.y0, r.x1, r.y1, r.hit), Status::kOk);
    }
    ASSERT_EQ(model.insert_ray(r.x0, r.y0, r.x1, r.y1, r.hit), Status::kOk);
  }
  EXPECT_GT(load_failures, 20u);
  EXPECT_GT(save_failures, 20u);
  EXPECT_TRUE(same_map(grid, model));
  // flush() stops at a failing save and keeps the rest dirty; the next flush completes.
  g_store.fail_save_at = g_store.saves;
  const Status f = grid.flush();
  g_store.fail_save_at = 0xFFFFFFFFu;
  if (f != Status::kOk) {
    EXPECT_EQ(f, Status::kDataLoss);
    ASSERT_EQ(grid.flush(), Status::kOk);
  }
  OccupancyGrid reread;
  ASSERT_EQ(reread.configure(c, g_ram2.buffers(), g_store), Status::kOk);
  EXPECT_TRUE(same_map(reread, model));
}

TEST(OccupancyGrid, RaysLeavingTheBoundsAreClippedNeverWrittenOutside) {
  g_store.reset();
  OccupancyGrid grid;
  GridConfig c = config_cells(40, 36);  // tiles: 2 x 2, the last ones partly outside
  c.origin_x = metres_mm(-500);
  c.origin_y = metres_mm(-500);
  ASSERT_EQ(grid.configure(c, g_ram3.buffers(), g_store), Status::kOk);
  // From cell (38, 5) eastwards out of the grid: cells 38, 39 get misses, nothing else.
  RayReport report;
  ASSERT_EQ(grid.insert_ray(metres_mm(1425), metres_mm(-225), metres_mm(2425), metres_mm(-225),
                            true, &report),
            Status::kOk);
  EXPECT_TRUE(report.clipped);
  EXPECT_EQ(report.cells, 2u);
  EXPECT_EQ(cell_value(grid, 38, 5), c.miss);
  EXPECT_EQ(cell_value(grid, 39, 5), c.miss);
  // The cells of tile (1, 0) beyond column 39 stay zero.
  ASSERT_EQ(grid.copy_tile(GridTile{1, 0}, Span<int8_t>(g_tile_a)), Status::kOk);
  for (uint32_t row = 0; row < kGridTileSide; ++row) {
    for (uint32_t col = 8; col < kGridTileSide; ++col)
      EXPECT_EQ(g_tile_a[row * kGridTileSide + col], 0) << row << "," << col;
  }
  // Down and to the left out of the corner.
  ASSERT_EQ(grid.insert_ray(metres_mm(-475), metres_mm(-400), metres_mm(-700), metres_mm(-900),
                            true, &report),
            Status::kOk);
  EXPECT_TRUE(report.clipped);
  EXPECT_GE(report.cells, 1u);
  // Starting outside, in any direction: rejected, nothing changes.
  const uint32_t rays = grid.stats().rays;
  EXPECT_EQ(grid.insert_ray(metres_mm(-501), metres_mm(0), metres_mm(0), metres_mm(0), true),
            Status::kOutOfRange);
  EXPECT_EQ(grid.insert_ray(metres_mm(0), metres_mm(1300), metres_mm(0), metres_mm(0), true),
            Status::kOutOfRange);
  // Absurd coordinates, too long rays: rejected, no crash.
  EXPECT_EQ(grid.insert_ray(Q31_32::max(), Q31_32::min(), Q31_32::min(), Q31_32::max(), true),
            Status::kOutOfRange);
  EXPECT_EQ(grid.insert_ray(metres_mm(0), metres_mm(0), Q31_32::max(), metres_mm(0), true),
            Status::kOutOfRange);
  EXPECT_EQ(grid.insert_ray(metres_mm(0), metres_mm(0), metres_mm(0), metres_mm(-300000), true),
            Status::kOutOfRange);
  EXPECT_EQ(grid.stats().rays, rays);
  // Queries outside.
  int8_t v = 0;
  EXPECT_EQ(grid.log_odds(GridCell{40, 0}, &v), Status::kOutOfRange);
  EXPECT_EQ(grid.log_odds(GridCell{-1, 0}, &v), Status::kOutOfRange);
  EXPECT_EQ(grid.log_odds(GridCell{0, 36}, &v), Status::kOutOfRange);
  EXPECT_EQ(grid.log_odds(GridCell{0, 0}, nullptr), Status::kInvalidArgument);
  EXPECT_EQ(grid.copy_tile(GridTile{2, 0}, Span<int8_t>(g_tile_a)), Status::kOutOfRange);
  EXPECT_EQ(grid.copy_tile(GridTile{0, 2}, Span<int8_t>(g_tile_a)), Status::kOutOfRange);
  EXPECT_EQ(grid.copy_tile(GridTile{0, 0}, Span<int8_t>(g_tile_a, 10)), Status::kInvalidArgument);
}

TEST(OccupancyGrid, CopyTileAndClear) {
  g_store.reset();
  OccupancyGrid grid;
  const GridConfig c = config_cells(128, 64);
  ASSERT_EQ(grid.configure(c, g_ram2.buffers(), g_store), Status::kOk);
  // Touch tiles (0,0), (1,0), (2,0) in turn: (0,0) is evicted to the store.
  for (int32_t t = 0; t < 3; ++t) {
    const Q31_32 x = metres_mm(t * 1600 + 25);
    ASSERT_EQ(grid.insert_ray(x, metres_mm(25), x, metres_mm(25), true), Status::kOk);
  }
  EXPECT_FALSE(grid.resident(GridTile{0, 0}));
  EXPECT_TRUE(grid.resident(GridTile{2, 0}));
  EXPECT_EQ(g_store.find(GridTile{0, 0}), 0);
  const uint32_t loads = grid.stats().tile_loads;
  ASSERT_EQ(grid.copy_tile(GridTile{0, 0}, Span<int8_t>(g_tile_a)), Status::kOk);  // store
  EXPECT_EQ(g_tile_a[0], c.hit);
  ASSERT_EQ(grid.copy_tile(GridTile{2, 0}, Span<int8_t>(g_tile_a)), Status::kOk);  // RAM
  EXPECT_EQ(g_tile_a[0], c.hit);
  g_tile_a[5] = 7;
  ASSERT_EQ(grid.copy_tile(GridTile{3, 1}, Span<int8_t>(g_tile_a)), Status::kOk);  // never saved
  for (int8_t v : g_tile_a)
    EXPECT_EQ(v, 0);
  EXPECT_FALSE(grid.resident(GridTile{0, 0}));  // copy_tile leaves the slots alone
  EXPECT_EQ(grid.stats().tile_loads, loads);
  // A store error on copy is reported.
  g_store.fail_load_at = g_store.loads;
  EXPECT_EQ(grid.copy_tile(GridTile{0, 0}, Span<int8_t>(g_tile_a)), Status::kUnavailable);
  g_store.fail_load_at = 0xFFFFFFFFu;
  // clear(): a failing store clear changes nothing; a working one forgets everything.
  g_store.fail_clear = true;
  EXPECT_EQ(grid.clear(), Status::kUnavailable);
  EXPECT_EQ(cell_value(grid, 64, 0), c.hit);
  g_store.fail_clear = false;
  ASSERT_EQ(grid.clear(), Status::kOk);
  EXPECT_EQ(g_store.clears, 1u);
  EXPECT_FALSE(grid.resident(GridTile{2, 0}));
  for (int32_t t = 0; t < 3; ++t)
    EXPECT_EQ(cell_value(grid, t * 32, 0), 0);
  // Rebuilt: the same rays give the same cells again.
  for (int32_t t = 0; t < 3; ++t) {
    const Q31_32 x = metres_mm(t * 1600 + 25);
    ASSERT_EQ(grid.insert_ray(x, metres_mm(25), x, metres_mm(25), true), Status::kOk);
  }
  for (int32_t t = 0; t < 3; ++t)
    EXPECT_EQ(cell_value(grid, t * 32, 0), c.hit);
}

// ---- Sensor rays ----

constexpr double kBamPerTurn = static_cast<double>(uint64_t{1} << 32);

double bam_radians(uint32_t bam) {
  return static_cast<double>(bam) * (2.0 * test::kPi / kBamPerTurn);
}
double q32_metres(Q31_32 v) {
  return static_cast<double>(v.raw()) / static_cast<double>(Q31_32::from_int(1).raw());
}

TEST(OccupancyGridSensor, SensorRayMatchesDoublePrecision) {
  test::Rng rng(75);
  double worst = 0.0;        // metres
  double worst_ratio = 0.0;  // error / bound
  for (uint32_t i = 0; i < 3000; ++i) {
    Pose2 pose;
    pose.x = Q31_32::from_raw(static_cast<int64_t>(rng.next64() % (uint64_t{100} << 32)) -
                              (int64_t{50} << 32));
    pose.y = Q31_32::from_raw(static_cast<int64_t>(rng.next64() % (uint64_t{100} << 32)) -
                              (int64_t{50} << 32));
    pose.heading = Angle{rng.next32()};
    const RangeSensor& sensor = kMyonInfrared[i % kMyonInfraredCount];
    const uint16_t range = static_cast<uint16_t>(rng.range(200, 1500));
    SensorRay ray;
    ASSERT_EQ(sensor_ray(pose, sensor, range, &ray), Status::kOk);
    EXPECT_TRUE(ray.use);
    EXPECT_TRUE(ray.hit);
    const double h = bam_radians(pose.heading.bam);
    const double mx = q32_metres(sensor.x);
    const double my = q32_metres(sensor.y);
    const double ox = q32_metres(pose.x) + test::ref_cos(h) * mx - test::ref_sin(h) * my;
    const double oy = q32_metres(pose.y) + test::ref_sin(h) * mx + test::ref_cos(h) * my;
    const double a = bam_radians(pose.heading.bam + sensor.angle.bam);
    const double ex = ox + test::ref_cos(a) * range / 1000.0;
    const double ey = oy + test::ref_sin(a) * range / 1000.0;
    const double bound = (test::ref_fabs(mx) + test::ref_fabs(my) + range / 1000.0) * 1.0e-9 +
                         1.0 / 2147483648.0 + 1e-13;  // + double rounding at 50 m
    const double errs[4] = {
        test::ref_fabs(q32_metres(ray.x0) - ox), test::ref_fabs(q32_metres(ray.y0) - oy),
        test::ref_fabs(q32_metres(ray.x1) - ex), test::ref_fabs(q32_metres(ray.y1) - ey)};
    for (double e : errs) {
      EXPECT_LE(e, bound) << i;
      if (e > worst) worst = e;
      if (e / bound > worst_ratio) worst_ratio = e / bound;
    }
  }
  test::log_figure("sensor ray end point: largest error (m)", worst);
  test::log_figure("sensor ray end point: largest error / bound", worst_ratio);
}

// Equal up to the rounding of the Q31.32 sums (a few 2^-32 m).
bool near_raw(Q31_32 a, Q31_32 b) {
  const int64_t d = a.raw() - b.raw();
  return d >= -2 && d <= 2;
}

TEST(OccupancyGridSensor, ReadingsOutOfRangeAndNoEcho) {
  Pose2 pose;
  pose.x = metres_mm(1000);
  pose.y = metres_mm(2000);
  pose.heading = Angle::from_degrees(90);
  const RangeSensor& front = kMyonInfrared[0];
  SensorRay ray;
  EXPECT_EQ(sensor_ray(pose, front, 199, &ray), Status::kOutOfRange);
  EXPECT_EQ(sensor_ray(pose, front, 1501, &ray), Status::kOutOfRange);
  EXPECT_EQ(sensor_ray(pose, front, 800, nullptr), Status::kInvalidArgument);
  // Heading north, the front sensor sits 0.2 m north of the centre and looks north; a
  // multiple of 90 degrees is exact in sincos, so the ray is exact.
  ASSERT_EQ(sensor_ray(pose, front, 800, &ray), Status::kOk);
  EXPECT_TRUE(near_raw(ray.x0, metres_mm(1000)));
  EXPECT_TRUE(near_raw(ray.y0, metres_mm(2200)));
  EXPECT_TRUE(near_raw(ray.x1, metres_mm(1000)));
  EXPECT_TRUE(near_raw(ray.y1, metres_mm(3000)));
  EXPECT_TRUE(ray.hit);
  // No echo: free up to no_echo_mm (1.4 m), no hit.
  ASSERT_EQ(sensor_ray(pose, front, 0, &ray), Status::kOk);
  EXPECT_TRUE(ray.use);
  EXPECT_FALSE(ray.hit);
  EXPECT_TRUE(near_raw(ray.y1, metres_mm(3600)));
  RangeSensor ignore = front;
  ignore.no_echo_mm = 0;
  ASSERT_EQ(sensor_ray(pose, ignore, 0, &ray), Status::kOk);
  EXPECT_FALSE(ray.use);
  // The rear sensor (180 degrees, 0.2 m behind): heading north, it looks south.
  ASSERT_EQ(sensor_ray(pose, kMyonInfrared[5], 500, &ray), Status::kOk);
  EXPECT_TRUE(near_raw(ray.y0, metres_mm(1800)));
  EXPECT_TRUE(near_raw(ray.y1, metres_mm(1300)));
  // In a grid: an ignored reading changes nothing; a bad one in a scan rejects the scan.
  g_store.reset();
  OccupancyGrid grid;
  ASSERT_EQ(grid.configure(config_cells(100, 100), g_ram3.buffers(), g_store), Status::kOk);
  RayReport report{5, true};
  ASSERT_EQ(grid.insert_reading(pose, ignore, 0, &report), Status::kOk);
  EXPECT_EQ(report.cells, 0u);
  EXPECT_EQ(grid.stats().rays, 0u);
  const uint16_t bad[kMyonInfraredCount] = {500, 500, 500, 100, 500, 500};
  EXPECT_EQ(
      grid.insert_scan(pose, Span<const RangeSensor>(kMyonInfrared), Span<const uint16_t>(bad)),
      Status::kOutOfRange);
  EXPECT_EQ(grid.stats().rays, 0u);
  EXPECT_EQ(
      grid.insert_scan(pose, Span<const RangeSensor>(kMyonInfrared), Span<const uint16_t>(bad, 3)),
      Status::kInvalidArgument);
  const uint16_t good[kMyonInfraredCount] = {500, 0, 1500, 200, 700, 0};
  ASSERT_EQ(
      grid.insert_scan(pose, Span<const RangeSensor>(kMyonInfrared), Span<const uint16_t>(good)),
      Status::kOk);
  EXPECT_EQ(grid.stats().rays, 6u);
  // The front ray ended at (1.0, 2.7): hit.
  GridCell cell;
  ASSERT_EQ(grid.cell_at(metres_mm(1000), metres_mm(2700), &cell), Status::kOk);
  EXPECT_EQ(cell_value(grid, cell.col, cell.row), grid.config().hit);
}

// ---- A synthetic room ----

// Walls (as lines) of a 2.4 m x 1.8 m room in the middle of 5 cm cells: x = 0.025 and 2.425,
// y = 0.025 and 1.825, so the wall cells are columns 0 and 48 and rows 0 and 36.
constexpr double kWallW = 0.025;
constexpr double kWallE = 2.425;
constexpr double kWallS = 0.025;
constexpr double kWallN = 1.825;

// Distance from (x, y) along direction a (radians) to the first wall.
double wall_distance(double x, double y, double a) {
  const double c = test::ref_cos(a);
  const double s = test::ref_sin(a);
  double t = 1e9;
  if (c > 1e-12) t = (kWallE - x) / c;
  if (c < -1e-12) t = (kWallW - x) / c;
  if (s > 1e-12 && (kWallN - y) / s < t) t = (kWallN - y) / s;
  if (s < -1e-12 && (kWallS - y) / s < t) t = (kWallS - y) / s;
  return t;
}

uint16_t reading_mm(double metres) {
  return static_cast<uint16_t>(test::ref_round(metres * 1000.0));
}

struct RoomCounts {
  uint32_t wall = 0, wall_occupied = 0, wall_free = 0;
  uint32_t inside = 0, inside_free = 0, inside_occupied = 0;
  uint32_t outside_touched = 0;
};

RoomCounts count_room(OccupancyGrid& grid) {
  RoomCounts n;
  for (int32_t row = 0; row < 40; ++row) {
    for (int32_t col = 0; col < 50; ++col) {
      int8_t v = 0;
      EXPECT_EQ(grid.log_odds(GridCell{col, row}, &v), Status::kOk);
      const CellState s = grid.classify(v);
      const bool outside = col > 48 || row > 36;
      const bool wall = !outside && (col == 0 || col == 48 || row == 0 || row == 36);
      if (outside) {
        if (v != 0) ++n.outside_touched;
      } else if (wall) {
        ++n.wall;
        if (s == CellState::kOccupied) ++n.wall_occupied;
        if (s == CellState::kFree) ++n.wall_free;
      } else {
        ++n.inside;
        if (s == CellState::kFree) ++n.inside_free;
        if (s == CellState::kOccupied) ++n.inside_occupied;
      }
    }
  }
  return n;
}

TEST(OccupancyGrid, SyntheticRoomScanClassifiesWallsAndInterior) {
  g_store.reset();
  OccupancyGrid grid;
  ASSERT_EQ(grid.configure(config_cells(50, 40), g_ram3.buffers(), g_store), Status::kOk);
  // A range sensor at the robot's centre turned through 72 directions at 12 poses.
  RangeSensor sweep;
  sweep.min_mm = 10;
  sweep.max_mm = 3500;
  sweep.no_echo_mm = 0;
  uint32_t rays = 0;
  for (int32_t py = 0; py < 3; ++py) {
    for (int32_t px = 0; px < 4; ++px) {
      Pose2 pose;
      pose.x = metres_mm(500 + 470 * px);
      pose.y = metres_mm(500 + 400 * py);
      pose.heading = Angle::from_degrees(7 * (px + 4 * py));
      for (int32_t k = 0; k < 72; ++k) {
        sweep.angle = Angle::from_degrees(5 * k);
        const double a = bam_radians(pose.heading.bam + sweep.angle.bam);
        const uint16_t r = reading_mm(wall_distance(q32_metres(pose.x), q32_metres(pose.y), a));
        ASSERT_EQ(grid.insert_reading(pose, sweep, r), Status::kOk);
        ++rays;
      }
    }
  }
  EXPECT_EQ(grid.stats().rays, rays);
  const RoomCounts n = count_room(grid);
  // The hits lie within 0.5 mm of the wall lines, in the middle of the wall cells: nothing
  // inside is ever hit, nothing outside is ever touched.
  EXPECT_EQ(n.inside_occupied, 0u);
  EXPECT_EQ(n.outside_touched, 0u);
  const double inside_free = static_cast<double>(n.inside_free) / n.inside;
  const double wall_occupied = static_cast<double>(n.wall_occupied) / n.wall;
  EXPECT_GE(inside_free, 0.95);
  EXPECT_GE(wall_occupied, 0.80);
  EXPECT_LE(n.wall_free, n.wall / 20);
  test::log_figure("room scan: interior cells free", inside_free);
  test::log_figure("room scan: wall cells occupied", wall_occupied);
  test::log_figure("room scan: wall cells free", static_cast<double>(n.wall_free) / n.wall);
}

// The six Myon sensors in the room: every echo lands in a wall cell.
TEST(OccupancyGrid, MyonScanInTheRoom) {
  g_store.reset();
  OccupancyGrid grid;
  ASSERT_EQ(grid.configure(config_cells(50, 40), g_ram3.buffers(), g_store), Status::kOk);
  Pose2 pose;
  pose.x = metres_mm(1200);
  pose.y = metres_mm(900);
  pose.heading = Angle::from_degrees(10);
  uint16_t readings[kMyonInfraredCount];
  for (uint32_t i = 0; i < kMyonInfraredCount; ++i) {
    SensorRay probe;
    ASSERT_EQ(sensor_ray(pose, kMyonInfrared[i], 1000, &probe), Status::kOk);
    const double a = bam_radians(pose.heading.bam + kMyonInfrared[i].angle.bam);
    const double d = wall_distance(q32_metres(probe.x0), q32_metres(probe.y0), a);
    readings[i] = d <= 1.5 ? reading_mm(d) : 0;
  }
  ASSERT_EQ(grid.insert_scan(pose, Span<const RangeSensor>(kMyonInfrared),
                             Span<const uint16_t>(readings)),
            Status::kOk);
  uint32_t echoes = 0;
  for (uint32_t i = 0; i < kMyonInfraredCount; ++i) {
    if (readings[i] == 0) continue;
    ++echoes;
    SensorRay ray;
    ASSERT_EQ(sensor_ray(pose, kMyonInfrared[i], readings[i], &ray), Status::kOk);
    GridCell cell;
    ASSERT_EQ(grid.cell_at(ray.x1, ray.y1, &cell), Status::kOk);
    EXPECT_TRUE(cell.col == 0 || cell.col == 48 || cell.row == 0 || cell.row == 36) << i;
    CellState st;
    ASSERT_EQ(grid.state(cell, &st), Status::kOk);
    EXPECT_EQ(st, CellState::kOccupied) << i;
  }
  EXPECT_GE(echoes, 5u);
  const RoomCounts n = count_room(grid);
  EXPECT_EQ(n.inside_occupied, 0u);
  EXPECT_EQ(n.outside_touched, 0u);
}

// ---- Paging along a corridor ----

// The robot drives 18 m along a 2 m wide corridor (walls at y = 0.525 and 2.525 m, centre
// line 1.525 m, a gentle weave of +-0.3 m and +-15 degrees) and inserts a six-sensor scan
// every 5 cm; the figures are tile loads per scan for 3, 4, 6 and 8 slots. A scan reaches
// +-1.7 m around the robot, i.e. up to 3 tile columns x 2 rows here: with fewer slots than
// that, LRU reloads tiles within every scan.
OccupancyGridStorage<8> g_ram8;
OccupancyGridStorage<6> g_ram6;
OccupancyGridStorage<4> g_ram4;

double corridor_distance(double y, double a) {
  const double s = test::ref_sin(a);
  if (s > 1e-12) return (2.525 - y) / s;
  if (s < -1e-12) return (0.525 - y) / s;
  return 1e9;
}

TEST(OccupancyGrid, PagingPerScanAlongACorridor) {
  const GridConfig c = config_cells(400, 64);  // 20 m x 3.2 m: 13 x 2 tiles
  constexpr uint32_t kConfigs = 4;
  const OccupancyGridBuffers buffers[kConfigs] = {g_ram3.buffers(), g_ram4.buffers(),
                                                  g_ram6.buffers(), g_ram8.buffers()};
  const char* const labels[kConfigs] = {
      "corridor: tile loads per scan, 3 slots", "corridor: tile loads per scan, 4 slots",
      "corridor: tile loads per scan, 6 slots", "corridor: tile loads per scan, 8 slots"};
  uint32_t loads[kConfigs] = {};
  uint32_t cells_per_config[kConfigs] = {};
  for (uint32_t k = 0; k < kConfigs; ++k) {
    g_store.reset();
    OccupancyGrid grid;
    ASSERT_EQ(grid.configure(c, buffers[k], g_store), Status::kOk);
    uint32_t scans = 0;
    for (int32_t step = 0; step <= 360; ++step) {
      const double x = 1.0 + 0.05 * step;
      const double phase = 2.0 * test::kPi * x / 6.0;
      Pose2 pose;
      pose.x = metres_mm(1000 + 50 * step);
      pose.y =
          metres_mm(1525 + static_cast<int64_t>(test::ref_round(300.0 * test::ref_sin(phase))));
      pose.heading = Angle::from_turn_ratio(
          static_cast<int64_t>(test::ref_round(15.0 / 360.0 * 1e6 * test::ref_cos(phase))),
          1000000);
      uint16_t readings[kMyonInfraredCount];
      for (uint32_t i = 0; i < kMyonInfraredCount; ++i) {
        SensorRay probe;
        ASSERT_EQ(sensor_ray(pose, kMyonInfrared[i], 1000, &probe), Status::kOk);
        const double a = bam_radians(pose.heading.bam + kMyonInfrared[i].angle.bam);
        const double d = corridor_distance(q32_metres(probe.y0), a);
        readings[i] = (d >= 0.2 && d <= 1.5) ? reading_mm(d) : 0;
      }
      ASSERT_EQ(grid.insert_scan(pose, Span<const RangeSensor>(kMyonInfrared),
                                 Span<const uint16_t>(readings)),
                Status::kOk);
      ++scans;
    }
    loads[k] = grid.stats().tile_loads;
    cells_per_config[k] = grid.stats().cells;
    test::log_figure(labels[k], static_cast<double>(loads[k]) / scans);
  }
  // Same map work whatever the slots; fewer loads with more slots; with 6 or more slots a
  // tile is loaded about once per pass (26 tiles in the corridor's two rows).
  for (uint32_t k = 1; k < kConfigs; ++k) {
    EXPECT_EQ(cells_per_config[k], cells_per_config[0]);
    EXPECT_LE(loads[k], loads[k - 1]);
  }
  EXPECT_LE(loads[2], 26u);
  EXPECT_LE(loads[3], 26u);
}

}  // namespace
}  // namespace seqslam
