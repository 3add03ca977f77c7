// seqslam config write|show: the firmware's run configuration (volume file `config`).
#include <CLI/CLI.hpp>

#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "app_limits.h"
#include "card_checks.h"
#include "cli_common.h"
#include "seqslam/localiser.h"
#include "seqslam/occupancy_grid.h"
#include "seqslam/preprocess.h"
#include "seqslam/spatial_trigger.h"
#include "seqslam/storage/run_files.h"
#include "seqslam_tools/cli_numbers.h"
#include "seqslam_tools/wxh.h"

namespace seqslam::cli {

namespace {

__extension__ typedef __int128 I128;

struct ModeName {
  storage::RunMode mode;
  const char* name;
};
constexpr ModeName kModes[] = {{storage::kModeTeach, "teach"},
                               {storage::kModeRepeat, "repeat"},
                               {storage::kModeRecord, "record"},
                               {storage::kModeExplore, "explore"},
                               {storage::kModeContinue, "continue"}};
// Explore is teach + repeat + mapping: those two are implied and not named with it.
constexpr uint8_t kExploreModes =
    storage::kModeTeach | storage::kModeRepeat | storage::kModeExplore;

std::string modes_text(uint8_t modes, const char* separator) {
  std::string s;
  const bool explore = (modes & storage::kModeExplore) != 0;
  for (const ModeName& m : kModes) {
    if ((modes & m.mode) == 0) continue;
    if (explore && (m.mode == storage::kModeTeach || m.mode == storage::kModeRepeat)) continue;
    if (!s.empty()) s += separator;
    s += m.name;
  }
  return s.empty() ? "(none)" : s;
}

const char* trigger_name(storage::TriggerMode t) {
  return t == storage::TriggerMode::kEveryFrame ? "every-frame" : "distance";
}

// The names `seqslam eval --matcher` uses for the two matchers the firmware can run.
const char* matcher_name(LocaliserMatcher m) {
  return m == LocaliserMatcher::kHeuristic ? "heuristic" : "diagonal";
}

// Validators: decimal numbers within a range, converted exactly by the callers.
std::string check_threshold(const std::string& text) {
  UQ16_16 threshold;
  return parse_threshold(text, &threshold);
}

// A UQ8.8 value (steps of 1/256) as from_ratio rounds it: "" when it is within 0..max_raw,
// else why not, naming the range in `unit`.
std::string check_uq8_8(const std::string& text, int64_t max_raw, const std::string& unit) {
  int64_t num = 0;
  int64_t den = 1;
  const std::string error = parse_decimal(text, &num, &den);
  if (!error.empty()) return error;
  const I128 raw = num < 0 ? -1 : (static_cast<I128>(num) * 256 + den / 2) / den;
  if (raw < 0 || raw > max_raw) {
    return "'" + text + "' is not within 0.." + shortest_decimal(max_raw, 8) + " " + unit;
  }
  return {};
}

std::string check_sigma(const std::string& text) {
  return check_uq8_8(text, UQ8_8::max().raw(), "grey levels (UQ8.8, steps of 1/256)");
}

// The heuristic's candidate threshold: grey levels per pixel, 0..255 as for seqslam eval.
std::string check_candidate_threshold(const std::string& text) {
  return check_uq8_8(text, 255 * 256, "grey levels per pixel");
}

// The spacing: a decimal; its range (above 0, at most SpatialTrigger::kMaxSpacing) is
// check_run_config's, with the firmware's own sentence.
std::string check_spacing(const std::string& text) {
  int64_t num = 0;
  int64_t den = 1;
  return parse_decimal(text, &num, &den);
}

// The heuristic's first scan: how it is spread over steps.
std::string heuristic_scan_text(const HeuristicConfig& h) {
  return h.scan_places == 0 ? std::string("in one step (scan places 0)")
                            : std::to_string(h.scan_places) + " library places a step";
}

std::string start_text(int32_t start) {
  return start == -1 ? std::string("unknown") : std::to_string(start);
}

template <typename F>
F exact(const std::string& text) {
  int64_t num = 0;
  int64_t den = 1;
  (void)parse_decimal(text, &num, &den);  // validated by CLI11 already
  return F::from_ratio(num, den);
}

// "X,Y" in metres, to whole millimetres within +-2 000 km (int32 mm).
std::string parse_grid_origin(const std::string& text, int32_t* x_mm, int32_t* y_mm) {
  const size_t comma = text.find(',');
  if (comma == std::string::npos) return "'" + text + "' is not X,Y in metres";
  int32_t mm[2] = {0, 0};
  const std::string parts[2] = {text.substr(0, comma), text.substr(comma + 1)};
  for (int i = 0; i < 2; ++i) {
    int64_t num = 0;
    int64_t den = 1;
    std::string error = parse_decimal(parts[i], &num, &den);
    if (!error.empty()) return error;
    if (num <= -1000000000000000 || num >= 1000000000000000) {
      return "'" + parts[i] + "' is out of range";
    }
    if ((num * 1000) % den != 0) return "'" + parts[i] + "' is finer than a millimetre";
    const int64_t v = num * 1000 / den;
    if (v < -2000000000 || v > 2000000000) return "'" + parts[i] + "' is out of range";
    mm[i] = static_cast<int32_t>(v);
  }
  *x_mm = mm[0];
  *y_mm = mm[1];
  return {};
}

// "WxH" cells, each 1..32768 (kMaxGridSide).
std::string parse_grid_size(const std::string& text, uint16_t* w, uint16_t* h) {
  uint32_t a = 0;
  uint32_t b = 0;
  if (!tools::split_wxh(text, &a, &b) || a == 0 || b == 0 || a > kMaxGridSide || b > kMaxGridSide) {
    return "'" + text + "' is not WxH cells, each 1.." + std::to_string(kMaxGridSide);
  }
  *w = static_cast<uint16_t>(a);
  *h = static_cast<uint16_t>(b);
  return {};
}

// The grid origin as "X,Y" in metres (as --grid-origin takes it).
std::string grid_origin_metres(const storage::RunConfig& c) {
  auto metres = [](int32_t mm) {
    const std::string sign = mm < 0 ? "-" : "";
    const int64_t a = mm < 0 ? -static_cast<int64_t>(mm) : mm;
    std::string frac = std::to_string(a % 1000);
    frac = std::string(3 - frac.size(), '0') + frac;
    while (!frac.empty() && frac.back() == '0')
      frac.pop_back();
    return sign + std::to_string(a / 1000) + (frac.empty() ? "" : "." + frac);
  };
  return metres(c.grid_origin_x_mm) + "," + metres(c.grid_origin_y_mm);
}

// The route search's `config write` options with their values.
std::string route_options(const RouteSearchConfig& r) {
  return " --route-window " + std::to_string(r.window) + " --route-slack " +
         std::to_string(r.slack) + " --route-growth " + shortest_decimal(r.growth.raw(), 8) +
         " --lost-after " + std::to_string(r.lost_after) + " --scan-places " +
         std::to_string(r.scan_places) + " --scan-seq-len " + std::to_string(r.scan_seq_len) +
         " --start " + start_text(r.start);
}

bool same_route(const RouteSearchConfig& a, const RouteSearchConfig& b) {
  return a.window == b.window && a.slack == b.slack && a.growth == b.growth &&
         a.lost_after == b.lost_after && a.scan_places == b.scan_places &&
         a.scan_seq_len == b.scan_seq_len && a.start == b.start;
}

// Why the firmware does not run the route search with `c` ("" when it does): explore runs
// the full search, the heuristic its own; teach alone never localises (firmware/app).
std::string route_unused(const storage::RunConfig& c) {
  if ((c.modes & storage::kModeExplore) != 0) return " (not used: explore runs the full search)";
  if (c.matcher == LocaliserMatcher::kHeuristic) return " (not used: heuristic matcher)";
  if ((c.modes & storage::kModeRepeat) == 0) return " (not used: no repeat mode)";
  return {};
}

// The options behind what check_run_config refused, with their values and the limit.
std::string run_issue_options(const storage::RunConfig& c, storage::RunIssue issue,
                              const storage::RunLimits& l, const std::string& spacing) {
  using storage::RunIssue;
  const auto at_most = [](const char* option, uint32_t value, uint32_t limit) {
    return std::string(option) + " " + std::to_string(value) + " (at most " + std::to_string(limit);
  };
  switch (issue) {
    case RunIssue::kNone:
      break;
    case RunIssue::kHeuristicNotBuilt:
      return "--matcher heuristic";
    case RunIssue::kMappingNotBuilt:
      return "--modes explore";
    case RunIssue::kExploreHeuristic:
      return "--modes explore with --matcher heuristic";
    case RunIssue::kRouteMaxShift:
      return "--max-shift " + std::to_string(c.max_shift) +
             " (0 for the route search: --matcher diagonal in teach or repeat mode)";
    case RunIssue::kSpacingOutOfRange:
      return "--spacing " + spacing + " (above 0 and at most " +
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
  }
  return {};
}

struct WriteOptions {
  std::string image;
  std::vector<std::string> modes;
  std::string trigger;
  std::string size;
  std::string preprocess;
  int seq_len = 0;
  int window = 0;
  int exclusion = 0;
  std::string threshold;
  std::string sigma_min;
  int max_shift = 0;
  int recent_exclusion = 0;
  std::string spacing;
  bool record_colour = false;
  std::string matcher;
  std::string grid_origin;
  std::string grid_size;
  std::string wheels;
  int grid_cell = 0;
  CLI::Option* grid_cell_opt = nullptr;
  int candidates = 0;
  int guard = 0;
  int heuristic_scan_places = 0;
  std::string candidate_threshold;
  int route_window = 0;
  int route_slack = 0;
  std::string route_growth;
  int lost_after = 0;
  int scan_places = 0;
  int scan_seq_len = 0;
  std::string start;
  // Which options were given.
  CLI::Option* seq_len_opt = nullptr;
  CLI::Option* window_opt = nullptr;
  CLI::Option* exclusion_opt = nullptr;
  CLI::Option* max_shift_opt = nullptr;
  CLI::Option* recent_opt = nullptr;
  CLI::Option* candidates_opt = nullptr;
  CLI::Option* guard_opt = nullptr;
  CLI::Option* heuristic_scan_places_opt = nullptr;
  CLI::Option* route_window_opt = nullptr;
  CLI::Option* route_slack_opt = nullptr;
  CLI::Option* lost_after_opt = nullptr;
  CLI::Option* scan_places_opt = nullptr;
  CLI::Option* scan_seq_len_opt = nullptr;
};

int run_write(const WriteOptions& o) {
  storage::RunConfig c;
  if (!o.modes.empty()) {
    c.modes = 0;
    for (const std::string& name : o.modes) {
      for (const ModeName& m : kModes) {
        if (name == m.name) c.modes = static_cast<uint8_t>(c.modes | m.mode);
      }
    }
    if (c.modes == 0) {
      return usage_error("--modes: give at least one of teach, repeat, record, explore, continue");
    }
    // Continue is an explore run's continuation: explore (and so teach and repeat) implied.
    if ((c.modes & storage::kModeContinue) != 0)
      c.modes = static_cast<uint8_t>(c.modes | storage::kModeExplore);
    if ((c.modes & storage::kModeExplore) != 0)
      c.modes = static_cast<uint8_t>(c.modes | kExploreModes);
  }
  if (!o.trigger.empty()) {
    c.trigger = o.trigger == "every-frame" ? storage::TriggerMode::kEveryFrame
                                           : storage::TriggerMode::kDistance;
  }
  if (!o.size.empty()) {
    uint16_t w = 0;
    uint16_t h = 0;
    const std::string error = parse_image_size(o.size, &w, &h);
    if (!error.empty()) return usage_error("--size: " + error);
    c.mapping = hal::PipelineMapping::reduction(w, h);
  }
  if (!o.preprocess.empty()) {
    (void)parse_preprocessing(o.preprocess, &c.preprocess.method);  // validated by CLI11
  }
  if (o.seq_len_opt->count() > 0) c.sequence.seq_len = static_cast<uint16_t>(o.seq_len);
  if (o.window_opt->count() > 0) c.sequence.window = static_cast<uint16_t>(o.window);
  if (o.exclusion_opt->count() > 0) c.sequence.exclusion = static_cast<uint16_t>(o.exclusion);
  if (!o.threshold.empty()) c.sequence.threshold = exact<UQ16_16>(o.threshold);
  if (!o.sigma_min.empty()) c.sequence.sigma_min = exact<UQ8_8>(o.sigma_min);
  if (o.max_shift_opt->count() > 0) c.max_shift = static_cast<uint8_t>(o.max_shift);
  if (o.recent_opt->count() > 0) c.recent_exclusion = static_cast<uint16_t>(o.recent_exclusion);
  if (!o.spacing.empty()) c.spacing = exact<Q31_32>(o.spacing);
  c.record_colour = o.record_colour;
  if (!o.matcher.empty()) {
    c.matcher =
        o.matcher == "heuristic" ? LocaliserMatcher::kHeuristic : LocaliserMatcher::kDiagonal;
  }
  if (o.candidates_opt->count() > 0) c.heuristic.candidates = static_cast<uint16_t>(o.candidates);
  if (o.guard_opt->count() > 0) c.heuristic.guard = static_cast<uint16_t>(o.guard);
  if (!o.candidate_threshold.empty()) c.heuristic.threshold = exact<UQ8_8>(o.candidate_threshold);
  if (o.heuristic_scan_places_opt->count() > 0)
    c.heuristic.scan_places = static_cast<uint16_t>(o.heuristic_scan_places);
  RouteSearchConfig& route = c.route;
  if (o.route_window_opt->count() > 0) route.window = static_cast<uint16_t>(o.route_window);
  if (o.route_slack_opt->count() > 0) route.slack = static_cast<uint16_t>(o.route_slack);
  if (!o.route_growth.empty()) route.growth = exact<UQ8_8>(o.route_growth);
  if (o.lost_after_opt->count() > 0) route.lost_after = static_cast<uint16_t>(o.lost_after);
  if (o.scan_places_opt->count() > 0) route.scan_places = static_cast<uint16_t>(o.scan_places);
  if (o.scan_seq_len_opt->count() > 0) route.scan_seq_len = static_cast<uint16_t>(o.scan_seq_len);
  if (!o.start.empty()) {
    (void)parse_route_start(o.start, &route.start);  // validated by CLI11
  }

  if (!o.wheels.empty() && !parse_wheel_constants(o.wheels, &c.odometry)) {
    return usage_error(
        "--wheels wants LEFT,RIGHT,TRACK in metres: circumferences above 0 and below 16, the "
        "track above 0 and below 100 (e.g. what seqslam slam --calibration-out wrote)");
  }
  if (!o.grid_origin.empty()) {
    const std::string error =
        parse_grid_origin(o.grid_origin, &c.grid_origin_x_mm, &c.grid_origin_y_mm);
    if (!error.empty()) return usage_error("--grid-origin: " + error);
  }
  if (!o.grid_size.empty()) {
    const std::string error = parse_grid_size(o.grid_size, &c.grid_width, &c.grid_height);
    if (!error.empty()) return usage_error("--grid-size: " + error);
  }
  if (o.grid_cell_opt->count() > 0) c.grid_cell_mm = static_cast<uint16_t>(o.grid_cell);
  if ((c.modes & storage::kModeExplore) != 0 && c.trigger != storage::TriggerMode::kDistance) {
    return usage_error("--modes explore needs --trigger distance (the map hangs from odometry)");
  }
  GridIssue grid_issue = GridIssue::kNone;
  if (check_grid_config(c.grid(), &grid_issue) != Status::kOk) {
    return usage_error(std::string("invalid grid: ") + grid_issue_text(grid_issue));
  }
  if (hal::check_mapping(c.mapping) != Status::kOk) {
    return usage_error("--size: the pixel-pipeline mapping is invalid");
  }
  const ConfigCheck check = check_localiser_config(c.localiser());
  if (!check.ok()) {
    return usage_error(std::string("invalid configuration: ") + config_issue_text(check.issue) +
                       " (" + status_name(check.status) + ")");
  }
  // What the firmware application (this build's, firmware/app/app_limits.h) refuses at start,
  // with its own sentence.
  const storage::RunCheck run = storage::check_run_config(c, app::kRunLimits);
  if (!run.ok()) {
    return usage_error(std::string("invalid configuration for the firmware: ") +
                       storage::run_issue_text(run.issue) + " (" + status_name(run.status) +
                       "): " + run_issue_options(c, run.issue, app::kRunLimits, o.spacing));
  }

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

void row(const char* key, const std::string& value) {
  std::printf("  %-18s %s\n", key, value.c_str());
}

// raw / 2^frac_bits in full (a binary fraction has a finite decimal), without trailing zeros.
std::string exact_decimal(int64_t raw, unsigned frac_bits) {
  std::string s = fixed_decimal(raw, frac_bits, frac_bits);
  while (s.find('.') != std::string::npos && (s.back() == '0' || s.back() == '.'))
    s.pop_back();
  return s;
}

std::string q16(int32_t raw) {
  return shortest_decimal(raw, 16);
}

// The `config write` options that reproduce `c`, or an empty string when some setting has
// no option (a mapping that is not a plain reduction, PN patch or odometry constants).
std::string as_options(const storage::RunConfig& c) {
  const storage::RunConfig d;
  if (c.mapping != hal::PipelineMapping::reduction(c.mapping.xmax, c.mapping.ymax)) return {};
  const PatchNormConfig& p = c.preprocess.patch;
  const PatchNormConfig& dp = d.preprocess.patch;
  if (p.patch_width != dp.patch_width || p.patch_height != dp.patch_height ||
      p.epsilon != dp.epsilon || p.gain != dp.gain) {
    return {};
  }
  const OdometryConfig& w = c.odometry;
  const OdometryConfig& dw = d.odometry;
  if (w.ticks_per_revolution != dw.ticks_per_revolution || w.counter_bits != dw.counter_bits ||
      w.max_ticks_per_update != dw.max_ticks_per_update) {
    return {};
  }
  std::string s =
      "--modes " + modes_text(c.modes, ",") + " --trigger " + trigger_name(c.trigger) + " --size " +
      std::to_string(c.mapping.xmax) + "x" + std::to_string(c.mapping.ymax) + " --preprocess " +
      preprocessing_name(c.preprocess.method) + " --seq-len " + std::to_string(c.sequence.seq_len) +
      " --window " + std::to_string(c.sequence.window) + " --exclusion " +
      std::to_string(c.sequence.exclusion) + " --threshold " +
      shortest_decimal(c.sequence.threshold.raw(), 16) + " --sigma-min " +
      shortest_decimal(c.sequence.sigma_min.raw(), 8) + " --max-shift " +
      std::to_string(c.max_shift) + " --recent-exclusion " + std::to_string(c.recent_exclusion) +
      " --spacing " + shortest_decimal(c.spacing.raw(), 32) + " --matcher " +
      matcher_name(c.matcher) + " --k " + std::to_string(c.heuristic.candidates) + " --guard " +
      std::to_string(c.heuristic.guard) + " --candidate-threshold " +
      shortest_decimal(c.heuristic.threshold.raw(), 8) + " --heuristic-scan-places " +
      std::to_string(c.heuristic.scan_places);
  s += " --grid-origin " + grid_origin_metres(c) + " --grid-size " + std::to_string(c.grid_width) +
       "x" + std::to_string(c.grid_height) + " --grid-cell " + std::to_string(c.grid_cell_mm);
  s += route_options(c.route);
  if (w.circumference_left != dw.circumference_left ||
      w.circumference_right != dw.circumference_right || w.track_width != dw.track_width) {
    s += " --wheels " + shortest_decimal(w.circumference_left.raw(), 32) + "," +
         shortest_decimal(w.circumference_right.raw(), 32) + "," +
         shortest_decimal(w.track_width.raw(), 32);
  }
  if (c.record_colour) s += " --record-colour";
  return s;
}

int run_show(const ShowOptions& o) {
  Disk disk;
  std::string error = disk.open(o.image, false);
  storage::Region region;
  if (error.empty()) error = disk.open_file(storage::kConfigFile, &region);
  if (!error.empty()) return fail(error);
  const std::string where = o.image + ":" + storage::kConfigFile;
  storage::RunConfig c;
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
  const hal::PipelineMapping& m = c.mapping;
  const PatchNormConfig& p = c.preprocess.patch;
  const OdometryConfig& w = c.odometry;
  std::printf("%s\n", where.c_str());
  row("modes", modes_text(c.modes, ", "));
  row("trigger",
      c.trigger == storage::TriggerMode::kDistance
          ? "distance (a place every " + shortest_decimal(c.spacing.raw(), 32) + " m of odometry)"
          : std::string("every-frame (every recorded frame is a place)"));
  row("spacing", shortest_decimal(c.spacing.raw(), 32) + " m");
  row("image size", std::to_string(m.xmax) + "x" + std::to_string(m.ymax) + " pixels");
  row("pipeline mapping", "a11 " + q16(m.a11.raw()) + ", a12 " + q16(m.a12.raw()) + ", a21 " +
                              q16(m.a21.raw()) + ", a22 " + q16(m.a22.raw()) + ", offset (" +
                              std::to_string(m.bx) + ", " + std::to_string(m.by) + ") pixels" +
                              (m == hal::PipelineMapping::reduction(m.xmax, m.ymax)
                                   ? " (plain reduction of the camera frame)"
                                   : ""));
  row("preprocessing", preprocessing_name(c.preprocess.method));
  row("PN patches", std::to_string(p.patch_width) + "x" + std::to_string(p.patch_height) +
                        " pixels, epsilon " + shortest_decimal(p.epsilon.raw(), 8) +
                        " grey levels, gain " + shortest_decimal(p.gain.raw(), 8) +
                        " grey levels per standard deviation");
  row("sequence length", std::to_string(c.sequence.seq_len) + " places (S)");
  row("window", std::to_string(c.sequence.window) + " places (W; 0 = no local normalisation)");
  row("exclusion", std::to_string(c.sequence.exclusion) + " places (R)");
  row("threshold", shortest_decimal(c.sequence.threshold.raw(), 16) +
                       " (localised when the confidence is below it)");
  row("sigma min", shortest_decimal(c.sequence.sigma_min.raw(), 8) + " grey levels");
  row("max shift", std::to_string(c.max_shift) + " pixels");
  row("recent exclusion", std::to_string(c.recent_exclusion) + " places");
  row("matcher", c.matcher == LocaliserMatcher::kHeuristic
                     ? "heuristic (greedy: k candidates from each sequence's first place, "
                       "followed over S places; disjoint sequences)"
                     : "diagonal (a sequence ending at every place)");
  row("heuristic", "k " + std::to_string(c.heuristic.candidates) + " candidates, guard " +
                       std::to_string(c.heuristic.guard) + " places, candidate threshold " +
                       shortest_decimal(c.heuristic.threshold.raw(), 8) +
                       " grey levels per pixel, first scan " + heuristic_scan_text(c.heuristic) +
                       (c.matcher == LocaliserMatcher::kHeuristic ? "" : " (not used)"));
  const RouteSearchConfig& r = c.route;
  const std::string unused = route_unused(c);
  row("route window", std::to_string(r.window) + " diagonals around the prediction" + unused);
  row("route slack", std::to_string(r.slack) + " places either side after a fix" + unused);
  row("route growth", shortest_decimal(r.growth.raw(), 8) + " places per place without a fix (" +
                          std::to_string(r.growth.raw()) +
                          "/256 = " + exact_decimal(r.growth.raw(), 8) + ")" + unused);
  row("lost after", std::to_string(r.lost_after) +
                        " places without a fix, then the relocalisation scan" + unused);
  row("scan places", std::to_string(r.scan_places) + " library places per step" + unused);
  const uint16_t scan_len = scan_seq_len(r, c.sequence);
  row("scan seq len",
      std::to_string(r.scan_seq_len) + " steps" +
          (scan_len != r.scan_seq_len ? " (" + std::to_string(scan_len) + " used: at most S)"
                                      : std::string()) +
          unused);
  const bool loop_closure = (c.modes & storage::kModeTeach) != 0 &&
                            (c.modes & storage::kModeRepeat) != 0 && unused.empty();
  row("start", (r.start == -1 ? std::string("unknown (a scan finds the place first)")
                              : "place " + std::to_string(r.start)) +
                   (loop_closure ? " (not used: teach + repeat starts unknown)" : unused));
  row("record colour", c.record_colour ? "yes" : "no");
  row("map grid", "origin (" + grid_origin_metres(c) + ") m, " + std::to_string(c.grid_width) +
                      "x" + std::to_string(c.grid_height) + " cells of " +
                      std::to_string(c.grid_cell_mm) + " mm" +
                      ((c.modes & storage::kModeExplore) != 0 ? "" : " (explore only; not used)"));
  row("odometry",
      std::to_string(w.ticks_per_revolution) + " ticks/revolution, circumference left " +
          shortest_decimal(w.circumference_left.raw(), 32) + " m, right " +
          shortest_decimal(w.circumference_right.raw(), 32) + " m, track width " +
          shortest_decimal(w.track_width.raw(), 32) + " m, " + std::to_string(w.counter_bits) +
          "-bit counters, at most " + std::to_string(w.max_ticks_per_update) + " ticks per update");
  const std::string options = as_options(c);
  std::printf("options: %s\n",
              options.empty() ? "(not expressible: mapping, PN patches or odometry differ from "
                                "the defaults)"
                              : options.c_str());
  return kExitOk;
}

}  // namespace

std::string run_config_summary(const storage::RunConfig& c) {
  std::string s = "modes " + modes_text(c.modes, ",") + ", trigger " + trigger_name(c.trigger);
  if (c.trigger == storage::TriggerMode::kDistance) {
    s += " every " + shortest_decimal(c.spacing.raw(), 32) + " m";
  }
  s += ", " + std::to_string(c.mapping.xmax) + "x" + std::to_string(c.mapping.ymax) + ", " +
       preprocessing_name(c.preprocess.method) + ", S=" + std::to_string(c.sequence.seq_len) +
       " W=" + std::to_string(c.sequence.window) + " R=" + std::to_string(c.sequence.exclusion) +
       ", threshold " + shortest_decimal(c.sequence.threshold.raw(), 16);
  if ((c.modes & storage::kModeExplore) != 0) {
    s += ", map origin (" + grid_origin_metres(c) + ") m " + std::to_string(c.grid_width) + "x" +
         std::to_string(c.grid_height) + " cells of " + std::to_string(c.grid_cell_mm) + " mm";
  }
  // The diagonal matcher is the default and stays implicit, so the line of every existing
  // configuration is unchanged.
  if (c.matcher == LocaliserMatcher::kHeuristic) {
    s += ", heuristic matcher k=" + std::to_string(c.heuristic.candidates) +
         " guard=" + std::to_string(c.heuristic.guard) + " candidate threshold " +
         shortest_decimal(c.heuristic.threshold.raw(), 8);
    if (c.heuristic.scan_places != storage::RunConfig{}.heuristic.scan_places)
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

  const storage::RunConfig d;
  auto w = std::make_shared<WriteOptions>();
  CLI::App* write = config->add_subcommand(
      "write",
      "Write a run configuration into volume file 'config'; unset options take the "
      "defaults shown");
  write->add_option("IMAGE", w->image, "Disk image file with a volume file 'config' (modified)")
      ->required();
  write
      ->add_option("--modes", w->modes,
                   "What the firmware does, any combination separated by commas: teach (build "
                   "and store the library), repeat (localise against it), record (write a dream "
                   "recording), explore (teach + repeat against the run's own places, and "
                   "mapping: pose graph, loop closures, occupancy grid; saves 'map', 'graph' "
                   "and the run's 'state'), continue (explore, continuing the run saved on the "
                   "card: its library and 'state'; the replay must hold the saved run and "
                   "what follows). Default " +
                       modes_text(d.modes, ","))
      ->delimiter(',')
      ->type_name("MODE,...")
      ->check(CLI::IsMember({"teach", "repeat", "record", "explore", "continue"}));
  write
      ->add_option("--trigger", w->trigger,
                   std::string("When an image becomes a place: distance (every --spacing metres "
                               "of odometry) or every-frame (every recorded frame; recordings "
                               "without odometry). Default ") +
                       trigger_name(d.trigger))
      ->type_name("MODE")
      ->check(CLI::IsMember({"distance", "every-frame"}));
  write
      ->add_option("--size", w->size,
                   "Image size in pixels after the FPGA's reduction of the 346x271 camera frame, "
                   "W * H <= 512 (sets the pipeline mapping). Default " +
                       std::to_string(d.mapping.xmax) + "x" + std::to_string(d.mapping.ymax))
      ->type_name("WxH")
      ->check(CLI::Validator(
          [](std::string& s) {
            uint16_t a = 0;
            uint16_t b = 0;
            return parse_image_size(s, &a, &b);
          },
          ""));
  write
      ->add_option("--preprocess", w->preprocess,
                   std::string("Preprocessing: none, he (histogram equalisation), pn (patch "
                               "normalisation), igk (inverse gamma), he-pn, igk-pn, igk-he. "
                               "Default ") +
                       preprocessing_name(d.preprocess.method))
      ->type_name("METHOD")
      ->check(CLI::IsMember(preprocessing_names()));
  w->seq_len_opt = write->add_option(
      "--seq-len", w->seq_len,
      "Sequence length S in places. The firmware's diagonal matcher holds at most " +
          std::to_string(app::kMaxSeqLen) + " (app::kMaxSeqLen; the heuristic up to " +
          std::to_string(kMaxSeqLen) + "). Default " + std::to_string(d.sequence.seq_len));
  w->seq_len_opt->type_name("S")->check(tools::whole<int>(1, kMaxSeqLen));
  w->window_opt = write->add_option(
      "--window", w->window,
      "Local normalisation window W in library places (0 = off, else 2.." +
          std::to_string(kMaxWindow) + "; the firmware's route search at most " +
          std::to_string(app::kMaxNormWindow) + "). Default " + std::to_string(d.sequence.window));
  w->window_opt->type_name("W")->check(tools::whole<int>(0, kMaxWindow));
  w->exclusion_opt =
      write->add_option("--exclusion", w->exclusion,
                        "Runner-up exclusion radius R in places around the best match (the "
                        "firmware's route search at most " +
                            std::to_string(app::kMaxExclusion) + "). Default " +
                            std::to_string(d.sequence.exclusion));
  w->exclusion_opt->type_name("R")->check(tools::whole<int>(0, 65535));
  write
      ->add_option("--threshold", w->threshold,
                   "Confidence threshold C (0..1): a match is accepted when best cost / "
                   "runner-up cost is below it. Default " +
                       shortest_decimal(d.sequence.threshold.raw(), 16))
      ->type_name("C")
      ->check(CLI::Validator([](std::string& s) { return check_threshold(s); }, ""));
  write
      ->add_option("--sigma-min", w->sigma_min,
                   "Smallest standard deviation used by the local normalisation, in grey "
                   "levels (> 0 when the window is on). Default " +
                       shortest_decimal(d.sequence.sigma_min.raw(), 8))
      ->type_name("G")
      ->check(CLI::Validator([](std::string& s) { return check_sigma(s); }, ""));
  w->max_shift_opt = write->add_option(
      "--max-shift", w->max_shift,
      "Horizontal shift tolerance of the image difference in pixels (0 = plain MAD; smaller "
      "than the image width; the firmware's route search takes 0). Default " +
          std::to_string(d.max_shift));
  w->max_shift_opt->type_name("N")->check(tools::whole<int>(0, 255));
  w->recent_opt = write->add_option(
      "--recent-exclusion", w->recent_exclusion,
      "Loop closure (teach + repeat): the newest places not matched against. Default " +
          std::to_string(d.recent_exclusion));
  w->recent_opt->type_name("N")->check(tools::whole<int>(1, 65535));
  write
      ->add_option("--spacing", w->spacing,
                   "Distance trigger spacing in metres of odometry, above 0 and at most " +
                       shortest_decimal(SpatialTrigger::kMaxSpacing.raw(), 32) + ". Default " +
                       shortest_decimal(d.spacing.raw(), 32))
      ->type_name("METRES")
      ->check(CLI::Validator([](std::string& s) { return check_spacing(s); }, ""));
  write
      ->add_option("--matcher", w->matcher,
                   std::string("Sequence matcher: diagonal (every sequence ending at each place) "
                               "or heuristic (the 2015 thesis's greedy Algorithm 1: k candidates "
                               "from each sequence's first place, followed over S places; its "
                               "costs are raw distance sums, so tune --threshold for it). A "
                               "firmware built without the heuristic refuses it at start. "
                               "Default ") +
                       matcher_name(d.matcher))
      ->type_name("NAME")
      ->check(CLI::IsMember({"diagonal", "heuristic"}));
  w->candidates_opt = write->add_option(
      "--k", w->candidates,
      "Heuristic: candidates followed. Default " + std::to_string(d.heuristic.candidates));
  w->candidates_opt->type_name("K")->check(tools::whole<int>(1, kMaxHeuristicCandidates));
  w->guard_opt = write->add_option(
      "--guard", w->guard,
      "Heuristic: guard window in places. Default " + std::to_string(d.heuristic.guard));
  w->guard_opt->type_name("N")->check(tools::whole<int>(1, 65535));
  w->heuristic_scan_places_opt = write->add_option(
      "--heuristic-scan-places", w->heuristic_scan_places,
      "Heuristic: library places its first scan of a sequence compares a step (0: the whole "
      "library in the sequence's first step). The head board spreads it to keep every step "
      "within its budget (docs/firmware.md). Default " +
          std::to_string(d.heuristic.scan_places));
  w->heuristic_scan_places_opt->type_name("N")->check(tools::whole<int>(0, 65535));
  write
      ->add_option("--candidate-threshold", w->candidate_threshold,
                   "Heuristic: a first-place distance must be below this many grey levels per "
                   "pixel to become a candidate (0..255). Default " +
                       shortest_decimal(d.heuristic.threshold.raw(), 8))
      ->type_name("G")
      ->check(CLI::Validator([](std::string& s) { return check_candidate_threshold(s); }, ""));
  // The route search (route_search.h): what the firmware's teach / repeat run with the
  // diagonal matcher; check_localiser_config checks the combination.
  const RouteSearchConfig& dr = d.route;
  w->route_window_opt = write->add_option(
      "--route-window", w->route_window,
      "Route search: diagonals the window keeps around the odometry's prediction (odd, at least "
      "2 R + 3; the firmware holds at most " +
          std::to_string(app::kWindowSlots) + "). Default " + std::to_string(dr.window));
  w->route_window_opt->type_name("N")->check(tools::whole<int>(0, 65535));
  w->route_slack_opt = write->add_option(
      "--route-slack", w->route_slack,
      "Route search: places either side of the prediction the answer may be right after a fix. "
      "Default " +
          std::to_string(dr.slack));
  w->route_slack_opt->type_name("N")->check(tools::whole<int>(0, 65535));
  write
      ->add_option("--route-growth", w->route_growth,
                   "Route search: places the search radius grows by per place travelled without "
                   "a fix (odometry drift along the route, e.g. 0.05 = 5 %), a decimal stored in "
                   "steps of 1/256 (0..255.99). Default " +
                       shortest_decimal(dr.growth.raw(), 8))
      ->type_name("X")
      ->check(CLI::Validator(
          [](std::string& v) {
            UQ8_8 ignored;
            return parse_route_growth(v, &ignored);
          },
          ""));
  w->lost_after_opt = write->add_option(
      "--lost-after", w->lost_after,
      "Route search: places without a fix before the relocalisation scan starts. Default " +
          std::to_string(dr.lost_after));
  w->lost_after_opt->type_name("N")->check(tools::whole<int>(1, 65535));
  w->scan_places_opt = write->add_option(
      "--scan-places", w->scan_places,
      "Route search: library places the relocalisation scan streams per step. Default " +
          std::to_string(dr.scan_places));
  w->scan_places_opt->type_name("N")->check(tools::whole<int>(1, 65535));
  w->scan_seq_len_opt = write->add_option(
      "--scan-seq-len", w->scan_seq_len,
      "Route search: the relocalisation scan's sequence length in steps (S if longer; the "
      "firmware holds at most " +
          std::to_string(app::kMaxScanSeqLen) + "). Default " + std::to_string(dr.scan_seq_len));
  w->scan_seq_len_opt->type_name("N")->check(tools::whole<int>(1, 65535));
  write
      ->add_option("--start", w->start,
                   "Route search, repeat mode: the library place the run starts at, or unknown "
                   "(nothing is localised until a scan has found the place; teach + repeat "
                   "always starts unknown). Default " +
                       start_text(dr.start))
      ->type_name("PLACE|unknown")
      ->check(CLI::Validator(
          [](std::string& v) {
            int32_t ignored = 0;
            return parse_route_start(v, &ignored);
          },
          ""));
  write
      ->add_option("--wheels", w->wheels,
                   "The wheel constants: left and right circumference and track width, metres "
                   "(e.g. calibrated: seqslam slam --calibration-out). Default " +
                       shortest_decimal(d.odometry.circumference_left.raw(), 32) + "," +
                       shortest_decimal(d.odometry.circumference_right.raw(), 32) + "," +
                       shortest_decimal(d.odometry.track_width.raw(), 32))
      ->type_name("LEFT,RIGHT,TRACK");
  write
      ->add_option("--grid-origin", w->grid_origin,
                   "Explore: the map's lower-left corner in the odometry frame (the run starts "
                   "at 0,0 heading along +x), metres to the millimetre. Default " +
                       grid_origin_metres(d))
      ->type_name("X,Y");
  write
      ->add_option("--grid-size", w->grid_size,
                   "Explore: the map's size in cells (each 1..32768). Default " +
                       std::to_string(d.grid_width) + "x" + std::to_string(d.grid_height))
      ->type_name("WxH");
  w->grid_cell_opt = write->add_option(
      "--grid-cell", w->grid_cell,
      "Explore: the map's cell side in millimetres. Default " + std::to_string(d.grid_cell_mm));
  w->grid_cell_opt->type_name("MM")->check(tools::whole<int>(10, 1000));
  write->add_flag("--record-colour", w->record_colour,
                  "Record mode: store the YUV 4:2:2 colour frame with each place (default: "
                  "grey only)");
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
