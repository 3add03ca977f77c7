// The true occupancy map of the lab, for judging the grid maps built from the infrared
// sensors: cells inside the building's floor areas are free unless a box that the infrared
// sensors can see (solid_ir) crosses the sensors' height plane there; everything else is
// unknown. Saved in the ROS map_server convention (PGM: 0 occupied, 254 free, 205 unknown,
// plus a YAML file with resolution and origin).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "seqslam_sim/world.h"

namespace seqslam::sim {

struct OccupancyMap {
  enum Cell : uint8_t { kUnknown = 0, kFree = 1, kOccupied = 2 };
  double resolution = 0.05;  // metres per cell
  double origin_x = 0.0;     // world coordinates of cell (0, 0)'s lower-left corner
  double origin_y = 0.0;
  int width = 0;
  int height = 0;
  std::vector<uint8_t> cells;  // row 0 = lowest y
  Cell at(int x, int y) const { return static_cast<Cell>(cells[raster_index(x, y, width)]); }
};

// Rasterises `world` at `height` above the floor (the infrared sensors' plane).
OccupancyMap true_map(const World& world, double resolution, double height);

// Writes <stem>.pgm and <stem>.yaml. Returns "" or an error.
std::string save_map(const OccupancyMap& map, const std::string& stem);

}  // namespace seqslam::sim
