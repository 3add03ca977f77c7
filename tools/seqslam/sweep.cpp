// seqslam sweep: a parameter grid over one or many library/query pairs. One CSV row per
// (pair, parameter combination), appended as each finishes, so an interrupted sweep resumes
// where it stopped; a progress bar on a terminal. docs/seqslam_eval.md.
//
// Work order: the pairs and image sizes are loaded once each; the difference matrix depends
// on (pair, size, preprocessing, max shift) only, so it is computed once per such group
// (with all threads) and the group's matcher settings (S, W, R, threshold) then run in
// parallel over it.
#include <unistd.h>
#include <CLI/CLI.hpp>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "cli_common.h"
#include "eval_common.h"
#include "progress.h"
#include "seqslam/preprocess.h"
#include "seqslam_tools/cli_numbers.h"
#include "seqslam_tools/evaluation.h"
#include "seqslam_tools/input_file.h"
#include "seqslam_tools/parallel.h"
#include "seqslam_tools/q_format.h"
#include "seqslam_tools/settings_cli.h"
#include "seqslam_tools/tune.h"

namespace seqslam::cli {

namespace {

namespace fs = std::filesystem;

// A setting's default value as the options write it.
std::string default_text(const char* name) {
  return setting_value_text(eval_defaults(), name);
}

struct SweepOptions {
  std::vector<std::string> pairs;  // LIB,QUERY,GROUND_TRUTH
  std::vector<std::string> pairs_files;  // seqslam-sim's pairs.csv files
  // The swept settings (the settings table's names and parsing), each a list of values; the
  // defaults are the evaluation's (eval_defaults()).
  std::vector<std::string> sizes;  // none given: each pair's recorded size, else the default's
  std::vector<std::string> preprocess = {default_text("preprocess")};
  std::vector<std::string> seq_len = {default_text("seq-len")};
  std::vector<std::string> window = {default_text("window")};
  std::vector<std::string> exclusion = {default_text("exclusion")};
  std::vector<std::string> threshold = {default_text("threshold")};
  std::vector<std::string> max_shift = {default_text("max-shift")};
  std::vector<std::string> matcher = {default_text("matcher")};
  std::vector<std::string> metric = {"mad"};
  std::string out;
  unsigned threads = 0;
  std::string cache;
  uint32_t max_memory_mib = static_cast<uint32_t>(tools::EvalConfig{}.max_memory >> 20);
  bool quiet = false;
};

const char* const kHeader = tools::kSweepHeader;
constexpr int kKeyColumns = 12;  // the columns that identify a row

std::string csv_field(const std::string& s) {
  if (s.find_first_of(",\"\n") == std::string::npos) return s;
  std::string o = "\"";
  for (const char c : s) {
    if (c == '"') o += '"';
    o += c;
  }
  return o + "\"";
}

// The first kKeyColumns fields of a CSV line, joined back (quotes kept), as the row's key.
std::string key_of_line(const std::string& line) {
  int fields = 0;
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    if (line[i] == '"') quoted = !quoted;
    if (line[i] == ',' && !quoted && ++fields == kKeyColumns) return line.substr(0, i);
  }
  return line;
}

struct Job {
  const PairSpec* pair;
  std::string size;
  std::string preprocess;
  std::string max_shift;
  std::string seq_len, window, exclusion;
  std::string threshold;
  std::string matcher;
  std::string metric;
  std::string key;
};

std::string key_of_job(const Job& j) {
  return csv_field(j.pair->library) + "," + csv_field(j.pair->query) + "," +
         csv_field(j.pair->truth) + "," + j.size + "," + j.preprocess + "," + j.seq_len + "," +
         j.window + "," + j.exclusion + "," + j.threshold + "," + j.max_shift + "," + j.matcher +
         "," + j.metric;
}

// A job's evaluation settings: its values over the evaluation's defaults. "" or what the core
// refuses.
std::string config_of(const Job& j, tools::EvalConfig* c) {
  storage::RunConfig run = eval_defaults();
  const std::pair<const char*, const std::string*> settings[] = {
      {"size", &j.size},           {"preprocess", &j.preprocess}, {"max-shift", &j.max_shift},
      {"seq-len", &j.seq_len},     {"window", &j.window},         {"exclusion", &j.exclusion},
      {"threshold", &j.threshold}, {"matcher", &j.matcher}};
  for (const auto& [name, text] : settings) {
    const std::string e = set_setting(&run, name, *text);  // validated by CLI11 already
    if (!e.empty()) return std::string("--") + name + " " + *text + ": " + e;
  }
  c->localiser = run.localiser();
  (void)tools::parse_metric(j.metric, &c->metric);
  const ConfigCheck check = check_localiser_config(c->localiser);
  return check.ok() ? "" : config_issue_text(check.issue);
}

std::string fmt(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", v);
  return buf;
}

// Writes the header to the results CSV, open for appending in place (a resumed sweep keeps
// every row written before it stopped; rows are flushed and checked as they are written),
// when the file is new. Returns "" or the message.
std::string start_output(const std::string& path, bool write_header, tools::OutputFile* out) {
  if (write_header) out->print("%s\n", kHeader);
  if (out->flush()) return {};
  // A cut header would make the next run refuse the file: leave it empty instead.
  std::error_code ec;
  if (write_header && fs::is_regular_file(path, ec)) fs::resize_file(path, 0, ec);
  return out->error() + " (the header)";
}

// Resume: the keys of the rows already in `path` (a regular file; a device or FIFO is not
// read: /dev/zero would never end). Every row is checked as tune checks it (check_sweep_row)
// and a key may appear once: a bad row is refused with its line number rather than kept and
// never run again. A last line cut short (an interrupted sweep) is dropped from the file.
// Returns "" or the message.
std::string read_done_rows(const std::string& path, std::set<std::string>* done,
                           bool* write_header) {
  std::string content;
  if (std::string e = tools::read_resume_file(path, &content); !e.empty()) return e;
  if (content.empty()) return {};
  if (content.rfind(std::string(kHeader) + "\n", 0) != 0) {
    return path +
           ":1: not a sweep results file of this version (the header differs); give another "
           "--out";
  }
  *write_header = false;
  size_t keep = content.size();
  if (content.back() != '\n') {
    keep = content.find_last_of('\n') + 1;
    warn(path + ": dropping an incomplete last line (the previous sweep was interrupted)");
    std::error_code ec;
    fs::resize_file(path, keep, ec);
    if (ec) return path + ": cannot truncate: " + ec.message();
  }
  std::map<std::string, size_t> lines;  // key -> line number
  std::vector<std::string> fields;
  size_t number = 1;
  size_t from = content.find('\n') + 1;
  while (from < keep) {
    const size_t nl = content.find('\n', from);
    const std::string line = content.substr(from, nl - from);
    from = nl + 1;
    ++number;
    const std::string where = path + ":" + std::to_string(number) + ": ";
    const std::string fix = "; remove the line (or give another --out) and run the sweep again";
    if (line.empty()) continue;
    if (!tools::split_sweep_line(line, &fields)) return where + "an unterminated quote" + fix;
    if (std::string why = tools::check_sweep_row(fields); !why.empty()) return where + why + fix;
    const auto [at, added] = lines.emplace(key_of_line(line), number);
    if (!added) {
      return where + "the same pair and setting as line " + std::to_string(at->second) +
             " (two sweeps into one file?)" + fix;
    }
    done->insert(at->first);
  }
  return {};
}

// The pairs of --pair and --pairs, or the exit status of the first bad one.
int collect_pairs(const SweepOptions& o, std::vector<PairSpec>* pairs) {
  for (const std::string& p : o.pairs) {
    std::stringstream ss(p);
    PairSpec spec;
    std::string extra;
    if (!std::getline(ss, spec.library, ',') || !std::getline(ss, spec.query, ',') ||
        !std::getline(ss, spec.truth, ',') || std::getline(ss, extra, ',')) {
      return usage_error("--pair '" + p + "': expected LIBRARY,QUERY,GROUND_TRUTH");
    }
    pairs->push_back(spec);
  }
  for (const std::string& file : o.pairs_files) {
    const std::string e = read_pairs_file(file, pairs);
    if (!e.empty()) return fail(e);
  }
  if (pairs->empty()) return usage_error("give at least one --pair or --pairs FILE");
  tools::InputFiles inputs = pair_inputs("", *pairs);
  for (const std::string& file : o.pairs_files)
    inputs.add(file);
  return refuse_inputs_as_outputs(inputs, {o.out});
}

// A pair's image size when --size is not given: its library's when that is a recording (the
// size it was made at), else the default.
std::vector<std::string> pair_sizes(const PairSpec& p) {
  storage::RunConfig run = eval_defaults();
  take_recorded_size(p.library, &run);
  return {setting_value_text(run, "size")};
}

// The grid: every combination of the pairs and the values, a repeated one once.
std::vector<Job> grid_jobs(const std::vector<PairSpec>& pairs, const SweepOptions& o) {
  std::vector<Job> jobs;
  std::set<std::string> keys;
  for (const PairSpec& p : pairs) {
    for (const std::string& size : o.sizes.empty() ? pair_sizes(p) : o.sizes) {
      for (const std::string& pre : o.preprocess) {
        for (const std::string& shift : o.max_shift) {
          for (const std::string& s : o.seq_len) {
            for (const std::string& w : o.window) {
              for (const std::string& r : o.exclusion) {
                for (const std::string& t : o.threshold) {
                  for (const std::string& m : o.matcher) {
                    for (const std::string& metric : o.metric) {
                      Job j{&p, size, pre, shift, s, w, r, t, m, metric, ""};
                      j.key = key_of_job(j);
                      if (keys.insert(j.key).second) jobs.push_back(j);
                    }
                  }
                }
              }
            }
          }
        }
      }
    }
  }
  return jobs;
}

// The results file as the jobs fill it: one row per evaluated job, whole rows only (nothing
// more after a failed write), from any thread.
class SweepRows {
 public:
  SweepRows(tools::OutputFile* out, size_t total, size_t already, size_t todo, bool bar)
      : out_(out), total_(total), already_(already), progress_(todo, bar) {}

