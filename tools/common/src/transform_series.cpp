#include "seqslam_tools/transform_series.h"

#include <algorithm>
#include <cstdlib>

namespace seqslam::tools {

ForcedScore score_forced(const EvalResult& result, const GroundTruth& truth, uint32_t seq_len) {
  ForcedScore s;
  double error_sum = 0.0;
  for (const QueryResult& m : result.matches) {
    if (m.query + 1 < seq_len || !truth.has_match(m.query)) continue;
    ++s.queries;
    if (m.library < 0) continue;
    ++s.answered;
    const auto place = static_cast<uint32_t>(m.library);
    if (truth.is_correct(m.query, place)) ++s.correct;
    uint32_t nearest = UINT32_MAX;
    for (const uint32_t t : truth.matches[m.query])
      nearest = std::min(nearest, t > place ? t - place : place - t);
    if (nearest <= 1) ++s.near;
    error_sum += nearest;
  }
  if (s.answered > 0) s.mae = error_sum / s.answered;
  return s;
}

namespace {

// Precision >= level by counts: correct >= level * queries, with level 1 meaning all.
bool reaches(const ForcedScore& s, double level) {
  if (s.queries == 0) return false;
  if (level >= 1.0) return s.correct == s.queries;
  return static_cast<double>(s.correct) >= level * static_cast<double>(s.queries) - 1e-9;
}

}  // namespace

PrecisionInterval precision_interval(std::vector<SeriesPoint> series, double centre, double level) {
  std::stable_sort(series.begin(), series.end(), [](const SeriesPoint& a, const SeriesPoint& b) {
    return a.strength < b.strength;
  });
  PrecisionInterval out;
  size_t c = series.size();
  for (size_t i = 0; i < series.size(); ++i) {
    if (series[i].strength == centre) {
      c = i;
      break;
    }
  }
  if (c == series.size() || !reaches(series[c].score, level)) return out;
  size_t lo = c;
  while (lo > 0 && reaches(series[lo - 1].score, level))
    --lo;
  size_t hi = c;
  while (hi + 1 < series.size() && reaches(series[hi + 1].score, level))
    ++hi;
  out.found = true;
  out.lo = series[lo].strength;
  out.hi = series[hi].strength;
  return out;
}

}  // namespace seqslam::tools
