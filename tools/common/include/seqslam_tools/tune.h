// Choosing settings by evidence (`seqslam tune`, docs/seqslam_eval.md "Tune"): from the rows of
// one or more `seqslam sweep` results files, leave-one-pair-out cross-validation. For every
// pair held out, the setting with the best score over the *other* pairs is chosen, and only
// its figures on the held-out pair are reported - a pair is never scored with settings tuned
// on it. Stability is how many folds chose the same setting.
//
// The rule (TuneRule, issue 33) is built so that no single answer can flip it: the measure is
// the area under the PR curve (recall at 100 % precision is decided by the one most confident
// wrong answer); a setting's figure on a pair is the least over it and its neighbours in S and
// W (the next swept values, the rest equal), so a setting must hold on both sides of it; its
// score is the worst over the pairs of that figure's gain over the default's, so a new default
// makes no known pair worse where one exists that does not; ties go to the mean in which each
// dataset weighs the same (dataset_of), so many simulated pairs do not drown two real ones.
#pragma once

#include <stdint.h>

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

// Reads the rows of a sweep results file (tools/seqslam/sweep.cpp writes them): a regular file
// whose header is the sweep's; a malformed row (check_sweep_row) is an error naming file and
// line.
Outcome<std::vector<TuneRow>> read_sweep_rows(const std::string& path);

// Rows read strictly (issue 34: sweep's resume kept rows cut short, of 22 or 24 fields, with
// NaN, top1 = 7 or NUL bytes, and never ran them again).
//
// Splits one CSV line (RFC 4180 quotes, as sweep writes paths that need them); false for an
// unterminated quote.
bool split_sweep_line(const std::string& line, std::vector<std::string>* fields);
// "" when `fields` are a row `seqslam sweep` can have written, else what is wrong, naming the
// column and the value: not 23 fields; an empty path or a control byte (NUL) anywhere; a
// setting its option refuses (check_sweep_setting); queries and accepted not whole numbers,
// accepted above queries; top1, recall_at_100_precision, auc_pr, the precisions, max_recall
// and recall not decimal numbers within 0..1 (NaN, 7); match_ms not a finite number >= 0.
std::string check_sweep_row(const std::vector<std::string>& fields);
// "" when `setting` is the sweep's 9 setting columns size,preprocess,seq_len,window,
// exclusion,threshold,max_shift,matcher,metric with values sweep accepts (WxH with W * H <=
// 512, a preprocessing name, S 1..100, W 0..255, R 0..65535, a threshold decimal in 0..1,
// max_shift 0..255, diagonal|slope|heuristic, mad|td|td-noscale, and a combination
// check_localiser_config accepts); else what is wrong (tune --default).
std::string check_sweep_setting(const std::string& setting);

// What a setting is chosen by.
enum class TuneMeasure : uint8_t {
  kAucPr,        // area under the PR curve (the default)
  kRecallAt100,  // recall at 100 % precision (before issue 33)
};

// How a setting's figures over the training pairs make its score.
enum class TuneObjective : uint8_t {
  // The worst over the pairs of its gain over the default setting (the measure, smoothed,
  // less the default's own on the pair; without the default swept, the measure itself): a
  // setting that makes any known pair worse than today's defaults scores below one that
  // makes none worse. Ties: the mean. The default.
  kWorstGain,
  // The mean over the pairs.
  kMean,
};

struct TuneRule {
  TuneObjective objective = TuneObjective::kWorstGain;
  TuneMeasure measure = TuneMeasure::kAucPr;
  // A setting's figure on a pair: the least over it and its S and W neighbours.
  bool smooth = true;
  // The mean over the training pairs (the objective, or its tie-break) gives each dataset
  // (dataset_of) the same weight.
  bool balance_datasets = true;
};

// The dataset a pair belongs to: the name of the directory the library is in (a recording's
// directory, or the parent of a directory of images), without a trailing "-s<seed>" (the
// simulator's light sets of seeds 1..3 are one dataset): "tests/data/corridor/ref,..." ->
// "corridor", ".../gardens_point/day_left,..." -> "gardens_point",
// ".../lights-s2/loop_noon-lamps.dream,..." -> "lights".
std::string dataset_of(const std::string& pair);

struct TuneFold {
  std::string held_out;         // the pair scored
  std::string dataset;          // its dataset_of
  std::string chosen;           // the setting chosen on the other pairs
  double chosen_measure = 0.0;  // the rule's measure on the held-out pair (unsmoothed)
  double chosen_recall = 0.0;   // on the held-out pair
  double chosen_auc = 0.0;
  bool has_default = false;  // the default setting was swept on this pair
  double default_measure = 0.0;
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
  TuneRule rule;
};

// Needs at least two pairs and one setting swept on all of them. A pair/setting seen twice
// with other figures is an error (two sweeps of different versions mixed).
Outcome<TuneReport> tune(const std::vector<TuneRow>& rows, const std::string& default_setting,
                         const TuneRule& rule = TuneRule{});

// The report as Markdown: the rule, the folds' table, the stability line, the recommendation,
// and per dataset the worst loss of the chosen settings against the default on a held-out pair
// (in points of the rule's measure).
std::string tune_markdown(const TuneReport& report, const std::string& default_setting);

}  // namespace seqslam::tools
