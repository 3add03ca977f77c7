// Export, loading and comparison of occupancy grid maps (ROS map_server convention).
#include "seqslam_tools/grid_export.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <vector>

#include "file_util.h"
#include "seqslam_tools/image_io.h"
#include "seqslam_tools/q_format.h"

namespace seqslam::tools {

namespace {

constexpr uint64_t kMaxYamlBytes = uint64_t{1} << 20;

// map_server's trinary values.
constexpr uint8_t kPgmFree = 254;
constexpr uint8_t kPgmOccupied = 0;
constexpr uint8_t kPgmUnknown = 205;

bool valid_map(const OccupancyMapImage& m) {
  return m.width > 0 && m.height > 0 && m.width <= kMaxMapSide && m.height <= kMaxMapSide &&
         m.cells.size() == static_cast<size_t>(m.width) * static_cast<size_t>(m.height) &&
         std::isfinite(m.resolution) && m.resolution > 0.0 && std::isfinite(m.origin_x) &&
         std::isfinite(m.origin_y);
}

// A double from the whole of `text` (no sign-less junk, no trailing characters), finite.
bool parse_double(std::string_view text, double* out) {
  text = detail::trim(text);
  if (text.empty()) return false;
  if (text.front() == '+') text.remove_prefix(1);  // from_chars rejects a leading '+'
  double v = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

// The value without a surrounding pair of quotes ('...' or "...").
std::string_view unquote(std::string_view v) {
  if (v.size() >= 2 && (v.front() == '"' || v.front() == '\'') && v.back() == v.front()) {
    return v.substr(1, v.size() - 2);
  }
  return v;
}

// Strips a '#' comment that is not inside quotes.
std::string_view strip_comment(std::string_view line) {
  char quote = 0;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quote != 0) {
      if (c == quote) quote = 0;
    } else if (c == '"' || c == '\'') {
      quote = c;
    } else if (c == '#') {
      return line.substr(0, i);
    }
  }
  return line;
}

std::string directory_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  if (slash == std::string::npos) return "";
  return path.substr(0, slash + 1);
}

std::string file_name_of(const std::string& path) {
  const size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

std::string format_double(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.9g", v);
  return buf;
}

struct YamlField {
  std::string value;
  size_t line = 0;
  bool present = false;
};

}  // namespace

double MapComparison::accuracy() const {
  const uint64_t n = scored();
  if (n == 0) return 0.0;
  return static_cast<double>(free_free + occupied_occupied) / static_cast<double>(n);
}

Outcome<OccupancyMapImage> grid_map(const OccupancyGrid& grid) {
  if (!grid.configured()) return Error{"occupancy grid: not configured"};
  const GridConfig& c = grid.config();
  OccupancyMapImage m;
  m.resolution = c.cell_mm / 1000.0;
  m.origin_x = to_double(c.origin_x);
  m.origin_y = to_double(c.origin_y);
  m.width = c.width;
  m.height = c.height;
  m.cells.assign(static_cast<size_t>(m.width) * static_cast<size_t>(m.height), CellState::kUnknown);
  std::vector<int8_t> tile(kGridTileCells);
  for (uint16_t ty = 0; ty < grid.tiles_y(); ++ty) {
    for (uint16_t tx = 0; tx < grid.tiles_x(); ++tx) {
      const Status s = grid.copy_tile(GridTile{tx, ty}, Span<int8_t>(tile.data(), tile.size()));
      if (s != Status::kOk) {
        return Error{"occupancy grid: tile (" + std::to_string(tx) + ", " + std::to_string(ty) +
                     "): " + status_name(s)};
      }
      for (uint32_t r = 0; r < kGridTileSide; ++r) {
        const uint32_t y = ty * kGridTileSide + r;
        if (y >= c.height) break;
        for (uint32_t col = 0; col < kGridTileSide; ++col) {
          const uint32_t x = tx * kGridTileSide + col;
          if (x >= c.width) break;
          m.cells[static_cast<size_t>(y) * c.width + x] =
              grid.classify(tile[r * kGridTileSide + col]);
        }
      }
    }
  }
  return m;
}

