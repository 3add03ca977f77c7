#include "eval_common.h"

#include <cerrno>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "seqslam/session/profile.h"
#include "cli_common.h"
#include "seqslam/preprocess.h"
#include "seqslam_tools/cli_numbers.h"
#include "seqslam_tools/dream_images.h"
#include "seqslam_tools/input_file.h"
#include "seqslam_tools/json_text.h"
#include "seqslam_tools/pr_metrics.h"
#include "seqslam_tools/q_format.h"

namespace seqslam::cli {

storage::RunConfig eval_defaults() {
  storage::RunConfig c;
  c.heuristic.scan_places = 0;
  return c;
}

void add_eval_options(CLI::App* app, EvalOptions* o) {
  app->add_option("library", o->library,
                  "Library: a dream recording, a directory of images (sorted by name) or an index "
                  "file (one image path per line)")
      ->required();
  app->add_option("query", o->query, "Query: the same kinds of input")->required();
  SettingOptions<>::Selection localiser;
  localiser.scopes = storage::kScopeImage | storage::kScopeSequence | storage::kScopeDifference |
                     storage::kScopeMatcher | storage::kScopeHeuristic | storage::kScopeSlope;
  o->settings.add(app, eval_defaults(), localiser);
  app->add_option(
         "--metric", o->metric,
         "Image difference: mad (the core's SAD), td (tangent distance, slower) or td-noscale "
         "(without the scaling tangent)")
      ->check(CLI::IsMember({"mad", "td", "td-noscale"}))
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

void take_recorded_size(const std::string& library, storage::RunConfig* run) {
  if (const auto recorded = tools::recorded_image_size(library)) {
    run->mapping = hal::PipelineMapping::reduction(recorded->width, recorded->height);
  }
}

void apply_settings(EvalOptions* o) {
  o->run = eval_defaults();
  if (!o->settings.given("size")) take_recorded_size(o->library, &o->run);
  o->settings.apply(&o->run);
  o->config.localiser = o->run.localiser();
  (void)tools::parse_metric(o->metric, &o->config.metric);  // validated by CLI11
  o->config.max_memory = uint64_t{o->max_memory_mib} << 20;
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
  apply_settings(&o);
  const LocaliserConfig& c = o.config.localiser;
  const ConfigCheck check = check_localiser_config(c);
  if (!check.ok()) return usage_error(config_issue_text(check.issue));
  const uint16_t w = c.image_size.width;
  const uint16_t h = c.image_size.height;
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

void add_search_options(CLI::App* app, SearchOptions* o, EvalOptions* eval) {
  app->add_option("--search", o->search,
                  "How the diagonal matcher searches: full (the whole library every step; the "
                  "PC's reference) or route (the head board's route search: a window around "
                  "the odometry's prediction and a relocalisation scan, run query by query "
                  "through the session as the firmware runs it; its storage holds S <= " +
                      std::to_string(profile::kMaxSeqLen) + ", W <= " +
                      std::to_string(profile::kMaxNormWindow) + ", R <= " +
                      std::to_string(profile::kMaxExclusion) + ", a window of " +
                      std::to_string(profile::kWindowSlots) + " diagonals and a scan sequence of " +
                      std::to_string(profile::kMaxScanSeqLen) + ")")
      ->check(CLI::IsMember({"full", "route"}))
      ->capture_default_str();
  SettingOptions<>::Selection route;
  route.scopes = storage::kScopeRoute;
  eval->settings.add(app, eval_defaults(), route);
}

namespace {

// The route search's settings given on the command line.
std::vector<std::string> given_route_options(const EvalOptions& eval) {
  std::vector<std::string> given;
  for (const char* name : {"route-window", "route-slack", "route-growth", "lost-after",
                           "scan-places", "scan-seq-len", "start", "jump-steps", "jump-ratio",
                           "match-level", "sharpness", "tail-steps", "tail-level"}) {
    if (eval.settings.given(name)) given.push_back(std::string("--") + name);
  }
  return given;
}

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
    case ConfigIssue::kRouteJumpStepsZero:
      return "--jump-steps";
    default:
      return nullptr;
  }
}

}  // namespace

int prepare_search(SearchOptions& s, EvalOptions& eval) {
  apply_settings(&eval);
  s.route = s.search == "route";
  const std::vector<std::string> given = given_route_options(eval);
  if (!s.route) {
    if (!given.empty()) {
      return usage_error(given.front() + " applies to the route search: add --search route");
    }
    return kExitOk;
  }
  const auto refuse = [](const std::string& why) { return usage_error("--search route: " + why); };
  const LocaliserConfig& c = eval.config.localiser;
  if (c.matcher != LocaliserMatcher::kDiagonal) {
    return refuse(std::string("the route search runs the diagonal matcher only (--matcher ") +
                  tools::matcher_name(c.matcher) + " given)");
  }
  if (eval.metric != "mad") {
    return refuse("the route search uses the core's SAD (--metric mad; " + eval.metric + " given)");
  }
  if (c.max_shift != 0) {
    return refuse("the route search uses the plain SAD: --max-shift must be 0");
  }
  if (!eval.config.cache_dir.empty()) {
    return refuse("--cache: the route search computes no difference matrix");
  }
  s.start_given = eval.settings.given("start");
  s.start_source = eval.run.route.start;
  // The position is set once the library is loaded (resolve_route_start).
  LocaliserConfig probe = c;
  probe.route.start = s.start_source < 0 ? -1 : 0;
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
    return usage_error("--start " + std::to_string(s.start_source) +
                       ": not a place of the library (source indices " +
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
    // The recall denominator as the full search's: every query with a full sequence (a
    // route search's earlier answers, a short scan's carried along, are not scored).
    if (q + 1 < seq_len) continue;
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
         std::to_string(route.scan_seq_len) + ", jump after " + std::to_string(route.jump_steps) +
         " steps below " + shortest_decimal(route.jump_ratio.raw(), 16) + ", start " +
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

nlohmann::ordered_json route_json(const RouteEvaluation& r, const tools::InputSequence& library,
                                  const tools::InputSequence& query) {
  using Json = nlohmann::ordered_json;
  const RouteSearchConfig& c = r.result.config.localiser.route;
  const tools::RouteCapacity cap = tools::route_capacity();
  Json doc;
  doc["search"] =
      Json{{"kind", "route"},
           {"window", c.window},
           {"slack", c.slack},
           {"growth", tools::json_decimal(shortest_decimal(c.growth.raw(), 8))},
           {"lost_after", c.lost_after},
           {"scan_places", c.scan_places},
           {"scan_seq_len", c.scan_seq_len},
           {"start", c.start < 0 ? Json("unknown") : Json(int64_t{c.start} + library.offset)},
           {"jump_steps", c.jump_steps},
           {"jump_ratio", tools::json_decimal(shortest_decimal(c.jump_ratio.raw(), 16))},
           {"match_level", tools::json_decimal(shortest_decimal(c.match_level.raw(), 16))},
           {"sharpness", tools::json_decimal(shortest_decimal(c.sharpness.raw(), 16))},
           {"tail_steps", c.tail_steps},
           {"tail_level", tools::json_decimal(shortest_decimal(c.tail_level.raw(), 16))},
           {"query_steps", cap.query_steps},
           {"library_ram", false}};
  doc["route"] = Json{{"localised", r.localised},
                      {"withheld", r.withheld},
                      {"withheld_untracked", r.withheld_untracked},
                      {"withheld_probation", r.withheld_probation},
                      {"withheld_carried", r.withheld_carried},
                      {"fixes", r.fixes},
                      {"scan_steps", r.scan_steps},
                      {"scans_completed", r.scans_completed},
                      {"jumps", r.jumps},
                      {"carried", r.carried},
                      {"probation", r.probation},
                      {"scan_errors", r.scan_errors}};
  Json steps = Json::array();
  for (size_t i = 0; i < r.steps.size(); ++i) {
    const RouteStepInfo& f = r.steps[i].info;
    steps.push_back(Json{{"query", i + query.offset},
                         {"localised", r.steps[i].match.localised},
                         {"tracking", f.tracking},
                         {"probation", f.probation},
                         {"fix", f.fix},
                         {"carried", f.carried},
                         {"scan", f.scan_running},
                         {"scan_completed", f.scan_completed},
                         {"jump", f.scan_jumped}});
  }
  doc["route_steps"] = std::move(steps);
  return doc;
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
