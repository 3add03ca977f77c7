// A self-contained HTML page of one `seqslam slam` result (docs/mapping.md, "The SLAM
// report"): the true map, the map built from the corrected poses and the map built from dead
// reckoning side by side at one scale, in one world frame (the union of the three maps'
// extents; ROS map_server origin and resolution honoured), the trajectories (true, dead
// reckoning, corrected) drawn over them as SVG in metres, the accepted closures as segments,
// and the figures table.
//
// Inputs, from the slam output directory DIR (`seqslam slam --out DIR`):
//   DIR/trajectory.csv   per place: place, run, true_x, true_y, odo_x, odo_y, corrected_x,
//                        corrected_y, decision, ... (columns found by the header's names;
//                        true_* empty when the recording has no ground truth);
//   DIR/closures.csv     matched_place, place, true_distance_m (empty without truth);
//   DIR/map.yaml (+ .pgm), DIR/map_odometry.yaml (+ .pgm): grid_export's load_map;
// optional: the true map (map_server YAML, e.g. seqslam-sim's lab_map.yaml) and the JSON of
// figures (`seqslam slam --json`, slam_figures.h). Figures come from the JSON when it is
// given; otherwise the ones the files allow are computed from them (RMSE from the CSV,
// closures and false closures from closures.csv, map accuracy by compare_maps against the
// true map, occupied precision and recall near the true path by compare_maps_near_path) and
// the rest are shown as unknown.
//
// The page works offline: CSS inline, maps as PNG data URIs (html_embed, as report.cpp), the
// overlays inline SVG.
#pragma once

#include <stdint.h>

#include <optional>
#include <string>
#include <vector>

#include "seqslam_tools/grid_export.h"
#include "seqslam_tools/outcome.h"
#include "seqslam_tools/slam_figures.h"

namespace seqslam::tools {

struct SlamPlace {
  uint32_t place = 0;
  uint32_t run = 0;
  bool has_truth = false;
  double true_x = 0, true_y = 0;
  double odo_x = 0, odo_y = 0;
  double corrected_x = 0, corrected_y = 0;
  std::string decision;
};

struct SlamClosure {
  uint32_t matched = 0;  // the older place
  uint32_t place = 0;    // the place that closed
  bool has_truth = false;
  double true_distance = 0;  // metres between the two places' true poses
};

// One figure of the table: its label and value as text ("" = unknown).
struct SlamFigure {
  std::string key;  // stable id, e.g. "rmse_corrected_m" (the slam JSON's name)
  std::string label;
  std::string value;
  std::string source;  // "json" or "computed" or ""
};

struct SlamReportData {
  std::string directory;
  std::vector<SlamPlace> places;
  std::vector<SlamClosure> closures;
  OccupancyMapImage map;           // corrected poses
  OccupancyMapImage map_odometry;  // dead reckoning
  bool has_true_map = false;
  OccupancyMapImage true_map;
  std::string true_map_path;
  std::string json_path;
  std::vector<SlamFigure> figures;
  // Obstacles near the true path: from the JSON (source "json") or, without them there,
  // computed from the files with kDefaultPathBand (source "computed"; needs the true map and
  // true poses for every place).
  std::optional<SlamNearPathFigures> near_path;
  std::string near_path_source;
};

// The band round the true path the page scores the maps in when the JSON does not say (the
// default of `seqslam slam --path-band`).
inline constexpr double kDefaultPathBand = 1.0;

// Readers. Errors name the file and, for a line, "file:line: " and the problem: missing file,
// a missing header column, a line with another number of fields than the header, a field that
// is not a number (or not a place index), a place out of order or out of range, no rows.
Outcome<std::vector<SlamPlace>> load_slam_trajectory(const std::string& path);
// `places`: the trajectory's place count (closures must name places below it).
Outcome<std::vector<SlamClosure>> load_slam_closures(const std::string& path, uint32_t places);

// Everything for the page: DIR's files, the true map (optional, "" = none) and the figures
// JSON (optional, "" = none; read by parse_slam_figures, slam_figures.h: its errors give the
// key, or the line and column for text that is not JSON; its places must be the
// trajectory's). Maps must share one resolution (relative 1e-6) and be within
// kMaxSlamReportCells.
inline constexpr uint64_t kMaxSlamReportCells = uint64_t{4096} * 4096;
Outcome<SlamReportData> load_slam_report(const std::string& directory,
                                         const std::string& true_map_yaml,
                                         const std::string& json_path);

// The whole HTML document (UTF-8). Element ids: slam-figures (the table), map-true,
// map-corrected, map-odometry (each a figure holding the map image and an SVG overlay with
// polylines of class traj-true / traj-odometry / traj-corrected and a group of class closures
// of <line> segments; the corrected and dead-reckoning captions end in a span of class
// near-path with the map's figures near the true path, when there are any). Table rows near
// the path have keys near_path.{corrected,dead_reckoning}.{occupied_precision,
// occupied_recall, occupied_precision_within_1_cell, occupied_recall_within_1_cell,
// balanced_accuracy}.
Outcome<std::string> render_slam_report(const SlamReportData& data, const std::string& title);

}  // namespace seqslam::tools
