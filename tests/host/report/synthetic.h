// Synthetic evaluations for the report tests: small inputs (32x16 images), a run with the
// matrices (some matches correct, some wrong, some not accepted, the first S-1 queries without
// a candidate) and a second run labelled "<he&pn>" to overlay.
#pragma once

#include <cstdint>

#include "seqslam_tools/evaluation.h"
#include "seqslam_tools/ground_truth.h"
#include "seqslam_tools/report.h"

namespace seqslam::tools::test {

struct SyntheticOptions {
  uint32_t library = 60;
  uint32_t queries = 50;
  bool ground_truth = true;
  bool poses = true;
  bool second_run = true;
  bool second_run_empty = false;  // the second run has no match candidate at all
};

// Query q shows library place q + kShift (within +-2 places: correct).
inline constexpr uint32_t kShift = 5;
inline constexpr uint16_t kSeqLen = 10;

struct Synthetic {
  InputSequence library;
  InputSequence query;
  GroundTruth truth;
  EvalResult first;   // "none", with matrices
  EvalResult second;  // "<he&pn>", without matrices
  std::vector<ReportRun> runs() const;
  ReportOptions options() const;  // with the ground truth when there is one
  bool has_ground_truth = true;
  bool has_second = true;
};

Synthetic make_synthetic(const SyntheticOptions& options);

}  // namespace seqslam::tools::test
