#include "eval_common.h"

#include <cerrno>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "app_limits.h"
#include "cli_common.h"
#include "seqslam/preprocess.h"
#include "seqslam_tools/cli_numbers.h"
#include "seqslam_tools/input_file.h"
#include "seqslam_tools/pr_metrics.h"
#include "seqslam_tools/q_format.h"

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
  app->add_option("--seq-len", o->config.localiser.sequence.seq_len, "Sequence length S")
      ->check(tools::whole<int>(1, kMaxSeqLen))
      ->capture_default_str();
  app->add_option(
         "--window", o->config.localiser.sequence.window,
         "Local normalisation window W (0 = off, else 2.." + std::to_string(kMaxWindow) + ")")
      ->check(tools::whole<int>(0, kMaxWindow))
      ->capture_default_str();
  app->add_option("--exclusion", o->config.localiser.sequence.exclusion,
                  "Runner-up exclusion radius R in places")
      ->check(tools::whole_of<uint16_t>())
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
      ->check(tools::whole<int>(0, 255))
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
  app->add_option("--k", o->candidates, "Heuristic: candidates followed")
      ->check(tools::whole<int>(1, kMaxHeuristicCandidates))
      ->capture_default_str();
  app->add_option("--guard", o->guard, "Heuristic: guard window in places")
      ->check(tools::whole<int>(1, 65535))
      ->capture_default_str();
  app->add_option("--candidate-threshold", o->candidate_threshold,
                  "Heuristic: a first-image distance must be below this many grey levels per "
                  "pixel to become a candidate")
      ->check(tools::real(0.0, 255.0))
      ->capture_default_str();
  app->add_option("--vmin", o->vmin, "Slope: slowest query/library speed ratio")
      ->check(tools::real(0.01, 4.0))
      ->capture_default_str();
  app->add_option("--vmax", o->vmax, "Slope: fastest ratio")
      ->check(tools::real(0.01, 4.0))
      ->capture_default_str();
  app->add_option("--vsteps", o->vsteps, "Slope: velocities tried between vmin and vmax")
      ->check(tools::whole<int>(1, 32))
      ->capture_default_str();
  app->add_option("--library-range", o->library_range,
                  "Use library images FIRST:LAST (source indices, LAST excluded)");
  app->add_option("--query-range", o->query_range, "Use query images FIRST:LAST");
  app->add_option("--threads", o->config.threads, "Threads (0 = all cores)")
      ->check(tools::whole_of<unsigned>())
      ->capture_default_str();
  app->add_option("--cache", o->config.cache_dir,
                  "Directory for cached difference matrices (re-used when the preprocessed images "
                  "and the difference settings are the same)");
  app->add_option("--band", o->config.band_rows,
                  "Compute the difference matrix this many query rows at a time (0 = bands of up "
                  "to 1024 rows; the whole matrix with --cache or --report)")
      ->check(tools::whole<uint32_t>(0, tools::kEvalMaxPlaces))
      ->capture_default_str();
  app->add_option("--max-memory", o->max_memory_mib,
                  "MiB the evaluation may hold (images, difference rows, matcher state); a plan "
                  "above it is refused with the figure it needs")
      ->check(tools::whole<uint32_t>(1, 1u << 24))
      ->capture_default_str();
}

