// The HTML page of a `seqslam slam` result (slam_report.h): readers for its CSV and JSON
// outputs, then the page (maps as PNG data URIs, overlays as SVG in metres).
#include "seqslam_tools/slam_report.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <string_view>
#include <utility>

#include "file_util.h"
#include "html_embed.h"
#include "seqslam_tools/slam_figures.h"

namespace seqslam::tools {

namespace {

constexpr uint64_t kMaxCsvBytes = uint64_t{256} << 20;
constexpr uint32_t kMaxPlaces = 10000000;
constexpr double kFalseClosureMetres = 1.5;  // seqslam slam's (the pair ground truth's gate)
constexpr int kMaxRasterSide = 1600;         // map images beyond this are reduced
constexpr double kPanelWidth = 460.0;        // CSS pixels of each map panel
constexpr double kPanelMaxHeight = 640.0;

using detail::html_escape;

std::string where(const std::string& path, size_t line) {
  return path + ":" + std::to_string(line) + ": ";
}

bool parse_number(std::string_view text, double* out) {
  text = detail::trim(text);
  if (text.empty()) return false;
  if (text.front() == '+') text.remove_prefix(1);
  double v = 0.0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

bool parse_index(std::string_view text, uint32_t* out) {
  text = detail::trim(text);
  if (text.empty()) return false;
  uint32_t v = 0;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), v);
  if (ec != std::errc() || end != text.data() + text.size() || v >= kMaxPlaces) return false;
  *out = v;
  return true;
}

std::vector<std::string_view> split_fields(std::string_view line) {
  std::vector<std::string_view> fields;
  size_t start = 0;
  for (;;) {
    const size_t comma = line.find(',', start);
    fields.push_back(detail::trim(line.substr(start, comma - start)));
    if (comma == std::string_view::npos) break;
    start = comma + 1;
  }
  return fields;
}

// A CSV with a header naming its columns; `wanted` columns must be present.
struct Csv {
  std::vector<size_t> column;  // index of wanted[k]
  size_t fields = 0;
  std::vector<std::pair<size_t, std::vector<std::string_view>>> rows;  // (line, fields)
  std::string text;                                                    // owns the views
};

Outcome<Csv> read_csv(const std::string& path, const std::vector<const char*>& wanted) {
  Csv csv;
  Outcome<std::string> text = detail::read_file_text(path, kMaxCsvBytes);
  if (!text.ok()) return Error{text.error()};
  csv.text = std::move(text.value());
  const std::vector<std::string_view> lines = detail::split_lines(csv.text);
  size_t first = 0;
  while (first < lines.size() && detail::trim(lines[first]).empty())
    ++first;
  if (first == lines.size()) return Error{path + ": empty (no header line)"};
  const std::vector<std::string_view> header = split_fields(detail::trim(lines[first]));
  csv.fields = header.size();
  for (const char* name : wanted) {
    const auto it = std::find(header.begin(), header.end(), std::string_view(name));
    if (it == header.end()) {
      return Error{where(path, first + 1) + "the header has no column '" + name + "' (found '" +
                   detail::printable(detail::trim(lines[first])) + "')"};
    }
    csv.column.push_back(static_cast<size_t>(it - header.begin()));
  }
  for (size_t i = first + 1; i < lines.size(); ++i) {
    const std::string_view line = detail::trim(lines[i]);
    if (line.empty()) continue;
    std::vector<std::string_view> f = split_fields(line);
    if (f.size() != csv.fields) {
      return Error{where(path, i + 1) + std::to_string(f.size()) + " fields, the header has " +
                   std::to_string(csv.fields) + " ('" + detail::printable(line) + "')"};
    }
    csv.rows.emplace_back(i + 1, std::move(f));
  }
  return csv;
}

std::string fixed(double v, int decimals) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

// The world rectangle the panels share, in whole (reduced) pixels of `factor` cells.
struct Frame {
  double x0 = 0, y0 = 0;  // lower-left corner, metres
  double resolution = 0.05;
  int factor = 1;  // cells per image pixel
  int width = 1;   // image pixels
  int height = 1;
  double metres_x() const { return width * factor * resolution; }
  double metres_y() const { return height * factor * resolution; }
};

enum class Shade : uint8_t { kOutside, kUnknown, kFree, kOccupied };

std::vector<uint8_t> map_raster(const Frame& f, const OccupancyMapImage* map) {
  std::vector<uint8_t> rgb(static_cast<size_t>(f.width) * static_cast<size_t>(f.height) * 3);
  for (int py = 0; py < f.height; ++py) {
    for (int px = 0; px < f.width; ++px) {
      Shade shade = Shade::kOutside;
      if (map != nullptr) {
        // The block of factor x factor frame cells under this pixel; occupied wins over free,
        // free over unknown (thin walls survive the reduction).
        const int row = f.height - 1 - py;  // image rows run from the top (highest y)
        for (int cy = 0; cy < f.factor; ++cy) {
          for (int cx = 0; cx < f.factor; ++cx) {
            const double wx = f.x0 + (px * f.factor + cx + 0.5) * f.resolution;
            const double wy = f.y0 + (row * f.factor + cy + 0.5) * f.resolution;
            const double mx = std::floor((wx - map->origin_x) / map->resolution);
            const double my = std::floor((wy - map->origin_y) / map->resolution);
            if (mx < 0 || my < 0 || mx >= map->width || my >= map->height) continue;
            const CellState s = map->at(static_cast<int>(mx), static_cast<int>(my));
            const Shade here = s == CellState::kOccupied ? Shade::kOccupied
                               : s == CellState::kFree   ? Shade::kFree
                                                         : Shade::kUnknown;
            shade = std::max(shade, here);
          }
        }
      }
      static const uint8_t kColours[4][3] = {
          {226, 232, 240}, {205, 205, 205}, {255, 255, 255}, {20, 20, 20}};
      uint8_t* out =
          &rgb[(static_cast<size_t>(py) * static_cast<size_t>(f.width) + static_cast<size_t>(px)) *
               3];
      for (int k = 0; k < 3; ++k)
        out[k] = kColours[static_cast<int>(shade)][k];
    }
  }
  return rgb;
}

// SVG y runs down: world (x, y) is drawn at (x, -y), so the viewBox starts at -y_top.
std::string point(double x, double y) {
  return fixed(x, 3) + "," + fixed(-y, 3);
}

struct Track {
  const char* cls;
  const char* colour;
  const char* label;
  bool dashed;
};

std::string polylines(const std::vector<SlamPlace>& places, const Track& t, double SlamPlace::*x,
                      double SlamPlace::*y, bool needs_truth) {
  std::string out;
  std::string points;
  uint32_t run = places.empty() ? 0 : places.front().run;
  const auto flush = [&]() {
    if (!points.empty()) {
      out += "<polyline class=\"" + std::string(t.cls) + "\" fill=\"none\" stroke=\"" + t.colour +
             "\" stroke-width=\"" + (t.dashed ? "1.2" : "1.8") +
             "\" vector-effect=\"non-scaling-stroke\"" +
             (t.dashed ? " stroke-dasharray=\"5 3\"" : "") + " points=\"" + points + "\"/>";
    }
    points.clear();
  };
  for (const SlamPlace& p : places) {
    if (needs_truth && !p.has_truth) continue;
    if (p.run != run) {  // each run's odometry starts afresh: no segment between runs
      flush();
      run = p.run;
    }
    if (!points.empty()) points += ' ';
    points += point(p.*x, p.*y);
  }
  flush();
  return out;
}

std::string closure_lines(const SlamReportData& d, double SlamPlace::*x, double SlamPlace::*y,
                          bool needs_truth) {
  std::string out =
      "<g class=\"closures\" stroke=\"#e67e00\" stroke-width=\"1\" "
      "vector-effect=\"non-scaling-stroke\">";
  for (const SlamClosure& c : d.closures) {
    const SlamPlace& a = d.places[c.matched];
    const SlamPlace& b = d.places[c.place];
    if (needs_truth && (!a.has_truth || !b.has_truth)) continue;
    out += "<line vector-effect=\"non-scaling-stroke\" x1=\"" + fixed(a.*x, 3) + "\" y1=\"" +
           fixed(-(a.*y), 3) + "\" x2=\"" + fixed(b.*x, 3) + "\" y2=\"" + fixed(-(b.*y), 3) +
           "\"><title>closure " + std::to_string(c.matched) + " - " + std::to_string(c.place) +
           "</title></line>";
  }
  return out + "</g>";
}

const Track kTrue{"traj-true", "#1a9850", "true", false};
const Track kOdometry{"traj-odometry", "#d73027", "dead reckoning", true};
const Track kCorrected{"traj-corrected", "#2c7bb6", "corrected", false};

const char kStyle[] = R"(
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:0;color:#222;background:#fff}
main{max-width:1500px;margin:0 auto;padding:12px 20px 40px}
h1{font-size:1.5em;margin:.4em 0}h2{border-bottom:2px solid #ddd;padding-bottom:4px;margin-top:1.4em}
table{border-collapse:collapse;margin:.3em 0 .8em;font-size:.9em}
th,td{border:1px solid #ccc;padding:3px 8px;text-align:left}th{background:#f3f3f3}
td.v{text-align:right;font-variant-numeric:tabular-nums}
.note{color:#666;font-style:italic}.path{font-family:monospace;word-break:break-all}
.row{display:flex;flex-wrap:nowrap;overflow-x:auto;gap:16px;align-items:flex-start}
figure{margin:0}figcaption{font-size:.85em;color:#444;margin-top:4px;max-width:460px}
.panel{position:relative;border:1px solid #999}
.panel img{position:absolute;left:0;top:0;image-rendering:pixelated}
.panel svg{position:absolute;left:0;top:0}
.legend{font-size:.85em;display:flex;flex-wrap:wrap;gap:4px 16px;margin:.4em 0}
.swatch{display:inline-block;width:18px;height:0;border-top:3px solid;vertical-align:middle}
.swatch.dashed{border-top-style:dashed}
)";

// The figures of the slam JSON the page shows, by the table's keys, and its figures near the
// path (if it has them) into `d`; "" or the error.
std::string read_json_figures(const std::string& json_path, const std::string& dir,
                              SlamReportData* d, std::map<std::string, double>* json) {
  Outcome<std::string> text = detail::read_file_text(json_path, kMaxSlamFiguresBytes);
  if (!text.ok()) return text.error();
  Outcome<SlamFigures> parsed = parse_slam_figures(text.value(), json_path);
  if (!parsed) return parsed.error();
  const SlamFigures& fig = parsed.value();
  if (fig.places != d->places.size()) {
    return json_path + ": places " + std::to_string(fig.places) + ", but " + dir +
           "trajectory.csv has " + std::to_string(d->places.size()) + " (figures of another run?)";
  }
  std::map<std::string, double>& j = *json;
  j["closures"] = fig.closures;
  j["decisions.rejected_inconsistent"] =
      fig.decisions[static_cast<size_t>(LoopClosureClass::kRejectedInconsistent)];
  j["rejected_position"] = fig.rejected_position;
  j["rejected_heading"] = fig.rejected_heading;
  j["rejected_image"] = fig.rejected_image;
  if (fig.truth) {
    j["rmse_dead_reckoning_m"] = fig.truth->rmse_dead_reckoning_m;
    j["rmse_corrected_m"] = fig.truth->rmse_corrected_m;
    j["false_closures"] = fig.truth->false_closures;
  }
  if (fig.map) {
    j["map_accuracy_corrected"] = fig.map->map_accuracy_corrected;
    j["map_accuracy_dead_reckoning"] = fig.map->map_accuracy_dead_reckoning;
    if (fig.map->near_path) {
      d->near_path = fig.map->near_path;
      d->near_path_source = "json";
    }
  }
  d->json_path = json_path;
  return "";
}

// Without them from the JSON, the figures near the path from the files: both maps against the
// true map round the true poses of trajectory.csv, band kDefaultPathBand (left out when a
// map's geometry does not match the true map's, as the map accuracy is).
void compute_near_path(SlamReportData* d) {
  if (d->near_path || !d->has_true_map) return;
  std::vector<PathPoint> path;
  for (const SlamPlace& p : d->places) {
    if (!p.has_truth) return;
    path.push_back({p.true_x, p.true_y, p.run});
  }
  auto fixed = compare_maps_near_path(d->map, d->true_map, path, kDefaultPathBand);
  auto dead = compare_maps_near_path(d->map_odometry, d->true_map, path, kDefaultPathBand);
  if (!fixed.ok() || !dead.ok()) return;
  d->near_path = SlamNearPathFigures{kDefaultPathBand, fixed.value(), dead.value()};
  d->near_path_source = "computed";
}

// The table's rows near the path, after the others.
void near_path_rows(SlamReportData* d) {
  if (!d->near_path) return;
  const std::string band = fixed(d->near_path->band_m, 2);
  const std::pair<const char*, const NearPathComparison*> maps[] = {
      {"corrected", &d->near_path->corrected}, {"dead_reckoning", &d->near_path->dead_reckoning}};
  for (const auto& [name, c] : maps) {
    const std::string map = std::string(name) == "corrected" ? "corrected" : "dead reckoning";
    const struct {
      const char* key;
      std::string label;
      double value;
    } rows[] = {
        {"occupied_precision", "occupied precision", c->precision()},
        {"occupied_recall", "occupied recall", c->recall()},
        {"occupied_precision_within_1_cell", "occupied precision, within one cell",
         c->precision_within_cell()},
        {"occupied_recall_within_1_cell", "occupied recall, within one cell",
         c->recall_within_cell()},
        {"balanced_accuracy", "balanced accuracy", c->balanced_accuracy()},
    };
    for (const auto& r : rows) {
      d->figures.push_back({std::string("near_path.") + name + "." + r.key,
                            "near the true path (" + band + " m), " + map + ": " + r.label,
                            fixed(r.value, 3), d->near_path_source});
    }
  }
}

// A map panel's caption line of its figures near the path ("" without them).
std::string near_path_caption(const SlamReportData& d, const NearPathComparison& c) {
  if (!d.near_path) return "";
  return "<br><span class=\"near-path\">Within " + fixed(d.near_path->band_m, 2) +
         " m of the true path: occupied precision " + fixed(c.precision(), 3) + ", recall " +
         fixed(c.recall(), 3) + " (within one cell " + fixed(c.precision_within_cell(), 3) + ", " +
         fixed(c.recall_within_cell(), 3) + "), balanced accuracy " +
         fixed(c.balanced_accuracy(), 3) + "; " + std::to_string(c.grid_occupied) +
         " cells called occupied, " + std::to_string(c.truth_occupied) + " truly, " +
         std::to_string(c.occupied_occupied) + " both, of " + std::to_string(c.cells) +
         " scored.</span>";
}

}  // namespace

Outcome<std::vector<SlamPlace>> load_slam_trajectory(const std::string& path) {
  const std::vector<const char*> wanted = {"place",       "run",         "true_x",
                                           "true_y",      "odo_x",       "odo_y",
                                           "corrected_x", "corrected_y", "decision"};
  Outcome<Csv> csv = read_csv(path, wanted);
  if (!csv.ok()) return Error{csv.error()};
  const Csv& c = csv.value();
  std::vector<SlamPlace> places;
  for (const auto& [line, f] : c.rows) {
    const auto field = [&](size_t k) { return f[c.column[k]]; };
    SlamPlace p;
    if (!parse_index(field(0), &p.place) || p.place != places.size()) {
      return Error{where(path, line) + "place must be " + std::to_string(places.size()) +
                   " (places in order from 0), found '" + detail::printable(field(0)) + "'"};
    }
    if (!parse_index(field(1), &p.run)) {
      return Error{where(path, line) + "run is not a run index: '" + detail::printable(field(1)) +
                   "'"};
    }
    const bool no_truth = field(2).empty() && field(3).empty();
    p.has_truth = !no_truth;
    struct Num {
      size_t k;
      double* out;
    } nums[] = {{2, &p.true_x}, {3, &p.true_y},      {4, &p.odo_x},
                {5, &p.odo_y},  {6, &p.corrected_x}, {7, &p.corrected_y}};
    for (const Num& n : nums) {
      if (no_truth && n.k <= 3) continue;
      if (!parse_number(field(n.k), n.out)) {
        return Error{where(path, line) + wanted[n.k] + " is not a number: '" +
                     detail::printable(field(n.k)) + "'"};
      }
    }
    p.decision = std::string(field(8));
    places.push_back(std::move(p));
  }
  if (places.empty()) return Error{path + ": no places (only a header)"};
  return places;
}

Outcome<std::vector<SlamClosure>> load_slam_closures(const std::string& path, uint32_t places) {
  Outcome<Csv> csv = read_csv(path, {"matched_place", "place", "true_distance_m"});
  if (!csv.ok()) return Error{csv.error()};
  const Csv& c = csv.value();
  std::vector<SlamClosure> closures;
  for (const auto& [line, f] : c.rows) {
    SlamClosure k;
    const std::string_view a = f[c.column[0]], b = f[c.column[1]], t = f[c.column[2]];
    if (!parse_index(a, &k.matched) || !parse_index(b, &k.place) || k.matched >= places ||
        k.place >= places) {
      return Error{where(path, line) + "places must be indices below " + std::to_string(places) +
                   " (the trajectory's places), found '" + detail::printable(a) + "', '" +
                   detail::printable(b) + "'"};
    }
    if (!t.empty()) {
      if (!parse_number(t, &k.true_distance) || k.true_distance < 0) {
        return Error{where(path, line) + "true_distance_m is not a distance: '" +
                     detail::printable(t) + "'"};
      }
      k.has_truth = true;
    }
    closures.push_back(k);
  }
  return closures;
}

Outcome<SlamReportData> load_slam_report(const std::string& directory,
                                         const std::string& true_map_yaml,
                                         const std::string& json_path) {
  SlamReportData d;
  d.directory = directory;
  const std::string dir =
      directory.empty() || directory.back() == '/' ? directory : directory + "/";
  auto places = load_slam_trajectory(dir + "trajectory.csv");
  if (!places) return Error{places.error()};
  d.places = std::move(places.value());
  auto closures = load_slam_closures(dir + "closures.csv", static_cast<uint32_t>(d.places.size()));
  if (!closures) return Error{closures.error()};
  d.closures = std::move(closures.value());
  const auto load = [](const std::string& yaml, OccupancyMapImage* out) -> std::string {
    auto m = load_map(yaml);
    if (!m) return m.error();
    *out = std::move(m.value());
    if (static_cast<uint64_t>(out->width) * static_cast<uint64_t>(out->height) >
        kMaxSlamReportCells) {
      return yaml + ": " + std::to_string(out->width) + " x " + std::to_string(out->height) +
             " cells, more than the report draws (" + std::to_string(kMaxSlamReportCells) + ")";
    }
    return "";
  };
  std::string e = load(dir + "map.yaml", &d.map);
  if (e.empty()) e = load(dir + "map_odometry.yaml", &d.map_odometry);
  if (e.empty() && !true_map_yaml.empty()) {
    e = load(true_map_yaml, &d.true_map);
    d.has_true_map = true;
    d.true_map_path = true_map_yaml;
  }
  if (!e.empty()) return Error{e};
  const double res = d.map.resolution;
  const std::pair<const OccupancyMapImage*, std::string> others[] = {
      {&d.map_odometry, dir + "map_odometry.yaml"}, {&d.true_map, true_map_yaml}};
  for (const auto& [m, name] : others) {
    if (m == &d.true_map && !d.has_true_map) continue;
    if (std::fabs(m->resolution - res) > 1e-6 * res) {
      return Error{name + ": resolution " + fixed(m->resolution, 4) + " m differs from " + dir +
                   "map.yaml's " + fixed(res, 4) + " m (the panels share one scale)"};
    }
  }

  // Figures: from the JSON when given (those of the table it has), else what the files allow.
  std::map<std::string, double> json;
  if (!json_path.empty()) {
    const std::string error = read_json_figures(json_path, dir, &d, &json);
    if (!error.empty()) return Error{error};
  }
  const bool truth =
      std::all_of(d.places.begin(), d.places.end(), [](const SlamPlace& p) { return p.has_truth; });
  double se_dead = 0, se_fixed = 0;
  for (const SlamPlace& p : d.places) {
    se_dead += std::pow(p.odo_x - p.true_x, 2) + std::pow(p.odo_y - p.true_y, 2);
    se_fixed += std::pow(p.corrected_x - p.true_x, 2) + std::pow(p.corrected_y - p.true_y, 2);
  }
  const double n = static_cast<double>(d.places.size());
  uint32_t false_closures = 0;
  bool closure_truth = true;
  for (const SlamClosure& c : d.closures) {
    closure_truth = closure_truth && c.has_truth;
    if (c.has_truth && c.true_distance > kFalseClosureMetres) ++false_closures;
  }
  const auto rejected =
      static_cast<double>(std::count_if(d.places.begin(), d.places.end(), [](const SlamPlace& p) {
        return p.decision == "rejected_inconsistent";
      }));
  double acc_fixed = -1, acc_dead = -1;
  if (d.has_true_map) {
    auto a = compare_maps(d.map, d.true_map);
    auto b = compare_maps(d.map_odometry, d.true_map);
    if (a.ok()) acc_fixed = a.value().accuracy();
    if (b.ok()) acc_dead = b.value().accuracy();
  }
  struct Spec {
    const char* key;
    const char* label;
    bool computable;
    double computed;
    int decimals;
  };
  const double rmse_dead = std::sqrt(se_dead / n), rmse_fixed = std::sqrt(se_fixed / n);
  const Spec specs[] = {
      {"rmse_dead_reckoning_m", "RMSE dead reckoning (m)", truth, rmse_dead, 3},
      {"rmse_corrected_m", "RMSE corrected (m)", truth, rmse_fixed, 3},
      {"ratio", "ratio corrected / dead reckoning", truth && rmse_dead > 0,
       rmse_dead > 0 ? rmse_fixed / rmse_dead : 0, 2},
      {"closures", "closures", true, static_cast<double>(d.closures.size()), 0},
      {"false_closures", "false closures (true distance > 1.5 m)", truth && closure_truth,
       static_cast<double>(false_closures), 0},
      {"decisions.rejected_inconsistent", "rejections (all reasons)", true, rejected, 0},
      {"rejected_position", "rejections: position", false, 0, 0},
      {"rejected_heading", "rejections: heading", false, 0, 0},
      {"rejected_image", "rejections: image", false, 0, 0},
      {"map_accuracy_corrected", "map accuracy corrected", acc_fixed >= 0, acc_fixed, 3},
      {"map_accuracy_dead_reckoning", "map accuracy dead reckoning", acc_dead >= 0, acc_dead, 3},
  };
  for (const Spec& s : specs) {
    SlamFigure f;
    f.key = s.key;
    f.label = s.label;
    const std::string key = s.key;
    if (key == "ratio" && json.count("rmse_dead_reckoning_m") && json.count("rmse_corrected_m") &&
        json["rmse_dead_reckoning_m"] > 0) {
      f.value = fixed(json["rmse_corrected_m"] / json["rmse_dead_reckoning_m"], s.decimals);
      f.source = "json";
    } else if (json.count(key) != 0) {
      f.value = fixed(json[key], s.decimals);
      f.source = "json";
    } else if (s.computable) {
      f.value = fixed(s.computed, s.decimals);
      f.source = "computed";
    }
    d.figures.push_back(std::move(f));
  }
  compute_near_path(&d);
  near_path_rows(&d);
  return d;
}

Outcome<std::string> render_slam_report(const SlamReportData& d, const std::string& title_in) {
  if (d.places.empty()) return Error{"slam report: no places"};
  for (const SlamClosure& c : d.closures) {
    if (c.matched >= d.places.size() || c.place >= d.places.size()) {
      return Error{"slam report: a closure names a place beyond the trajectory"};
    }
  }
  const std::string title = title_in.empty() ? "SLAM result" : title_in;
  // The frame: every map's extent and every pose, at the corrected map's resolution.
  double x0 = std::numeric_limits<double>::infinity(), y0 = x0, x1 = -x0, y1 = -x0;
  const auto extend = [&](double x, double y) {
    x0 = std::min(x0, x), y0 = std::min(y0, y), x1 = std::max(x1, x), y1 = std::max(y1, y);
  };
  const auto extend_map = [&](const OccupancyMapImage& m) {
    extend(m.origin_x, m.origin_y);
    extend(m.origin_x + m.width * m.resolution, m.origin_y + m.height * m.resolution);
  };
  extend_map(d.map);
  extend_map(d.map_odometry);
  if (d.has_true_map) extend_map(d.true_map);
  for (const SlamPlace& p : d.places) {
    extend(p.odo_x, p.odo_y);
    extend(p.corrected_x, p.corrected_y);
    if (p.has_truth) extend(p.true_x, p.true_y);
  }
  Frame f;
  f.resolution = d.map.resolution;
  f.x0 = x0;
  f.y0 = y0;
  const double cells_x = std::ceil((x1 - x0) / f.resolution);
  const double cells_y = std::ceil((y1 - y0) / f.resolution);
  if (!(cells_x >= 1 && cells_y >= 1) || cells_x * cells_y > 4.0 * kMaxSlamReportCells) {
    return Error{"slam report: the poses and maps span " + fixed(x1 - x0, 1) + " x " +
                 fixed(y1 - y0, 1) + " m, too large to draw"};
  }
  f.factor = std::max(1, static_cast<int>(std::ceil(std::max(cells_x, cells_y) / kMaxRasterSide)));
  f.width = static_cast<int>(std::ceil(cells_x / f.factor));
  f.height = static_cast<int>(std::ceil(cells_y / f.factor));
  double w = kPanelWidth;
  double h = w * f.height / f.width;
  if (h > kPanelMaxHeight) {
    w *= kPanelMaxHeight / h;
    h = kPanelMaxHeight;
  }
  const std::string view_box = fixed(f.x0, 3) + " " + fixed(-(f.y0 + f.metres_y()), 3) + " " +
                               fixed(f.metres_x(), 3) + " " + fixed(f.metres_y(), 3);
  const bool truth =
      std::any_of(d.places.begin(), d.places.end(), [](const SlamPlace& p) { return p.has_truth; });

  // `extra`: HTML after the caption (figures), not in the image's alt text.
  const auto panel = [&](const char* id, const char* caption, const OccupancyMapImage* map,
                         const std::string& overlay, const std::string& extra) {
    const std::string uri = detail::png_data_uri(f.width, f.height, 3, map_raster(f, map));
    std::string out = "<figure id=\"" + std::string(id) +
                      "\"><div class=\"panel\" style=\"width:" + fixed(w, 0) +
                      "px;height:" + fixed(h, 0) + "px\">";
    if (!uri.empty()) {
      out += "<img alt=\"" + html_escape(caption) + "\" width=\"" + fixed(w, 0) + "\" height=\"" +
             fixed(h, 0) + "\" src=\"" + uri + "\">";
    }
    out += "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" + fixed(w, 0) + "\" height=\"" +
           fixed(h, 0) + "\" viewBox=\"" + view_box + "\" preserveAspectRatio=\"none\">" + overlay +
           "</svg></div><figcaption>" + caption + extra + "</figcaption></figure>";
    return out;
  };
  std::string true_overlay, corrected_overlay, odometry_overlay;
  if (truth) {
    true_overlay += polylines(d.places, kOdometry, &SlamPlace::odo_x, &SlamPlace::odo_y, false);
    true_overlay +=
        polylines(d.places, kCorrected, &SlamPlace::corrected_x, &SlamPlace::corrected_y, false);
    true_overlay += polylines(d.places, kTrue, &SlamPlace::true_x, &SlamPlace::true_y, true);
    true_overlay += closure_lines(d, &SlamPlace::true_x, &SlamPlace::true_y, true);
    corrected_overlay += polylines(d.places, kTrue, &SlamPlace::true_x, &SlamPlace::true_y, true);
    odometry_overlay += polylines(d.places, kTrue, &SlamPlace::true_x, &SlamPlace::true_y, true);
  }
  corrected_overlay +=
      polylines(d.places, kCorrected, &SlamPlace::corrected_x, &SlamPlace::corrected_y, false);
  corrected_overlay += closure_lines(d, &SlamPlace::corrected_x, &SlamPlace::corrected_y, false);
  odometry_overlay += polylines(d.places, kOdometry, &SlamPlace::odo_x, &SlamPlace::odo_y, false);

  std::string html;
  html += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>" +
          html_escape(title) + "</title><style>" + kStyle + "</style></head>\n<body><main>\n<h1>" +
          html_escape(title) + "</h1>\n<p>Output of <span class=\"path\">" +
          html_escape(d.directory) + "</span>: " + std::to_string(d.places.size()) + " places, " +
          std::to_string(d.closures.size()) + " closures" +
          (d.json_path.empty()
               ? ""
               : "; figures from <span class=\"path\">" + html_escape(d.json_path) + "</span>") +
          ".</p>\n";

  html +=
      "<section id=\"sec-figures\"><h2>Figures</h2><table id=\"slam-figures\"><tr><th>figure"
      "</th><th>value</th><th>from</th></tr>";
  for (const SlamFigure& fig : d.figures) {
    html += "<tr data-key=\"" + html_escape(fig.key) + "\"><td>" + html_escape(fig.label) +
            "</td><td class=\"v\">" + (fig.value.empty() ? "unknown" : html_escape(fig.value)) +
            "</td><td>" +
            (fig.source == "json"       ? "the slam JSON"
             : fig.source == "computed" ? "computed from the files"
                                        : "needs --json") +
            "</td></tr>";
  }
  html +=
      "</table><p class=\"note\">Map accuracy: the fraction of the cells the grid calls free or "
      "occupied that the true map agrees with (grid_export compare_maps). Near the true path "
      "(compare_maps_near_path): over the true map's known cells whose centre is within the "
      "band of the true trajectory, precision is the share of the cells the map calls occupied "
      "that are truly occupied, recall the share of the truly occupied cells the map calls "
      "occupied (a cell the map leaves unknown counts as not occupied), balanced accuracy the "
      "mean of recall and the share of truly free cells not called occupied; within one cell, "
      "a wall drawn one cell off counts. Trajectories are aligned at the first place's true "
      "pose, as seqslam slam writes them.</p></section>\n";

  html += "<section id=\"sec-maps\"><h2>Maps</h2><p>One frame for all three: x " + fixed(f.x0, 2) +
          " .. " + fixed(f.x0 + f.metres_x(), 2) + " m, y " + fixed(f.y0, 2) + " .. " +
          fixed(f.y0 + f.metres_y(), 2) + " m, " + fixed(f.resolution * 100, 1) + " cm cells" +
          (f.factor > 1 ? ", drawn " + std::to_string(f.factor) + " x " + std::to_string(f.factor) +
                              " cells per pixel (occupied wins)"
                        : std::string()) +
          ". White free, black occupied, grey unknown, blue-grey outside the map.</p>"
          "<div class=\"legend\">";
  for (const Track* t : {&kTrue, &kOdometry, &kCorrected}) {
    html += std::string("<span><span class=\"swatch") + (t->dashed ? " dashed" : "") +
            "\" style=\"border-color:" + t->colour + "\"></span> " + t->label + "</span>";
  }
  html +=
      "<span><span class=\"swatch\" style=\"border-color:#e67e00\"></span> closure (matched "
      "place - place)</span></div>\n<div class=\"row\">";
  const std::string true_caption =
      d.has_true_map
          ? "True map (" + html_escape(d.true_map_path) + ")" +
                (truth ? " with all three trajectories and the closures at the true poses" : "")
          : std::string("No true map given (--true-map)") +
                (truth ? "; all three trajectories and the closures at the true poses" : "");
  html += panel("map-true", true_caption.c_str(), d.has_true_map ? &d.true_map : nullptr,
                true_overlay, "");
  html += panel(
      "map-corrected", "Map from the corrected poses (map.yaml), corrected trajectory and closures",
      &d.map, corrected_overlay, d.near_path ? near_path_caption(d, d.near_path->corrected) : "");
  html +=
      panel("map-odometry", "Map from dead reckoning (map_odometry.yaml), dead-reckoned trajectory",
            &d.map_odometry, odometry_overlay,
            d.near_path ? near_path_caption(d, d.near_path->dead_reckoning) : "");
  html += "</div></section>\n</main></body></html>\n";
  return html;
}

}  // namespace seqslam::tools
