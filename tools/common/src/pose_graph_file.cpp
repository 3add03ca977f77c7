#include "seqslam_tools/pose_graph_file.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <algorithm>
#include <fstream>
#include <iterator>
#include <set>
#include <sstream>

namespace seqslam::tools {

namespace {

constexpr double kPi = 3.14159265358979323846;

std::string where(const std::string& name, int line) {
  return name + ":" + std::to_string(line) + ": ";
}

// Whitespace-separated fields of one line.
std::vector<std::string_view> fields_of(std::string_view line) {
  std::vector<std::string_view> out;
  size_t i = 0;
  while (i < line.size()) {
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t' || line[i] == '\r')) ++i;
    const size_t start = i;
    while (i < line.size() && line[i] != ' ' && line[i] != '\t' && line[i] != '\r') ++i;
    if (i > start) out.push_back(line.substr(start, i - start));
  }
  return out;
}

bool parse_number(std::string_view field, double* out) {
  if (field.empty() || field.size() > 64) return false;
  const std::string s(field);
  char* end = nullptr;
  errno = 0;
  const double v = std::strtod(s.c_str(), &end);
  if (end != s.c_str() + s.size() || errno == ERANGE || !std::isfinite(v)) return false;
  *out = v;
  return true;
}

bool parse_id(std::string_view field, long* out) {
  if (field.empty() || field.size() > 6) return false;
  long v = 0;
  for (const char c : field) {
    if (c < '0' || c > '9') return false;
    v = v * 10 + (c - '0');
  }
  if (v > kMaxGraphId) return false;
  *out = v;
  return true;
}

// Symmetric positive semi-definite with a positive diagonal (the upper triangle xx xy xt yy yt
// tt), by a Cholesky factorisation that allows a relative rounding of 1e-9.
bool information_ok(const double m[6]) {
  const double a[3][3] = {{m[0], m[1], m[2]}, {m[1], m[3], m[4]}, {m[2], m[4], m[5]}};
  if (!(m[0] > 0.0 && m[3] > 0.0 && m[5] > 0.0)) return false;
  double l[3][3] = {};
  for (int j = 0; j < 3; ++j) {
    double d = a[j][j];
    for (int k = 0; k < j; ++k) d -= l[j][k] * l[j][k];
    if (d < -1e-9 * a[j][j]) return false;
    l[j][j] = d > 0.0 ? std::sqrt(d) : 0.0;
    for (int i = j + 1; i < 3; ++i) {
      double s = a[i][j];
      for (int k = 0; k < j; ++k) s -= l[i][k] * l[j][k];
      l[i][j] = l[j][j] > 0.0 ? s / l[j][j] : 0.0;
      if (l[j][j] == 0.0 && std::fabs(s) > 1e-9 * std::sqrt(a[i][i] * a[j][j])) return false;
    }
  }
  return true;
}

// S^T S for the upper-triangular square root S (sxx sxy sxt syy syt stt, row-first).
void information_from_root(const double s[6], double out[6]) {
  const double r[3][3] = {{s[0], s[1], s[2]}, {0.0, s[3], s[4]}, {0.0, 0.0, s[5]}};
  int k = 0;
  for (int i = 0; i < 3; ++i) {
    for (int j = i; j < 3; ++j) {
      double v = 0.0;
      for (int t = 0; t < 3; ++t) v += r[t][i] * r[t][j];
      out[k++] = v;
    }
  }
}

}  // namespace

double wrap_angle(double radians) {
  double a = std::fmod(radians, 2.0 * kPi);
  if (a > kPi) a -= 2.0 * kPi;
  if (a <= -kPi) a += 2.0 * kPi;
  return a;
}

GraphPose compose(const GraphPose& a, const GraphPose& b) {
  const double c = std::cos(a.theta);
  const double s = std::sin(a.theta);
  return GraphPose{a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, a.theta + b.theta};
}

GraphPose between(const GraphPose& a, const GraphPose& b) {
  const double c = std::cos(a.theta);
  const double s = std::sin(a.theta);
  const double dx = b.x - a.x;
  const double dy = b.y - a.y;
  return GraphPose{c * dx + s * dy, -s * dx + c * dy, b.theta - a.theta};
}

namespace {
// R(angle) Omega_pos R^T and R(angle) Omega_pt for an upper triangle xx xy xt yy yt tt.
void turn_information(double angle, const double in[6], double out[6]) {
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  const double a = in[0], k = in[1], l = in[3];
  out[0] = a * c * c - 2 * k * c * s + l * s * s;
  out[1] = (a - l) * c * s + k * (c * c - s * s);
  out[3] = a * s * s + 2 * k * c * s + l * c * c;
  out[2] = c * in[2] - s * in[4];
  out[4] = s * in[2] + c * in[4];
  out[5] = in[5];
}
}  // namespace

void information_in_from_frame(const GraphEdge& edge, double out[6]) {
  turn_information(edge.measured.theta, edge.info, out);
}

void information_to_g2o(double dtheta, const double in[6], double out[6]) {
  turn_information(-dtheta, in, out);
}

Outcome<GraphFile> parse_pose_graph(std::string_view text, const std::string& name) {
  GraphFile g;
  std::set<long> vertex_ids;
  bool g2o = false;
  int line_no = 0;
  size_t pos = 0;
  while (pos < text.size()) {
    size_t end = text.find('\n', pos);
    if (end == std::string_view::npos) end = text.size();
    const std::string_view line = text.substr(pos, end - pos);
    pos = end + 1;
    ++line_no;
    if (line.find('\0') != std::string_view::npos) {
      return Error{where(name, line_no) + "a NUL byte: not a text file"};
    }
    const std::vector<std::string_view> f = fields_of(line);
    if (f.empty() || f[0][0] == '#') continue;
    const std::string_view tag = f[0];
    const bool isam_record = tag == "ODOMETRY" || tag == "EDGE2";
    const bool g2o_record = tag == "VERTEX_SE2" || tag == "EDGE_SE2" || tag == "FIX";
    if (!isam_record && !g2o_record) {
      const std::string shown(tag.substr(0, 40));
      return Error{where(name, line_no) + "unknown record '" + shown +
                   "' (2-D pose graphs: g2o VERTEX_SE2 / EDGE_SE2, iSAM ODOMETRY / EDGE2)"};
    }
    if ((isam_record && g2o) || (g2o_record && g.isam)) {
      return Error{where(name, line_no) + "g2o and iSAM records in one file"};
    }
    g2o = g2o || g2o_record;
    g.isam = g.isam || isam_record;
    if (tag == "FIX") {
      long id = 0;
      if (f.size() != 2 || !parse_id(f[1], &id)) {
        return Error{where(name, line_no) + "FIX needs one id in 0.." +
                     std::to_string(kMaxGraphId)};
      }
      if (id != 0) {
        return Error{where(name, line_no) + "only node 0 can be fixed (the optimiser's anchor)"};
      }
      continue;
    }
    if (tag == "VERTEX_SE2") {
      GraphVertex v;
      v.line = line_no;
      if (f.size() != 5) {
        return Error{where(name, line_no) + "VERTEX_SE2 needs 4 fields (id x y theta), found " +
                     std::to_string(f.size() - 1)};
      }
      if (!parse_id(f[1], &v.id)) {
        return Error{where(name, line_no) + "the vertex id must be an integer 0.." +
                     std::to_string(kMaxGraphId)};
      }
      if (!parse_number(f[2], &v.pose.x) || !parse_number(f[3], &v.pose.y) ||
          !parse_number(f[4], &v.pose.theta)) {
        return Error{where(name, line_no) + "x, y and theta must be finite numbers"};
      }
      if (!vertex_ids.insert(v.id).second) {
        return Error{where(name, line_no) + "vertex " + std::to_string(v.id) + " given twice"};
      }
      g.vertices.push_back(v);
      continue;
    }
    // An edge (EDGE_SE2, ODOMETRY, EDGE2): i j dx dy dtheta and six information numbers.
    GraphEdge e;
    e.line = line_no;
    if (f.size() != 12) {
      return Error{where(name, line_no) + std::string(tag) +
                   " needs 11 fields (i j dx dy dtheta and 6 information numbers), found " +
                   std::to_string(f.size() - 1)};
    }
    if (!parse_id(f[1], &e.from) || !parse_id(f[2], &e.to)) {
      return Error{where(name, line_no) + "the node ids must be integers 0.." +
                   std::to_string(kMaxGraphId)};
    }
    if (e.from == e.to) {
      return Error{where(name, line_no) + "an edge from node " + std::to_string(e.from) +
                   " to itself"};
    }
    double numbers[9];
    for (int k = 0; k < 9; ++k) {
      if (!parse_number(f[static_cast<size_t>(3 + k)], &numbers[k])) {
        return Error{where(name, line_no) + "field " + std::to_string(4 + k) +
                     " must be a finite number"};
      }
    }
    e.measured = GraphPose{numbers[0], numbers[1], numbers[2]};
    if (isam_record) {
      information_from_root(numbers + 3, e.info);
    } else {
      for (int k = 0; k < 6; ++k) e.info[k] = numbers[3 + k];
    }
    if (!information_ok(e.info)) {
      return Error{where(name, line_no) +
                   "the information matrix must be symmetric positive semi-definite with a "
                   "positive diagonal"};
    }
    g.edges.push_back(e);
  }
  if (g.edges.empty() && g.vertices.empty()) {
    return Error{name + ": no vertices or edges (not a 2-D pose graph)"};
  }
  return g;
}

Outcome<GraphFile> load_pose_graph(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot open"};
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return Error{path + ": read failed"};
  return parse_pose_graph(text.str(), path);
}

double graph_chi2(const GraphFile& graph, const std::vector<GraphPose>& poses) {
  double sum = 0.0;
  for (const GraphEdge& e : graph.edges) {
    const GraphPose& a = poses[static_cast<size_t>(e.from)];
    const GraphPose& b = poses[static_cast<size_t>(e.to)];
    // Z^-1 (A^-1 B): the estimate's relative pose seen from the measurement.
    const GraphPose r = between(e.measured, between(a, b));
    const double v[3] = {r.x, r.y, wrap_angle(r.theta)};
    const double* m = e.info;
    sum += m[0] * v[0] * v[0] + m[3] * v[1] * v[1] + m[5] * v[2] * v[2] +
           2.0 * (m[1] * v[0] * v[1] + m[2] * v[0] * v[2] + m[4] * v[1] * v[2]);
  }
  return sum;
}

Outcome<std::vector<GraphPose>> graph_trajectory(const GraphFile& graph, const std::string& name) {
  if (!graph.vertices.empty()) {
    const size_t n = graph.vertices.size();
    std::vector<GraphPose> out(n);
    std::vector<bool> seen(n, false);
    for (const GraphVertex& v : graph.vertices) {
      if (static_cast<size_t>(v.id) >= n) {
        return Error{where(name, v.line) + "vertex ids must be 0.." + std::to_string(n - 1) +
                     " (one each)"};
      }
      out[static_cast<size_t>(v.id)] = v.pose;
      seen[static_cast<size_t>(v.id)] = true;
    }
    for (size_t k = 0; k < n; ++k) {
      if (!seen[k]) return Error{name + ": vertex " + std::to_string(k) + " is missing"};
    }
    return out;
  }
  // Chained odometry: the first edge k-1 -> k for each k.
  long last = 0;
  for (const GraphEdge& e : graph.edges) last = std::max(last, std::max(e.from, e.to));
  const size_t n = static_cast<size_t>(last) + 1;
  std::vector<const GraphEdge*> step(n, nullptr);
  for (const GraphEdge& e : graph.edges) {
    if (e.to == e.from + 1 && step[static_cast<size_t>(e.to)] == nullptr) {
      step[static_cast<size_t>(e.to)] = &e;
    }
  }
  std::vector<GraphPose> out(n);
  for (size_t k = 1; k < n; ++k) {
    if (step[k] == nullptr) {
      return Error{name + ": no odometry edge " + std::to_string(k - 1) + " -> " +
                   std::to_string(k) + " (a trajectory needs one for every node)"};
    }
    out[k] = compose(out[k - 1], step[k]->measured);
  }
  return out;
}

double absolute_trajectory_error(const std::vector<GraphPose>& estimate,
                                 const std::vector<GraphPose>& truth) {
  const size_t n = std::min(estimate.size(), truth.size());
  if (n == 0) return 0.0;
  double ex = 0, ey = 0, tx = 0, ty = 0;
  for (size_t i = 0; i < n; ++i) {
    ex += estimate[i].x;
    ey += estimate[i].y;
    tx += truth[i].x;
    ty += truth[i].y;
  }
  ex /= static_cast<double>(n);
  ey /= static_cast<double>(n);
  tx /= static_cast<double>(n);
  ty /= static_cast<double>(n);
  // The rotation that best maps the centred estimate onto the centred truth.
  double sc = 0, ss = 0;
  for (size_t i = 0; i < n; ++i) {
    const double ax = estimate[i].x - ex, ay = estimate[i].y - ey;
    const double bx = truth[i].x - tx, by = truth[i].y - ty;
    sc += ax * bx + ay * by;
    ss += ax * by - ay * bx;
  }
  const double phi = std::atan2(ss, sc);
  const double c = std::cos(phi), s = std::sin(phi);
  double sum = 0;
  for (size_t i = 0; i < n; ++i) {
    const double ax = estimate[i].x - ex, ay = estimate[i].y - ey;
    const double dx = c * ax - s * ay - (truth[i].x - tx);
    const double dy = s * ax + c * ay - (truth[i].y - ty);
    sum += dx * dx + dy * dy;
  }
  return std::sqrt(sum / static_cast<double>(n));
}

std::string g2o_text(const std::vector<GraphPose>& poses, const std::vector<GraphEdge>& edges) {
  std::string out;
  char buf[512];
  for (size_t i = 0; i < poses.size(); ++i) {
    std::snprintf(buf, sizeof buf, "VERTEX_SE2 %zu %.17g %.17g %.17g\n", i, poses[i].x,
                  poses[i].y, poses[i].theta);
    out += buf;
  }
  for (const GraphEdge& e : edges) {
    std::snprintf(buf, sizeof buf,
                  "EDGE_SE2 %ld %ld %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g %.17g\n",
                  e.from, e.to, e.measured.x, e.measured.y, e.measured.theta, e.info[0],
                  e.info[1], e.info[2], e.info[3], e.info[4], e.info[5]);
    out += buf;
  }
  return out;
}

}  // namespace seqslam::tools
