// Pose-graph figures of the mapping benchmark image, seqslam_bench_mapping (issue 7;
// bench_mapping_main.cpp): the optimiser's cost per slice of optimise_step on the test loop
// of tests/unit/test_pose_graph.cpp (457 nodes, 3 closures), and the cost of one whole mapping
// step per place as the firmware's explore mode and `seqslam slam` run it: the core's Explorer,
// with the library and the map on a card (instructions, card bytes and requests, time).
#pragma once

#include <stdint.h>

#include "bench_card.h"

namespace seqslam::bench {

struct PoseGraphFigures {
  uint32_t nodes;
  uint32_t closures;
  uint32_t slice_units;    // budget of each optimise_step call
  uint32_t slices;         // calls until converged
  uint64_t units;          // work units until converged
  uint32_t iterations;     // CG iterations (three stages)
  uint64_t slice_mean;     // instructions per call (mean over the calls)
  uint64_t slice_max;      // the most expensive call
  uint64_t total;          // instructions until converged
  uint64_t add_node;       // instructions per add_node (mean over the loop)
  uint64_t add_closure;    // instructions per add_loop_closure (mean)
  uint32_t storage_bytes;  // PoseGraphStorage<512, 600>
  uint32_t object_bytes;   // sizeof(PoseGraph)
  int64_t rmse_um;         // optimised RMSE against the truth, micrometres (sanity)
};

// Builds the loop in external memory, optimises it in slices of `slice_units`; false if a
// call fails.
bool run_pose_graph(uint32_t slice_units, PoseGraphFigures* f);
// One human-readable line.
void print_pose_graph(const PoseGraphFigures& f);
// The JSON object's members without its closing brace: {"nodes": ..., ...
void print_pose_graph_json(const PoseGraphFigures& f);

// One mapping step per place as the component that ships runs it: the core's seqslam::Explorer
// (explorer.h) with its defaults, Explorer::scan for every 10 ms infrared snapshot since the
// previous place, Explorer::place after the localiser (whose cost is the localisation step of
// the other images) appended the place to the library, Explorer::finish after the last place.
// The library's images (the closure alignment and heading read them) and the map's tiles are
// on a card (bench_card.h: counted, priced by the SD model). Each StepStats is over the steps
// that ran its part; the counts by index, kMappingCountNames (bench_pose_graph.cpp) holds their
// JSON names, which the human-readable line uses too (one table keeps the image small).
enum MappingCount : uint32_t {
  kCountPlaces,           // steps measured (one per place)
  kCountLap,              // places of the first lap; the rest revisit its start
  kCountSnapshots,        // six-sensor snapshots per place (none before the first)
  kCountBudget,           // optimiser units per place (ExplorerConfig::optimise_budget)
  kCountClosures,         // closure edges added
  kCountRealigned,        // ... joined to a neighbour of the matched place
  kCountAlignFailures,    // ... whose alignment could not read an image (card errors)
  kCountHeadingFailures,  // ... whose heading could not be measured
  kCountTileLoads,        // grid tile loads and saves over the run (to and from the card)
  kCountTileSaves,
  kCountMapTiles,     // distinct tiles in the map file
  kCountRejected,     // readings the grid refused
  kCountStepsOver,    // whole steps over 40 ms at 72 MHz with the card
  kCountPlacesOver,   // place() alone over 40 ms
  kCountUnitsOnline,  // optimiser units spent by the per-place slices
  kCountFinish,       // finish(): instructions (no card), units, slices, converged (0/1)
  kCountFinishUnits,
  kCountFinishSlices,
  kCountConverged,
  kMappingCounts
};

struct MappingStepFigures {
  StepStats step;           // a whole step: place() and the scan()s since the previous place
  StepStats closure_step;   // the whole steps whose place() added a closure edge
  StepStats place;          // place() alone
  StepStats closure_place;  // place() of the closure steps
  StepStats scan;           // one scan(), per snapshot
  uint64_t v[kMappingCounts];
};

// The mapping step's card (external memory): library metadata and images, map tiles.
uint32_t mapping_card_bytes();
// Runs the sequence; false if a call fails, the card fails or the gate does not close.
bool run_mapping_step(MappingStepFigures* f);
void print_mapping_step(const MappingStepFigures& f);
// The JSON object's members without its closing brace, like print_pose_graph_json.
void print_mapping_step_json(const MappingStepFigures& f);

}  // namespace seqslam::bench
