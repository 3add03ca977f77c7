#include "synthetic.h"

#include <cmath>
#include <limits>

#include "seqslam_tools/pr_metrics.h"

namespace seqslam::tools::test {
namespace {

GrayImage pattern(uint32_t place, int brightness) {
  GrayImage image;
  image.width = 32;
  image.height = 16;
  image.pixels.resize(32 * 16);
  for (int y = 0; y < 16; ++y) {
    for (int x = 0; x < 32; ++x) {
      const int stripe = ((x + static_cast<int>(place) * 3) / 4 + y / 4) % 2 == 0 ? 60 : 180;
      const int v =
          stripe + static_cast<int>((place * 37u + static_cast<uint32_t>(x)) % 40u) + brightness;
      image.pixels[static_cast<size_t>(y * 32 + x)] =
          static_cast<uint8_t>(v < 0 ? 0 : (v > 255 ? 255 : v));
    }
  }
  return image;
}

PoseD loop_pose(double s, double radius, double dx) {
  return PoseD{radius * std::cos(s) + dx, 0.6 * radius * std::sin(s), s + M_PI / 2};
}

}  // namespace

std::vector<ReportRun> Synthetic::runs() const {
  std::vector<ReportRun> out{{"none", &first}};
  if (has_second) out.push_back({"<he&pn>", &second});
  return out;
}

ReportOptions Synthetic::options() const {
  ReportOptions o;
  o.title = "synthetic \"report\" <test>";
  if (has_ground_truth) o.truth = &truth;
  return o;
}

Synthetic make_synthetic(const SyntheticOptions& options) {
  Synthetic s;
  s.has_ground_truth = options.ground_truth;
  s.has_second = options.second_run;
  const uint32_t L = options.library;
  const uint32_t Q = options.queries;
  s.library.source = "sim/noon & lamps/<library>.dream";
  s.library.kind = "dream";
  s.library.source_size = L;
  s.query.source = "sim/morning/query.dream";
  s.query.kind = "dream";
  s.query.offset = 100;
  s.query.source_size = Q + 200;
  for (uint32_t j = 0; j < L; ++j) {
    s.library.images.push_back(pattern(j, 0));
    s.library.names.push_back("place " + std::to_string(j));
    if (options.poses) {
      const double t = 2 * M_PI * j / L;
      s.library.truth.push_back(loop_pose(t, 8.0, 0.0));
      s.library.odometry.push_back(loop_pose(t * 1.04, 8.3, 0.2));
    }
  }
  for (uint32_t q = 0; q < Q; ++q) {
    s.query.images.push_back(pattern(q + kShift, 25));
    s.query.names.push_back("place " + std::to_string(q + s.query.offset));
    if (options.poses) {
      const double t = 2 * M_PI * (q + kShift) / L;
      s.query.truth.push_back(loop_pose(t, 8.1, 0.1));
      s.query.odometry.push_back(loop_pose(t * 0.97, 7.8, -0.3));
    }
  }
  // Queries q match library q+5 +- 2; the last three queries are novel (no correct place).
  s.truth.matches.resize(Q);
  for (uint32_t q = 0; q + 3 < Q || (Q < 4 && q < Q); ++q) {
    for (uint32_t j = q + kShift >= 2 ? q + kShift - 2 : 0; j <= q + kShift + 2 && j < L; ++j) {
      s.truth.matches[q].push_back(j);
    }
  }

  EvalResult& r = s.first;
  r.config.localiser.image_size = {32, 16};
  r.config.localiser.preprocess.method = Preprocessing::kNone;
  r.config.localiser.sequence.seq_len = kSeqLen;
  r.config.localiser.sequence.window = 20;
  r.config.localiser.sequence.exclusion = 5;
  r.config.keep_matrices = true;
  r.library_size = L;
  r.query_size = Q;
  r.has_ground_truth = options.ground_truth;
  r.timing = {1.5, 2.25, 3.0, 0.75, 7.5, false};
  r.differences.resize(static_cast<size_t>(Q) * L);
  r.sequence_costs.resize(static_cast<size_t>(Q) * L);
  for (uint32_t q = 0; q < Q; ++q) {
    for (uint32_t j = 0; j < L; ++j) {
      const uint32_t target = q + kShift;
      const uint32_t off = j > target ? j - target : target - j;
      // The exact place is the matrix's minimum (2000); others have some noise.
      const uint32_t d =
          2000 + (off == 0 ? 0 : 400 * (off < 12 ? off : 12) + (q * 31 + j * 17) % 97);
      r.differences[static_cast<size_t>(q) * L + j] = d;
      r.sequence_costs[static_cast<size_t>(q) * L + j] =
          q + 1 < kSeqLen ? std::numeric_limits<float>::quiet_NaN() : static_cast<float>(d) / 64.0f;
    }
  }
  const double threshold = 0.85;
  for (uint32_t q = 0; q < Q; ++q) {
    QueryResult m;
    m.query = q;
    if (q + 1 >= kSeqLen) {
      m.library = static_cast<int32_t>(std::min(q + kShift, L - 1));
      m.confidence = 0.3 + 0.02 * (q % 20);
      if (q % 7 == 0) {  // a confident wrong match, far away
        m.library = static_cast<int32_t>((q + kShift + L / 2) % L);
        m.confidence = 0.55;
      }
      if (q % 5 == 0) m.confidence = 0.93;  // not accepted
      m.runner_up = (m.library + 20) % static_cast<int32_t>(L);
      m.accepted = m.confidence < threshold;
    }
    if (options.ground_truth) {
      m.has_truth = s.truth.has_match(q);
      m.correct = m.library >= 0 && s.truth.is_correct(q, static_cast<uint32_t>(m.library));
    }
    r.matches.push_back(m);
  }

  EvalResult& t = s.second;
  t = r;
  t.config.localiser.preprocess.method = Preprocessing::kHistEqPatchNorm;
  t.config.localiser.sequence.threshold = UQ16_16::from_ratio(9, 10);
  t.config.keep_matrices = false;
  t.differences.clear();
  t.sequence_costs.clear();
  t.timing.matrix_from_cache = true;
  for (QueryResult& m : t.matches) {
    if (options.second_run_empty) {
      m.library = -1;
      m.runner_up = -1;
      m.confidence = 1.0;
      m.accepted = false;
      m.correct = false;
      continue;
    }
    if (m.library < 0) continue;
    m.confidence = 0.2 + 0.7 * ((m.query * 37) % 50) / 50.0;
    m.accepted = m.confidence < 0.9;
  }

  for (EvalResult* e : {&s.first, &s.second}) {
    if (!e->has_ground_truth) continue;
    std::vector<MatchRecord> records;
    size_t denominator = 0;
    for (const QueryResult& m : e->matches) {
      if (m.library < 0) continue;
      records.push_back({m.query, m.library, m.confidence, m.correct});
      if (m.has_truth) ++denominator;
    }
    e->summary = evaluate_pr(records, denominator);
  }
  return s;
}

}  // namespace seqslam::tools::test
