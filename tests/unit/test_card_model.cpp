// The SD card as a measured cost: CountingBlockDevice (hal/counting_block_device.h) against
// the fake card with its fault schedule - forwarding, request / block / failure counts, bad
// arguments, snapshots - and the SPI timing model (hal/sd_card_model.h) against times
// computed by hand from the formula in its header (docs/card_model.md).
#include "seqslam/hal/counting_block_device.h"

#include "seqslam/hal/fake_block_device.h"
#include "seqslam/hal/sd_card_model.h"
#include "seqslam/span.h"
#include "test.h"

namespace seqslam::hal {
namespace {

constexpr uint32_t kCardBlocks = 64;
constexpr uint64_t kMax = ~uint64_t{0};
constexpr uint32_t kMax32 = 0xFFFFFFFFu;

// A fresh fake card (contents: a byte pattern) and a counter in front of it, in static
// storage: the target's tests keep large objects off the stack.
struct Rig {
  uint8_t bytes[kCardBlocks * kBlockSize];
  FakeBlockDevice card{Span<uint8_t>(bytes, sizeof bytes)};
  CountingBlockDevice counted{card};
  uint8_t buffer[8 * kBlockSize];

  void reset() {
    for (uint32_t i = 0; i < sizeof bytes; ++i)
      bytes[i] = static_cast<uint8_t>(i * 7u + (i >> 9));
    card = FakeBlockDevice(Span<uint8_t>(bytes, sizeof bytes));
    counted.reset_counters();
  }
};

Rig g_rig;

Rig& fresh_rig() {
  g_rig.reset();
  return g_rig;
}

// Hides a value from the optimiser, so that the model's arithmetic (64-bit division on the
// target) runs when the test runs instead of being folded at compile time.
template <typename T>
T opaque(T v) {
  volatile T x = v;
  return x;
}

// spi_bytes_ns() on values the optimiser cannot see.
uint64_t bus_ns(uint64_t bytes, uint32_t clock_hz) {
  volatile uint32_t f = clock_hz;
  return spi_bytes_ns(opaque(bytes), f);
}

CardCounters counters(uint32_t reads, uint32_t multi_reads, uint32_t blocks_read, uint32_t writes,
                      uint32_t multi_writes, uint32_t blocks_written, uint32_t syncs = 0,
                      uint32_t failed = 0) {
  CardCounters c;
  c.read_requests = opaque(reads);
  c.multi_read_requests = opaque(multi_reads);
  c.blocks_read = opaque(blocks_read);
  c.write_requests = opaque(writes);
  c.multi_write_requests = opaque(multi_writes);
  c.blocks_written = opaque(blocks_written);
  c.sync_requests = opaque(syncs);
  c.failed_requests = opaque(failed);
  return c;
}

void expect_counters(const CardCounters& got, const CardCounters& want) {
  EXPECT_EQ(got.read_requests, want.read_requests);
  EXPECT_EQ(got.multi_read_requests, want.multi_read_requests);
  EXPECT_EQ(got.blocks_read, want.blocks_read);
  EXPECT_EQ(got.write_requests, want.write_requests);
  EXPECT_EQ(got.multi_write_requests, want.multi_write_requests);
  EXPECT_EQ(got.blocks_written, want.blocks_written);
  EXPECT_EQ(got.sync_requests, want.sync_requests);
  EXPECT_EQ(got.failed_requests, want.failed_requests);
  EXPECT_TRUE(got == want);
}

// ---- CountingBlockDevice -------------------------------------------------------------

TEST(CountingBlockDevice, ForwardsDataAndCapacityUnchanged) {
  Rig& r = fresh_rig();
  EXPECT_EQ(r.counted.block_count(), kCardBlocks);
  EXPECT_EQ(r.counted.capacity_bytes(), uint64_t{kCardBlocks} * kBlockSize);
  EXPECT_EQ(&r.counted.device(), static_cast<BlockDevice*>(&r.card));

  // A 3-block write lands on the card at the right place, and nowhere else.
  for (uint32_t i = 0; i < 3 * kBlockSize; ++i)
    r.buffer[i] = static_cast<uint8_t>(0xA5u ^ i);
  ASSERT_EQ(r.counted.write(10, 3, r.buffer), Status::kOk);
  for (uint32_t i = 0; i < 3 * kBlockSize; ++i) {
    if (r.bytes[10 * kBlockSize + i] != static_cast<uint8_t>(0xA5u ^ i)) {
      ADD_FAILURE() << "written byte " << i;
      break;
    }
  }
  EXPECT_EQ(r.bytes[10 * kBlockSize - 1], static_cast<uint8_t>((10 * kBlockSize - 1) * 7u + 9u));
  EXPECT_EQ(r.bytes[13 * kBlockSize], static_cast<uint8_t>(13 * kBlockSize * 7u + 13u));

  // Reads return the card's bytes.
  ASSERT_EQ(r.counted.read(40, 2, r.buffer), Status::kOk);
  for (uint32_t i = 0; i < 2 * kBlockSize; ++i) {
    if (r.buffer[i] != r.bytes[40 * kBlockSize + i]) {
      ADD_FAILURE() << "read byte " << i;
      break;
    }
  }
  ASSERT_EQ(r.counted.sync(), Status::kOk);
  // One call each reached the card.
  EXPECT_EQ(r.card.writes(), 1u);
  EXPECT_EQ(r.card.reads(), 1u);
  EXPECT_EQ(r.card.syncs(), 1u);
}

TEST(CountingBlockDevice, CountsRequestsMultiBlockRequestsAndBlocks) {
  Rig& r = fresh_rig();
  expect_counters(r.counted.counters(), CardCounters{});
  ASSERT_EQ(r.counted.read(0, 1, r.buffer), Status::kOk);
  ASSERT_EQ(r.counted.read(5, 8, r.buffer), Status::kOk);
  ASSERT_EQ(r.counted.read(63, 1, r.buffer), Status::kOk);
  ASSERT_EQ(r.counted.write(2, 1, r.buffer), Status::kOk);
  ASSERT_EQ(r.counted.write(20, 4, r.buffer), Status::kOk);
  ASSERT_EQ(r.counted.write(30, 2, r.buffer), Status::kOk);
  ASSERT_EQ(r.counted.sync(), Status::kOk);
  ASSERT_EQ(r.counted.sync(), Status::kOk);
  expect_counters(r.counted.counters(), counters(3, 1, 10, 3, 2, 7, 2, 0));
  // The card saw exactly the counted requests.
  EXPECT_EQ(r.card.reads(), r.counted.counters().read_requests);
  EXPECT_EQ(r.card.writes(), r.counted.counters().write_requests);
  EXPECT_EQ(r.card.syncs(), r.counted.counters().sync_requests);
  EXPECT_EQ(r.card.bytes_written(), r.counted.counters().blocks_written * kBlockSize);
}

TEST(CountingBlockDevice, DeviceFailuresArePassedThroughAndCounted) {
  Rig& r = fresh_rig();
  BlockFaults f;
  f.fail_read = 2;   // the second read reaching the card
  f.fail_write = 1;  // the first write
  r.card.set_faults(f);
  EXPECT_EQ(r.counted.read(0, 2, r.buffer), Status::kOk);
  EXPECT_EQ(r.counted.read(3, 4, r.buffer), Status::kDataLoss);
  EXPECT_EQ(r.counted.read(9, 1, r.buffer), Status::kOk);
  EXPECT_EQ(r.counted.write(1, 3, r.buffer), Status::kDataLoss);
  EXPECT_EQ(r.counted.write(1, 1, r.buffer), Status::kOk);
  // Failed requests stay in the request and block counts (the card was asked).
  expect_counters(r.counted.counters(), counters(3, 2, 7, 2, 1, 4, 0, 2));
}

TEST(CountingBlockDevice, PowerCutFailsEverythingAfterAndEveryFailureCounts) {
  Rig& r = fresh_rig();
  BlockFaults f;
  f.power_cut_after_byte = 700;  // inside the second block of the first write
  r.card.set_faults(f);
  EXPECT_EQ(r.counted.write(4, 2, r.buffer), Status::kUnavailable);
  EXPECT_FALSE(r.card.powered());
  EXPECT_EQ(r.counted.read(4, 1, r.buffer), Status::kUnavailable);
  EXPECT_EQ(r.counted.sync(), Status::kUnavailable);
  expect_counters(r.counted.counters(), counters(1, 0, 1, 1, 1, 2, 1, 3));
  r.card.restore_power();
  EXPECT_EQ(r.counted.sync(), Status::kOk);
  EXPECT_EQ(r.counted.counters().sync_requests, 2u);
  EXPECT_EQ(r.counted.counters().failed_requests, 3u);
}

TEST(CountingBlockDevice, BadArgumentsNeverReachTheCardAndAreNotCounted) {
  Rig& r = fresh_rig();
  EXPECT_EQ(r.counted.read(0, 1, nullptr), Status::kInvalidArgument);
  EXPECT_EQ(r.counted.read(0, 0, r.buffer), Status::kInvalidArgument);
  EXPECT_EQ(r.counted.read(kCardBlocks, 1, r.buffer), Status::kOutOfRange);
  EXPECT_EQ(r.counted.read(kCardBlocks - 2, 3, r.buffer), Status::kOutOfRange);
  EXPECT_EQ(r.counted.read(1, 0xFFFFFFFFu, r.buffer), Status::kOutOfRange);
  EXPECT_EQ(r.counted.write(0, 1, nullptr), Status::kInvalidArgument);
  EXPECT_EQ(r.counted.write(0, 0, r.buffer), Status::kInvalidArgument);
  EXPECT_EQ(r.counted.write(kCardBlocks - 1, 2, r.buffer), Status::kOutOfRange);
  expect_counters(r.counted.counters(), CardCounters{});
  EXPECT_EQ(r.card.reads(), 0u);
  EXPECT_EQ(r.card.writes(), 0u);
  // The last block is in range.
  EXPECT_EQ(r.counted.read(kCardBlocks - 1, 1, r.buffer), Status::kOk);
  expect_counters(r.counted.counters(), counters(1, 0, 1, 0, 0, 0));
}

TEST(CountingBlockDevice, SnapshotsGivePerStepFiguresAndResetZeroes) {
  Rig& r = fresh_rig();
  ASSERT_EQ(r.counted.read(0, 4, r.buffer), Status::kOk);  // before the "step"
  const CardCounters mark = r.counted.counters();
  ASSERT_EQ(r.counted.read(8, 3, r.buffer), Status::kOk);
  ASSERT_EQ(r.counted.write(16, 1, r.buffer), Status::kOk);
  ASSERT_EQ(r.counted.sync(), Status::kOk);
  const CardCounters step = counters(1, 1, 3, 1, 0, 1, 1, 0);
  expect_counters(r.counted.since(mark), step);
  expect_counters(difference(r.counted.counters(), mark), step);
  EXPECT_TRUE(r.counted.since(r.counted.counters()) == CardCounters{});
  r.counted.reset_counters();
  expect_counters(r.counted.counters(), CardCounters{});
  // The card's own counters are not the decorator's business.
  EXPECT_EQ(r.card.reads(), 2u);
}

TEST(CountingBlockDevice, DifferenceIsExactAcrossAWrap) {
  const CardCounters before = counters(kMax32 - 1, kMax32, kMax32 - 9, 5, 0, 0, kMax32, 7);
  const CardCounters after = counters(2, 3, 20, 6, 1, 8, 0, 7);  // each wrapped (or not) once
  expect_counters(difference(after, before), counters(4, 4, 30, 1, 1, 8, 1, 0));
  EXPECT_TRUE(difference(after, before) != CardCounters{});
}

// ---- The SPI timing model ------------------------------------------------------------
// Defaults at 25 MHz: 320 ns per byte. Bytes per command frame (CMD17/18/24/25 with
// select, NCR and R1): 2 + 6 + 8 + 1 = 17; CMD12: 6 + 8 + 1 + 2 = 17; CMD13: 2 + 6 + 8 + 2 =
// 18; a block read: 1 + 512 + 2 = 515; a block written: 1 + 1 + 512 + 2 + 1 = 517.

TEST(SdCardModel, ZeroCountersCostNothing) {
  const SdSpiTiming t;
  EXPECT_EQ(card_bus_bytes(CardCounters{}, t), 0u);
  EXPECT_EQ(card_wait_ns(CardCounters{}, t), 0u);
  EXPECT_EQ(card_time_ns(CardCounters{}), 0u);
  EXPECT_EQ(card_commands(CardCounters{}), 0u);
}

TEST(SdCardModel, OneSingleBlockRead) {
  const CardCounters c = counters(1, 0, 1, 0, 0, 0);
  const SdSpiTiming t;
  EXPECT_EQ(card_bus_bytes(c, t), 17u + 515u);
  EXPECT_EQ(card_wait_ns(c, t), 500000u);        // NAC only, no block after the first
  EXPECT_EQ(card_time_ns(c), uint64_t{670240});  // 532 * 320 + 500 000
  EXPECT_EQ(card_commands(c), 1u);               // CMD17
  static_assert(card_time_ns(CardCounters{1, 0, 1}) == 670240,
                "the model is usable at compile time");
}

TEST(SdCardModel, OneHundredBlockRead) {
  const CardCounters c = counters(1, 1, 100, 0, 0, 0);
  const SdSpiTiming t;
  EXPECT_EQ(card_bus_bytes(c, t), 17u + 17u + 100u * 515u);  // 51 534
  EXPECT_EQ(card_wait_ns(c, t), 500000u + 99u * 10000u);     // 1 490 000
  EXPECT_EQ(card_time_ns(c), uint64_t{17980880});            // 16 490 880 + 1 490 000
  EXPECT_EQ(card_commands(c), 2u);                           // CMD18 + CMD12
}

TEST(SdCardModel, OneSingleBlockWrite) {
  const CardCounters c = counters(0, 0, 0, 1, 0, 1);
  const SdSpiTiming t;
  EXPECT_EQ(card_bus_bytes(c, t), 17u + 18u + 517u);  // 552
  EXPECT_EQ(card_wait_ns(c, t), 1000000u + 50000u);
  EXPECT_EQ(card_time_ns(c), uint64_t{1226640});  // 176 640 + 1 050 000
  EXPECT_EQ(card_commands(c), 2u);                // CMD24 + CMD13
  // Without the status check: one command, 18 bytes (5 760 ns) less.
  SdSpiTiming no_status;
  no_status.status_after_write = 0;
  EXPECT_EQ(card_time_ns(c, no_status), uint64_t{1220880});
  EXPECT_EQ(card_commands(c, no_status), 1u);
}

TEST(SdCardModel, OneEightBlockWriteAndASync) {
  const CardCounters c = counters(0, 0, 0, 1, 1, 8, 1);
  const SdSpiTiming t;
  EXPECT_EQ(card_bus_bytes(c, t), 17u + 18u + 2u + 8u * 517u + 1u);  // 4 174
  EXPECT_EQ(card_wait_ns(c, t), 1000000u + 8u * 50000u);
  EXPECT_EQ(card_time_ns(c), uint64_t{2735680});  // 1 335 680 + 1 400 000
  EXPECT_EQ(card_commands(c), 2u);                // CMD25 + CMD13; Stop Tran is a token
}

TEST(SdCardModel, A450PlaceLibraryOneBlockAtATimeAndInOneRequest) {
  // docs/card_model.md's worked example.
  const uint64_t singles = card_time_ns(counters(450, 0, 450, 0, 0, 0));
  const uint64_t one_request = card_time_ns(counters(1, 1, 450, 0, 0, 0));
  EXPECT_EQ(singles, uint64_t{301608000});     // 450 * 670 240
  EXPECT_EQ(one_request, uint64_t{79160880});  // 231 784 * 320 + 500 000 + 449 * 10 000
  EXPECT_LT(one_request, singles);
}

TEST(SdCardModel, FailedRequestsCostTheSameAsGoodOnes) {
  EXPECT_EQ(card_time_ns(counters(1, 0, 1, 0, 0, 0, 0, 1)),
            card_time_ns(counters(1, 0, 1, 0, 0, 0, 0, 0)));
}

TEST(SdCardModel, TimeGrowsWithEveryCounter) {
  // Start from a mixed set and grow each field alone: the time never falls, and grows for
  // every field that stands for bus bytes or card time (all but failed_requests).
  const CardCounters base = counters(3, 1, 12, 2, 1, 9, 1, 0);
  const uint64_t t0 = card_time_ns(base);
  CardCounters c = base;
  ++c.read_requests;
  EXPECT_GT(card_time_ns(c), t0);
  c = base;
  ++c.multi_read_requests;
  EXPECT_GT(card_time_ns(c), t0);
  c = base;
  ++c.blocks_read;
  EXPECT_GT(card_time_ns(c), t0);
  c = base;
  ++c.write_requests;
  EXPECT_GT(card_time_ns(c), t0);
  c = base;
  ++c.multi_write_requests;
  EXPECT_GT(card_time_ns(c), t0);
  c = base;
  ++c.blocks_written;
  EXPECT_GT(card_time_ns(c), t0);
  c = base;
  ++c.sync_requests;
  EXPECT_GT(card_time_ns(c), t0);
  c = base;
  ++c.failed_requests;
  EXPECT_EQ(card_time_ns(c), t0);
  // Reading more blocks one request at a time only ever costs more.
  uint64_t previous = 0;
  for (uint32_t n = 1; n <= 64; ++n) {
    const uint64_t now = card_time_ns(counters(n, 0, n, 0, 0, 0));
    EXPECT_GT(now, previous);
    // One multi-block request is never dearer than n single-block ones.
    EXPECT_LE(card_time_ns(counters(1, n > 1 ? 1 : 0, n, 0, 0, 0)), now);
    previous = now;
  }
}

TEST(SdCardModel, ParametersAreUsed) {
  // A user's measured card: other access and busy times, another clock.
  SdSpiTiming t;
  t.spi_clock_hz = 12500000;  // 640 ns per byte
  t.read_access_ns = 250000;
  t.read_next_block_ns = 0;
  EXPECT_EQ(card_time_ns(counters(1, 1, 4, 0, 0, 0), t),
            uint64_t{(17 + 17 + 4 * 515) * 640 + 250000});
  // Only the bus left: the time is bytes * 8 / f.
  SdSpiTiming bus_only;
  bus_only.read_access_ns = 0;
  bus_only.read_next_block_ns = 0;
  bus_only.write_request_busy_ns = 0;
  bus_only.write_block_busy_ns = 0;
  const CardCounters c = counters(2, 1, 9, 3, 1, 5, 2);
  EXPECT_EQ(card_wait_ns(c, bus_only), 0u);
  EXPECT_EQ(card_time_ns(c, bus_only), card_bus_bytes(c, bus_only) * 320u);
  // Every byte parameter counts.
  SdSpiTiming longer_ncr;
  longer_ncr.ncr_bytes = 9;
  EXPECT_EQ(card_bus_bytes(c, longer_ncr), card_bus_bytes(c, SdSpiTiming{}) + 2 + 1 + 3 + 3);
}

TEST(SdCardModel, BusTimeRoundsToTheNearestNanosecondAndSaturates) {
  EXPECT_EQ(bus_ns(0, 25000000), 0u);
  EXPECT_EQ(bus_ns(1, 25000000), 320u);
  EXPECT_EQ(bus_ns(1, 18000000), 444u);  // 444.44 (72 MHz / 4)
  EXPECT_EQ(bus_ns(2, 18000000), 889u);  // 888.89
  EXPECT_EQ(bus_ns(9, 18000000), 4000u);
  EXPECT_EQ(bus_ns(3, 16000000), 1500u);
  EXPECT_EQ(bus_ns(1, 3), 2666666667u);   // 8/3 s, rounded up
  EXPECT_EQ(bus_ns(1, 0xFFFFFFFFu), 2u);  // 1.86 ns
  // Large counts stay exact: 10^15 bytes at 25 MHz is 3.2 * 10^17 ns.
  EXPECT_EQ(bus_ns(uint64_t{1000000000000000}, 25000000), uint64_t{320000000000000000});
  EXPECT_EQ(bus_ns(uint64_t{1000000000000001}, 18000000), uint64_t{444444444444444889});
  EXPECT_EQ(bus_ns(kMax, 25000000), kMax);
  EXPECT_EQ(bus_ns(1, 0), kMax);
  EXPECT_EQ(bus_ns(0, 0), 0u);
  // Full 32-bit counters stay exact in 64 bits: 2^32 - 1 one-block reads with their CMD12
  // (as if multi-block) cost (549 bytes * 320 ns + 500 us) each.
  EXPECT_EQ(card_time_ns(counters(kMax32, kMax32, kMax32, 0, 0, 0)),
            uint64_t{kMax32} * (549 * 320 + 500000));
  EXPECT_EQ(card_commands(counters(kMax32, kMax32, kMax32, kMax32, 0, kMax32)),
            uint64_t{kMax32} * 4);  // CMD17/18, CMD12, CMD24, CMD13
  // Extreme parameters saturate instead of wrapping to a small time.
  SdSpiTiming slow;
  slow.write_request_busy_ns = kMax32;
  slow.write_block_busy_ns = kMax32;
  slow.nwr_bytes = kMax32;
  const CardCounters writes = counters(0, 0, 0, kMax32, 0, kMax32);
  EXPECT_EQ(card_wait_ns(writes, slow), kMax);
  EXPECT_EQ(card_bus_bytes(writes, slow), kMax);
  EXPECT_EQ(card_time_ns(writes, slow), kMax);
}

// The decorator and the model together: one "step" of traffic on the fake card, priced.
TEST(SdCardModel, PricesTheTrafficCountedOnTheFakeCard) {
  Rig& r = fresh_rig();
  ASSERT_EQ(r.counted.write(0, 1, r.buffer), Status::kOk);  // before the step
  const CardCounters mark = r.counted.counters();
  ASSERT_EQ(r.counted.read(8, 8, r.buffer), Status::kOk);    // the library
  ASSERT_EQ(r.counted.read(1, 1, r.buffer), Status::kOk);    // a header
  ASSERT_EQ(r.counted.write(30, 1, r.buffer), Status::kOk);  // a result record
  ASSERT_EQ(r.counted.sync(), Status::kOk);
  const CardCounters step = r.counted.since(mark);
  // 8-block read: 17 + 17 + 8 * 515 bytes, 500 + 7 * 10 us; single read 670.24 us; single
  // write 1 226.64 us; sync 0.32 us.
  const uint64_t eight = uint64_t{17 + 17 + 8 * 515} * 320 + 500000 + 7 * 10000;
  EXPECT_EQ(card_time_ns(step), eight + 670240 + 1226640 + 320);
  EXPECT_EQ(card_commands(step), 5u);  // CMD18, CMD12, CMD17, CMD24, CMD13
}

}  // namespace
}  // namespace seqslam::hal
