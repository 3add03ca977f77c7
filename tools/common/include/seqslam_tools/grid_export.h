// Occupancy grid maps on the PC: export of the core's OccupancyGrid in the ROS map_server
// convention, loading such maps (e.g. the simulator's true map, host_sim true_map.h), and the
// map-quality figure of issue 7: the fraction of correctly classified cells inside the area
// the grid has explored.
//
// map_server convention, as written here:
//   <stem>.pgm   binary PGM (P5, maxval 255), one byte per cell, the FIRST image row is the
//                TOP of the map (highest y); 254 free, 0 occupied, 205 unknown;
//   <stem>.yaml  image: <stem file name>.pgm
//                resolution: <metres per cell>
//                origin: [<x>, <y>, 0.0]     (the lower-left corner of the bottom-left cell)
//                negate: 0
//                occupied_thresh: 0.65
//                free_thresh: 0.196
// Reading (load_map) follows map_server's trinary interpretation: with negate 0 a pixel v has
// occupancy p = (255 - v) / 255 (negate 1: v / 255); occupied if p > occupied_thresh, free if
// p < free_thresh, unknown otherwise. So 0 is occupied, 254 free and 205 (p = 0.19608, just
// above 0.196) unknown, and maps from other tools (PNG too) read the way ROS reads them.
#pragma once

#include <stdint.h>

#include <string>
#include <vector>

#include "seqslam/occupancy_grid.h"
#include "seqslam_tools/outcome.h"

namespace seqslam::tools {

// A classified map in world order: cell (x, y) covers [origin_x + x res, origin_x + (x+1) res)
// x [same for y]; row 0 is the LOWEST y (the file's last image row).
struct OccupancyMapImage {
  double resolution = 0.05;  // metres per cell, > 0
  double origin_x = 0.0;     // metres
  double origin_y = 0.0;
  int width = 0;
  int height = 0;
  std::vector<CellState> cells;  // width * height, row-major from the lowest y

  CellState at(int x, int y) const {
    return cells[static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x)];
  }
};

// Largest side of a map load_map accepts (cells); larger headers are treated as corrupt.
inline constexpr int kMaxMapSide = 16384;

// The grid's classification of every cell inside its bounds, through copy_tile (resident tiles
// from RAM, the others from its TileStore; the grid's slots are not changed). Resolution and
// origin from the grid's configuration. Errors: not configured, or a store error (naming the
// tile and the status).
Outcome<OccupancyMapImage> grid_map(const OccupancyGrid& grid);

// Writes <stem>.pgm and <stem>.yaml as described above (the YAML names the PGM by its file
// name, so the pair can be moved together). False with a message naming the file on failure
// (and for an empty or inconsistent map).
bool save_map(const OccupancyMapImage& map, const std::string& stem, std::string* error);

// Reads a map_server YAML file and the image it names (a relative name is taken relative to
// the YAML file's directory). Keys image, resolution and origin are required; negate (0 or 1,
// default 0), occupied_thresh (default 0.65), free_thresh (default 0.196) and mode (only
// "trinary") are optional; other keys are ignored. Errors name the file (and the line):
// missing file, missing or repeated key, a value that is not a number / not in range (origin
// must be [x, y, yaw] with finite numbers, resolution > 0, 0 <= free_thresh <=
// occupied_thresh <= 1), an unreadable, truncated or garbage image (image_io's loader), or a
// side beyond kMaxMapSide.
Outcome<OccupancyMapImage> load_map(const std::string& yaml_path);

// Confusion of a grid map against a true map, counted over the cells the GRID classifies
// free or occupied (the explored area); the truth's unknown cells (outside the floor areas,
// or outside the true map's extent) are counted apart and not scored.
struct MapComparison {
  uint64_t free_free = 0;          // truth free, grid free
  uint64_t free_occupied = 0;      // truth free, grid occupied (a phantom obstacle)
  uint64_t occupied_free = 0;      // truth occupied, grid free (a missed obstacle)
  uint64_t occupied_occupied = 0;  // truth occupied, grid occupied
  uint64_t truth_unknown = 0;      // grid known, truth unknown: not scored
  uint64_t grid_unknown = 0;       // truth known, grid unknown: not explored (not scored)

  uint64_t scored() const { return free_free + free_occupied + occupied_free + occupied_occupied; }
  // (free_free + occupied_occupied) / scored(); 0 when nothing is scored.
  double accuracy() const;
};

// Compares `grid` with `truth`. The resolutions must agree (relative 1e-9) and the origins
// must differ by a whole number of cells (to 1e-6 cell); otherwise an error. Grid cells
// outside the truth's extent count as truth unknown.
Outcome<MapComparison> compare_maps(const OccupancyMapImage& grid, const OccupancyMapImage& truth);

}  // namespace seqslam::tools
