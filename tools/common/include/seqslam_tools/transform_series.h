// Scores for the perspective experiment of the 2015 thesis [A 4.3.1] (`seqslam transforms`,
// docs/perspective.md): a library against the same route seen through a transformation
// (head roll, horizontal shift, zoom) at many strengths, and the interval of strengths over
// which a matcher keeps a given precision ([A Table 5.9]).
#pragma once

#include <cstdint>
#include <vector>

#include "seqslam_tools/evaluation.h"
#include "seqslam_tools/ground_truth.h"

namespace seqslam::tools {

// The thesis's measures with forced answers (recall 100 %): every query that has a full
// sequence and a true match counts; an answer of -1 (the heuristic's "unknown") is wrong.
struct ForcedScore {
  uint32_t queries = 0;  // queries with a full sequence and a true match
  uint32_t correct = 0;  // of them, answered with a correct place
  // Of them, answered within one place of a correct place: +-2 places of the true one with
  // the usual +-1 truth, i.e. near misses count (40 cm at the robot's 20 cm spacing).
  uint32_t near = 0;
  double mae = 0.0;  // mean |answer - nearest correct place| in places, over the answered
  uint32_t answered = 0;
  double precision() const { return queries == 0 ? 0.0 : static_cast<double>(correct) / queries; }
  // The same score with near misses counted as correct.
  ForcedScore near_as_correct() const {
    ForcedScore s = *this;
    s.correct = near;
    return s;
  }
};

// `seq_len`: queries before seq_len - 1 have no full sequence and are skipped.
ForcedScore score_forced(const EvalResult& result, const GroundTruth& truth, uint32_t seq_len);

struct SeriesPoint {
  double strength = 0.0;  // degrees, pixels or zoom factor
  ForcedScore score;
};

// The widest interval [lo, hi] of sampled strengths containing `centre` in which every
// sample reaches `level` (precision >= level; level 1 means every query correct). Samples
// may come in any order; repeated strengths must agree. `found` is false when the sample at
// `centre` is missing or fails.
struct PrecisionInterval {
  bool found = false;
  double lo = 0.0;
  double hi = 0.0;
};
PrecisionInterval precision_interval(std::vector<SeriesPoint> series, double centre, double level);

}  // namespace seqslam::tools
