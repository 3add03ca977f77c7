// seqslam config write|show: the firmware's run configuration (volume file `config`). Every
// option and every row of `config show` comes from the settings table
// (storage/run_config.h, via settings_cli.h); what is here is what the table cannot say: the
// modes' implications, the checks' messages, the summary line.
#include <CLI/CLI.hpp>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "card_checks.h"
#include "cli_common.h"
#include "seqslam/localiser.h"
#include "seqslam/occupancy_grid.h"
#include "seqslam/session/profile.h"
#include "seqslam/spatial_trigger.h"
#include "seqslam/storage/run_files.h"
#include "seqslam_tools/settings_cli.h"

namespace seqslam::cli {

namespace {

using storage::RunConfig;

// Explore is teach + repeat + mapping, and continue is explore's continuation: the modes they
// imply are set with them.
uint8_t implied_modes(uint8_t modes) {
  if ((modes & storage::kModeContinue) != 0) modes |= storage::kModeExplore;
  if ((modes & storage::kModeExplore) != 0) modes |= storage::kModeTeach | storage::kModeRepeat;
  return modes;
}

std::string modes_text(uint8_t modes, const char* separator) {
  // Explore implies teach and repeat: they are not named with it.
  const bool explore = (modes & storage::kModeExplore) != 0;
  std::string s;
  for (uint8_t i = 0; i < 5; ++i) {
    if ((modes & (1u << i)) == 0) continue;
    if (explore && (1u << i) <= storage::kModeRepeat) continue;
    if (!s.empty()) s += separator;
    s += storage::kModeNames[i];
  }
  return s.empty() ? "(none)" : s;
}

std::string start_text(int32_t start) {
  return start == -1 ? std::string("unknown") : std::to_string(start);
}

bool same_route(const RouteSearchConfig& a, const RouteSearchConfig& b) {
  return a.window == b.window && a.slack == b.slack && a.growth == b.growth &&
         a.lost_after == b.lost_after && a.scan_places == b.scan_places &&
         a.scan_seq_len == b.scan_seq_len && a.start == b.start;
}

std::string grid_origin_metres(const RunConfig& c) {
  return setting_text::text(c.grid_origin, storage::Setting{});
}

// The options behind what check_run_config refused, with their values and the limit.
std::string run_issue_options(const RunConfig& c, storage::RunIssue issue,
                              const storage::RunLimits& l) {
  using storage::RunIssue;
  const auto at_most = [](const char* option, uint32_t value, uint32_t limit) {
    return std::string(option) + " " + std::to_string(value) + " (at most " + std::to_string(limit);
  };
  switch (issue) {
    case RunIssue::kNone:
      break;
    case RunIssue::kHeuristicNotBuilt:
      return "--matcher heuristic";
    case RunIssue::kSlopeNotBuilt:
      return "--matcher slope";
    case RunIssue::kMappingNotBuilt:
      return "--modes explore";
    case RunIssue::kExploreHeuristic:
      return "--modes explore with --matcher heuristic";
    case RunIssue::kRouteMaxShift:
      return "--max-shift " + std::to_string(c.max_shift) +
             " (0 for the route search: --matcher diagonal in teach or repeat mode)";
    case RunIssue::kSpacingOutOfRange:
      return "--spacing " + shortest_decimal(c.spacing.raw(), 32) + " (above 0 and at most " +
             shortest_decimal(SpatialTrigger::kMaxSpacing.raw(), 32) + ")";
    case RunIssue::kSeqLenAboveLimit:
      return at_most("--seq-len", c.sequence.seq_len, l.seq_len) + " with --matcher diagonal)";
    case RunIssue::kWindowAboveLimit:
      return at_most("--window", c.sequence.window, l.norm_window) + " for the route search)";
    case RunIssue::kExclusionAboveLimit:
      return at_most("--exclusion", c.sequence.exclusion, l.exclusion) + " for the route search)";
    case RunIssue::kRouteWindowAboveLimit:
      return at_most("--route-window", c.route.window, l.route_window) + ")";
    case RunIssue::kScanSeqLenAboveLimit:
      return at_most("--scan-seq-len", scan_seq_len(c.route, c.sequence), l.scan_seq_len) +
             ", the shorter of it and --seq-len)";
    case RunIssue::kRouteWindowTooNarrow:
      return "--route-window " + std::to_string(c.route.window) + " (at least 2 x --exclusion " +
             std::to_string(c.sequence.exclusion) + " + 3 = " +
             std::to_string(2 * c.sequence.exclusion + 3) + ")";
  }
  return {};
}

struct WriteOptions {
  std::string image;
  SettingOptions<> settings;
};

// The checks of a configuration from the command line, with messages that name the option;
// kExitOk or the usage error's status.
int check_written(const RunConfig& c) {
  if ((c.modes & storage::kModeExplore) != 0 && c.trigger != storage::TriggerMode::kDistance) {
    return usage_error("--modes explore needs --trigger distance (the map hangs from odometry)");
  }
  GridIssue grid_issue = GridIssue::kNone;
  if (check_grid_config(c.grid(), &grid_issue) != Status::kOk) {
    return usage_error(std::string("invalid grid: ") + grid_issue_text(grid_issue));
  }
  const ConfigCheck check = check_localiser_config(c.localiser());
  if (!check.ok()) {
    return usage_error(std::string("invalid configuration: ") + config_issue_text(check.issue) +
                       " (" + status_name(check.status) + ")");
  }
  const storage::SettingsCheck settings = storage::check_run_settings(c);
  if (!settings.ok()) {
    return usage_error("invalid configuration: " +
                       (settings.setting >= 0
                            ? "--" + setting_name(settings.setting) + " is out of its range"
                            : std::string("the modes, mapping or odometry")) +
                       " (" + status_name(settings.status) + ")");
  }
  // What the firmware (this build's capacity profile, session/profile.h) refuses at start,
  // with its own sentence.
  const storage::RunCheck run = storage::check_run_config(c, profile::kRunLimits);
  if (!run.ok()) {
    return usage_error(std::string("invalid configuration for the firmware: ") +
                       storage::run_issue_text(run.issue) + " (" + status_name(run.status) +
                       "): " + run_issue_options(c, run.issue, profile::kRunLimits));
  }
  return kExitOk;
}

int run_write(const WriteOptions& o) {
  RunConfig c;
  // A replay's images are the size they were recorded at: without --size, its mapping.
  const auto replay_mapping =
      o.settings.given("size") ? std::nullopt : card_replay_mapping(o.image);
  if (replay_mapping && *replay_mapping != c.mapping) {
    c.mapping = *replay_mapping;
    std::printf("%s: image size %ux%u and mapping from the card's replay (--size to choose)\n",
                o.image.c_str(), c.mapping.xmax, c.mapping.ymax);
  }
  o.settings.apply(&c);
  c.modes = implied_modes(c.modes);
  if (const int rc = check_written(c); rc != kExitOk) return rc;
  Disk disk;
  std::string error = disk.open(o.image, true);
  storage::Region region;
  if (error.empty()) error = disk.open_file(storage::kConfigFile, &region);
  if (!error.empty()) return fail(error);
  // Against the card's data (its library, query history, replay), before it is touched.
  if (const int rc = check_config_for_card(disk, c); rc != kExitOk) return rc;
  const Status s = storage::write_run_config(region, c);
  const std::string where = o.image + ":" + storage::kConfigFile;
  if (s == Status::kResourceExhausted) {
    return fail(where + ": the volume file is too small for a run configuration (" +
                std::to_string(region.block_count()) + " block(s); it needs 1)");
  }
  if (s != Status::kOk) {
    const std::string device_error = disk.device().error();
    return fail(where + ": cannot write the run configuration: " + status_name(s) +
                (device_error.empty() ? "" : " (" + device_error + ")"));
  }
  std::printf("%s: %s\n", where.c_str(), run_config_summary(c).c_str());
  return kExitOk;
}

struct ShowOptions {
  std::string image;
};

// What the table's rows do not say: the parts of the composite settings that have no option.
void print_details(const RunConfig& c) {
  const hal::PipelineMapping& m = c.mapping;
  const PatchNormConfig& p = c.preprocess.patch;
  const OdometryConfig& w = c.odometry;
  const auto q16 = [](int32_t raw) { return shortest_decimal(raw, 16); };
  std::printf("  %-22s a11 %s, a12 %s, a21 %s, a22 %s, offset (%d, %d) pixels%s\n",
              "pipeline mapping", q16(m.a11.raw()).c_str(), q16(m.a12.raw()).c_str(),
              q16(m.a21.raw()).c_str(), q16(m.a22.raw()).c_str(), m.bx, m.by,
              setting_text::expressible(m) ? " (plain reduction of the camera frame)" : "");
  std::printf(
      "  %-22s %ux%u pixels, epsilon %s grey levels, gain %s grey levels per standard "
      "deviation\n",
      "PN patches", p.patch_width, p.patch_height, shortest_decimal(p.epsilon.raw(), 8).c_str(),
      shortest_decimal(p.gain.raw(), 8).c_str());
  std::printf("  %-22s %u ticks/revolution, %u-bit counters, at most %u ticks per update\n",
              "encoders", static_cast<unsigned>(w.ticks_per_revolution),
              static_cast<unsigned>(w.counter_bits), static_cast<unsigned>(w.max_ticks_per_update));
}

// What a row of `config show` means where the value alone does not say it: the symbols of
// the method (S, W, R), what the start and the scan's length amount to, the value stored.
void explain_row(const RunConfig& c, SettingRow* r) {
  static const struct {
    const char* name;
    const char* meaning;
  } kMeanings[] = {
      {"seq-len", "(S)"},
      {"window", "(W; 0 = no local normalisation)"},
      {"exclusion", "(R)"},
      {"threshold", "(localised when the confidence is below it)"},
  };
  for (const auto& m : kMeanings) {
    if (r->name == m.name) r->value += std::string(" ") + m.meaning;
  }
  const bool loop_closure =
      (c.modes & storage::kModeTeach) != 0 && (c.modes & storage::kModeRepeat) != 0;
  if (r->name == "trigger") {
    r->value += c.trigger == storage::TriggerMode::kEveryFrame
                    ? " (every recorded frame is a place)"
                    : " (a place every " + shortest_decimal(c.spacing.raw(), 32) + " m driven)";
  } else if (r->name == "start") {
    r->value = c.route.start < 0 ? "unknown (a scan finds the place first)"
                                 : "place " + std::to_string(c.route.start);
    if (r->note.empty() && loop_closure) r->note = "(not used: teach + repeat starts unknown)";
  } else if (r->name == "scan-seq-len") {
    const uint16_t used = scan_seq_len(c.route, c.sequence);
    if (used != c.route.scan_seq_len) r->value += " (" + std::to_string(used) + " used: at most S)";
  } else if (r->name == "route-growth") {
    // The value is stored in 1/256 places: the fraction and its exact decimal.
    const uint16_t raw = c.route.growth.raw();
    r->value += " (" + std::to_string(raw) + "/256 = " + exact_decimal(raw, 8) + ")";
  }
}

int run_show(const ShowOptions& o) {
  Disk disk;
  std::string error = disk.open(o.image, false);
  storage::Region region;
  if (error.empty()) error = disk.open_file(storage::kConfigFile, &region);
  if (!error.empty()) return fail(error);
  const std::string where = o.image + ":" + storage::kConfigFile;
  RunConfig c;
  storage::LogProblem problem = storage::LogProblem::kNone;
  const Status s = storage::read_run_config(region, &c, &problem);
  if (s != Status::kOk) {
    if (problem == storage::LogProblem::kVersion) {
      return fail(where + ": not a usable run configuration: " +
                  storage::log_problem_text(problem) + " (this tool reads and writes version " +
                  std::to_string(storage::kRunConfigKind.version) +
                  "): write it again with `seqslam config write`");
    }
    if (problem != storage::LogProblem::kNone) {
      return fail(where +
                  ": not a usable run configuration: " + storage::log_problem_text(problem));
    }
    return fail(where + ": the run configuration is damaged or invalid (" + status_name(s) + ")");
  }
  std::printf("%s\n", where.c_str());
  for (SettingRow& r : setting_rows(c)) {
    explain_row(c, &r);
    std::printf("  %-22s %s%s%s\n", r.name.c_str(), r.value.c_str(), r.note.empty() ? "" : " ",
                r.note.c_str());
  }
  print_details(c);
  const std::string options = setting_options_text(c, 0xFFFF, true);
  std::printf("options: %s\n",
              options.empty() ? "(not expressible: mapping, PN patches or encoder constants "
                                "differ from the defaults)"
                              : options.c_str());
  return kExitOk;
}

}  // namespace

std::string run_config_summary(const RunConfig& c) {
  std::string s = "modes " + modes_text(c.modes, ",") + ", trigger " +
                  storage::kTriggerNames[static_cast<uint8_t>(c.trigger) & 1];
  if (c.trigger == storage::TriggerMode::kDistance) {
    s += " every " + shortest_decimal(c.spacing.raw(), 32) + " m";
  }
  s += ", " + std::to_string(c.mapping.xmax) + "x" + std::to_string(c.mapping.ymax) + ", " +
       preprocessing_name(c.preprocess.method) + ", S=" + std::to_string(c.sequence.seq_len) +
       " W=" + std::to_string(c.sequence.window) + " R=" + std::to_string(c.sequence.exclusion) +
       ", threshold " + shortest_decimal(c.sequence.threshold.raw(), 16);
  if ((c.modes & storage::kModeExplore) != 0) {
    s += ", map origin (" + grid_origin_metres(c) + ") m " + std::to_string(c.grid_size.width) +
         "x" + std::to_string(c.grid_size.height) + " cells of " + std::to_string(c.grid_cell_mm) +
         " mm";
  }
  // The diagonal matcher is the default and stays implicit, so the line of every existing
  // configuration is unchanged.
  if (c.matcher == LocaliserMatcher::kHeuristic) {
    s += ", heuristic matcher k=" + std::to_string(c.heuristic.candidates) +
         " guard=" + std::to_string(c.heuristic.guard) + " candidate threshold " +
         shortest_decimal(c.heuristic.threshold.raw(), 8);
    if (c.heuristic.scan_places != RunConfig{}.heuristic.scan_places)
      s += " first-scan-places=" + std::to_string(c.heuristic.scan_places);
  }
  // Likewise the route search's settings when they are the defaults.
  const RouteSearchConfig& r = c.route;
  if (!same_route(r, RouteSearchConfig{})) {
    s += ", route window=" + std::to_string(r.window) + " slack=" + std::to_string(r.slack) +
         " growth=" + shortest_decimal(r.growth.raw(), 8) +
         " lost-after=" + std::to_string(r.lost_after) +
         " scan-places=" + std::to_string(r.scan_places) +
         " scan-seq-len=" + std::to_string(r.scan_seq_len) + " start=" + start_text(r.start);
  }
  return s;
}

void add_config_commands(CLI::App& app, Command* chosen) {
  CLI::App* config = app.add_subcommand(
      "config", "The firmware's run configuration (volume file 'config' of a disk image)");
  config->require_subcommand(1);

  auto w = std::make_shared<WriteOptions>();
  CLI::App* write = config->add_subcommand(
      "write",
      "Write a run configuration into volume file 'config'; unset options take the "
      "defaults shown. A configuration this build's firmware cannot run (its capacity "
      "profile: S <= " +
          std::to_string(profile::kMaxSeqLen) +
          ", W <= " + std::to_string(profile::kMaxNormWindow) + " and R <= " +
          std::to_string(profile::kMaxExclusion) + " for the route search, ...) is refused");
  write->add_option("IMAGE", w->image, "Disk image file with a volume file 'config' (modified)")
      ->required();
  // Every setting the card carries.
  SettingOptions<>::Selection all;
  all.card_only = true;
  w->settings.add(write, RunConfig{}, all);
  write->callback([chosen, w] { *chosen = [w] { return run_write(*w); }; });

  auto s = std::make_shared<ShowOptions>();
  CLI::App* show = config->add_subcommand(
      "show",
      "Print the run configuration of volume file 'config', and the `config write` "
      "options that reproduce it");
  show->add_option("IMAGE", s->image, "Disk image file with a volume file 'config'")->required();
  show->callback([chosen, s] { *chosen = [s] { return run_show(*s); }; });
}

}  // namespace seqslam::cli