bool save_map(const OccupancyMapImage& map, const std::string& stem, std::string* error) {
  const std::string pgm = stem + ".pgm";
  if (!valid_map(map)) {
    detail::set_error(error, pgm + ": the map is empty or inconsistent (size, resolution)");
    return false;
  }
  GrayImage image;
  image.width = map.width;
  image.height = map.height;
  image.pixels.resize(map.cells.size());
  for (int y = 0; y < map.height; ++y) {
    const size_t row = static_cast<size_t>(map.height - 1 - y) * static_cast<size_t>(map.width);
    for (int x = 0; x < map.width; ++x) {
      const CellState s = map.at(x, y);
      image.pixels[row + static_cast<size_t>(x)] = s == CellState::kOccupied ? kPgmOccupied
                                                   : s == CellState::kFree   ? kPgmFree
                                                                             : kPgmUnknown;
    }
  }
  if (!save_pgm(pgm, image, error)) return false;
  const std::string yaml = "image: " + file_name_of(pgm) +
                           "\nresolution: " + format_double(map.resolution) + "\norigin: [" +
                           format_double(map.origin_x) + ", " + format_double(map.origin_y) +
                           ", 0.0]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\n";
  return detail::write_file_bytes(stem + ".yaml", yaml.data(), yaml.size(), error);
}

Outcome<OccupancyMapImage> load_map(const std::string& yaml_path) {
  Outcome<std::string> text = detail::read_file_text(yaml_path, kMaxYamlBytes);
  if (!text.ok()) return Error{text.error()};
  const char* const kKeys[] = {"image",           "resolution",  "origin", "negate",
                               "occupied_thresh", "free_thresh", "mode"};
  constexpr size_t kKeyCount = sizeof(kKeys) / sizeof(kKeys[0]);
  YamlField fields[kKeyCount];
  const std::vector<std::string_view> lines = detail::split_lines(text.value());
  for (size_t i = 0; i < lines.size(); ++i) {
    const std::string where = yaml_path + ":" + std::to_string(i + 1) + ": ";
    const std::string_view line = detail::trim(strip_comment(lines[i]));
    if (line.empty() || line == "---") continue;
    const size_t colon = line.find(':');
    if (colon == std::string_view::npos) {
      return Error{where + "expected 'key: value', found '" + detail::printable(line) + "'"};
    }
    const std::string_view key = detail::trim(line.substr(0, colon));
    const std::string_view value = detail::trim(line.substr(colon + 1));
    for (size_t k = 0; k < kKeyCount; ++k) {
      if (key != kKeys[k]) continue;
      if (fields[k].present) return Error{where + "key '" + std::string(key) + "' repeated"};
      fields[k] = YamlField{std::string(unquote(value)), i + 1, true};
    }
  }
  for (size_t k = 0; k < 3; ++k) {
    if (!fields[k].present) {
      return Error{yaml_path + ": missing key '" + kKeys[k] + "' (a map_server map needs image, " +
                   "resolution and origin)"};
    }
  }
  const auto at_line = [&](size_t k) {
    return yaml_path + ":" + std::to_string(fields[k].line) + ": ";
  };
  OccupancyMapImage m;
  if (fields[0].value.empty()) return Error{at_line(0) + "image is empty"};
  if (!parse_double(fields[1].value, &m.resolution) || m.resolution <= 0.0) {
    return Error{at_line(1) + "resolution must be a number > 0, found '" +
                 detail::printable(fields[1].value) + "'"};
  }
  {
    std::string_view o = detail::trim(fields[2].value);
    std::vector<double> numbers;
    bool ok = o.size() >= 2 && o.front() == '[' && o.back() == ']';
    if (ok) {
      o = o.substr(1, o.size() - 2);
      while (ok) {
        const size_t comma = o.find(',');
        double v = 0.0;
        ok = parse_double(o.substr(0, comma), &v);
        if (ok) numbers.push_back(v);
        if (comma == std::string_view::npos) break;
        o.remove_prefix(comma + 1);
      }
    }
    if (!ok || numbers.size() != 3) {
      return Error{at_line(2) + "origin must be [x, y, yaw] with three numbers, found '" +
                   detail::printable(fields[2].value) + "'"};
    }
    m.origin_x = numbers[0];
    m.origin_y = numbers[1];
  }
  int negate = 0;
  if (fields[3].present) {
    if (fields[3].value != "0" && fields[3].value != "1") {
      return Error{at_line(3) + "negate must be 0 or 1, found '" +
                   detail::printable(fields[3].value) + "'"};
    }
    negate = fields[3].value == "1" ? 1 : 0;
  }
  double occupied_thresh = 0.65;
  double free_thresh = 0.196;
  if (fields[4].present && !parse_double(fields[4].value, &occupied_thresh)) {
    return Error{at_line(4) + "occupied_thresh must be a number, found '" +
                 detail::printable(fields[4].value) + "'"};
  }
  if (fields[5].present && !parse_double(fields[5].value, &free_thresh)) {
    return Error{at_line(5) + "free_thresh must be a number, found '" +
                 detail::printable(fields[5].value) + "'"};
  }
  if (free_thresh < 0.0 || occupied_thresh > 1.0 || free_thresh > occupied_thresh) {
    return Error{yaml_path + ": thresholds must satisfy 0 <= free_thresh <= occupied_thresh <= 1"};
  }
  if (fields[6].present && fields[6].value != "trinary") {
    return Error{at_line(6) + "only mode 'trinary' is supported, found '" +
                 detail::printable(fields[6].value) + "'"};
  }
  const std::string& image_name = fields[0].value;
  const std::string image_path =
      image_name.front() == '/' ? image_name : directory_of(yaml_path) + image_name;
  LoadedImage image = load_gray(image_path);
  if (!image.ok()) return Error{yaml_path + ": image: " + image.error()};
  const GrayImage& g = image.value();
  if (g.width > kMaxMapSide || g.height > kMaxMapSide) {
    return Error{image_path + ": larger than " + std::to_string(kMaxMapSide) + " cells a side"};
  }
  m.width = g.width;
  m.height = g.height;
  m.cells.resize(static_cast<size_t>(m.width) * static_cast<size_t>(m.height));
  for (int r = 0; r < g.height; ++r) {
    const int y = g.height - 1 - r;  // the first image row is the top of the map
    for (int x = 0; x < g.width; ++x) {
      const double v = g.at(x, r);
      const double p = negate != 0 ? v / 255.0 : (255.0 - v) / 255.0;
      const CellState s = p > occupied_thresh ? CellState::kOccupied
                          : p < free_thresh   ? CellState::kFree
                                              : CellState::kUnknown;
      m.cells[static_cast<size_t>(y) * static_cast<size_t>(m.width) + static_cast<size_t>(x)] = s;
    }
  }
  return m;
}

