#include "seqslam_tools/pr_metrics.h"

#include <cmath>
#include <limits>
#include <vector>

#include <gtest/gtest.h>

namespace seqslam::tools {
namespace {

constexpr double kEps = 1e-12;

MatchRecord rec(uint32_t query, int64_t reference, double confidence, bool correct) {
  MatchRecord r;
  r.query = query;
  r.reference = reference;
  r.confidence = confidence;
  r.correct = correct;
  return r;
}

void expect_finite(const PrSummary& s) {
  EXPECT_TRUE(std::isfinite(s.recall_at_100_precision));
  EXPECT_TRUE(std::isfinite(s.auc_pr));
  EXPECT_TRUE(std::isfinite(s.max_recall));
  EXPECT_TRUE(std::isfinite(s.top1));
  for (const PrPoint& p : s.curve) {
    EXPECT_FALSE(std::isnan(p.confidence_threshold));
    EXPECT_TRUE(std::isfinite(p.precision));
    EXPECT_TRUE(std::isfinite(p.recall));
  }
}

void expect_point(const PrPoint& p, double threshold, double precision, double recall,
                  size_t accepted, size_t tp) {
  EXPECT_DOUBLE_EQ(p.confidence_threshold, threshold);
  EXPECT_NEAR(p.precision, precision, kEps);
  EXPECT_NEAR(p.recall, recall, kEps);
  EXPECT_EQ(p.accepted, accepted);
  EXPECT_EQ(p.true_positives, tp);
}

// Five queries (D = 5), no ties. Query 4 has no match and is never accepted.
//   sorted: 0.1 T, 0.2 T, 0.3 F, 0.4 T
//   points: (0.1: P 1/1, R 1/5) (0.2: P 2/2, R 2/5) (0.3: P 2/3, R 2/5) (0.4: P 3/4, R 3/5)
//   recall@100%P = 2/5 = 0.4
//   AUC from (0, 1): 0.2 * (1 + 1)/2 + 0.2 * (1 + 1)/2 + 0 + 0.2 * (2/3 + 3/4)/2
//                  = 0.2 + 0.2 + 0.2 * 17/24 = 0.4 + 17/120 = 65/120 = 13/24
TEST(PrMetrics, HandComputedWithoutTies) {
  // Given out of order on purpose.
  const std::vector<MatchRecord> records = {rec(3, 30, 0.4, true), rec(1, 10, 0.2, true),
                                            rec(4, -1, 0.05, true), rec(0, 0, 0.1, true),
                                            rec(2, 99, 0.3, false)};
  const PrSummary s = evaluate_pr(records, 5);
  expect_finite(s);
  EXPECT_EQ(s.queries, 5u);
  EXPECT_EQ(s.records, 5u);
  EXPECT_EQ(s.accepted_total, 4u);
  ASSERT_EQ(s.curve.size(), 4u);
  expect_point(s.curve[0], 0.1, 1.0, 0.2, 1, 1);
  expect_point(s.curve[1], 0.2, 1.0, 0.4, 2, 2);
  expect_point(s.curve[2], 0.3, 2.0 / 3.0, 0.4, 3, 2);
  expect_point(s.curve[3], 0.4, 0.75, 0.6, 4, 3);
  EXPECT_NEAR(s.recall_at_100_precision, 0.4, kEps);
  EXPECT_NEAR(s.auc_pr, 13.0 / 24.0, kEps);
  EXPECT_NEAR(s.max_recall, 0.6, kEps);
  EXPECT_NEAR(s.top1, 0.6, kEps);

  // Highest precision among points with recall >= r.
  EXPECT_NEAR(s.precision_at_recall(0.0), 1.0, kEps);
  EXPECT_NEAR(s.precision_at_recall(0.4), 1.0, kEps);
  EXPECT_NEAR(s.precision_at_recall(0.5), 0.75, kEps);
  EXPECT_NEAR(s.precision_at_recall(0.6), 0.75, kEps);
  EXPECT_EQ(s.precision_at_recall(0.61), 0.0);
  EXPECT_EQ(s.precision_at_recall(std::numeric_limits<double>::quiet_NaN()), 0.0);

  // at_threshold accepts confidence < c (strictly).
  expect_point(s.at_threshold(0.1), 0.1, 0.0, 0.0, 0, 0);
  expect_point(s.at_threshold(0.15), 0.15, 1.0, 0.2, 1, 1);
  expect_point(s.at_threshold(0.3), 0.3, 1.0, 0.4, 2, 2);
  expect_point(s.at_threshold(0.35), 0.35, 2.0 / 3.0, 0.4, 3, 2);
  expect_point(s.at_threshold(1.0), 1.0, 0.75, 0.6, 4, 3);
  const PrPoint nan_point = s.at_threshold(std::numeric_limits<double>::quiet_NaN());
  EXPECT_EQ(nan_point.accepted, 0u);
  EXPECT_EQ(nan_point.precision, 0.0);
}

// Ties form one step. D = 4.
//   groups: 0.1 {T}      -> accepted 1, TP 1: P 1,   R 1/4
//           0.2 {T, F}   -> accepted 3, TP 2: P 2/3, R 2/4   (no point between T and F)
//           0.5 {T}      -> accepted 4, TP 3: P 3/4, R 3/4
//   recall@100%P = 1/4 (the tie group at 0.2 contains the first error)
//   AUC from (0, 1): 1/4 * (1 + 1)/2 + 1/4 * (1 + 2/3)/2 + 1/4 * (2/3 + 3/4)/2
//                  = 1/4 + 5/24 + 17/96 = 24/96 + 20/96 + 17/96 = 61/96
TEST(PrMetrics, TiesFormOneStep) {
  const std::vector<MatchRecord> records = {rec(2, 5, 0.2, false), rec(0, 0, 0.1, true),
                                            rec(1, 1, 0.2, true), rec(3, 3, 0.5, true)};
  const PrSummary s = evaluate_pr(records, 4);
  expect_finite(s);
  ASSERT_EQ(s.curve.size(), 3u);
  expect_point(s.curve[0], 0.1, 1.0, 0.25, 1, 1);
  expect_point(s.curve[1], 0.2, 2.0 / 3.0, 0.5, 3, 2);
  expect_point(s.curve[2], 0.5, 0.75, 0.75, 4, 3);
  EXPECT_NEAR(s.recall_at_100_precision, 0.25, kEps);
  EXPECT_NEAR(s.auc_pr, 61.0 / 96.0, kEps);
  EXPECT_NEAR(s.max_recall, 0.75, kEps);
  EXPECT_NEAR(s.top1, 0.75, kEps);
  // Thresholds inside the tie cannot split it.
  expect_point(s.at_threshold(0.2), 0.2, 1.0, 0.25, 1, 1);
  expect_point(s.at_threshold(0.2000001), 0.2000001, 2.0 / 3.0, 0.5, 3, 2);
}

// The first accepted group contains an error: recall@100%P is 0. D = 3.
//   groups: 0.1 {F, T} -> P 1/2, R 1/3;   0.3 {T} -> P 2/3, R 2/3
//   AUC from (0, 1/2): 1/3 * (1/2 + 1/2)/2 + 1/3 * (1/2 + 2/3)/2 = 1/6 + 7/36 = 13/36
TEST(PrMetrics, FirstGroupWithErrorGivesZeroRecallAt100) {
  const std::vector<MatchRecord> records = {rec(0, 7, 0.1, false), rec(1, 1, 0.1, true),
                                            rec(2, 2, 0.3, true)};
  const PrSummary s = evaluate_pr(records, 3);
  expect_finite(s);
  ASSERT_EQ(s.curve.size(), 2u);
  expect_point(s.curve[0], 0.1, 0.5, 1.0 / 3.0, 2, 1);
  expect_point(s.curve[1], 0.3, 2.0 / 3.0, 2.0 / 3.0, 3, 2);
  EXPECT_EQ(s.recall_at_100_precision, 0.0);
  EXPECT_NEAR(s.auc_pr, 13.0 / 36.0, kEps);
  EXPECT_NEAR(s.max_recall, 2.0 / 3.0, kEps);
}

// All correct, D = 4: recall@100%P = 1 and AUC = 4 * (1/4 * 1) = 1.
TEST(PrMetrics, AllCorrect) {
  const std::vector<MatchRecord> records = {rec(0, 0, 0.1, true), rec(1, 1, 0.2, true),
                                            rec(2, 2, 0.3, true), rec(3, 3, 0.4, true)};
  const PrSummary s = evaluate_pr(records, 4);
  EXPECT_NEAR(s.recall_at_100_precision, 1.0, kEps);
  EXPECT_NEAR(s.auc_pr, 1.0, kEps);
  EXPECT_NEAR(s.max_recall, 1.0, kEps);
  EXPECT_NEAR(s.top1, 1.0, kEps);
  EXPECT_NEAR(s.precision_at_recall(1.0), 1.0, kEps);
}

// The denominator counts queries without a record too (they cap the reachable recall):
// 2 correct records, D = 8 -> max recall 1/4; AUC from (0, 1): 1/8 + 1/8 = 1/4.
TEST(PrMetrics, DenominatorIsTheCallers) {
  const std::vector<MatchRecord> records = {rec(0, 0, 0.1, true), rec(5, 5, 0.6, true)};
  const PrSummary s = evaluate_pr(records, 8);
  EXPECT_EQ(s.queries, 8u);
  EXPECT_NEAR(s.max_recall, 0.25, kEps);
  EXPECT_NEAR(s.recall_at_100_precision, 0.25, kEps);
  EXPECT_NEAR(s.auc_pr, 0.25, kEps);
}

TEST(PrMetrics, DegenerateInputsGiveZeros) {
  // No records.
  PrSummary s = evaluate_pr({}, 10);
  expect_finite(s);
  EXPECT_TRUE(s.curve.empty());
  EXPECT_EQ(s.accepted_total, 0u);
  EXPECT_EQ(s.auc_pr, 0.0);
  EXPECT_EQ(s.recall_at_100_precision, 0.0);
  EXPECT_EQ(s.max_recall, 0.0);
  EXPECT_EQ(s.top1, 0.0);
  EXPECT_EQ(s.precision_at_recall(0.0), 0.0);
  EXPECT_EQ(s.at_threshold(0.5).accepted, 0u);

  // No records and D = 0.
  s = evaluate_pr({}, 0);
  expect_finite(s);
  EXPECT_EQ(s.auc_pr, 0.0);

  // Records but D = 0: recall is 0 everywhere, precision still defined.
  s = evaluate_pr({rec(0, 0, 0.1, true), rec(1, 2, 0.2, false)}, 0);
  expect_finite(s);
  ASSERT_EQ(s.curve.size(), 2u);
  EXPECT_EQ(s.curve[0].recall, 0.0);
  EXPECT_EQ(s.curve[0].precision, 1.0);
  EXPECT_EQ(s.auc_pr, 0.0);
  EXPECT_EQ(s.max_recall, 0.0);
  EXPECT_EQ(s.top1, 0.0);
  EXPECT_EQ(s.recall_at_100_precision, 0.0);

  // All incorrect.
  s = evaluate_pr({rec(0, 3, 0.1, false), rec(1, 4, 0.2, false), rec(2, 4, 0.2, false)}, 3);
  expect_finite(s);
  ASSERT_EQ(s.curve.size(), 2u);
  EXPECT_EQ(s.curve[1].precision, 0.0);
  EXPECT_EQ(s.auc_pr, 0.0);
  EXPECT_EQ(s.recall_at_100_precision, 0.0);
  EXPECT_EQ(s.max_recall, 0.0);
  EXPECT_EQ(s.precision_at_recall(0.0), 0.0);

  // Nothing eligible: every reference is -1 (correct flags are ignored for them).
  s = evaluate_pr({rec(0, -1, 0.1, true), rec(1, -1, 0.0, false)}, 2);
  expect_finite(s);
  EXPECT_EQ(s.records, 2u);
  EXPECT_EQ(s.accepted_total, 0u);
  EXPECT_TRUE(s.curve.empty());
  EXPECT_EQ(s.max_recall, 0.0);
  EXPECT_EQ(s.top1, 0.0);
}

TEST(PrMetrics, NanConfidenceSortsLast) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const std::vector<MatchRecord> records = {rec(0, 0, nan, false), rec(1, 1, 0.5, true),
                                            rec(2, 2, nan, true)};
  const PrSummary s = evaluate_pr(records, 3);
  expect_finite(s);
  ASSERT_EQ(s.curve.size(), 2u);
  expect_point(s.curve[0], 0.5, 1.0, 1.0 / 3.0, 1, 1);
  EXPECT_TRUE(std::isinf(s.curve[1].confidence_threshold));
  EXPECT_EQ(s.curve[1].accepted, 3u);
  EXPECT_NEAR(s.recall_at_100_precision, 1.0 / 3.0, kEps);
}

// With several records for one query, the first in (confidence, query, input) order is the
// query's best match for top1; on equal confidence the earlier input record wins.
TEST(PrMetrics, Top1UsesEachQuerysBestRecord) {
  PrSummary s = evaluate_pr({rec(0, 9, 0.5, true), rec(0, 3, 0.1, false)}, 1);
  EXPECT_EQ(s.top1, 0.0);                // best (0.1) is wrong
  EXPECT_NEAR(s.max_recall, 1.0, kEps);  // every correct record counts for recall
  s = evaluate_pr({rec(0, 3, 0.2, false), rec(0, 9, 0.2, true)}, 1);
  EXPECT_EQ(s.top1, 0.0);  // tie: input order
  s = evaluate_pr({rec(0, 9, 0.2, true), rec(0, 3, 0.2, false)}, 1);
  EXPECT_NEAR(s.top1, 1.0, kEps);
  // Ties between different queries are ordered by query index; the curve is unaffected.
  s = evaluate_pr({rec(7, 7, 0.3, true), rec(2, 2, 0.3, false), rec(4, 4, 0.3, true)}, 3);
  ASSERT_EQ(s.curve.size(), 1u);
  expect_point(s.curve[0], 0.3, 2.0 / 3.0, 2.0 / 3.0, 3, 2);
  EXPECT_NEAR(s.top1, 2.0 / 3.0, kEps);
}

}  // namespace
}  // namespace seqslam::tools
