// seqslam-demo: runs the fixed-point localiser (the firmware's code) over a library and a
// query image sequence, one image per step, and prints the matches, their confidences and
// the precision/recall reached against the ground truth.
//
// Default data: the corridor dataset bundled in tests/data/corridor (Milford 2013). It is
// time-sampled (no odometry), so one frame is one step; the diagonal matcher still applies
// because both traverses move at similar speed.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "seqslam/hal/host_file.h"
#include "seqslam/seqslam.h"
#include "seqslam_tools/core_run.h"
#include "seqslam_tools/dataset.h"
#include "seqslam_tools/ground_truth.h"
#include "seqslam_tools/output_file.h"
#include "seqslam_tools/pr_metrics.h"
#include "seqslam_tools/q_format.h"
#include "seqslam_tools/settings_cli.h"

namespace {

using namespace seqslam;

struct Options {
  std::string data = SEQSLAM_DEFAULT_DATA;
  // The image, S, W, R and the threshold: the settings table's options.
  cli::SettingOptions<> settings;
  LocaliserConfig config;
  bool quiet = false;
};

// Returns 0 to continue, otherwise an exit status (-1: --help was printed).
int parse(int argc, char** argv, Options* o) {
  CLI::App app{
      "The fixed-point localiser (the firmware's code) over a library and a query image "
      "sequence, one image per step: the matches, their confidences and precision/recall "
      "against the ground truth"};
  app.add_option("--data", o->data,
                 "Directory with ref/ and query/ image directories and ground_truth.csv")
      ->capture_default_str();
  cli::SettingOptions<>::Selection selection;
  selection.scopes = storage::kScopeImage | storage::kScopeSequence;
  selection.except = {"sigma-min"};
  o->settings.add(&app, storage::RunConfig{}, selection);
  app.add_flag("--quiet", o->quiet, "Only the figures, not every match");
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    app.exit(e);
    return -1;
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  storage::RunConfig run;
  o->settings.apply(&run);
  o->config = run.localiser();
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  seqslam::hal::ignore_file_size_signal();  // ulimit -f: a write error with a message
  Options opt;
  const int p = parse(argc, argv, &opt);
  if (p != 0) return p < 0 ? 0 : p;
  const LocaliserConfig& c = opt.config;
  const ConfigCheck check = check_localiser_config(c);
  if (!check.ok()) {
    std::fprintf(stderr, "seqslam-demo: %s (%s)\n", config_issue_text(check.issue),
                 status_name(check.status));
    return 2;
  }
  const tools::LoadedSequence library =
      tools::load_sequence(opt.data + "/ref", c.image_size.width, c.image_size.height);
  const tools::LoadedSequence queries =
      tools::load_sequence(opt.data + "/query", c.image_size.width, c.image_size.height);
  const tools::LoadedGroundTruth truth = tools::load_ground_truth(opt.data + "/ground_truth.csv");
  for (const std::string* err : {&library.error(), &queries.error(), &truth.error()}) {
    if (!err->empty()) {
      std::fprintf(stderr, "seqslam-demo: %s\n", err->c_str());
      return 1;
    }
  }

  const auto matches = tools::run_core(library.value().images, queries.value().images, opt.config);
  if (!matches) {
    std::fprintf(stderr, "seqslam-demo: %s\n", matches.error().c_str());
    return 1;
  }

  const double threshold = tools::to_double(c.sequence.threshold);
  std::printf("seqslam demo: %s\n", opt.data.c_str());
  std::printf("library %zu images, query %zu images, one image per step\n",
              library.value().images.size(), queries.value().images.size());
  std::printf(
      "config: %ux%u %s, S=%u, W=%u, R=%u, threshold %.2f "
      "(fixed-point core, the firmware's code)\n\n",
      c.image_size.width, c.image_size.height, preprocessing_name(c.preprocess.method),
      c.sequence.seq_len, c.sequence.window, c.sequence.exclusion, threshold);
  if (!opt.quiet) std::printf("query  place  confidence  decision       truth\n");
  const tools::GroundTruth& gt = truth.value();
  for (size_t q = 0; q < matches.value().size() && !opt.quiet; ++q) {
    const tools::CoreMatch& m = matches.value()[q];
    if (m.place < 0) continue;
    std::printf("%5zu  %5d  %10.3f  %-13s  %s\n", q, m.place, m.confidence,
                m.localised ? "localised" : "not localised",
                gt.is_correct(static_cast<uint32_t>(q), static_cast<uint32_t>(m.place)) ? "correct"
                                                                                        : "wrong");
  }
  // Recall denominator: every query with a full sequence (the corridor's ground truth has a
  // correct reference for each).
  const tools::PrSummary s = tools::score_matches(
      matches.value(), [&](uint32_t q, uint32_t r) { return gt.is_correct(q, r); },
      [](uint32_t) { return true; });
  const tools::PrPoint op = s.at_threshold(threshold);
  std::printf("\n%zu queries with a full sequence (the first S-1 have none)\n", s.queries);
  std::printf("best match correct (top-1, no threshold): %.1f %%\n", 100.0 * s.top1);
  std::printf("at threshold %.2f: %zu accepted, precision %.1f %%, recall %.1f %%\n", threshold,
              op.accepted, 100.0 * op.precision, 100.0 * op.recall);
  std::printf("recall at 100 %% precision: %.1f %%; area under the PR curve: %.3f\n",
              100.0 * s.recall_at_100_precision, s.auc_pr);
  // The figures are the output: lost on a full disk or /dev/full, the run failed.
  if (const std::string error = tools::finish_stdout(); !error.empty()) {
    std::fprintf(stderr, "seqslam-demo: %s\n", error.c_str());
    return 1;
  }
  return 0;
}
