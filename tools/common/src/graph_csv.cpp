#include "seqslam_tools/graph_csv.h"

#include <cstdio>

#include "seqslam_tools/q_format.h"

namespace seqslam::tools {

std::string graph_node_line(uint32_t index, uint32_t place, const Pose2& pose) {
  char line[160];
  std::snprintf(line, sizeof line, "%u,%u,%.6f,%.6f,%.6f\n", index, place, to_double(pose.x),
                to_double(pose.y), to_degrees(pose.heading));
  return line;
}

std::string graph_edge_line(const PoseGraphEdge& e, bool closure) {
  char line[200];
  std::snprintf(line, sizeof line, "%u,%u,%s,%.6f,%.6f,%.6f,%.5f,%.5f\n", e.from, e.to,
                closure ? "closure" : "odometry", to_double(e.dx), to_double(e.dy),
                to_degrees(e.dtheta), to_double(e.info_xy), to_double(e.info_heading));
  return line;
}

std::string graph_nodes_csv(const PoseGraph& graph) {
  std::string text = kGraphNodesHeader;
  for (uint32_t i = 0; i < graph.node_count(); ++i)
    text += graph_node_line(i, graph.place(i).value(), graph.pose(i).value());
  return text;
}

std::string graph_edges_csv(const PoseGraph& graph) {
  std::string text = kGraphEdgesHeader;
  const uint32_t odometry_edges = graph.node_count() > 0 ? graph.node_count() - 1 : 0;
  for (uint32_t i = 0; i < graph.edge_count(); ++i)
    text += graph_edge_line(graph.edge(i).value(), i >= odometry_edges);
  return text;
}

}  // namespace seqslam::tools
