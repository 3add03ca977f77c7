#include "reference.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "seqslam_tools/q_format.h"

namespace seqslam::reference {

Params Params::from(const LocaliserConfig& c) {
  Params p;
  p.width = c.image_size.width;
  p.height = c.image_size.height;
  p.method = c.preprocess.method;
  p.patch_width = c.preprocess.patch.patch_width;
  p.patch_height = c.preprocess.patch.patch_height;
  p.pn_epsilon = tools::to_double(c.preprocess.patch.epsilon);
  p.pn_gain = tools::to_double(c.preprocess.patch.gain);
  p.max_shift = c.max_shift;
  p.seq_len = c.sequence.seq_len;
  p.window = c.sequence.window;
  p.sigma_min = tools::to_double(c.sequence.sigma_min);
  p.exclusion = c.sequence.exclusion;
  p.threshold = tools::to_double(c.sequence.threshold);
  p.recent_exclusion = c.recent_exclusion;
  return p;
}

Image equalise_histogram(const Image& in) {
  // r' = round(255 * cdf(r)), eq. 4.3.
  std::vector<double> count(256, 0.0);
  for (uint8_t v : in)
    count[v] += 1.0;
  std::vector<double> cdf(256);
  double cum = 0.0;
  for (int r = 0; r < 256; ++r) {
    cum += count[static_cast<size_t>(r)];
    cdf[static_cast<size_t>(r)] = cum / static_cast<double>(in.size());
  }
  Image out(in.size());
  for (size_t i = 0; i < in.size(); ++i) {
    out[i] = static_cast<uint8_t>(std::round(255.0 * cdf[in[i]]));
  }
  return out;
}

Image patch_normalise(const Params& p, const Image& in) {
  // Eq. 4.1 per patch, then 128 + gain * z clamped to 8 bits (preprocess.h).
  Image out(in.size());
  const int cols = std::max(1, p.width / p.patch_width);
  const int rows = std::max(1, p.height / p.patch_height);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < cols; ++c) {
      const int x0 = c * p.width / cols, x1 = (c + 1) * p.width / cols;
      const int y0 = r * p.height / rows, y1 = (r + 1) * p.height / rows;
      double sum = 0.0, n = 0.0;
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x)
          sum += in[static_cast<size_t>(y * p.width + x)], n += 1.0;
      const double mean = sum / n;
      double var = 0.0;
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          const double d = in[static_cast<size_t>(y * p.width + x)] - mean;
          var += d * d;
        }
      const double den = std::sqrt(var / n) + p.pn_epsilon;
      for (int y = y0; y < y1; ++y)
        for (int x = x0; x < x1; ++x) {
          const size_t i = static_cast<size_t>(y * p.width + x);
          const double v = den > 0.0 ? std::round(128.0 + p.pn_gain * (in[i] - mean) / den) : 128.0;
          out[i] = static_cast<uint8_t>(std::clamp(v, 0.0, 255.0));
        }
    }
  }
  return out;
}

Image inverse_gamma(const Image& in) {
  Image out(in.size());
  for (size_t i = 0; i < in.size(); ++i) {
    out[i] = static_cast<uint8_t>(std::round(255.0 * std::pow(in[i] / 255.0, 1.0 / 0.45)));
  }
  return out;
}

Image preprocess(const Params& p, const Image& in) {
  switch (p.method) {
    case Preprocessing::kNone:
      return in;
    case Preprocessing::kHistEq:
      return equalise_histogram(in);
    case Preprocessing::kPatchNorm:
      return patch_normalise(p, in);
    case Preprocessing::kInvGamma:
      return inverse_gamma(in);
    case Preprocessing::kHistEqPatchNorm:
      return patch_normalise(p, equalise_histogram(in));
    case Preprocessing::kInvGammaPatchNorm:
      return patch_normalise(p, inverse_gamma(in));
    case Preprocessing::kInvGammaHistEq:
      return equalise_histogram(inverse_gamma(in));
  }
  return in;
}

double mad(const Params& p, const Image& a, const Image& b) {
  double best = std::numeric_limits<double>::infinity();
  for (int dx = -p.max_shift; dx <= p.max_shift; ++dx) {
    double total = 0.0;
    double n = 0.0;
    for (int y = 0; y < p.height; ++y) {
      for (int x = 0; x < p.width; ++x) {
        const int xa = x + std::max(dx, 0);
        const int xb = x + std::max(-dx, 0);
        if (xa >= p.width || xb >= p.width) continue;
        total += std::fabs(static_cast<double>(a[static_cast<size_t>(y * p.width + xa)]) -
                           b[static_cast<size_t>(y * p.width + xb)]);
        n += 1.0;
      }
    }
    best = std::min(best, total / n);
  }
  return best;
}

