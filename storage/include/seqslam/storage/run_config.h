// The run configuration: what the firmware does and with which settings, and THE table of
// those settings. Every setting is listed once, in the table below (visit_run_settings() and
// the sections it calls, one per card format version), with its name,
// the field it sets, its range, the card format version that carries it, where it is used and
// its help text; the field's type gives its number format (the Q format of a Fixed, degrees
// of an Angle, the names of an enum). Everything else is derived from that list:
//   - the card's codec (run_files.cpp: write_run_config / read_run_config), in list order;
//   - the check of a configuration read from the card or given on a command line
//     (check_run_settings: the ranges, then the core's own checks and the build's limits);
//   - on the PC, every subcommand's options, `config show` and `config write`
//     (tools/seqslam/settings_cli.cpp).
// A new setting is one entry here plus its use. The table is a visitor (as state_io.h's
// components list their state): V is called as v(field, Setting) for every setting and
// v.pad(bytes) for the card's reserved bytes. Help texts are SEQSLAM_HELP(...) and vanish
// from a build without message texts (the head board), whose visitors use the ranges only.
#pragma once

#include <stdint.h>

#include "seqslam/explorer.h"
#include "seqslam/hal/pixel_buffer.h"
#include "seqslam/localiser.h"
#include "seqslam/messages.h"
#include "seqslam/occupancy_grid.h"
#include "seqslam/odometry.h"
#include "seqslam/spatial_trigger.h"

// The table's visitors are inlined into each use, so a visitor that reads only the ranges
// (the card's codec and check) leaves every name and help text out of the image.
#define SEQSLAM_SETTINGS_INLINE __attribute__((always_inline)) inline

// The settings a card does not carry (kPcOnly below: the slope matcher's and the explorer's)
// exist only where they are used, in the PC's builds; the head board's RunConfig leaves them
// out (it runs neither, and its RAM and code are counted).
#ifndef SEQSLAM_PC_SETTINGS
#define SEQSLAM_PC_SETTINGS 1
#endif

#if SEQSLAM_MESSAGE_TEXTS
#define SEQSLAM_HELP(text) text
#else
#define SEQSLAM_HELP(text) nullptr
#endif

namespace seqslam::storage {

enum RunMode : uint8_t {
  kModeTeach = 1u << 0,     // build the library from this run and store it
  kModeRepeat = 1u << 1,    // localise against the stored library (with kModeTeach: against this
                            // run's own earlier places - loop closure - while building it)
  kModeRecord = 1u << 2,    // write this run as a dream recording
  kModeExplore = 1u << 3,   // with kModeTeach and kModeRepeat (required): also build the pose
                            // graph, close loops and build the occupancy grid (map, graph files)
  kModeContinue = 1u << 4,  // with kModeExplore (required): continue the explore run saved on
                            // the card (library, `state` file) instead of starting a new one
};
inline constexpr uint8_t kAllModes =
    kModeTeach | kModeRepeat | kModeRecord | kModeExplore | kModeContinue;

enum class TriggerMode : uint8_t {
  kDistance = 0,    // a capture every `spacing` metres of odometry (the robot)
  kEveryFrame = 1,  // every recorded frame is a place (recordings without odometry)
};

// HeuristicConfig's defaults with the head board's scan budget: 96 library places a step for
// the first image's greedy scan (about 29 ms of a step with the card, docs/firmware.md).
constexpr HeuristicConfig robot_heuristic() {
  HeuristicConfig h;
  h.scan_places = 96;
  return h;
}

// Explore: the occupancy grid's frame (the odometry frame: the run starts at the origin,
// heading along +x) and bounds.
struct MapOrigin {
  int32_t x_mm = -40000;
  int32_t y_mm = -40000;
};
struct MapSize {
  uint16_t width = 1600;  // cells
  uint16_t height = 1600;
};

// Explore: the explorer's own settings (ExplorerConfig's, the rest comes from the run).
struct ExploreSettings {
  LoopClosureConfig gate{};
  EdgeInformation closure_information = ExplorerConfig{}.closure_information;
  UQ16_16 closure_lateral = explorer_graph_config().closure_lateral;
  ClosureAlignConfig align = ExplorerConfig{}.align;
  uint8_t closure_shift = ExplorerConfig{}.max_shift;
  Angle hfov = ExplorerConfig{}.hfov;
  uint32_t optimise_budget = ExplorerConfig{}.optimise_budget;
};

struct RunConfig {
  uint8_t modes = kModeRepeat;
  TriggerMode trigger = TriggerMode::kDistance;
  // The image size and preprocessing are the core's defaults (LocaliserConfig: 12x10, HE then
  // PN, chosen on every real pair; docs/accuracy.md, "Choosing the defaults").
  hal::PipelineMapping mapping = hal::PipelineMapping::reduction(
      LocaliserConfig{}.image_size.width, LocaliserConfig{}.image_size.height);
  PreprocessConfig preprocess = LocaliserConfig{}.preprocess;
  SequenceConfig sequence{};
  uint8_t max_shift = 0;
  uint16_t recent_exclusion = 50;
  OdometryConfig odometry{};
  Q31_32 spacing = Q31_32::from_ratio(1, 5);
  bool record_colour = false;
  LocaliserMatcher matcher = LocaliserMatcher::kDiagonal;
  // Candidates (k), candidate threshold, guard and the scan's budget are settings; seq_len and
  // exclusion are not (the heuristic uses sequence.seq_len and sequence.exclusion, see
  // LocaliserConfig).
  HeuristicConfig heuristic = robot_heuristic();
#if SEQSLAM_PC_SETTINGS
  // The slope matcher's velocities (its `seq` is not used: `sequence` is).
  SlopeConfig slope{};
#endif
  // Explore: 80 m x 80 m of 5 cm cells centred on the start by default.
  MapOrigin grid_origin{};
  uint16_t grid_cell_mm = 50;
  MapSize grid_size{};
  // The route search (teach / repeat with the diagonal matcher; route_search.h). Its start
  // place is used in repeat mode; teach + repeat (loop closure) always starts unknown.
  RouteSearchConfig route{};
#if SEQSLAM_PC_SETTINGS
  ExploreSettings explore{};
#endif

