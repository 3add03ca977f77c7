// Runs the fixed-point localiser (the firmware's code) over a library and a query image
// sequence on the PC: teach every library image, then localise each query image in order.
// Shared by seqslam-demo and the simulator's evaluation so both measure the same thing.
#pragma once

#include <cstdint>
#include <vector>

#include "seqslam/localiser.h"
#include "seqslam_tools/image_io.h"
#include "seqslam_tools/outcome.h"
#include "seqslam_tools/pr_metrics.h"

namespace seqslam::tools {

// Largest library and sequence length the host runs support.
inline constexpr uint32_t kCoreRunMaxPlaces = 4000;
inline constexpr uint16_t kCoreRunMaxSeq = 100;

struct CoreMatch {
  int32_t place = -1;       // best library place; -1 until a full sequence exists
  double confidence = 1.0;  // best / runner-up sequence cost (smaller = surer)
  bool localised = false;   // confidence below the configured threshold
};

// All images must be config.image_size. Errors: invalid configuration (named), too many
// library images, a core failure (status named).
Outcome<std::vector<CoreMatch>> run_core(const std::vector<GrayImage>& library,
                                         const std::vector<GrayImage>& queries,
                                         const LocaliserConfig& config);

// Precision/recall of `matches` against ground truth `is_correct(query, place)`. Queries
// without a candidate (place < 0: no full sequence yet) are not records. The recall
// denominator is the number of queries that have a candidate and, when `has_match` is given,
// a correct place to find at all (novel places cannot be recalled).
template <typename IsCorrect, typename HasMatch>
PrSummary score_matches(const std::vector<CoreMatch>& matches, IsCorrect is_correct,
                        HasMatch has_match) {
  std::vector<MatchRecord> records;
  size_t denominator = 0;
  for (size_t q = 0; q < matches.size(); ++q) {
    if (matches[q].place < 0) continue;
    MatchRecord r;
    r.query = static_cast<uint32_t>(q);
    r.reference = matches[q].place;
    r.confidence = matches[q].confidence;
    r.correct = is_correct(r.query, static_cast<uint32_t>(matches[q].place));
    records.push_back(r);
    if (has_match(r.query)) ++denominator;
  }
  return evaluate_pr(records, denominator);
}

}  // namespace seqslam::tools
