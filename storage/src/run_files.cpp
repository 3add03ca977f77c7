#include "seqslam/storage/run_files.h"

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
  w.i32(c.mapping.a11.raw());
  w.i32(c.mapping.a12.raw());
  w.i32(c.mapping.a21.raw());
  w.i32(c.mapping.a22.raw());
  w.i16(c.mapping.bx);
  w.i16(c.mapping.by);
  w.u16(c.mapping.xmax);
  w.u16(c.mapping.ymax);
  w.u8(static_cast<uint8_t>(c.preprocess.method));
  w.u8(c.preprocess.patch.patch_width);
  w.u8(c.preprocess.patch.patch_height);
  w.u8(0);
  w.u16(c.preprocess.patch.epsilon.raw());
  w.u16(c.preprocess.patch.gain.raw());
  w.u16(c.sequence.seq_len);
  w.u16(c.sequence.window);
  w.u16(c.sequence.sigma_min.raw());
  w.u16(c.sequence.exclusion);
  w.u32(c.sequence.threshold.raw());
  w.u16(c.recent_exclusion);
  w.u16(0);
  w.u32(c.odometry.ticks_per_revolution);
  w.i64(c.odometry.circumference_left.raw());
  w.i64(c.odometry.circumference_right.raw());
  w.i64(c.odometry.track_width.raw());
  w.u8(c.odometry.counter_bits);
  w.zeros(3);
  w.u32(c.odometry.max_ticks_per_update);
  w.i64(c.spacing.raw());
  return w.ok() ? static_cast<uint32_t>(w.position()) : 0;
}

bool decode(const uint8_t* data, uint32_t size, RunConfig* out) {
  ByteReader r(data, size);
  RunConfig c;
  c.modes = r.u8();
  c.trigger = static_cast<TriggerMode>(r.u8());
  c.max_shift = r.u8();
  c.record_colour = r.u8() != 0;
  c.mapping.a11 = Q15_16::from_raw(r.i32());
  c.mapping.a12 = Q15_16::from_raw(r.i32());
  c.mapping.a21 = Q15_16::from_raw(r.i32());
  c.mapping.a22 = Q15_16::from_raw(r.i32());
  c.mapping.bx = r.i16();
  c.mapping.by = r.i16();
  c.mapping.xmax = r.u16();
  c.mapping.ymax = r.u16();
  c.preprocess.method = static_cast<Preprocessing>(r.u8());
  c.preprocess.patch.patch_width = r.u8();
  c.preprocess.patch.patch_height = r.u8();
  r.skip(1);
  c.preprocess.patch.epsilon = UQ8_8::from_raw(r.u16());
  c.preprocess.patch.gain = UQ8_8::from_raw(r.u16());
  c.sequence.seq_len = r.u16();
  c.sequence.window = r.u16();
  c.sequence.sigma_min = UQ8_8::from_raw(r.u16());
  c.sequence.exclusion = r.u16();
  c.sequence.threshold = UQ16_16::from_raw(r.u32());
  c.recent_exclusion = r.u16();
  r.skip(2);
  c.odometry.ticks_per_revolution = r.u32();
  c.odometry.circumference_left = Q31_32::from_raw(r.i64());
  c.odometry.circumference_right = Q31_32::from_raw(r.i64());
  c.odometry.track_width = Q31_32::from_raw(r.i64());
  c.odometry.counter_bits = r.u8();
  r.skip(3);
  c.odometry.max_ticks_per_update = r.u32();
  c.spacing = Q31_32::from_raw(r.i64());
  if (!r.ok()) return false;
  *out = c;
  return true;
}

bool valid(const RunConfig& c) {
  if (c.modes == 0 || c.modes > (kModeTeach | kModeRepeat | kModeRecord)) return false;
  if (c.trigger != TriggerMode::kDistance && c.trigger != TriggerMode::kEveryFrame) return false;
  if (hal::check_mapping(c.mapping) != Status::kOk) return false;
  if (!check_localiser_config(c.localiser()).ok()) return false;
  Odometry probe;
  return probe.configure(c.odometry) == Status::kOk && c.spacing.raw() > 0;
}

}  // namespace

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

Status ResultsWriter::append(const RunResult& r, LogProblem* problem) {
  uint8_t buf[kResultBytes];
  ByteWriter w(buf, sizeof buf);
  w.u32(r.step);
  w.u32(r.capture);
  w.u32(r.timestamp_us);
  w.i64(r.pose.x.raw());
  w.i64(r.pose.y.raw());
  w.u32(r.pose.heading.bam);
  w.i32(r.place);
  w.i32(r.runner_up);
  w.u32(r.cost);
  w.u32(r.runner_up_cost);
  w.u32(r.confidence.raw());
  w.u8(r.localised ? 1 : 0);
  w.zeros(3);
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
  x.pose.x = Q31_32::from_raw(r.i64());
  x.pose.y = Q31_32::from_raw(r.i64());
  x.pose.heading = Angle{r.u32()};
  x.place = r.i32();
  x.runner_up = r.i32();
  x.cost = r.u32();
  x.runner_up_cost = r.u32();
  x.confidence = UQ16_16::from_raw(r.u32());
  x.localised = r.u8() != 0;
  *out = x;
  return Status::kOk;
}

}  // namespace seqslam::storage
