// The true occupancy map (host_sim/include/seqslam_sim/true_map.h): rasterisation of a small
// world at the infrared sensors' height, and the ROS map_server files.
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "seqslam_sim/robot.h"
#include "seqslam_sim/true_map.h"
#include "seqslam_sim/world.h"
#include "sim_test_util.h"

namespace seqslam::sim {
namespace {

Box box(Vec3 lo, Vec3 hi, bool solid_ir = true) {
  Box b;
  b.lo = lo;
  b.hi = hi;
  b.solid_ir = solid_ir;
  return b;
}

struct Rect {
  double x0, y0, x1, y1;
};

// A 4 m x 3 m room (the area) with: an obstacle crossing the sensors' 12 cm plane, a shelf
// above it, a box the sensors do not see (glass), and a lamp far outside the room that only
// widens the bounds (so there is unknown space around the room). Edges avoid the 5 cm grid
// so every cell is clearly in or out.
constexpr Rect kRoom{0.0, 0.0, 4.0, 3.0};
constexpr Rect kObstacle{1.01, 1.02, 1.49, 1.18};
constexpr Rect kShelf{2.02, 2.02, 2.48, 2.48};
constexpr Rect kGlass{3.02, 0.52, 3.28, 0.78};

World small_world() {
  World w(3.0);
  w.add_area(Area{kRoom.x0, kRoom.y0, kRoom.x1, kRoom.y1});
  w.add(box(Vec3{kObstacle.x0, kObstacle.y0, 0.0}, Vec3{kObstacle.x1, kObstacle.y1, 0.5}));
  w.add(box(Vec3{kShelf.x0, kShelf.y0, 1.0}, Vec3{kShelf.x1, kShelf.y1, 2.0}));
  w.add(box(Vec3{kGlass.x0, kGlass.y0, 0.0}, Vec3{kGlass.x1, kGlass.y1, 1.0}, false));
  w.add(box(Vec3{-0.52, -0.52, 2.9}, Vec3{-0.48, -0.48, 3.0}));
  w.add(box(Vec3{5.02, 4.02, 2.9}, Vec3{5.08, 4.08, 3.0}));
  return w;
}

// Whether cell (x, y) of `m` overlaps `r` (with positive area).
bool overlaps(const OccupancyMap& m, int x, int y, const Rect& r) {
  const double cx0 = m.origin_x + x * m.resolution;
  const double cy0 = m.origin_y + y * m.resolution;
  return cx0 < r.x1 && cx0 + m.resolution > r.x0 && cy0 < r.y1 && cy0 + m.resolution > r.y0;
}

TEST(SimTrueMap, CellsOccupiedFreeUnknown) {
  const World w = small_world();
  const OccupancyMap m = true_map(w, 0.05, kInfraredHeight);
  EXPECT_EQ(m.resolution, 0.05);
  EXPECT_EQ(m.origin_x, -1.0);  // floor of the bounds
  EXPECT_EQ(m.origin_y, -1.0);
  ASSERT_GE(m.origin_x + m.width * m.resolution, 5.08 - 1e-9);
  ASSERT_GE(m.origin_y + m.height * m.resolution, 4.08 - 1e-9);
  ASSERT_EQ(m.cells.size(), static_cast<size_t>(m.width) * static_cast<size_t>(m.height));
  int occupied = 0, free_cells = 0, unknown = 0, wrong = 0;
  for (int y = 0; y < m.height; ++y) {
    for (int x = 0; x < m.width; ++x) {
      const double cx = m.origin_x + (x + 0.5) * m.resolution;
      const double cy = m.origin_y + (y + 0.5) * m.resolution;
      OccupancyMap::Cell want = OccupancyMap::kUnknown;
      if (overlaps(m, x, y, kObstacle)) {
        want = OccupancyMap::kOccupied;
      } else if (cx > kRoom.x0 && cx < kRoom.x1 && cy > kRoom.y0 && cy < kRoom.y1) {
        want = OccupancyMap::kFree;  // including under the shelf and at the glass box
      }
      const OccupancyMap::Cell got = m.at(x, y);
      if (got != want && ++wrong <= 5) {
        ADD_FAILURE() << "cell (" << x << ", " << y << ") at (" << cx << ", " << cy
                      << "): " << int{got} << ", expected " << int{want};
      }
      occupied += got == OccupancyMap::kOccupied;
      free_cells += got == OccupancyMap::kFree;
      unknown += got == OccupancyMap::kUnknown;
    }
  }
  EXPECT_EQ(wrong, 0);
  // 1.00..1.50 x 1.00..1.20: 10 x 4 cells.
  EXPECT_EQ(occupied, 40);
  EXPECT_EQ(free_cells, 80 * 60 - 40);
  EXPECT_GT(unknown, 0);
}

TEST(SimTrueMap, FacesOnCellBoundariesMarkOnlyTheCellsInside) {
  // Box faces exactly on the 5 cm grid (origin -1): 1.00..1.50 x 2.00..2.20 overlaps 10 x 4
  // cells with positive area; the cells beyond its faces stay free, whatever the rounding
  // of (face - origin) / resolution.
  World w(3.0);
  w.add_area(Area{0.0, 0.0, 4.0, 3.0});
  w.add(box(Vec3{1.0, 2.0, 0.0}, Vec3{1.5, 2.2, 0.5}));
  w.add(box(Vec3{-0.52, -0.52, 2.9}, Vec3{-0.48, -0.48, 3.0}));  // bounds: lamps outside
  w.add(box(Vec3{5.02, 4.02, 2.9}, Vec3{5.08, 4.08, 3.0}));
  const OccupancyMap m = true_map(w, 0.05, kInfraredHeight);
  ASSERT_EQ(m.origin_x, -1.0);
  ASSERT_EQ(m.origin_y, -1.0);
  ASSERT_GT(m.width, 60);
  ASSERT_GT(m.height, 70);
  int occupied = 0;
  for (const uint8_t c : m.cells)
    occupied += c == OccupancyMap::kOccupied;
  EXPECT_EQ(occupied, 40);
  // Cells (40..49, 60..63) are the box; (39, 60), (50, 60), (40, 59), (40, 64) are not.
  EXPECT_EQ(m.at(40, 60), OccupancyMap::kOccupied);
  EXPECT_EQ(m.at(49, 63), OccupancyMap::kOccupied);
  EXPECT_EQ(m.at(39, 60), OccupancyMap::kFree);
  EXPECT_EQ(m.at(50, 60), OccupancyMap::kFree);
  EXPECT_EQ(m.at(40, 59), OccupancyMap::kFree);
  EXPECT_EQ(m.at(40, 64), OccupancyMap::kFree);
}

TEST(SimTrueMap, SavedAsRosMap) {
  const World w = small_world();
  const OccupancyMap m = true_map(w, 0.05, kInfraredHeight);
  test::ScratchDir dir;
  const std::string stem = dir.path() + "/lab_map";
  ASSERT_EQ(save_map(m, stem), "");

  bool ok = false;
  const std::vector<char> pgm = test::read_bytes(stem + ".pgm", &ok);
  ASSERT_TRUE(ok);
  const std::string header =
      "P5\n" + std::to_string(m.width) + " " + std::to_string(m.height) + "\n255\n";
  ASSERT_EQ(pgm.size(),
            header.size() + static_cast<size_t>(m.width) * static_cast<size_t>(m.height));
  ASSERT_EQ(std::string(pgm.begin(), pgm.begin() + static_cast<std::ptrdiff_t>(header.size())),
            header);
  int counts[3] = {0, 0, 0};
  for (int y = 0; y < m.height; ++y) {
    for (int x = 0; x < m.width; ++x) {
      // Image rows run top-down: row 0 is the highest y.
      const size_t at = header.size() + raster_index(x, m.height - 1 - y, m.width);
      const auto value = static_cast<uint8_t>(pgm[at]);
      const OccupancyMap::Cell c = m.at(x, y);
      const uint8_t want = c == OccupancyMap::kOccupied ? 0 : c == OccupancyMap::kFree ? 254 : 205;
      ASSERT_EQ(value, want) << "cell (" << x << ", " << y << ")";
      ++counts[c];
    }
  }
  EXPECT_EQ(counts[OccupancyMap::kOccupied], 40);
  EXPECT_GT(counts[OccupancyMap::kFree], 0);
  EXPECT_GT(counts[OccupancyMap::kUnknown], 0);

  std::ifstream yaml(stem + ".yaml");
  ASSERT_TRUE(yaml);
  std::string line, image;
  double resolution = 0.0, ox = 1e9, oy = 1e9, oz = 1e9;
  int negate = -1;
  while (std::getline(yaml, line)) {
    char buf[256] = {};
    if (std::sscanf(line.c_str(), "image: %255s", buf) == 1) image = buf;
    std::sscanf(line.c_str(), "resolution: %lf", &resolution);
    std::sscanf(line.c_str(), "origin: [%lf, %lf, %lf]", &ox, &oy, &oz);
    std::sscanf(line.c_str(), "negate: %d", &negate);
  }
  EXPECT_EQ(image, "lab_map.pgm");  // relative to the YAML file
  EXPECT_NEAR(resolution, 0.05, 1e-9);
  EXPECT_NEAR(ox, -1.0, 1e-9);
  EXPECT_NEAR(oy, -1.0, 1e-9);
  EXPECT_NEAR(oz, 0.0, 1e-9);
  EXPECT_EQ(negate, 0);

  EXPECT_NE(save_map(m, dir.path() + "/missing/lab_map"), "");
}

}  // namespace
}  // namespace seqslam::sim
