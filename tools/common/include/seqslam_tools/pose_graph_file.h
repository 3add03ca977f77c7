// 2-D pose-graph files of the SLAM literature (issue 35): g2o (VERTEX_SE2 / EDGE_SE2 with the
// upper triangle of the 3x3 information) and iSAM's text format (ODOMETRY / EDGE2 with the
// upper-triangular square-root information, /work/shared/data/posegraph/iSAM_data_README.txt),
// read into one in-memory form; g2o written back; the g2o objective (chi2) and the absolute
// trajectory error for the reports of `seqslam graph` (docs/mapping.md, "Public pose graphs").
//
// Depends on nothing but the C++ library (the fuzz target compiles it on its own). Bad input
// is refused with "NAME:LINE: what is wrong"; nothing is trusted (counts, ids, numbers).
#pragma once

#include <string>
#include <string_view>
#include <vector>

#include "seqslam_tools/outcome.h"

namespace seqslam::tools {

struct GraphPose {
  double x = 0.0;
  double y = 0.0;
  double theta = 0.0;  // radians
};

struct GraphVertex {
  long id = 0;
  GraphPose pose;
  int line = 0;
};

// The pose of `to` seen from `from` and the information of that measurement in from's frame,
// the upper triangle of the symmetric 3x3 matrix (x, y, theta): xx xy xt yy yt tt.
struct GraphEdge {
  long from = 0;
  long to = 0;
  GraphPose measured;
  double info[6] = {0, 0, 0, 0, 0, 0};
  int line = 0;
};

struct GraphFile {
  std::vector<GraphVertex> vertices;  // in file order
  std::vector<GraphEdge> edges;       // in file order
  bool isam = false;                  // the records were iSAM's (ODOMETRY / EDGE2)
};

// Ids are 0..kMaxGraphId (the core's node indices are 16-bit, pose_graph.h).
inline constexpr long kMaxGraphId = 65534;

// Parses `text`; `name` is used in messages. Records: `VERTEX_SE2 id x y theta`, `EDGE_SE2 i j
// dx dy dtheta I11 I12 I13 I22 I23 I33`, `ODOMETRY|EDGE2 i j dx dy dtheta sxx sxy sxt syy syt
// stt` (information = S^T S), `FIX id`; blank lines and lines starting with '#' are skipped.
// Refused: any other record, a wrong number of fields, a field that is not a finite number
// or not an id in 0..kMaxGraphId, a vertex given twice, an edge from a node to itself, an
// information matrix that is not symmetric positive semi-definite with a positive diagonal,
// g2o and iSAM records mixed.
Outcome<GraphFile> parse_pose_graph(std::string_view text, const std::string& name);
// Reads and parses the file (messages name it).
Outcome<GraphFile> load_pose_graph(const std::string& path);

// a (+) b and a^-1 (+) b for poses (the SE(2) group; headings not wrapped).
GraphPose compose(const GraphPose& a, const GraphPose& b);
GraphPose between(const GraphPose& a, const GraphPose& b);
double wrap_angle(double radians);  // to (-pi, pi]

// g2o's information (of the error Z^-1 (X_from^-1 X_to)) as the information of the error
// (R_from^T (p_to - p_from) - d, theta_to - theta_from - dtheta), the pose graph core's: the
// position rows and columns turned by the measured dtheta (R Omega_pos R^T, R Omega_pt), the
// heading's unchanged; the same objective exactly. `to_g2o` is the inverse.
void information_in_from_frame(const GraphEdge& edge, double out[6]);
void information_to_g2o(double dtheta, const double in[6], double out[6]);

// The g2o objective sum_e r^T Omega r, r = (between(between(from, to) ...)): the error of
// `poses[to]` against `poses[from]` composed with the measurement, in the measurement's frame
// (x, y, wrapped theta), with the edge's full 3x3 information. poses[id] for every id used.
double graph_chi2(const GraphFile& graph, const std::vector<GraphPose>& poses);

// A trajectory of nodes 0..n-1 for --truth: the file's vertices (ids 0..n-1, every one
// present), or without vertices its chained odometry (edge k-1 -> k for every k, the first
// such edge; node 0 at the origin) as iSAM's ground-truth files give it. "" or what is
// missing.
Outcome<std::vector<GraphPose>> graph_trajectory(const GraphFile& graph, const std::string& name);

// Root-mean-square position error of `estimate` against `truth` (the first min(sizes)
// poses) after the best rigid 2-D alignment (rotation and translation, least squares).
double absolute_trajectory_error(const std::vector<GraphPose>& estimate,
                                 const std::vector<GraphPose>& truth);

// g2o text: VERTEX_SE2 lines for `poses` (ids 0..n-1), then EDGE_SE2 lines for `edges` with
// their information (full precision, %.17g).
std::string g2o_text(const std::vector<GraphPose>& poses, const std::vector<GraphEdge>& edges);

}  // namespace seqslam::tools
