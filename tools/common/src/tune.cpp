#include "seqslam_tools/tune.h"

#include "seqslam/storage/run_config.h"
#include "seqslam_tools/settings_cli.h"

#include <algorithm>
#include <array>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

#include "file_util.h"
#include "seqslam/hal/pixel_buffer.h"
#include "seqslam/limits.h"
#include "seqslam/localiser.h"
#include "seqslam/preprocess.h"
#include "seqslam/storage/run_config.h"
#include "seqslam_tools/evaluation.h"
#include "seqslam_tools/input_file.h"
#include "seqslam_tools/settings_cli.h"
#include "seqslam_tools/wxh.h"

namespace seqslam::tools {

namespace {

constexpr size_t kColumns = 23;  // kSweepHeader's
constexpr size_t kPairColumns = 3;
constexpr size_t kSettingColumns = 9;
constexpr size_t kTop1 = 13;
constexpr size_t kRecall100 = 14;
constexpr size_t kAuc = 15;

// A figure of the sweep: a finite number in [0, 1].
bool parse_fraction(const std::string& s, double* out) {
  double v = 0;
  if (!parse_finite_field(s, &v) || v < 0.0 || v > 1.0) return false;
  *out = v;
  return true;
}

bool whole_in(const std::string& s, uint64_t lo, uint64_t hi, uint64_t* out) {
  return parse_whole_field(s, lo, hi, out);
}

// Columns of a row (kSweepHeader).
constexpr size_t kSettingFirst = 3;
constexpr size_t kQueries = 12;
constexpr size_t kAccepted = 19;
constexpr size_t kMatchMs = 22;

// The 9 setting columns from `f[first]` on, read as their options read them (the settings
// table, storage/run_config.h): "" or "COLUMN 'VALUE': why".
std::string check_setting(const std::vector<std::string>& f, size_t first) {
  static const char* const kNames[] = {"size",      "preprocess", "seq_len", "window", "exclusion",
                                       "threshold", "max_shift",  "matcher", "metric"};
  static const char* const kSettings[] = {"size",      "preprocess", "seq-len",   "window",
                                          "exclusion", "threshold",  "max-shift", "matcher"};
  const auto bad = [&](size_t k, const std::string& why) {
    return std::string(kNames[k]) + " '" + detail::printable(f[first + k]) + "': " + why;
  };
  storage::RunConfig run;
  for (size_t k = 0; k < 8; ++k) {
    // The table's message names the value: "seq_len: '0' is not within 1..100 places".
    const std::string e = cli::set_setting(&run, kSettings[k], f[first + k]);
    if (!e.empty()) return std::string(kNames[k]) + ": " + e;
  }
  MetricKind metric = MetricKind::kMad;
  if (!parse_metric(f[first + 8], &metric)) return bad(8, "not mad, td or td-noscale");
  const ConfigCheck check = check_localiser_config(run.localiser());
  if (!check.ok()) return std::string("the setting is invalid: ") + config_issue_text(check.issue);
  return {};
}

std::string join(const std::vector<std::string>& f, size_t first, size_t count) {
  std::string s;
  for (size_t i = first; i < first + count; ++i)
    s += (i > first ? "," : "") + f[i];
  return s;
}

struct Figures {
  double recall = 0.0;
  double auc = 0.0;
  double top1 = 0.0;
};

double measure_of(const Figures& f, TuneMeasure m) {
  return m == TuneMeasure::kAucPr ? f.auc : f.recall;
}

using PairFigures = std::map<std::string, Figures>;                   // pair -> figures
using Table = std::map<std::string, PairFigures>;                     // setting -> pair -> figures
using Scores = std::map<std::string, std::map<std::string, double>>;  // setting -> pair -> score

std::vector<std::string> setting_fields(const std::string& setting) {
  std::vector<std::string> f;
  (void)split_sweep_line(setting, &f);
  return f;
}

// The settings next to `setting` in S (column 2) and W (column 3): for each, the complete
// settings equal in every other column whose value is the next one swept below and above.
std::vector<std::string> neighbours(const std::string& setting,
                                    const std::vector<std::string>& settings) {
  const std::vector<std::string> me = setting_fields(setting);
  std::vector<std::string> out;
  for (const size_t column : {size_t{2}, size_t{3}}) {
    if (column >= me.size()) break;
    const long mine = std::atol(me[column].c_str());
    std::string below, above;
    long below_v = -1, above_v = -1;
    for (const std::string& other : settings) {
      const std::vector<std::string> f = setting_fields(other);
      bool same = f.size() == me.size();
      for (size_t k = 0; same && k < f.size(); ++k)
        same = k == column || f[k] == me[k];
      if (!same) continue;
      const long v = std::atol(f[column].c_str());
      if (v < mine && (below_v < 0 || v > below_v)) below_v = v, below = other;
      if (v > mine && (above_v < 0 || v < above_v)) above_v = v, above = other;
    }
    if (!below.empty()) out.push_back(below);
    if (!above.empty()) out.push_back(above);
  }
  return out;
}

// What the choice reads, derived once from the table for every complete setting and pair:
// the rule's score (its measure, or with smoothing the least over it and its neighbours), the
// other measure and top-1 for the tie-breaks, and each pair's dataset (one group unless the
// rule balances datasets).
struct Evidence {
  Scores score;
  Scores other;
  Scores top1;
  std::map<std::string, std::string> dataset;  // pair -> dataset_of(pair), or ""
};

Evidence evidence_of(const Table& table, const std::vector<std::string>& settings,
                     const TuneRule& rule) {
  const TuneMeasure other =
      rule.measure == TuneMeasure::kAucPr ? TuneMeasure::kRecallAt100 : TuneMeasure::kAucPr;
  Evidence e;
  for (const std::string& s : settings) {
    const std::vector<std::string> near =
        rule.smooth ? neighbours(s, settings) : std::vector<std::string>{};
    for (const auto& [pair, f] : table.at(s)) {
      double v = measure_of(f, rule.measure);
      for (const std::string& n : near)
        v = std::min(v, measure_of(table.at(n).at(pair), rule.measure));
      e.score[s][pair] = v;
      e.other[s][pair] = measure_of(f, other);
      e.top1[s][pair] = f.top1;
      if (e.dataset.count(pair) == 0)
        e.dataset[pair] = rule.balance_datasets ? dataset_of(pair) : std::string();
    }
  }
  return e;
}

// The mean of a setting's values over the pairs except `skip` (nullptr: all), each dataset
// weighing the same (`dataset`: every pair's).
double mean_score(const std::map<std::string, double>& by_pair, const std::string* skip,
                  const std::map<std::string, std::string>& dataset) {
  std::map<std::string, std::pair<double, size_t>> groups;  // dataset -> (sum, count)
  for (const auto& [pair, v] : by_pair) {
    if (skip != nullptr && pair == *skip) continue;
    auto& g = groups[dataset.at(pair)];
    g.first += v;
    ++g.second;
  }
  double sum = 0.0;
  for (const auto& [name, g] : groups)
    sum += g.first / static_cast<double>(g.second);
  return groups.empty() ? 0.0 : sum / static_cast<double>(groups.size());
}

// The worst over the pairs except `skip` of a setting's score less the default's figure on the
// pair (`base`; empty: 0).
double worst_gain(const std::map<std::string, double>& by_pair, const PairFigures* base,
                  const std::string* skip, TuneMeasure m) {
  double worst = 0.0;
  bool any = false;
  for (const auto& [pair, v] : by_pair) {
    if (skip != nullptr && pair == *skip) continue;
    const double gain = v - (base != nullptr ? measure_of(base->at(pair), m) : 0.0);
    worst = any ? std::min(worst, gain) : gain;
    any = true;
  }
  return worst;
}

// The best setting by the rule over the pairs except `skip`: its objective, then the mean of
// its scores, the other measure's mean, top-1's mean, then the setting's text (settings are
// sorted: equal figures keep the first). `base`: the default's figures, or nullptr.
std::string best_setting(const Evidence& e, const std::vector<std::string>& settings,
                         const PairFigures* base, const std::string* skip, const TuneRule& rule) {
  std::string best;
  std::array<double, 4> best_key{};
  for (const std::string& s : settings) {
    const double mean = mean_score(e.score.at(s), skip, e.dataset);
    const std::array<double, 4> key{rule.objective == TuneObjective::kWorstGain
                                        ? worst_gain(e.score.at(s), base, skip, rule.measure)
                                        : mean,
                                    mean, mean_score(e.other.at(s), skip, e.dataset),
                                    mean_score(e.top1.at(s), skip, e.dataset)};
    if (best.empty() || key > best_key) {
      best = s;
      best_key = key;
    }
  }
  return best;
}

// "directory/library -> query" by their file names (the table's pair column; the full paths
// are in the sweep's rows).
std::string pair_label(const std::string& pair) {
  std::vector<std::string> f;
  if (!split_sweep_line(pair, &f) || f.size() != kPairColumns) return pair;
  const auto name = [](const std::string& path) {
    std::string p = path;
    while (p.size() > 1 && p.back() == '/')
      p.pop_back();
    const size_t slash = p.find_last_of('/');
    std::string n = slash == std::string::npos ? p : p.substr(slash + 1);
    const size_t dot = n.find_last_of('.');
    return dot == std::string::npos || dot == 0 ? n : n.substr(0, dot);
  };
  // The library's directory too: the simulator's sets of several seeds have the same names.
  std::string lib = f[0];
  while (lib.size() > 1 && lib.back() == '/')
    lib.pop_back();
  const size_t slash = lib.find_last_of('/');
  const std::string dir = slash == std::string::npos ? std::string() : name(lib.substr(0, slash));
  return (dir.empty() ? std::string() : dir + "/") + name(f[0]) + " -> " + name(f[1]);
}

std::string percent(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", 100.0 * v);
  return b;
}

}  // namespace

bool split_sweep_line(const std::string& line, std::vector<std::string>* fields) {
  fields->clear();
  std::string f;
  bool quoted = false;
  for (size_t i = 0; i < line.size(); ++i) {
    const char c = line[i];
    if (quoted) {
      if (c == '"' && i + 1 < line.size() && line[i + 1] == '"') {
        f += '"';
        ++i;
      } else if (c == '"') {
        quoted = false;
      } else {
        f += c;
      }
    } else if (c == '"') {
      quoted = true;
    } else if (c == ',') {
      fields->push_back(f);
      f.clear();
    } else {
      f += c;
    }
  }
  fields->push_back(f);
  return !quoted;
}

std::string check_sweep_row(const std::vector<std::string>& f) {
  if (f.size() != kColumns) {
    return "expected " + std::to_string(kColumns) + " comma-separated fields, found " +
           std::to_string(f.size()) + " (a line cut short or run together with another?)";
  }
  for (size_t k = 0; k < f.size(); ++k) {
    if (control_byte_at(f[k]) >= 0) {
      return "field " + std::to_string(k + 1) + " '" + detail::printable(f[k]) +
             "' holds a control byte: a damaged file";
    }
  }
  for (size_t k = 0; k < kPairColumns; ++k) {
    if (f[k].empty()) return "field " + std::to_string(k + 1) + " (a path) is empty";
  }
  if (std::string why = check_setting(f, kSettingFirst); !why.empty()) return why;
  uint64_t queries = 0;
  if (!whole_in(f[kQueries], 0, UINT32_MAX, &queries)) {
    return "queries '" + detail::printable(f[kQueries]) + "' is not a whole number";
  }
  static const char* const kFigureNames[] = {"top1",
                                             "recall_at_100_precision",
                                             "auc_pr",
                                             "precision_at_recall_0.5",
                                             "precision_at_recall_0.85",
                                             "max_recall",
                                             "accepted",
                                             "precision",
                                             "recall"};
  for (size_t k = kQueries + 1; k < kMatchMs; ++k) {
    const std::string name = kFigureNames[k - kQueries - 1];
    const std::string value = " '" + detail::printable(f[k]) + "'";
    uint64_t accepted = 0;
    double v = 0;
    if (k == kAccepted && !whole_in(f[k], 0, queries, &accepted)) {
      return name + value + " is not a whole number within 0.." + std::to_string(queries) +
             " (the queries)";
    }
    if (k != kAccepted && !parse_fraction(f[k], &v)) {
      return name + value + " is not a number within 0..1";
    }
  }
  double ms = 0;
  if (!parse_finite_field(f[kMatchMs], &ms) || ms < 0) {
    return "match_ms '" + detail::printable(f[kMatchMs]) + "' is not a finite number >= 0";
  }
  return {};
}

std::string check_sweep_setting(const std::string& setting) {
  std::vector<std::string> f;
  if (!split_sweep_line(setting, &f) || f.size() != kSettingColumns) {
    return "'" + detail::printable(setting) + "' is not " + std::to_string(kSettingColumns) +
           " comma-separated values size,preprocess,seq_len,window,exclusion,threshold," +
           "max_shift,matcher,metric";
  }
  return check_setting(f, 0);
}

Outcome<std::vector<TuneRow>> read_sweep_rows(const std::string& path) {
  // A regular file only: /dev/zero has no line end, and reading it grew without bound.
  if (std::string why = check_regular_input(path); !why.empty()) return Error{why};
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error{path + ": cannot open"};
  std::string line;
  if (!std::getline(in, line)) return Error{path + ": empty (expected a sweep results file)"};
  if (line != kSweepHeader)
    return Error{path + ":1: not a sweep results file of this version (the header differs)"};
  std::vector<TuneRow> rows;
  std::vector<std::string> f;
  for (size_t n = 2; std::getline(in, line); ++n) {
    const std::string where = path + ":" + std::to_string(n) + ": ";
    if (line.empty()) continue;
    if (!split_sweep_line(line, &f)) return Error{where + "an unterminated quote"};
    if (std::string why = check_sweep_row(f); !why.empty()) {
      return Error{where + why + " (re-run the sweep to write the row again)"};
    }
    TuneRow r;
    r.pair = join(f, 0, kPairColumns);
    r.setting = join(f, kPairColumns, kSettingColumns);
    (void)parse_fraction(f[kTop1], &r.top1);  // checked above
    (void)parse_fraction(f[kRecall100], &r.recall_at_100_precision);
    (void)parse_fraction(f[kAuc], &r.auc_pr);
    rows.push_back(std::move(r));
  }
  if (in.bad()) return Error{path + ": read error"};
  return rows;
}

std::string dataset_of(const std::string& pair) {
  std::vector<std::string> f;
  std::string library = pair;
  if (split_sweep_line(pair, &f) && f.size() == kPairColumns) library = f[0];
  while (library.size() > 1 && library.back() == '/')
    library.pop_back();
  // The directory the library is in: a recording's, or the traversal directory's parent.
  const size_t slash = library.find_last_of('/');
  const std::string dir = slash == std::string::npos ? std::string(".") : library.substr(0, slash);
  const size_t up = dir.find_last_of('/');
  std::string name = up == std::string::npos ? dir : dir.substr(up + 1);
  const size_t seed = name.rfind("-s");
  if (seed != std::string::npos && seed + 2 < name.size() &&
      name.find_first_not_of("0123456789", seed + 2) == std::string::npos) {
    name.resize(seed);
  }
  return name;
}

Outcome<TuneReport> tune(const std::vector<TuneRow>& rows, const std::string& default_setting,
                         const TuneRule& rule) {
  TuneReport rep;
  rep.rule = rule;
  Table table;
  std::set<std::string> seen_pairs;
  for (const TuneRow& r : rows) {
    if (seen_pairs.insert(r.pair).second) rep.pairs.push_back(r.pair);
    const Figures f{r.recall_at_100_precision, r.auc_pr, r.top1};
    auto& by_pair = table[r.setting];
    const auto it = by_pair.find(r.pair);
    if (it != by_pair.end()) {
      const Figures& g = it->second;
      if (g.recall != f.recall || g.auc != f.auc || g.top1 != f.top1)
        return Error{"pair " + r.pair + ", setting " + r.setting +
                     ": two rows with different figures (results of different versions?)"};
      continue;
    }
    by_pair.emplace(r.pair, f);
  }
  if (rep.pairs.size() < 2)
    return Error{"tune needs at least two pairs (one is held out in turn); the results have " +
                 std::to_string(rep.pairs.size())};
  for (const auto& [setting, by_pair] : table) {
    if (by_pair.size() == rep.pairs.size()) {
      rep.settings.push_back(setting);
    } else {
      ++rep.incomplete_settings;
    }
  }
  if (rep.settings.empty())
    return Error{"no setting was swept on every pair (complete the sweep first)"};
  const Evidence evidence = evidence_of(table, rep.settings, rule);
  std::map<std::string, size_t> chosen_count;
  const auto def = table.find(default_setting);
  // The default's figures on every pair, or none (incomplete: not a baseline).
  const PairFigures* base =
      def != table.end() && def->second.size() == rep.pairs.size() ? &def->second : nullptr;
  for (const std::string& pair : rep.pairs) {
    TuneFold fold;
    fold.held_out = pair;
    fold.dataset = dataset_of(pair);
    fold.chosen = best_setting(evidence, rep.settings, base, &pair, rule);
    const Figures& c = table.at(fold.chosen).at(pair);
    fold.chosen_measure = measure_of(c, rule.measure);
    fold.chosen_recall = c.recall;
    fold.chosen_auc = c.auc;
    if (def != table.end() && def->second.count(pair) != 0) {
      const Figures& d = def->second.at(pair);
      fold.has_default = true;
      fold.default_measure = measure_of(d, rule.measure);
      fold.default_recall = d.recall;
      fold.default_auc = d.auc;
    }
    ++chosen_count[fold.chosen];
    rep.folds.push_back(fold);
  }
  rep.overall = best_setting(evidence, rep.settings, base, nullptr, rule);
  rep.overall_folds = chosen_count.count(rep.overall) != 0 ? chosen_count[rep.overall] : 0;
  rep.distinct_choices = chosen_count.size();
  return rep;
}

namespace {

std::string points(double diff) {
  char d[32];
  std::snprintf(d, sizeof d, "%+.1f", 100.0 * diff);
  return d;
}

std::string rule_text(const TuneRule& rule) {
  std::string t = rule.measure == TuneMeasure::kAucPr ? "area under the PR curve (AUC)"
                                                      : "recall at 100 % precision";
  if (rule.smooth) t += ", each setting's the least over it and its S and W neighbours";
  const std::string mean = rule.balance_datasets
                               ? "the mean over the other pairs with each dataset weighing the same"
                               : "the mean over the other pairs";
  if (rule.objective == TuneObjective::kWorstGain) {
    t += ": the best worst gain over the default on any of the other pairs, ties to " + mean;
  } else {
    t += ": " + mean;
  }
  return t;
}

}  // namespace

std::string tune_markdown(const TuneReport& r, const std::string& default_setting) {
  std::ostringstream o;
  const char* m = r.rule.measure == TuneMeasure::kAucPr ? "AUC" : "recall at 100 % P";
  o << "Settings: size,preprocess,seq_len,window,exclusion,threshold,max_shift,matcher,metric. "
    << r.settings.size() << " settings swept on all " << r.pairs.size() << " pairs";
  if (r.incomplete_settings > 0) o << " (" << r.incomplete_settings << " incomplete, left out)";
  o << "; default " << default_setting << ".\n\n";
  o << "Each pair held out in turn; the setting is chosen on the other pairs by "
    << rule_text(r.rule) << ", and scored on the held-out pair only (figures in %).\n\n";
  o << "| held-out pair | dataset | chosen on the others | " << m << " | recall at 100 % P | "
    << "default: " << m << " | recall at 100 % P | chosen - default (" << m << ", points) |\n";
  o << "| --- | --- | --- | --- | --- | --- | --- | --- |\n";
  std::map<std::string, double> worst;  // dataset -> worst difference
  for (const TuneFold& f : r.folds) {
    o << "| " << pair_label(f.held_out) << " | " << f.dataset << " | " << f.chosen << " | "
      << percent(f.chosen_measure) << " | " << percent(f.chosen_recall) << " | ";
    if (f.has_default) {
      const double diff = f.chosen_measure - f.default_measure;
      o << percent(f.default_measure) << " | " << percent(f.default_recall) << " | " << points(diff)
        << " |\n";
      const auto it = worst.find(f.dataset);
      if (it == worst.end() || diff < it->second) worst[f.dataset] = diff;
    } else {
      o << "not swept | - | - |\n";
    }
  }
  o << "\nStability: " << r.distinct_choices << " distinct setting(s) chosen over "
    << r.folds.size() << " folds; the best over all pairs, " << r.overall << ", was chosen in "
    << r.overall_folds << " of " << r.folds.size() << ".\n";
  if (worst.empty()) {
    o << "The default setting was not swept: no comparison.\n";
    return o.str();
  }
  bool first = true;
  std::string losing;
  o << "Worst held-out difference against the default (" << m << ", points):";
  for (const auto& [dataset, w] : worst) {
    o << (first ? " " : "; ") << dataset << " " << points(w);
    if (w < -0.02) losing += (losing.empty() ? "" : ", ") + dataset;
    first = false;
  }
  o << " ("
    << (losing.empty() ? "no held-out pair loses more than 2 points"
                       : "more than 2 points lost on a held-out pair of: " + losing)
    << ").\n";
  return o.str();
}

}  // namespace seqslam::tools
