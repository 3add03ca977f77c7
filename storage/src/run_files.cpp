#include "seqslam/storage/run_files.h"

#include "codec.h"
#include "seqslam/messages.h"
#include "seqslam/spatial_trigger.h"
#include "seqslam/storage/bytes.h"

namespace seqslam::storage {

namespace {

constexpr uint8_t kResultRecord = 1;
constexpr uint32_t kResultBytes = 56;

uint32_t encode(const RunConfig& c, uint8_t* out, uint32_t capacity) {
  ByteWriter w(out, capacity);
  w.u8(c.modes);
  w.u8(static_cast<uint8_t>(c.trigger));
  w.u8(c.max_shift);
  w.u8(c.record_colour ? 1 : 0);
  codec::put_mapping(w, c.mapping);
  codec::put_preprocess(w, c.preprocess);
  w.u16(c.sequence.seq_len);
  w.u16(c.sequence.window);
  w.u16(c.sequence.sigma_min.raw());
  w.u16(c.sequence.exclusion);
  w.u32(c.sequence.threshold.raw());
  w.u16(c.recent_exclusion);
  w.u16(0);
  codec::put_odometry(w, c.odometry);
  w.i64(c.spacing.raw());
  // Version 2: the sequence matcher.
  w.u8(static_cast<uint8_t>(c.matcher));
  w.u8(0);
  w.u16(c.heuristic.candidates);
  w.u16(c.heuristic.guard);
  w.u16(c.heuristic.threshold.raw());
  // Version 3: the explore mode's grid.
  w.i32(c.grid_origin_x_mm);
  w.i32(c.grid_origin_y_mm);
  w.u16(c.grid_cell_mm);
  w.u16(c.grid_width);
  w.u16(c.grid_height);
  w.u16(0);
  // Version 4: the route search.
  w.u16(c.route.window);
  w.u16(c.route.slack);
  w.u16(c.route.growth.raw());
  w.u16(c.route.lost_after);
  w.u16(c.route.scan_places);
  w.u16(c.route.scan_seq_len);
  w.i32(c.route.start);
  w.u16(c.heuristic.scan_places);
  w.u16(0);
  return w.ok() ? static_cast<uint32_t>(w.position()) : 0;
}

bool decode(const uint8_t* data, uint32_t size, RunConfig* out) {
  ByteReader r(data, size);
  RunConfig c;
  c.modes = r.u8();
  c.trigger = static_cast<TriggerMode>(r.u8());
  c.max_shift = r.u8();
  c.record_colour = r.u8() != 0;
  c.mapping = codec::get_mapping(r);
  c.preprocess = codec::get_preprocess(r);
  c.sequence.seq_len = r.u16();
  c.sequence.window = r.u16();
  c.sequence.sigma_min = UQ8_8::from_raw(r.u16());
  c.sequence.exclusion = r.u16();
  c.sequence.threshold = UQ16_16::from_raw(r.u32());
  c.recent_exclusion = r.u16();
  r.skip(2);
  c.odometry = codec::get_odometry(r);
  c.spacing = Q31_32::from_raw(r.i64());
  // Any byte value is representable in the enum; an unknown one is refused by valid().
  c.matcher = static_cast<LocaliserMatcher>(r.u8());
  r.skip(1);
  c.heuristic.candidates = r.u16();
  c.heuristic.guard = r.u16();
  c.heuristic.threshold = UQ8_8::from_raw(r.u16());
  c.grid_origin_x_mm = r.i32();
  c.grid_origin_y_mm = r.i32();
  c.grid_cell_mm = r.u16();
  c.grid_width = r.u16();
  c.grid_height = r.u16();
  r.skip(2);
  c.route.window = r.u16();
  c.route.slack = r.u16();
  c.route.growth = UQ8_8::from_raw(r.u16());
  c.route.lost_after = r.u16();
  c.route.scan_places = r.u16();
  c.route.scan_seq_len = r.u16();
  c.route.start = r.i32();
  c.heuristic.scan_places = r.u16();
  r.skip(2);
  if (!r.ok()) return false;
  *out = c;
  return true;
}

bool valid(const RunConfig& c) {
  if (c.modes == 0 ||
      c.modes > (kModeTeach | kModeRepeat | kModeRecord | kModeExplore | kModeContinue)) {
    return false;
  }
  if ((c.modes & (kModeContinue | kModeExplore)) == kModeContinue) return false;
  // Explore is teach + repeat (the run against its own places) with mapping, on odometry.
  if ((c.modes & kModeExplore) != 0 &&
      ((c.modes & (kModeTeach | kModeRepeat)) != (kModeTeach | kModeRepeat) ||
       c.trigger != TriggerMode::kDistance)) {
    return false;
  }
  // The grid is checked whatever the modes, like the heuristic's settings: the ranges of
  // check_grid_config (occupancy_grid.h; the log-odds settings are GridConfig's defaults),
  // tested here directly so that a firmware without mapping does not link the grid's code.
  if (c.grid_cell_mm < 10 || c.grid_cell_mm > 1000 || c.grid_width == 0 ||
      c.grid_width > kMaxGridSide || c.grid_height == 0 || c.grid_height > kMaxGridSide) {
    return false;
  }
  if (c.trigger != TriggerMode::kDistance && c.trigger != TriggerMode::kEveryFrame) return false;
  if (hal::check_mapping(c.mapping) != Status::kOk) return false;
  if (!check_localiser_config(c.localiser()).ok()) return false;
  Odometry probe;
  return probe.configure(c.odometry) == Status::kOk && c.spacing.raw() > 0;
}

}  // namespace

const char* run_issue_text(RunIssue issue) {
#if !SEQSLAM_MESSAGE_TEXTS
  return message_code("RC", static_cast<uint32_t>(issue));
#endif
  switch (issue) {
    case RunIssue::kNone:
      return "the application runs this configuration";
    case RunIssue::kHeuristicNotBuilt:
      return "matcher heuristic: not built in (SEQSLAM_APP_HEURISTIC=0)";
    case RunIssue::kMappingNotBuilt:
      return "explore: mapping not built in (SEQSLAM_APP_MAPPING=0)";
    case RunIssue::kSpacingOutOfRange:
      return "spacing must be above 0 and at most 1000 m (SpatialTrigger::kMaxSpacing)";
    case RunIssue::kExploreHeuristic:
      return "explore runs the diagonal matcher's full search, not the heuristic";
    case RunIssue::kSeqLenAboveLimit:
      return "sequence.seq_len above this firmware's kMaxSeqLen (the diagonal matcher)";
    case RunIssue::kWindowAboveLimit:
      return "sequence.window above this firmware's kMaxNormWindow (the route search)";
    case RunIssue::kExclusionAboveLimit:
      return "sequence.exclusion above this firmware's kMaxExclusion (the route search)";
    case RunIssue::kRouteWindowAboveLimit:
      return "route.window above this firmware's kWindowSlots (the route search)";
    case RunIssue::kScanSeqLenAboveLimit:
      return "route.scan_seq_len (at most S) above this firmware's kMaxScanSeqLen (the route "
             "search)";
    case RunIssue::kRouteMaxShift:
      return "the route search uses the plain SAD: max_shift must be 0";
  }
  return "unknown run configuration issue";
}

Status write_run_config(hal::BlockDevice& device, const RunConfig& config) {
  if (!valid(config)) return Status::kInvalidArgument;
  uint8_t payload[kLogHeaderPayloadMax];
  const uint32_t size = encode(config, payload, sizeof payload);
  LogWriter w;
  return w.create(device, kRunConfigKind, payload, size);
}

Status read_run_config(hal::BlockDevice& device, RunConfig* config, LogProblem* problem) {
  LogReader r;
  uint8_t payload[kLogHeaderPayloadMax];
  uint32_t size = 0;
  uint8_t none[1];
  const Status s = r.open(device, kRunConfigKind, payload, sizeof payload, &size,
                          Span<uint8_t>(none, 1), problem);
  if (s != Status::kOk) return s;
  RunConfig c;
  if (!decode(payload, size, &c) || !valid(c)) return Status::kDataLoss;
  *config = c;
  return Status::kOk;
}

Status ResultsWriter::create(hal::BlockDevice& device, LogProblem* problem) {
  return log_.create(device, kResultsKind, nullptr, 0, problem);
}

Status ResultsWriter::reopen(hal::BlockDevice& device, LogProblem* problem) {
  uint8_t buffer[kRecordOverhead + kResultBytes];
  return log_.reopen(device, kResultsKind, Span<uint8_t>(buffer), problem);
}

Status ResultsWriter::append(const RunResult& r, LogProblem* problem) {
  uint8_t buf[kResultBytes];
  ByteWriter w(buf, sizeof buf);
  w.u32(r.step);
  w.u32(r.capture);
  w.u32(r.timestamp_us);
  codec::put_pose(w, r.pose);
  w.i32(r.place);
  w.i32(r.runner_up);
  w.u32(r.cost);
  w.u32(r.runner_up_cost);
  w.u32(r.confidence.raw());
  w.u8(r.localised ? 1 : 0);
  w.u8(r.route);
  w.zeros(2);
  const ByteSpan part{buf, w.position()};
  return log_.append(kResultRecord, &part, 1, problem);
}

Status ResultsReader::open(hal::BlockDevice& device, LogProblem* problem) {
  return log_.open(device, kResultsKind, nullptr, 0, nullptr,
                   Span<uint8_t>(buffer_, sizeof buffer_), problem);
}

Status ResultsReader::next(RunResult* out) {
  RecordView v;
  const Status s = log_.next(&v);
  if (s != Status::kOk) return s;
  if (v.type != kResultRecord || v.payload_size != kResultBytes) return Status::kDataLoss;
  ByteReader r(v.payload, v.payload_size);
  RunResult x;
  x.step = r.u32();
  x.capture = r.u32();
  x.timestamp_us = r.u32();
  x.pose = codec::get_pose(r);
  x.place = r.i32();
  x.runner_up = r.i32();
  x.cost = r.u32();
  x.runner_up_cost = r.u32();
  x.confidence = UQ16_16::from_raw(r.u32());
  x.localised = r.u8() != 0;
  x.route = r.u8();
  *out = x;
  return Status::kOk;
}

}  // namespace seqslam::storage
