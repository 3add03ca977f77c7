// seqslam transforms: the perspective experiment of the 2015 thesis [A 4.3.1] on a
// seqslam-sim perspective set (docs/perspective.md).
//
// Every pair of the set is the library against the same route seen through one
// transformation (head roll, horizontal or vertical shift, zoom). For each pair, metric (MAD,
// TD) and matcher (diagonal, heuristic) the query sequences are scored the thesis's way:
// sequences of S places, forced answers (the heuristic with no candidate threshold and a
// fresh run per sequence start), precision = correct / all, MAE in places. The tables give,
// per precision level, the interval of strengths around the identity over which it holds
// ([A Table 5.9]). Rows are appended to a CSV as pairs finish; a re-run skips them, so an
// interrupted run resumes and a finished one only re-prints its tables.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "cli_common.h"
#include "eval_common.h"
#include "seqslam/preprocess.h"
#include "seqslam_tools/cli_numbers.h"
#include "seqslam_tools/evaluation.h"
#include "seqslam_tools/input_file.h"
#include "seqslam_tools/settings_cli.h"
#include "seqslam_tools/transform_series.h"
#include "seqslam_tools/tune.h"

namespace seqslam::cli {

namespace {

// The experiment's defaults: the evaluation's, with the 2015 thesis's HE and S = 10 and
// OpenSeqSLAM's Rwindow = 10 (the thesis's experiment, docs/perspective.md).
storage::RunConfig transforms_defaults() {
  storage::RunConfig c = eval_defaults();
  c.preprocess.method = Preprocessing::kHistEq;
  c.sequence.seq_len = 10;
  c.sequence.window = 10;
  return c;
}

struct TransformsOptions {
  std::string pairs_file;
  // The image, S, R and the heuristic's k and guard: the settings table's options.
  SettingOptions<> settings;
  std::vector<std::string> windows = {"10"};  // diagonal: the first is "Diagonal", others by W
  std::vector<std::string> matchers = {"diagonal", "heuristic"};
  std::vector<std::string> metrics = {"mad", "td"};
  std::string out;
  std::string table;
  unsigned threads = 0;
  bool quiet = false;
};

const char* kHeader = "kind,strength,matcher,metric,queries,correct,precision,mae,answered,near";
constexpr int kFields = 10;

struct Transform {
  double rotation = 0.0, shift_x = 0.0, shift_y = 0.0, scale = 1.0;
  bool identity() const {
    return rotation == 0.0 && shift_x == 0.0 && shift_y == 0.0 && scale == 1.0;
  }
};

// The transformation from seqslam-sim's file name: ..._rot+010.5_tx+000.0_ty+000.0_s1.000.dream
bool parse_transform(const std::string& path, Transform* t) {
  const std::string name = std::filesystem::path(path).filename().string();
  const size_t at = name.rfind("_rot");
  if (at == std::string::npos) return false;
  char tail[32] = {};
  const int n = std::sscanf(name.c_str() + at, "_rot%lf_tx%lf_ty%lf_s%lf%31s", &t->rotation,
                            &t->shift_x, &t->shift_y, &t->scale, tail);
  return n == 5 && std::string(tail) == ".dream" && t->scale > 0.0;
}

// The kinds a transformation belongs to (the identity to all) with its strength there.
std::vector<std::pair<std::string, double>> kinds_of(const Transform& t) {
  std::vector<std::pair<std::string, double>> k;
  if (t.identity()) return {{"rotation", 0.0}, {"shift_x", 0.0}, {"shift_y", 0.0}, {"scale", 1.0}};
  const int changed =
      (t.rotation != 0.0) + (t.shift_x != 0.0) + (t.shift_y != 0.0) + (t.scale != 1.0);
  if (changed != 1) return k;  // combined transformations are not a series
  if (t.rotation != 0.0) k.emplace_back("rotation", t.rotation);
  if (t.shift_x != 0.0) k.emplace_back("shift_x", t.shift_x);
  if (t.shift_y != 0.0) k.emplace_back("shift_y", t.shift_y);
  if (t.scale != 1.0) k.emplace_back("scale", t.scale);
  return k;
}

// "Diagonal-TD", "Heuristic-MAD"; an extra diagonal window W shows as "Diagonal/W0-MAD".
std::string method_name(const std::string& matcher, const std::string& metric) {
  std::string m = matcher;
  m[0] = static_cast<char>(m[0] - 'a' + 'A');
  const size_t w = m.find("_w");
  if (w != std::string::npos) m = m.substr(0, w) + "/W" + m.substr(w + 2);
  std::string d = metric;
  for (char& c : d)
    if (c >= 'a' && c <= 'z') c = static_cast<char>(c - 'a' + 'A');
  return m + "-" + d;
}

// The results so far: (kind, method) -> series.
using Series = std::map<std::pair<std::string, std::string>, std::vector<tools::SeriesPoint>>;

struct Row {
  std::string kind;
  double strength = 0.0;
  std::string matcher, metric;
  tools::ForcedScore score;
};

std::string row_key(const std::string& kind, double strength, const std::string& matcher,
                    const std::string& metric) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.4f", strength);
  return kind + "," + buf + "," + matcher + "," + metric;
}

// One row of an earlier run, read strictly (issue 34: a resume file is checked row by row,
// never trusted): "" and *r, or what is wrong with it.
std::string parse_row(const std::string& line, Row* r) {
  std::vector<std::string> f;
  if (!tools::split_sweep_line(line, &f) || f.size() != static_cast<size_t>(kFields)) {
    return "expected " + std::to_string(kFields) + " comma-separated fields";
  }
  for (const std::string& field : f) {
    if (tools::control_byte_at(field) >= 0) return "a control byte (a NUL: a damaged file)";
  }
  static const char* const kKinds[] = {"rotation", "shift_x", "shift_y", "scale"};
  if (std::find(std::begin(kKinds), std::end(kKinds), f[0]) == std::end(kKinds)) {
    return "kind '" + f[0] + "' is not rotation, shift_x, shift_y or scale";
  }
  r->kind = f[0];
  if (!tools::parse_finite_field(f[1], &r->strength))
    return "strength '" + f[1] + "' is not a number";
  if (f[2].empty() ||
      f[2].find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_") != std::string::npos) {
    return "matcher '" + f[2] + "' is not a matcher name";
  }
  r->matcher = f[2];
  tools::MetricKind metric = tools::MetricKind::kMad;
  if (!tools::parse_metric(f[3], &metric))
    return "metric '" + f[3] + "' is not mad, td or td-noscale";
  r->metric = f[3];
  uint64_t n[4] = {0, 0, 0, 0};  // queries, correct, answered, near
  const size_t at[4] = {4, 5, 8, 9};
  for (size_t k = 0; k < 4; ++k) {
    if (!tools::parse_whole_field(f[at[k]], 0, UINT32_MAX, &n[k])) {
      return "field " + std::to_string(at[k] + 1) + " '" + f[at[k]] + "' is not a whole number";
    }
  }
  double precision = 0;
  if (!tools::parse_finite_field(f[6], &precision) || precision < 0 || precision > 1) {
    return "precision '" + f[6] + "' is not a number within 0..1";
  }
  if (!tools::parse_finite_field(f[7], &r->score.mae) || r->score.mae < 0) {
    return "mae '" + f[7] + "' is not a number >= 0";
  }
  r->score.queries = static_cast<uint32_t>(n[0]);
  r->score.correct = static_cast<uint32_t>(n[1]);
  r->score.answered = static_cast<uint32_t>(n[2]);
  r->score.near = static_cast<uint32_t>(n[3]);
  if (r->score.correct > r->score.near || r->score.near > r->score.answered ||
      r->score.answered > r->score.queries) {
    return "inconsistent counts (correct <= near <= answered <= queries)";
  }
  return {};
}

// Opens --out to append to it in place, its lock held from here on (no other run appends
// meanwhile), and reads the rows an earlier run wrote: each checked, each (kind, strength,
// matcher, metric) once; a bad row refuses the run with its line; a last line cut short by an
// interruption is dropped from the file and run again. A new or empty file gets the header.
// Returns "" or the message.
std::string open_rows(const std::string& path, std::vector<Row>* rows, tools::OutputFile* out) {
  std::string error = out->open(path, tools::OutputFile::Mode::kAppend);
  if (!error.empty()) return error;
  std::string content;  // a device or FIFO is not read: nothing to resume
  error = tools::read_resume_file(path, &content);
  if (!error.empty()) return error;
  if (content.empty()) {
    out->print("%s\n", kHeader);
    return out->flush() ? std::string() : out->error() + " (the header)";
  }
  if (content.rfind(std::string(kHeader) + "\n", 0) != 0) {
    return path + ":1: not a seqslam transforms CSV (header differs)";
  }
  size_t keep = content.size();
  if (content.back() != '\n') {
    keep = content.find_last_of('\n') + 1;
    warn(path + ": dropping an incomplete last line");
    std::error_code ec;
    std::filesystem::resize_file(path, keep, ec);
    if (ec) return path + ": cannot truncate: " + ec.message();
  }
  std::map<std::string, int> lines;
  int number = 1;
  for (size_t from = content.find('\n') + 1; from < keep;) {
    const size_t nl = content.find('\n', from);
    const std::string line = content.substr(from, nl - from);
    from = nl + 1;
    ++number;
    const std::string where = path + ":" + std::to_string(number) + ": ";
    const std::string fix = "; remove the line (or give another --out) and run again";
    Row r;
    if (std::string why = parse_row(line, &r); !why.empty()) return where + why + fix;
    const auto [it, added] =
        lines.emplace(row_key(r.kind, r.strength, r.matcher, r.metric), number);
    if (!added) {
      return where + "the same row as line " + std::to_string(it->second) + fix;
    }
    rows->push_back(r);
  }
  return {};
}

// Writes and flushes one row; false when the write failed (out.error() says why).
bool write_row(tools::OutputFile& out, const std::string& key, const tools::ForcedScore& s) {
  return out.print("%s,%u,%u,%.6f,%.4f,%u,%u\n", key.c_str(), s.queries, s.correct, s.precision(),
                   s.mae, s.answered, s.near) &&
         out.flush();
}

std::string interval_text(const tools::PrecisionInterval& i) {
  if (!i.found) return "-";
  char buf[64];
  std::snprintf(buf, sizeof buf, "[%.1f, %.1f]", i.lo, i.hi);
  return buf;
}

// Markdown tables per kind: precision intervals, then precision / MAE at a few strengths.
std::string tables(const std::vector<Row>& rows, const std::vector<std::string>& methods,
                   const std::string& size) {
  Series series;
  std::set<std::string> kinds;
  for (const Row& r : rows) {
    series[{r.kind, method_name(r.matcher, r.metric)}].push_back({r.strength, r.score});
    kinds.insert(r.kind);
  }
  std::ostringstream o;
  const std::pair<const char*, const char*> units[] = {{"rotation", "degrees of head roll"},
                                                       {"shift_x", "pixels of horizontal shift"},
                                                       {"shift_y", "pixels of vertical shift"},
                                                       {"scale", "zoom factor"}};
  for (const auto& [kind, unit] : units) {
    if (kinds.count(kind) == 0) continue;
    // Only series with more than the identity are worth a table.
    size_t samples = 0;
    for (const std::string& m : methods)
      samples = std::max(samples, series[{kind, m}].size());
    if (samples < 2) continue;
    const double centre = std::string(kind) == "scale" ? 1.0 : 0.0;
    const auto interval_table = [&](const char* title, bool near) {
      o << "\n" << size << ", " << kind << " (" << unit << "), " << title << ":\n\n";
      o << "| precision |";
      for (const std::string& m : methods)
        o << " " << m << " |";
      o << "\n|---|";
      for (size_t i = 0; i < methods.size(); ++i)
        o << "---|";
      o << "\n";
      const std::pair<const char*, double> levels[] = {{"= 1.00", 1.0},
                                                       {">= 0.98", 0.98},
                                                       {">= 0.95", 0.95},
                                                       {">= 0.90", 0.90},
                                                       {">= 0.80", 0.80}};
      for (const auto& [label, level] : levels) {
        o << "| " << label << " |";
        for (const std::string& m : methods) {
          std::vector<tools::SeriesPoint> points = series[{kind, m}];
          if (near) {
            for (tools::SeriesPoint& p : points)
              p.score = p.score.near_as_correct();
          }
          o << " " << interval_text(tools::precision_interval(points, centre, level)) << " |";
        }
        o << "\n";
      }
    };
    interval_table("interval with the precision", false);
    interval_table("interval with the precision, answers within +-2 places counted correct", true);
    // Precision and MAE at the identity and at quarter, half and all of the largest strength.
    std::set<double> strengths;
    for (const std::string& m : methods)
      for (const tools::SeriesPoint& p : series[{kind, m}])
        strengths.insert(p.strength);
    const double lo = *strengths.begin() - centre;
    const double hi = *strengths.rbegin() - centre;
    std::set<double> picks;
    for (const double f : {1.0, 0.5, 0.25}) {
      for (const double want : {centre + f * lo, centre + f * hi}) {
        double best = *strengths.begin();
        for (const double s : strengths)
          if (std::fabs(s - want) < std::fabs(best - want)) best = s;
        picks.insert(best);
      }
    }
    picks.insert(centre);
    o << "\n" << size << ", " << kind << ": precision / MAE (places) at\n\n| " << kind << " |";
    for (const std::string& m : methods)
      o << " " << m << " |";
    o << "\n|---|";
    for (size_t i = 0; i < methods.size(); ++i)
      o << "---|";
    o << "\n";
    for (const double s : picks) {
      char buf[48];
      std::snprintf(buf, sizeof buf, "| %.2f |", s);
      o << buf;
      for (const std::string& m : methods) {
        const tools::SeriesPoint* found = nullptr;
        for (const tools::SeriesPoint& p : series[{kind, m}])
          if (p.strength == s) found = &p;
        if (found == nullptr) {
          o << " - |";
          continue;
        }
        std::snprintf(buf, sizeof buf, " %.3f / %.1f |", found->score.precision(),
                      found->score.mae);
        o << buf;
      }
      o << "\n";
    }
  }
  return o.str();
}

// The matcher runs: each matcher once, the diagonal once per window (extra windows named
// diagonal_wW).
struct MatcherRun {
  std::string name;
  std::string matcher;
  int window = 0;
};

// The evaluation settings and the matcher runs from the options; kExitOk or the usage error.
// The pairs' image size is the first library's when it is a recording and --size is not given.
int transforms_setup(const TransformsOptions& o, const std::vector<PairSpec>& pairs,
                     tools::EvalConfig* base, std::vector<MatcherRun>* runs) {
  storage::RunConfig run = transforms_defaults();
  if (!pairs.empty() && !o.settings.given("size")) take_recorded_size(pairs.front().library, &run);
  o.settings.apply(&run);
  base->localiser = run.localiser();
  LocaliserConfig& lc = base->localiser;
  const ConfigCheck check = check_localiser_config(lc);
  if (!check.ok()) return usage_error(config_issue_text(check.issue));
  base->threads = o.threads;
  // The heuristic as the thesis ran it here: no candidate threshold (every place may be a
  // candidate, so there is always an answer) and one fresh run per sequence start.
  lc.heuristic.threshold = UQ8_8::from_raw(0xFFFF);
  base->heuristic_every_start = true;
  const int first_window = std::stoi(o.windows.front());  // validated by CLI11
  for (const std::string& m : o.matchers) {
    if (m != "diagonal") {
      runs->push_back({m, m, first_window});
      continue;
    }
    for (size_t i = 0; i < o.windows.size(); ++i)
      runs->push_back({i == 0 ? m : m + "_w" + o.windows[i], m, std::stoi(o.windows[i])});
  }
  for (const MatcherRun& r : *runs) {
    LocaliserConfig probe = lc;
    probe.sequence.window = static_cast<uint16_t>(r.window);
    const ConfigCheck wc = check_localiser_config(probe);
    if (!wc.ok()) return usage_error(config_issue_text(wc.issue));
  }
  return kExitOk;
}

int run_transforms(const TransformsOptions& o) {
  std::vector<PairSpec> pairs;
  const std::string pe = read_pairs_file(o.pairs_file, &pairs);
  if (!pe.empty()) return fail(pe);
  if (const int rc = refuse_inputs_as_outputs(pair_inputs(o.pairs_file, pairs), {o.out, o.table});
      rc != kExitOk) {
    return rc;
  }
  tools::EvalConfig base;
  std::vector<MatcherRun> runs;
  if (const int rc = transforms_setup(o, pairs, &base, &runs); rc != kExitOk) return rc;
  const LocaliserConfig& lc = base.localiser;
  const uint16_t w = lc.image_size.width;
  const uint16_t h = lc.image_size.height;
  std::vector<std::string> methods;
  for (const MatcherRun& r : runs)
    for (const std::string& d : o.metrics)
      methods.push_back(method_name(r.name, d));

  struct Work {
    const PairSpec* pair;
    std::vector<std::pair<std::string, double>> kinds;
  };
  std::vector<Work> work;
  for (const PairSpec& p : pairs) {
    Transform t;
    if (!parse_transform(p.query, &t)) {
      return fail(p.query +
                  ": not a perspective recording (expected seqslam-sim's "
                  "..._rotR_txX_tyY_sS.dream name)");
    }
    auto k = kinds_of(t);
    if (!k.empty()) work.push_back({&p, k});
  }

  std::vector<Row> rows;
  std::set<std::string> done;
  tools::OutputFile out;
  if (!o.out.empty()) {
    const std::string e = open_rows(o.out, &rows, &out);
    if (!e.empty()) return fail(e);
    for (const Row& r : rows)
      done.insert(row_key(r.kind, r.strength, r.matcher, r.metric));
  }

  std::map<std::string, tools::InputSequence> libraries;
  size_t index = 0;
  for (const Work& wk : work) {
    ++index;
    bool needed = false;
    for (const auto& [kind, strength] : wk.kinds)
      for (const MatcherRun& m : runs)
        for (const std::string& d : o.metrics)
          needed = needed || done.count(row_key(kind, strength, m.name, d)) == 0;
    if (!needed) continue;
    const PairSpec& p = *wk.pair;
    if (libraries.count(p.library) == 0) {
      auto lib = tools::load_input(p.library, w, h);
      if (!lib) return fail(lib.error());
      libraries.emplace(p.library, std::move(lib).value());
    }
    const tools::InputSequence& library = libraries.at(p.library);
    auto query = tools::load_input(p.query, w, h);
    if (!query) return fail(query.error());
    auto truth = tools::resolve_ground_truth(p.truth, library, query.value());
    if (!truth) return fail(truth.error());
    for (const std::string& d : o.metrics) {
      tools::EvalConfig c = base;
      (void)tools::parse_metric(d, &c.metric);
      const auto matrix = tools::difference_matrix(library, query.value(), c);
      if (!matrix) return fail(matrix.error());
      for (const MatcherRun& run : runs) {
        const std::string& m = run.name;
        (void)tools::parse_matcher(run.matcher, &c.localiser.matcher);
        c.localiser.sequence.window = static_cast<uint16_t>(run.window);
        const auto r = tools::evaluate_matrix(matrix.value(), c, &truth.value());
        if (!r) return fail(r.error());
        const tools::ForcedScore score =
            tools::score_forced(r.value(), truth.value(), lc.sequence.seq_len);
        for (const auto& [kind, strength] : wk.kinds) {
          const std::string key = row_key(kind, strength, m, d);
          if (done.count(key) != 0) continue;
          done.insert(key);
          rows.push_back({kind, strength, m, d, score});
          if (out.is_open() && !write_row(out, key, score)) {
            return fail(out.error() + " (row " + key + "; " + std::to_string(rows.size() - 1) +
                        " rows in the file)");
          }
        }
        if (!o.quiet) {
          std::fprintf(stderr, "[%zu/%zu] %s %s: precision %.3f (%u/%u), MAE %.1f\n", index,
                       work.size(), std::filesystem::path(p.query).filename().c_str(),
                       method_name(m, d).c_str(), score.precision(), score.correct, score.queries,
                       score.mae);
        }
      }
    }
  }
  if (out.is_open()) {
    const std::string e = out.commit();
    if (!e.empty()) return fail(e);
  }

  const std::string text = tables(rows, methods, std::to_string(w) + "x" + std::to_string(h));
  std::fputs(text.c_str(), stdout);
  if (!o.table.empty()) {
    const std::string e = tools::write_output(o.table, text);
    if (!e.empty()) return fail(e);
  }
  return kExitOk;
}

}  // namespace