namespace {

// Truth cell of grid cell (x, y): (x + dx, y + dy). Both maps valid, one resolution, origins a
// whole number of cells apart; otherwise an error ("compare maps: ...").
std::string cell_offset(const OccupancyMapImage& grid, const OccupancyMapImage& truth, long* dx,
                        long* dy) {
  if (!valid_map(grid)) return "compare maps: the grid map is empty or inconsistent";
  if (!valid_map(truth)) return "compare maps: the true map is empty or inconsistent";
  const double res = truth.resolution;
  if (std::fabs(grid.resolution - res) > 1e-9 * res) {
    return "compare maps: resolutions differ (grid " + format_double(grid.resolution) +
           " m, truth " + format_double(res) + " m)";
  }
  const double fx = (grid.origin_x - truth.origin_x) / res;
  const double fy = (grid.origin_y - truth.origin_y) / res;
  const double ox = std::round(fx);
  const double oy = std::round(fy);
  if (std::fabs(fx - ox) > 1e-6 || std::fabs(fy - oy) > 1e-6 || std::fabs(ox) > 1e9 ||
      std::fabs(oy) > 1e9) {
    return "compare maps: the origins are not a whole number of cells apart (grid [" +
           format_double(grid.origin_x) + ", " + format_double(grid.origin_y) + "], truth [" +
           format_double(truth.origin_x) + ", " + format_double(truth.origin_y) + "])";
  }
  *dx = static_cast<long>(ox);
  *dy = static_cast<long>(oy);
  return "";
}

}  // namespace

