#include "seqslam_tools/pr_metrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_set>
#include <vector>

namespace seqslam::tools {
namespace {

// The sort key: NaN sorts as +inf so the order is a strict weak ordering.
double key(double confidence) {
  return std::isnan(confidence) ? std::numeric_limits<double>::infinity() : confidence;
}

double ratio(size_t numerator, size_t denominator) {
  return denominator == 0 ? 0.0 : static_cast<double>(numerator) / static_cast<double>(denominator);
}

}  // namespace

double PrSummary::precision_at_recall(double r) const {
  double best = 0.0;
  for (const PrPoint& p : curve) {
    if (p.recall >= r - 1e-12) best = std::max(best, p.precision);
  }
  return best;
}

PrPoint PrSummary::at_threshold(double c) const {
  PrPoint result;
  result.confidence_threshold = c;
  // Points are in increasing threshold order; the last one below c is the operating point.
  for (const PrPoint& p : curve) {
    if (!(p.confidence_threshold < c)) break;
    result.precision = p.precision;
    result.recall = p.recall;
    result.accepted = p.accepted;
    result.true_positives = p.true_positives;
  }
  return result;
}

PrSummary evaluate_pr(const std::vector<MatchRecord>& records, size_t recall_denominator) {
  PrSummary summary;
  summary.queries = recall_denominator;
  summary.records = records.size();

  std::vector<const MatchRecord*> eligible;
  eligible.reserve(records.size());
  for (const MatchRecord& r : records) {
    if (r.reference >= 0) eligible.push_back(&r);
  }
  std::stable_sort(eligible.begin(), eligible.end(),
                   [](const MatchRecord* a, const MatchRecord* b) {
                     const double ka = key(a->confidence);
                     const double kb = key(b->confidence);
                     if (ka != kb) return ka < kb;
                     return a->query < b->query;
                   });
  summary.accepted_total = eligible.size();

  size_t tp = 0;
  size_t top1_correct = 0;
  std::unordered_set<uint32_t> seen_queries;
  for (size_t i = 0; i < eligible.size();) {
    const double group_key = key(eligible[i]->confidence);
    size_t j = i;
    for (; j < eligible.size() && key(eligible[j]->confidence) == group_key; ++j) {
      const MatchRecord& r = *eligible[j];
      if (r.correct) ++tp;
      // The first record of a query in this order is its best match.
      if (seen_queries.insert(r.query).second && r.correct) ++top1_correct;
    }
    PrPoint point;
    point.confidence_threshold = group_key;
    point.accepted = j;
    point.true_positives = tp;
    point.precision = ratio(tp, j);
    point.recall = ratio(tp, recall_denominator);
    summary.curve.push_back(point);
    if (tp == j) summary.recall_at_100_precision = point.recall;
    i = j;
  }

  double previous_recall = 0.0;
  double previous_precision = summary.curve.empty() ? 0.0 : summary.curve.front().precision;
  for (const PrPoint& p : summary.curve) {
    summary.auc_pr += (p.recall - previous_recall) * (p.precision + previous_precision) / 2.0;
    previous_recall = p.recall;
    previous_precision = p.precision;
  }
  summary.max_recall = ratio(tp, recall_denominator);
  summary.top1 = ratio(top1_correct, recall_denominator);
  return summary;
}

}  // namespace seqslam::tools
