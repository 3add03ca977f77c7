// Dream-sequence recordings: round trips of both variants and every kind of bad input.
#include "seqslam/storage/dream.h"

#include "seqslam/storage/bytes.h"
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

// Writes `places` places, with `per_place` snapshots before each (full variant).
Status record(hal::BlockDevice& device, DreamVariant variant, bool colour, uint32_t places,
              uint32_t per_place) {
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
  card.bytes[512 * 3 + 100] ^= 0x10;
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
  // records before it are read; the cut one ends the log as a damaged tail.
  card.reset();
  ASSERT_EQ(record(card.device, DreamVariant::kFull, false, 10, 1), Status::kOk);
  // Header + 4 blocks: snapshot/place pairs of 640 bytes end at 1152, 1792, 2432; the fourth
  // place (2482..3072) is cut at 2560.
  Region truncated(card.device, 0, 5);
  ASSERT_EQ(r.open(truncated, buffer), Status::kOk);
  uint32_t places = 0;
  while ((s = r.next(&item)) == Status::kOk)
    places += item.type == DreamRecord::kPlace ? 1 : 0;
  EXPECT_EQ(s, Status::kOutOfRange);
  EXPECT_EQ(r.log_problem(), LogProblem::kEndDamagedTail);
  EXPECT_EQ(places, 3u);
}

TEST(Dream, WriteErrorsAndAFullCard) {
  static FakeCard<8> small;  // 7 data blocks: a handful of places
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

}  // namespace
}  // namespace seqslam::storage