namespace {

// z-scores over the window of eq. 4.6 (population std, floored at sigma_min).
std::vector<double> z_scores(const Params& p, const std::vector<double>& d) {
  const int n = static_cast<int>(d.size());
  const int h = p.window / 2;
  std::vector<double> z(d.size());
  for (int j = 0; j < n; ++j) {
    const int lo = std::max(0, j - h);
    const int hi = std::min(n - 1, j + h);
    double sum = 0.0;
    for (int k = lo; k <= hi; ++k)
      sum += d[static_cast<size_t>(k)];
    const double mean = sum / (hi - lo + 1);
    double var = 0.0;
    for (int k = lo; k <= hi; ++k) {
      var += (d[static_cast<size_t>(k)] - mean) * (d[static_cast<size_t>(k)] - mean);
    }
    const double sd = std::max(std::sqrt(var / (hi - lo + 1)), p.sigma_min);
    z[static_cast<size_t>(j)] = (d[static_cast<size_t>(j)] - mean) / sd;
  }
  return z;
}

}  // namespace

std::vector<double> normalise(const Params& p, const std::vector<double>& mad_row) {
  if (p.window == 0) {
    std::vector<double> out(mad_row.size());
    for (size_t j = 0; j < mad_row.size(); ++j)
      out[j] = mad_row[j] / 8.0;
    return out;
  }
  // Offset B = sqrt(W) rounded down to 1/2048 (normalise.h).
  const double offset = std::floor(std::sqrt(static_cast<double>(p.window)) * 2048.0) / 2048.0;
  std::vector<double> out = z_scores(p, mad_row);
  for (double& v : out)
    v += offset;
  return out;
}

Match select(const Params& p, const std::vector<double>& cost, const std::vector<bool>& valid,
             double offset) {
  Match m;
  for (size_t j = 0; j < cost.size(); ++j) {
    if (valid[j] && (m.place < 0 || cost[j] < m.cost)) {
      m.place = static_cast<int>(j);
      m.cost = cost[j];
    }
  }
  if (m.place < 0) return m;
  for (size_t j = 0; j < cost.size(); ++j) {
    if (std::abs(static_cast<int>(j) - m.place) <= p.exclusion || !valid[j]) continue;
    if (m.runner_up < 0 || cost[j] < m.runner_up_cost) {
      m.runner_up = static_cast<int>(j);
      m.runner_up_cost = cost[j];
    }
  }
  m.cost -= offset;
  if (m.runner_up >= 0) m.runner_up_cost -= offset;
  if (m.runner_up >= 0 && m.runner_up_cost > 0.0) m.confidence = m.cost / m.runner_up_cost;
  m.localised = m.runner_up >= 0 && m.confidence < p.threshold;
  return m;
}

void Pipeline::teach(const Image& raw) {
  library_.push_back(preprocess(p_, raw));
}

Match Pipeline::localise(const Image& raw) {
  return step(preprocess(p_, raw), library_.size());
}

Match Pipeline::observe(const Image& raw) {
  const Image q = preprocess(p_, raw);
  const size_t size = library_.size();
  const size_t older = size > static_cast<size_t>(p_.recent_exclusion)
                           ? size - static_cast<size_t>(p_.recent_exclusion)
                           : 0;
  const Match m = step(q, older);
  library_.push_back(q);
  return m;
}

Match Pipeline::step(const Image& query, size_t places) {
  last_mad_.assign(places, 0.0);
  for (size_t j = 0; j < places; ++j)
    last_mad_[j] = mad(p_, query, library_[j]);
  rows_.push_back(normalise(p_, last_mad_));
  for (double v : rows_.back())
    min_value_ = std::min(min_value_, v);
  // Direct eq. 4.12: valid iff the S diagonal cells exist in rows since the last reset.
  const size_t i = rows_.size() - 1;
  const size_t s = static_cast<size_t>(p_.seq_len);
  last_costs_.assign(places, 0.0);
  last_valid_.assign(places, false);
  for (size_t j = 0; j < places; ++j) {
    if (i + 1 < first_row_ + s || j + 1 < s) continue;
    double c = 0.0;
    bool ok = true;
    for (size_t k = 0; k < s && ok; ++k) {
      const std::vector<double>& row = rows_[i - k];
      if (j - k >= row.size()) {
        ok = false;
      } else {
        c += row[j - k];
      }
    }
    last_valid_[j] = ok;
    if (ok) last_costs_[j] = c;
  }
  const double offset = std::isfinite(min_value_) ? p_.seq_len * min_value_ : 0.0;
  return select(p_, last_costs_, last_valid_, offset);
}

std::vector<Match> batch_match(const Params& p,
                               const std::vector<std::vector<double>>& mad_matrix) {
  std::vector<std::vector<double>> z;
  double global_min = std::numeric_limits<double>::infinity();
  for (const std::vector<double>& row : mad_matrix) {
    z.push_back(p.window == 0 ? row : z_scores(p, row));
    for (double v : z.back())
      global_min = std::min(global_min, v);
  }
  for (std::vector<double>& row : z)
    for (double& v : row)
      v -= global_min;
  std::vector<Match> out;
  const size_t s = static_cast<size_t>(p.seq_len);
  for (size_t i = 0; i < z.size(); ++i) {
    const size_t places = z[i].size();
    std::vector<double> cost(places, 0.0);
    std::vector<bool> valid(places, false);
    for (size_t j = 0; j < places && i + 1 >= s; ++j) {
      if (j + 1 < s) continue;
      double c = 0.0;
      for (size_t k = 0; k < s; ++k)
        c += z[i - k][j - k];
      cost[j] = c;
      valid[j] = true;
    }
    out.push_back(select(p, cost, valid, 0.0));
  }
  return out;
}

