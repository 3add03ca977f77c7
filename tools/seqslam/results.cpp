// seqslam results: the firmware's localisation results (volume file `results`) as a table
// or CSV, or scored against a ground truth (precision / recall, as seqslam-demo scores).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "cli_common.h"
#include "seqslam_tools/json_text.h"
#include "seqslam/storage/run_files.h"
#include "seqslam_tools/ground_truth.h"
#include "seqslam_tools/output_file.h"
#include "seqslam_tools/pr_metrics.h"
#include "seqslam_tools/q_format.h"

namespace seqslam::cli {

namespace {

struct ResultsOptions {
  std::string source;
  std::string csv;
  std::string ground_truth;
  std::string threshold;  // empty: the run configuration's (see choose_threshold)
  std::string json;
};

// The threshold the scores are reported at, and where it comes from (for the summary).
struct Threshold {
  UQ16_16 value = SequenceConfig{}.threshold;
  std::string source;
  bool explicit_value = false;
};

// The results file records no threshold (RunResult and the results log header hold none),
// so the honest source is what the firmware reads at start: the volume file `config` of the
// same disk image, or its defaults when there is no such file (firmware/app). A standalone
// results file has neither: the library's default. Returns "" or a message for fail().
std::string choose_threshold(const ResultsOptions& o, const LogSource& source, Threshold* out) {
  if (!o.threshold.empty()) {
    (void)parse_threshold(o.threshold, &out->value);  // validated by CLI11 already
    out->source = "given with --threshold";
    out->explicit_value = true;
    return {};
  }
  const Disk* disk = source.disk();
  if (disk == nullptr) {
    out->source =
        "the default: a standalone results file does not record the threshold (give "
        "--threshold)";
    return {};
  }
  storage::Region region;
  if (disk->volume().open(storage::kConfigFile, &region) != Status::kOk) {
    out->source = "the firmware's default: " + disk->path() + " has no volume file 'config'";
    return {};
  }
  const std::string where = disk->path() + ":" + storage::kConfigFile;
  storage::RunConfig config;
  storage::LogProblem problem = storage::LogProblem::kNone;
  const Status s = storage::read_run_config(region, &config, &problem);
  if (s != Status::kOk) {
    return where + ": not a usable run configuration (" +
           (problem != storage::LogProblem::kNone ? std::string(storage::log_problem_text(problem))
                                                  : std::string(status_name(s))) +
           "), so the threshold the firmware used is unknown: give --threshold";
  }
  out->value = config.sequence.threshold;
  out->source = "the run configuration " + where;
  return {};
}

// Whether the route search withheld a step's answer whatever its confidence (route_search.h):
// no prediction yet, a jump on probation, or a scan's place carried along (not measured).
// Only in a log the route search wrote (`route_log`): other searches leave the byte 0.
bool route_withheld(const storage::RunResult& r, bool route_log) {
  return route_log && !r.localised &&
         ((r.route & storage::kRouteTracking) == 0 || (r.route & storage::kRouteProbation) != 0 ||
          (r.route & storage::kRouteCarried) != 0);
}

// The firmware stored its decision (localised = place >= 0 and confidence < its threshold;
// the route search may also withhold an answer, see route_withheld) with every result. When
// the threshold was not given, check that the one found agrees: a configuration rewritten
// after the run would otherwise give figures for another threshold.
void check_localised_flags(const std::vector<storage::RunResult>& results, const Threshold& t,
                           bool route_log) {
  uint32_t disagree = 0;
  bool any_localised = false;
  bool any_rejected = false;
  uint32_t highest_localised = 0;  // raw confidences
  uint32_t lowest_rejected = 0;
  bool flags_fit_a_threshold = true;
  for (const storage::RunResult& r : results) {
    if (route_withheld(r, route_log)) continue;  // says nothing about the threshold
    const uint32_t c = r.confidence.raw();
    if (r.localised != (r.place >= 0 && c < t.value.raw())) ++disagree;
    if (r.place < 0) {
      if (r.localised) flags_fit_a_threshold = false;
    } else if (r.localised) {
      highest_localised = any_localised ? std::max(highest_localised, c) : c;
      any_localised = true;
    } else {
      lowest_rejected = any_rejected ? std::min(lowest_rejected, c) : c;
      any_rejected = true;
    }
  }
  if (disagree == 0) return;
  if (any_localised && any_rejected && highest_localised >= lowest_rejected) {
    flags_fit_a_threshold = false;
  }
  std::string fit = "no single threshold fits the flags";
  if (flags_fit_a_threshold) {
    fit = "the flags fit a threshold";
    if (any_localised) fit += " above " + shortest_decimal(highest_localised, 16);
    if (any_localised && any_rejected) fit += " and";
    if (any_rejected) fit += " at most " + shortest_decimal(lowest_rejected, 16);
  }
  warn(std::to_string(disagree) + " of " + std::to_string(results.size()) +
       " results disagree on 'localised' with threshold " + shortest_decimal(t.value.raw(), 16) +
       " (" + t.source +
       "): the firmware ran with another threshold (configuration changed after the run?); " + fit +
       "; give --threshold");
}

struct Scores {
  size_t results = 0;  // scored results, with and without a match candidate
  tools::PrSummary summary;
  tools::PrPoint at_threshold;
};

std::string scores_json(const Scores& s, const Threshold& t) {
  const nlohmann::ordered_json doc{
      {"queries", s.summary.queries},
      {"top1", s.summary.top1},
      {"threshold", tools::json_decimal(shortest_decimal(t.value.raw(), 16))},
      {"accepted", s.at_threshold.accepted},
      {"precision", s.at_threshold.precision},
      {"recall", s.at_threshold.recall},
      {"recall_at_100_precision", s.summary.recall_at_100_precision},
      {"auc_pr", s.summary.auc_pr}};
  return tools::json_text(doc, tools::JsonNumbers::kShortest);
}

// Writes `text` to `path` ('-': standard output). Returns "" or a message for fail().
std::string write_text(const std::string& path, const std::string& text) {
  tools::OutputFile out;
  const std::string error = out.open(path);
  if (!error.empty()) return error;
  out.write(text);
  return out.commit();
}

// One record per result with a match candidate (place >= 0), the query being the capture
// (place) index of the run; the recall denominator is their number. The same definitions as
// tools/demo/seqslam_demo.cpp: the first S-1 steps, without a full sequence, do not count.
// An answer the route search withheld (route_withheld) ranks after every answer the board
// could have given as localised, as in `seqslam eval --search route` (docs/seqslam_eval.md):
// at any threshold below 1 it is not accepted, whatever its confidence.
Scores score(const std::vector<storage::RunResult>& results, const tools::GroundTruth& truth,
             const Threshold& t, bool route_log) {
  std::vector<tools::MatchRecord> records;
  for (const storage::RunResult& r : results) {
    if (r.place < 0) continue;
    tools::MatchRecord m;
    m.query = r.capture;
    m.reference = r.place;
    m.confidence = tools::to_double(r.confidence);  // exact: compares as the firmware's raw values
    if (route_withheld(r, route_log)) m.confidence += 1.0;
    m.correct = truth.is_correct(r.capture, static_cast<uint32_t>(r.place));
    records.push_back(m);
  }
  Scores s;
  s.results = results.size();
  s.summary = tools::evaluate_pr(records, records.size());
  s.at_threshold = s.summary.at_threshold(tools::to_double(t.value));
  return s;
}

// A ground truth for places the run never reached belongs to another run. Returns "" or the
// message for fail().
std::string check_ground_truth_fits(const std::string& path, const tools::GroundTruth& truth,
                                    const std::vector<storage::RunResult>& results,
                                    const std::string& source) {
  if (truth.matches.empty()) return {};
  const size_t last_query = truth.matches.size() - 1;
  uint32_t last_capture = 0;
  for (const storage::RunResult& r : results)
    last_capture = std::max(last_capture, r.capture);
  if (!results.empty() && last_query <= last_capture) return {};
  const std::string reached = results.empty() ? source + " holds no results"
                                              : "the results in " + source + " end at capture " +
                                                    std::to_string(last_capture);
  return path + ": the ground truth has queries up to " + std::to_string(last_query) + ", but " +
         reached +
         ": the ground truth of another run? (a ground truth for fewer places is fine; if the "
         "run was cut short, drop the rows beyond its last capture)";
}

// What the route search did at a step (RunResult::route, storage::RouteResultBits) as
// letters, in this order: T tracking (a prediction existed), P probation (a scan's jump awaits
// a later scan's word), S the relocalisation scan ran, s ... and completed, J ... and jumped
// (a candidate away from the prediction), C the answer is a scan's place carried along its
// diagonal; '?' for bits this version does not know; "-" for none. docs/seqslam_cli.md.
struct RouteFlag {
  uint8_t bit;
  char letter;
};
constexpr RouteFlag kRouteFlags[] = {
    {storage::kRouteTracking, 'T'},    {storage::kRouteProbation, 'P'},
    {storage::kRouteScanRunning, 'S'}, {storage::kRouteScanCompleted, 's'},
    {storage::kRouteJumped, 'J'},      {storage::kRouteCarried, 'C'},
};

std::string route_letters(uint8_t bits) {
  std::string s;
  uint8_t known = 0;
  for (const RouteFlag& f : kRouteFlags) {
    known = static_cast<uint8_t>(known | f.bit);
    if ((bits & f.bit) != 0) s += f.letter;
  }
  if ((bits & ~known) != 0) s += '?';
  return s.empty() ? "-" : s;
}

// Counts of the route flags over a results log (the summary's "route search" line).
struct RouteCounts {
  bool any = false;  // some result has route flags: the route search wrote them
  uint32_t tracking = 0;
  uint32_t probation = 0;
  uint32_t scan_steps = 0;
  uint32_t scans_completed = 0;
  uint32_t jumps = 0;
  uint32_t carried = 0;
};

RouteCounts count_route(const std::vector<storage::RunResult>& results) {
  RouteCounts c;
  for (const storage::RunResult& r : results) {
    if (r.route != 0) c.any = true;
    if ((r.route & storage::kRouteTracking) != 0) ++c.tracking;
    if ((r.route & storage::kRouteProbation) != 0) ++c.probation;
    if ((r.route & storage::kRouteScanRunning) != 0) ++c.scan_steps;
    if ((r.route & storage::kRouteScanCompleted) != 0) ++c.scans_completed;
    if ((r.route & storage::kRouteJumped) != 0) ++c.jumps;
    if ((r.route & storage::kRouteCarried) != 0) ++c.carried;
  }
  return c;
}

std::string route_summary(const RouteCounts& c) {
  return "route search: scans completed " + std::to_string(c.scans_completed) + ", jumps " +
         std::to_string(c.jumps) + ", carried answers " + std::to_string(c.carried) +
         "; steps with the scan running " + std::to_string(c.scan_steps) + ", on probation " +
         std::to_string(c.probation) + ", tracking " + std::to_string(c.tracking);
}

// Metres (Q31.32) with 10 decimals and degrees (binary angles) with 8 read back exactly;
// confidence (UQ16.16) as raw / 65536 with 6 decimals; the route letters when `route`.
bool print_csv(tools::OutputFile& out, const storage::RunResult& r, bool route) {
  return out.print(
      "%u,%u,%u,%s,%s,%s,%d,%d,%u,%u,%s,%d%s%s\n", r.step, r.capture, r.timestamp_us,
      fixed_decimal(r.pose.x.raw(), 32, 10).c_str(), fixed_decimal(r.pose.y.raw(), 32, 10).c_str(),
      angle_degrees(r.pose.heading.bam, 8).c_str(), r.place, r.runner_up, r.cost, r.runner_up_cost,
      fixed_decimal(r.confidence.raw(), 16, 6).c_str(), r.localised ? 1 : 0, route ? "," : "",
      route ? route_letters(r.route).c_str() : "");
}

void print_row(const storage::RunResult& r, bool route) {
  if (route) {
    std::printf("%6u %7u %12u %10s %10s %11s %6d %9d %10u %14u %10s %-9s %s\n", r.step, r.capture,
                r.timestamp_us, fixed_decimal(r.pose.x.raw(), 32, 3).c_str(),
                fixed_decimal(r.pose.y.raw(), 32, 3).c_str(),
                angle_degrees(r.pose.heading.bam, 2).c_str(), r.place, r.runner_up, r.cost,
                r.runner_up_cost, fixed_decimal(r.confidence.raw(), 16, 4).c_str(),
                r.localised ? "yes" : "no", route_letters(r.route).c_str());
    return;
  }
  std::printf(
      "%6u %7u %12u %10s %10s %11s %6d %9d %10u %14u %10s %s\n", r.step, r.capture, r.timestamp_us,
      fixed_decimal(r.pose.x.raw(), 32, 3).c_str(), fixed_decimal(r.pose.y.raw(), 32, 3).c_str(),
      angle_degrees(r.pose.heading.bam, 2).c_str(), r.place, r.runner_up, r.cost, r.runner_up_cost,
      fixed_decimal(r.confidence.raw(), 16, 4).c_str(), r.localised ? "yes" : "no");
}

// The human-readable summary (the same sentences as seqslam-demo's).
void print_scores(const ResultsOptions& o, const std::string& log_line,
                  const std::string& route_line, const tools::GroundTruth& truth,
                  const Threshold& threshold, const Scores& sc) {
  size_t with_match = 0;
  for (uint32_t q = 0; q < truth.matches.size(); ++q)
    if (truth.has_match(q)) ++with_match;
  const std::string thr = shortest_decimal(threshold.value.raw(), 16);
  std::printf("%s\n", log_line.c_str());
  if (!route_line.empty()) std::printf("%s\n", route_line.c_str());
  if (truth.matches.empty()) {
    std::printf("ground truth %s: no queries\n", o.ground_truth.c_str());
  } else {
    std::printf("ground truth %s: queries 0..%zu, %zu with a correct reference\n",
                o.ground_truth.c_str(), truth.matches.size() - 1, with_match);
  }
  std::printf("threshold %s: %s\n", thr.c_str(), threshold.source.c_str());
  std::printf("%zu queries with a full sequence (results with a match candidate; %zu without)\n",
              sc.summary.queries, sc.results - sc.summary.queries);
  std::printf("best match correct (top-1, no threshold): %.1f %%\n", 100.0 * sc.summary.top1);
  std::printf("at threshold %s: %zu accepted, precision %.1f %%, recall %.1f %%\n", thr.c_str(),
              sc.at_threshold.accepted, 100.0 * sc.at_threshold.precision,
              100.0 * sc.at_threshold.recall);
  std::printf("recall at 100 %% precision: %.1f %%; area under the PR curve: %.3f\n",
              100.0 * sc.summary.recall_at_100_precision, sc.summary.auc_pr);
  if (!o.csv.empty()) std::printf("CSV written to %s\n", o.csv.c_str());
  if (!o.json.empty()) std::printf("JSON written to %s\n", o.json.c_str());
}

// The warnings of how the results log ended (a damaged tail, a damaged commit slot, results
// lost) and the exit status they give: 1 when results were lost.
int log_end_status(LogSource& source, const storage::ResultsReader& reader,
                   uint32_t damaged) {
  const storage::LogProblem how = reader.end_problem();
  int code = kExitOk;
  if (how == storage::LogProblem::kEndDamagedTail) {
    warn(source.name() + ": " + storage::log_problem_text(how));
  }
  if (const uint32_t slot = storage::damaged_commit_slot(source.device(), storage::kResultsKind);
      slot != 0) {
    warn(source.name() + ": " + storage::log_problem_text(storage::LogProblem::kCommitSlotDamaged) +
         " (slot " + std::to_string(slot) + ")");
    code = kExitFailure;
  }
  if (how == storage::LogProblem::kEndTruncated) {
    warn(source.name() + ": " + storage::log_problem_text(how) + ": " +
         (reader.lost_records() > 0 ? std::to_string(reader.lost_records()) + " result(s) lost"
                                    : std::string("how many results it held is unknown")));
    code = kExitFailure;
  } else if (damaged > 0) {
    warn(source.name() + ": " + std::to_string(damaged) +
         " damaged record(s) in the middle of the log were skipped (" +
         std::to_string(reader.lost_records()) + " result(s) lost)");
    code = kExitFailure;
  }
  if (warn_if_truncated(source)) code = kExitFailure;
  return code;
}

int run_results(const ResultsOptions& o) {
  const bool scoring = !o.ground_truth.empty();
  if (scoring && o.csv == "-") {
    return usage_error(
        "--csv -: with --ground-truth the summary goes to standard output; write the CSV to a "
        "file");
  }
  // An output that is an input is refused before anything is read or written.
  tools::InputFiles inputs;
  inputs.add(log_source_file(o.source));
  if (scoring) inputs.add(o.ground_truth);
  if (const int rc = refuse_inputs_as_outputs(inputs, {o.csv, o.json}); rc != kExitOk) return rc;
  LogSource source;
  const std::string error = source.open(o.source, storage::kResultsFile);
  if (!error.empty()) return fail(error);
  storage::ResultsReader reader;
  storage::LogProblem problem = storage::LogProblem::kNone;
  if (reader.open(source.device(), &problem) != Status::kOk) {
    return fail(source.name() + ": " + log_open_problem(source.device(), "results", problem));
  }
  tools::GroundTruth truth;
  Threshold threshold;
  if (scoring) {
    tools::LoadedGroundTruth loaded = tools::load_ground_truth(o.ground_truth);
    if (!loaded) return fail(loaded.error());
    truth = std::move(loaded).value();
    const std::string why = choose_threshold(o, source, &threshold);
    if (!why.empty()) return fail(why);
  }

  const bool csv = !o.csv.empty();
  const bool to_stdout = !csv || o.csv == "-";
  const bool table = !csv && !scoring;
  tools::OutputFile out;  // the CSV: a temporary renamed over OUT, or standard output
  if (csv) {
    const std::string open_error = out.open(o.csv);
    if (!open_error.empty()) return fail(open_error);
  }
  // Read every result first: the route column is there when any result has route flags
  // (results of other searches, and of firmware before the route search, print as before).
  uint32_t count = 0;
  uint32_t localised = 0;
  uint32_t damaged = 0;
  std::vector<storage::RunResult> results;
  Status end = Status::kOk;
  for (;;) {
    storage::RunResult r;
    const Status s = reader.next(&r);
    if (s == Status::kOk) {
      ++count;
      if (r.localised) ++localised;
      results.push_back(r);
    } else if (s == Status::kDataLoss || s == Status::kResourceExhausted) {
      ++damaged;
    } else {
      end = s;
      break;
    }
  }
  const RouteCounts route = count_route(results);
  if (csv) {
    out.print(
        "step,capture,timestamp_us,x_m,y_m,heading_deg,place,runner_up,cost,"
        "runner_up_cost,confidence,localised%s\n",
        route.any ? ",route" : "");
  } else if (table) {
    if (route.any) {
      std::printf("%6s %7s %12s %10s %10s %11s %6s %9s %10s %14s %10s %-9s %s\n", "step", "capture",
                  "timestamp_us", "x_m", "y_m", "heading_deg", "place", "runner_up", "cost",
                  "runner_up_cost", "confidence", "localised", "route");
    } else {
      std::printf("%6s %7s %12s %10s %10s %11s %6s %9s %10s %14s %10s %s\n", "step", "capture",
                  "timestamp_us", "x_m", "y_m", "heading_deg", "place", "runner_up", "cost",
                  "runner_up_cost", "confidence", "localised");
    }
  }
  for (size_t i = 0; i < results.size(); ++i) {
    if (csv) {
      if (!print_csv(out, results[i], route.any)) {
        return fail(out.error() + " (at result " + std::to_string(i) + ", CSV line " +
                    std::to_string(i + 2) + ")");
      }
    } else if (table) {
      print_row(results[i], route.any);
    }
  }
  if (csv) {
    const std::string write_error = out.commit();
    if (!write_error.empty()) return fail(write_error);
  }

  const storage::LogProblem how = reader.end_problem();
  std::string ending = how == storage::LogProblem::kEndClean ? "the log ends cleanly"
                       : how == storage::LogProblem::kEndDamagedTail
                           ? "the log ends with a damaged tail"
                           : std::string("the log ends: ") + storage::log_problem_text(how);
  const std::string summary = std::to_string(count) + " results (" + std::to_string(localised) +
                              " localised), " + std::to_string(damaged) + " damaged records; " +
                              ending;
  const std::string route_line = route.any ? route_summary(route) : std::string();
  if (table) {
    std::printf("%s\n", summary.c_str());
    if (route.any) std::printf("%s\n", route_line.c_str());
  } else if (!scoring && !to_stdout) {
    std::printf("%s: %s\n", o.csv.c_str(), summary.c_str());
    if (route.any) std::printf("%s: %s\n", o.csv.c_str(), route_line.c_str());
  }

  if (end != Status::kOutOfRange) {
    return fail(source.name() + ": read failed after " + std::to_string(count) + " results (" +
                status_name(end) + ")");
  }
  if (scoring) {
    const std::string misfit =
        check_ground_truth_fits(o.ground_truth, truth, results, source.name());
    if (!misfit.empty()) return fail(misfit);
    if (!threshold.explicit_value) check_localised_flags(results, threshold, route.any);
    const Scores sc = score(results, truth, threshold, route.any);
    if (!o.json.empty()) {
      const std::string why = write_text(o.json, scores_json(sc, threshold));
      if (!why.empty()) return fail(why);
    }
    if (o.json != "-") {
      print_scores(o, source.name() + ": " + summary, route_line, truth, threshold, sc);
    }
    std::fflush(stdout);
  }
  return log_end_status(source, reader, damaged);
}

}  // namespace

void add_results_command(CLI::App& app, Command* chosen) {
  auto o = std::make_shared<ResultsOptions>();
  CLI::App* results =
      app.add_subcommand("results",
                         "Print the firmware's localisation results (one per step) as a table, "
                         "write them as CSV, or score them against a ground truth");
  results
      ->add_option("IMAGE", o->source,
                   "Disk image (reads its volume file 'results'), IMAGE:NAME for another "
                   "volume file, or a standalone results file")
      ->required();
  results
      ->add_option(
          "--csv", o->csv,
          "Write CSV to OUT ('-' = standard output) with the header step,capture,timestamp_us,"
          "x_m,y_m,heading_deg,place,runner_up,cost,runner_up_cost,confidence,localised[,route]: "
          "timestamp in microseconds, position in metres (10 decimals) and heading in degrees "
          "(-180..180, 8 decimals) exactly as stored, costs as stored integers, confidence = best "
          "/ runner-up cost (6 decimals, smaller = more certain), localised 1/0; route (only when "
          "some result has route-search flags): T tracking, P probation, S scan ran, s scan "
          "completed, J jumped, C carried, - none")
      ->type_name("OUT");
  CLI::Option* truth =
      results
          ->add_option(
              "--ground-truth", o->ground_truth,
              "Score the results against FILE (CSV 'query_index,matching_reference_indices', as "
              "tests/data/corridor/ground_truth.csv; query = the capture (place) index of this "
              "run, references = library place indices) and print a summary instead of the "
              "table: queries with a full sequence (results with a match candidate), top-1 "
              "correct, accepted / precision / recall at the threshold, recall at 100 % "
              "precision, area under the PR curve. A ground truth with queries beyond the last "
              "capture of the results is an error (status 1): it belongs to another run")
          ->type_name("FILE");
  results
      ->add_option("--threshold", o->threshold,
                   "Confidence threshold C (0..1) for the accepted / precision / recall figures "
                   "(accepted when confidence < C, as the firmware decides). Default: the "
                   "threshold of the run configuration (volume file 'config' of the same disk "
                   "image; the results file does not record it), 0.85 (the firmware's default) "
                   "when the image has no 'config' or the results are a standalone file. A "
                   "default that disagrees with the stored 'localised' flags is warned about")
      ->type_name("C")
      ->needs(truth)
      ->check(CLI::Validator(
          [](std::string& s) {
            UQ16_16 ignored;
            return parse_threshold(s, &ignored);
          },
          ""));
  results
      ->add_option("--json", o->json,
                   "Also write the scores as JSON to OUT ('-' = standard output, instead of the "
                   "summary): keys queries, top1, threshold, accepted, precision, recall, "
                   "recall_at_100_precision, auc_pr (fractions 0..1, not percent)")
      ->type_name("OUT")
      ->needs(truth);
  results->callback([chosen, o] { *chosen = [o] { return run_results(*o); }; });
}

}  // namespace seqslam::cli
