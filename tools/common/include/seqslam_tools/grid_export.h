// Occupancy grid maps on the PC: export of the core's OccupancyGrid in the ROS map_server
// convention, loading such maps (e.g. the simulator's true map, host_sim true_map.h), and the
// map-quality figure of issue 7: the fraction of correctly classified cells inside the area
// the grid has explored, and occupied-cell precision and recall near the robot's path.
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

// Obstacles near a path (issue 16): occupied-cell precision and recall of a grid map against a
// true map over the cells near the robot's true path, where a navigating robot needs them.
//
// The band: the true map's cells whose centre lies within `band_m` of the path, a polyline
// through the poses in order. Consecutive poses are joined by a segment when they belong to
// the same run and lie at most kPathMaxStep apart (a kidnap or a new run starts a new piece;
// a pose alone in its piece is a point). Only band cells the truth knows (free or occupied)
// are scored; the grid's cells are read at the same world position (origins a whole number
// of cells apart, as compare_maps), outside the grid counting as unknown.
//
// One binary question per scored cell: does the grid call it occupied? Cells the grid leaves
// unknown (or calls free) are "not occupied": they count against recall (a wall not seen is
// a wall missed), never against precision, and as correct for a truly free cell in the true
// negative rate. So
//   precision          = TP / grid_occupied                    (TP = both occupied)
//   recall             = TP / truth_occupied
//   balanced accuracy  = (recall + TN / truth_free) / 2         (TN = truly free, grid not
//                                                                 occupied)
// The "within one cell" pair forgives a wall drawn one cell off: a grid-occupied band cell is
// right when a truly occupied cell is in its 3 x 3 neighbourhood, a truly occupied band cell
// is found when a grid-occupied cell is in its neighbourhood (neighbours may lie outside the
// band). A rate whose denominator is 0 is 0.
struct PathPoint {
  double x = 0, y = 0;  // metres, the true map's world frame
  uint32_t run = 0;
};
inline constexpr double kPathMaxStep = 1.0;  // metres; a longer step is a jump, not driven

struct NearPathComparison {
  uint64_t cells = 0;                     // band cells the truth knows (scored)
  uint64_t truth_occupied = 0;            // of them truly occupied (the rest truly free)
  uint64_t grid_occupied = 0;             // of them called occupied by the grid
  uint64_t grid_free = 0;                 // called free (the rest: unknown to the grid)
  uint64_t occupied_occupied = 0;         // TP: truly occupied and called occupied
  uint64_t grid_occupied_near_truth = 0;  // called occupied, truly occupied cell within 1 cell
  uint64_t truth_occupied_near_grid = 0;  // truly occupied, called-occupied cell within 1 cell

  uint64_t truth_free() const { return cells - truth_occupied; }
  uint64_t grid_unknown() const { return cells - grid_occupied - grid_free; }
  double precision() const;
  double recall() const;
  double true_negative_rate() const;
  double balanced_accuracy() const;
  double precision_within_cell() const;
  double recall_within_cell() const;
  // The counts can come from one comparison (each part no larger than its whole).
  bool consistent() const;
};
bool operator==(const NearPathComparison& a, const NearPathComparison& b);

// Compares `grid` with `truth` in the band of `band_m` (> 0, finite) metres round `path`.
// Errors: as compare_maps for the geometry; a band that is not a positive finite number; a
// pose that is not finite. An empty path gives an empty band (all counts 0).
Outcome<NearPathComparison> compare_maps_near_path(const OccupancyMapImage& grid,
                                                   const OccupancyMapImage& truth,
                                                   const std::vector<PathPoint>& path,
                                                   double band_m);

}  // namespace seqslam::tools