Outcome<MapComparison> compare_maps(const OccupancyMapImage& grid, const OccupancyMapImage& truth) {
  long dx = 0, dy = 0;
  if (std::string e = cell_offset(grid, truth, &dx, &dy); !e.empty()) return Error{e};
  const auto truth_at = [&](long x, long y) {
    if (x < 0 || y < 0 || x >= truth.width || y >= truth.height) return CellState::kUnknown;
    return truth.at(static_cast<int>(x), static_cast<int>(y));
  };
  const auto grid_at = [&](long x, long y) {
    if (x < 0 || y < 0 || x >= grid.width || y >= grid.height) return CellState::kUnknown;
    return grid.at(static_cast<int>(x), static_cast<int>(y));
  };
  MapComparison c;
  for (int y = 0; y < grid.height; ++y) {
    for (int x = 0; x < grid.width; ++x) {
      const CellState g = grid.at(x, y);
      if (g == CellState::kUnknown) continue;
      const CellState t = truth_at(x + dx, y + dy);
      if (t == CellState::kUnknown) {
        ++c.truth_unknown;
      } else if (t == CellState::kFree) {
        ++(g == CellState::kFree ? c.free_free : c.free_occupied);
      } else {
        ++(g == CellState::kFree ? c.occupied_free : c.occupied_occupied);
      }
    }
  }
  for (int y = 0; y < truth.height; ++y) {
    for (int x = 0; x < truth.width; ++x) {
      if (truth.at(x, y) != CellState::kUnknown && grid_at(x - dx, y - dy) == CellState::kUnknown) {
        ++c.grid_unknown;
      }
    }
  }
  return c;
}

namespace {

double ratio(uint64_t part, uint64_t whole) {
  return whole == 0 ? 0.0 : static_cast<double>(part) / static_cast<double>(whole);
}

// Distance from p to the segment a-b (a point when a == b).
double segment_distance(double px, double py, const PathPoint& a, const PathPoint& b) {
  const double vx = b.x - a.x, vy = b.y - a.y;
  const double len2 = vx * vx + vy * vy;
  double t = len2 > 0 ? ((px - a.x) * vx + (py - a.y) * vy) / len2 : 0.0;
  t = std::min(1.0, std::max(0.0, t));
  return std::hypot(px - (a.x + t * vx), py - (a.y + t * vy));
}

// The band: 1 for every cell of `m` whose centre is within `band` of a piece of the path.
std::vector<uint8_t> path_band(const OccupancyMapImage& m, const std::vector<PathPoint>& path,
                               double band) {
  std::vector<uint8_t> in(m.cells.size(), 0);
  const double res = m.resolution;
  const auto mark = [&](const PathPoint& a, const PathPoint& b) {
    // Cells whose centre can be within reach: the segment's box grown by the band.
    const auto first = [&](double w, double origin) {
      return std::floor((w - band - origin) / res - 0.5);
    };
    const auto last = [&](double w, double origin) {
      return std::ceil((w + band - origin) / res - 0.5);
    };
    const double x0 = std::max(0.0, first(std::min(a.x, b.x), m.origin_x));
    const double x1 = std::min(m.width - 1.0, last(std::max(a.x, b.x), m.origin_x));
    const double y0 = std::max(0.0, first(std::min(a.y, b.y), m.origin_y));
    const double y1 = std::min(m.height - 1.0, last(std::max(a.y, b.y), m.origin_y));
    for (double y = y0; y <= y1; ++y) {
      for (double x = x0; x <= x1; ++x) {
        const double cx = m.origin_x + (x + 0.5) * res, cy = m.origin_y + (y + 0.5) * res;
        if (segment_distance(cx, cy, a, b) <= band) {
          in[static_cast<size_t>(y) * static_cast<size_t>(m.width) + static_cast<size_t>(x)] = 1;
        }
      }
    }
  };
  for (size_t i = 0; i < path.size(); ++i) {
    const bool joined =
        i > 0 && path[i - 1].run == path[i].run &&
        std::hypot(path[i].x - path[i - 1].x, path[i].y - path[i - 1].y) <= kPathMaxStep;
    const bool alone = !joined && (i + 1 == path.size() || path[i + 1].run != path[i].run ||
                                   std::hypot(path[i + 1].x - path[i].x,
                                              path[i + 1].y - path[i].y) > kPathMaxStep);
    if (joined) mark(path[i - 1], path[i]);
    if (alone) mark(path[i], path[i]);
  }
  return in;
}

}  // namespace

