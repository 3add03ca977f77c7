// The figures of one `seqslam slam` run (`--json FILE`): the struct, its JSON writer and its
// reader, one definition for the tool that writes them and the report that reads them
// (slam_report.h). The JSON library (nlohmann/json) stays inside slam_figures.cpp.
//
// The document is one JSON object, keys in this order (the members below, same names):
//   places, runs, decisions {no_sequence, closure, pending, rejected_inconsistent, aliasing,
//   novelty, relocalised: one count per LoopClosureClass, loop_closure_class_name()},
//   rejected_position, rejected_heading, rejected_image, closures, optimiser_work, slices,
//   final_slices, max_solve_places, wheels, closure_heading, hfov_deg, align_length,
//   align_range, align_shift, closures_realigned,
//   has_truth, then only when true: rmse_dead_reckoning_m, rmse_corrected_m, rmse_online_m,
//     max_error_dead_reckoning_m, max_error_corrected_m, false_closures,
//     largest_closure_true_distance_m, closure_heading_error_rms_deg,
//     closure_same_heading_error_rms_deg, closure_along_error_rms_m,
//     closure_gate_along_error_rms_m, events [{place, kind, relocalised_after}],
//   has_map, then only when true: map_accuracy_corrected, map_cells_corrected,
//     map_accuracy_dead_reckoning, map_cells_dead_reckoning, and, when measured (true poses
//     too), near_path {band_m, corrected {...}, dead_reckoning {...}}: each map's
//     NearPathComparison (grid_export.h) as its counts cells, truth_occupied, grid_occupied,
//     grid_free, occupied_occupied, grid_occupied_near_truth, truth_occupied_near_grid, then
//     the rates they give, occupied_precision, occupied_recall, balanced_accuracy,
//     occupied_precision_within_1_cell, occupied_recall_within_1_cell (written for readers
//     of the file; the reader takes the counts and ignores the rates),
//   unreliable_places, relocalisations, align_failures, heading_failures, closure_lateral, and
//   when the run was
//   calibrated: calibration {accepted, difference, track, sigma_difference, sigma_track,
//   closures_used, closures_skipped, residual_before_m, residual_after_m, corrected_wheels,
//   has_truth, then only when true: true_difference, true_track, true_mean}.
#pragma once

#include <stdint.h>

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "seqslam/loop_closure.h"
#include "seqslam_tools/grid_export.h"
#include "seqslam_tools/outcome.h"

