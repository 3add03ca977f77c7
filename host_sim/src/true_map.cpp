#include "seqslam_sim/true_map.h"

#include <cmath>
#include <cstdio>

#include "seqslam_tools/output_file.h"

namespace seqslam::sim {

OccupancyMap true_map(const World& world, double resolution, double height) {
  OccupancyMap m;
  m.resolution = resolution;
  const Area b = world.bounds();
  m.origin_x = std::floor(b.x0);
  m.origin_y = std::floor(b.y0);
  m.width = static_cast<int>(std::ceil((b.x1 - m.origin_x) / resolution));
  m.height = static_cast<int>(std::ceil((b.y1 - m.origin_y) / resolution));
  m.cells.assign(static_cast<size_t>(m.width) * static_cast<size_t>(m.height),
                 OccupancyMap::kUnknown);
  for (int y = 0; y < m.height; ++y) {
    for (int x = 0; x < m.width; ++x) {
      const double cx = m.origin_x + (x + 0.5) * resolution;
      const double cy = m.origin_y + (y + 0.5) * resolution;
      if (world.inside_areas(cx, cy)) m.cells[raster_index(x, y, m.width)] = OccupancyMap::kFree;
    }
  }
  for (const Box& box : world.boxes()) {
    if (!box.solid_ir || box.lo.z > height || box.hi.z < height) continue;
    const int x0 =
        std::max(0, static_cast<int>(std::floor((box.lo.x - m.origin_x) / resolution + 1e-9)));
    // Cells the box overlaps with positive area: a face on a cell boundary does not mark the
    // cell beyond it.
    const int x1 = std::min(
        m.width - 1,
        std::max(x0, static_cast<int>(std::ceil((box.hi.x - m.origin_x) / resolution - 1e-9)) - 1));
    const int y0 =
        std::max(0, static_cast<int>(std::floor((box.lo.y - m.origin_y) / resolution + 1e-9)));
    const int y1 = std::min(
        m.height - 1,
        std::max(y0, static_cast<int>(std::ceil((box.hi.y - m.origin_y) / resolution - 1e-9)) - 1));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x)
        m.cells[raster_index(x, y, m.width)] = OccupancyMap::kOccupied;
    }
  }
  return m;
}

std::string save_map(const OccupancyMap& m, const std::string& stem) {
  // Each file a temporary renamed over it (tools::OutputFile): every write checked.
  const std::string pgm = stem + ".pgm";
  tools::OutputFile f;
  std::string error = f.open(pgm);
  if (!error.empty()) return error;
  f.print("P5\n%d %d\n255\n", m.width, m.height);
  std::vector<uint8_t> row(static_cast<size_t>(m.width));
  for (int y = m.height - 1; y >= 0; --y) {  // image rows top-down = decreasing y
    for (int x = 0; x < m.width; ++x) {
      const OccupancyMap::Cell c = m.at(x, y);
      row[static_cast<size_t>(x)] = c == OccupancyMap::kOccupied ? 0
                                    : c == OccupancyMap::kFree   ? 254
                                                                 : 205;
    }
    f.write(row.data(), row.size());
  }
  error = f.commit();
  if (!error.empty()) return error;
  const std::string yaml = stem + ".yaml";
  error = f.open(yaml);
  if (!error.empty()) return error;
  const size_t slash = pgm.find_last_of('/');
  f.print(
      "image: %s\nresolution: %.3f\norigin: [%.3f, %.3f, 0.0]\nnegate: 0\n"
      "occupied_thresh: 0.65\nfree_thresh: 0.196\n",
      slash == std::string::npos ? pgm.c_str() : pgm.c_str() + slash + 1, m.resolution, m.origin_x,
      m.origin_y);
  return f.commit();
}

}  // namespace seqslam::sim