std::vector<Match> slope_match(const Params& p, const std::vector<std::vector<double>>& rows,
                               const std::vector<double>& velocities) {
  std::vector<Match> out;
  const long s = p.seq_len;
  double min_value = std::numeric_limits<double>::infinity();
  for (size_t i = 0; i < rows.size(); ++i) {
    for (double v : rows[i])
      min_value = std::min(min_value, v);
    const size_t places = rows[i].size();
    std::vector<double> cost(places, 0.0);
    std::vector<bool> valid(places, false);
    for (size_t j = 0; j < places && static_cast<long>(i) + 1 >= s; ++j) {
      for (double v : velocities) {
        double c = 0.0;
        bool ok = true;
        for (long k = 0; k < s && ok; ++k) {
          const std::vector<double>& row = rows[i - static_cast<size_t>(k)];
          const double x = std::floor(static_cast<double>(j) - v * static_cast<double>(k) + 0.5);
          if (x < 0.0 || x >= static_cast<double>(row.size())) {
            ok = false;
          } else {
            c += row[static_cast<size_t>(x)];
          }
        }
        if (ok && (!valid[j] || c < cost[j])) {
          cost[j] = c;
          valid[j] = true;
        }
      }
    }
    const double offset = std::isfinite(min_value) ? p.seq_len * min_value : 0.0;
    out.push_back(select(p, cost, valid, offset));
  }
  return out;
}

}  // namespace seqslam::reference

// ---- Occupancy grid ----
namespace seqslam::reference {

std::vector<GridCellRef> grid_supercover(double x0, double y0, double x1, double y1, double tie) {
  GridCellRef c{static_cast<long>(std::floor(x0)), static_cast<long>(std::floor(y0))};
  const GridCellRef end{static_cast<long>(std::floor(x1)), static_cast<long>(std::floor(y1))};
  std::vector<GridCellRef> out{c};
  const double dx = x1 - x0;
  const double dy = y1 - y0;
  const long sx = dx > 0 ? 1 : -1;
  const long sy = dy > 0 ? 1 : -1;
  const double inf = std::numeric_limits<double>::infinity();
  // t at which the segment leaves the current column / row (the boundary ahead of it); an
  // axis whose end index is reached never steps again, so the walk cannot overshoot.
  auto t_x = [&]() {
    if (dx == 0.0 || c.col == end.col) return inf;
    return (static_cast<double>(sx > 0 ? c.col + 1 : c.col) - x0) / dx;
  };
  auto t_y = [&]() {
    if (dy == 0.0 || c.row == end.row) return inf;
    return (static_cast<double>(sy > 0 ? c.row + 1 : c.row) - y0) / dy;
  };
  while (!(c == end)) {
    const double tx = t_x();
    const double ty = t_y();
    if (tx != inf && ty != inf && std::fabs(tx - ty) <= tie) {
      out.push_back({c.col + sx, c.row});
      out.push_back({c.col, c.row + sy});
      c.col += sx;
      c.row += sy;
    } else if (tx < ty) {
      c.col += sx;
    } else {
      c.row += sy;
    }
    out.push_back(c);
  }
  return out;
}

}  // namespace seqslam::reference

