// libFuzzer target: arbitrary bytes as a 2-D pose-graph file (g2o or iSAM text,
// seqslam_tools/pose_graph_file.h). Parsing must end with a graph or a message naming a line,
// never crash, hang or read out of bounds (ASan/UBSan); what it accepts must be consistent:
// ids in range, no self edges, finite numbers, information with a positive diagonal; the
// objective of the graph at the origin is finite; and a graph written as g2o reads back with
// the same counts.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "seqslam_tools/pose_graph_file.h"

namespace {

[[noreturn]] void violated(const char* what) {
  std::fprintf(stderr, "pose graph file property violated: %s\n", what);
  std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace seqslam::tools;
  const std::string text(reinterpret_cast<const char*>(data), size);
  const Outcome<GraphFile> g = parse_pose_graph(text, "fuzz");
  if (!g.ok()) {
    if (g.error().rfind("fuzz", 0) != 0) violated("a message that does not name the file");
    return 0;
  }
  long last = 0;
  for (const GraphVertex& v : g.value().vertices) {
    if (v.id < 0 || v.id > kMaxGraphId) violated("vertex id out of range");
    if (!std::isfinite(v.pose.x) || !std::isfinite(v.pose.theta)) violated("non-finite vertex");
    last = std::max(last, v.id);
  }
  for (const GraphEdge& e : g.value().edges) {
    if (e.from < 0 || e.to < 0 || e.from > kMaxGraphId || e.to > kMaxGraphId) {
      violated("edge id out of range");
    }
    if (e.from == e.to) violated("self edge accepted");
    if (!(e.info[0] > 0 && e.info[3] > 0 && e.info[5] > 0)) violated("information diagonal");
    last = std::max(last, std::max(e.from, e.to));
  }
  // The objective at the origin (every pose zero) is a finite sum when the numbers are small;
  // huge accepted values may overflow to inf, never to NaN from bad indexing.
  std::vector<GraphPose> origin(static_cast<size_t>(last) + 1);
  const double chi2 = graph_chi2(g.value(), origin);
  if (std::isnan(chi2) && g.value().edges.size() < 4) {
    bool huge = false;
    for (const GraphEdge& e : g.value().edges)
      for (const double v : e.info) huge = huge || std::fabs(v) > 1e100;
    for (const GraphEdge& e : g.value().edges) {
      huge = huge || std::fabs(e.measured.x) > 1e100 || std::fabs(e.measured.y) > 1e100 ||
             std::fabs(e.measured.theta) > 1e100;
    }
    if (!huge) violated("NaN objective from small numbers");
  }
  if (g.value().isam) return 0;
  const std::string again = g2o_text(origin, g.value().edges);
  const Outcome<GraphFile> h = parse_pose_graph(again, "fuzz-again");
  if (!h.ok()) {
    // Values printed at full precision read back, but a matrix on the edge of semi-definite
    // may be refused after the round trip of its decimals; nothing else may fail.
    if (h.error().find("information matrix") == std::string::npos) violated("g2o round trip");
    return 0;
  }
  if (h.value().edges.size() != g.value().edges.size() ||
      h.value().vertices.size() != origin.size()) {
    violated("g2o round trip counts");
  }
  return 0;
}
