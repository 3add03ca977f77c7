// Options and input loading shared by seqslam run, eval, sweep and report.
#pragma once

#include <CLI/CLI.hpp>

#include <string>
#include <vector>

#include "seqslam/route_search.h"
#include "seqslam/storage/run_config.h"
#include "seqslam_tools/core_run.h"
#include "seqslam_tools/evaluation.h"
#include "seqslam_tools/ground_truth.h"
#include "seqslam_tools/output_file.h"
#include "seqslam_tools/settings_cli.h"

namespace seqslam::cli {

// The defaults of the PC's evaluation: the run configuration's (the settings table), except
// that the heuristic's first scan of a sequence runs in one step (the PC has no step budget;
// the head board spreads it over heuristic-scan-places places a step).
storage::RunConfig eval_defaults();

struct EvalOptions {
  std::string library;
  std::string query;
  std::string library_range;
  std::string query_range;
  std::string metric = "mad";
  uint32_t max_memory_mib = static_cast<uint32_t>(tools::EvalConfig{}.max_memory >> 20);
  // The localiser's settings, from the settings table (storage/run_config.h).
  SettingOptions<> settings;
  storage::RunConfig run = eval_defaults();  // the settings given, over the defaults
  tools::EvalConfig config;  // filled by apply_settings / load_inputs
};

// A recording's images are the size it was made at: a dream recording `library` gives *run
// its own image size (other inputs leave *run as it is). For when --size is not given.
void take_recorded_size(const std::string& library, storage::RunConfig* run);

// The settings given on the command line over eval_defaults(), into o->run and o->config
// (idempotent). Without --size, a dream recording as the library gives its own image size.
void apply_settings(EvalOptions* o);

// Registers LIBRARY QUERY, the localiser's settings from the settings table (the image, the
// sequence, the difference, the matcher and its own settings) and the evaluation's options
// (--metric, ranges, --threads, --cache, --band, --max-memory).
void add_eval_options(CLI::App* app, EvalOptions* o);

struct Loaded {
  tools::InputSequence library;
  tools::InputSequence query;
  double load_ms = 0.0;
};

// The files an evaluation reads: the library and the query (with the images a directory or
// an index file lists) and a ground-truth file (not identity:/poses:), for
// refuse_inputs_as_outputs.
tools::InputFiles eval_inputs(const EvalOptions& o, const std::string& ground_truth);

// Completes o->config from the options and loads both inputs. Returns kExitOk, or the exit
// status after printing the message (usage errors 2, input errors 1).
int load_inputs(EvalOptions& o, Loaded* out);

struct GroundTruthRef {
  const tools::GroundTruth* truth = nullptr;
};

// Writes the HTML report of one evaluation (report.cpp). Returns an exit status.
int write_report(const std::string& path, const tools::EvalResult& result,
                 const tools::InputSequence& library, const tools::InputSequence& query,
                 const tools::GroundTruth& truth);

// ---------------------------------------------------------------------------------------
// Which search the diagonal matcher runs (seqslam run / eval --search; docs/seqslam_eval.md):
//   full  - the whole library every step, in bulk over the difference matrix (the default;
//           the evaluation engine);
//   route - the head board's route search (route_search.h), sequentially through the
//           Localiser exactly as the firmware configures it (tools::run_route).
// The route settings have the names and defaults of `seqslam config write` (the firmware's).

struct SearchOptions {
  std::string search = "full";
  // Set by prepare_search():
  bool route = false;
  int32_t start_source = 0;  // a library source index, or -1 (unknown)
  bool start_given = false;
};

// Registers --search and the route search's settings from the settings table (on `eval`'s
// settings: --route-window, --route-slack, --route-growth, --lost-after, --scan-places,
// --scan-seq-len, --start).
void add_search_options(CLI::App* app, SearchOptions* o, EvalOptions* eval);

// Checks --search and the route options against the other options before any input is
// loaded, and writes the route settings to eval->config.localiser.route (the start is set
// by resolve_route_start once the library is loaded). With --search full any route option
// is refused; with route, what the firmware's route search cannot run (another matcher or
// metric, --max-shift, settings above its storage) is. Returns kExitOk or the status after
// printing the usage error (2).
int prepare_search(SearchOptions& s, EvalOptions& eval);

// --start (a library source index) as a position in the loaded (ranged) library; unknown
// stays -1; without --start the library's first place. kExitOk or a usage error (2) for a
// place outside the library.
int resolve_route_start(const SearchOptions& s, const tools::InputSequence& library,
                        LocaliserConfig* config);

// The route search's results as an evaluation (run / eval print and write them as for the
// full search) and what it did at each step.
struct RouteEvaluation {
  tools::EvalResult result;                  // matches: the board's answers; accepted = localised
  std::vector<tools::RouteCoreMatch> steps;  // one per query
  // Counts over the steps.
  size_t localised = 0;  // answers the board gave as localised
  size_t withheld = 0;   // answers with a confidence below the threshold the search withheld
  size_t withheld_untracked = 0, withheld_probation = 0, withheld_carried = 0;
  size_t fixes = 0, scan_steps = 0, scans_completed = 0, jumps = 0, carried = 0, probation = 0;
  size_t scan_errors = 0;
};

// Runs the route search on loaded inputs (config.localiser.route complete) and scores it
// against `truth` (may be null) as the full search is scored: the recall denominator is
// every query with a full sequence behind it (an answer of -1 there counts as "unknown
// place", never correct). The PR ranking is by confidence, except that an answer the search
// withholds (not localised although its confidence is below the threshold: no prediction
// yet, a jump on probation, a scan's place carried along) ranks after every other answer:
// at the threshold, the accepted answers are exactly the board's localised ones.
tools::Outcome<RouteEvaluation> evaluate_route(const tools::InputSequence& library,
                                               const tools::InputSequence& query,
                                               const tools::EvalConfig& config,
                                               const tools::GroundTruth* truth);

// One line for the text summary's header: "route search (window 33, ...)".
std::string route_settings_text(const RouteSearchConfig& route,
                                const tools::InputSequence& library);
// The route counts for the text summary (one line).
std::string route_counts_text(const RouteEvaluation& r);
// The members `eval_json` writes before "matches": "search", "route" (counts) and
// "route_steps" (one per query: its flags).
nlohmann::ordered_json route_json(const RouteEvaluation& r, const tools::InputSequence& library,
                                  const tools::InputSequence& query);

// A library/query pair with its ground truth (a file, identity:TOL or poses:METRES).
struct PairSpec {
  std::string library, query, truth, label;
};

// Appends the pairs of a seqslam-sim pairs.csv (library,query,ground_truth,description;
// paths relative to the file's directory). Returns "" or an error naming the file and line.
std::string read_pairs_file(const std::string& path, std::vector<PairSpec>* out);

// The files a set of pairs reads (the pairs file, each pair's library and query with the
// images they list, a ground-truth file), for refuse_inputs_as_outputs.
tools::InputFiles pair_inputs(const std::string& pairs_file, const std::vector<PairSpec>& pairs);

}  // namespace seqslam::cli
