// seqslam run / eval: the localiser (the firmware's fixed-point core) on a library and a query
// sequence - dream recordings, image directories or index files - with per-query results, and
// with a ground truth the precision/recall figures of the 2025 thesis (docs/seqslam_eval.md).
// --search full (default) runs the evaluation engine's full search; --search route the head
// board's route search, query by query through the Localiser (eval_common.h).
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include "cli_common.h"
#include "eval_common.h"
#include "progress.h"
#include "reference.h"
#include "seqslam_tools/evaluation.h"
#include "seqslam_tools/q_format.h"

namespace seqslam::cli {

namespace {

struct RunOptions {
  EvalOptions eval;
  SearchOptions search;
  std::string csv;
  std::string json;
};

struct EvalCommandOptions {
  EvalOptions eval;
  SearchOptions search;
  std::string ground_truth;
  std::string json;
  std::string report;
  bool reference = false;
  bool quiet = false;
};

// Writes `text` to `path` ('-' = standard output) through tools::OutputFile (a temporary
// renamed over the file; every write checked). Returns an exit status.
int write_text(const std::string& path, const std::string& text) {
  const std::string error = tools::write_output(path, text);
  return error.empty() ? kExitOk : fail(error);
}

// One result's columns (query, library, runner_up, confidence, accepted[, has_truth, correct])
// in the recordings' numbering, without the line's end.
void append_match(const tools::QueryResult& m, bool has_truth, const tools::InputSequence& library,
                  const tools::InputSequence& query, std::string* s) {
  char buf[160];
  std::snprintf(buf, sizeof buf, "%u,%lld,%lld,%.6f,%d", m.query + query.offset,
                m.library < 0 ? -1LL : static_cast<long long>(m.library) + library.offset,
                m.runner_up < 0 ? -1LL : static_cast<long long>(m.runner_up) + library.offset,
                m.confidence, m.accepted ? 1 : 0);
  *s += buf;
  if (has_truth) *s += std::string(",") + (m.has_truth ? "1" : "0") + "," + (m.correct ? "1" : "0");
}

std::string results_csv(const tools::EvalResult& r, const tools::InputSequence& library,
                        const tools::InputSequence& query) {
  std::string s = "query,library,runner_up,confidence,accepted";
  s += r.has_ground_truth ? ",has_truth,correct\n" : "\n";
  for (const tools::QueryResult& m : r.matches) {
    append_match(m, r.has_ground_truth, library, query, &s);
    s += "\n";
  }
  return s;
}

// The route search's CSV: the same columns, then what it did at each step (0/1): a prediction
// existed (tracking), a scan's jump awaited confirmation (probation), the answer was a fix, the
// relocalisation scan ran (scan), ... completed (scan_completed), ... named a place away from
// the prediction (jump),
// the answer is a scan's place carried along (carried). `accepted` is the board's decision
// (localised).
std::string route_csv(const RouteEvaluation& e, const tools::InputSequence& library,
                      const tools::InputSequence& query) {
  const tools::EvalResult& r = e.result;
  std::string s = "query,library,runner_up,confidence,accepted";
  s += r.has_ground_truth ? ",has_truth,correct" : "";
  s += ",tracking,probation,fix,scan,scan_completed,jump,carried\n";
  for (size_t i = 0; i < r.matches.size(); ++i) {
    const tools::QueryResult& m = r.matches[i];
    const RouteStepInfo& f = e.steps[i].info;
    append_match(m, r.has_ground_truth, library, query, &s);
    char buf[64];
    std::snprintf(buf, sizeof buf, ",%d,%d,%d,%d,%d,%d,%d\n", f.tracking, f.probation, f.fix,
                  f.scan_running, f.scan_completed, f.scan_jumped, f.carried);
    s += buf;
  }
  return s;
}

void print_summary(const tools::EvalResult& r, double threshold, std::FILE* to) {
  const tools::PrSummary& s = r.summary;
  const tools::PrPoint op = s.at_threshold(threshold);
  std::fprintf(to, "%zu queries with a full sequence (the recall denominator)\n", s.queries);
  std::fprintf(to, "best match correct (top-1, no threshold): %.1f %%\n", 100.0 * s.top1);
  std::fprintf(to, "at threshold %.2f: %zu accepted, precision %.1f %%, recall %.1f %%\n",
               threshold, op.accepted, 100.0 * op.precision, 100.0 * op.recall);
  std::fprintf(to, "recall at 100 %% precision: %.1f %%; area under the PR curve: %.3f\n",
               100.0 * s.recall_at_100_precision, s.auc_pr);
  std::fprintf(to, "precision at recall 0.5: %.1f %%, at 0.85: %.1f %%; max recall %.1f %%\n",
               100.0 * s.precision_at_recall(0.5), 100.0 * s.precision_at_recall(0.85),
               100.0 * s.max_recall);
}

// How one confidence rule of the double-precision reference ranks the same best places.
struct RuleFigures {
  tools::PrSummary summary;
  size_t same = 0;  // queries where this rule's best place is the core's
};

// The double-precision reference beside the core (docs/normalisation.md, "Which offset ranks
// best"): the online rule the core implements (S times the running minimum), the batch rule of
// OpenSeqSLAM (the whole matrix shifted by its global minimum: not online, it needs every
// query first) and the fixed offset (the costs as stored, D+ = z + sqrt(W); online and the
// same at every step). All three have the same best places; only the ranking differs.
struct ReferenceComparison {
  size_t compared = 0;
  double worst = 0.0;  // largest |confidence difference| between the core and the online rule
  RuleFigures online, batch, fixed;
};

RuleFigures rule_figures(const std::vector<reference::Match>& matches,
                         const tools::EvalResult& core, const GroundTruthRef& truth) {
  RuleFigures f;
  std::vector<tools::MatchRecord> records;
  size_t denominator = 0;
  for (size_t q = 0; q < matches.size(); ++q) {
    const reference::Match& m = matches[q];
    if (m.place < 0) continue;
    if (m.place == core.matches[q].library) f.same += 1;
    if (truth.truth == nullptr) continue;
    records.push_back(tools::MatchRecord{
        static_cast<uint32_t>(q), m.place, m.confidence,
        truth.truth->is_correct(static_cast<uint32_t>(q), static_cast<uint32_t>(m.place))});
    ++denominator;
  }
  if (truth.truth != nullptr) f.summary = tools::evaluate_pr(records, denominator);
  return f;
}

// The double-precision reference pipeline over the same inputs (slow: direct sums), for a
// side-by-side comparison with the core.
ReferenceComparison compare_with_reference(const tools::EvalResult& core,
                                           const tools::InputSequence& library,
                                           const tools::InputSequence& query,
                                           const GroundTruthRef& truth) {
  const reference::Params params = reference::Params::from(core.config.localiser);
  reference::Pipeline ref(params);
  for (const tools::GrayImage& img : library.images)
    ref.teach(img.pixels);
  ReferenceComparison c;
  std::vector<reference::Match> online, fixed;
  std::vector<std::vector<double>> mad_rows;
  for (size_t q = 0; q < query.images.size(); ++q) {
    online.push_back(ref.localise(query.images[q].pixels));
    fixed.push_back(reference::select(params, ref.last_costs(), ref.last_valid(), 0.0));
    mad_rows.push_back(ref.last_mad_row());
    const reference::Match& m = online.back();
    const tools::QueryResult& r = core.matches[q];
    if (m.place >= 0 && r.library >= 0) {
      ++c.compared;
      c.worst = std::max(c.worst, std::fabs(m.confidence - r.confidence));
    }
  }
  c.online = rule_figures(online, core, truth);
  c.batch = rule_figures(reference::batch_match(params, mad_rows), core, truth);
  c.fixed = rule_figures(fixed, core, truth);
  return c;
}

void print_reference(const ReferenceComparison& c, std::FILE* to) {
  std::fprintf(to,
               "\nreference (double precision, direct sums): same best place on %zu of %zu "
               "queries, largest confidence difference %.2e\n",
               c.online.same, c.compared, c.worst);
  const auto line = [to](const char* rule, const RuleFigures& f) {
    std::fprintf(
        to, "reference, %s: top-1 %.1f %%, recall at 100 %% precision %.1f %%, AUC-PR %.3f\n", rule,
        100.0 * f.summary.top1, 100.0 * f.summary.recall_at_100_precision, f.summary.auc_pr);
  };
  line("online offset (the core's rule)", c.online);
  line("batch global minimum (not online)", c.batch);
  line("fixed offset (costs as stored)", c.fixed);
}

nlohmann::ordered_json rule_json(const RuleFigures& f) {
  return nlohmann::ordered_json{{"same_place", f.same},
                                {"top1", f.summary.top1},
                                {"recall_at_100_precision", f.summary.recall_at_100_precision},
                                {"auc_pr", f.summary.auc_pr}};
}

// The member "reference" of the eval JSON (--reference).
nlohmann::ordered_json reference_json(const ReferenceComparison& c) {
  nlohmann::ordered_json reference{
      {"engine", "double precision"},
      {"same_place", c.online.same},
      {"compared", c.compared},
      {"max_confidence_difference", c.worst},
      {"top1", c.online.summary.top1},
      {"recall_at_100_precision", c.online.summary.recall_at_100_precision},
      {"auc_pr", c.online.summary.auc_pr},
      {"batch", rule_json(c.batch)},
      {"fixed_offset", rule_json(c.fixed)}};
  return nlohmann::ordered_json{{"reference", std::move(reference)}};
}

}  // namespace

namespace {

int run_command(RunOptions& o) {
  if (const int rc = prepare_search(o.search, o.eval); rc != kExitOk) return rc;
  if (const int rc = refuse_inputs_as_outputs(eval_inputs(o.eval, ""), {o.csv, o.json});
      rc != kExitOk)
    return rc;
  Loaded in;
  if (const int rc = load_inputs(o.eval, &in); rc != kExitOk) return rc;
  if (o.search.route) {
    tools::EvalConfig config = o.eval.config;
    if (const int rc = resolve_route_start(o.search, in.library, &config.localiser); rc != kExitOk)
      return rc;
    auto e = evaluate_route(in.library, in.query, config, nullptr);
    if (!e) return fail(e.error());
    e.value().result.timing.load_ms = in.load_ms;
    if (!o.json.empty()) {
      const std::string json = tools::eval_json(e.value().result, in.library, in.query,
                                                route_json(e.value(), in.library, in.query));
      if (const int rc = write_text(o.json, json); rc != 0) return rc;
    }
    if (!o.csv.empty() || o.json.empty()) {
      return write_text(o.csv.empty() ? "-" : o.csv, route_csv(e.value(), in.library, in.query));
    }
    return kExitOk;
  }
  Progress progress(in.query.images.size(), isatty(fileno(stderr)) != 0);
  auto r = tools::evaluate(in.library, in.query, o.eval.config, nullptr,
                           [&](uint32_t done, uint32_t) { progress.update(done); });
  if (!r) return fail(r.error());
  r.value().timing.load_ms = in.load_ms;
  if (!o.json.empty()) {
    if (const int rc = write_text(o.json, tools::eval_json(r.value(), in.library, in.query));
        rc != 0)
      return rc;
  }
  if (!o.csv.empty() || o.json.empty()) {
    return write_text(o.csv.empty() ? "-" : o.csv, results_csv(r.value(), in.library, in.query));
  }
  return kExitOk;
}

// What eval prints: the inputs and settings, the scores, the route search's counts, the time.
void print_eval_text(const Loaded& in, const tools::EvalConfig& config,
                     const tools::EvalResult& result, const RouteEvaluation* route,
                     std::FILE* text) {
  std::fprintf(
      text,
      "library %s: %zu images; query %s: %zu images; %ux%u %s, S=%u, W=%u, R=%u, %s matcher "
      "(fixed-point core)\n",
      in.library.source.c_str(), in.library.images.size(), in.query.source.c_str(),
      in.query.images.size(), config.localiser.image_size.width, config.localiser.image_size.height,
      preprocessing_name(config.localiser.preprocess.method), config.localiser.sequence.seq_len,
      config.localiser.sequence.window, config.localiser.sequence.exclusion,
      tools::matcher_name(config.localiser.matcher));
  if (route != nullptr) {
    std::fprintf(text, "%s\n", route_settings_text(config.localiser.route, in.library).c_str());
  }
  print_summary(result, tools::to_double(config.localiser.sequence.threshold), text);
  if (route != nullptr) std::fprintf(text, "%s\n", route_counts_text(*route).c_str());
  std::fprintf(text,
               "time: load %.0f ms, preprocess %.0f ms, differences %.0f ms%s, match %.0f ms, "
               "total %.0f ms\n",
               result.timing.load_ms, result.timing.preprocess_ms, result.timing.differences_ms,
               result.timing.matrix_from_cache ? " (cached)" : "", result.timing.match_ms,
               result.timing.total_ms);
}

int eval_command(EvalCommandOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  if (const int rc = prepare_search(o.search, o.eval); rc != kExitOk) return rc;
  const bool route = o.search.route;
  if (route && !o.report.empty()) {
    return usage_error(
        "--search route: --report shows the full search's matrices; use --search full");
  }
  if (route && o.reference) {
    return usage_error(
        "--search route: --reference compares the full search with the double-precision "
        "pipeline; use --search full");
  }
  if (const int rc =
          refuse_inputs_as_outputs(eval_inputs(o.eval, o.ground_truth), {o.json, o.report});
      rc != kExitOk)
    return rc;
  Loaded in;
  if (const int rc = load_inputs(o.eval, &in); rc != kExitOk) return rc;
  const auto truth = tools::resolve_ground_truth(o.ground_truth, in.library, in.query);
  if (!truth) return fail(truth.error());
  tools::EvalConfig config = o.eval.config;
  config.keep_matrices = !o.report.empty();
  if (route) {
    if (const int rc = resolve_route_start(o.search, in.library, &config.localiser); rc != kExitOk)
      return rc;
  }
  RouteEvaluation route_eval;
  tools::Outcome<tools::EvalResult> r = tools::EvalResult{};
  if (route) {
    auto e = evaluate_route(in.library, in.query, config, &truth.value());
    if (!e) return fail(e.error());
    route_eval = std::move(e).value();
    r = route_eval.result;
  } else {
    Progress progress(in.query.images.size(), !o.quiet && isatty(fileno(stderr)) != 0);
    r = tools::evaluate(in.library, in.query, config, &truth.value(),
                        [&](uint32_t done, uint32_t) { progress.update(done); });
  }
  if (!r) return fail(r.error());
  tools::EvalResult& result = r.value();
  result.timing.load_ms = in.load_ms;
  result.timing.total_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  // The text goes to stderr when the JSON goes to stdout, so stdout stays valid JSON.
  std::FILE* text = o.json == "-" ? stderr : stdout;
  if (!o.quiet) print_eval_text(in, config, result, route ? &route_eval : nullptr, text);
  nlohmann::ordered_json extra = nlohmann::ordered_json::object();
  if (route) extra = route_json(route_eval, in.library, in.query);
  if (o.reference) {
    const ReferenceComparison ref =
        compare_with_reference(result, in.library, in.query, GroundTruthRef{&truth.value()});
    if (!o.quiet) print_reference(ref, text);
    extra = reference_json(ref);
  }
  if (!o.json.empty()) {
    const int rc = write_text(o.json, tools::eval_json(result, in.library, in.query, extra));
    if (rc != kExitOk) return rc;
  }
  if (!o.report.empty()) {
    const int rc = write_report(o.report, result, in.library, in.query, truth.value());
    if (rc != kExitOk) return rc;
    if (!o.quiet) std::fprintf(text, "report: %s\n", o.report.c_str());
  }
  return kExitOk;
}

}  // namespace

void add_eval_commands(CLI::App& app, Command* chosen) {
  auto run_o = std::make_shared<RunOptions>();
  CLI::App* run = app.add_subcommand(
      "run", "Localise a query sequence against a library: per-query results (CSV or JSON)");
  add_eval_options(run, &run_o->eval);
  add_search_options(run, &run_o->search, &run_o->eval);
  run->add_option("--csv", run_o->csv,
                  "Write the results as CSV to this file (- = stdout; the default)");
  run->add_option("--json", run_o->json, "Write the results as JSON to this file (- = stdout)");
  run->callback([run_o, chosen] { *chosen = [run_o]() -> int { return run_command(*run_o); }; });

  auto ev_o = std::make_shared<EvalCommandOptions>();
  CLI::App* ev = app.add_subcommand(
      "eval", "Localise and score against a ground truth: precision/recall, JSON, HTML report");
  add_eval_options(ev, &ev_o->eval);
  add_search_options(ev, &ev_o->search, &ev_o->eval);
  ev->add_option("--ground-truth", ev_o->ground_truth,
                 "identity:TOL (query i matches library i+-TOL), poses:METRES (true poses of "
                 "simulated recordings within METRES), or a CSV file "
                 "query_index,matching_reference_indices (source indices)")
      ->required();
  ev->add_option("--json", ev_o->json, "Write summary and per-query matches as JSON (- = stdout)");
  ev->add_option("--report", ev_o->report, "Write the HTML report of this evaluation");
  ev->add_flag("--reference", ev_o->reference,
               "Also run the double-precision reference pipeline and compare (slow), and rank its "
               "answers under the online, batch and fixed confidence offsets "
               "(docs/normalisation.md); printed, and in the JSON as \"reference\"");
  ev->add_flag("--quiet", ev_o->quiet, "Print nothing but errors");
  ev->callback([ev_o, chosen] { *chosen = [ev_o]() -> int { return eval_command(*ev_o); }; });
}

}  // namespace seqslam::cli
