// Simulated runs and the scenarios built from them.
//
// A run = the lab (with its per-run differences) + a light condition + a route driven by the
// simulated robot. generate_run() drives it, decides captures exactly as the firmware does
// (the core's Odometry and SpatialTrigger on the encoder stream, with the firmware's default
// wheel constants - which are not the robot's true ones), renders a camera frame at each
// capture, reduces it through the pixel pipeline and writes:
//   <name>.dream      - a full dream recording (every 10 ms snapshot, every place with its
//                       image) with a ground-truth record (true pose) after each place;
//   <name>.truth.csv  - per place: true pose, odometry pose, time (for people and plots).
// Scenarios (docs/simulator.md) are sets of runs plus library/query pairs, each pair with a
// ground-truth file in the corridor dataset's CSV format, listed in DIR/pairs.csv.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "seqslam/hal/pixel_buffer.h"
#include "seqslam_sim/lab.h"
#include "seqslam_sim/render.h"
#include "seqslam_sim/robot.h"

namespace seqslam::sim {

struct RunSpec {
  std::string name;
  std::string light = "noon-lamps";
  uint64_t seed = 1;        // the lab's per-run differences, sensor noise, and (default) the drive
  uint64_t drive_seed = 0;  // if not 0: the drive's own seed (two runs along the same track)
  uint64_t world_seed = 0;  // if not 0: the lab's per-run differences (people, chairs) from it
  std::vector<Leg> legs;
  LabOptions lab{};
  DriveOptions drive{};
  CameraModel camera{};
  hal::PipelineMapping mapping = hal::PipelineMapping::reduction(32, 16);
  unsigned threads = 1;  // rendering threads (the output does not depend on it)
};

struct PlaceTruth {
  uint32_t index = 0;
  TruePose truth;     // where the robot really was
  TruePose odometry;  // where its dead reckoning (firmware constants) put it
  uint32_t timestamp_us = 0;
};

struct RunSummary {
  std::string name;
  std::string light;
  uint32_t snapshots = 0;
  double length_m = 0.0;     // true distance driven
  double end_error_m = 0.0;  // |odometry end - true end|, both from the same start
  double end_heading_error_deg = 0.0;
  double max_lateral_m = 0.0;  // largest deviation from the route's centre line
  double max_heading_dev_deg = 0.0;
  double seconds = 0.0;  // wall time spent generating
  std::vector<PlaceTruth> places;
};

// Simulates `spec` and writes its files into `dir`. Returns "" or an error message.
std::string generate_run(const RunSpec& spec, const std::string& dir, RunSummary* summary);

// Drives `spec` without rendering or writing anything: the summary's odometry figures and
// true / odometry poses of the places (for odometry studies). Returns "" or an error.
std::string simulate_drive(const RunSpec& spec, RunSummary* summary);

// Ground truth for a library/query pair from the true poses: for each query place the
// library places whose true heading is within `max_heading_deg` are candidates; the nearest
// one within `gate_m` and its neighbours up to `tolerance` places either side (the 2025
// thesis's +-1 image) are correct. Queries with no candidate inside the gate (novelty, the
// transit between segments) have none.
struct TruthRule {
  double gate_m = 1.5;
  uint32_t tolerance = 1;
  double max_heading_deg = 60.0;
  // A library that passes a place more than once (the perspective tour): every pass's nearest
  // place (+-tolerance) is correct, not only the overall nearest. A pass is a run of
  // consecutive library places inside the gate.
  bool every_pass = false;
};
std::vector<std::vector<uint32_t>> pair_truth(const std::vector<PlaceTruth>& library,
                                              const std::vector<PlaceTruth>& query,
                                              const TruthRule& rule = {});
// Writes it as "query_index,matching_reference_indices" CSV. Returns "" or an error.
std::string write_truth_csv(const std::string& path,
                            const std::vector<std::vector<uint32_t>>& truth);

// Routes through the lab (metres; docs/simulator.md draws them).
namespace routes {
std::vector<Leg> loop();       // the ~90 m loop round the central block, start = end
std::vector<Leg> jump();       // the loop's segments in another order via the cross corridor
std::vector<Leg> kidnapped();  // part of the loop, then lifted to another part of it
std::vector<Leg> novelty();    // the loop with an excursion into the workshop room
std::vector<Leg> long_tour();  // loop + workshop + cross-corridor lap (~800 places)
std::vector<Leg> explore();    // the loop twice in one run: the second lap closes loops
// The loop's western half (through the cross corridor) once, then its first 12 m again: a
// short run (~65 m) whose end revisits its start (tests of `seqslam slam`).
std::vector<Leg> explore_short();
// A figure of eight twice (~230 m): both turning directions in one run, so the wheel constants
// can be calibrated from its loop closures (docs/mapping.md, "Odometry that calibrates itself").
std::vector<Leg> calibrate();
// Teach/repeat over a whole route: ~1 km (~5 000 places at 20 cm) in one drive, 14 laps of
// the central block's lanes joined on the south lane: the ~90 m loop both ways, its western
// and eastern halves (through the cross corridor) both ways, a figure of eight, and the
// workshop twice (once each way), in a varied order, so that most places are passed several
// times and in both directions (route_test.cpp checks these).
std::vector<Leg> route_1km();
}  // namespace routes

// Perspective sets: image-plane transformations of the full camera frame, before the pixel
// pipeline (as the 2015 thesis applied them before downsampling).
struct PerspectiveTransform {
  double rotation_deg = 0.0;
  double shift_x_px = 0.0;  // camera pixels (346 wide)
  double shift_y_px = 0.0;
  double scale = 1.0;
  std::string label() const;
};

// Drives `spec` once, renders each place on an enlarged canvas and writes one reduced
// recording per transform: <spec.name>_<label>.dream (with ground-truth records).
std::string generate_perspective_set(const RunSpec& spec,
                                     const std::vector<PerspectiveTransform>& transforms,
                                     const std::string& dir, RunSummary* summary);

}  // namespace seqslam::sim
