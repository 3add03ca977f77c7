// Precision-recall evaluation of a localiser's matches, as defined in the 2025 thesis.
//
// Each query yields at most one MatchRecord: its best reference (or none) and a confidence
// where SMALLER MEANS MORE CERTAIN (e.g. the sequence score ratio, in [0, 1]). A threshold t
// on the confidence decides which matches are "accepted"; sweeping it gives the curve.
//
// Definitions (all computed by evaluate_pr):
//  * Eligible records: those with reference >= 0. A record with reference < 0 (-1 = "no
//    match") is never accepted, whatever its confidence, and is never a true positive even if
//    its `correct` flag is set.
//  * Order: eligible records sorted by confidence ascending (most certain first); ties are
//    broken by query index ascending, then by input order. A NaN confidence sorts as +inf
//    (least certain).
//  * Accepting a prefix of that order: accepted = its length, TP = its records with
//    correct == true,
//        precision = TP / accepted   (0 when nothing is accepted),
//        recall    = TP / D          (0 when D == 0),
//    where D is the recall denominator passed by the caller: the number of queries that could
//    be localised (those with a full sequence behind them).
//  * Curve: records with equal confidence form one group and are accepted together (one
//    threshold cannot split them); one PrPoint is emitted after each whole group, in order.
//    The point's confidence_threshold is that group's confidence: accepting everything with
//    confidence <= threshold gives the point. Points therefore have non-decreasing recall.
//  * recall_at_100_precision: the largest recall among curve points whose precision is exactly
//    1 (TP == accepted, compared in integers). Once an incorrect record is accepted precision
//    can never return to 1, so this is the recall just before the first mistake's group;
//    0 when the first group already contains an incorrect record.
//  * auc_pr: area under the curve by the trapezoid rule over recall, from the point
//    (recall 0, precision of the first curve point) through every curve point in order:
//        sum_i (r_i - r_{i-1}) * (p_i + p_{i-1}) / 2,   with (r_{-1}, p_{-1}) = (0, p_0).
//    It is at most max_recall (precision <= 1).
//  * max_recall: recall with everything eligible accepted (= TP over all eligible / D).
//  * top1: the fraction of D whose best match is correct regardless of confidence: the number
//    of distinct queries whose first eligible record in the order above is correct, over D.
//    With one record per query, top1 == max_recall.
// Degenerate inputs (no records, D == 0, nothing eligible, all incorrect) give zeros (and an
// empty curve when nothing is eligible), never NaN. If D is smaller than the number of correct
// records (a caller error) recall may exceed 1; it is not clamped.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include <vector>

namespace seqslam::tools {

struct MatchRecord {
  uint32_t query = 0;
  int64_t reference = -1;   // best reference index; -1 = no match
  double confidence = 1.0;  // smaller = more certain, normally in [0, 1]
  bool correct = false;     // reference is a correct match (ground truth)
};

struct PrPoint {
  double confidence_threshold = 0.0;  // see the header comment: accepts confidence <= it
  double precision = 0.0;
  double recall = 0.0;
  size_t accepted = 0;        // records accepted at this point
  size_t true_positives = 0;  // of which correct
};

struct PrSummary {
  size_t queries = 0;         // the recall denominator D
  size_t records = 0;         // records passed in (eligible or not)
  size_t accepted_total = 0;  // eligible records (accepted when everything is accepted)
  double recall_at_100_precision = 0.0;
  double auc_pr = 0.0;
  double max_recall = 0.0;
  double top1 = 0.0;
  std::vector<PrPoint> curve;  // one point per confidence group, increasing threshold

  // The highest precision among curve points with recall >= r (within 1e-12, so a value
  // printed from a recall compares equal to it); 0 if no point reaches r.
  double precision_at_recall(double r) const;
  // The operating point that accepts exactly the eligible records with confidence < c
  // (strictly less). Returns {c, precision, recall, accepted, TP}; all zero (threshold c)
  // when nothing is accepted, including for NaN c.
  PrPoint at_threshold(double c) const;
};

// Evaluates `records` against the recall denominator (see the definitions above).
PrSummary evaluate_pr(const std::vector<MatchRecord>& records, size_t recall_denominator);

}  // namespace seqslam::tools
