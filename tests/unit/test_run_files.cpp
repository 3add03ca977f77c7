// The firmware's run configuration on the card (format version 4): round trip of every
// setting including the sequence matcher, the explore mode's grid and the route search, the
// byte layout of the fields added by versions 2, 3 and 4, refusal of other versions (1 to 3
// included), and kDataLoss for stored values the localiser or the grid would refuse.
#include "seqslam/storage/run_files.h"

#include "seqslam/session/profile.h"
#include "seqslam/messages.h"
#include "seqslam/spatial_trigger.h"
#include "seqslam/storage/record_log.h"
#include "storage_fixtures.h"
#include "test.h"

namespace seqslam::storage {
namespace {

constexpr uint32_t kPayloadV1 = 96;   // version 1: up to and including the spacing
constexpr uint32_t kPayloadV2 = 104;  // + matcher, reserved, k, guard, candidate threshold
constexpr uint32_t kPayloadV3 = 120;  // + grid origin x, y (mm), cell, width, height, reserved
constexpr uint32_t kPayloadV4 = 140;  // + route window, slack, growth, lost_after, scan_places,
                                      //   scan_seq_len, start; heuristic scan budget, reserved

test::FakeCard<8> g_card;

RunConfig heuristic_config() {
  RunConfig c;
  c.modes = kModeTeach | kModeRepeat;
  c.mapping = hal::PipelineMapping::reduction(25, 20);
  c.sequence.seq_len = 12;
  c.sequence.exclusion = 4;
  c.max_shift = 2;
  c.recent_exclusion = 33;
  c.matcher = LocaliserMatcher::kHeuristic;
  c.heuristic.candidates = 7;
  c.heuristic.guard = 3;
  c.heuristic.threshold = UQ8_8::from_ratio(71, 2);  // 35.5 grey levels per pixel
  c.heuristic.scan_places = 40;
  return c;
}

// The header payload of the configuration on the card.
uint32_t stored_payload(uint8_t* out) {
  const uint8_t* block = g_card.bytes;
  const uint32_t size = static_cast<uint32_t>(block[10] | block[11] << 8);
  for (uint32_t i = 0; i < size && i < kLogHeaderPayloadMax; ++i)
    out[i] = block[16 + i];
  return size;
}

// Writes a log header of the configuration's kind (or `kind`) with an arbitrary payload, as a
// damaged or foreign writer would (with a valid checksum).
void write_raw(const uint8_t* payload, uint32_t size, const LogKind& kind = kRunConfigKind) {
  LogWriter w;
  ASSERT_EQ(w.create(g_card.device, kind, payload, size), Status::kOk);
}

TEST(RunConfig, RoundTripOfEverySettingIncludingTheMatcher) {
  g_card.reset();
  RunConfig c = heuristic_config();
  ASSERT_EQ(write_run_config(g_card.device, c), Status::kOk);
  RunConfig r;
  ASSERT_EQ(read_run_config(g_card.device, &r), Status::kOk);
  EXPECT_EQ(r.modes, c.modes);
  EXPECT_TRUE(r.mapping == c.mapping);
  EXPECT_EQ(r.sequence.seq_len, 12u);
  EXPECT_EQ(r.sequence.exclusion, 4u);
  EXPECT_EQ(r.max_shift, 2u);
  EXPECT_EQ(r.recent_exclusion, 33u);
  EXPECT_TRUE(r.matcher == LocaliserMatcher::kHeuristic);
  EXPECT_EQ(r.heuristic.candidates, 7u);
  EXPECT_EQ(r.heuristic.guard, 3u);
  EXPECT_EQ(r.heuristic.threshold.raw(), UQ8_8::from_ratio(71, 2).raw());
  EXPECT_EQ(r.heuristic.scan_places, 40u);
  const LocaliserConfig lc = r.localiser();
  EXPECT_TRUE(lc.matcher == LocaliserMatcher::kHeuristic);
  EXPECT_EQ(lc.heuristic.candidates, 7u);
  EXPECT_TRUE(check_localiser_config(lc).ok());

  // The defaults: the diagonal matcher and HeuristicConfig's settings.
  g_card.reset();
  ASSERT_EQ(write_run_config(g_card.device, RunConfig{}), Status::kOk);
  ASSERT_EQ(read_run_config(g_card.device, &r), Status::kOk);
  EXPECT_TRUE(r.matcher == LocaliserMatcher::kDiagonal);
  EXPECT_EQ(r.heuristic.candidates, HeuristicConfig{}.candidates);
  EXPECT_EQ(r.heuristic.guard, HeuristicConfig{}.guard);
  EXPECT_EQ(r.heuristic.threshold.raw(), HeuristicConfig{}.threshold.raw());
}

TEST(RunConfig, Version2LayoutAppendsTheMatcherFields) {
  g_card.reset();
  ASSERT_EQ(write_run_config(g_card.device, heuristic_config()), Status::kOk);
  const uint8_t* block = g_card.bytes;
  // Format version 4 of the run configuration in a format-2 log with room for records.
  EXPECT_EQ(block[8] | block[9] << 8, 4 | kLogFormat2 | kLogHasRecords);
  uint8_t p[kLogHeaderPayloadMax];
  ASSERT_EQ(stored_payload(p), kPayloadV4);
  EXPECT_EQ(p[96], 1u);  // matcher: heuristic
  EXPECT_EQ(p[97], 0u);  // reserved
  EXPECT_EQ(p[98] | p[99] << 8, 7);
  EXPECT_EQ(p[100] | p[101] << 8, 3);
  EXPECT_EQ(p[102] | p[103] << 8, 71 * 128);  // UQ8.8 of 35.5
}

TEST(RunConfig, OtherVersionsAreRefused) {
  // A version-1 configuration (the first 96 bytes of today's layout): refused, not run with
  // a guessed matcher.
  g_card.reset();
  ASSERT_EQ(write_run_config(g_card.device, RunConfig{}), Status::kOk);
  uint8_t p[kLogHeaderPayloadMax];
  ASSERT_EQ(stored_payload(p), kPayloadV4);
  g_card.reset();
  LogKind other = kRunConfigKind;
  other.version = 1;
  write_raw(p, kPayloadV1, other);
  RunConfig r;
  r.recent_exclusion = 77;
  LogProblem problem = LogProblem::kNone;
  EXPECT_EQ(read_run_config(g_card.device, &r, &problem), Status::kFailedPrecondition);
  EXPECT_TRUE(problem == LogProblem::kVersion);
  EXPECT_EQ(r.recent_exclusion, 77u);  // untouched
  // A version-2 configuration (the first 104 bytes): refused, not run without the grid.
  g_card.reset();
  other.version = 2;
  write_raw(p, kPayloadV2, other);
  problem = LogProblem::kNone;
  EXPECT_EQ(read_run_config(g_card.device, &r, &problem), Status::kFailedPrecondition);
  EXPECT_TRUE(problem == LogProblem::kVersion);
  EXPECT_EQ(r.recent_exclusion, 77u);
  // A version-3 configuration (the first 120 bytes): refused, not run without the route
  // search's settings.
  g_card.reset();
  other.version = 3;
  write_raw(p, kPayloadV3, other);
  problem = LogProblem::kNone;
  EXPECT_EQ(read_run_config(g_card.device, &r, &problem), Status::kFailedPrecondition);
  EXPECT_TRUE(problem == LogProblem::kVersion);
  // A future version too.
  g_card.reset();
  other.version = 5;
  write_raw(p, kPayloadV4, other);
  EXPECT_EQ(read_run_config(g_card.device, &r, &problem), Status::kFailedPrecondition);
  // The same payload as version 4 reads (so the refusals above are the version's doing).
  g_card.reset();
  write_raw(p, kPayloadV4);
  EXPECT_EQ(read_run_config(g_card.device, &r), Status::kOk);
}

TEST(RunConfig, ExploreModeAndGridRoundTripAndLayout) {
  g_card.reset();
  RunConfig c;
  c.modes = kModeTeach | kModeRepeat | kModeExplore | kModeRecord;
  c.grid_origin.x_mm = -12345;
  c.grid_origin.y_mm = 678;
  c.grid_cell_mm = 100;
  c.grid_size.width = 300;
  c.grid_size.height = 32768;
  ASSERT_EQ(write_run_config(g_card.device, c), Status::kOk);
  RunConfig r;
  ASSERT_EQ(read_run_config(g_card.device, &r), Status::kOk);
  EXPECT_EQ(r.modes, c.modes);
  EXPECT_EQ(r.grid_origin.x_mm, -12345);
  EXPECT_EQ(r.grid_origin.y_mm, 678);
  EXPECT_EQ(r.grid_cell_mm, 100u);
  EXPECT_EQ(r.grid_size.width, 300u);
  EXPECT_EQ(r.grid_size.height, 32768u);
  const GridConfig g = r.grid();
  EXPECT_EQ(g.origin_x.raw(), Q31_32::from_ratio(-12345, 1000).raw());
  EXPECT_EQ(g.cell_mm, 100u);
  EXPECT_EQ(check_grid_config(g), Status::kOk);
  uint8_t p[kLogHeaderPayloadMax];
  ASSERT_EQ(stored_payload(p), kPayloadV4);
  EXPECT_EQ(p[0], kModeTeach | kModeRepeat | kModeExplore | kModeRecord);
  const uint32_t x = static_cast<uint32_t>(p[104] | p[105] << 8 | p[106] << 16) |
                     static_cast<uint32_t>(p[107]) << 24;
  EXPECT_EQ(static_cast<int32_t>(x), -12345);
  EXPECT_EQ(p[112] | p[113] << 8, 100);
  EXPECT_EQ(p[114] | p[115] << 8, 300);
  EXPECT_EQ(p[116] | p[117] << 8, 32768);
}

TEST(RunConfig, ExploreWithoutTeachAndRepeatOrOnEveryFrameIsRefused) {
  RunConfig c;
  c.modes = kModeExplore;  // explore is teach + repeat with mapping
  EXPECT_EQ(write_run_config(g_card.device, c), Status::kInvalidArgument);
  c.modes = kModeExplore | kModeTeach;
  EXPECT_EQ(write_run_config(g_card.device, c), Status::kInvalidArgument);
  c.modes = kModeTeach | kModeRepeat | kModeExplore;
  c.trigger = TriggerMode::kEveryFrame;  // no odometry: nothing to hang the map from
  EXPECT_EQ(write_run_config(g_card.device, c), Status::kInvalidArgument);
  c.trigger = TriggerMode::kDistance;
  EXPECT_EQ(write_run_config(g_card.device, c), Status::kOk);
  // Continuing is an explore run's (the saved run's state is the explorer's).
  c.modes = kModeTeach | kModeRepeat | kModeContinue;
  EXPECT_EQ(write_run_config(g_card.device, c), Status::kInvalidArgument);
  c.modes = kModeTeach | kModeRepeat | kModeExplore | kModeContinue;
  EXPECT_EQ(write_run_config(g_card.device, c), Status::kOk);
  RunConfig back;
  ASSERT_EQ(read_run_config(g_card.device, &back), Status::kOk);
  EXPECT_EQ(back.modes, c.modes);
  c.modes = kModeTeach | kModeRepeat | kModeExplore;
  // Stored: an unknown mode bit, explore alone, or grid settings the grid would refuse.
  g_card.reset();
  ASSERT_EQ(write_run_config(g_card.device, c), Status::kOk);
  uint8_t good[kLogHeaderPayloadMax];
  ASSERT_EQ(stored_payload(good), kPayloadV4);
  struct Damage {
    uint32_t offset;
    uint8_t value;
  };
  const Damage cases[] = {
      {0, 1u << 5 | kModeTeach},                      // unknown mode bit
      {0, kModeExplore},                              // explore without teach + repeat
      {0, kModeContinue | kModeTeach | kModeRepeat},  // continue without explore
      {112, 9},                                       // cell 9 mm (< 10)
      {114, 0},     // width 0 (low byte; default 1600 = 0x0640 -> 0x0600 != 0)
      {117, 0x81},  // height 0x81xx > 32768
  };
  for (const Damage& d : cases) {
    uint8_t q[kLogHeaderPayloadMax];
    for (uint32_t i = 0; i < kPayloadV4; ++i)
      q[i] = good[i];
    q[d.offset] = d.value;
    if (d.offset == 114) q[115] = 0;
    g_card.reset();
    write_raw(q, kPayloadV4);
    RunConfig r;
    EXPECT_EQ(read_run_config(g_card.device, &r), Status::kDataLoss) << "offset " << d.offset;
  }
  // Cut short: a header without the grid fields, or without the route's.
  g_card.reset();
  write_raw(good, kPayloadV2);
  RunConfig cut;
  EXPECT_EQ(read_run_config(g_card.device, &cut), Status::kDataLoss);
  g_card.reset();
  write_raw(good, kPayloadV3);
  RunConfig r;
  EXPECT_EQ(read_run_config(g_card.device, &r), Status::kDataLoss);
}

TEST(RunConfig, UnknownOrInvalidMatcherSettingsAreDataLoss) {
  g_card.reset();
  ASSERT_EQ(write_run_config(g_card.device, heuristic_config()), Status::kOk);
  uint8_t good[kLogHeaderPayloadMax];
  ASSERT_EQ(stored_payload(good), kPayloadV4);
  struct Damage {
    uint32_t offset;
    uint8_t value;
  };
  const Damage cases[] = {
      {96, 3},     // unknown matcher
      {96, 0xFF},  // unknown matcher
      {98, 0},     // k = 0
      {98, 17},    // k = 17 > kMaxHeuristicCandidates
      {100, 0},    // guard = 0 (low byte; the high byte is 0)
  };
  for (const Damage& d : cases) {
    uint8_t p[kLogHeaderPayloadMax];
    for (uint32_t i = 0; i < kPayloadV4; ++i)
      p[i] = good[i];
    p[d.offset] = d.value;
    g_card.reset();
    write_raw(p, kPayloadV4);
    RunConfig r;
    EXPECT_EQ(read_run_config(g_card.device, &r), Status::kDataLoss) << "offset " << d.offset;
  }
  // Cut short: a header without the matcher fields (version 1's length).
  g_card.reset();
  write_raw(good, kPayloadV1);
  RunConfig r;
  EXPECT_EQ(read_run_config(g_card.device, &r), Status::kDataLoss);
  // The diagonal matcher with the stored heuristic settings intact reads fine.
  good[96] = 0;
  g_card.reset();
  write_raw(good, kPayloadV4);
  ASSERT_EQ(read_run_config(g_card.device, &r), Status::kOk);
  EXPECT_TRUE(r.matcher == LocaliserMatcher::kDiagonal);
  EXPECT_EQ(r.heuristic.candidates, 7u);
}

TEST(RunConfig, RouteSearchRoundTripLayoutAndDamage) {
  g_card.reset();
  RunConfig c;
  c.route.window = 41;
  c.route.slack = 3;
  c.route.growth = UQ8_8::from_ratio(1, 10);
  c.route.lost_after = 45;
  c.route.scan_places = 20;
  c.route.scan_seq_len = 12;
  c.route.start = 123456;
  ASSERT_EQ(write_run_config(g_card.device, c), Status::kOk);
  RunConfig r;
  ASSERT_EQ(read_run_config(g_card.device, &r), Status::kOk);
  EXPECT_EQ(r.route.window, 41u);
  EXPECT_EQ(r.route.slack, 3u);
  EXPECT_EQ(r.route.growth.raw(), UQ8_8::from_ratio(1, 10).raw());
  EXPECT_EQ(r.route.lost_after, 45u);
  EXPECT_EQ(r.route.scan_places, 20u);
  EXPECT_EQ(r.route.scan_seq_len, 12u);
  EXPECT_EQ(r.route.start, 123456);
  EXPECT_EQ(r.localiser().route.window, 41u);
  uint8_t good[kLogHeaderPayloadMax];
  ASSERT_EQ(stored_payload(good), kPayloadV4);
  EXPECT_EQ(good[120] | good[121] << 8, 41);
  EXPECT_EQ(good[122] | good[123] << 8, 3);
  EXPECT_EQ(good[124] | good[125] << 8, UQ8_8::from_ratio(1, 10).raw());
  EXPECT_EQ(good[126] | good[127] << 8, 45);
  EXPECT_EQ(good[128] | good[129] << 8, 20);
  EXPECT_EQ(good[130] | good[131] << 8, 12);
  EXPECT_EQ(good[132] | good[133] << 8 | good[134] << 16, 123456);
  EXPECT_EQ(good[136] | good[137] << 8, 96);  // the heuristic's default budget for the robot
  EXPECT_EQ(good[138] | good[139] << 8, 0);   // reserved
  // Stored values the route search would refuse.
  struct Damage {
    uint32_t offset;
    uint8_t value;
  };
  const Damage cases[] = {
      {120, 40},    // window even
      {126, 0},     // lost_after 0
      {128, 0},     // scan_places 0
      {130, 0},     // scan_seq_len 0
      {135, 0xFF},  // start below -1 (0xFF01E240 as int32)
  };
  for (const Damage& d : cases) {
    uint8_t p[kLogHeaderPayloadMax];
    for (uint32_t i = 0; i < kPayloadV4; ++i)
      p[i] = good[i];
    p[d.offset] = d.value;
    g_card.reset();
    write_raw(p, kPayloadV4);
    EXPECT_EQ(read_run_config(g_card.device, &r), Status::kDataLoss) << "offset " << d.offset;
  }
  // A window too narrow for R is a run the route search cannot do, not a damaged file: the
  // card reads, and the firmware's run check refuses it (before any file is opened).
  {
    uint8_t p[kLogHeaderPayloadMax];
    for (uint32_t i = 0; i < kPayloadV4; ++i)
      p[i] = good[i];
    p[120] = 21;  // R = 10: at least 23
    g_card.reset();
    write_raw(p, kPayloadV4);
    RunConfig narrow;
    ASSERT_EQ(read_run_config(g_card.device, &narrow), Status::kOk);
    RunLimits limits;
    limits.seq_len = 30;
    limits.norm_window = 50;
    limits.exclusion = 10;
    limits.route_window = 41;
    limits.scan_seq_len = 10;
    EXPECT_EQ(check_run_config(narrow, limits).issue, RunIssue::kRouteWindowTooNarrow);
  }
  // An unknown start (-1) is fine.
  c.route.start = -1;
  g_card.reset();
  ASSERT_EQ(write_run_config(g_card.device, c), Status::kOk);
  ASSERT_EQ(read_run_config(g_card.device, &r), Status::kOk);
  EXPECT_EQ(r.route.start, -1);
}

TEST(RunConfig, WriteRefusesWhatTheLocaliserWouldRefuse) {
  g_card.reset();
  RunConfig c = heuristic_config();
  c.matcher = static_cast<LocaliserMatcher>(3);
  EXPECT_EQ(write_run_config(g_card.device, c), Status::kInvalidArgument);
  c = heuristic_config();
  c.heuristic.candidates = 0;
  EXPECT_EQ(write_run_config(g_card.device, c), Status::kInvalidArgument);
  c = heuristic_config();
  c.heuristic.guard = 0;
  EXPECT_EQ(write_run_config(g_card.device, c), Status::kInvalidArgument);
  // Nothing was written.
  RunConfig r;
  EXPECT_NE(read_run_config(g_card.device, &r), Status::kOk);
}

// ---------------------------------------------------------------------------------------
// check_run_config: what a build of the application runs (firmware/app/app_limits.h). The
// sizes are the application's own constants; the features are switched per test.

RunLimits app_limits(bool heuristic = true, bool mapping = true) {
  RunLimits l = profile::kRunLimits;
  l.heuristic = heuristic;
  l.mapping = mapping;
  return l;
}

// The issue check_run_config finds for `c` with `limits`, after checking its status.
RunIssue issue_of(const RunConfig& c, const RunLimits& limits) {
  const RunCheck check = check_run_config(c, limits);
  Status want = Status::kOutOfRange;
  switch (check.issue) {
    case RunIssue::kNone:
      want = Status::kOk;
      break;
    case RunIssue::kHeuristicNotBuilt:
    case RunIssue::kMappingNotBuilt:
      want = Status::kFailedPrecondition;
      break;
    case RunIssue::kExploreHeuristic:
    case RunIssue::kRouteMaxShift:
      want = Status::kInvalidArgument;
      break;
    default:
      break;
  }
  EXPECT_EQ(check.status, want);
  EXPECT_EQ(check.ok(), check.issue == RunIssue::kNone);
  return check.issue;
}

TEST(RunCheck, TheApplicationsLimitsAreItsConstants) {
  EXPECT_EQ(profile::kRunLimits.seq_len, profile::kMaxSeqLen);
  EXPECT_EQ(profile::kRunLimits.norm_window, profile::kMaxNormWindow);
  EXPECT_EQ(profile::kRunLimits.exclusion, profile::kMaxExclusion);
  EXPECT_EQ(profile::kRunLimits.route_window, profile::kWindowSlots);
  EXPECT_EQ(profile::kRunLimits.scan_seq_len, profile::kMaxScanSeqLen);
  // The defaults run on every build, with or without the optional features.
  for (int features = 0; features < 4; ++features) {
    EXPECT_EQ(issue_of(RunConfig{}, app_limits(features & 1, features & 2)), RunIssue::kNone);
  }
}

TEST(RunCheck, EverySizeAtItsLimitAndOneAbove) {
  const RunLimits limits = app_limits();
  // The route search runs (repeat, diagonal): every size counts.
  RunConfig c;
  c.sequence.seq_len = profile::kMaxSeqLen;
  c.sequence.window = profile::kMaxNormWindow;
  c.sequence.exclusion = profile::kMaxExclusion;
  c.route.window = profile::kWindowSlots;
  c.route.scan_seq_len = profile::kMaxScanSeqLen;
  EXPECT_EQ(issue_of(c, limits), RunIssue::kNone);
  RunConfig above = c;
  above.sequence.seq_len = profile::kMaxSeqLen + 1;
  EXPECT_EQ(issue_of(above, limits), RunIssue::kSeqLenAboveLimit);
  above = c;
  above.sequence.window = profile::kMaxNormWindow + 1;
  EXPECT_EQ(issue_of(above, limits), RunIssue::kWindowAboveLimit);
  above = c;
  above.sequence.exclusion = profile::kMaxExclusion + 1;
  EXPECT_EQ(issue_of(above, limits), RunIssue::kExclusionAboveLimit);
  above = c;
  above.route.window = profile::kWindowSlots + 1;
  EXPECT_EQ(issue_of(above, limits), RunIssue::kRouteWindowAboveLimit);
  above = c;
  above.route.scan_seq_len = profile::kMaxScanSeqLen + 1;
  EXPECT_EQ(issue_of(above, limits), RunIssue::kScanSeqLenAboveLimit);
  // The scan's sequence is at most S: a longer scan_seq_len with a short S is fine.
  above.sequence.seq_len = profile::kMaxScanSeqLen;
  EXPECT_EQ(issue_of(above, limits), RunIssue::kNone);
  above.sequence.seq_len = profile::kMaxScanSeqLen + 1;
  EXPECT_EQ(issue_of(above, limits), RunIssue::kScanSeqLenAboveLimit);
  // The spacing: above 0, at most the trigger's kMaxSpacing (1000 m), to the last step.
  RunConfig s;
  s.spacing = SpatialTrigger::kMaxSpacing;
  EXPECT_EQ(issue_of(s, limits), RunIssue::kNone);
  s.spacing = Q31_32::from_raw(SpatialTrigger::kMaxSpacing.raw() + 1);
  EXPECT_EQ(issue_of(s, limits), RunIssue::kSpacingOutOfRange);
  s.spacing = Q31_32::from_raw(1);
  EXPECT_EQ(issue_of(s, limits), RunIssue::kNone);
  s.spacing = Q31_32::from_raw(0);
  EXPECT_EQ(issue_of(s, limits), RunIssue::kSpacingOutOfRange);
  s.spacing = Q31_32::from_int(-1);
  EXPECT_EQ(issue_of(s, limits), RunIssue::kSpacingOutOfRange);
  // Explore's full search holds the diagonal matcher's S too.
  RunConfig x;
  x.modes = kModeTeach | kModeRepeat | kModeExplore;
  x.sequence.seq_len = profile::kMaxSeqLen;
  EXPECT_EQ(issue_of(x, limits), RunIssue::kNone);
  x.sequence.seq_len = profile::kMaxSeqLen + 1;
  EXPECT_EQ(issue_of(x, limits), RunIssue::kSeqLenAboveLimit);
}

TEST(RunCheck, TheRouteSearchsSizesOnlyWhereItRuns) {
  const RunLimits limits = app_limits();
  RunConfig c;
  c.sequence.window = profile::kMaxNormWindow + 2;
  c.sequence.exclusion = profile::kMaxExclusion + 1;
  c.route.window = profile::kWindowSlots + 2;
  c.route.scan_seq_len = profile::kMaxScanSeqLen + 1;
  c.max_shift = 1;
  // Teach alone configures the route search (to check it), repeat and teach + repeat run it.
  for (const uint8_t modes : {uint8_t{kModeTeach}, uint8_t{kModeRepeat},
                              uint8_t{kModeTeach | kModeRepeat | kModeRecord}}) {
    c.modes = modes;
    EXPECT_EQ(issue_of(c, limits), RunIssue::kWindowAboveLimit);
  }
  // Record alone, explore (its full search) and the heuristic do not.
  c.modes = kModeRecord;
  EXPECT_EQ(issue_of(c, limits), RunIssue::kNone);
  c.modes = kModeTeach | kModeRepeat | kModeExplore;
  EXPECT_EQ(issue_of(c, limits), RunIssue::kNone);
  c.modes = kModeRepeat;
  c.matcher = LocaliserMatcher::kHeuristic;
  EXPECT_EQ(issue_of(c, limits), RunIssue::kNone);
  // ... nor S: the heuristic's state does not grow with it (up to the core's kMaxSeqLen).
  c.sequence.seq_len = kMaxSeqLen;
  EXPECT_EQ(issue_of(c, limits), RunIssue::kNone);
  // The route search takes the plain SAD.
  RunConfig shift;
  shift.max_shift = 1;
  EXPECT_EQ(issue_of(shift, limits), RunIssue::kRouteMaxShift);
  shift.max_shift = 0;
  EXPECT_EQ(issue_of(shift, limits), RunIssue::kNone);
}

TEST(RunCheck, FeaturesNotBuiltInAreRefused) {
  RunConfig h;
  h.matcher = LocaliserMatcher::kHeuristic;
  EXPECT_EQ(issue_of(h, app_limits(true, false)), RunIssue::kNone);
  EXPECT_EQ(issue_of(h, app_limits(false, true)), RunIssue::kHeuristicNotBuilt);
  RunConfig x;
  x.modes = kModeTeach | kModeRepeat | kModeExplore;
  EXPECT_EQ(issue_of(x, app_limits(false, true)), RunIssue::kNone);
  EXPECT_EQ(issue_of(x, app_limits(true, false)), RunIssue::kMappingNotBuilt);
  // Explore runs the diagonal matcher's full search.
  x.matcher = LocaliserMatcher::kHeuristic;
  EXPECT_EQ(issue_of(x, app_limits()), RunIssue::kExploreHeuristic);
}

TEST(RunCheck, TheBoardPrintsACode) {
  // The board's build prints a code, the PC's a sentence (seqslam explain RC<n>; its test
  // checks that every issue has one).
  EXPECT_EQ(run_issue_text(RunIssue::kSeqLenAboveLimit)[0], SEQSLAM_MESSAGE_TEXTS ? 's' : 'R');
}

// Every block of a results log zeroed, and the log cut at every block: the reader reports the
// loss (kDataLoss) every time, and the results it returns are the ones written.
TEST(Results, EveryCutAndEveryZeroedBlockIsReported) {
  static test::FakeCard<40> card;
  static test::FakeCard<40> copy;
  card.reset();
  ResultsWriter w;
  ASSERT_EQ(w.create(card.device), Status::kOk);
  for (uint32_t i = 0; i < 60; ++i) {
    RunResult r;
    r.step = i;
    r.capture = i * 3;
    ASSERT_EQ(w.append(r), Status::kOk);
  }
  const auto losses = [](hal::BlockDevice& device) -> uint32_t {
    ResultsReader r;
    if (r.open(device) != Status::kOk) return uint32_t{1000};
    uint32_t reported = 0;
    RunResult out;
    for (uint32_t calls = 0; calls < 1000; ++calls) {
      const Status st = r.next(&out);
      if (st == Status::kDataLoss) ++reported;
      if (st == Status::kOutOfRange) break;
      if (st == Status::kOk) {
        EXPECT_EQ(out.capture, out.step * 3);
      }
    }
    return reported;
  };
  // The blocks the log uses: up to the last block that is not the fill pattern.
  uint32_t used = 0;
  for (uint32_t b = 0; b < 40; ++b) {
    if (card.bytes[b * 512] != 0xEE || card.bytes[b * 512 + 511] != 0xEE) used = b + 1;
  }
  ASSERT_GT(used, 4u);
  for (uint32_t b = 1; b < used; ++b) {
    hal::FakeBlockDevice cut(Span<uint8_t>(card.bytes, static_cast<size_t>(b) * 512));
    EXPECT_GT(losses(cut), 0u) << "cut at block " << b;
    for (uint32_t k = 0; k < sizeof card.bytes; ++k)
      copy.bytes[k] = card.bytes[k];
    for (uint32_t k = 0; k < 512; ++k)
      copy.bytes[b * 512 + k] = 0;
    const uint32_t reported = losses(copy.device);
    if (b >= kFirstRecordOffset / 512) {
      EXPECT_GT(reported, 0u) << "zeroed block " << b;
    } else {
      EXPECT_EQ(reported, 0u) << "zeroed commit slot " << b;
    }
  }
}

}  // namespace
}  // namespace seqslam::storage
