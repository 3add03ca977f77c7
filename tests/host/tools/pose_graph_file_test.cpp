// 2-D pose-graph files (seqslam_tools/pose_graph_file.h, issue 35): g2o and iSAM records read
// into one form (iSAM's square-root information squared), the objective and the trajectory
// error against hand-computed values, g2o written and read back, the information turned
// between g2o's convention and the core's and back, and every kind of bad file refused with
// its line number.
#include "seqslam_tools/pose_graph_file.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

namespace seqslam::tools::test {
namespace {

TEST(PoseGraphFile, ReadsG2oAndIsam) {
  const auto g = parse_pose_graph(
      "# a comment\n"
      "VERTEX_SE2 0 0 0 0\n"
      "VERTEX_SE2 1 1.5 -0.25 0.1\n"
      "\n"
      "EDGE_SE2 0 1 1.5 -0.25 0.1 10 1 2 20 3 30\r\n"
      "FIX 0\n",
      "a.g2o");
  ASSERT_TRUE(g.ok()) << g.error();
  ASSERT_EQ(g.value().vertices.size(), 2u);
  ASSERT_EQ(g.value().edges.size(), 1u);
  EXPECT_FALSE(g.value().isam);
  const GraphEdge& e = g.value().edges[0];
  EXPECT_EQ(e.from, 0);
  EXPECT_EQ(e.to, 1);
  EXPECT_EQ(e.line, 5);
  EXPECT_DOUBLE_EQ(e.measured.theta, 0.1);
  const double want[6] = {10, 1, 2, 20, 3, 30};
  for (int k = 0; k < 6; ++k) EXPECT_DOUBLE_EQ(e.info[k], want[k]);

  // iSAM: the information is S^T S of the upper-triangular root (sxx sxy sxt syy syt stt).
  const auto i = parse_pose_graph("ODOMETRY 0 1 1 0 0 2 1 0 3 0 4\nEDGE2 1 0 -1 0 0 2 0 0 2 0 2\n",
                                  "m.txt");
  ASSERT_TRUE(i.ok()) << i.error();
  EXPECT_TRUE(i.value().isam);
  const double* m = i.value().edges[0].info;
  EXPECT_DOUBLE_EQ(m[0], 4);   // 2*2
  EXPECT_DOUBLE_EQ(m[1], 2);   // 2*1
  EXPECT_DOUBLE_EQ(m[2], 0);
  EXPECT_DOUBLE_EQ(m[3], 10);  // 1 + 9
  EXPECT_DOUBLE_EQ(m[4], 0);
  EXPECT_DOUBLE_EQ(m[5], 16);
}

TEST(PoseGraphFile, RefusesBadFilesWithTheLine) {
  const struct {
    const char* text;
    const char* message;
  } bad[] = {
      {"", "g.g2o: no vertices or edges"},
      {"VERTEX_SE2 0 0 0 0\nVERTEX_SE3:QUAT 1 0 0 0 0 0 0 1\n", "g.g2o:2: unknown record"},
      {"VERTEX_SE2 0 0 0\n", "g.g2o:1: VERTEX_SE2 needs 4 fields"},
      {"VERTEX_SE2 -1 0 0 0\n", "g.g2o:1: the vertex id must be"},
      {"VERTEX_SE2 65535 0 0 0\n", "g.g2o:1: the vertex id must be"},
      {"VERTEX_SE2 0 nan 0 0\n", "g.g2o:1: x, y and theta must be finite"},
      {"VERTEX_SE2 0 1e999 0 0\n", "g.g2o:1: x, y and theta must be finite"},
      {"VERTEX_SE2 0 0 0 0\nVERTEX_SE2 0 1 0 0\n", "g.g2o:2: vertex 0 given twice"},
      {"EDGE_SE2 0 1 1 0 0 1 0 0 1 0\n", "g.g2o:1: EDGE_SE2 needs 11 fields"},
      {"EDGE_SE2 0 0 1 0 0 1 0 0 1 0 1\n", "g.g2o:1: an edge from node 0 to itself"},
      {"EDGE_SE2 0 x 1 0 0 1 0 0 1 0 1\n", "g.g2o:1: the node ids must be"},
      {"EDGE_SE2 0 1 1 0 0 1 0 0 1 0 abc\n", "g.g2o:1: field 12 must be a finite number"},
      {"EDGE_SE2 0 1 1 0 0 1 5 0 1 0 1\n", "g.g2o:1: the information matrix must be"},
      {"EDGE_SE2 0 1 1 0 0 -1 0 0 1 0 1\n", "g.g2o:1: the information matrix must be"},
      {"EDGE_SE2 0 1 1 0 0 1 0 0 1 0 0\n", "g.g2o:1: the information matrix must be"},
      {"VERTEX_SE2 0 0 0 0\nODOMETRY 0 1 1 0 0 1 0 0 1 0 1\n", "g.g2o:2: g2o and iSAM records"},
      {"FIX 3\n", "g.g2o:1: only node 0 can be fixed"},
  };
  for (const auto& b : bad) {
    const auto g = parse_pose_graph(b.text, "g.g2o");
    ASSERT_FALSE(g.ok()) << b.text;
    EXPECT_EQ(g.error().rfind(b.message, 0), 0u) << "got: " << g.error();
  }
  const char binary[] = "VERTEX_SE2 0 0 0 0\n\nVERTEX_SE2 1 0\0 0 0\n";
  const auto nul = parse_pose_graph(std::string(binary, sizeof binary - 1), "g.g2o");
  ASSERT_FALSE(nul.ok());
  EXPECT_EQ(nul.error().rfind("g.g2o:3: a NUL byte", 0), 0u) << nul.error();
  EXPECT_FALSE(load_pose_graph("/nonexistent/graph.g2o").ok());
}

TEST(PoseGraphFile, ObjectiveTrajectoryAndAlignment) {
  // Two nodes, the edge measures 1 m ahead; the estimate has node 1 at (1, 0.1): error 0.1 m
  // across, information 100 there: chi2 1.
  const auto g = parse_pose_graph("EDGE_SE2 0 1 1 0 0 1 0 0 100 0 1\n", "g");
  ASSERT_TRUE(g.ok());
  EXPECT_NEAR(graph_chi2(g.value(), {{0, 0, 0}, {1, 0.1, 0}}), 1.0, 1e-12);
  // The heading error is wrapped: 2 pi + 0.1 counts as 0.1.
  EXPECT_NEAR(graph_chi2(g.value(), {{0, 0, 0}, {1, 0, 0.1 + 2 * M_PI}}), 0.01, 1e-12);
  // A trajectory from chained odometry (iSAM ground truth) and from vertices.
  const auto chain = parse_pose_graph(
      "EDGE2 0 1 1 0 1.5707963267948966 1 0 0 1 0 1\nEDGE2 1 2 2 0 0 1 0 0 1 0 1\n"
      "EDGE2 0 2 0 0 0 1 0 0 1 0 1\n",
      "t");
  ASSERT_TRUE(chain.ok());
  const auto t = graph_trajectory(chain.value(), "t");
  ASSERT_TRUE(t.ok()) << t.error();
  ASSERT_EQ(t.value().size(), 3u);
  EXPECT_NEAR(t.value()[2].x, 1.0, 1e-12);
  EXPECT_NEAR(t.value()[2].y, 2.0, 1e-12);
  const auto gap = parse_pose_graph("EDGE2 0 1 1 0 0 1 0 0 1 0 1\nEDGE2 1 3 1 0 0 1 0 0 1 0 1\n", "t");
  ASSERT_TRUE(gap.ok());
  EXPECT_FALSE(graph_trajectory(gap.value(), "t").ok()) << "no edge 2 -> 3";
  const auto holes = parse_pose_graph("VERTEX_SE2 0 0 0 0\nVERTEX_SE2 2 0 0 0\n", "v");
  ASSERT_TRUE(holes.ok());
  EXPECT_FALSE(graph_trajectory(holes.value(), "v").ok()) << "vertex 1 missing";
  // ATE: a rotated and shifted copy aligns to 0; one point off by d gives d sqrt(...) RMS.
  std::vector<GraphPose> truth = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
  std::vector<GraphPose> moved;
  for (const GraphPose& p : truth) {
    moved.push_back({5 + std::cos(0.3) * p.x - std::sin(0.3) * p.y,
                     -2 + std::sin(0.3) * p.x + std::cos(0.3) * p.y, p.theta});
  }
  EXPECT_NEAR(absolute_trajectory_error(moved, truth), 0.0, 1e-12);
  std::vector<GraphPose> scaled = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0}};
  EXPECT_NEAR(absolute_trajectory_error(scaled, truth), std::sqrt(0.5), 1e-12);
}

