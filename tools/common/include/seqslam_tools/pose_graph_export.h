// The core's pose graph as a g2o graph (pose_graph_file.h) and the figures of `seqslam graph`
// as JSON (issue 35; docs/mapping.md, "Public pose graphs").
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "seqslam/pose_graph.h"
#include "seqslam_tools/pose_graph_file.h"

namespace seqslam::tools {

// The graph's current estimates (metres, radians in (-pi, pi]).
std::vector<GraphPose> graph_poses_of(const PoseGraph& graph);
// Its edges (odometry first, then closures) with their stored information divided by
// `information_scale` (the factor the caller multiplied the data's information by to fit the
// core's UQ16.16; 1 for the explorer's own weights).
std::vector<GraphEdge> graph_edges_of(const PoseGraph& graph, double information_scale);

// What `seqslam graph` reports. Optional figures are written as null when absent. JSON keys:
// input, format, nodes, edges, odometry_edges, loop_closures, information_scale_log2,
// chi2_chained_odometry, chi2_optimised (the g2o objective with the file's information),
// chi2_file_vertices, ate_chained_odometry_m, ate_optimised_m, work_units, slices,
// cg_iterations, residual_recomputations, relinearisations, rescales, max_scale_bits, stalls,
// wall_time_s, exit_reason ("tolerance": every stage certified its tolerance; "resolution":
// some stage ended at the rounding floor, the halving rule, with the bounds below;
// "exhausted": some stage ran out of recomputations or relinearisations, with the bounds
// below; "failed"), the certified bounds (objective_bound_headings, objective_bound_positions,
// objective_bound_finish: the excess of each stage's objective over its exact minimum, in the
// file's chi2 units; heading_bound_rad, position_bound_m: LAGO's estimates against the exact
// LAGO solution, sqrt(V bound)), the settings, and with
// --reference reference_gauss_newton_chi2, reference_max_position_difference_m,
// reference_max_heading_difference_rad, reference_ate_m.
struct GraphFigures {
  std::string input;
  std::string format;  // "g2o" or "isam"
  uint32_t nodes = 0;
  uint32_t edges = 0;
  uint32_t odometry_edges = 0;
  uint32_t loop_closures = 0;
  int information_scale_log2 = 0;  // the data's information times 2^this in the core
  double chi2_initial = 0.0;       // the chained odometry (where the optimiser starts)
  double chi2_final = 0.0;
  std::optional<double> chi2_file_vertices;  // the file's own VERTEX_SE2 estimates, if any
  std::optional<double> ate_initial_m;       // --truth: after the best rigid 2-D alignment
  std::optional<double> ate_final_m;
  uint64_t work_units = 0;
  uint64_t slices = 0;
  uint32_t cg_iterations = 0;
  uint32_t residual_recomputations = 0;
  uint32_t relinearisations = 0;
  uint32_t rescales = 0;
  uint32_t max_scale = 0;
  uint32_t stalls = 0;
  double wall_time_s = 0.0;
  std::string exit_reason;  // "tolerance", "resolution", "exhausted" or "failed"
  std::optional<double> objective_bound_headings;  // certified bounds (pose_graph.h,
  std::optional<double> objective_bound_positions;  // PoseGraphStats::objective_bound), the
  std::optional<double> objective_bound_finish;     // file's chi2 units
  std::optional<double> heading_bound_rad;
  std::optional<double> position_bound_m;
  // Settings.
  double tolerance_xy_m = 0.0;
  double tolerance_heading_rad = 0.0;
  double tolerance_objective = 0.0;  // the file's chi2 units (0: off)
  uint32_t max_iterations = 0;
  uint32_t max_restarts = 0;
  uint32_t refine_restarts = 0;
  // --reference: double-precision Gauss-Newton of the same stored problem from the result.
  std::optional<double> reference_chi2;
  std::optional<double> reference_max_position_difference_m;
  std::optional<double> reference_max_heading_difference_rad;
  std::optional<double> reference_ate_m;
};

std::string graph_figures_json(const GraphFigures& f);

}  // namespace seqslam::tools
