// Occupancy grid maps on the host (seqslam_tools/grid_export.h): export in the map_server
// convention and back, reading the simulator's true map, the confusion counts, bad input for
// the loader, and the map quality of the core's grid built from a simulated drive.
#include "seqslam_tools/grid_export.h"
#include "seqslam_tools/q_format.h"
#include "seqslam_tools/ram_tile_store.h"

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "seqslam/occupancy_grid.h"
#include "seqslam/odometry.h"
#include "seqslam_sim/lab.h"
#include "seqslam_sim/rng.h"
#include "seqslam_sim/robot.h"
#include "seqslam_sim/scenario.h"
#include "seqslam_sim/true_map.h"
#include "test_util.h"

namespace seqslam::tools {
namespace {

using ::testing::HasSubstr;

Q31_32 metres(double m) {
  return from_double<Q31_32>(m);
}

TEST(GridExport, RoundTripThroughPgmAndYaml) {
  RamTileStore store;
  static OccupancyGridStorage<3> ram;
  OccupancyGrid grid;
  GridConfig c;
  c.width = 70;  // 3 x 2 tiles, the last column and row partly outside
  c.height = 40;
  c.origin_x = metres(-1.25);
  c.origin_y = metres(2.5);
  ASSERT_EQ(grid.configure(c, ram.buffers(), store), Status::kOk);
  // A few hits and free rays, spread over the tiles so some are evicted to the store.
  for (int i = 0; i < 40; ++i) {
    const double x0 = -1.2 + 0.08 * i;
    ASSERT_EQ(grid.insert_ray(metres(x0), metres(2.6), metres(x0 + 0.3), metres(4.3), true),
              Status::kOk);
    ASSERT_EQ(grid.insert_ray(metres(x0), metres(2.6), metres(x0 + 0.3), metres(3.5), false),
              Status::kOk);
    ASSERT_EQ(grid.insert_ray(metres(x0), metres(2.6), metres(x0 + 0.3), metres(3.5), false),
              Status::kOk);
    ASSERT_EQ(grid.insert_ray(metres(x0), metres(2.6), metres(x0 + 0.3), metres(3.5), false),
              Status::kOk);
    ASSERT_EQ(grid.insert_ray(metres(x0), metres(2.6), metres(x0 + 0.3), metres(3.5), false),
              Status::kOk);
  }
  ASSERT_GT(store.tile_count(), 0u);
  const Outcome<OccupancyMapImage> map = grid_map(grid);
  ASSERT_TRUE(map.ok()) << map.error();
  const OccupancyMapImage& m = map.value();
  EXPECT_EQ(m.width, 70);
  EXPECT_EQ(m.height, 40);
  EXPECT_DOUBLE_EQ(m.resolution, 0.05);
  EXPECT_DOUBLE_EQ(m.origin_x, -1.25);
  EXPECT_DOUBLE_EQ(m.origin_y, 2.5);
  int counts[3] = {};
  for (int y = 0; y < 40; ++y) {
    for (int x = 0; x < 70; ++x) {
      CellState s;
      ASSERT_EQ(grid.state(GridCell{x, y}, &s), Status::kOk);
      EXPECT_EQ(m.at(x, y), s) << x << "," << y;
      ++counts[static_cast<int>(s)];
    }
  }
  EXPECT_GT(counts[1], 50);  // free
  EXPECT_GT(counts[2], 20);  // occupied

  test::TempDir dir;
  std::string error;
  ASSERT_TRUE(save_map(m, dir.file("grid"), &error)) << error;
  const std::vector<uint8_t> pgm = test::read_file(dir.file("grid.pgm"));
  const std::string header = "P5\n70 40\n255\n";
  ASSERT_EQ(pgm.size(), header.size() + 70u * 40u);
  EXPECT_EQ(std::string(pgm.begin(), pgm.begin() + static_cast<long>(header.size())), header);
  // The first image row is the top of the map (y = 39), values 254 / 0 / 205.
  for (int x = 0; x < 70; ++x) {
    for (int r = 0; r < 40; ++r) {
      const uint8_t v = pgm[header.size() + static_cast<size_t>(r) * 70 + static_cast<size_t>(x)];
      const CellState s = m.at(x, 39 - r);
      EXPECT_EQ(v, s == CellState::kFree ? 254 : s == CellState::kOccupied ? 0 : 205);
    }
  }
  EXPECT_EQ(test::to_string(test::read_file(dir.file("grid.yaml"))),
            "image: grid.pgm\nresolution: 0.05\norigin: [-1.25, 2.5, 0.0]\nnegate: 0\n"
            "occupied_thresh: 0.65\nfree_thresh: 0.196\n");
  const Outcome<OccupancyMapImage> back = load_map(dir.file("grid.yaml"));
  ASSERT_TRUE(back.ok()) << back.error();
  EXPECT_EQ(back.value().width, 70);
  EXPECT_EQ(back.value().height, 40);
  EXPECT_DOUBLE_EQ(back.value().resolution, 0.05);
  EXPECT_DOUBLE_EQ(back.value().origin_x, -1.25);
  EXPECT_DOUBLE_EQ(back.value().origin_y, 2.5);
  EXPECT_TRUE(back.value().cells == m.cells);
  // Compared with itself: every explored cell is right.
  const Outcome<MapComparison> self = compare_maps(m, back.value());
  ASSERT_TRUE(self.ok()) << self.error();
  EXPECT_EQ(self.value().scored(), static_cast<uint64_t>(counts[1] + counts[2]));
  EXPECT_DOUBLE_EQ(self.value().accuracy(), 1.0);
  EXPECT_EQ(self.value().grid_unknown, 0u);
}

TEST(GridExport, ReadsTheSimulatorsTrueMap) {
  sim::LabOptions still;
  still.people = false;
  still.move_chairs = false;
  const sim::OccupancyMap truth =
      sim::true_map(sim::build_lab(0, still), 0.05, sim::kInfraredHeight);
  test::TempDir dir;
  ASSERT_EQ(sim::save_map(truth, dir.file("lab_map")), "");
  const Outcome<OccupancyMapImage> m = load_map(dir.file("lab_map.yaml"));
  ASSERT_TRUE(m.ok()) << m.error();
  ASSERT_EQ(m.value().width, truth.width);
  ASSERT_EQ(m.value().height, truth.height);
  EXPECT_DOUBLE_EQ(m.value().resolution, 0.05);
  EXPECT_DOUBLE_EQ(m.value().origin_x, truth.origin_x);
  EXPECT_DOUBLE_EQ(m.value().origin_y, truth.origin_y);
  size_t differ = 0;
  for (int y = 0; y < truth.height; ++y) {
    for (int x = 0; x < truth.width; ++x) {
      const CellState want = truth.at(x, y) == sim::OccupancyMap::kFree       ? CellState::kFree
                             : truth.at(x, y) == sim::OccupancyMap::kOccupied ? CellState::kOccupied
                                                                              : CellState::kUnknown;
      if (m.value().at(x, y) != want) ++differ;
    }
  }
  EXPECT_EQ(differ, 0u);
}

OccupancyMapImage small_map(int w, int h, double ox, double oy, CellState fill) {
  OccupancyMapImage m;
  m.width = w;
  m.height = h;
  m.origin_x = ox;
  m.origin_y = oy;
  m.cells.assign(static_cast<size_t>(w) * static_cast<size_t>(h), fill);
  return m;
}
void set(OccupancyMapImage& m, int x, int y, CellState s) {
  m.cells[static_cast<size_t>(y) * static_cast<size_t>(m.width) + static_cast<size_t>(x)] = s;
}

TEST(GridExport, CompareCountsTheConfusionInTheExploredArea) {
  // Truth: 6 x 4 cells at origin (0, 0), all free but column 5 occupied, row 3 unknown.
  OccupancyMapImage truth = small_map(6, 4, 0.0, 0.0, CellState::kFree);
  for (int y = 0; y < 4; ++y)
    set(truth, 5, y, CellState::kOccupied);
  for (int x = 0; x < 6; ++x)
    set(truth, x, 3, CellState::kUnknown);
  // Grid: 4 x 4 cells starting two cells to the right (origin x 0.1): grid column g is truth
  // column g + 2; grid column 3 (truth 5) is the wall, grid columns 4.. are outside.
  OccupancyMapImage grid = small_map(4, 4, 0.1, 0.0, CellState::kUnknown);
  set(grid, 0, 0, CellState::kFree);      // free / free
  set(grid, 1, 0, CellState::kFree);      // free / free
  set(grid, 2, 0, CellState::kOccupied);  // free / occupied: phantom
  set(grid, 3, 0, CellState::kOccupied);  // occupied / occupied
  set(grid, 3, 1, CellState::kFree);      // occupied / free: missed
  set(grid, 0, 3, CellState::kFree);      // truth unknown
  const Outcome<MapComparison> r = compare_maps(grid, truth);
  ASSERT_TRUE(r.ok()) << r.error();
  const MapComparison& c = r.value();
  EXPECT_EQ(c.free_free, 2u);
  EXPECT_EQ(c.free_occupied, 1u);
  EXPECT_EQ(c.occupied_occupied, 1u);
  EXPECT_EQ(c.occupied_free, 1u);
  EXPECT_EQ(c.truth_unknown, 1u);
  EXPECT_EQ(c.scored(), 5u);
  EXPECT_DOUBLE_EQ(c.accuracy(), 3.0 / 5.0);
  // Truth-known cells the grid left unknown (or does not cover): 18 known - 5 scored.
  EXPECT_EQ(c.grid_unknown, 13u);
  // Nothing explored: accuracy 0, no division by zero.
  const Outcome<MapComparison> none =
      compare_maps(small_map(2, 2, 0.0, 0.0, CellState::kUnknown), truth);
  ASSERT_TRUE(none.ok());
  EXPECT_EQ(none.value().scored(), 0u);
  EXPECT_EQ(none.value().accuracy(), 0.0);
  // Mismatched geometry is refused.
  OccupancyMapImage coarse = grid;
  coarse.resolution = 0.1;
  EXPECT_THAT(compare_maps(coarse, truth).error(), HasSubstr("resolutions differ"));
  OccupancyMapImage shifted = grid;
  shifted.origin_x = 0.125;
  EXPECT_THAT(compare_maps(shifted, truth).error(), HasSubstr("whole number of cells"));
  OccupancyMapImage broken = grid;
  broken.cells.pop_back();
  EXPECT_THAT(compare_maps(broken, truth).error(), HasSubstr("inconsistent"));
  std::string error;
  test::TempDir dir;
  EXPECT_FALSE(save_map(broken, dir.file("broken"), &error));
  EXPECT_THAT(error, HasSubstr("inconsistent"));
}

TEST(GridExport, NearPathCountsOccupiedCellsInTheBandRoundThePath) {
  // Truth: 8 x 5 cells of 10 cm at the origin (centres 0.05 .. 0.75, 0.05 .. 0.45), free but
  // a wall in row 3 (columns 2..5), an occupied cell (7, 3) and an unknown cell (5, 1).
  OccupancyMapImage truth = small_map(8, 5, 0.0, 0.0, CellState::kFree);
  truth.resolution = 0.1;
  for (int x = 2; x <= 5; ++x)
    set(truth, x, 3, CellState::kOccupied);
  set(truth, 7, 3, CellState::kOccupied);
  set(truth, 5, 1, CellState::kUnknown);
  // The path: run 0 drives (0.25, 0.25) -> (0.55, 0.25); run 1 is seen at (0.75, 0.05), then
  // jumps (2 m, a kidnap) off the map. Band 0.12 m: row 2 columns 1..6 (6 cells), rows 1 and
  // 3 columns 2..5 (4 + 4; dy 0.1 leaves 0.066 m beyond the ends), and round the lone pose
  // (7, 0), (6, 0), (7, 1): 17 cells, (5, 1) unknown to the truth: 16 scored, 4 of them truly
  // occupied (row 3). No segment joins the runs (it would cross (6, 1)) or spans the jump (it
  // would reach (7, 3)).
  const std::vector<PathPoint> path = {
      {0.25, 0.25, 0}, {0.55, 0.25, 0}, {0.75, 0.05, 1}, {0.75, 2.05, 1}};
  // Grid: 6 x 5 cells one cell to the right (grid column g is truth column g + 1; truth column
  // 7 is outside it: unknown). Written in truth columns below; the rest of it free.
  OccupancyMapImage grid = small_map(6, 5, 0.1, 0.0, CellState::kFree);
  grid.resolution = 0.1;
  const auto at_truth = [&](int x, int y, CellState s) { set(grid, x - 1, y, s); };
  at_truth(2, 3, CellState::kOccupied);  // TP
  at_truth(3, 3, CellState::kOccupied);  // TP
  at_truth(4, 3, CellState::kUnknown);   // FN: a wall not seen
  at_truth(5, 3, CellState::kFree);      // FN, nothing occupied round it either
  at_truth(3, 2, CellState::kOccupied);  // FP, but next to the wall (3, 3)
  at_truth(6, 0, CellState::kOccupied);  // FP, no wall near
  at_truth(6, 1, CellState::kOccupied);  // outside the band: not counted
  at_truth(1, 4, CellState::kOccupied);  // outside the band: not counted
  const Outcome<NearPathComparison> r = compare_maps_near_path(grid, truth, path, 0.12);
  ASSERT_TRUE(r.ok()) << r.error();
  const NearPathComparison& c = r.value();
  EXPECT_EQ(c.cells, 16u);
  EXPECT_EQ(c.truth_occupied, 4u);
  EXPECT_EQ(c.truth_free(), 12u);
  EXPECT_EQ(c.grid_occupied, 4u);             // (2, 3), (3, 3), (3, 2), (6, 0)
  EXPECT_EQ(c.grid_free, 9u);                 // row 2 but (3, 2): 5; row 1: 3; (5, 3)
  EXPECT_EQ(c.grid_unknown(), 3u);            // (4, 3); (7, 0), (7, 1) outside the grid
  EXPECT_EQ(c.occupied_occupied, 2u);         // TP
  EXPECT_EQ(c.grid_occupied_near_truth, 3u);  // all but (6, 0)
  EXPECT_EQ(c.truth_occupied_near_grid, 3u);  // all but (5, 3)
  EXPECT_TRUE(c.consistent());
  EXPECT_DOUBLE_EQ(c.precision(), 2.0 / 4);             // TP / (TP + FP)
  EXPECT_DOUBLE_EQ(c.recall(), 2.0 / 4);                // TP / (TP + FN)
  EXPECT_DOUBLE_EQ(c.true_negative_rate(), 10.0 / 12);  // 12 truly free, 2 called occupied
  EXPECT_DOUBLE_EQ(c.balanced_accuracy(), (2.0 / 4 + 10.0 / 12) / 2);
  EXPECT_DOUBLE_EQ(c.precision_within_cell(), 3.0 / 4);
  EXPECT_DOUBLE_EQ(c.recall_within_cell(), 3.0 / 4);

  // Without the jump (0.9 m: driven), the segment (0.75, 0.05) - (0.75, 0.95) puts columns 6
  // and 7 into the band: new are (6, 1), (6, 3), (6, 4), (7, 2), (7, 3), (7, 4), of which
  // (7, 3) is truly occupied and (6, 1) called occupied.
  std::vector<PathPoint> joined = path;
  joined[3].y = 0.95;
  const Outcome<NearPathComparison> j = compare_maps_near_path(grid, truth, joined, 0.12);
  ASSERT_TRUE(j.ok()) << j.error();
  EXPECT_EQ(j.value().cells, 16u + 6u);
  EXPECT_EQ(j.value().truth_occupied, 5u);
  EXPECT_EQ(j.value().grid_occupied, 5u);

  // No path: nothing scored, every rate 0. Bad band or geometry: refused.
  const Outcome<NearPathComparison> none = compare_maps_near_path(grid, truth, {}, 1.0);
  ASSERT_TRUE(none.ok());
  EXPECT_EQ(none.value(), NearPathComparison{});
  EXPECT_EQ(none.value().precision(), 0.0);
  EXPECT_EQ(none.value().balanced_accuracy(), 0.0);
  EXPECT_THAT(compare_maps_near_path(grid, truth, path, 0.0).error(), HasSubstr("band"));
  EXPECT_THAT(compare_maps_near_path(grid, truth, path, std::nan("")).error(), HasSubstr("band"));
  EXPECT_THAT(compare_maps_near_path(grid, truth, {{std::nan(""), 0.0, 0}}, 1.0).error(),
              HasSubstr("not finite"));
  OccupancyMapImage shifted = grid;
  shifted.origin_x = 0.125;
  EXPECT_THAT(compare_maps_near_path(shifted, truth, path, 1.0).error(),
              HasSubstr("whole number of cells"));
  NearPathComparison bad = c;
  bad.occupied_occupied = 5;
  EXPECT_FALSE(bad.consistent());
}

class GridLoadErrors : public ::testing::Test {
 protected:
  // A valid 4 x 3 PGM named map.pgm and a YAML file with the given text.
  std::string write(const std::string& yaml) {
    test::write_file(dir_.file("map.pgm"), std::string("P5\n4 3\n255\n") + std::string(12, '\xfe'));
    test::write_file(dir_.file("map.yaml"), yaml);
    return dir_.file("map.yaml");
  }
  std::string error_of(const std::string& yaml) {
    const Outcome<OccupancyMapImage> m = load_map(write(yaml));
    EXPECT_FALSE(m.ok());
    return m.error();
  }
  test::TempDir dir_;
};

constexpr const char* kGood =
    "image: map.pgm\nresolution: 0.05\norigin: [1.0, -2.0, 0.0]\nnegate: 0\n"
    "occupied_thresh: 0.65\nfree_thresh: 0.196\n";

TEST_F(GridLoadErrors, AcceptsTheMinimalAndCommentedForms) {
  const Outcome<OccupancyMapImage> full = load_map(write(kGood));
  ASSERT_TRUE(full.ok()) << full.error();
  EXPECT_EQ(full.value().width, 4);
  EXPECT_EQ(full.value().at(3, 2), CellState::kFree);
  const Outcome<OccupancyMapImage> minimal =
      load_map(write("# a comment\n---\nimage: \"map.pgm\"  # quoted\nresolution: 0.1\r\n"
                     "origin: [ -3 , +4.5,0 ]\nmode: trinary\nother_key: whatever\n"));
  ASSERT_TRUE(minimal.ok()) << minimal.error();
  EXPECT_DOUBLE_EQ(minimal.value().resolution, 0.1);
  EXPECT_DOUBLE_EQ(minimal.value().origin_x, -3.0);
  EXPECT_DOUBLE_EQ(minimal.value().origin_y, 4.5);
  // negate 1 turns 254 into occupied.
  const Outcome<OccupancyMapImage> negated =
      load_map(write("image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\nnegate: 1\n"));
  ASSERT_TRUE(negated.ok()) << negated.error();
  EXPECT_EQ(negated.value().at(0, 0), CellState::kOccupied);
}

TEST_F(GridLoadErrors, MissingFilesAndKeys) {
  EXPECT_THAT(load_map(dir_.file("nothing.yaml")).error(), HasSubstr("nothing.yaml"));
  EXPECT_THAT(error_of("resolution: 0.05\norigin: [0, 0, 0]\n"), HasSubstr("missing key 'image'"));
  EXPECT_THAT(error_of("image: map.pgm\norigin: [0, 0, 0]\n"),
              HasSubstr("missing key 'resolution'"));
  EXPECT_THAT(error_of("image: map.pgm\nresolution: 0.05\n"), HasSubstr("missing key 'origin'"));
  EXPECT_THAT(error_of(""), HasSubstr("missing key"));
  EXPECT_THAT(error_of("image: map.pgm\nimage: map.pgm\nresolution: 1\norigin: [0, 0, 0]\n"),
              HasSubstr(":2: key 'image' repeated"));
  EXPECT_THAT(error_of("image map.pgm\n"), HasSubstr(":1: expected 'key: value'"));
  EXPECT_THAT(error_of("image: \"\"\nresolution: 0.05\norigin: [0, 0, 0]\n"),
              HasSubstr("image is empty"));
}

TEST_F(GridLoadErrors, BadValues) {
  EXPECT_THAT(error_of("image: map.pgm\nresolution: 0\norigin: [0, 0, 0]\n"),
              HasSubstr(":2: resolution must be a number > 0"));
  EXPECT_THAT(error_of("image: map.pgm\nresolution: -0.05\norigin: [0, 0, 0]\n"),
              HasSubstr("resolution must be"));
  EXPECT_THAT(error_of("image: map.pgm\nresolution: 5cm\norigin: [0, 0, 0]\n"),
              HasSubstr("found '5cm'"));
  EXPECT_THAT(error_of("image: map.pgm\nresolution: nan\norigin: [0, 0, 0]\n"),
              HasSubstr("resolution must be"));
  EXPECT_THAT(error_of("image: map.pgm\nresolution: 0.05\norigin: [0, 0]\n"),
              HasSubstr(":3: origin must be [x, y, yaw]"));
  EXPECT_THAT(error_of("image: map.pgm\nresolution: 0.05\norigin: 0, 0, 0\n"),
              HasSubstr("origin must be"));
  EXPECT_THAT(error_of("image: map.pgm\nresolution: 0.05\norigin: [0, x, 0]\n"),
              HasSubstr("origin must be"));
  EXPECT_THAT(error_of("image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0, 0]\n"),
              HasSubstr("origin must be"));
  EXPECT_THAT(error_of("image: map.pgm\nresolution: 0.05\norigin: [0,0,0]\nnegate: 2\n"),
              HasSubstr("negate must be 0 or 1"));
  EXPECT_THAT(error_of("image: map.pgm\nresolution: 0.05\norigin: [0,0,0]\nfree_thresh: 0.9\n"),
              HasSubstr("thresholds must satisfy"));
  EXPECT_THAT(
      error_of("image: map.pgm\nresolution: 0.05\norigin: [0,0,0]\noccupied_thresh: high\n"),
      HasSubstr("occupied_thresh must be a number"));
  EXPECT_THAT(error_of("image: map.pgm\nresolution: 0.05\norigin: [0,0,0]\nmode: raw\n"),
              HasSubstr("only mode 'trinary'"));
}

TEST_F(GridLoadErrors, MissingTruncatedAndGarbageImages) {
  const std::string yaml = "image: map.pgm\nresolution: 0.05\norigin: [0, 0, 0]\n";
  const std::string path = write(yaml);
  test::write_file(dir_.file("map.pgm"), std::string("P5\n4 3\n255\n") + std::string(7, 'x'));
  Outcome<OccupancyMapImage> m = load_map(path);
  ASSERT_FALSE(m.ok());
  EXPECT_THAT(m.error(), HasSubstr("map.yaml: image: "));
  EXPECT_THAT(m.error(), HasSubstr("map.pgm"));
  test::write_file(dir_.file("map.pgm"), std::string("this is not an image at all"));
  EXPECT_FALSE(load_map(path).ok());
  test::write_file(dir_.file("map.pgm"), std::string());
  EXPECT_FALSE(load_map(path).ok());
  test::write_file(dir_.file("map.pgm"), std::string("P5\n0 3\n255\n"));
  EXPECT_FALSE(load_map(path).ok());
  std::remove(dir_.file("map.pgm").c_str());
  m = load_map(path);
  ASSERT_FALSE(m.ok());
  EXPECT_THAT(m.error(), HasSubstr("map.pgm"));
  // A directory as the YAML file.
  EXPECT_FALSE(load_map(dir_.path()).ok());
}

OccupancyMapImage from_sim(const sim::OccupancyMap& t) {
  OccupancyMapImage m;
  m.resolution = t.resolution;
  m.origin_x = t.origin_x;
  m.origin_y = t.origin_y;
  m.width = t.width;
  m.height = t.height;
  for (uint8_t v : t.cells) {
    m.cells.push_back(v == sim::OccupancyMap::kFree       ? CellState::kFree
                      : v == sim::OccupancyMap::kOccupied ? CellState::kOccupied
                                                          : CellState::kUnknown);
  }
  return m;
}

void print_comparison(const char* name, const MapComparison& q) {
  std::printf(
      "[ figure   ] loop map, %s: accuracy %.4f over %llu explored cells (free/free %llu, "
      "free->occupied %llu, occupied->free %llu, occupied/occupied %llu; truth unknown "
      "%llu)\n",
      name, q.accuracy(), static_cast<unsigned long long>(q.scored()),
      static_cast<unsigned long long>(q.free_free),
      static_cast<unsigned long long>(q.free_occupied),
      static_cast<unsigned long long>(q.occupied_free),
      static_cast<unsigned long long>(q.occupied_occupied),
      static_cast<unsigned long long>(q.truth_unknown));
}

// The acceptance figure of issue 7 on the simulator: the core's grid built from the infrared
// readings of the ~90 m loop (a drive through a run's lab, with its people and moved chairs),
// scored against the static true map (what seqslam-sim writes) inside the explored area - with
// the true poses (the best a pose graph can do) and with dead-reckoned poses (no loop
// closure). Also scored against the run's own lab (people and chairs included), which
// separates what moved from mapping errors.
TEST(GridExport, SimulatedLoopMapQuality) {
  sim::LabOptions still;
  still.people = false;
  still.move_chairs = false;
  const sim::OccupancyMap true_map =
      sim::true_map(sim::build_lab(0, still), 0.05, sim::kInfraredHeight);
  const OccupancyMapImage truth = from_sim(true_map);
  const sim::World world = sim::build_lab(11);  // a run's lab: people, chairs moved
  const OccupancyMapImage run_truth = from_sim(sim::true_map(world, 0.05, sim::kInfraredHeight));
  sim::Rng rng(12);
  const std::vector<sim::DriveTick> ticks =
      sim::drive(sim::routes::loop(), sim::DriveOptions{}, world, rng);
  ASSERT_GT(ticks.size(), 10000u);

  GridConfig c;
  c.origin_x = metres(true_map.origin_x);
  c.origin_y = metres(true_map.origin_y);
  c.width = static_cast<uint16_t>(true_map.width);
  c.height = static_cast<uint16_t>(true_map.height);
  static OccupancyGridStorage<8> ram;
  for (int mode = 0; mode < 2; ++mode) {
    RamTileStore store;
    OccupancyGrid grid;
    ASSERT_EQ(grid.configure(c, ram.buffers(), store), Status::kOk);
    Odometry odometry;
    ASSERT_EQ(odometry.configure(OdometryConfig{}), Status::kOk);
    const sim::TruePose& t0 = ticks[0].truth;
    odometry.reset(Pose2{metres(t0.x), metres(t0.y), angle_from_radians(t0.heading)},
                   ticks[0].snapshot.encoder_left, ticks[0].snapshot.encoder_right);
    uint64_t echoes = 0;
    uint64_t readings = 0;
    for (size_t i = 0; i < ticks.size(); ++i) {
      const hal::SensorSnapshot& s = ticks[i].snapshot;
      ASSERT_LE(s.infrared_count, kMyonInfraredCount);
      if (i > 0) {
        ASSERT_EQ(odometry.update(s.encoder_left, s.encoder_right), Status::kOk);
      }
      if (i % 2 != 0) continue;  // every other snapshot (50 Hz) is plenty at <= 0.35 m/s
      const Pose2 pose = mode == 0 ? Pose2{metres(ticks[i].truth.x), metres(ticks[i].truth.y),
                                           angle_from_radians(ticks[i].truth.heading)}
                                   : odometry.pose();
      ASSERT_EQ(grid.insert_scan(pose, Span<const RangeSensor>(kMyonInfrared, s.infrared_count),
                                 Span<const uint16_t>(s.infrared_mm, s.infrared_count)),
                Status::kOk)
          << i;
      for (uint32_t k = 0; k < s.infrared_count; ++k)
        echoes += s.infrared_mm[k] != 0 ? 1 : 0;
      readings += s.infrared_count;
    }
    const Outcome<OccupancyMapImage> m = grid_map(grid);
    ASSERT_TRUE(m.ok()) << m.error();
    const Outcome<MapComparison> r = compare_maps(m.value(), truth);
    ASSERT_TRUE(r.ok()) << r.error();
    const Outcome<MapComparison> own = compare_maps(m.value(), run_truth);
    ASSERT_TRUE(own.ok()) << own.error();
    const MapComparison& q = r.value();
    print_comparison(
        mode == 0 ? "true poses vs static true map" : "dead reckoning vs static true map", q);
    print_comparison(mode == 0 ? "true poses vs the run's lab" : "dead reckoning vs the run's lab",
                     own.value());
    std::printf(
        "[ figure   ] loop map: %llu readings, %llu echoes, %u rays, %u cell updates, "
        "tile loads %u, saves %u (8 slots)\n",
        static_cast<unsigned long long>(readings), static_cast<unsigned long long>(echoes),
        grid.stats().rays, grid.stats().cells, grid.stats().tile_loads, grid.stats().tile_saves);
    EXPECT_GT(q.scored(), 20000u);
    if (mode == 0) {
      EXPECT_GE(q.accuracy(), 0.99);
      EXPECT_GE(own.value().accuracy(), q.accuracy());
      test::TempDir dir;
      std::string error;
      EXPECT_TRUE(save_map(m.value(), dir.file("loop"), &error)) << error;
    } else {
      EXPECT_GE(q.accuracy(), 0.95);
    }
  }
}

}  // namespace
}  // namespace seqslam::tools