TEST(PoseGraphFile, WritesG2oThatReadsBack) {
  GraphEdge e;
  e.from = 0;
  e.to = 1;
  e.measured = {0.1, 0.2, 0.3};
  const double info[6] = {1.0 / 3, 0.1, 0.0, 7, 0.2, 11};
  for (int k = 0; k < 6; ++k) e.info[k] = info[k];
  const std::string text = g2o_text({{0, 0, 0}, {1.0 / 3, -2.0 / 7, 0.5}}, {e});
  const auto g = parse_pose_graph(text, "out.g2o");
  ASSERT_TRUE(g.ok()) << g.error();
  ASSERT_EQ(g.value().vertices.size(), 2u);
  EXPECT_EQ(g.value().vertices[1].pose.x, 1.0 / 3) << "full precision";
  EXPECT_EQ(g.value().vertices[1].pose.y, -2.0 / 7);
  for (int k = 0; k < 6; ++k) EXPECT_EQ(g.value().edges[0].info[k], info[k]);
  // g2o's information and the core's (in the from frame, before the measured turn) describe
  // the same objective: turned there and back is the identity, and the quadratic forms agree.
  double core[6], back[6];
  information_in_from_frame(e, core);
  information_to_g2o(e.measured.theta, core, back);
  for (int k = 0; k < 6; ++k) EXPECT_NEAR(back[k], info[k], 1e-12);
  const double v[3] = {0.3, -0.7, 0.2};  // an error in g2o's frame
  const double c = std::cos(0.3), s = std::sin(0.3);
  const double w[3] = {c * v[0] - s * v[1], s * v[0] + c * v[1], v[2]};  // the core's
  auto form = [](const double* m, const double* x) {
    return m[0] * x[0] * x[0] + m[3] * x[1] * x[1] + m[5] * x[2] * x[2] +
           2 * (m[1] * x[0] * x[1] + m[2] * x[0] * x[2] + m[4] * x[1] * x[2]);
  };
  EXPECT_NEAR(form(info, v), form(core, w), 1e-12);
}

}  // namespace
}  // namespace seqslam::tools::test