void add_transforms_command(CLI::App& app, Command* chosen) {
  auto o = std::make_shared<TransformsOptions>();
  CLI::App* c = app.add_subcommand(
      "transforms",
      "The 2015 thesis's perspective experiment on a seqslam-sim perspective set: precision "
      "and MAE per transformation strength, and the intervals that keep a precision");
  c->add_option("--pairs", o->pairs_file,
                "The set's pairs.csv (seqslam-sim generate "
                "--scenario perspective)")
      ->required();
  SettingOptions<>::Selection single;
  single.scopes = storage::kScopeImage | storage::kScopeSequence | storage::kScopeHeuristic;
  single.except = {"window", "threshold", "sigma-min", "candidate-threshold",
                   "heuristic-scan-places"};
  o->settings.add(c, transforms_defaults(), single);
  add_setting_list(c, "window", &o->windows);
  add_setting_list(c, "matcher", &o->matchers);
  c->add_option("--metric", o->metrics, "Image differences")
      ->delimiter(',')
      ->check(CLI::IsMember({"mad", "td", "td-noscale"}))
      ->capture_default_str();
  c->add_option("--out", o->out,
                "Rows CSV (kind,strength,matcher,metric,...); rows already there are not re-run");
  c->add_option("--table", o->table, "Also write the Markdown tables to this file");
  c->add_option("--threads", o->threads, "Threads (0 = all cores)")
      ->check(tools::whole_of<unsigned>())
      ->capture_default_str();
  c->add_flag("--quiet", o->quiet, "No per-pair progress on stderr");
  c->callback([o, chosen] { *chosen = [o] { return run_transforms(*o); }; });
}

}  // namespace seqslam::cli
