#include "seqslam/storage/dream.h"

#include "codec.h"
#include "seqslam/messages.h"
#include "seqslam/storage/bytes.h"

namespace seqslam::storage {

namespace {

constexpr uint32_t kSnapshotFixed = 24;
constexpr uint32_t kPlaceFixed = 52;
constexpr uint32_t kReducedFixed = 16;
constexpr uint32_t kTruthSize = 24;
constexpr uint8_t kFormatGray = 0;
constexpr uint8_t kFormatGrayYuv = 1;

Status fail(DreamProblem* out, DreamProblem p, Status s) {
  if (out != nullptr) *out = p;
  return s;
}

Status check_header(const DreamHeader& h, DreamProblem* problem) {
  if (h.variant != DreamVariant::kFull && h.variant != DreamVariant::kReduced) {
    return fail(problem, DreamProblem::kBadHeader, Status::kInvalidArgument);
  }
  if (h.colour != ColourFormat::kNone && h.colour != ColourFormat::kYuv422) {
    return fail(problem, DreamProblem::kBadHeader, Status::kInvalidArgument);
  }
  if (hal::check_mapping(h.mapping) != Status::kOk || h.infrared_count > hal::kMaxInfrared ||
      h.snapshot_period_us == 0) {
    return fail(problem, DreamProblem::kBadHeader, Status::kInvalidArgument);
  }
  if (h.image_size().pixels() > kMaxPixels) {
    return fail(problem, DreamProblem::kImageTooLarge, Status::kOutOfRange);
  }
  if (h.variant == DreamVariant::kFull) {
    Odometry probe;
    if (probe.configure(h.wheels) != Status::kOk || h.spacing.raw() <= 0) {
      return fail(problem, DreamProblem::kBadHeader, Status::kInvalidArgument);
    }
  }
  return fail(problem, DreamProblem::kNone, Status::kOk);
}

}  // namespace

RangeSensor range_sensor_of(const InfraredMount& m) {
  RangeSensor r;
  r.x = Q31_32::from_ratio(m.x_mm, 1000);
  r.y = Q31_32::from_ratio(m.y_mm, 1000);
  r.angle = Angle{static_cast<uint32_t>(m.angle) << 16};
  r.min_mm = m.min_mm;
  r.max_mm = m.max_mm;
  r.no_echo_mm = m.max_mm > 100 ? static_cast<uint16_t>(m.max_mm - 100) : 0;
  return r;
}

const char* dream_problem_text(DreamProblem p) {
#if !SEQSLAM_MESSAGE_TEXTS
  return message_code("DP", static_cast<uint32_t>(p));
#endif
  switch (p) {
    case DreamProblem::kNone:
      return "ok";
    case DreamProblem::kLog:
      return "the record log failed (see the log problem)";
    case DreamProblem::kBadHeader:
      return "dream header fields out of range (variant, colour, pipeline mapping, wheel "
             "constants, spacing, sensor count)";
    case DreamProblem::kImageTooLarge:
      return "the recording's images are larger than this build's SEQSLAM_MAX_PIXELS";
    case DreamProblem::kUnknownRecord:
      return "a record type this format version does not define";
    case DreamProblem::kWrongVariant:
      return "a record type the recording's variant does not allow (e.g. a snapshot in a "
             "reduced recording)";
    case DreamProblem::kBadRecordSize:
      return "a record whose size does not match its contents";
    case DreamProblem::kOutOfOrder:
      return "records out of order: snapshot sequence not increasing, place index not the "
             "next one, a place not right after the snapshot it was captured at, or a true "
             "pose not for the place before it or a second one for the same place";
    case DreamProblem::kBadImage:
      return "a place whose image size differs from the header's";
  }
  return "unknown dream problem";
}

const char* dream_problem_reason(DreamProblem p, LogProblem log) {
  return p == DreamProblem::kLog ? log_problem_text(log) : dream_problem_text(p);
}

uint32_t encode_dream_header(const DreamHeader& h, uint8_t* out, uint32_t capacity) {
  ByteWriter w(out, capacity);
  w.u8(static_cast<uint8_t>(h.variant));
  w.u8(static_cast<uint8_t>(h.colour));
  w.u16(0);
  w.u16(h.camera_width);
  w.u16(h.camera_height);
  w.u16(h.camera_gamma.raw());
  w.u16(0);
  codec::put_mapping(w, h.mapping);
  codec::put_odometry(w, h.wheels);
  w.i64(h.spacing.raw());
  w.u32(h.snapshot_period_us);
  w.u8(h.infrared_count);
  w.u8(h.has_head ? 1 : 0);
  w.u16(0);
  for (const InfraredMount& m : h.infrared) {
    w.i16(m.x_mm);
    w.i16(m.y_mm);
    w.u16(m.angle);
    w.u16(m.min_mm);
    w.u16(m.max_mm);
  }
  return w.ok() ? static_cast<uint32_t>(w.position()) : 0;
}

Status decode_dream_header(const uint8_t* data, uint32_t size, DreamHeader* out,
                           DreamProblem* problem) {
  ByteReader r(data, size);
  DreamHeader h;
  h.variant = static_cast<DreamVariant>(r.u8());
  h.colour = static_cast<ColourFormat>(r.u8());
  r.skip(2);
  h.camera_width = r.u16();
  h.camera_height = r.u16();
  h.camera_gamma = UQ8_8::from_raw(r.u16());
  r.skip(2);
  h.mapping = codec::get_mapping(r);
  h.wheels = codec::get_odometry(r);
  h.spacing = Q31_32::from_raw(r.i64());
  h.snapshot_period_us = r.u32();
  h.infrared_count = r.u8();
  h.has_head = r.u8() != 0;
  r.skip(2);
  for (InfraredMount& m : h.infrared) {
    m.x_mm = r.i16();
    m.y_mm = r.i16();
    m.angle = r.u16();
    m.min_mm = r.u16();
    m.max_mm = r.u16();
  }
  if (!r.ok()) return fail(problem, DreamProblem::kBadHeader, Status::kDataLoss);
  const Status s = check_header(h, problem);
  if (s == Status::kInvalidArgument) return Status::kDataLoss;  // stored, so damaged
  if (s != Status::kOk) return s;
  *out = h;
  return Status::kOk;
}

// ---------------------------------------------------------------------------------------
// Writer

Status DreamWriter::create(hal::BlockDevice& device, const DreamHeader& header,
                           DreamProblem* problem) {
  open_ = false;
  Status s = check_header(header, problem);
  if (s != Status::kOk) return s;
  uint8_t payload[kLogHeaderPayloadMax];
  const uint32_t size = encode_dream_header(header, payload, sizeof payload);
  s = log_.create(device, kDreamKind, payload, size, &log_problem_);
  if (s != Status::kOk) return fail(problem, DreamProblem::kLog, s);
  header_ = header;
  places_ = 0;
  truth_written_ = false;
  open_ = true;
  return fail(problem, DreamProblem::kNone, Status::kOk);
}

Status DreamWriter::append(DreamRecord type, const ByteSpan* parts, uint32_t count,
                           DreamProblem* problem) {
  const Status s = log_.append(static_cast<uint8_t>(type), parts, count, &log_problem_);
  return s != Status::kOk ? fail(problem, DreamProblem::kLog, s)
                          : fail(problem, DreamProblem::kNone, Status::kOk);
}

Status DreamWriter::snapshot(const hal::SensorSnapshot& snap, DreamProblem* problem) {
  if (!open_) return Status::kFailedPrecondition;
  if (header_.variant != DreamVariant::kFull) {
    return fail(problem, DreamProblem::kWrongVariant, Status::kFailedPrecondition);
  }
  const uint8_t n = snap.infrared_count <= hal::kMaxInfrared ? snap.infrared_count : 0;
  uint8_t buf[kSnapshotFixed + 2 * hal::kMaxInfrared];
  ByteWriter w(buf, sizeof buf);
  w.u32(snap.timestamp_us);
  w.u32(snap.sequence);
  w.u8(snap.flags);
  w.u8(n);
  w.u16(0);
  w.u32(snap.encoder_left);
  w.u32(snap.encoder_right);
  w.i16(snap.head_pan);
  w.i16(snap.head_tilt);
  for (uint32_t i = 0; i < n; ++i)
    w.u16(snap.infrared_mm[i]);
  const ByteSpan part{buf, w.position()};
  return append(DreamRecord::kSnapshot, &part, 1, problem);
}

Status DreamWriter::place(const DreamPlace& p, DreamProblem* problem) {
  if (!open_) return Status::kFailedPrecondition;
  if (p.index != places_) return fail(problem, DreamProblem::kOutOfOrder, Status::kInvalidArgument);
  const ImageSize size = header_.image_size();
  const bool colour = header_.colour == ColourFormat::kYuv422;
  if (p.size != size || p.gray == nullptr || (colour && p.yuv == nullptr) ||
      p.infrared_count > hal::kMaxInfrared) {
    return fail(problem, DreamProblem::kBadImage, Status::kInvalidArgument);
  }
  uint8_t buf[kPlaceFixed + 2 * hal::kMaxInfrared];
  ByteWriter w(buf, sizeof buf);
  DreamRecord type = DreamRecord::kPlace;
  if (header_.variant == DreamVariant::kReduced) {
    type = DreamRecord::kReducedPlace;
    w.u32(p.index);
    w.u32(p.timestamp_us);
    w.i16(p.head_pan);
    w.i16(p.head_tilt);
    w.u16(size.width);
    w.u16(size.height);
  } else {
    w.u32(p.index);
    w.u32(p.bus_sequence);
    w.u32(p.timestamp_us);
    w.u32(p.encoder_left);
    w.u32(p.encoder_right);
    codec::put_pose(w, p.pose);
    w.i16(p.head_pan);
    w.i16(p.head_tilt);
    w.u8(p.infrared_count);
    w.u8(colour ? kFormatGrayYuv : kFormatGray);
    w.u16(size.width);
    w.u16(size.height);
    w.u16(0);
    for (uint32_t i = 0; i < p.infrared_count; ++i)
      w.u16(p.infrared_mm[i]);
  }
  ByteSpan parts[3] = {{buf, w.position()}, {p.gray, size.pixels()}, {p.yuv, 0}};
  uint32_t count = 2;
  if (colour && type == DreamRecord::kPlace) {
    parts[2].size = 2u * size.pixels();
    count = 3;
  }
  const Status s = append(type, parts, count, problem);
  if (s == Status::kOk) {
    ++places_;
    truth_written_ = false;
  }
  return s;
}

Status DreamWriter::truth(const DreamTruth& t, DreamProblem* problem) {
  if (!open_) return Status::kFailedPrecondition;
  if (places_ == 0 || t.place_index != places_ - 1 || truth_written_) {
    return fail(problem, DreamProblem::kOutOfOrder, Status::kInvalidArgument);
  }
  uint8_t buf[kTruthSize];
  ByteWriter w(buf, sizeof buf);
  w.u32(t.place_index);
  codec::put_pose(w, t.pose);
  const ByteSpan part{buf, w.position()};
  const Status s = append(DreamRecord::kTruth, &part, 1, problem);
  if (s == Status::kOk) truth_written_ = true;
  return s;
}

// ---------------------------------------------------------------------------------------
// Reader

Status DreamReader::open(hal::BlockDevice& device, Span<uint8_t> buffer, DreamProblem* problem) {
  uint8_t payload[kLogHeaderPayloadMax];
  uint32_t size = 0;
  opened_ = false;
  Status s = log_.open(device, kDreamKind, payload, sizeof payload, &size, buffer, &open_problem_);
  if (s != Status::kOk) return fail(problem, DreamProblem::kLog, s);
  s = decode_dream_header(payload, size, &header_, problem);
  if (s != Status::kOk) return s;
  opened_ = true;
  problem_ = DreamProblem::kNone;
  after_damage_ = false;
  places_ = 0;
  snapshots_ = 0;
  missed_ = 0;
  truths_ = 0;
  truth_place_ = 0;
  have_truth_ = false;
  last_bus_sequence_ = 0;
  have_snapshot_ = false;
  return fail(problem, DreamProblem::kNone, Status::kOk);
}

Status DreamReader::next(DreamItem* out) {
  if (out == nullptr) return Status::kInvalidArgument;
  RecordView v;
  const Status s = log_.next(&v);
  if (s != Status::kOk) {
    problem_ = DreamProblem::kLog;
    if (s == Status::kDataLoss) after_damage_ = true;
    return s;
  }
  problem_ = DreamProblem::kNone;
  return decode(v, out);
}

Status DreamReader::decode(const RecordView& v, DreamItem* out) {
  const bool full = header_.variant == DreamVariant::kFull;
  const ImageSize size = header_.image_size();
  const uint32_t pixels = size.pixels();
  ByteReader r(v.payload, v.payload_size);
  auto bad = [this](DreamProblem p) {
    problem_ = p;
    return Status::kDataLoss;
  };
  switch (static_cast<DreamRecord>(v.type)) {
    case DreamRecord::kSnapshot: {
      if (!full) return bad(DreamProblem::kWrongVariant);
      hal::SensorSnapshot& snap = out->snapshot;
      snap = hal::SensorSnapshot{};
      snap.timestamp_us = r.u32();
      snap.sequence = r.u32();
      snap.flags = r.u8();
      snap.infrared_count = r.u8();
      r.skip(2);
      snap.encoder_left = r.u32();
      snap.encoder_right = r.u32();
      snap.head_pan = r.i16();
      snap.head_tilt = r.i16();
      if (snap.infrared_count > hal::kMaxInfrared ||
          v.payload_size != kSnapshotFixed + 2u * snap.infrared_count) {
        return bad(DreamProblem::kBadRecordSize);
      }
      for (uint32_t i = 0; i < snap.infrared_count; ++i)
        snap.infrared_mm[i] = r.u16();
      // The bus counts snapshots in 32 bits and wraps (after 497 days at 100 Hz): a step is
      // forward when it is below half the counter's range, modulo 2^32, so a recording that
      // crosses the wrap reads in order and its gaps count as missed snapshots.
      const uint32_t step = snap.sequence - last_bus_sequence_;
      if (have_snapshot_ && (step == 0 || step >= 0x80000000u)) {
        return bad(DreamProblem::kOutOfOrder);
      }
      if (have_snapshot_) missed_ += step - 1;
      last_bus_sequence_ = snap.sequence;
      have_snapshot_ = true;
      ++snapshots_;
      out->type = DreamRecord::kSnapshot;
      return Status::kOk;
    }
    case DreamRecord::kPlace:
    case DreamRecord::kReducedPlace: {
      const bool reduced = static_cast<DreamRecord>(v.type) == DreamRecord::kReducedPlace;
      if (reduced == full) return bad(DreamProblem::kWrongVariant);
      DreamPlace& p = out->place;
      p = DreamPlace{};
      uint32_t colour_bytes = 0;
      if (reduced) {
        p.index = r.u32();
        p.timestamp_us = r.u32();
        p.head_pan = r.i16();
        p.head_tilt = r.i16();
        p.size.width = r.u16();
        p.size.height = r.u16();
        if (v.payload_size != kReducedFixed + pixels) return bad(DreamProblem::kBadRecordSize);
      } else {
        p.index = r.u32();
        p.bus_sequence = r.u32();
        p.timestamp_us = r.u32();
        p.encoder_left = r.u32();
        p.encoder_right = r.u32();
        p.pose = codec::get_pose(r);
        p.head_pan = r.i16();
        p.head_tilt = r.i16();
        p.infrared_count = r.u8();
        const uint8_t format = r.u8();
        p.size.width = r.u16();
        p.size.height = r.u16();
        r.skip(2);
        if (format != kFormatGray && format != kFormatGrayYuv) {
          return bad(DreamProblem::kBadRecordSize);
        }
        colour_bytes = format == kFormatGrayYuv ? 2 * pixels : 0;
        if (p.infrared_count > hal::kMaxInfrared ||
            v.payload_size != kPlaceFixed + 2u * p.infrared_count + pixels + colour_bytes) {
          return bad(DreamProblem::kBadRecordSize);
        }
        for (uint32_t i = 0; i < p.infrared_count; ++i)
          p.infrared_mm[i] = r.u16();
      }
      if (p.size != size) return bad(DreamProblem::kBadImage);
      p.gray = r.bytes(pixels);
      if (colour_bytes > 0) p.yuv = r.bytes(colour_bytes);
      // After a damaged record the next place may follow a lost place or a lost snapshot.
      const bool may_skip = after_damage_;
      after_damage_ = false;
      if (may_skip && p.index > places_) places_ = p.index;
      if (p.index != places_) {
        places_ = p.index + 1;  // report once, then follow the recording's numbering
        return bad(DreamProblem::kOutOfOrder);
      }
      if (full && !may_skip && (!have_snapshot_ || p.bus_sequence != last_bus_sequence_)) {
        ++places_;
        return bad(DreamProblem::kOutOfOrder);
      }
      ++places_;
      out->type = static_cast<DreamRecord>(v.type);
      return Status::kOk;
    }
    case DreamRecord::kTruth: {
      if (v.payload_size != kTruthSize) return bad(DreamProblem::kBadRecordSize);
      DreamTruth& t = out->truth;
      t = DreamTruth{};
      t.place_index = r.u32();
      t.pose = codec::get_pose(r);
      // It names the place read last; after a damaged record, possibly a lost later one.
      const bool last = places_ > 0 && t.place_index == places_ - 1;
      const bool lost = after_damage_ && t.place_index >= places_;
      if ((!last && !lost) || (have_truth_ && truth_place_ == t.place_index)) {
        return bad(DreamProblem::kOutOfOrder);
      }
      truth_place_ = t.place_index;
      have_truth_ = true;
      ++truths_;
      out->type = DreamRecord::kTruth;
      return Status::kOk;
    }
  }
  return bad(DreamProblem::kUnknownRecord);
}

}  // namespace seqslam::storage