namespace seqslam::tools {

// A relocalisation event of a run with true poses: a kidnap or a return to known ground.
struct SlamEvent {
  uint32_t place = 0;
  std::string kind;                // "kidnap", "known ground again"
  int32_t relocalised_after = -1;  // places until relocalised; -1 = not relocalised
};

// The figures that need true poses (has_truth).
struct SlamTruthFigures {
  double rmse_dead_reckoning_m = 0;
  double rmse_corrected_m = 0;
  double rmse_online_m = 0;
  double max_error_dead_reckoning_m = 0;
  double max_error_corrected_m = 0;
  uint32_t false_closures = 0;
  double largest_closure_true_distance_m = 0;
  double closure_heading_error_rms_deg = 0;
  double closure_same_heading_error_rms_deg = 0;
  double closure_along_error_rms_m = 0;
  double closure_gate_along_error_rms_m = 0;
  std::vector<SlamEvent> events;
};

// Obstacles near the path: compare_maps_near_path of the two built maps against the true map
// in the band of `band_m` round the true path (needs true poses as well as the true map).
struct SlamNearPathFigures {
  double band_m = 0;
  NearPathComparison corrected;
  NearPathComparison dead_reckoning;
};

// The figures that need a true map (has_map): compare_maps of the two built maps.
struct SlamMapFigures {
  double map_accuracy_corrected = 0;
  uint64_t map_cells_corrected = 0;
  double map_accuracy_dead_reckoning = 0;
  uint64_t map_cells_dead_reckoning = 0;
  // Written when measured; a document without it (no true poses, or written before it
  // existed) reads as none.
  std::optional<SlamNearPathFigures> near_path;
};

// The wheel calibration from the run's closures (wheel_calibration.h): fractions relative to the
// constants the odometry ran with; the true ones normalised to their mean wheel.
struct SlamCalibrationFigures {
  bool accepted = false;
  double difference = 0;
  double track = 0;
  double sigma_difference = 0;
  double sigma_track = 0;
  uint32_t closures_used = 0;
  uint32_t closures_skipped = 0;
  double residual_before_m = 0;
  double residual_after_m = 0;
  std::string corrected_wheels;           // "LEFT,RIGHT,TRACK" metres
  std::optional<double> true_difference;  // all three or none
  std::optional<double> true_track;
  std::optional<double> true_mean;
};

struct SlamFigures {
  uint32_t places = 0;
  uint32_t runs = 0;
  std::array<uint32_t, kLoopClosureClasses> decisions{};  // indexed by LoopClosureClass
  uint32_t rejected_position = 0;
  uint32_t rejected_heading = 0;
  uint32_t rejected_image = 0;
  uint32_t closures = 0;
  uint64_t optimiser_work = 0;
  uint32_t slices = 0;
  uint32_t final_slices = 0;
  uint32_t max_solve_places = 0;
  std::string wheels;           // "" = the recording's place poses
  std::string closure_heading;  // "image" | "none"
  double hfov_deg = 0;
  int32_t align_length = 0;
  int32_t align_range = 0;
  int32_t align_shift = 0;
  uint32_t closures_realigned = 0;
  std::optional<SlamTruthFigures> truth;  // has_truth
  std::optional<SlamMapFigures> map;      // has_map
  uint32_t unreliable_places = 0;
  uint32_t relocalisations = 0;
  // Closures measured without the images (0 on the PC): the alignment, or the heading, could
  // not read the card. Always written; a document without them (written before they
  // existed) reads as 0.
  uint32_t align_failures = 0;
  uint32_t heading_failures = 0;
  // The closures' position information across the route as a fraction of along it
  // (PoseGraphConfig::closure_lateral), 0..1; a document without it (written before it
  // existed) reads as 1, what those runs used.
  double closure_lateral = 1.0;
  // Optional: documents written before the calibration existed read as none.
  std::optional<SlamCalibrationFigures> calibration;
};

// Member-wise (doubles exactly: the writer's numbers read back to the same values).
bool operator==(const SlamEvent& a, const SlamEvent& b);
bool operator==(const SlamTruthFigures& a, const SlamTruthFigures& b);
bool operator==(const SlamNearPathFigures& a, const SlamNearPathFigures& b);
bool operator==(const SlamMapFigures& a, const SlamMapFigures& b);
bool operator==(const SlamCalibrationFigures& a, const SlamCalibrationFigures& b);
bool operator==(const SlamFigures& a, const SlamFigures& b);
bool operator!=(const SlamFigures& a, const SlamFigures& b);

// The largest document parse_slam_figures reads.
inline constexpr uint64_t kMaxSlamFiguresBytes = uint64_t{16} << 20;

// The document, indented by 2, ending in a newline. Doubles at full (round-trip) precision;
// a non-finite double comes out as null (which the reader refuses). Strings that are not
// UTF-8 have the bad bytes replaced by U+FFFD. Does not throw (but for memory).
std::string slam_figures_json(const SlamFigures& figures);

// Reads a document of slam_figures_json. `path` only names the document in messages. Errors
// start with "PATH: " and name the problem: larger than kMaxSlamFiguresBytes, not JSON (the
// JSON parser's message with line and column), nested too deeply, not an object, a missing
// key, a key of the wrong type (named as "decisions.closure", "events[2].kind"), a count
// that is negative, fractional or out of range, an incomplete has_truth or has_map group.
// Every key the writer writes is required, except align_failures and heading_failures (0
// when absent), closure_lateral (1 when absent) and near_path (none when absent; when present, its
// counts are required and must be consistent: NearPathComparison::consistent, band_m > 0); keys it
// does not know are ignored, as are the group keys when has_truth / has_map is false. Does not
// throw.
Outcome<SlamFigures> parse_slam_figures(const std::string& text, const std::string& path);

}  // namespace seqslam::tools