double NearPathComparison::precision() const {
  return ratio(occupied_occupied, grid_occupied);
}
double NearPathComparison::recall() const {
  return ratio(occupied_occupied, truth_occupied);
}
double NearPathComparison::true_negative_rate() const {
  // Truly free cells the grid does not call occupied (free or unknown).
  return ratio(truth_free() - (grid_occupied - occupied_occupied), truth_free());
}
double NearPathComparison::balanced_accuracy() const {
  return (recall() + true_negative_rate()) / 2;
}
double NearPathComparison::precision_within_cell() const {
  return ratio(grid_occupied_near_truth, grid_occupied);
}
double NearPathComparison::recall_within_cell() const {
  return ratio(truth_occupied_near_grid, truth_occupied);
}

bool NearPathComparison::consistent() const {
  return truth_occupied <= cells && grid_occupied <= cells && grid_free <= cells - grid_occupied &&
         occupied_occupied <= std::min(truth_occupied, grid_occupied) &&
         grid_occupied - occupied_occupied <= cells - truth_occupied &&
         grid_occupied_near_truth >= occupied_occupied &&
         grid_occupied_near_truth <= grid_occupied &&
         truth_occupied_near_grid >= occupied_occupied &&
         truth_occupied_near_grid <= truth_occupied;
}

bool operator==(const NearPathComparison& a, const NearPathComparison& b) {
  return a.cells == b.cells && a.truth_occupied == b.truth_occupied &&
         a.grid_occupied == b.grid_occupied && a.grid_free == b.grid_free &&
         a.occupied_occupied == b.occupied_occupied &&
         a.grid_occupied_near_truth == b.grid_occupied_near_truth &&
         a.truth_occupied_near_grid == b.truth_occupied_near_grid;
}

Outcome<NearPathComparison> compare_maps_near_path(const OccupancyMapImage& grid,
                                                   const OccupancyMapImage& truth,
                                                   const std::vector<PathPoint>& path,
                                                   double band_m) {
  long dx = 0, dy = 0;
  if (std::string e = cell_offset(grid, truth, &dx, &dy); !e.empty()) return Error{e};
  if (!std::isfinite(band_m) || band_m <= 0) {
    return Error{"compare maps near the path: the band must be a positive number of metres"};
  }
  for (const PathPoint& p : path) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y))
      return Error{"compare maps near the path: a pose is not finite"};
  }
  const auto occupied = [](const OccupancyMapImage& m, long x, long y) {
    return x >= 0 && y >= 0 && x < m.width && y < m.height &&
           m.at(static_cast<int>(x), static_cast<int>(y)) == CellState::kOccupied;
  };
  // Any occupied cell of `m` in the 3 x 3 block round (x, y).
  const auto occupied_near = [&](const OccupancyMapImage& m, long x, long y) {
    for (long j = -1; j <= 1; ++j) {
      for (long i = -1; i <= 1; ++i) {
        if (occupied(m, x + i, y + j)) return true;
      }
    }
    return false;
  };
  const std::vector<uint8_t> band = path_band(truth, path, band_m);
  NearPathComparison c;
  for (long y = 0; y < truth.height; ++y) {
    for (long x = 0; x < truth.width; ++x) {
      const CellState t = truth.at(static_cast<int>(x), static_cast<int>(y));
      if (band[static_cast<size_t>(y * truth.width + x)] == 0 || t == CellState::kUnknown) continue;
      const long gx = x - dx, gy = y - dy;
      const bool inside = gx >= 0 && gy >= 0 && gx < grid.width && gy < grid.height;
      const CellState g =
          inside ? grid.at(static_cast<int>(gx), static_cast<int>(gy)) : CellState::kUnknown;
      ++c.cells;
      if (g == CellState::kFree) ++c.grid_free;
      if (t == CellState::kOccupied) {
        ++c.truth_occupied;
        if (occupied_near(grid, gx, gy)) ++c.truth_occupied_near_grid;
      }
      if (g == CellState::kOccupied) {
        ++c.grid_occupied;
        if (t == CellState::kOccupied) ++c.occupied_occupied;
        if (occupied_near(truth, x, y)) ++c.grid_occupied_near_truth;
      }
    }
  }
  return c;
}

}  // namespace seqslam::tools