// ---- Pose graph ----
namespace seqslam::reference {

namespace {

constexpr double kPoseTwoPi = 6.283185307179586476925286766559;

// In-place dense Cholesky A = L L^T of an SPD matrix (row-major n x n; L in the lower half).
void cholesky_factor(std::vector<double>& a, size_t n) {
  for (size_t j = 0; j < n; ++j) {
    double d = a[j * n + j];
    for (size_t k = 0; k < j; ++k)
      d -= a[j * n + k] * a[j * n + k];
    const double l = std::sqrt(d);
    a[j * n + j] = l;
    for (size_t i = j + 1; i < n; ++i) {
      double s = a[i * n + j];
      for (size_t k = 0; k < j; ++k)
        s -= a[i * n + k] * a[j * n + k];
      a[i * n + j] = s / l;
    }
  }
}

std::vector<double> cholesky_solve(const std::vector<double>& l, size_t n, std::vector<double> b) {
  for (size_t i = 0; i < n; ++i) {
    for (size_t k = 0; k < i; ++k)
      b[i] -= l[i * n + k] * b[k];
    b[i] /= l[i * n + i];
  }
  for (size_t i = n; i-- > 0;) {
    for (size_t k = i + 1; k < n; ++k)
      b[i] -= l[k * n + i] * b[k];
    b[i] /= l[i * n + i];
  }
  return b;
}

// The weighted Laplacian system of min sum w (x_to - x_from - m)^2 with x_0 = x0 known, over
// the unknowns x_1..x_{n-1}; returns x_0..x_{n-1}. `l` receives the factor for reuse.
struct LinearTerm {
  size_t from;
  size_t to;
  double w;
  double m;
};
std::vector<double> laplacian_rhs(size_t n, const std::vector<LinearTerm>& terms, double x0) {
  std::vector<double> b(n - 1, 0.0);
  for (const LinearTerm& t : terms) {
    if (t.to != 0) b[t.to - 1] += t.w * (t.m + (t.from == 0 ? x0 : 0.0));
    if (t.from != 0) b[t.from - 1] += t.w * (-t.m + (t.to == 0 ? x0 : 0.0));
  }
  return b;
}
std::vector<double> laplacian_factor(size_t n, const std::vector<LinearTerm>& terms) {
  const size_t u = n - 1;
  std::vector<double> a(u * u, 0.0);
  for (const LinearTerm& t : terms) {
    if (t.to != 0) a[(t.to - 1) * u + (t.to - 1)] += t.w;
    if (t.from != 0) a[(t.from - 1) * u + (t.from - 1)] += t.w;
    if (t.to != 0 && t.from != 0) {
      a[(t.to - 1) * u + (t.from - 1)] -= t.w;
      a[(t.from - 1) * u + (t.to - 1)] -= t.w;
    }
  }
  cholesky_factor(a, u);
  return a;
}
std::vector<double> with_anchor(double x0, const std::vector<double>& rest) {
  std::vector<double> x{x0};
  x.insert(x.end(), rest.begin(), rest.end());
  return x;
}

// Row-major 3x3 matrix and 3-vector (aggregates, so brace lists initialise them).
struct M3 {
  double v[9];
  double& operator[](size_t i) { return v[i]; }
  const double& operator[](size_t i) const { return v[i]; }
};
struct V3 {
  double v[3];
  double& operator[](size_t i) { return v[i]; }
  const double& operator[](size_t i) const { return v[i]; }
};

M3 m3_mul(const M3& a, const M3& b) {
  M3 c{};
  for (size_t i = 0; i < 3; ++i)
    for (size_t j = 0; j < 3; ++j)
      for (size_t k = 0; k < 3; ++k)
        c[i * 3 + j] += a[i * 3 + k] * b[k * 3 + j];
  return c;
}
M3 m3_transpose(const M3& a) {
  M3 t{};
  for (size_t i = 0; i < 3; ++i)
    for (size_t j = 0; j < 3; ++j)
      t[i * 3 + j] = a[j * 3 + i];
  return t;
}
V3 m3_apply(const M3& a, const V3& v) {
  V3 r{};
  for (size_t i = 0; i < 3; ++i)
    for (size_t k = 0; k < 3; ++k)
      r[i] += a[i * 3 + k] * v[k];
  return r;
}
M3 m3_inverse(const M3& m) {
  const double a = m[0], b = m[1], c = m[2], d = m[3], e = m[4], f = m[5], g = m[6], h = m[7],
               i = m[8];
  const double A = e * i - f * h, B = -(d * i - f * g), C = d * h - e * g;
  const double det = a * A + b * B + c * C;
  M3 r{A, -(b * i - c * h), b * f - c * e, B, a * i - c * g, -(a * f - c * d),
       C, -(a * h - b * g), a * e - b * d};
  for (size_t k = 0; k < 9; ++k)
    r[k] /= det;
  return r;
}
// a^T w b
M3 m3_weighted(const M3& a, const M3& w, const M3& b) {
  return m3_mul(m3_mul(m3_transpose(a), w), b);
}

double wrap_pi(double a) {
  return a - kPoseTwoPi * std::round(a / kPoseTwoPi);
}

}  // namespace

namespace {

double lateral_info(const PoseEdgeRef& e) {
  return e.info_lateral < 0.0 ? e.info_xy : e.info_lateral;
}

// The position stage with direction-dependent weights: one dense SPD system over
// (x_1, y_1, .., x_{n-1}, y_{n-1}), W = R diag(info_xy, info_lateral) R^T per edge.
std::vector<PoseRef> positions_coupled(const std::vector<PoseEdgeRef>& edges,
                                       const std::vector<double>& theta, const PoseRef& anchor) {
  const size_t n = theta.size();
  const size_t u = 2 * (n - 1);
  std::vector<double> a(u * u, 0.0);
  std::vector<double> b(u, 0.0);
  for (const PoseEdgeRef& e : edges) {
    const size_t f = static_cast<size_t>(e.from);
    const size_t t = static_cast<size_t>(e.to);
    const double c = std::cos(theta[f]);
    const double s = std::sin(theta[f]);
    // W = R Omega R^T, Omega = [[along, cross], [cross, lateral]] in from's frame.
    const double wa = e.info_xy;
    const double wl = lateral_info(e);
    const double wc = e.info_cross;
    const double w[2][2] = {
        {wa * c * c + wl * s * s - 2 * wc * c * s, (wa - wl) * c * s + wc * (c * c - s * s)},
        {(wa - wl) * c * s + wc * (c * c - s * s), wa * s * s + wl * c * c + 2 * wc * c * s}};
    // r = p_t - p_f - m; the known anchor moves to the right-hand side.
    double m[2] = {c * e.dx - s * e.dy, s * e.dx + c * e.dy};
    const double p0[2] = {anchor.x, anchor.y};
    for (size_t i = 0; i < 2; ++i) {
      if (f == 0) m[i] += p0[i];
      if (t == 0) m[i] -= p0[i];
    }
    for (size_t i = 0; i < 2; ++i) {
      for (size_t j = 0; j < 2; ++j) {
        if (t != 0) a[(2 * (t - 1) + i) * u + 2 * (t - 1) + j] += w[i][j];
        if (f != 0) a[(2 * (f - 1) + i) * u + 2 * (f - 1) + j] += w[i][j];
        if (t != 0 && f != 0) {
          a[(2 * (t - 1) + i) * u + 2 * (f - 1) + j] -= w[i][j];
          a[(2 * (f - 1) + i) * u + 2 * (t - 1) + j] -= w[i][j];
        }
      }
      const double wm = w[i][0] * m[0] + w[i][1] * m[1];
      if (t != 0) b[2 * (t - 1) + i] += wm;
      if (f != 0) b[2 * (f - 1) + i] -= wm;
    }
  }
  cholesky_factor(a, u);
  const std::vector<double> p = cholesky_solve(a, u, b);
  std::vector<PoseRef> out(n, anchor);
  for (size_t k = 1; k < n; ++k)
    out[k] = PoseRef{p[2 * (k - 1)], p[2 * (k - 1) + 1], theta[k]};
  return out;
}

}  // namespace

std::vector<PoseEdgeRef> pose_edges_of(const PoseGraph& graph) {
  std::vector<PoseEdgeRef> edges;
  for (uint32_t k = 0; k < graph.edge_count(); ++k) {
    const PoseGraphEdge e = graph.edge(k).value();
    PoseEdgeRef r;
    r.from = e.from;
    r.to = e.to;
    r.dx = tools::to_double(e.dx);
    r.dy = tools::to_double(e.dy);
    r.dtheta = tools::to_radians(e.dtheta);
    r.info_xy = tools::to_double(e.info_xy);
    r.info_heading = tools::to_double(e.info_heading);
    r.info_lateral = tools::to_double(e.info_lateral);
    r.info_cross = tools::to_double(e.info_cross);
    r.info_along_heading = tools::to_double(e.info_along_heading);
    r.info_lateral_heading = tools::to_double(e.info_lateral_heading);
    edges.push_back(r);
  }
  return edges;
}

std::vector<PoseRef> pose_graph_linear(int nodes, const std::vector<PoseEdgeRef>& edges,
                                       const PoseRef& anchor) {
  const size_t n = static_cast<size_t>(nodes);
  std::vector<PoseRef> out(n, anchor);
  if (n <= 1) return out;
  // Unwrapping: the odometry chain's turn between the two nodes of each closure.
  std::vector<double> chain(n, anchor.theta);
  for (size_t k = 1; k < n; ++k)
    chain[k] = chain[k - 1] + edges[k - 1].dtheta;
  std::vector<LinearTerm> heading;
  for (size_t i = 0; i < edges.size(); ++i) {
    const PoseEdgeRef& e = edges[i];
    const size_t f = static_cast<size_t>(e.from);
    const size_t t = static_cast<size_t>(e.to);
    double m = e.dtheta;
    if (i >= n - 1) {
      const double turn = chain[t] - chain[f];
      m += kPoseTwoPi * std::round((turn - m) / kPoseTwoPi);
    }
    heading.push_back({f, t, e.info_heading, m});
  }
  const std::vector<double> theta = with_anchor(
      anchor.theta,
      cholesky_solve(laplacian_factor(n, heading), n - 1, laplacian_rhs(n, heading, anchor.theta)));
  for (const PoseEdgeRef& e : edges) {
    if (lateral_info(e) != e.info_xy || e.info_cross != 0.0) {
      return positions_coupled(edges, theta, anchor);
    }
  }
  std::vector<LinearTerm> px;
  std::vector<LinearTerm> py;
  for (const PoseEdgeRef& e : edges) {
    const size_t f = static_cast<size_t>(e.from);
    const size_t t = static_cast<size_t>(e.to);
    const double c = std::cos(theta[f]);
    const double s = std::sin(theta[f]);
    px.push_back({f, t, e.info_xy, c * e.dx - s * e.dy});
    py.push_back({f, t, e.info_xy, s * e.dx + c * e.dy});
  }
  const std::vector<double> l = laplacian_factor(n, px);  // the same matrix for x and y
  const std::vector<double> x =
      with_anchor(anchor.x, cholesky_solve(l, n - 1, laplacian_rhs(n, px, anchor.x)));
  const std::vector<double> y =
      with_anchor(anchor.y, cholesky_solve(l, n - 1, laplacian_rhs(n, py, anchor.y)));
  for (size_t i = 0; i < n; ++i)
    out[i] = PoseRef{x[i], y[i], theta[i]};
  return out;
}

namespace {

// min sum over terms of (x_to - x_from - m)^T W (x_to - x_from - m), x_0 = x0 known, for
// `dim` components (W dim x dim, row-major), by CG preconditioned with the chain (terms[k-1]
// joins k-1 and k) weighted by `chain_w` (a scalar per chain term, <= W's smallest eigenvalue).
struct BlockTerm {
  size_t from;
  size_t to;
  double w[4];
  double m[2];
};
std::vector<double> solve_laplacian_cg(size_t n, size_t dim, const std::vector<BlockTerm>& terms,
                                       const std::vector<double>& chain_w, const double* x0) {
  const size_t u = (n - 1) * dim;
  auto at = [dim](size_t node, size_t c) { return (node - 1) * dim + c; };
  std::vector<double> b(u, 0.0);
  for (const BlockTerm& t : terms) {
    double m[2] = {t.m[0], t.m[1]};
    for (size_t c = 0; c < dim; ++c) {
      if (t.from == 0) m[c] += x0[c];
      if (t.to == 0) m[c] -= x0[c];
    }
    for (size_t i = 0; i < dim; ++i) {
      double wm = 0.0;
      for (size_t j = 0; j < dim; ++j)
        wm += t.w[i * dim + j] * m[j];
      if (t.to != 0) b[at(t.to, i)] += wm;
      if (t.from != 0) b[at(t.from, i)] -= wm;
    }
  }
  auto apply = [&](const std::vector<double>& v) {
    std::vector<double> y(u, 0.0);
    for (const BlockTerm& t : terms) {
      double d[2] = {0.0, 0.0};
      for (size_t c = 0; c < dim; ++c) {
        d[c] = (t.to != 0 ? v[at(t.to, c)] : 0.0) - (t.from != 0 ? v[at(t.from, c)] : 0.0);
      }
      for (size_t i = 0; i < dim; ++i) {
        double wd = 0.0;
        for (size_t j = 0; j < dim; ++j)
          wd += t.w[i * dim + j] * d[j];
        if (t.to != 0) y[at(t.to, i)] += wd;
        if (t.from != 0) y[at(t.from, i)] -= wd;
      }
    }
    return y;
  };
  // The chain: suffix sums (the flow through each chain edge) times its variance, then prefix
  // sums.
  auto precondition = [&](const std::vector<double>& r) {
    std::vector<double> z(u, 0.0);
    for (size_t c = 0; c < dim; ++c) {
      double flow = 0.0;
      for (size_t k = n - 1; k >= 1; --k) {
        flow += r[at(k, c)];
        z[at(k, c)] = flow / chain_w[k - 1];
      }
      for (size_t k = 2; k < n; ++k)
        z[at(k, c)] += z[at(k - 1, c)];
    }
    return z;
  };
  auto dot = [](const std::vector<double>& a, const std::vector<double>& c) {
    double s = 0.0;
    for (size_t i = 0; i < a.size(); ++i)
      s += a[i] * c[i];
    return s;
  };
  std::vector<double> x(u, 0.0);
  std::vector<double> r = b;
  std::vector<double> z = precondition(r);
  std::vector<double> p = z;
  double rz = dot(r, z);
  const double stop = 1e-30 * dot(b, b);
  for (int it = 0; it < 20000 && dot(r, r) > stop; ++it) {
    const std::vector<double> q = apply(p);
    const double alpha = rz / dot(p, q);
    for (size_t i = 0; i < u; ++i) {
      x[i] += alpha * p[i];
      r[i] -= alpha * q[i];
    }
    z = precondition(r);
    const double rz_new = dot(r, z);
    const double beta = rz_new / rz;
    rz = rz_new;
    for (size_t i = 0; i < u; ++i)
      p[i] = z[i] + beta * p[i];
  }
  return x;
}

}  // namespace

std::vector<PoseRef> pose_graph_linear_iterative(int nodes, const std::vector<PoseEdgeRef>& edges,
                                                 const PoseRef& anchor) {
  const size_t n = static_cast<size_t>(nodes);
  std::vector<PoseRef> out(n, anchor);
  if (n <= 1) return out;
  std::vector<double> chain(n, anchor.theta);
  for (size_t k = 1; k < n; ++k)
    chain[k] = chain[k - 1] + edges[k - 1].dtheta;
  std::vector<BlockTerm> heading;
  std::vector<double> chain_h(n - 1);
  for (size_t i = 0; i < edges.size(); ++i) {
    const PoseEdgeRef& e = edges[i];
    const size_t f = static_cast<size_t>(e.from);
    const size_t t = static_cast<size_t>(e.to);
    double m = e.dtheta;
    if (i >= n - 1) m += kPoseTwoPi * std::round((chain[t] - chain[f] - m) / kPoseTwoPi);
    heading.push_back({f, t, {e.info_heading, 0, 0, 0}, {m, 0}});
    if (i < n - 1) chain_h[i] = e.info_heading;
  }
  const std::vector<double> th = solve_laplacian_cg(n, 1, heading, chain_h, &anchor.theta);
  std::vector<double> theta(n, anchor.theta);
  for (size_t k = 1; k < n; ++k)
    theta[k] = th[k - 1];
  std::vector<BlockTerm> pos;
  std::vector<double> chain_p(n - 1);
  for (size_t i = 0; i < edges.size(); ++i) {
    const PoseEdgeRef& e = edges[i];
    const size_t f = static_cast<size_t>(e.from);
    const double c = std::cos(theta[f]);
    const double s = std::sin(theta[f]);
    const double wa = e.info_xy;
    const double wl = lateral_info(e);
    const double wc = e.info_cross;
    const double w01 = (wa - wl) * c * s + wc * (c * c - s * s);
    pos.push_back({f,
                   static_cast<size_t>(e.to),
                   {wa * c * c + wl * s * s - 2 * wc * c * s, w01, w01,
                    wa * s * s + wl * c * c + 2 * wc * c * s},
                   {c * e.dx - s * e.dy, s * e.dx + c * e.dy}});
    if (i < n - 1) {
      // The smallest eigenvalue of the position information.
      const double h = (wa + wl) / 2;
      chain_p[i] = h - std::sqrt((wa - wl) * (wa - wl) / 4 + wc * wc);
    }
  }
  const double p0[2] = {anchor.x, anchor.y};
  const std::vector<double> p = solve_laplacian_cg(n, 2, pos, chain_p, p0);
  for (size_t k = 1; k < n; ++k)
    out[k] = PoseRef{p[2 * (k - 1)], p[2 * (k - 1) + 1], theta[k]};
  return out;
}

namespace {

// One edge linearised at the current estimate: e(x) ~ e + a dx_from + b dx_to.
struct GnLin {
  size_t from;
  size_t to;
  M3 a;  // d e / d x_from
  M3 b;  // d e / d x_to
  V3 e;
  M3 w;  // the information (symmetric)
};

std::vector<GnLin> gn_linearise(const std::vector<PoseEdgeRef>& edges,
                                const std::vector<PoseRef>& x, double var_xy, double var_heading) {
  std::vector<GnLin> lin;
  const double sxy = 1.0 / var_xy;
  const double sxt = 1.0 / std::sqrt(var_xy * var_heading);
  for (const PoseEdgeRef& ed : edges) {
    const PoseRef& pf = x[static_cast<size_t>(ed.from)];
    const PoseRef& pt = x[static_cast<size_t>(ed.to)];
    const double c = std::cos(pf.theta);
    const double s = std::sin(pf.theta);
    const double gx = pt.x - pf.x;
    const double gy = pt.y - pf.y;
    GnLin l;
    l.from = static_cast<size_t>(ed.from);
    l.to = static_cast<size_t>(ed.to);
    l.e = {c * gx + s * gy - ed.dx, -s * gx + c * gy - ed.dy,
           wrap_pi(pt.theta - pf.theta - ed.dtheta)};
    l.a = {-c, -s, -s * gx + c * gy, s, -c, -c * gx - s * gy, 0.0, 0.0, -1.0};
    l.b = {c, s, 0.0, -s, c, 0.0, 0.0, 0.0, 1.0};
    l.w = {ed.info_xy * sxy,
           ed.info_cross * sxy,
           ed.info_along_heading * sxt,
           ed.info_cross * sxy,
           lateral_info(ed) * sxy,
           ed.info_lateral_heading * sxt,
           ed.info_along_heading * sxt,
           ed.info_lateral_heading * sxt,
           ed.info_heading / var_heading};
    lin.push_back(l);
  }
  return lin;
}

// y[node - 1] += m^T v for the unknown nodes (node 0 is fixed: its block is 0).
void gn_add_transposed(const M3& m, const V3& v, size_t node, std::vector<V3>* y) {
  if (node == 0) return;
  const V3 t = m3_apply(m3_transpose(m), v);
  for (size_t i = 0; i < 3; ++i)
    (*y)[node - 1][i] += t[i];
}

// H v = sum J^T W J v over the u unknown blocks.
std::vector<V3> gn_apply(const std::vector<GnLin>& lin, size_t u, const std::vector<V3>& v) {
  std::vector<V3> y(u, V3{});
  for (const GnLin& l : lin) {
    V3 jv{};
    if (l.from != 0) jv = m3_apply(l.a, v[l.from - 1]);
    if (l.to != 0) {
      const V3 bv = m3_apply(l.b, v[l.to - 1]);
      for (size_t i = 0; i < 3; ++i)
        jv[i] += bv[i];
    }
    jv = m3_apply(l.w, jv);
    gn_add_transposed(l.a, jv, l.from, &y);
    gn_add_transposed(l.b, jv, l.to, &y);
  }
  return y;
}

// The right-hand side -J^T W e.
std::vector<V3> gn_rhs(const std::vector<GnLin>& lin, size_t u) {
  std::vector<V3> rhs(u, V3{});
  for (const GnLin& l : lin) {
    V3 we = m3_apply(l.w, l.e);
    for (size_t i = 0; i < 3; ++i)
      we[i] = -we[i];
    gn_add_transposed(l.a, we, l.from, &rhs);
    gn_add_transposed(l.b, we, l.to, &rhs);
  }
  return rhs;
}

// The odometry chain's block-tridiagonal part of H (edges 0..n-2 are the chain), factored by
// block elimination (S_k = D_k - C_k^T S_{k-1}^-1 C_k, C_k the block between k-1 and k).
class GnChainPreconditioner {
 public:
  GnChainPreconditioner(const std::vector<GnLin>& lin, size_t n)
      : u_(n - 1), upper_(u_, M3{}), s_inv_(u_) {
    std::vector<M3> diag(u_, M3{});
    for (size_t k = 1; k < n; ++k) {
      const GnLin& l = lin[k - 1];
      const M3 bb = m3_weighted(l.b, l.w, l.b);
      for (size_t i = 0; i < 9; ++i)
        diag[k - 1][i] += bb[i];
      if (k >= 2) {
        const M3 aa = m3_weighted(l.a, l.w, l.a);
        for (size_t i = 0; i < 9; ++i)
          diag[k - 2][i] += aa[i];
        upper_[k - 1] = m3_weighted(l.a, l.w, l.b);
      }
    }
    for (size_t k = 0; k < u_; ++k) {
      M3 s = diag[k];
      if (k >= 1) {
        const M3 t = m3_mul(m3_mul(m3_transpose(upper_[k]), s_inv_[k - 1]), upper_[k]);
        for (size_t i = 0; i < 9; ++i)
          s[i] -= t[i];
      }
      s_inv_[k] = m3_inverse(s);
    }
  }