  void emit(const Job& j, const tools::EvalConfig& c, const tools::EvalResult& r) {
    const tools::PrSummary& s = r.summary;
    const tools::PrPoint op = s.at_threshold(tools::to_double(c.localiser.sequence.threshold));
    const std::string row = j.key + "," + std::to_string(s.queries) + "," + fmt(s.top1) + "," +
                            fmt(s.recall_at_100_precision) + "," + fmt(s.auc_pr) + "," +
                            fmt(s.precision_at_recall(0.5)) + "," +
                            fmt(s.precision_at_recall(0.85)) + "," + fmt(s.max_recall) + "," +
                            std::to_string(op.accepted) + "," + fmt(op.precision) + "," +
                            fmt(op.recall) + "," + fmt(r.timing.match_ms) + "\n";
    {
      std::lock_guard<std::mutex> lock(mutex_);
      if (!out_->write(row) || !out_->flush()) return;
      ++written_;
    }
    progress_.step();
  }
  bool failed() const { return out_->failed(); }
  size_t rows() const { return already_ + written_; }
  std::string failure() const {
    return out_->error() + ": " + std::to_string(rows()) + " of " + std::to_string(total_) +
           " rows are in the file (" + std::to_string(written_) +
           " written now); run the sweep again to add the rest";
  }