  // The occupancy grid these settings amount to (log-odds settings: GridConfig's defaults).
  GridConfig grid() const {
    GridConfig g;
    g.origin_x = Q31_32::from_ratio(grid_origin.x_mm, 1000);
    g.origin_y = Q31_32::from_ratio(grid_origin.y_mm, 1000);
    g.cell_mm = grid_cell_mm;
    g.width = grid_size.width;
    g.height = grid_size.height;
    return g;
  }

  // The localiser configuration these settings amount to.
  LocaliserConfig localiser() const {
    LocaliserConfig c;
    c.image_size = mapping.size();
    c.preprocess = preprocess;
    c.max_shift = max_shift;
    c.sequence = sequence;
    c.recent_exclusion = recent_exclusion;
    c.matcher = matcher;
    c.heuristic = heuristic;
    c.route = route;
#if SEQSLAM_PC_SETTINGS
    c.slope = slope;
#endif
    return c;
  }

  // The explorer configuration these settings amount to (the sensors and storage come from
  // the run).
  ExplorerConfig explorer() const {
    ExplorerConfig e;
#if SEQSLAM_PC_SETTINGS
    e.gate = explore.gate;
    e.graph.closure_lateral = explore.closure_lateral;
    e.grid = grid();
    e.closure_information = explore.closure_information;
    e.align = explore.align;
    e.max_shift = explore.closure_shift;
    e.hfov = explore.hfov;
    e.optimise_budget = explore.optimise_budget;
#endif
    e.recent_exclusion = recent_exclusion;
    e.spacing = spacing;
    return e;
  }
};

// ---------------------------------------------------------------------------------------
// The settings table.

// Where a setting is used: which subcommands offer it, and which runs `config show` marks it
// "not used" for.
enum SettingScope : uint16_t {
  kScopeRun = 1u << 0,        // the firmware's run: modes, trigger, spacing, wheels, recording
  kScopeImage = 1u << 1,      // the image: size and preprocessing
  kScopeSequence = 1u << 2,   // the sequence matchers: S, W, R, threshold, sigma min
  kScopeDifference = 1u << 3, // the image difference (max shift)
  kScopeMatcher = 1u << 4,    // which sequence matcher
  kScopeHeuristic = 1u << 5,  // the heuristic matcher's own settings
  kScopeRoute = 1u << 6,      // the route search (the head board's teach / repeat)
  kScopeLoop = 1u << 7,       // loop closure in one run (teach + repeat, explore)
  kScopeMap = 1u << 8,        // explore: the occupancy grid
  kScopeExplore = 1u << 9,    // explore: the gate, closure edges, alignment, optimiser
  kScopeSlope = 1u << 10,     // the slope matcher's velocities
};

// How a setting reads and prints beyond what its field's type says.
enum class SettingFormat : uint8_t {
  kAuto = 0,   // by the field's type: a whole number, a Fixed as an exact decimal, an Angle in
               // degrees, an enum by names[], a bool as a switch, the composites below
  kFlags,      // a bit set, the names of its bits (names[bit]) separated by commas
  kPlace,      // a place index, or -1 written "unknown"
};

struct Setting {
  const char* name = nullptr;  // "seq-len": the option --seq-len, the config show row
  int64_t min = 0;             // the range of the raw value (a Fixed's raw, an Angle's bam)
  int64_t max = 0;
  uint8_t since = 1;           // the card format version that added it; kPcOnly: not on it
  uint16_t scope = 0;          // SettingScope bits
  SettingFormat format = SettingFormat::kAuto;
  const char* const* names = nullptr;  // enums and flags: the name of each value / bit
  uint8_t name_count = 0;
  const char* unit = nullptr;  // after the value in config show ("places", "m")
  const char* help = nullptr;  // SEQSLAM_HELP(...)