  std::vector<V3> operator()(const std::vector<V3>& r) const {
    std::vector<V3> y = r;
    for (size_t k = 1; k < u_; ++k) {
      const V3 t = m3_apply(m3_transpose(upper_[k]), m3_apply(s_inv_[k - 1], y[k - 1]));
      for (size_t i = 0; i < 3; ++i)
        y[k][i] -= t[i];
    }
    std::vector<V3> z(u_);
    for (size_t k = u_; k-- > 0;) {
      V3 v = y[k];
      if (k + 1 < u_) {
        const V3 t = m3_apply(upper_[k + 1], z[k + 1]);
        for (size_t i = 0; i < 3; ++i)
          v[i] -= t[i];
      }
      z[k] = m3_apply(s_inv_[k], v);
    }
    return z;
  }

 private:
  size_t u_;
  std::vector<M3> upper_;  // upper_[k-1]: block (k-1, k) for k >= 2
  std::vector<M3> s_inv_;
};

double gn_dot(const std::vector<V3>& a, const std::vector<V3>& b) {
  double s = 0.0;
  for (size_t k = 0; k < a.size(); ++k)
    for (size_t i = 0; i < 3; ++i)
      s += a[k][i] * b[k][i];
  return s;
}

// The Gauss-Newton step: H delta = rhs by preconditioned CG to 1e-14 of the right-hand side.
std::vector<V3> gn_step(const std::vector<GnLin>& lin, size_t n) {
  const size_t u = n - 1;
  const GnChainPreconditioner precondition(lin, n);
  const std::vector<V3> rhs = gn_rhs(lin, u);
  std::vector<V3> delta(u, V3{});
  std::vector<V3> r = rhs;
  std::vector<V3> z = precondition(r);
  std::vector<V3> p = z;
  double rz = gn_dot(r, z);
  const double stop = 1e-28 * gn_dot(rhs, rhs);
  for (size_t cg = 0; cg < 10 * 3 * u && gn_dot(r, r) > stop; ++cg) {
    const std::vector<V3> q = gn_apply(lin, u, p);
    const double alpha = rz / gn_dot(p, q);
    for (size_t k = 0; k < u; ++k)
      for (size_t i = 0; i < 3; ++i) {
        delta[k][i] += alpha * p[k][i];
        r[k][i] -= alpha * q[k][i];
      }
    z = precondition(r);
    const double rz_new = gn_dot(r, z);
    const double beta = rz_new / rz;
    rz = rz_new;
    for (size_t k = 0; k < u; ++k)
      for (size_t i = 0; i < 3; ++i)
        p[k][i] = z[k][i] + beta * p[k][i];
  }
  return delta;
}

}  // namespace

std::vector<PoseRef> pose_graph_gauss_newton(const std::vector<PoseEdgeRef>& edges,
                                             const std::vector<PoseRef>& initial, double var_xy,
                                             double var_heading, int iterations) {
  std::vector<PoseRef> x = initial;
  const size_t n = x.size();
  if (n <= 1) return x;
  for (int it = 0; it < iterations; ++it) {
    const std::vector<V3> delta = gn_step(gn_linearise(edges, x, var_xy, var_heading), n);
    double largest = 0.0;
    for (size_t k = 0; k + 1 < n; ++k) {
      x[k + 1].x += delta[k][0];
      x[k + 1].y += delta[k][1];
      x[k + 1].theta += delta[k][2];
      for (size_t i = 0; i < 3; ++i)
        largest = std::max(largest, std::fabs(delta[k][i]));
    }
    if (largest < 1e-12) break;
  }
  return x;
}

}  // namespace seqslam::reference