 private:
  tools::OutputFile* out_;
  size_t total_, already_, written_ = 0;
  Progress progress_;
  std::mutex mutex_;
};

// The inputs of one pair at one image size, loaded once for the groups that share them.
struct PairInputs {
  std::string key;
  tools::InputSequence library, query;
  tools::GroundTruth truth;

  std::string load(const Job& first, const tools::EvalConfig& c) {
    const std::string k =
        first.pair->library + "|" + first.pair->query + "|" + first.pair->truth + "|" + first.size;
    if (k == key) return {};
    const auto w = c.localiser.image_size.width;
    const auto h = c.localiser.image_size.height;
    auto lib = tools::load_input(first.pair->library, w, h);
    if (!lib) return lib.error();
    auto qry = tools::load_input(first.pair->query, w, h);
    if (!qry) return qry.error();
    library = std::move(lib).value();
    query = std::move(qry).value();
    auto gt = tools::resolve_ground_truth(first.pair->truth, library, query);
    if (!gt) return gt.error();
    truth = std::move(gt).value();
    key = k;
    return {};
  }
};

// The jobs that share one difference matrix: the matrix once and the settings on it in
// parallel, or (a route too long for a whole matrix in --max-memory) each setting in bands,
// its differences computed again. Returns "" or the message.
std::string run_group(const std::vector<const Job*>& members, const tools::EvalConfig& base,
                      const PairInputs& in, SweepRows* rows) {
  const auto L = static_cast<uint32_t>(in.library.images.size());
  const auto Q = static_cast<uint32_t>(in.query.images.size());
  if (L != 0 && Q != 0 && tools::eval_memory(L, Q, base, Q).total() > base.max_memory) {
    for (const Job* j : members) {
      tools::EvalConfig c = base;
      c.cache_dir.clear();
      (void)config_of(*j, &c);
      const auto r = tools::evaluate(in.library, in.query, c, &in.truth);
      if (!r) return j->key + ": " + r.error();
      rows->emit(*j, c, r.value());
      if (rows->failed()) return rows->failure();
    }
    return {};
  }
  const auto matrix = tools::difference_matrix(in.library, in.query, base);
  if (!matrix) return matrix.error();
  std::vector<std::string> errors(members.size());
  tools::parallel_for(members.size(), base.threads, [&](size_t i) {
    const Job& j = *members[i];
    tools::EvalConfig c = base;
    (void)config_of(j, &c);
    const auto r = tools::evaluate_matrix(matrix.value(), c, &in.truth);
    if (!r) {
      errors[i] = j.key + ": " + r.error();
      return;
    }
    rows->emit(j, c, r.value());
  });
  if (rows->failed()) return rows->failure();
  for (const std::string& e : errors) {
    if (!e.empty()) return e;
  }
  return {};
}

int run_sweep(const SweepOptions& o) {
  std::vector<PairSpec> pairs;
  if (const int rc = collect_pairs(o, &pairs); rc != kExitOk) return rc;
  // The grid; every combination checked before anything runs.
  const std::vector<Job> jobs = grid_jobs(pairs, o);
  for (const Job& j : jobs) {
    tools::EvalConfig c;
    const std::string e = config_of(j, &c);
    if (!e.empty()) return usage_error("combination " + j.key + ": " + e);
  }

  // The output first: opening it takes its lock, so no other sweep appends to it while this
  // one reads what is there and adds the rest (two at once wrote duplicate rows).
  tools::OutputFile out;
  if (const std::string error = out.open(o.out, tools::OutputFile::Mode::kAppend); !error.empty()) {
    return fail(error);
  }
  std::set<std::string> done;
  bool write_header = true;
  if (const std::string error = read_done_rows(o.out, &done, &write_header); !error.empty()) {
    return fail(error);
  }
  std::vector<const Job*> todo;
  for (const Job& j : jobs) {
    if (done.count(j.key) == 0) todo.push_back(&j);
  }
  if (const std::string error = start_output(o.out, write_header, &out); !error.empty()) {
    return fail(error);
  }
  if (!o.quiet) {
    std::printf("sweep: %zu combinations x pairs, %zu already in %s, %zu to run\n", jobs.size(),
                jobs.size() - todo.size(), o.out.c_str(), todo.size());
    std::fflush(stdout);
  }
  SweepRows rows(&out, jobs.size(), jobs.size() - todo.size(), todo.size(),
                 !o.quiet && isatty(fileno(stderr)) != 0);

  // Groups sharing one difference matrix, in order.
  std::map<std::string, std::vector<const Job*>> groups;
  std::vector<std::string> group_order;
  for (const Job* j : todo) {
    const std::string g = j->pair->library + "|" + j->pair->query + "|" + j->pair->truth + "|" +
                          j->size + "|" + j->preprocess + "|" + j->max_shift + "|" + j->metric;
    if (groups.find(g) == groups.end()) group_order.push_back(g);
    groups[g].push_back(j);
  }
  PairInputs inputs;
  for (const std::string& g : group_order) {
    const std::vector<const Job*>& members = groups[g];
    tools::EvalConfig base;
    base.threads = o.threads != 0 ? o.threads : std::max(1u, std::thread::hardware_concurrency());
    base.cache_dir = o.cache;
    base.max_memory = uint64_t{o.max_memory_mib} << 20;
    (void)config_of(*members.front(), &base);
    if (const std::string e = inputs.load(*members.front(), base); !e.empty()) return fail(e);
    if (const std::string e = run_group(members, base, inputs, &rows); !e.empty()) return fail(e);
  }
  if (const std::string error = out.commit(); !error.empty()) {
    return fail(error + " (" + std::to_string(rows.rows()) + " of " + std::to_string(jobs.size()) +
                " rows)");
  }
  if (!o.quiet) std::printf("sweep: done, %zu rows in %s\n", rows.rows(), o.out.c_str());
  return kExitOk;
}

}  // namespace

