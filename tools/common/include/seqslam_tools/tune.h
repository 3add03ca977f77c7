// Choosing settings by evidence (`seqslam tune`, docs/seqslam_eval.md "Tune"): from the rows of
// one or more `seqslam sweep` results files, leave-one-pair-out cross-validation. For every
// pair held out, the setting with the best mean recall at 100 % precision over the *other*
// pairs is chosen (ties: mean AUC, then mean top-1, then the setting's text), and only its
// figures on the held-out pair are reported - a pair is never scored with settings tuned on it.
// Stability is how many folds chose the same setting.
#pragma once

#include <cstddef>
#include <string>
#include <vector>

#include "seqslam_tools/outcome.h"

namespace seqslam::tools {

// The header of a sweep results file (written by `seqslam sweep`, read by `seqslam tune`).
inline constexpr const char* kSweepHeader =
    "library,query,ground_truth,size,preprocess,seq_len,window,exclusion,threshold,max_shift,"
    "matcher,metric,queries,top1,recall_at_100_precision,auc_pr,precision_at_recall_0.5,"
    "precision_at_recall_0.85,max_recall,accepted,precision,recall,match_ms";

// One row of a sweep results file, as tune reads it.
struct TuneRow {
  std::string pair;  // "library,query,ground_truth"
  std::string
      setting;  // "size,preprocess,seq_len,window,exclusion,threshold,max_shift,matcher,metric"
  double recall_at_100_precision = 0.0;
  double auc_pr = 0.0;
  double top1 = 0.0;
};

// Reads the rows of a sweep results file (tools/seqslam/sweep.cpp writes them): the header
// must be the sweep's; a malformed line is an error naming file and line.
Outcome<std::vector<TuneRow>> read_sweep_rows(const std::string& path);

struct TuneFold {
  std::string held_out;        // the pair scored
  std::string chosen;          // the setting chosen on the other pairs
  double chosen_recall = 0.0;  // on the held-out pair
  double chosen_auc = 0.0;
  bool has_default = false;  // the default setting was swept on this pair
  double default_recall = 0.0;
  double default_auc = 0.0;
};

struct TuneReport {
  std::vector<std::string> pairs;     // in first-seen order
  std::vector<std::string> settings;  // complete ones (swept on every pair), sorted
  size_t incomplete_settings = 0;     // swept on some pairs only: left out
  std::vector<TuneFold> folds;        // one per pair
  std::string overall;                // the best setting over all pairs (the recommendation)
  size_t overall_folds = 0;           // folds that chose it (stability)
  size_t distinct_choices = 0;        // distinct settings chosen over the folds
};

// Needs at least two pairs and one setting swept on all of them. A pair/setting seen twice
// with other figures is an error (two sweeps of different versions mixed).
Outcome<TuneReport> tune(const std::vector<TuneRow>& rows, const std::string& default_setting);

// The report as Markdown: the folds' table, the stability line, the recommendation and the
// worst loss of the chosen settings against the default on a held-out pair.
std::string tune_markdown(const TuneReport& report, const std::string& default_setting);

}  // namespace seqslam::tools
