// seqslam tune: settings chosen by evidence from `seqslam sweep` results, with every pair
// held out in turn (seqslam_tools/tune.h; docs/seqslam_eval.md "Tune").
#include <CLI/CLI.hpp>

#include <memory>
#include <string>
#include <vector>

#include "cli_common.h"
#include "seqslam_tools/output_file.h"
#include "seqslam_tools/tune.h"

namespace seqslam::cli {

namespace {

struct TuneOptions {
  std::vector<std::string> results;
  // `seqslam eval`'s defaults, in the sweep's setting columns.
  std::string default_setting = "32x16,he,30,50,10,0.85,0,diagonal,mad";
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
  const auto report = tools::tune(rows, o.default_setting);
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
  c->add_option("--out", o->out, "Write the Markdown report here (- = standard output)")
      ->capture_default_str();
  c->callback([o, chosen] { *chosen = [o] { return run_tune(*o); }; });
}

}  // namespace seqslam::cli
