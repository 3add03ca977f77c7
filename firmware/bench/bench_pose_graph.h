// Pose-graph figures of the mapping benchmark image, seqslam_bench_mapping (issue 7;
// bench_mapping_main.cpp): the optimiser's cost per slice of optimise_step on the test loop
// of tests/unit/test_pose_graph.cpp (457 nodes, 3 closures), and the cost of one whole mapping
// step per place as `seqslam slam` runs it (gate, graph, closure, one optimiser slice, the
// grid update for the snapshots since the last place).
#pragma once

#include <stdint.h>

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

// One mapping step per place, as the robot would run it after Localiser::observe (whose cost
// is the localisation step of the other image, seqslam_bench): the infrared snapshots recorded
// since the previous place into the occupancy grid (hung from that place's estimate),
// PoseGraph::add_node, LoopClosureGate::decide, add_loop_closure on a closure, one optimise_step
// slice. The figures by index; kMappingFigureNames (bench_pose_graph.cpp) holds their JSON names,
// which the human-readable line uses too (one table keeps the image small).
enum MappingFigure : uint32_t {
  kFigPlaces,     // steps measured (one per place)
  kFigLap,        // places of the first lap; the rest revisit its start
  kFigSnapshots,  // six-sensor snapshots per place
  kFigBudget,     // optimise_step units per place
  kFigClosures,   // steps that added a closure edge
  kFigTileLoads,  // over the whole sequence (6 resident tiles)
  kFigTileSaves,
  // Instructions, mean and max (in pairs, in the order of MappingPart) over the steps that
  // ran the part: a whole step; a whole step with a closure; the grid update for the
  // snapshots since the previous place (a pose and an insert_scan each); one optimise_step
  // slice; LoopClosureGate::decide; PoseGraph::add_node; PoseGraph::add_loop_closure.
  kFigFirstPart,
  kMappingFigureCount = kFigFirstPart + 14
};
enum MappingPart : uint32_t {
  kPartStep,
  kPartClosureStep,
  kPartGrid,
  kPartSlice,
  kPartDecide,
  kPartAddNode,
  kPartAddClosure,
  kMappingParts
};

struct MappingStepFigures {
  uint64_t v[kMappingFigureCount];
};

// Runs the sequence in external memory; false if a call fails or the gate does not close.
bool run_mapping_step(MappingStepFigures* f);
void print_mapping_step(const MappingStepFigures& f);
// The JSON object's members without its closing brace, like print_pose_graph_json.
void print_mapping_step_json(const MappingStepFigures& f);

}  // namespace seqslam::bench
