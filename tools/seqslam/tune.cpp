// seqslam tune: settings chosen by evidence from `seqslam sweep` results, with every pair
// held out in turn (seqslam_tools/tune.h; docs/seqslam_eval.md "Tune").
#include <CLI/CLI.hpp>

#include <memory>
#include <string>
#include <vector>

#include "cli_common.h"
#include "eval_common.h"
#include "seqslam_tools/output_file.h"
#include "seqslam_tools/settings_cli.h"
#include "seqslam_tools/tune.h"

namespace seqslam::cli {

namespace {

// `seqslam eval`'s defaults (the settings table's), in the sweep's setting columns.
std::string eval_default_setting() {
  std::string s;
  for (const char* name : {"size", "preprocess", "seq-len", "window", "exclusion", "threshold",
                           "max-shift", "matcher"})
    s += setting_value_text(eval_defaults(), name) + ",";
  return s + "mad";
}

struct TuneOptions {
  std::vector<std::string> results;
  std::string default_setting = eval_default_setting();
  std::string objective = "worst-gain";
  std::string measure = "auc";
  bool no_smoothing = false;
  bool no_dataset_balance = false;
  std::string out = "-";
};

int run_tune(const TuneOptions& o) {
  // A setting sweep could have run, or the comparison is with nothing (it accepted
  // "32x16,he,30", a NaN threshold, seq_len 0 and said "not swept").
  if (std::string why = tools::check_sweep_setting(o.default_setting); !why.empty()) {
    return usage_error("--default: " + why);
  }
  tools::InputFiles inputs;
  for (const std::string& r : o.results)
    inputs.add(r);
  if (const int rc = refuse_inputs_as_outputs(inputs, {o.out}); rc != kExitOk) return rc;
  std::vector<tools::TuneRow> rows;
  for (const std::string& path : o.results) {
    auto r = tools::read_sweep_rows(path);
    if (!r) return fail(r.error());
    rows.insert(rows.end(), r.value().begin(), r.value().end());
  }
  tools::TuneRule rule;
  rule.objective =
      o.objective == "mean" ? tools::TuneObjective::kMean : tools::TuneObjective::kWorstGain;
  rule.measure = o.measure == "auc" ? tools::TuneMeasure::kAucPr : tools::TuneMeasure::kRecallAt100;
  rule.smooth = !o.no_smoothing;
  rule.balance_datasets = !o.no_dataset_balance;
  const auto report = tools::tune(rows, o.default_setting, rule);
  if (!report) return fail(report.error());
  const std::string error =
      tools::write_output(o.out, tools::tune_markdown(report.value(), o.default_setting));
  return error.empty() ? kExitOk : fail(error);
}

}  // namespace

void add_tune_command(CLI::App& app, Command* chosen) {
  auto o = std::make_shared<TuneOptions>();
  CLI::App* c = app.add_subcommand(
      "tune",
      "Choose settings from sweep results by leave-one-pair-out cross-validation: each pair is "
      "scored only with settings chosen on the others");
  c->add_option("results", o->results, "Results files of seqslam sweep (rows of one version)")
      ->required();
  c->add_option("--default", o->default_setting,
                "The setting to compare with, in the sweep's columns size,preprocess,seq_len,"
                "window,exclusion,threshold,max_shift,matcher,metric")
      ->capture_default_str();
  c->add_option("--objective", o->objective,
                "How a setting's figures over the other pairs make its score: worst-gain (the "
                "worst over the pairs of its gain over --default, ties to the mean) or mean")
      ->check(CLI::IsMember({"worst-gain", "mean"}))
      ->capture_default_str();
  c->add_option("--measure", o->measure,
                "What settings are chosen by: auc (area under the PR curve) or recall-at-100 "
                "(recall at 100 % precision, which one confident wrong answer decides)")
      ->check(CLI::IsMember({"auc", "recall-at-100"}))
      ->capture_default_str();
  c->add_flag("--no-smoothing", o->no_smoothing,
              "Score each setting by its own figure (default: the least over it and its "
              "neighbours in S and W)");
  c->add_flag("--no-dataset-balance", o->no_dataset_balance,
              "Average over pairs (default: each dataset, the library's directory without "
              "-s<seed>, weighs the same)");
  c->add_option("--out", o->out, "Write the Markdown report here (- = standard output)")
      ->capture_default_str();
  c->callback([o, chosen] { *chosen = [o] { return run_tune(*o); }; });
}

}  // namespace seqslam::cli
