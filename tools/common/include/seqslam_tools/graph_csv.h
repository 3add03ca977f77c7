// The pose graph as two CSV files, one line per node and per edge: what `seqslam disk map`
// exports from the card's `graph` file and `seqslam slam --out` from its replay, so the two
// can be compared byte for byte (the same graph gives the same text).
#pragma once

#include <stdint.h>

#include <string>

#include "seqslam/pose_graph.h"

namespace seqslam::tools {

// "index,place,x_m,y_m,heading_deg" and one line per node (6 decimals, heading signed).
inline constexpr const char* kGraphNodesHeader = "index,place,x_m,y_m,heading_deg\n";
std::string graph_node_line(uint32_t index, uint32_t place, const Pose2& pose);

// "from,to,kind,dx_m,dy_m,dtheta_deg,info_xy,info_heading" and one line per edge (kind
// "odometry" or "closure").
inline constexpr const char* kGraphEdgesHeader =
    "from,to,kind,dx_m,dy_m,dtheta_deg,info_xy,info_heading\n";
std::string graph_edge_line(const PoseGraphEdge& edge, bool closure);

// Both files' text of a graph in memory (edges in the graph's order: odometry, then closures).
std::string graph_nodes_csv(const PoseGraph& graph);
std::string graph_edges_csv(const PoseGraph& graph);

}  // namespace seqslam::tools
