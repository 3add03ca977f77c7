// seqslam report (and eval --report): the self-contained HTML page of an evaluation
// (tools/common/src/report.cpp renders it; docs/seqslam_report.md explains it).
#include <CLI/CLI.hpp>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "cli_common.h"
#include "eval_common.h"
#include "seqslam/preprocess.h"
#include "seqslam_tools/cli_numbers.h"
#include "seqslam_tools/report.h"

namespace seqslam::cli {

namespace {

struct ReportOptions {
  EvalOptions eval;
  std::string ground_truth;
  std::string out;
  std::vector<std::string> compare;  // more preprocessing methods, overlaid
  std::vector<uint32_t> pairs_at;    // query positions whose image pairs to show
  std::string title;
};

int save(const std::string& path, const std::vector<tools::ReportRun>& runs,
         const tools::InputSequence& library, const tools::InputSequence& query,
         const tools::GroundTruth& truth, const std::vector<uint32_t>& pairs_at,
         const std::string& title) {
  tools::ReportOptions options;
  options.title = title;
  options.truth = &truth;
  for (const uint32_t q : pairs_at) {
    // Given as source indices; the report wants positions in the (ranged) query input.
    if (q >= query.offset) options.pair_queries.push_back(q - query.offset);
  }
  const auto html = tools::render_report(runs, library, query, options);
  if (!html) return fail(path + ": " + html.error());
  std::string error;
  if (!tools::write_report(path, html.value(), &error)) return fail(error);
  return kExitOk;
}

}  // namespace

int write_report(const std::string& path, const tools::EvalResult& result,
                 const tools::InputSequence& library, const tools::InputSequence& query,
                 const tools::GroundTruth& truth) {
  const std::vector<tools::ReportRun> runs = {
      {preprocessing_name(result.config.localiser.preprocess.method), &result}};
  return save(path, runs, library, query, truth, {}, "");
}

void add_report_command(CLI::App& app, Command* chosen) {
  auto o = std::make_shared<ReportOptions>();
  CLI::App* c = app.add_subcommand(
      "report",
      "Evaluate and write a self-contained HTML report: matrices with the matches and "
      "the ground truth, PR curves, matches over time, trajectories, image pairs");
  add_eval_options(c, &o->eval);
  c->add_option("--ground-truth", o->ground_truth,
                "identity:TOL, poses:METRES or a CSV file (as for eval)")
      ->required();
  c->add_option("--out", o->out, "The HTML file to write")->required();
  c->add_option("--compare", o->compare,
                "More preprocessing methods to evaluate and overlay in the PR charts (e.g. "
                "none,pn); the matrices show the first (--preprocess)")
      ->delimiter(',')
      ->check(CLI::IsMember(preprocessing_names()));
  c->add_option("--pairs-at", o->pairs_at,
                "Query indices (source) whose image pairs to show (default: chosen from the "
                "results)")
      ->delimiter(',')
      ->check(tools::whole_of<uint32_t>());
  c->add_option("--title", o->title, "Page title");
  c->callback([o, chosen] {
    *chosen = [o]() -> int {
      if (const int rc = refuse_inputs_as_outputs(eval_inputs(o->eval, o->ground_truth), {o->out});
          rc != kExitOk)
        return rc;
      Loaded in;
      if (const int rc = load_inputs(o->eval, &in); rc != kExitOk) return rc;
      const auto truth = tools::resolve_ground_truth(o->ground_truth, in.library, in.query);
      if (!truth) return fail(truth.error());
      std::vector<std::unique_ptr<tools::EvalResult>> results;
      std::vector<tools::ReportRun> runs;
      std::vector<std::string> labels = {
          preprocessing_name(o->eval.config.localiser.preprocess.method)};
      labels.insert(labels.end(), o->compare.begin(), o->compare.end());
      for (size_t k = 0; k < labels.size(); ++k) {
        tools::EvalConfig config = o->eval.config;
        config.keep_matrices = k == 0;
        (void)parse_preprocessing(labels[k], &config.localiser.preprocess.method);
        auto r = tools::evaluate(in.library, in.query, config, &truth.value());
        if (!r) return fail(r.error());
        r.value().timing.load_ms = in.load_ms;
        results.push_back(std::make_unique<tools::EvalResult>(std::move(r).value()));
        runs.push_back({labels[k], results.back().get()});
        const tools::PrSummary& s = results.back()->summary;
        std::printf("%-6s top-1 %.1f %%, recall at 100 %% precision %.1f %%, AUC-PR %.3f\n",
                    labels[k].c_str(), 100.0 * s.top1, 100.0 * s.recall_at_100_precision, s.auc_pr);
      }
      const int rc = save(o->out, runs, in.library, in.query, truth.value(), o->pairs_at, o->title);
      if (rc == kExitOk) std::printf("report: %s\n", o->out.c_str());
      return rc;
    };
  });
}

}  // namespace seqslam::cli
