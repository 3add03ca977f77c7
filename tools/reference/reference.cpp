#include "reference.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace seqslam::reference {

Params Params::from(const LocaliserConfig& c) {
  Params p;
  p.width = c.image_size.width;
  p.height = c.image_size.height;
  p.method = c.preprocess.method;
  p.patch_width = c.preprocess.patch.patch_width;
  p.patch_height = c.preprocess.patch.patch_height;
  p.pn_epsilon = c.preprocess.patch.epsilon.raw() / 256.0;
  p.pn_gain = c.preprocess.patch.gain.raw() / 256.0;
  p.max_shift = c.max_shift;
  p.seq_len = c.sequence.seq_len;
  p.window = c.sequence.window;
  p.sigma_min = c.sequence.sigma_min.raw() / 256.0;
  p.exclusion = c.sequence.exclusion;
  p.threshold = c.sequence.threshold.raw() / 65536.0;
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