void add_sweep_command(CLI::App& app, Command* chosen) {
  auto o = std::make_shared<SweepOptions>();
  CLI::App* c = app.add_subcommand(
      "sweep",
      "Evaluate a parameter grid over library/query pairs; rows appended to a CSV "
      "(an interrupted sweep resumes)");
  c->add_option("--pair", o->pairs, "LIBRARY,QUERY,GROUND_TRUTH (repeat for more pairs)");
  c->add_option("--pairs", o->pairs_files,
                "A pairs.csv as seqslam-sim writes it (library,query,ground_truth,description); "
                "repeat for more files");
  // The grid's settings: the settings table's names, help and ranges.
  for (const auto& [name, values] :
       {std::pair<const char*, std::vector<std::string>*>{"size", &o->sizes},
        {"preprocess", &o->preprocess},
        {"seq-len", &o->seq_len},
        {"window", &o->window},
        {"exclusion", &o->exclusion},
        {"threshold", &o->threshold},
        {"max-shift", &o->max_shift},
        {"matcher", &o->matcher}}) {
    CLI::Option* option = add_setting_list(c, name, values);
    if (values == &o->sizes)
      option->default_str("each pair's recorded size, else " + default_text("size"));
  }
  c->add_option("--metric", o->metric, "Image differences (mad, td)")
      ->delimiter(',')
      ->check(CLI::IsMember({"mad", "td", "td-noscale"}))
      ->capture_default_str();
  c->add_option("--out", o->out, "Results CSV (appended; rows already there are not re-run)")
      ->required();
  c->add_option("--threads", o->threads, "Threads (0 = all cores)")
      ->check(tools::whole_of<unsigned>())
      ->capture_default_str();
  c->add_option("--cache", o->cache, "Directory for cached difference matrices");
  c->add_option("--max-memory", o->max_memory_mib,
                "MiB a pair's evaluation may hold: above it (a long route) each setting is "
                "evaluated in bands of query rows instead of sharing one whole matrix")
      ->check(tools::whole<uint32_t>(1, 1u << 24))
      ->capture_default_str();
  c->add_flag("--quiet", o->quiet, "No progress or summary (errors only)");
  c->callback([o, chosen] { *chosen = [o] { return run_sweep(*o); }; });
}

}  // namespace seqslam::cli
