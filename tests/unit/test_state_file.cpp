// The `state` file (state_file.h): a saved state reads back byte for byte across many
// records; a state cut by a power cut at any write, damaged, saved with another key, or read
// beyond its end is refused with its reason, never read in part.
#include "seqslam/storage/state_file.h"

#include "seqslam/hal/fake_block_device.h"
#include "storage_fixtures.h"
#include "test.h"

namespace seqslam::storage {
namespace {

constexpr uint32_t kKey = 0x51A7E001u;
constexpr uint32_t kBytes = 3000;  // seven chunks, the last one partly filled

uint8_t byte_at(uint32_t i) {
  return static_cast<uint8_t>(i * 7u + (i >> 8));
}

// Writes the state in pieces of 1 to 13 bytes, as StateOut writes fields.
Status save(hal::BlockDevice& device, uint32_t key = kKey) {
  StateFileWriter w;
  Status s = w.create(device, key);
  uint8_t piece[13];
  for (uint32_t i = 0; i < kBytes && s == Status::kOk;) {
    const uint32_t n = 1 + i % 13 < kBytes - i ? 1 + i % 13 : kBytes - i;
    for (uint32_t k = 0; k < n; ++k)
      piece[k] = byte_at(i + k);
    s = w.write(piece, n);
    i += n;
  }
  if (s == Status::kOk) s = w.finish();
  return s;
}

TEST(StateFile, ReadsBackByteForByte) {
  static test::FakeCard<40> card;
  card.reset();
  ASSERT_EQ(save(card.device), Status::kOk);
  StateFileReader r;
  StateProblem p = StateProblem::kLog;
  ASSERT_EQ(r.open(card.device, kKey, &p), Status::kOk);
  EXPECT_EQ(p, StateProblem::kNone);
  EXPECT_EQ(r.bytes(), kBytes);
  uint8_t b[7];
  for (uint32_t i = 0; i < kBytes; i += 7) {
    const uint32_t n = kBytes - i < 7 ? kBytes - i : 7;
    ASSERT_EQ(r.read(b, n), Status::kOk) << i;
    for (uint32_t k = 0; k < n; ++k)
      ASSERT_EQ(b[k], byte_at(i + k)) << i + k;
  }
  EXPECT_TRUE(r.at_end());
  EXPECT_EQ(r.read(b, 1), Status::kDataLoss);
  EXPECT_EQ(r.problem(), StateProblem::kOverrun);
}

TEST(StateFile, RefusesAnotherKeyADamagedStateAndAnyCut) {
  static test::FakeCard<40> card;
  card.reset();
  ASSERT_EQ(save(card.device, kKey + 1), Status::kOk);
  StateFileReader r;
  StateProblem p = StateProblem::kNone;
  EXPECT_EQ(r.open(card.device, kKey, &p), Status::kFailedPrecondition);
  EXPECT_EQ(p, StateProblem::kKey);
  uint8_t b[1];
  EXPECT_EQ(r.read(b, 1), Status::kDataLoss);  // nothing to read after a refusal

  // A byte of a chunk flipped: the record's CRC fails.
  card.reset();
  ASSERT_EQ(save(card.device), Status::kOk);
  card.bytes[3 * 512 + 200] ^= 0x01;
  EXPECT_EQ(r.open(card.device, kKey, &p), Status::kDataLoss);
  EXPECT_EQ(p, StateProblem::kLog);

  // A power cut after every write of the save, and in the middle of each: no state at all
  // until its end record is on the card (its block is the second-last write, its commit the
  // last); from then on the whole state.
  card.reset();
  ASSERT_EQ(save(card.device), Status::kOk);
  const uint64_t total = card.device.bytes_written();
  const uint64_t end_record = total - 2 * hal::kBlockSize;  // its block write starts here
  uint32_t cuts = 0, whole = 0;
  for (uint64_t cut = 0; cut < total; cut += 256) {
    card.reset();
    hal::BlockFaults faults;
    faults.power_cut_after_byte = cut;
    card.device.set_faults(faults);
    EXPECT_NE(save(card.device), Status::kOk);
    card.device.restore_power();
    card.device.set_faults(hal::BlockFaults{});
    ++cuts;
    if (r.open(card.device, kKey, &p) != Status::kOk) {
      EXPECT_TRUE(p == StateProblem::kIncomplete || p == StateProblem::kLog)
          << state_problem_text(p);
      continue;
    }
    EXPECT_GT(cut, end_record) << "a state before its end record was written";
    bool same = r.bytes() == kBytes;
    for (uint32_t i = 0; i < kBytes && same; ++i)
      same = r.read(b, 1) == Status::kOk && b[0] == byte_at(i);
    EXPECT_TRUE(same) << "cut after byte " << static_cast<uint32_t>(cut);
    ++whole;
  }
  EXPECT_GT(cuts, 20u);
  EXPECT_GE(whole, 1u);
  EXPECT_LE(whole, 3u);
}

TEST(StateFile, AStateSavedTwiceIsTheLastOne) {
  static test::FakeCard<40> card;
  card.reset();
  ASSERT_EQ(save(card.device), Status::kOk);
  // A shorter state over it: the old chunks are of an older session, never read.
  StateFileWriter w;
  ASSERT_EQ(w.create(card.device, kKey), Status::kOk);
  const uint8_t one[3] = {9, 8, 7};
  ASSERT_EQ(w.write(one, 3), Status::kOk);
  ASSERT_EQ(w.finish(), Status::kOk);
  EXPECT_EQ(w.write(one, 1), Status::kFailedPrecondition);
  StateFileReader r;
  ASSERT_EQ(r.open(card.device, kKey), Status::kOk);
  EXPECT_EQ(r.bytes(), 3u);
  uint8_t b[3];
  ASSERT_EQ(r.read(b, 3), Status::kOk);
  EXPECT_EQ(b[2], 7);
  EXPECT_TRUE(r.at_end());
}

}  // namespace
}  // namespace seqslam::storage
