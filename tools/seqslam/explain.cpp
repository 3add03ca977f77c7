// seqslam explain CODE... | --all: the sentences behind the message codes the head board
// prints. Builds without message texts (the board: SEQSLAM_MESSAGE_TEXTS = 0, seqslam/messages.h)
// return "<family><value>" from the core's and storage's *_text() functions, e.g. "PL10" for
// LibraryProblem 10; this host build has the sentences, so the same functions decode them.
// docs/messages.md is `seqslam explain --all` (tests/host/cli/explain.sh compares the two).
#include <CLI/CLI.hpp>

#include <cctype>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "cli_common.h"
#include "seqslam/explorer.h"
#include "seqslam/heuristic_matcher.h"
#include "seqslam/localiser.h"
#include "seqslam/occupancy_grid.h"
#include "seqslam/route_search.h"
#include "seqslam/session/session.h"
#include "seqslam/storage/dream.h"
#include "seqslam/storage/library_store.h"
#include "seqslam/storage/map_store.h"
#include "seqslam/storage/record_log.h"
#include "seqslam/storage/run_files.h"
#include "seqslam/storage/volume.h"
#include "seqslam_tools/output_file.h"

namespace seqslam::cli {

namespace {

// One family of codes: the two letters the board prints, the enum, its last enumerator and
// the text function. The enums number their enumerators 0, 1, ... without gaps.
struct Family {
  const char* code;
  const char* name;
  uint32_t last;  // the value of the enum's last enumerator
  const char* (*text)(uint32_t value);
};

template <typename E>
constexpr uint32_t value_of(E e) {
  return static_cast<uint32_t>(e);
}

// The families in the order of seqslam/messages.h. `last` is the enum's last enumerator:
// when one is added after it, the text function names it (its switch must, under -Wswitch),
// check_family() sees that value+1 is no longer the function's "unknown" answer, and
// `explain` fails (status 1; tests/host/cli/explain.sh) until the bound here is moved.
const Family kFamilies[] = {
    {"CI", "ConfigIssue", value_of(ConfigIssue::kRouteJumpStepsZero),
     [](uint32_t v) { return config_issue_text(static_cast<ConfigIssue>(v)); }},
    {"RI", "RouteIssue", value_of(RouteIssue::kJumpStepsZero),
     [](uint32_t v) { return route_issue_text(static_cast<RouteIssue>(v)); }},
    {"HI", "HeuristicIssue", value_of(HeuristicIssue::kPixelsOutOfRange),
     [](uint32_t v) { return heuristic_issue_text(static_cast<HeuristicIssue>(v)); }},
    {"GI", "GridIssue", value_of(GridIssue::kNoSlots),
     [](uint32_t v) { return grid_issue_text(static_cast<GridIssue>(v)); }},
    {"EI", "ExplorerIssue", value_of(ExplorerIssue::kSpacing),
     [](uint32_t v) { return explorer_issue_text(static_cast<ExplorerIssue>(v)); }},
    {"LP", "LogProblem", value_of(storage::LogProblem::kCommitSlotDamaged),
     [](uint32_t v) { return storage::log_problem_text(static_cast<storage::LogProblem>(v)); }},
    {"DP", "DreamProblem", value_of(storage::DreamProblem::kBadImage),
     [](uint32_t v) { return storage::dream_problem_text(static_cast<storage::DreamProblem>(v)); }},
    {"PL", "LibraryProblem", value_of(storage::LibraryProblem::kImagesFull),
     [](uint32_t v) {
       return storage::library_problem_text(static_cast<storage::LibraryProblem>(v));
     }},
    {"VP", "VolumeProblem", value_of(storage::VolumeProblem::kTooLarge),
     [](uint32_t v) {
       return storage::volume_problem_text(static_cast<storage::VolumeProblem>(v));
     }},
    {"MP", "MapProblem", value_of(storage::MapProblem::kIndexFull),
     [](uint32_t v) { return storage::map_problem_text(static_cast<storage::MapProblem>(v)); }},
    {"RC", "RunIssue", value_of(storage::RunIssue::kRouteWindowTooNarrow),
     [](uint32_t v) { return storage::run_issue_text(static_cast<storage::RunIssue>(v)); }},
    {"SE", "SessionIssue", value_of(session::SessionIssue::kExplorer),
     [](uint32_t v) {
       return session::session_issue_text(static_cast<session::SessionIssue>(v));
     }},
    {"FW", "FirmwareIssue", value_of(session::FirmwareIssue::kScanCannotComplete),
     [](uint32_t v) {
       return session::firmware_issue_text(static_cast<session::FirmwareIssue>(v));
     }},
};

// Every enum is uint8_t: 255 is no enumerator, so its text is the function's fallback.
constexpr uint32_t kNoEnumerator = 255;

// "" when `last` is the family's last enumerator: the value after it gets the same answer as
// a value that is certainly none (the fallback), and `last` itself a different one.
std::string check_family(const Family& f) {
  const char* fallback = f.text(kNoEnumerator);
  if (f.last + 1 >= kNoEnumerator || std::strcmp(f.text(f.last + 1), fallback) != 0) {
    return std::string("the message table is out of date: ") + f.name + " has an enumerator " +
           std::to_string(f.last + 1) + " ('" + f.text(f.last + 1) +
           "'): move its bound in tools/seqslam/explain.cpp and regenerate docs/messages.md "
           "(seqslam explain --all)";
  }
  if (std::strcmp(f.text(f.last), fallback) == 0) {
    return std::string("the message table is out of date: ") + f.name + " has no enumerator " +
           std::to_string(f.last) + ": move its bound in tools/seqslam/explain.cpp";
  }
  return {};
}

std::string families_text() {
  std::string s;
  for (const Family& f : kFamilies) {
    if (!s.empty()) s += ", ";
    s += std::string(f.code) + " " + f.name;
  }
  return s;
}

struct Decoded {
  const Family* family = nullptr;
  uint32_t value = 0;
};

// "PL10" (any case): two letters and a decimal number. Returns "" or what is wrong.
std::string decode(const std::string& code, Decoded* out) {
  const std::string usage = "'" + code +
                            "' is not a message code: two letters (the family) and a number, as "
                            "the board prints them, e.g. PL10";
  if (code.size() < 3 || !std::isalpha(static_cast<unsigned char>(code[0])) ||
      !std::isalpha(static_cast<unsigned char>(code[1]))) {
    return usage;
  }
  uint64_t value = 0;
  for (size_t i = 2; i < code.size(); ++i) {
    const char c = code[i];
    if (c < '0' || c > '9') return usage;
    if (value < 1000000000) value = value * 10 + static_cast<uint64_t>(c - '0');
  }
  const char family[3] = {static_cast<char>(std::toupper(static_cast<unsigned char>(code[0]))),
                          static_cast<char>(std::toupper(static_cast<unsigned char>(code[1]))),
                          '\0'};
  for (const Family& f : kFamilies) {
    if (std::strcmp(f.code, family) != 0) continue;
    if (value > f.last) {
      return "'" + code + "': " + f.name + " has the values 0.." + std::to_string(f.last) + " (" +
             f.code + "0.." + f.code + std::to_string(f.last) +
             "): a board built from newer sources than this tool?";
    }
    out->family = &f;
    out->value = static_cast<uint32_t>(value);
    return {};
  }
  return "'" + code + "': unknown family '" + family + "' (the families are " + families_text() +
         ")";
}

// A sentence in a Markdown table cell.
std::string cell(const char* text) {
  std::string s;
  for (const char* p = text; *p != '\0'; ++p) {
    if (*p == '|') s += '\\';
    s += *p;
  }
  return s;
}

struct ExplainOptions {
  std::vector<std::string> codes;
  bool all = false;
};

int run_explain(const ExplainOptions& o) {
  if (o.all == !o.codes.empty()) {
    return usage_error(o.all ? "give either CODE... or --all, not both"
                             : "give a message CODE (e.g. PL10) or --all");
  }
  std::vector<Decoded> decoded;
  for (const std::string& code : o.codes) {
    Decoded d;
    const std::string error = decode(code, &d);
    if (!error.empty()) return usage_error(error);
    decoded.push_back(d);
  }
  // The bounds are checked first: a stale one would call a new code out of range.
  for (const Family& f : kFamilies) {
    bool used = o.all;
    for (const Decoded& d : decoded)
      used = used || d.family == &f;
    const std::string error = used ? check_family(f) : std::string();
    if (!error.empty()) return fail("internal: " + error);
  }
  if (o.all) {
    std::string table = "| code | family | value | message |\n| --- | --- | --- | --- |\n";
    for (const Family& f : kFamilies) {
      for (uint32_t v = 0; v <= f.last; ++v) {
        const std::string n = std::to_string(v);
        table += "| " + std::string(f.code) + n + " | " + f.name + " | " + n + " | " +
                 cell(f.text(v)) + " |\n";
      }
    }
    tools::write_stdout(table);
    return kExitOk;
  }
  for (const Decoded& d : decoded) {
    std::printf("%s%u: %s %u: %s\n", d.family->code, d.value, d.family->name, d.value,
                d.family->text(d.value));
  }
  return kExitOk;
}

}  // namespace

void add_explain_command(CLI::App& app, Command* chosen) {
  auto o = std::make_shared<ExplainOptions>();
  CLI::App* explain = app.add_subcommand(
      "explain",
      "Print the sentence behind a message code the head board prints (e.g. PL10: the board's "
      "firmware is built without message texts), or every code as a Markdown table");
  explain
      ->add_option("CODE", o->codes,
                   "Message codes as the board prints them, any case: the family (" +
                       families_text() + ") followed by the enumerator's value")
      ->type_name("CODE");
  explain->add_flag("--all", o->all,
                    "Print every code with its family, value and sentence as a Markdown table "
                    "(docs/messages.md)");
  explain->callback([chosen, o] { *chosen = [o] { return run_explain(*o); }; });
}

}  // namespace seqslam::cli
