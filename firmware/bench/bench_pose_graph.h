// Pose-graph figures of the benchmark firmware (issue 7): the optimiser's cost per slice of
// optimise_step on the test loop of tests/unit/test_pose_graph.cpp (457 nodes, 3 closures).
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

}  // namespace seqslam::bench
