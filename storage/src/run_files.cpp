#include "seqslam/storage/run_files.h"

#include "codec.h"
#include "seqslam/messages.h"
#include "seqslam/spatial_trigger.h"
#include "seqslam/storage/bytes.h"
#include "seqslam/storage/settings_codec.h"

namespace seqslam::storage {

namespace {

constexpr uint8_t kResultRecord = 1;
constexpr uint32_t kResultBytes = 56;

}  // namespace

namespace {

// kCardOnly: what a card carries (the board reads a card; the rest are its defaults).
template <bool kCardOnly>
SettingsCheck check_settings(const RunConfig& c) {
  const int16_t out_of_range = first_setting_out_of_range<kCardOnly>(RunSettings{}, c);
  if (out_of_range >= 0) return {Status::kOutOfRange, out_of_range};
  const SettingsCheck invalid{Status::kInvalidArgument, -1};
  if ((c.modes & (kModeContinue | kModeExplore)) == kModeContinue) return invalid;
  // Explore is teach + repeat (the run against its own places) with mapping, on odometry.
  if ((c.modes & kModeExplore) != 0 &&
      ((c.modes & (kModeTeach | kModeRepeat)) != (kModeTeach | kModeRepeat) ||
       c.trigger != TriggerMode::kDistance)) {
    return invalid;
  }
  if (hal::check_mapping(c.mapping) != Status::kOk) return invalid;
  if (!check_localiser_config(c.localiser()).ok()) return invalid;
  Odometry probe;
  if (probe.configure(c.odometry) != Status::kOk) return invalid;
  return {};
}

}  // namespace

SettingsCheck check_run_settings(const RunConfig& c) {
  return check_settings<false>(c);
}

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
    case RunIssue::kSlopeNotBuilt:
      return "matcher slope: the firmware has no slope matcher (the PC tools do)";
    case RunIssue::kRouteWindowTooNarrow:
      return "route.window must be at least 2 * sequence.exclusion + 3 (the route search)";
  }
  return "unknown run configuration issue";
}

Status write_run_config(hal::BlockDevice& device, const RunConfig& config) {
  if (!check_run_settings(config).ok()) return Status::kInvalidArgument;
  uint8_t payload[kLogHeaderPayloadMax];
  const uint32_t size = encode_settings(RunSettings{}, config, payload, sizeof payload);
  LogWriter w;
  return w.create(device, kRunConfigKind, payload, size);
}

Status read_run_config(hal::BlockDevice& device, RunConfig* config, LogProblem* problem) {
  LogReader r;
  uint8_t payload[kLogHeaderPayloadMax];
  uint32_t size = 0;
  uint8_t none[1];
  SEQSLAM_TRY(r.open(device, kRunConfigKind, payload, sizeof payload, &size, Span<uint8_t>(none, 1),
                     problem));
  // The settings the card does not carry keep the caller's values.
  RunConfig c = *config;
  if (!decode_settings(RunSettings{}, payload, size, &c) || !check_settings<true>(c).ok()) {
    return Status::kDataLoss;
  }
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
  SEQSLAM_TRY(log_.next(&v));
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
