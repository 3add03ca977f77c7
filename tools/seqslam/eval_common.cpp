#include "eval_common.h"

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "cli_common.h"
#include "seqslam/preprocess.h"

namespace seqslam::cli {

void add_eval_options(CLI::App* app, EvalOptions* o) {
  const LocaliserConfig d;
  app->add_option("library", o->library,
                  "Library: a dream recording, a directory of images (sorted by name) or an index "
                  "file (one image path per line)")
      ->required();
  app->add_option("query", o->query, "Query: the same kinds of input")->required();
  app->add_option("--size", o->size,
                  "Image size WxH; images are reduced by the pixel pipeline's area-averaging "
                  "model (dream recordings must already have it)")
      ->capture_default_str();
  app->add_option("--preprocess", o->preprocess, "Preprocessing")
      ->check(CLI::IsMember(preprocessing_names()))
      ->capture_default_str();
  o->config.localiser = d;
  app->add_option("--seq-len", o->config.localiser.sequence.seq_len, "Sequence length S (1..100)")
      ->capture_default_str();
  app->add_option("--window", o->config.localiser.sequence.window,
                  "Local normalisation window W (0 = off, else 2..255)")
      ->capture_default_str();
  app->add_option("--exclusion", o->config.localiser.sequence.exclusion,
                  "Runner-up exclusion radius R in places")
      ->capture_default_str();
  app->add_option("--threshold", o->threshold,
                  "Confidence threshold C (0..1): accepted when best / runner-up is below it "
                  "(default 0.85)")
      ->check(CLI::Validator(
          [](std::string& s) {
            UQ16_16 t;
            return parse_threshold(s, &t);
          },
          "C"));
  app->add_option("--max-shift", o->max_shift,
                  "Horizontal shift tolerance of the difference in pixels (0 = MAD)")
      ->check(CLI::Range(0, 255))
      ->capture_default_str();
  app->add_option("--matcher", o->matcher,
                  "Sequence matcher: diagonal (spatially sampled runs), slope (OpenSeqSLAM's "
                  "velocity search, for time-sampled data), heuristic (the 2015 thesis's greedy "
                  "Algorithm 1; every step reports its anytime best)")
      ->check(CLI::IsMember({"diagonal", "slope", "heuristic"}))
      ->capture_default_str();
  app->add_option(
         "--metric", o->metric,
         "Image difference: mad (the core's SAD), td (tangent distance, slower) or td-noscale "
         "(without the scaling tangent)")
      ->check(CLI::IsMember({"mad", "td", "td-noscale"}))
      ->capture_default_str();
  app->add_option("--k", o->candidates, "Heuristic: candidates followed (1..16)")
      ->check(CLI::Range(1, 16))
      ->capture_default_str();
  app->add_option("--guard", o->guard, "Heuristic: guard window in places")
      ->check(CLI::Range(1, 65535))
      ->capture_default_str();
  app->add_option("--candidate-threshold", o->candidate_threshold,
                  "Heuristic: a first-image distance must be below this many grey levels per "
                  "pixel to become a candidate")
      ->check(CLI::Range(0.0, 255.0))
      ->capture_default_str();
  app->add_option("--vmin", o->vmin, "Slope: slowest query/library speed ratio")
      ->check(CLI::Range(0.01, 4.0))
      ->capture_default_str();
  app->add_option("--vmax", o->vmax, "Slope: fastest ratio")
      ->check(CLI::Range(0.01, 4.0))
      ->capture_default_str();
  app->add_option("--vsteps", o->vsteps, "Slope: velocities tried between vmin and vmax")
      ->check(CLI::Range(1, 32))
      ->capture_default_str();
  app->add_option("--library-range", o->library_range,
                  "Use library images FIRST:LAST (source indices, LAST excluded)");
  app->add_option("--query-range", o->query_range, "Use query images FIRST:LAST");
  app->add_option("--threads", o->config.threads, "Threads (0 = all cores)")->capture_default_str();
  app->add_option("--cache", o->config.cache_dir,
                  "Directory for cached difference matrices (re-used when the preprocessed images "
                  "and the difference settings are the same)");
}

int load_inputs(EvalOptions& o, Loaded* out) {
  uint16_t w = 0, h = 0;
  const std::string size_error = parse_image_size(o.size, &w, &h);
  if (!size_error.empty()) return usage_error("--size: " + size_error);
  LocaliserConfig& c = o.config.localiser;
  c.image_size = ImageSize{w, h};
  (void)parse_preprocessing(o.preprocess, &c.preprocess.method);  // validated by CLI11
  if (!o.threshold.empty()) (void)parse_threshold(o.threshold, &c.sequence.threshold);
  (void)tools::parse_matcher(o.matcher, &o.config.matcher);  // validated by CLI11
  (void)tools::parse_metric(o.metric, &o.config.metric);
  c.max_shift = static_cast<uint8_t>(o.max_shift);
  o.config.heuristic.candidates = static_cast<uint16_t>(o.candidates);
  o.config.heuristic.guard = static_cast<uint16_t>(o.guard);
  o.config.heuristic.threshold =
      UQ8_8::from_raw(static_cast<uint16_t>(std::lround(o.candidate_threshold * 256.0)));
  o.config.slope.vmin = UQ8_8::from_raw(static_cast<uint16_t>(std::lround(o.vmin * 256.0)));
  o.config.slope.vmax = UQ8_8::from_raw(static_cast<uint16_t>(std::lround(o.vmax * 256.0)));
  o.config.slope.vsteps = static_cast<uint8_t>(o.vsteps);
  if (o.config.matcher == tools::MatcherKind::kSlope) {
    tools::EvalConfig probe = o.config;
    probe.slope.seq = c.sequence;
    const Status s = check_slope_config(probe.slope);
    if (s != Status::kOk) {
      return usage_error(std::string("slope settings (--vmin <= --vmax; --vsteps 1 needs them "
                                     "equal): ") +
                         status_name(s));
    }
  }
  const ConfigCheck check = check_localiser_config(c);
  if (!check.ok()) return usage_error(config_issue_text(check.issue));
  tools::IndexRange lr, qr;
  if (!o.library_range.empty()) {
    const auto r = tools::parse_index_range(o.library_range);
    if (!r) return usage_error("--library-range: " + r.error());
    lr = r.value();
  }
  if (!o.query_range.empty()) {
    const auto r = tools::parse_index_range(o.query_range);
    if (!r) return usage_error("--query-range: " + r.error());
    qr = r.value();
  }
  const auto start = std::chrono::steady_clock::now();
  auto lib = tools::load_input(o.library, w, h, lr);
  if (!lib) return fail(lib.error());
  auto qry = tools::load_input(o.query, w, h, qr);
  if (!qry) return fail(qry.error());
  out->library = std::move(lib).value();
  out->query = std::move(qry).value();
  out->load_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  return kExitOk;
}

// Reads seqslam-sim's pairs.csv (library,query,ground_truth,description; paths relative to
// the file's directory).
std::string read_pairs_file(const std::string& path, std::vector<PairSpec>* out) {
  std::ifstream in(path);
  if (!in) return path + ": cannot open";
  namespace fs = std::filesystem;
  const fs::path dir = fs::path(path).parent_path();
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (number == 1) {
      if (line.rfind("library,query,ground_truth", 0) != 0) {
        return path + ":1: expected the header library,query,ground_truth,description";
      }
      continue;
    }
    if (line.empty()) continue;
    std::stringstream ss(line);
    PairSpec p;
    if (!std::getline(ss, p.library, ',') || !std::getline(ss, p.query, ',') ||
        !std::getline(ss, p.truth, ',')) {
      return path + ":" + std::to_string(number) +
             ": expected library,query,ground_truth[,description]";
    }
    std::getline(ss, p.label);
    const auto rel = [&](const std::string& f) {
      return fs::path(f).is_absolute() ? f : (dir / f).string();
    };
    p.library = rel(p.library);
    p.query = rel(p.query);
    if (p.truth.rfind("identity:", 0) != 0 && p.truth.rfind("poses:", 0) != 0)
      p.truth = rel(p.truth);
    out->push_back(p);
  }
  if (out->empty()) return path + ": no pairs";
  return "";
}

}  // namespace seqslam::cli
