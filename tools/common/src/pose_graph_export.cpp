#include "seqslam_tools/pose_graph_export.h"

#include <nlohmann/json.hpp>

#include "seqslam_tools/q_format.h"

namespace seqslam::tools {

std::vector<GraphPose> graph_poses_of(const PoseGraph& graph) {
  std::vector<GraphPose> out;
  for (uint32_t i = 0; i < graph.node_count(); ++i) {
    const Pose2 p = graph.pose(i).value();
    out.push_back(GraphPose{to_double(p.x), to_double(p.y), to_radians(p.heading)});
  }
  return out;
}

std::vector<GraphEdge> graph_edges_of(const PoseGraph& graph, double information_scale) {
  std::vector<GraphEdge> out;
  for (uint32_t i = 0; i < graph.edge_count(); ++i) {
    const PoseGraphEdge e = graph.edge(i).value();
    GraphEdge g;
    g.from = e.from;
    g.to = e.to;
    g.measured = GraphPose{to_double(e.dx), to_double(e.dy), to_radians(e.dtheta)};
    const double k = 1.0 / information_scale;
    const double core[6] = {to_double(e.info_xy) * k,      to_double(e.info_cross) * k,
                            to_double(e.info_along_heading) * k, to_double(e.info_lateral) * k,
                            to_double(e.info_lateral_heading) * k, to_double(e.info_heading) * k};
    information_to_g2o(g.measured.theta, core, g.info);
    out.push_back(g);
  }
  return out;
}

namespace {
nlohmann::ordered_json optional_number(const std::optional<double>& v) {
  return v ? nlohmann::ordered_json(*v) : nlohmann::ordered_json(nullptr);
}
}  // namespace

std::string graph_figures_json(const GraphFigures& f) {
  nlohmann::ordered_json j;
  j["input"] = f.input;
  j["format"] = f.format;
  j["nodes"] = f.nodes;
  j["edges"] = f.edges;
  j["odometry_edges"] = f.odometry_edges;
  j["loop_closures"] = f.loop_closures;
  j["information_scale_log2"] = f.information_scale_log2;
  j["chi2_chained_odometry"] = f.chi2_initial;
  j["chi2_optimised"] = f.chi2_final;
  j["chi2_file_vertices"] = optional_number(f.chi2_file_vertices);
  j["ate_chained_odometry_m"] = optional_number(f.ate_initial_m);
  j["ate_optimised_m"] = optional_number(f.ate_final_m);
  j["work_units"] = f.work_units;
  j["slices"] = f.slices;
  j["cg_iterations"] = f.cg_iterations;
  j["residual_recomputations"] = f.residual_recomputations;
  j["relinearisations"] = f.relinearisations;
  j["rescales"] = f.rescales;
  j["max_scale_bits"] = f.max_scale;
  j["stalls"] = f.stalls;
  j["wall_time_s"] = f.wall_time_s;
  j["exit_reason"] = f.exit_reason;
  j["objective_bound_headings"] = optional_number(f.objective_bound_headings);
  j["objective_bound_positions"] = optional_number(f.objective_bound_positions);
  j["objective_bound_finish"] = optional_number(f.objective_bound_finish);
  j["heading_bound_rad"] = optional_number(f.heading_bound_rad);
  j["position_bound_m"] = optional_number(f.position_bound_m);
  j["tolerance_xy_m"] = f.tolerance_xy_m;
  j["tolerance_heading_rad"] = f.tolerance_heading_rad;
  j["tolerance_objective"] = f.tolerance_objective;
  j["max_iterations"] = f.max_iterations;
  j["max_restarts"] = f.max_restarts;
  j["refine_restarts"] = f.refine_restarts;
  j["reference_gauss_newton_chi2"] = optional_number(f.reference_chi2);
  j["reference_max_position_difference_m"] =
      optional_number(f.reference_max_position_difference_m);
  j["reference_max_heading_difference_rad"] =
      optional_number(f.reference_max_heading_difference_rad);
  j["reference_ate_m"] = optional_number(f.reference_ate_m);
  return j.dump(2) + "\n";
}

}  // namespace seqslam::tools
