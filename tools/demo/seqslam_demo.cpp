// seqslam-demo: runs the fixed-point localiser (the firmware's code) over a library and a
// query image sequence, one image per step, and prints the matches, their confidences and
// the precision/recall reached against the ground truth.
//
// Default data: the corridor dataset bundled in tests/data/corridor (Milford 2013). It is
// time-sampled (no odometry), so one frame is one step; the diagonal matcher still applies
// because both traverses move at similar speed.
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
#include "seqslam_tools/wxh.h"

namespace {

using namespace seqslam;

constexpr uint16_t kMaxSeq = tools::kCoreRunMaxSeq;

struct Options {
  std::string data = SEQSLAM_DEFAULT_DATA;
  LocaliserConfig config;
  bool quiet = false;
};

void usage(FILE* out) {
  std::fprintf(out,
               "usage: seqslam-demo [--data DIR] [--size WxH] [--preprocess none|he|pn|igk|he-pn|"
               "igk-pn|igk-he]\n"
               "                    [--seq-len S] [--window W] [--exclusion R] [--threshold C] "
               "[--quiet]\n"
               "DIR holds ref/ and query/ image directories and ground_truth.csv\n"
               "(default: %s).\n",
               SEQSLAM_DEFAULT_DATA);
}

bool parse_int(const char* text, long lo, long hi, long* out) {
  char* end = nullptr;
  const long v = std::strtol(text, &end, 10);
  if (end == text || *end != '\0' || v < lo || v > hi) return false;
  *out = v;
  return true;
}

// Returns 0 to continue, otherwise an exit status.
int parse(int argc, char** argv, Options* o) {
  o->config.image_size = ImageSize{32, 16};
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const char* v = i + 1 < argc ? argv[i + 1] : nullptr;
    long n = 0;
    // `range`: what the option takes, for the message.
    auto need = [&](bool ok, const std::string& range = "") {
      if (!ok) {
        std::fprintf(stderr, "seqslam-demo: bad or missing value for %s%s%s\n", a.c_str(),
                     range.empty() ? "" : ": ", range.c_str());
      }
      return ok;
    };
    if (a == "--help" || a == "-h") {
      usage(stdout);
      return -1;
    } else if (a == "--quiet") {
      o->quiet = true;
      continue;
    } else if (a == "--data") {
      if (!need(v != nullptr)) return 2;
      o->data = v;
    } else if (a == "--size") {
      uint32_t w = 0;
      uint32_t h = 0;
      if (!need(v != nullptr && tools::split_wxh(v, &w, &h) && w > 0 && h > 0 &&
                    w <= kMaxImageSide && h <= kMaxImageSide,
                "WxH, each 1.." + std::to_string(kMaxImageSide))) {
        return 2;
      }
      o->config.image_size = ImageSize{static_cast<uint16_t>(w), static_cast<uint16_t>(h)};
    } else if (a == "--preprocess") {
      bool found = false;
      for (int m = 0; m <= 6 && v != nullptr; ++m) {
        if (std::string(preprocessing_name(static_cast<Preprocessing>(m))) == v) {
          o->config.preprocess.method = static_cast<Preprocessing>(m);
          found = true;
        }
      }
      if (!need(found, "none, he, pn, igk, he-pn, igk-pn or igk-he")) return 2;
    } else if (a == "--seq-len") {
      if (!need(v != nullptr && parse_int(v, 1, kMaxSeq, &n), "1.." + std::to_string(kMaxSeq))) {
        return 2;
      }
      o->config.sequence.seq_len = static_cast<uint16_t>(n);
    } else if (a == "--window") {
      if (!need(v != nullptr && parse_int(v, 0, kMaxWindow, &n),
                "0.." + std::to_string(kMaxWindow))) {
        return 2;
      }
      o->config.sequence.window = static_cast<uint16_t>(n);
    } else if (a == "--exclusion") {
      if (!need(v != nullptr && parse_int(v, 0, 10000, &n), "0..10000")) return 2;
      o->config.sequence.exclusion = static_cast<uint16_t>(n);
    } else if (a == "--threshold") {
      char* end = nullptr;
      const double c = v != nullptr ? std::strtod(v, &end) : -1.0;
      if (!need(v != nullptr && end != v && *end == '\0' && c >= 0.0 && c <= 1.0, "0..1")) {
        return 2;
      }
      o->config.sequence.threshold = UQ16_16::from_raw(static_cast<uint32_t>(c * 65536.0 + 0.5));
    } else {
      std::fprintf(stderr, "seqslam-demo: unknown option %s\n", a.c_str());
      usage(stderr);
      return 2;
    }
    ++i;
  }
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
