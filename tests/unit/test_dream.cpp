// Dream-sequence recordings: round trips of both variants and every kind of bad input.
#include "seqslam/storage/dream.h"

#include "seqslam/storage/bytes.h"
#include "seqslam/storage/dream_replay.h"
#include "seqslam/storage/volume.h"
#include "storage_fixtures.h"
#include "test.h"

namespace seqslam::storage {
namespace {

using test::FakeCard;

uint8_t g_gray[512];
uint8_t g_yuv[1024];
uint8_t g_buffer[kDreamRecordMax];

DreamPlace make_place(uint32_t i, const hal::SensorSnapshot& at) {
  for (uint32_t k = 0; k < 512; ++k)
    g_gray[k] = test::place_pixel(i, k);
  for (uint32_t k = 0; k < 1024; ++k)
    g_yuv[k] = static_cast<uint8_t>(k ^ i);
  DreamPlace p;
  p.index = i;
  p.bus_sequence = at.sequence;
  p.timestamp_us = at.timestamp_us;
  p.encoder_left = at.encoder_left;
  p.encoder_right = at.encoder_right;
  p.pose = Pose2{Q31_32::from_ratio(i, 5), Q31_32::from_ratio(-static_cast<int64_t>(i), 100),
                 Angle{i * 1000u}};
  p.head_pan = at.head_pan;
  p.head_tilt = at.head_tilt;
  p.infrared_count = at.infrared_count;
  for (uint32_t k = 0; k < at.infrared_count; ++k)
    p.infrared_mm[k] = at.infrared_mm[k];
  p.size = ImageSize{32, 16};
  p.gray = g_gray;
  p.yuv = g_yuv;
  return p;
}

// The true pose of place i: negative and extreme coordinates, headings on both sides of the
// wrap (0, just below a full turn, -180 degrees, just below +180 degrees, -90 degrees).
DreamTruth make_truth(uint32_t i) {
  static const int64_t kX[] = {0, -1, -0x7FFFFFFFFFFFFFFF - 1, 0x7FFFFFFFFFFFFFFF, -0x123456789AB};
  static const uint32_t kHeading[] = {0, 0xFFFFFFFFu, 0x80000000u, 0x7FFFFFFFu, 0xC0000000u};
  DreamTruth t;
  t.place_index = i;
  t.pose.x = Q31_32::from_raw(kX[i % 5] + static_cast<int64_t>(i % 5 == 2 ? i : 0));
  t.pose.y = Q31_32::from_raw((static_cast<int64_t>(i) - 7) * 0x180000001);
  t.pose.heading = Angle{kHeading[i % 5] + (i / 5) * 0x10001u};
  return t;
}

// Whether place i gets a truth record (`truths`: none, all, or all but every third).
enum class Truths { kNone, kAll, kSome };
bool has_truth(Truths truths, uint32_t i) {
  return truths == Truths::kAll || (truths == Truths::kSome && i % 3 != 1);
}

// Writes `places` places, with `per_place` snapshots before each (full variant), and truth
// records after the places `truths` selects.
Status record(hal::BlockDevice& device, DreamVariant variant, bool colour, uint32_t places,
              uint32_t per_place, Truths truths = Truths::kNone) {
  DreamWriter w;
  Status s = w.create(device, test::dream_header(variant, colour));
  uint32_t snap = 0;
  for (uint32_t i = 0; i < places && s == Status::kOk; ++i) {
    hal::SensorSnapshot last = test::snapshot(snap);
    for (uint32_t k = 0; k < per_place && s == Status::kOk; ++k) {
      last = test::snapshot(snap++);
      s = w.snapshot(last);
    }
    if (s == Status::kOk) s = w.place(make_place(i, last));
    if (s == Status::kOk && has_truth(truths, i)) s = w.truth(make_truth(i));
  }
  return s;
}

TEST(Dream, FullRecordingRoundTrip) {
  static FakeCard<600> card;
  card.reset();
  ASSERT_EQ(record(card.device, DreamVariant::kFull, true, 40, 3), Status::kOk);
  DreamReader r;
  ASSERT_EQ(r.open(card.device, Span<uint8_t>(g_buffer, sizeof g_buffer)), Status::kOk);
  EXPECT_EQ(r.header().image_size(), (ImageSize{32, 16}));
  EXPECT_EQ(r.header().infrared_count, 3);
  EXPECT_EQ(r.header().infrared[2].angle, 16384);
  EXPECT_TRUE(r.header().wheels.circumference_right == OdometryConfig{}.circumference_right);
  DreamItem item;
  uint32_t snaps = 0, places = 0;
  Status s;
  while ((s = r.next(&item)) == Status::kOk) {
    if (item.type == DreamRecord::kSnapshot) {
      const hal::SensorSnapshot want = test::snapshot(snaps++);
      EXPECT_EQ(item.snapshot.sequence, want.sequence);
      EXPECT_EQ(item.snapshot.encoder_left, want.encoder_left);  // wrapped counts pass through
      EXPECT_EQ(item.snapshot.infrared_mm[2], want.infrared_mm[2]);
      EXPECT_EQ(item.snapshot.head_pan, want.head_pan);
    } else {
      const DreamPlace& p = item.place;
      EXPECT_EQ(p.index, places);
      EXPECT_EQ(p.pose.x.raw(), Q31_32::from_ratio(places, 5).raw());
      EXPECT_EQ(p.pose.heading.bam, places * 1000u);
      EXPECT_EQ(p.infrared_count, 3);
      for (uint32_t k = 0; k < 512; ++k) {
        if (p.gray[k] != test::place_pixel(places, k)) {
          ADD_FAILURE() << "place " << places << " pixel " << k;
          break;
        }
      }
      ASSERT_TRUE(p.yuv != nullptr);
      EXPECT_EQ(p.yuv[77], static_cast<uint8_t>(77 ^ places));
      ++places;
    }
  }
  EXPECT_EQ(s, Status::kOutOfRange);
  EXPECT_EQ(r.log_problem(), LogProblem::kEndClean);
  EXPECT_EQ(places, 40u);
  EXPECT_EQ(snaps, 120u);
  EXPECT_EQ(r.missed_snapshots(), 0u);
}

TEST(Dream, ReducedRecordingKeepsGreyAndHeadOnly) {
  static FakeCard<200> card;
  card.reset();
  ASSERT_EQ(record(card.device, DreamVariant::kReduced, false, 30, 0), Status::kOk);
  DreamWriter w;  // a snapshot is not allowed in a reduced recording
  ASSERT_EQ(w.create(card.device, test::dream_header(DreamVariant::kReduced)), Status::kOk);
  DreamProblem p = DreamProblem::kNone;
  EXPECT_EQ(w.snapshot(test::snapshot(0), &p), Status::kFailedPrecondition);
  EXPECT_EQ(p, DreamProblem::kWrongVariant);
  ASSERT_EQ(record(card.device, DreamVariant::kReduced, false, 30, 0), Status::kOk);
  DreamReader r;
  ASSERT_EQ(r.open(card.device, Span<uint8_t>(g_buffer, sizeof g_buffer)), Status::kOk);
  DreamItem item;
  uint32_t places = 0;
  while (r.next(&item) == Status::kOk) {
    EXPECT_EQ(item.type, DreamRecord::kReducedPlace);
    EXPECT_EQ(item.place.gray[100], test::place_pixel(places, 100));
    EXPECT_EQ(item.place.head_tilt, -1820);
    EXPECT_EQ(item.place.pose.x.raw(), 0);  // not stored in the reduced variant
    ++places;
  }
  EXPECT_EQ(places, 30u);
}

TEST(Dream, DroppedSnapshotsAreCountedNotInvented) {
  static FakeCard<200> card;
  card.reset();
  DreamWriter w;
  ASSERT_EQ(w.create(card.device, test::dream_header(DreamVariant::kFull)), Status::kOk);
  for (uint32_t i = 0; i < 50; ++i) {
    if (i % 10 == 3) continue;  // the bus dropped it
    ASSERT_EQ(w.snapshot(test::snapshot(i)), Status::kOk);
  }
  DreamReader r;
  ASSERT_EQ(r.open(card.device, Span<uint8_t>(g_buffer, sizeof g_buffer)), Status::kOk);
  DreamItem item;
  while (r.next(&item) == Status::kOk) {
  }
  EXPECT_EQ(r.snapshots(), 45u);
  EXPECT_EQ(r.missed_snapshots(), 5u);
}

// The bus's 32-bit sequence wraps: a recording across the wrap reads in order, its gap there
// counted; a step back (or of 2^31 and more) is still out of order.
TEST(Dream, TheBusSequenceWrapsInOrder) {
  static FakeCard<200> card;
  card.reset();
  DreamWriter w;
  ASSERT_EQ(w.create(card.device, test::dream_header(DreamVariant::kFull)), Status::kOk);
  const uint32_t sequences[] = {0xFFFFFFFDu, 0xFFFFFFFEu, 0xFFFFFFFFu, 1u, 2u, 1u, 0x80000002u};
  for (const uint32_t sequence : sequences) {
    hal::SensorSnapshot snap = test::snapshot(0);
    snap.sequence = sequence;
    ASSERT_EQ(w.snapshot(snap), Status::kOk);
  }
  DreamReader r;
  ASSERT_EQ(r.open(card.device, Span<uint8_t>(g_buffer, sizeof g_buffer)), Status::kOk);
  DreamItem item;
  for (uint32_t i = 0; i < 5; ++i)
    EXPECT_EQ(r.next(&item), Status::kOk) << "snapshot " << i;
  EXPECT_EQ(r.missed_snapshots(), 1u);          // 0 was dropped
  EXPECT_EQ(r.next(&item), Status::kDataLoss);  // back from 2 to 1
  EXPECT_EQ(r.problem(), DreamProblem::kOutOfOrder);
  EXPECT_EQ(r.next(&item), Status::kDataLoss);  // 2^31 ahead of 2: not forward
  EXPECT_EQ(r.problem(), DreamProblem::kOutOfOrder);
  EXPECT_EQ(r.next(&item), Status::kOutOfRange);
}

TEST(Dream, BadInputGetsAStatusAndAReason) {
  static FakeCard<200> card;
  DreamReader r;
  DreamProblem p = DreamProblem::kNone;
  const Span<uint8_t> buffer(g_buffer, sizeof g_buffer);
  DreamItem item;

  // Not a dream file / another version / a damaged header.
  card.reset(0);
  EXPECT_EQ(r.open(card.device, buffer, &p), Status::kDataLoss);
  EXPECT_EQ(p, DreamProblem::kLog);
  LogWriter other;
  const LogKind v2{{'S', 'Q', 'D', 'R', 'E', 'A', 'M', '1'}, 2};
  ASSERT_EQ(other.create(card.device, v2, nullptr, 0), Status::kOk);
  EXPECT_EQ(r.open(card.device, buffer, &p), Status::kFailedPrecondition);
  // A header with absurd fields, written through the raw log.
  uint8_t header[kLogHeaderPayloadMax];
  DreamHeader bad = test::dream_header(DreamVariant::kFull);
  bad.mapping.xmax = 64;  // 64 x 16 = 1024 superpixels: more than the FPGA buffer
  uint32_t n = encode_dream_header(bad, header, sizeof header);
  ASSERT_EQ(other.create(card.device, kDreamKind, header, n), Status::kOk);
  EXPECT_EQ(r.open(card.device, buffer, &p), Status::kDataLoss);
  EXPECT_EQ(p, DreamProblem::kBadHeader);
  DreamWriter w;
  EXPECT_EQ(w.create(card.device, bad, &p), Status::kInvalidArgument);
  EXPECT_EQ(p, DreamProblem::kBadHeader);
  bad = test::dream_header(DreamVariant::kFull);
  bad.wheels.ticks_per_revolution = 0;
  EXPECT_EQ(w.create(card.device, bad, &p), Status::kInvalidArgument);

  // Records with wrong sizes, unknown types and disorder, written through the raw log.
  const DreamHeader good = test::dream_header(DreamVariant::kFull);
  n = encode_dream_header(good, header, sizeof header);
  ASSERT_EQ(other.create(card.device, kDreamKind, header, n), Status::kOk);
  uint8_t junk[40] = {};
  const ByteSpan short_snapshot{junk, 10};
  ASSERT_EQ(other.append(static_cast<uint8_t>(DreamRecord::kSnapshot), &short_snapshot, 1),
            Status::kOk);
  const ByteSpan unknown{junk, 4};
  ASSERT_EQ(other.append(99, &unknown, 1), Status::kOk);
  ASSERT_EQ(r.open(card.device, buffer), Status::kOk);
  EXPECT_EQ(r.next(&item), Status::kDataLoss);
  EXPECT_EQ(r.problem(), DreamProblem::kBadRecordSize);
  EXPECT_EQ(r.next(&item), Status::kDataLoss);
  EXPECT_EQ(r.problem(), DreamProblem::kUnknownRecord);
  EXPECT_EQ(r.next(&item), Status::kOutOfRange);

  // Out of order: a snapshot going back in time, a place without its snapshot, a gap in
  // place indices (the writer refuses it; the reader reports it when a file has one).
  ASSERT_EQ(w.create(card.device, good), Status::kOk);
  ASSERT_EQ(w.snapshot(test::snapshot(5)), Status::kOk);
  ASSERT_EQ(w.snapshot(test::snapshot(4)), Status::kOk);
  ASSERT_EQ(w.place(make_place(0, test::snapshot(1))), Status::kOk);
  EXPECT_EQ(w.place(make_place(2, test::snapshot(5)), &p), Status::kInvalidArgument);
  EXPECT_EQ(p, DreamProblem::kOutOfOrder);
  ASSERT_EQ(r.open(card.device, buffer), Status::kOk);
  EXPECT_EQ(r.next(&item), Status::kOk);
  EXPECT_EQ(r.next(&item), Status::kDataLoss);
  EXPECT_EQ(r.problem(), DreamProblem::kOutOfOrder);
  EXPECT_EQ(r.next(&item), Status::kDataLoss);  // the place names snapshot 1001, last was 1005
  EXPECT_EQ(r.problem(), DreamProblem::kOutOfOrder);

  // A place with the wrong image size is refused by the writer.
  ASSERT_EQ(w.create(card.device, good), Status::kOk);
  DreamPlace wrong = make_place(0, test::snapshot(0));
  wrong.size = ImageSize{16, 32};
  EXPECT_EQ(w.place(wrong, &p), Status::kInvalidArgument);
  EXPECT_EQ(p, DreamProblem::kBadImage);

  // A checksum mismatch in the middle: reported, and reading goes on after it.
  card.reset();
  ASSERT_EQ(record(card.device, DreamVariant::kFull, false, 10, 1), Status::kOk);
  card.bytes[kFirstRecordOffset + 2 * 512 + 100] ^= 0x10;
  ASSERT_EQ(r.open(card.device, buffer), Status::kOk);
  uint32_t ok = 0, damaged = 0;
  Status s;
  while ((s = r.next(&item)) != Status::kOutOfRange) {
    if (s == Status::kOk) ++ok;
    if (s == Status::kDataLoss) ++damaged;
  }
  EXPECT_EQ(damaged, 1u);
  EXPECT_EQ(ok, 19u);

  // A truncated file (e.g. a partial copy): the device ends in the middle of a record. The
  // records before it are read; then the log reports the committed records it lost (the
  // commit slots say 20 records were written), not a clean end or a power cut.
  card.reset();
  ASSERT_EQ(record(card.device, DreamVariant::kFull, false, 10, 1), Status::kOk);
  // Header, commit slots + 4 blocks: snapshot/place pairs of 640 bytes end at 640, 1280, 1920
  // past the first record; the fourth place (1970..2560) is cut at 2048.
  Region truncated(card.device, 0, 7);
  ASSERT_EQ(r.open(truncated, buffer), Status::kOk);
  uint32_t places = 0;
  while ((s = r.next(&item)) == Status::kOk)
    places += item.type == DreamRecord::kPlace ? 1 : 0;
  EXPECT_EQ(s, Status::kDataLoss);
  EXPECT_EQ(r.log_problem(), LogProblem::kEndTruncated);
  EXPECT_EQ(r.next(&item), Status::kOutOfRange);
  EXPECT_EQ(places, 3u);
}

TEST(Dream, TruthPosesRoundTripInBothVariants) {
  static FakeCard<600> card;
  for (int variant = 1; variant <= 2; ++variant) {
    const bool full = variant == 1;
    card.reset();
    ASSERT_EQ(record(card.device, static_cast<DreamVariant>(variant), full, 20, full ? 2 : 0,
                     Truths::kSome),
              Status::kOk);
    DreamReader r;
    ASSERT_EQ(r.open(card.device, Span<uint8_t>(g_buffer, sizeof g_buffer)), Status::kOk);
    DreamItem item;
    uint32_t places = 0, truths = 0, snaps = 0;
    bool after_place = false;  // the previous item was a place (a truth must follow one)
    Status s;
    while ((s = r.next(&item)) == Status::kOk) {
      if (item.type == DreamRecord::kTruth) {
        ASSERT_TRUE(after_place);
        const DreamTruth want = make_truth(places - 1);
        EXPECT_EQ(item.truth.place_index, places - 1);
        EXPECT_EQ(item.truth.pose.x.raw(), want.pose.x.raw());
        EXPECT_EQ(item.truth.pose.y.raw(), want.pose.y.raw());
        EXPECT_EQ(item.truth.pose.heading.bam, want.pose.heading.bam);
        EXPECT_TRUE(has_truth(Truths::kSome, places - 1));
        ++truths;
        after_place = false;
        continue;
      }
      if (after_place) {
        EXPECT_FALSE(has_truth(Truths::kSome, places - 1));
      }
      after_place = item.type != DreamRecord::kSnapshot;
      if (item.type == DreamRecord::kSnapshot) {
        ++snaps;
        continue;
      }
      EXPECT_EQ(item.type, full ? DreamRecord::kPlace : DreamRecord::kReducedPlace);
      EXPECT_EQ(item.place.index, places);
      EXPECT_EQ(item.place.gray[200], test::place_pixel(places, 200));
      if (full) {
        EXPECT_EQ(item.place.pose.x.raw(), Q31_32::from_ratio(places, 5).raw());
      }
      ++places;
    }
    EXPECT_EQ(s, Status::kOutOfRange);
    EXPECT_EQ(r.log_problem(), LogProblem::kEndClean);
    EXPECT_EQ(places, 20u);
    EXPECT_EQ(r.places(), 20u);
    EXPECT_EQ(truths, 13u);  // all but places 1, 4, 7, 10, 13, 16, 19
    EXPECT_EQ(r.truths(), 13u);
    EXPECT_EQ(snaps, full ? 40u : 0u);
  }
}

TEST(Dream, WriterRefusesTruthOutOfOrder) {
  static FakeCard<200> card;
  for (int variant = 1; variant <= 2; ++variant) {
    card.reset();
    DreamWriter w;
    DreamProblem p = DreamProblem::kNone;
    EXPECT_EQ(w.truth(make_truth(0), &p), Status::kFailedPrecondition);  // not created
    ASSERT_EQ(w.create(card.device, test::dream_header(static_cast<DreamVariant>(variant))),
              Status::kOk);
    EXPECT_EQ(w.truth(make_truth(0), &p), Status::kInvalidArgument);  // before any place
    EXPECT_EQ(p, DreamProblem::kOutOfOrder);
    if (variant == 1) {
      ASSERT_EQ(w.snapshot(test::snapshot(0)), Status::kOk);
    }
    ASSERT_EQ(w.place(make_place(0, test::snapshot(0))), Status::kOk);
    p = DreamProblem::kNone;
    EXPECT_EQ(w.truth(make_truth(1), &p), Status::kInvalidArgument);  // a place not yet written
    EXPECT_EQ(p, DreamProblem::kOutOfOrder);
    ASSERT_EQ(w.truth(make_truth(0), &p), Status::kOk);
    EXPECT_EQ(p, DreamProblem::kNone);
    p = DreamProblem::kNone;
    EXPECT_EQ(w.truth(make_truth(0), &p), Status::kInvalidArgument);  // a second one
    EXPECT_EQ(p, DreamProblem::kOutOfOrder);
    if (variant == 1) {
      ASSERT_EQ(w.snapshot(test::snapshot(1)), Status::kOk);
    }
    ASSERT_EQ(w.place(make_place(1, test::snapshot(1))), Status::kOk);
    p = DreamProblem::kNone;
    EXPECT_EQ(w.truth(make_truth(0), &p), Status::kInvalidArgument);  // not the last place
    EXPECT_EQ(p, DreamProblem::kOutOfOrder);
    EXPECT_EQ(w.truth(make_truth(1)), Status::kOk);
    // What was refused was not written: the file reads back cleanly with two truths.
    DreamReader r;
    ASSERT_EQ(r.open(card.device, Span<uint8_t>(g_buffer, sizeof g_buffer)), Status::kOk);
    DreamItem item;
    Status s;
    while ((s = r.next(&item)) == Status::kOk) {
    }
    EXPECT_EQ(s, Status::kOutOfRange);
    EXPECT_EQ(r.places(), 2u);
    EXPECT_EQ(r.truths(), 2u);
  }
  // A write error: the truth gets the device's status and the log's problem, as a place would.
  card.reset();
  DreamWriter w;
  DreamProblem p = DreamProblem::kNone;
  ASSERT_EQ(w.create(card.device, test::dream_header(DreamVariant::kReduced)), Status::kOk);
  ASSERT_EQ(w.place(make_place(0, test::snapshot(0))), Status::kOk);
  hal::BlockFaults faults;
  faults.fail_write = card.device.writes() + 1;
  card.device.set_faults(faults);
  EXPECT_EQ(w.truth(make_truth(0), &p), Status::kDataLoss);
  EXPECT_EQ(p, DreamProblem::kLog);
  EXPECT_EQ(w.log_problem(), LogProblem::kDeviceError);
  EXPECT_EQ(w.truth(make_truth(0), &p), Status::kFailedPrecondition);
}

// Appends a truth record with `size` payload bytes through the raw log.
Status raw_truth(LogWriter& log, uint32_t index, uint32_t size = 24) {
  uint8_t payload[32] = {};
  ByteWriter w(payload, sizeof payload);
  w.u32(index);
  w.i64(-5);
  w.i64(7);
  w.u32(0x80000000u);
  const ByteSpan part{payload, size};
  return log.append(static_cast<uint8_t>(DreamRecord::kTruth), &part, 1);
}

// Appends reduced place `i` through the raw log (the writer would refuse the disorder).
Status raw_reduced_place(LogWriter& log, uint32_t i) {
  uint8_t fixed[16];
  ByteWriter w(fixed, sizeof fixed);
  w.u32(i);
  w.u32(i * 100);
  w.i16(0);
  w.i16(0);
  w.u16(32);
  w.u16(16);
  for (uint32_t k = 0; k < 512; ++k)
    g_gray[k] = test::place_pixel(i, k);
  const ByteSpan parts[2] = {{fixed, 16}, {g_gray, 512}};
  return log.append(static_cast<uint8_t>(DreamRecord::kReducedPlace), parts, 2);
}

TEST(Dream, ReaderRefusesBadTruthRecords) {
  static FakeCard<200> card;
  card.reset();
  uint8_t header[kLogHeaderPayloadMax];
  const uint32_t n =
      encode_dream_header(test::dream_header(DreamVariant::kReduced), header, sizeof header);
  LogWriter log;
  ASSERT_EQ(log.create(card.device, kDreamKind, header, n), Status::kOk);
  ASSERT_EQ(raw_truth(log, 0), Status::kOk);  // 1: before any place
  ASSERT_EQ(raw_reduced_place(log, 0), Status::kOk);
  ASSERT_EQ(raw_truth(log, 0, 20), Status::kOk);  // 3: too short
  ASSERT_EQ(raw_truth(log, 0, 28), Status::kOk);  // 4: too long
  ASSERT_EQ(raw_truth(log, 1), Status::kOk);      // 5: a place not read yet
  ASSERT_EQ(raw_truth(log, 0), Status::kOk);      // 6: fine
  ASSERT_EQ(raw_truth(log, 0), Status::kOk);      // 7: a second one for place 0
  ASSERT_EQ(raw_reduced_place(log, 1), Status::kOk);
  ASSERT_EQ(raw_truth(log, 0), Status::kOk);  // 9: not the last place
  ASSERT_EQ(raw_truth(log, 1), Status::kOk);  // 10: fine

  DreamReader r;
  ASSERT_EQ(r.open(card.device, Span<uint8_t>(g_buffer, sizeof g_buffer)), Status::kOk);
  DreamItem item;
  EXPECT_EQ(r.next(&item), Status::kDataLoss);
  EXPECT_EQ(r.problem(), DreamProblem::kOutOfOrder);
  ASSERT_EQ(r.next(&item), Status::kOk);
  EXPECT_EQ(item.type, DreamRecord::kReducedPlace);
  EXPECT_EQ(r.next(&item), Status::kDataLoss);
  EXPECT_EQ(r.problem(), DreamProblem::kBadRecordSize);
  EXPECT_EQ(r.next(&item), Status::kDataLoss);
  EXPECT_EQ(r.problem(), DreamProblem::kBadRecordSize);
  EXPECT_EQ(r.next(&item), Status::kDataLoss);
  EXPECT_EQ(r.problem(), DreamProblem::kOutOfOrder);
  ASSERT_EQ(r.next(&item), Status::kOk);
  EXPECT_EQ(item.type, DreamRecord::kTruth);
  EXPECT_EQ(item.truth.place_index, 0u);
  EXPECT_EQ(item.truth.pose.x.raw(), -5);
  EXPECT_EQ(item.truth.pose.y.raw(), 7);
  EXPECT_EQ(item.truth.pose.heading.bam, 0x80000000u);
  EXPECT_EQ(r.next(&item), Status::kDataLoss);
  EXPECT_EQ(r.problem(), DreamProblem::kOutOfOrder);
  ASSERT_EQ(r.next(&item), Status::kOk);
  EXPECT_EQ(item.type, DreamRecord::kReducedPlace);
  EXPECT_EQ(r.next(&item), Status::kDataLoss);
  EXPECT_EQ(r.problem(), DreamProblem::kOutOfOrder);
  ASSERT_EQ(r.next(&item), Status::kOk);
  EXPECT_EQ(item.truth.place_index, 1u);
  EXPECT_EQ(r.next(&item), Status::kOutOfRange);
  EXPECT_EQ(r.places(), 2u);
  EXPECT_EQ(r.truths(), 2u);

  // After a damaged record a truth may name the place that was lost, once.
  card.reset();
  ASSERT_EQ(log.create(card.device, kDreamKind, header, n), Status::kOk);
  ASSERT_EQ(raw_reduced_place(log, 0), Status::kOk);
  const uint64_t lost = log.end_offset();
  ASSERT_EQ(raw_reduced_place(log, 1), Status::kOk);
  ASSERT_EQ(raw_truth(log, 1), Status::kOk);
  ASSERT_EQ(raw_truth(log, 1), Status::kOk);
  ASSERT_EQ(raw_reduced_place(log, 2), Status::kOk);
  ASSERT_EQ(raw_truth(log, 2), Status::kOk);
  card.bytes[lost + 100] ^= 0x01;  // in place 1's pixels
  ASSERT_EQ(r.open(card.device, Span<uint8_t>(g_buffer, sizeof g_buffer)), Status::kOk);
  ASSERT_EQ(r.next(&item), Status::kOk);
  EXPECT_EQ(r.next(&item), Status::kDataLoss);
  EXPECT_EQ(r.problem(), DreamProblem::kLog);
  ASSERT_EQ(r.next(&item), Status::kOk);
  EXPECT_EQ(item.type, DreamRecord::kTruth);
  EXPECT_EQ(item.truth.place_index, 1u);
  EXPECT_EQ(r.next(&item), Status::kDataLoss);
  EXPECT_EQ(r.problem(), DreamProblem::kOutOfOrder);
  ASSERT_EQ(r.next(&item), Status::kOk);
  EXPECT_EQ(item.place.index, 2u);
  ASSERT_EQ(r.next(&item), Status::kOk);
  EXPECT_EQ(item.truth.place_index, 2u);
  EXPECT_EQ(r.next(&item), Status::kOutOfRange);
  EXPECT_EQ(r.truths(), 2u);
}

// What the firmware sees of a replay: every snapshot and every frame it could capture, in
// order, folded into one number (and counted).
struct ReplayTrace {
  uint32_t hash = 2166136261u;
  uint32_t snapshots = 0;
  uint32_t frames = 0;
  uint32_t skipped = 0;
  uint32_t bad = 0;
  void add(uint32_t v) { hash = (hash ^ v) * 16777619u; }
};

ReplayTrace replay_trace(hal::BlockDevice& device, bool capture_every_other) {
  static DreamReplay replay;
  ReplayTrace t;
  if (replay.open(device, Span<uint8_t>(g_buffer, sizeof g_buffer)) != Status::kOk) return t;
  if (replay.configure(replay.header().mapping) != Status::kOk) return t;
  hal::SensorSnapshot snap;
  while (replay.next(&snap) == Status::kOk) {
    ++t.snapshots;
    t.add(snap.sequence);
    t.add(snap.timestamp_us);
    t.add(snap.encoder_left);
    t.add(static_cast<uint16_t>(snap.head_pan));
    if (capture_every_other && t.snapshots % 2 == 0) continue;
    if (replay.capture() != Status::kOk) continue;
    hal::Frame frame;
    if (replay.read(&frame) != Status::kOk) continue;
    ++t.frames;
    t.add(frame.sequence);
    t.add(frame.timestamp_us);
    for (uint32_t k = 0; k < frame.size.pixels(); ++k)
      t.add(frame.gray[k]);
  }
  t.skipped = replay.skipped_places();
  t.bad = replay.bad_records();
  return t;
}

TEST(Dream, ReplayIgnoresTruthRecords) {
  static FakeCard<200> with;
  static FakeCard<200> without;
  for (int variant = 1; variant <= 2; ++variant) {
    const DreamVariant v = static_cast<DreamVariant>(variant);
    const uint32_t per_place = variant == 1 ? 3 : 0;
    with.reset();
    without.reset();
    ASSERT_EQ(record(with.device, v, false, 12, per_place, Truths::kSome), Status::kOk);
    ASSERT_EQ(record(without.device, v, false, 12, per_place, Truths::kNone), Status::kOk);
    // Full recordings also with a capture at every other snapshot only (places skipped).
    for (int every_other = 0; every_other <= (variant == 1 ? 1 : 0); ++every_other) {
      const ReplayTrace a = replay_trace(with.device, every_other == 1);
      const ReplayTrace b = replay_trace(without.device, every_other == 1);
      EXPECT_EQ(a.hash, b.hash);
      EXPECT_EQ(a.snapshots, b.snapshots);
      EXPECT_EQ(a.frames, b.frames);
      EXPECT_EQ(a.skipped, b.skipped);
      EXPECT_EQ(a.bad, 0u);
      EXPECT_EQ(b.bad, 0u);
      EXPECT_EQ(a.snapshots, variant == 1 ? 36u : 12u);
      if (every_other == 0) {
        EXPECT_EQ(a.frames, 12u);
      }
    }
  }
}

TEST(Dream, WriteErrorsAndAFullCard) {
  static FakeCard<10> small;  // 7 data blocks after the header and commit slots
  small.reset();
  Status s = record(small.device, DreamVariant::kFull, false, 50, 1);
  EXPECT_EQ(s, Status::kResourceExhausted);
  DreamReader r;
  ASSERT_EQ(r.open(small.device, Span<uint8_t>(g_buffer, sizeof g_buffer)), Status::kOk);
  DreamItem item;
  uint32_t places = 0;
  while (r.next(&item) == Status::kOk)
    places += item.type == DreamRecord::kPlace ? 1 : 0;
  EXPECT_EQ(r.log_problem(), LogProblem::kEndClean);  // a full card loses nothing written
  EXPECT_GE(places, 5u);

  static FakeCard<200> card;
  card.reset();
  hal::BlockFaults faults;
  faults.fail_write = 9;
  card.device.set_faults(faults);
  DreamWriter w;
  DreamProblem p = DreamProblem::kNone;
  s = Status::kOk;
  ASSERT_EQ(w.create(card.device, test::dream_header(DreamVariant::kFull)), Status::kOk);
  uint32_t i = 0;
  for (; i < 20 && s == Status::kOk; ++i)
    s = w.snapshot(test::snapshot(i));
  EXPECT_EQ(s, Status::kDataLoss);
  EXPECT_EQ(w.log_problem(), LogProblem::kDeviceError);
  EXPECT_EQ(w.snapshot(test::snapshot(i), &p), Status::kFailedPrecondition);
}

// Every block of a recording zeroed, and the file cut at every block: the reader reports the
// loss (kDataLoss) every time, and the places it does return are the recorded ones.
TEST(Dream, EveryCutAndEveryZeroedBlockIsReported) {
  static FakeCard<200> card;
  static FakeCard<200> copy;
  card.reset();
  DreamWriter w;
  ASSERT_EQ(w.create(card.device, test::dream_header(DreamVariant::kFull)), Status::kOk);
  for (uint32_t i = 0; i < 12; ++i) {
    ASSERT_EQ(w.snapshot(test::snapshot(i)), Status::kOk);
    ASSERT_EQ(w.place(make_place(i, test::snapshot(i))), Status::kOk);
  }
  const uint32_t blocks = static_cast<uint32_t>((w.log().end_offset() + 511) / 512);
  // How many kDataLoss a read of `device` reports; checks every place it returns.
  const auto losses = [](hal::BlockDevice& device, bool* opened) {
    DreamReader r;
    *opened = r.open(device, Span<uint8_t>(g_buffer, sizeof g_buffer)) == Status::kOk;
    uint32_t reported = 0;
    DreamItem item;
    for (uint32_t calls = 0; *opened && calls < 1000; ++calls) {
      const Status st = r.next(&item);
      if (st == Status::kDataLoss) ++reported;
      if (st == Status::kOutOfRange) break;
      if (st == Status::kOk && item.type == DreamRecord::kPlace) {
        EXPECT_EQ(item.place.gray[7], test::place_pixel(item.place.index, 7));
      }
    }
    return reported;
  };
  for (uint32_t b = 1; b < blocks; ++b) {
    hal::FakeBlockDevice cut(Span<uint8_t>(card.bytes, static_cast<size_t>(b) * 512));
    bool opened = false;
    EXPECT_GT(losses(cut, &opened), 0u) << "cut at block " << b;
    EXPECT_TRUE(opened);
    for (uint32_t k = 0; k < sizeof card.bytes; ++k)
      copy.bytes[k] = card.bytes[k];
    for (uint32_t k = 0; k < 512; ++k)
      copy.bytes[b * 512 + k] = 0;
    const uint32_t reported = losses(copy.device, &opened);
    EXPECT_TRUE(opened);
    if (b >= kFirstRecordOffset / 512) {
      EXPECT_GT(reported, 0u) << "zeroed block " << b;
    } else {
      EXPECT_EQ(reported, 0u) << "zeroed commit slot " << b;  // the other slot holds a commit
    }
  }
}

}  // namespace
}  // namespace seqslam::storage
