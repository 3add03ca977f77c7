// The perspective experiment's scores (seqslam_tools/transform_series.h): forced-answer
// precision and MAE over hand-made results, and the precision intervals of [A Table 5.9].
#include "seqslam_tools/transform_series.h"

#include <vector>

#include <gtest/gtest.h>

namespace seqslam::tools {
namespace {

QueryResult answer(uint32_t q, int32_t place) {
  QueryResult r;
  r.query = q;
  r.library = place;
  return r;
}

TEST(TransformSeries, ForcedScoreCountsEveryQueryWithASequenceAndATruth) {
  GroundTruth truth;
  truth.matches = {{0}, {1}, {1, 2, 3}, {3, 4}, {}, {10, 20}, {6}};
  EvalResult r;
  r.matches = {answer(0, 0),  answer(1, 1),  // before the sequence is full: skipped
               answer(2, 2),                 // correct
               answer(3, 5),                 // wrong, a near miss: 1 place from 4
               answer(4, 4),                 // no truth: skipped
               answer(5, 16),                // wrong, 4 from 20 (the nearest of two)
               answer(6, -1)};               // unknown: counted, wrong, no error term
  const ForcedScore s = score_forced(r, truth, 3);
  EXPECT_EQ(s.queries, 4u);
  EXPECT_EQ(s.correct, 1u);
  EXPECT_EQ(s.answered, 3u);
  EXPECT_EQ(s.near, 2u);  // the correct one and the near miss
  EXPECT_DOUBLE_EQ(s.mae, (0.0 + 1.0 + 4.0) / 3.0);
  EXPECT_DOUBLE_EQ(s.precision(), 0.25);
  EXPECT_DOUBLE_EQ(s.near_as_correct().precision(), 0.5);
  EXPECT_EQ(score_forced(EvalResult{}, truth, 3).precision(), 0.0);  // nothing: 0, not NaN
}

ForcedScore score(uint32_t correct, uint32_t queries) {
  ForcedScore s;
  s.correct = correct;
  s.queries = queries;
  return s;
}

TEST(TransformSeries, IntervalIsTheContiguousRunAroundTheCentre) {
  // Unsorted on purpose; the precision dips at -2 and recovers at -3 (not counted: the
  // interval must be contiguous around 0).
  const std::vector<SeriesPoint> series = {{1.0, score(100, 100)}, {-1.0, score(99, 100)},
                                           {0.0, score(100, 100)}, {2.0, score(95, 100)},
                                           {-2.0, score(79, 100)}, {-3.0, score(100, 100)},
                                           {3.0, score(90, 100)}};
  const auto at = [&](double level) { return precision_interval(series, 0.0, level); };
  PrecisionInterval i = at(1.0);
  ASSERT_TRUE(i.found);
  EXPECT_EQ(i.lo, 0.0);
  EXPECT_EQ(i.hi, 1.0);
  i = at(0.98);
  EXPECT_EQ(i.lo, -1.0);
  EXPECT_EQ(i.hi, 1.0);
  i = at(0.95);  // exactly 0.95 reaches it
  EXPECT_EQ(i.lo, -1.0);
  EXPECT_EQ(i.hi, 2.0);
  i = at(0.80);
  EXPECT_EQ(i.lo, -1.0);  // 0.79 at -2 stops it
  EXPECT_EQ(i.hi, 3.0);
  i = at(0.5);
  EXPECT_EQ(i.lo, -3.0);
  EXPECT_EQ(i.hi, 3.0);
}

TEST(TransformSeries, NoIntervalWhenTheCentreFailsOrIsMissing) {
  const std::vector<SeriesPoint> series = {
      {-1.0, score(100, 100)}, {0.0, score(99, 100)}, {1.0, score(100, 100)}};
  EXPECT_FALSE(precision_interval(series, 0.0, 1.0).found);
  EXPECT_TRUE(precision_interval(series, 0.0, 0.99).found);
  EXPECT_FALSE(precision_interval(series, 0.5, 0.5).found);  // no sample there
  EXPECT_FALSE(precision_interval({}, 0.0, 0.5).found);
  // A sample with no queries never reaches a level (0/0 is not a precision).
  EXPECT_FALSE(precision_interval({{0.0, score(0, 0)}}, 0.0, 0.0).found);
  // Scale series centre on 1.
  const PrecisionInterval s =
      precision_interval({{1.0, score(5, 5)}, {2.0, score(5, 5)}, {3.0, score(1, 5)}}, 1.0, 1.0);
  ASSERT_TRUE(s.found);
  EXPECT_EQ(s.lo, 1.0);
  EXPECT_EQ(s.hi, 2.0);
}

}  // namespace
}  // namespace seqslam::tools