tools::InputFiles eval_inputs(const EvalOptions& o, const std::string& ground_truth) {
  tools::InputFiles inputs;
  inputs.add_sequence(o.library);
  inputs.add_sequence(o.query);
  if (!ground_truth.empty() && ground_truth.rfind("identity:", 0) != 0 &&
      ground_truth.rfind("poses:", 0) != 0) {
    inputs.add(ground_truth);
  }
  return inputs;
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
  o.config.heuristic.threshold = tools::from_double<UQ8_8>(o.candidate_threshold);
  o.config.slope.vmin = tools::from_double<UQ8_8>(o.vmin);
  o.config.slope.vmax = tools::from_double<UQ8_8>(o.vmax);
  o.config.slope.vsteps = static_cast<uint8_t>(o.vsteps);
  o.config.max_memory = uint64_t{o.max_memory_mib} << 20;
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

// ---------------------------------------------------------------------------------------
// --search

namespace {

// --start for eval and run: a library source index (>= 0) or unknown.
std::string parse_eval_start(const std::string& text, int32_t* start) {
  std::string error = parse_route_start(text, start);
  if (error.empty() && *start < -1)
    error = "'" + text + "' is not a library place (a whole number >= 0) or 'unknown'";
  return error;
}

}  // namespace

void add_search_options(CLI::App* app, SearchOptions* o) {
  const RouteSearchConfig d;
  app->add_option("--search", o->search,
                  "How the diagonal matcher searches: full (the whole library every step; the "
                  "PC's reference) or route (the head board's route search: a window around "
                  "the odometry's prediction and a relocalisation scan, run query by query "
                  "through the Localiser as the firmware configures it)")
      ->check(CLI::IsMember({"full", "route"}))
      ->capture_default_str();
  const auto count = [](int lo) { return tools::whole<int>(lo, 65535); };
  o->route_options.push_back(
      app->add_option("--route-window", o->route_window,
                      "Route search: diagonals the window keeps around the prediction (odd, at "
                      "least 2 R + 3; the head board holds at most " +
                          std::to_string(app::kWindowSlots) + "). Default " +
                          std::to_string(d.window))
          ->type_name("N")
          ->check(count(0)));
  o->route_options.push_back(
      app->add_option("--route-slack", o->route_slack,
                      "Route search: places either side of the prediction the answer may be "
                      "right after a fix. Default " +
                          std::to_string(d.slack))
          ->type_name("N")
          ->check(count(0)));
  o->route_options.push_back(
      app->add_option("--route-growth", o->route_growth,
                      "Route search: places the search radius grows by per place without a fix "
                      "(a decimal, stored in steps of 1/256). Default " +
                          shortest_decimal(d.growth.raw(), 8))
          ->type_name("X")
          ->check(CLI::Validator(
              [](std::string& v) {
                UQ8_8 ignored;
                return parse_route_growth(v, &ignored);
              },
              "")));
  o->route_options.push_back(
      app->add_option("--lost-after", o->lost_after,
                      "Route search: places without a fix before the relocalisation scan "
                      "starts (>= 1). Default " +
                          std::to_string(d.lost_after))
          ->type_name("N")
          ->check(count(0)));
  o->route_options.push_back(
      app->add_option("--scan-places", o->scan_places,
                      "Route search: library places the scan streams per step (>= 1). Default " +
                          std::to_string(d.scan_places))
          ->type_name("N")
          ->check(count(0)));
  o->route_options.push_back(
      app->add_option("--scan-seq-len", o->scan_seq_len,
                      "Route search: the scan's sequence length (>= 1; S if longer; the head "
                      "board holds at most " +
                          std::to_string(app::kMaxScanSeqLen) + "). Default " +
                          std::to_string(d.scan_seq_len))
          ->type_name("N")
          ->check(count(0)));
  o->route_options.push_back(
      app->add_option("--start", o->start,
                      "Route search: the library place (source index) the query run starts at, "
                      "or unknown (nothing is localised until a scan has found the place). "
                      "Default: the library's first place")
          ->type_name("PLACE|unknown")
          ->check(CLI::Validator(
              [](std::string& v) {
                int32_t ignored = 0;
                return parse_eval_start(v, &ignored);
              },
              "")));
}

namespace {

// The option that sets a route setting, for messages.
const char* route_option_of(ConfigIssue issue) {
  switch (issue) {
    case ConfigIssue::kRouteWindowOutOfRange:
      return "--route-window";
    case ConfigIssue::kRouteLostAfterZero:
      return "--lost-after";
    case ConfigIssue::kRouteScanPlacesZero:
      return "--scan-places";
    case ConfigIssue::kRouteScanSeqLenOutOfRange:
      return "--scan-seq-len";
    case ConfigIssue::kRouteStartOutOfRange:
      return "--start";
    default:
      return nullptr;
  }
}

}  // namespace

int prepare_search(SearchOptions& s, EvalOptions& eval) {
  s.route = s.search == "route";
  if (!s.route) {
    for (const CLI::Option* opt : s.route_options) {
      if (opt->count() > 0) {
        return usage_error(opt->get_name() + " applies to the route search: add --search route");
      }
    }
    return kExitOk;
  }
  const auto refuse = [](const std::string& why) { return usage_error("--search route: " + why); };
  if (eval.matcher != "diagonal") {
    return refuse("the route search runs the diagonal matcher only (--matcher " + eval.matcher +
                  " given)");
  }
  if (eval.metric != "mad") {
    return refuse("the route search uses the core's SAD (--metric mad; " + eval.metric + " given)");
  }
  if (eval.max_shift != 0) {
    return refuse("the route search uses the plain SAD: --max-shift must be 0");
  }
  if (!eval.config.cache_dir.empty()) {
    return refuse("--cache: the route search computes no difference matrix");
  }
  RouteSearchConfig& r = eval.config.localiser.route;
  r = RouteSearchConfig{};
  r.window = static_cast<uint16_t>(s.route_window);
  r.slack = static_cast<uint16_t>(s.route_slack);
  if (!s.route_growth.empty()) (void)parse_route_growth(s.route_growth, &r.growth);  // checked
  r.lost_after = static_cast<uint16_t>(s.lost_after);
  r.scan_places = static_cast<uint16_t>(s.scan_places);
  r.scan_seq_len = static_cast<uint16_t>(s.scan_seq_len);
  s.start_given = !s.start.empty();
  s.start_source = 0;
  if (s.start_given) (void)parse_eval_start(s.start, &s.start_source);  // checked by CLI11
  r.start = s.start_source < 0 ? -1 : 0;  // the position is set once the library is loaded
  LocaliserConfig probe = eval.config.localiser;
  probe.max_shift = static_cast<uint8_t>(eval.max_shift);
  const ConfigCheck check = check_localiser_config(probe);
  if (!check.ok()) {
    const char* option = route_option_of(check.issue);
    return refuse(std::string(option != nullptr ? option : "settings") + ": " +
                  config_issue_text(check.issue));
  }
  const std::string why = tools::route_search_refusal(probe);
  if (!why.empty()) return refuse(why);
  return kExitOk;
}

int resolve_route_start(const SearchOptions& s, const tools::InputSequence& library,
                        LocaliserConfig* config) {
  if (s.start_source < 0) {
    config->route.start = -1;
    return kExitOk;
  }
  const int64_t position = static_cast<int64_t>(s.start_source) - library.offset;
  if (s.start_given && (position < 0 || position >= static_cast<int64_t>(library.images.size()))) {
    return usage_error("--start " + s.start + ": not a place of the library (source indices " +
                       std::to_string(library.offset) + ".." +
                       std::to_string(library.offset + library.images.size() - 1) + ")");
  }
  config->route.start = s.start_given ? static_cast<int32_t>(position) : 0;
  return kExitOk;
}

tools::Outcome<RouteEvaluation> evaluate_route(const tools::InputSequence& library,
                                               const tools::InputSequence& query,
                                               const tools::EvalConfig& config,
                                               const tools::GroundTruth* truth) {
  const auto start = std::chrono::steady_clock::now();
  auto run = tools::run_route(library.images, query.images, config.localiser);
  if (!run) return tools::Error{"route search: " + run.error()};
  RouteEvaluation e;
  e.steps = std::move(run).value();
  tools::EvalResult& r = e.result;
  r.config = config;
  r.library_size = static_cast<uint32_t>(library.images.size());
  r.query_size = static_cast<uint32_t>(query.images.size());
  r.timing.match_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  r.timing.total_ms = r.timing.match_ms;
  const UQ16_16 threshold = config.localiser.sequence.threshold;
  const uint32_t seq_len = config.localiser.sequence.seq_len;
  std::vector<tools::MatchRecord> records;
  size_t denominator = 0;
  r.matches.resize(e.steps.size());
  for (uint32_t q = 0; q < e.steps.size(); ++q) {
    const Match& m = e.steps[q].match;
    const RouteStepInfo& info = e.steps[q].info;
    tools::QueryResult& qr = r.matches[q];
    qr.query = q;
    qr.library = m.place;
    qr.runner_up = m.runner_up;
    qr.confidence = tools::to_double(m.confidence);
    qr.accepted = m.localised;
    if (truth != nullptr) {
      qr.has_truth = truth->has_match(q);
      qr.correct = m.place >= 0 && truth->is_correct(q, static_cast<uint32_t>(m.place));
    }
    const bool withheld = m.place >= 0 && !m.localised && m.confidence < threshold;
    if (m.localised) ++e.localised;
    if (withheld) {
      ++e.withheld;
      if (info.carried) {
        ++e.withheld_carried;
      } else if (info.probation) {
        ++e.withheld_probation;
      } else {
        ++e.withheld_untracked;
      }
    }
    if (info.fix) ++e.fixes;
    if (info.scan_running) ++e.scan_steps;
    if (info.scan_completed) ++e.scans_completed;
    if (info.scan_jumped) ++e.jumps;
    if (info.carried) ++e.carried;
    if (info.probation) ++e.probation;
    if (info.scan_status != Status::kOk) ++e.scan_errors;
    // The recall denominator as the full search's: every query with a full sequence.
    if (m.place < 0 && q + 1 < seq_len) continue;
    ++denominator;
    if (m.place >= 0) {
      // A withheld answer ranks after every answer the board could give as localised.
      const double rank = withheld ? 1.0 + qr.confidence : qr.confidence;
      records.push_back(tools::MatchRecord{q, m.place, rank, qr.correct});
    }
  }
  if (truth != nullptr) {
    r.has_ground_truth = true;
    r.summary = tools::evaluate_pr(records, denominator);
  }
  return e;
}

std::string route_settings_text(const RouteSearchConfig& route,
                                const tools::InputSequence& library) {
  const tools::RouteCapacity cap = tools::route_capacity();
  return "route search: window " + std::to_string(route.window) + ", slack " +
         std::to_string(route.slack) + ", growth " + shortest_decimal(route.growth.raw(), 8) +
         ", lost after " + std::to_string(route.lost_after) + ", scan " +
         std::to_string(route.scan_places) + " places a step, scan sequence " +
         std::to_string(route.scan_seq_len) + ", start " +
         (route.start < 0 ? std::string("unknown")
                          : "place " + std::to_string(int64_t{route.start} + library.offset)) +
         "; the head board's storage, query history " + std::to_string(cap.query_steps) + " steps";
}

std::string route_counts_text(const RouteEvaluation& r) {
  return "route search: " + std::to_string(r.localised) + " answers localised, " +
         std::to_string(r.withheld) + " withheld below the threshold (" +
         std::to_string(r.withheld_untracked) + " without a prediction, " +
         std::to_string(r.withheld_probation) + " on probation, " +
         std::to_string(r.withheld_carried) + " carried); " + std::to_string(r.fixes) +
         " fixes, scans completed " + std::to_string(r.scans_completed) + " (" +
         std::to_string(r.scan_steps) + " steps), jumps " + std::to_string(r.jumps) +
         ", carried answers " + std::to_string(r.carried) + ", steps on probation " +
         std::to_string(r.probation) +
         (r.scan_errors > 0 ? ", scan errors " + std::to_string(r.scan_errors) : std::string());
}

std::string route_json(const RouteEvaluation& r, const tools::InputSequence& library,
                       const tools::InputSequence& query) {
  const RouteSearchConfig& c = r.result.config.localiser.route;
  const tools::RouteCapacity cap = tools::route_capacity();
  std::ostringstream o;
  o << "  \"search\": {\"kind\": \"route\", \"window\": " << c.window << ", \"slack\": " << c.slack
    << ", \"growth\": " << shortest_decimal(c.growth.raw(), 8)
    << ", \"lost_after\": " << c.lost_after << ", \"scan_places\": " << c.scan_places
    << ", \"scan_seq_len\": " << c.scan_seq_len << ", \"start\": "
    << (c.start < 0 ? std::string("\"unknown\"")
                    : std::to_string(int64_t{c.start} + library.offset))
    << ", \"query_steps\": " << cap.query_steps << ", \"library_ram\": false},\n";
  o << "  \"route\": {\"localised\": " << r.localised << ", \"withheld\": " << r.withheld
    << ", \"withheld_untracked\": " << r.withheld_untracked
    << ", \"withheld_probation\": " << r.withheld_probation
    << ", \"withheld_carried\": " << r.withheld_carried << ", \"fixes\": " << r.fixes
    << ", \"scan_steps\": " << r.scan_steps << ", \"scans_completed\": " << r.scans_completed
    << ", \"jumps\": " << r.jumps << ", \"carried\": " << r.carried
    << ", \"probation\": " << r.probation << ", \"scan_errors\": " << r.scan_errors << "},\n";
  const auto b = [](bool v) { return v ? "true" : "false"; };
  o << "  \"route_steps\": [";
  for (size_t i = 0; i < r.steps.size(); ++i) {
    const RouteStepInfo& f = r.steps[i].info;
    o << (i ? ",\n    " : "\n    ") << "{\"query\": " << i + query.offset
      << ", \"localised\": " << b(r.steps[i].match.localised) << ", \"tracking\": " << b(f.tracking)
      << ", \"probation\": " << b(f.probation) << ", \"fix\": " << b(f.fix)
      << ", \"carried\": " << b(f.carried) << ", \"scan\": " << b(f.scan_running)
      << ", \"scan_completed\": " << b(f.scan_completed) << ", \"jump\": " << b(f.scan_jumped)
      << "}";
  }
  o << "\n  ],\n";
  return o.str();
}

// Reads seqslam-sim's pairs.csv (library,query,ground_truth,description; paths relative to
// the file's directory).
std::string read_pairs_file(const std::string& path, std::vector<PairSpec>* out) {
  if (std::string why = tools::check_regular_input(path); !why.empty()) return why;
  std::ifstream in(path);
  if (!in) return path + ": cannot open: " + std::strerror(errno);
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

tools::InputFiles pair_inputs(const std::string& pairs_file, const std::vector<PairSpec>& pairs) {
  tools::InputFiles inputs;
  inputs.add(pairs_file);
  for (const PairSpec& p : pairs) {
    inputs.add_sequence(p.library);
    inputs.add_sequence(p.query);
    inputs.add(p.truth);  // identity:/poses: name no file and are ignored
  }
  return inputs;
}

}  // namespace seqslam::cli