  SEQSLAM_SETTINGS_INLINE constexpr Setting with_names(const char* const* n, uint8_t count) const {
    Setting s = *this;
    s.names = n;
    s.name_count = count;
    return s;
  }
  SEQSLAM_SETTINGS_INLINE constexpr Setting in(const char* u) const {
    Setting s = *this;
    s.unit = u;
    return s;
  }
  SEQSLAM_SETTINGS_INLINE constexpr Setting as(SettingFormat f) const {
    Setting s = *this;
    s.format = f;
    return s;
  }
};

// A setting over raw values [min, max], used by `scope`, on the card since `since`.
SEQSLAM_SETTINGS_INLINE constexpr Setting setting(const char* name, int64_t min, int64_t max,
                                                  uint16_t scope, uint8_t since,
                                                  const char* help) {
  Setting s;
  s.name = name;
  s.min = min;
  s.max = max;
  s.scope = scope;
  s.since = since;
  s.help = help;
  return s;
}

// The card format this build writes (the largest `since` below); run_files.h's log kind.
inline constexpr uint16_t kRunConfigVersion = 4;
// `since` of a setting the card does not carry: the PC tools take it as an option, the
// firmware runs its default.
inline constexpr uint8_t kPcOnly = 0;

inline constexpr const char* kModeNames[] = {"teach", "repeat", "record", "explore", "continue"};
inline constexpr const char* kTriggerNames[] = {"distance", "every-frame"};
inline constexpr const char* kMatcherNames[] = {"diagonal", "heuristic", "slope"};

namespace detail {
constexpr int64_t metres(int64_t m) {
  return Q31_32::from_int(m).raw();
}
constexpr int64_t degrees(int64_t d) {
  return Angle::from_degrees(d).bam;
}
constexpr int64_t uq16(int64_t v) {
  return UQ16_16::from_int(v).raw();
}
}  // namespace detail

// Version 1: the run, the image, the sequence, the odometry and the trigger.
template <class V, class C>
SEQSLAM_SETTINGS_INLINE constexpr void visit_base_settings(V& v, C& c) {
  constexpr uint16_t kCore = kScopeSequence;
  using detail::uq16;
  v(c.modes,
    setting("modes", 1, kAllModes, kScopeRun, 1,
            SEQSLAM_HELP("What the firmware does, any combination separated by commas: teach "
                         "(build and store the library), repeat (localise against it), record "
                         "(write a dream recording), explore (teach + repeat against the run's "
                         "own places, and mapping: pose graph, loop closures, occupancy grid; "
                         "saves 'map', 'graph' and the run's 'state'), continue (explore, "
                         "continuing the run saved on the card: its library and 'state'; the "
                         "replay must hold the saved run and what follows)"))
        .with_names(kModeNames, 5)
        .as(SettingFormat::kFlags));
  v(c.trigger, setting("trigger", 0, 1, kScopeRun, 1,
                       SEQSLAM_HELP("When an image becomes a place: distance (every --spacing "
                                    "metres of odometry) or every-frame (every recorded frame; "
                                    "recordings without odometry)"))
                   .with_names(kTriggerNames, 2));
  v(c.max_shift, setting("max-shift", 0, 255, kScopeDifference, 1,
                         SEQSLAM_HELP("Horizontal shift tolerance of the image difference "
                                      "(0 = plain MAD; smaller than the image width; the "
                                      "firmware's route search takes 0)"))
                     .in("pixels"));
  v(c.record_colour, setting("record-colour", 0, 1, kScopeRun, 1,
                             SEQSLAM_HELP("Record mode: store the YUV 4:2:2 colour frame with "
                                          "each place (default: grey only)")));
  v(c.mapping,
    setting("size", 1, hal::kPixelBufferCapacity, kScopeImage, 1,
            SEQSLAM_HELP("Image size WxH in pixels after the FPGA's reduction of the 346x271 "
                         "camera frame, W * H <= 512 (the pixel buffer; sets the pipeline "
                         "mapping)"))
        .in("pixels"));
  v(c.preprocess, setting("preprocess", 0, 6, kScopeImage, 1,
                          SEQSLAM_HELP("Preprocessing: none, he (histogram equalisation), pn "
                                       "(patch normalisation), igk (inverse gamma), he-pn, "
                                       "igk-pn, igk-he")));
  v(c.sequence.seq_len, setting("seq-len", 1, kMaxSeqLen, kCore, 1,
                                SEQSLAM_HELP("Sequence length S in places"))
                            .in("places"));
  v(c.sequence.window,
    setting("window", 0, kMaxWindow, kCore, 1,
            SEQSLAM_HELP("Local normalisation window W in library places (0 = off, else 2..255)"))
        .in("places"));
  v(c.sequence.sigma_min,
    setting("sigma-min", 0, UQ8_8::max().raw(), kCore, 1,
            SEQSLAM_HELP("Smallest standard deviation the local normalisation uses, in grey "
                         "levels (> 0 when the window is on)"))
        .in("grey levels"));
  v(c.sequence.exclusion,
    setting("exclusion", 0, 65535, kCore, 1,
            SEQSLAM_HELP("Runner-up exclusion radius R in places around the best match"))
        .in("places"));
  v(c.sequence.threshold,
    setting("threshold", 0, uq16(1), kCore, 1,
            SEQSLAM_HELP("Confidence threshold C (0..1): a match is accepted when best cost / "
                         "runner-up cost is below it")));
  v(c.recent_exclusion,
    setting("recent-exclusion", 1, 65535, kScopeLoop, 1,
            SEQSLAM_HELP("Loop closure (teach + repeat, explore): the newest places not "
                         "matched against"))
        .in("places"));
  v.pad(2);
  v(c.odometry, setting("wheels", 0, 0, kScopeRun, 1,
                        SEQSLAM_HELP("The wheel constants LEFT,RIGHT,TRACK: left and right "
                                     "circumference and track width, metres (e.g. calibrated: "
                                     "seqslam slam --calibration-out)")));
  v(c.spacing, setting("spacing", 1, SpatialTrigger::kMaxSpacing.raw(), kScopeRun, 1,
                       SEQSLAM_HELP("Distance trigger spacing in metres of odometry"))
                   .in("m"));
}

// Version 2: the sequence matcher.
template <class V, class C>
SEQSLAM_SETTINGS_INLINE constexpr void visit_matcher_settings(V& v, C& c) {
  v(c.matcher, setting("matcher", 0, 2, kScopeMatcher, 2,
                       SEQSLAM_HELP("Sequence matcher: diagonal (a sequence ending at every "
                                    "place: spatially sampled runs), heuristic (the 2015 "
                                    "thesis's greedy Algorithm 1: k candidates from each "
                                    "sequence's first place, followed over S places; its costs "
                                    "are raw distance sums, so tune --threshold for it) or "
                                    "slope (OpenSeqSLAM's velocity search, for time-sampled "
                                    "runs; not in the firmware)"))
                   .with_names(kMatcherNames, 3));
  v.pad(1);
  v(c.heuristic.candidates, setting("k", 1, kMaxHeuristicCandidates, kScopeHeuristic, 2,
                                    SEQSLAM_HELP("Heuristic: candidates followed")));
  v(c.heuristic.guard, setting("guard", 1, 65535, kScopeHeuristic, 2,
                               SEQSLAM_HELP("Heuristic: guard window in places"))
                           .in("places"));
  v(c.heuristic.threshold,
    setting("candidate-threshold", 0, 255 * 256, kScopeHeuristic, 2,
            SEQSLAM_HELP("Heuristic: a first-place distance must be below this many grey "
                         "levels per pixel to become a candidate"))
        .in("grey levels per pixel"));
}

// Version 3: the explore mode's map.
template <class V, class C>
SEQSLAM_SETTINGS_INLINE constexpr void visit_map_settings(V& v, C& c) {
  v(c.grid_origin,
    setting("grid-origin", -2000000000, 2000000000, kScopeMap, 3,
            SEQSLAM_HELP("Explore: the map's lower-left corner X,Y in the odometry frame (the "
                         "run starts at 0,0 heading along +x), metres to the millimetre"))
        .in("m"));
  v(c.grid_cell_mm, setting("grid-cell", 10, 1000, kScopeMap, 3,
                            SEQSLAM_HELP("Explore: the map's cell side in millimetres"))
                        .in("mm"));
  v(c.grid_size, setting("grid-size", 1, kMaxGridSide, kScopeMap, 3,
                         SEQSLAM_HELP("Explore: the map's size WxH in cells"))
                     .in("cells"));
  v.pad(2);
}

// Version 4: the route search.
template <class V, class C>
SEQSLAM_SETTINGS_INLINE constexpr void visit_route_settings(V& v, C& c) {
  v(c.route.window,
    setting("route-window", 0, 65535, kScopeRoute, 4,
            SEQSLAM_HELP("Route search: diagonals the window keeps around the odometry's "
                         "prediction (odd, at least 2 R + 3)"))
        .in("diagonals"));
  v(c.route.slack, setting("route-slack", 0, 65535, kScopeRoute, 4,
                           SEQSLAM_HELP("Route search: places either side of the prediction "
                                        "the answer may be right after a fix"))
                       .in("places"));
  v(c.route.growth,
    setting("route-growth", 0, UQ8_8::max().raw(), kScopeRoute, 4,
            SEQSLAM_HELP("Route search: places the search radius grows by per place travelled "
                         "without a fix (odometry drift along the route, e.g. 0.05 = 5 %)"))
        .in("places per place"));
  v(c.route.lost_after, setting("lost-after", 1, 65535, kScopeRoute, 4,
                                SEQSLAM_HELP("Route search: places without a fix before a "
                                             "confirmed scan may move the prediction"))
                            .in("places"));
  v(c.route.scan_places, setting("scan-places", 1, 65535, kScopeRoute, 4,
                                 SEQSLAM_HELP("Route search: library places the "
                                              "relocalisation scan streams per step, "
                                              "between places"))
                             .in("places"));
  v(c.route.scan_seq_len, setting("scan-seq-len", 1, 65535, kScopeRoute, 4,
                                  SEQSLAM_HELP("Route search: the relocalisation scan's "
                                               "sequence length (S if longer)"))
                              .in("steps"));
  v(c.route.start, setting("start", -1, 2147483647, kScopeRoute, 4,
                           SEQSLAM_HELP("Route search, repeat mode: the library place the run "
                                        "starts at, or unknown (nothing is localised until a "
                                        "scan has found the place; teach + repeat always "
                                        "starts unknown)"))
                       .as(SettingFormat::kPlace));
  v(c.heuristic.scan_places,
    setting("heuristic-scan-places", 0, 65535, kScopeHeuristic, 4,
            SEQSLAM_HELP("Heuristic: library places its first scan of a sequence compares a "
                         "step (0: the whole library in the sequence's first step); the head "
                         "board spreads it to keep every step within its budget"))
        .in("places"));
  v.pad(2);
}

#if SEQSLAM_PC_SETTINGS
// Not on the card: the slope matcher's and the explorer's.
template <class V, class C>
SEQSLAM_SETTINGS_INLINE constexpr void visit_pc_settings(V& v, C& c) {
  using detail::degrees;
  using detail::metres;
  using detail::uq16;
  // The route search's rules for fixes and jumps: not on the card (the firmware runs their
  // defaults, chosen on the simulator: docs/accuracy.md).
  v(c.route.jump_steps, setting("jump-steps", 1, 65535, kScopeRoute, kPcOnly,
                                SEQSLAM_HELP("Route search: steps of evidence a candidate "
                                             "needs before it may win (S if longer)"))
                            .in("steps"));
  v(c.route.jump_ratio,
    setting("jump-ratio", 0, uq16(1), kScopeRoute, kPcOnly,
            SEQSLAM_HELP("Route search: a candidate wins when its cost over its evidence is "
                         "below this times the prediction's over the same steps")));
  v(c.route.match_level,
    setting("match-level", 0, uq16(4), kScopeRoute, kPcOnly,
            SEQSLAM_HELP("Route search: a candidate no prediction disputes must have a mean "
                         "value over its evidence below this times the normalisation's mean "
                         "(0: no test)")));
  v(c.route.sharpness,
    setting("sharpness", 0, uq16(1), kScopeRoute, kPcOnly,
            SEQSLAM_HELP("Route search: a fix's cost over that of the best diagonal 2..R "
                         "places away must be below this (0: no test)")));
  v(c.route.tail_steps, setting("tail-steps", 0, 65535, kScopeRoute, kPcOnly,
                                SEQSLAM_HELP("Route search: a fix's last steps that must still "
                                             "match (0: no test; S if longer)"))
                            .in("steps"));
  v(c.route.tail_level,
    setting("tail-level", 0, uq16(4), kScopeRoute, kPcOnly,
            SEQSLAM_HELP("Route search: their mean value must be below this times the "
                         "normalisation's mean (1.0: no better than an average place)")));
  // The slope matcher: not on the card (the firmware does not run it).
  v(c.slope.vmin, setting("vmin", UQ8_8::from_ratio(1, 100).raw(), kMaxVelocityRaw, kScopeSlope,
                          kPcOnly, SEQSLAM_HELP("Slope: slowest query/library speed ratio")));
  v(c.slope.vmax, setting("vmax", UQ8_8::from_ratio(1, 100).raw(), kMaxVelocityRaw, kScopeSlope,
                          kPcOnly, SEQSLAM_HELP("Slope: fastest query/library speed ratio")));
  v(c.slope.vsteps, setting("vsteps", 1, kMaxVelocitySteps, kScopeSlope, kPcOnly,
                            SEQSLAM_HELP("Slope: velocities tried between vmin and vmax")));
  // The explorer: not on the card yet (the firmware's explore mode runs their defaults; the PC
  // tools, `seqslam slam`, take them as options).
  auto& g = c.explore.gate;
  constexpr uint16_t kEx = kScopeExplore;
  v(g.drift_base, setting("drift-base", 0, metres(1000), kEx, kPcOnly,
                          SEQSLAM_HELP("Gate: position bound at a fix, metres"))
                      .in("m"));
  v(g.drift_rate, setting("drift-rate", 0, uq16(1), kEx, kPcOnly,
                          SEQSLAM_HELP("Gate: position bound growth per metre driven"))
                      .in("m/m"));
  v(g.heading_base, setting("heading-base", 0, degrees(180), kEx, kPcOnly,
                            SEQSLAM_HELP("Gate: heading bound at a fix, degrees"))
                        .in("deg"));
  v(g.heading_rate, setting("heading-rate", 0, degrees(10), kEx, kPcOnly,
                            SEQSLAM_HELP("Gate: heading bound growth, degrees per metre"))
                        .in("deg/m"));
  v(g.near_radius, setting("near", 0, metres(1000), kEx, kPcOnly,
                           SEQSLAM_HELP("Gate: aliasing radius, metres (plus the drift bound)"))
                       .in("m"));
  v(g.confirm, setting("confirm", 1, 1000, kEx, kPcOnly,
                       SEQSLAM_HELP("Gate: consecutive consistent matches for a closure")));
  v(g.max_advance, setting("max-advance", 0, 1000, kEx, kPcOnly,
                           SEQSLAM_HELP("Gate: matched-place step between matches"))
                       .in("places"));
  v(g.relocalise, setting("relocalise", 0, 1000, kEx, kPcOnly,
                          SEQSLAM_HELP("Gate: confident, self-consistent matches odometry cannot "
                                       "explain before relocalising (0 = never)")));
  v(g.relocalise_support,
    setting("relocalise-support", 1, 1000, kEx, kPcOnly,
            SEQSLAM_HELP("Gate: confident matches that must agree with a proposed "
                         "relocalisation")));
  v(g.relocalise_turn,
    setting("relocalise-turn", 0, degrees(180), kEx, kPcOnly,
            SEQSLAM_HELP("Gate: turn (degrees) the relocalising run must include, seen alike by "
                         "odometry and by the matched places (0 = none)"))
        .in("deg"));
  v(g.relocalise_verify,
    setting("relocalise-verify", 0, metres(1000), kEx, kPcOnly,
            SEQSLAM_HELP("Gate: metres driven after a relocalisation is proposed before it may "
                         "be accepted (0 with --relocalise-support 1: at once)"))
        .in("m"));
  v(g.max_image_rank,
    setting("max-image-rank", 0, uq16(1), kEx, kPcOnly,
            SEQSLAM_HELP("Gate: reject a confident match when more than this fraction of the "
                         "known places are closer to the current image than the matched place "
                         "(1 = never)")));
  auto& e = c.explore;
  v(e.closure_information.xy,
    setting("closure-weight", UQ16_16::from_ratio(1, 1000).raw(), uq16(1000), kEx, kPcOnly,
            SEQSLAM_HELP("Closure edge position information (1 = as sure as 1 m of odometry)")));
  v(e.closure_information.heading, setting("closure-heading-weight", 0, uq16(1000), kEx, kPcOnly,
                                           SEQSLAM_HELP("Closure edge heading information")));
  v(e.closure_lateral,
    setting("closure-lateral", 0, uq16(1), kEx, kPcOnly,
            SEQSLAM_HELP("Closure edge position information across the route (perpendicular to "
                         "the matched place's heading), as a fraction of along it (1 = the "
                         "same)")));
  v(e.closure_shift,
    setting("closure-shift", 0, kMaxSubpixelShift, kEx, kPcOnly,
            SEQSLAM_HELP("Closure heading from the image: columns searched each way for the "
                         "horizontal shift between the two places' images (0 = none: the "
                         "same heading)"))
        .in("columns"));
  v(e.align.length, setting("align-length", 0, kMaxAlignLength, kEx, kPcOnly,
                            SEQSLAM_HELP("Closure alignment along the matched pass: places "
                                         "compared (0 = off: the closure joins the matched "
                                         "place, same position)"))
                        .in("places"));
  v(e.align.max_offset, setting("align-range", 0, kMaxAlignOffset, kEx, kPcOnly,
                                SEQSLAM_HELP("Closure alignment: places searched each way of "
                                             "the matched one"))
                            .in("places"));
  v(e.align.max_shift, setting("align-shift", 0, 16, kEx, kPcOnly,
                               SEQSLAM_HELP("Closure alignment: columns each image pair may be "
                                            "shifted (heading differences)"))
                           .in("columns"));
  v(e.hfov, setting("hfov", degrees(1), degrees(179), kEx, kPcOnly,
                    SEQSLAM_HELP("Effective horizontal field of view, degrees, that turns the "
                                 "image shift into a heading (calibrated on the simulator)"))
                .in("deg"));
  v(e.optimise_budget, setting("budget", 1, 10000000, kEx, kPcOnly,
                               SEQSLAM_HELP("Optimiser work units per place"))
                           .in("work units"));
}

#endif

// THE table. C is RunConfig or const RunConfig. The order is the card's (fields of a later
// format version after those of an earlier one, in the sections above); v.pad(n) marks
// reserved bytes.
template <class V, class C>
SEQSLAM_SETTINGS_INLINE constexpr void visit_run_settings(V& v, C& c) {
  visit_base_settings(v, c);
  visit_matcher_settings(v, c);
  visit_map_settings(v, c);
  visit_route_settings(v, c);
#if SEQSLAM_PC_SETTINGS
  visit_pc_settings(v, c);
#endif
}

// ---------------------------------------------------------------------------------------
// The build's limits.

// What a build of the firmware can run beyond what the table's ranges allow: the sizes its
// static state was made for and its optional features (session/profile.h has the firmware's;
// `seqslam config write` checks with the same ones before writing).
struct RunLimits {
  uint16_t seq_len = 0;       // S of the diagonal matcher (route search, explore's full search)
  uint16_t norm_window = 0;   // W (route search)
  uint16_t exclusion = 0;     // R (route search)
  uint16_t route_window = 0;  // route.window: the route search's diagonals
  uint16_t scan_seq_len = 0;  // the relocalisation scan's sequence (route.scan_seq_len, at most S)
  bool heuristic = false;     // the heuristic matcher is built in
  bool mapping = false;       // explore is built in
  bool slope = false;         // the slope matcher is built in (the PC's tools, not the firmware)
};

// Which setting check_run_config refused, grouped by the status it returns with it.
enum class RunIssue : uint8_t {
  kNone = 0,
  kHeuristicNotBuilt,      // kFailedPrecondition: matcher heuristic, not built in
  kMappingNotBuilt,        // kFailedPrecondition: explore, mapping not built in
  kExploreHeuristic,       // kInvalidArgument: explore with the heuristic matcher
  kRouteMaxShift,          // kInvalidArgument: route search with max_shift not 0
  kSpacingOutOfRange,      // kOutOfRange: spacing <= 0 or above SpatialTrigger::kMaxSpacing
  kSeqLenAboveLimit,       // kOutOfRange: diagonal matcher, sequence.seq_len > seq_len
  kWindowAboveLimit,       // kOutOfRange: route search, sequence.window > norm_window
  kExclusionAboveLimit,    // kOutOfRange: route search, sequence.exclusion > exclusion
  kRouteWindowAboveLimit,  // kOutOfRange: route search, route.window > route_window
  kScanSeqLenAboveLimit,   // kOutOfRange: route search, the scan's sequence > scan_seq_len
  kSlopeNotBuilt,          // kFailedPrecondition: matcher slope, not built in
  kRouteWindowTooNarrow,   // kOutOfRange: route search, route.window < 2 exclusion + 3
};
// A sentence naming the setting and the limit's name (a code "RC<n>" on the board).
const char* run_issue_text(RunIssue issue);

struct RunCheck {
  Status status = Status::kOk;
  RunIssue issue = RunIssue::kNone;
  constexpr bool ok() const { return status == Status::kOk; }
};

// Whether a build with `limits` runs `config` (one that read_run_config accepts): the
// firmware checks this at start, before it opens any file, and `seqslam config write` before
// it writes. The trigger's spacing, the matcher's and explore's features, S for the diagonal
// matcher (the route search and explore's full search) and, where the route search runs (the
// diagonal matcher in teach or repeat mode, not explore), its sizes and plain SAD.
// Inline: the firmware's limits are constants, folded into its copy (the head board's RAM).
SEQSLAM_SETTINGS_INLINE constexpr RunCheck check_run_config(const RunConfig& c, const RunLimits& limits) {
  const bool explore = (c.modes & kModeExplore) != 0;
  if (c.spacing.raw() <= 0 || c.spacing > SpatialTrigger::kMaxSpacing) {
    return {Status::kOutOfRange, RunIssue::kSpacingOutOfRange};
  }
  if (explore && !limits.mapping) return {Status::kFailedPrecondition, RunIssue::kMappingNotBuilt};
  if (c.matcher == LocaliserMatcher::kSlope && !limits.slope) {
    return {Status::kFailedPrecondition, RunIssue::kSlopeNotBuilt};
  }
  if (c.matcher == LocaliserMatcher::kHeuristic) {
    if (!limits.heuristic) return {Status::kFailedPrecondition, RunIssue::kHeuristicNotBuilt};
    if (explore) return {Status::kInvalidArgument, RunIssue::kExploreHeuristic};
    return {};
  }
  if (c.sequence.seq_len > limits.seq_len) {
    return {Status::kOutOfRange, RunIssue::kSeqLenAboveLimit};
  }
  // The route search runs with the diagonal matcher in teach and repeat mode (teach alone
  // configures it too), not in explore (its full search).
  if (explore || (c.modes & (kModeTeach | kModeRepeat)) == 0) return {};
  if (c.sequence.window > limits.norm_window) {
    return {Status::kOutOfRange, RunIssue::kWindowAboveLimit};
  }
  if (c.sequence.exclusion > limits.exclusion) {
    return {Status::kOutOfRange, RunIssue::kExclusionAboveLimit};
  }
  if (c.route.window > limits.route_window) {
    return {Status::kOutOfRange, RunIssue::kRouteWindowAboveLimit};
  }
  // A runner-up more than R places away must fit in the window (the core's own check sees
  // only settings, not whether the route search runs).
  if (c.route.window < 2u * c.sequence.exclusion + 3u) {
    return {Status::kOutOfRange, RunIssue::kRouteWindowTooNarrow};
  }
  // The scan's sequence: the shorter of route.scan_seq_len and S.
  if (c.route.scan_seq_len > limits.scan_seq_len && c.sequence.seq_len > limits.scan_seq_len) {
    return {Status::kOutOfRange, RunIssue::kScanSeqLenAboveLimit};
  }
  if (c.max_shift != 0) return {Status::kInvalidArgument, RunIssue::kRouteMaxShift};
  return {};
}

// What a query history of `steps` steps holds against the route search's relocalisation scan
// (docs/firmware.md): the scan compares the last scan_seq_len steps' images, which must still
// be in the history when it has streamed all `library_places` places, scan_places a step:
// library_places <= (steps - scan_seq_len + 1) x scan_places (measured with the PC firmware:
// 111 places, 16 a step, 10 images: 16 steps complete every scan, 15 abandon every one).
// `scan_seq_len` is the one the scan runs (scan_seq_len(route, sequence)).
enum class QueryFit : uint8_t {
  kFits = 0,
  kTooFewForImages,   // fewer steps than the scan's images: no scan can ever run
  kTooFewForLibrary,  // every scan over this library is abandoned: tracking only
};
SEQSLAM_SETTINGS_INLINE constexpr QueryFit query_history_fit(uint32_t steps, uint16_t scan_seq_len,
                                                            uint32_t library_places,
                                                            uint16_t scan_places) {
  if (steps < scan_seq_len) return QueryFit::kTooFewForImages;
  const uint64_t reach = uint64_t{steps - scan_seq_len + 1u} * scan_places;
  return library_places > reach ? QueryFit::kTooFewForLibrary : QueryFit::kFits;
}

// ---------------------------------------------------------------------------------------
// The check every configuration passes, whatever wrote it.

// What check_run_settings found: the first setting out of its range (its position in the
// table, counting from 0, and its Setting), or a combination the core, the trigger or the
// odometry refuses (setting -1).
struct SettingsCheck {
  Status status = Status::kOk;
  int16_t setting = -1;  // the table position of the setting out of range, or -1
  constexpr bool ok() const { return status == Status::kOk; }
};

// The table's ranges, then what the parts check together: the modes' combinations, the image
// mapping and preprocessing, the odometry, the core's localiser check
// (check_localiser_config) and, with mapping built in, the explorer's gate.
// kOutOfRange (a setting out of range: `setting` says which) or kInvalidArgument.
SettingsCheck check_run_settings(const RunConfig& config);

}  // namespace seqslam::storage
