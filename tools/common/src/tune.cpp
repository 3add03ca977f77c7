#include "seqslam_tools/tune.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <set>
#include <sstream>

namespace seqslam::tools {

namespace {

constexpr size_t kColumns = 23;  // kSweepHeader's
constexpr size_t kPairColumns = 3;
constexpr size_t kSettingColumns = 9;
constexpr size_t kTop1 = 13;
constexpr size_t kRecall100 = 14;
constexpr size_t kAuc = 15;

// Splits one CSV line (RFC 4180 quotes, as sweep writes paths that need them). false for an
// unterminated quote.
bool split_csv(const std::string& line, std::vector<std::string>* fields) {
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

// A figure of the sweep: a finite number in [0, 1].
bool parse_fraction(const std::string& s, double* out) {
  if (s.empty()) return false;
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(s.c_str(), &end);
  if (errno != 0 || end != s.c_str() + s.size() || !std::isfinite(v) || v < 0.0 || v > 1.0)
    return false;
  *out = v;
  return true;
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

// Mean figures of a setting over the pairs except `skip` (nullptr: all).
Figures mean_over(const std::map<std::string, Figures>& by_pair, const std::string* skip) {
  Figures m;
  size_t n = 0;
  for (const auto& [pair, f] : by_pair) {
    if (skip != nullptr && pair == *skip) continue;
    m.recall += f.recall;
    m.auc += f.auc;
    m.top1 += f.top1;
    ++n;
  }
  if (n > 0) {
    m.recall /= static_cast<double>(n);
    m.auc /= static_cast<double>(n);
    m.top1 /= static_cast<double>(n);
  }
  return m;
}

// Recall at 100 % precision first, AUC then top-1 as tie-breaks; a better figure wins.
bool better(const Figures& a, const Figures& b) {
  if (a.recall != b.recall) return a.recall > b.recall;
  if (a.auc != b.auc) return a.auc > b.auc;
  return a.top1 > b.top1;
}

std::string best_setting(const std::map<std::string, std::map<std::string, Figures>>& table,
                         const std::vector<std::string>& settings, const std::string* skip) {
  std::string best;
  Figures best_f;
  for (const std::string& s : settings) {  // sorted: equal figures keep the first
    const Figures f = mean_over(table.at(s), skip);
    if (best.empty() || better(f, best_f)) {
      best = s;
      best_f = f;
    }
  }
  return best;
}

// "library -> query" by their file names (the table's pair column; the full paths are in the
// sweep's rows).
std::string pair_label(const std::string& pair) {
  std::vector<std::string> f;
  if (!split_csv(pair, &f) || f.size() != kPairColumns) return pair;
  const auto name = [](const std::string& path) {
    std::string p = path;
    while (p.size() > 1 && p.back() == '/')
      p.pop_back();
    const size_t slash = p.find_last_of('/');
    std::string n = slash == std::string::npos ? p : p.substr(slash + 1);
    const size_t dot = n.find_last_of('.');
    return dot == std::string::npos || dot == 0 ? n : n.substr(0, dot);
  };
  return name(f[0]) + " -> " + name(f[1]);
}

std::string percent(double v) {
  char b[32];
  std::snprintf(b, sizeof b, "%.1f", 100.0 * v);
  return b;
}

}  // namespace

Outcome<std::vector<TuneRow>> read_sweep_rows(const std::string& path) {
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
    if (!split_csv(line, &f) || f.size() != kColumns) {
      return Error{where + "expected " + std::to_string(kColumns) +
                   " comma-separated fields (a line cut short? re-run the sweep to complete it)"};
    }
    TuneRow r;
    r.pair = join(f, 0, kPairColumns);
    r.setting = join(f, kPairColumns, kSettingColumns);
    if (!parse_fraction(f[kTop1], &r.top1) ||
        !parse_fraction(f[kRecall100], &r.recall_at_100_precision) ||
        !parse_fraction(f[kAuc], &r.auc_pr)) {
      return Error{where + "top1, recall_at_100_precision and auc_pr must be numbers in 0..1"};
    }
    rows.push_back(std::move(r));
  }
  if (in.bad()) return Error{path + ": read error"};
  return rows;
}

Outcome<TuneReport> tune(const std::vector<TuneRow>& rows, const std::string& default_setting) {
  TuneReport rep;
  std::map<std::string, std::map<std::string, Figures>> table;  // setting -> pair -> figures
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
  std::map<std::string, size_t> chosen_count;
  const auto def = table.find(default_setting);
  for (const std::string& pair : rep.pairs) {
    TuneFold fold;
    fold.held_out = pair;
    fold.chosen = best_setting(table, rep.settings, &pair);
    const Figures& c = table.at(fold.chosen).at(pair);
    fold.chosen_recall = c.recall;
    fold.chosen_auc = c.auc;
    if (def != table.end() && def->second.count(pair) != 0) {
      fold.has_default = true;
      fold.default_recall = def->second.at(pair).recall;
      fold.default_auc = def->second.at(pair).auc;
    }
    ++chosen_count[fold.chosen];
    rep.folds.push_back(fold);
  }
  rep.overall = best_setting(table, rep.settings, nullptr);
  rep.overall_folds = chosen_count.count(rep.overall) != 0 ? chosen_count[rep.overall] : 0;
  rep.distinct_choices = chosen_count.size();
  return rep;
}

std::string tune_markdown(const TuneReport& r, const std::string& default_setting) {
  std::ostringstream o;
  o << "Settings: size,preprocess,seq_len,window,exclusion,threshold,max_shift,matcher,metric. "
    << r.settings.size() << " settings swept on all " << r.pairs.size() << " pairs";
  if (r.incomplete_settings > 0) o << " (" << r.incomplete_settings << " incomplete, left out)";
  o << "; default " << default_setting << ".\n\n";
  o << "Each pair held out in turn; the setting is chosen on the other pairs (best mean recall "
       "at 100 % precision, then AUC), and scored on the held-out pair only.\n\n";
  o << "| held-out pair | chosen on the others | recall at 100 % P | AUC | default: recall "
       "at 100 % P | AUC | chosen - default (points) |\n";
  o << "| --- | --- | --- | --- | --- | --- | --- |\n";
  double worst = 0.0;
  bool any_default = false;
  for (const TuneFold& f : r.folds) {
    o << "| " << pair_label(f.held_out) << " | " << f.chosen << " | " << percent(f.chosen_recall)
      << " | " << percent(f.chosen_auc) << " | ";
    if (f.has_default) {
      const double diff = 100.0 * (f.chosen_recall - f.default_recall);
      char d[32];
      std::snprintf(d, sizeof d, "%+.1f", diff);
      o << percent(f.default_recall) << " | " << percent(f.default_auc) << " | " << d << " |\n";
      worst = any_default ? std::min(worst, diff) : diff;
      any_default = true;
    } else {
      o << "not swept | - | - |\n";
    }
  }
  o << "\nStability: " << r.distinct_choices << " distinct setting(s) chosen over "
    << r.folds.size() << " folds; the best over all pairs, " << r.overall << ", was chosen in "
    << r.overall_folds << " of " << r.folds.size() << ".\n";
  if (any_default) {
    char w[32];
    std::snprintf(w, sizeof w, "%+.1f", worst);
    o << "Worst held-out difference against the default: " << w << " points ("
      << (worst >= -2.0 ? "no held-out pair loses more than 2 points"
                        : "a held-out pair loses more than 2 points")
      << ").\n";
  } else {
    o << "The default setting was not swept: no comparison.\n";
  }
  return o.str();
}

}  // namespace seqslam::tools
