// The query history on the card (storage/query_store.h): round trips through the ring, images
// that are not a whole block, a failing write that must not leave a half-written step
// readable, failing reads, sizes the board cannot keep, bad configuration.
#include "seqslam/storage/query_store.h"

#include "seqslam/hal/counting_block_device.h"
#include "storage_fixtures.h"
#include "synthetic.h"
#include "test.h"

namespace seqslam {
namespace {

void image(uint32_t step, uint32_t pixels, uint8_t* out) {
  for (uint32_t k = 0; k < pixels; ++k)
    out[k] = test::place_pixel(step, k);
}

bool same(const uint8_t* a, uint32_t step, uint32_t pixels) {
  for (uint32_t k = 0; k < pixels; ++k) {
    if (a[k] != test::place_pixel(step, k)) return false;
  }
  return true;
}

TEST(StoredQueryHistory, RingOfWholeBlockImages) {
  static test::FakeCard<12> card;
  card.reset();
  uint8_t buffer[512];
  uint32_t grew[1];
  storage::StoredQueryHistory h;
  ASSERT_EQ(h.configure(card.device, 512, Span<uint8_t>(buffer), Span<uint32_t>(grew)),
            Status::kOk);
  EXPECT_EQ(h.capacity(), 12u);  // the file's 12 slots, fewer than the 32 bits
  uint8_t img[512];
  for (uint32_t step = 0; step < 30; ++step) {
    image(step, 512, img);
    ASSERT_EQ(h.put(step, img, 100 + step), Status::kOk);
    // Every step of the last 12 reads back, older ones are gone.
    for (uint32_t back = 0; back <= step; ++back) {
      const uint8_t* px = nullptr;
      uint32_t n = 0;
      const Status s = h.get(back, &px, &n);
      if (step - back < 12) {
        ASSERT_EQ(s, Status::kOk) << step << " " << back;
        EXPECT_TRUE(same(px, back, 512));
        EXPECT_EQ(n, 100 + back);
      } else {
        EXPECT_EQ(s, Status::kNotFound);
      }
    }
  }
}

TEST(StoredQueryHistory, ImagesOfPartBlocksAndOfSeveralBlocks) {
  static test::FakeCard<16> card;
  for (uint32_t pixels : {500u, 700u}) {  // 25x20 in one block; two blocks
    card.reset();
    uint8_t buffer[1024];
    uint32_t grew[1];
    storage::StoredQueryHistory h;
    ASSERT_EQ(h.configure(card.device, pixels, Span<uint8_t>(buffer), Span<uint32_t>(grew)),
              Status::kOk);
    EXPECT_EQ(h.capacity(), pixels <= 512 ? 16u : 8u);
    uint8_t img[700];
    for (uint32_t step = 0; step < 20; ++step) {
      image(step, pixels, img);
      ASSERT_EQ(h.put(step, img, 7), Status::kOk);
    }
    const uint8_t* px = nullptr;
    uint32_t n = 0;
    ASSERT_EQ(h.get(19 - (h.capacity() - 1), &px, &n), Status::kOk);
    EXPECT_TRUE(same(px, 19 - (h.capacity() - 1), pixels));
  }
}

TEST(StoredQueryHistory, LibrarySizesAsGrowthBitsThroughTheRing) {
  static test::FakeCard<20> card;
  card.reset();
  uint8_t buffer[512];
  uint32_t grew[1];
  storage::StoredQueryHistory h;
  ASSERT_EQ(h.configure(card.device, 512, Span<uint8_t>(buffer), Span<uint32_t>(grew)),
            Status::kOk);
  test::Rng rng(77);
  uint32_t sizes[200];
  uint32_t n = 50;
  uint8_t img[512];
  for (uint32_t step = 0; step < 200; ++step) {
    if (step == 120) {  // a reset: any size again
      h.clear();
      n = 7;
    } else if (rng.below(3) == 0) {
      ++n;  // loop closure adds a place on some steps
    }
    sizes[step] = n;
    image(step, 512, img);
    ASSERT_EQ(h.put(step, img, n), Status::kOk) << step;
    for (uint32_t back = step >= 19 ? step - 19 : 0; back <= step; ++back) {
      if (step >= 120 && back < 120) continue;  // forgotten by the reset
      uint32_t got = 0;
      ASSERT_EQ(h.places(back, &got), Status::kOk) << step << " " << back;
      EXPECT_EQ(got, sizes[back]) << step << " " << back;
    }
  }
}

TEST(StoredQueryHistory, PrefetchReadsConsecutiveStepsInOneRequest) {
  static test::FakeCard<10> card;
  card.reset();
  hal::CountingBlockDevice counted(card.device);
  uint8_t buffer[4 * 512];  // four slots
  uint32_t grew[1];
  storage::StoredQueryHistory h;
  ASSERT_EQ(h.configure(counted, 512, Span<uint8_t>(buffer), Span<uint32_t>(grew)),
            Status::kOk);
  uint8_t img[512];
  for (uint32_t step = 0; step < 14; ++step) {  // slots 0..9 hold steps 10..13 and 4..9
    image(step, 512, img);
    ASSERT_EQ(h.put(step, img, step), Status::kOk);
  }
  counted.reset_counters();
  uint32_t ready = 0;
  ASSERT_EQ(h.prefetch(5, 9, &ready), Status::kOk);
  EXPECT_EQ(ready, 4u);  // the buffer's four slots
  EXPECT_EQ(counted.counters().read_requests, 1u);
  EXPECT_EQ(counted.counters().blocks_read, 4u);
  for (uint32_t step = 5; step < 9; ++step) {
    const uint8_t* px = nullptr;
    uint32_t n = 0;
    ASSERT_EQ(h.get(step, &px, &n), Status::kOk);
    EXPECT_TRUE(same(px, step, 512)) << step;
    EXPECT_EQ(n, step);
  }
  EXPECT_EQ(counted.counters().read_requests, 1u);  // all four from the buffer
  // Across the ring's end: steps 9 (slot 9) then 10 (slot 0) are two requests.
  ASSERT_EQ(h.prefetch(9, 5, &ready), Status::kOk);
  EXPECT_EQ(ready, 1u);
  ASSERT_EQ(h.prefetch(10, 4, &ready), Status::kOk);
  EXPECT_EQ(ready, 4u);
  EXPECT_EQ(counted.counters().read_requests, 3u);
  // Steps no longer kept, and bad arguments.
  EXPECT_EQ(h.prefetch(3, 2, &ready), Status::kNotFound);
  EXPECT_EQ(h.prefetch(5, 0, &ready), Status::kInvalidArgument);
  uint32_t n = 0;
  EXPECT_EQ(h.places(12, &n), Status::kOk);
  EXPECT_EQ(n, 12u);
  EXPECT_EQ(h.places(2, &n), Status::kNotFound);
}

TEST(StoredQueryHistory, AFailedWriteLosesTheStepAndTheOneItsSlotHeld) {
  static test::FakeCard<4> card;
  card.reset();
  uint8_t buffer[512];
  uint32_t grew[1];
  storage::StoredQueryHistory h;
  ASSERT_EQ(h.configure(card.device, 512, Span<uint8_t>(buffer), Span<uint32_t>(grew)),
            Status::kOk);
  uint8_t img[512];
  for (uint32_t step = 0; step < 6; ++step) {
    image(step, 512, img);
    ASSERT_EQ(h.put(step, img, 1), Status::kOk);
  }
  hal::BlockFaults f;
  f.fail_write = 7;  // the next write
  card.device.set_faults(f);
  image(6, 512, img);
  EXPECT_EQ(h.put(6, img, 1), Status::kDataLoss);
  const uint8_t* px = nullptr;
  uint32_t n = 0;
  EXPECT_EQ(h.get(6, &px, &n), Status::kNotFound);
  EXPECT_EQ(h.get(2, &px, &n), Status::kNotFound);  // step 6 was going into its slot
  ASSERT_EQ(h.get(3, &px, &n), Status::kOk);
  EXPECT_TRUE(same(px, 3, 512));
  // The step can be retried.
  ASSERT_EQ(h.put(6, img, 1), Status::kOk);
  ASSERT_EQ(h.get(6, &px, &n), Status::kOk);
  EXPECT_TRUE(same(px, 6, 512));
}

TEST(StoredQueryHistory, FailingReadsAndBadInput) {
  static test::FakeCard<4> card;
  card.reset();
  uint8_t buffer[512];
  uint32_t grew[1];
  storage::StoredQueryHistory h;
  EXPECT_EQ(h.configure(card.device, 0, Span<uint8_t>(buffer), Span<uint32_t>(grew)),
            Status::kInvalidArgument);
  EXPECT_EQ(h.configure(card.device, 600, Span<uint8_t>(buffer), Span<uint32_t>(grew)),
            Status::kInvalidArgument);  // a two-block image needs a two-block buffer
  EXPECT_EQ(h.configure(card.device, 512, Span<uint8_t>(buffer), Span<uint32_t>()),
            Status::kResourceExhausted);
  ASSERT_EQ(h.configure(card.device, 512, Span<uint8_t>(buffer), Span<uint32_t>(grew)),
            Status::kOk);
  uint8_t img[512];
  image(0, 512, img);
  ASSERT_EQ(h.put(0, img, 9), Status::kOk);
  image(1, 512, img);
  EXPECT_EQ(h.put(1, img, 11), Status::kOutOfRange);  // sizes stay or grow by one a step
  EXPECT_EQ(h.put(1, img, 8), Status::kOutOfRange);
  ASSERT_EQ(h.put(1, img, 9), Status::kOk);
  hal::BlockFaults f;
  f.fail_read = 1;
  card.device.set_faults(f);
  const uint8_t* px = nullptr;
  uint32_t n = 0;
  EXPECT_EQ(h.get(0, &px, &n), Status::kDataLoss);  // step 1 is buffered, step 0 is read
  ASSERT_EQ(h.get(0, &px, &n), Status::kOk);        // the read is retried
  EXPECT_TRUE(same(px, 0, 512));
  EXPECT_EQ(h.get(1, nullptr, &n), Status::kInvalidArgument);
}

}  // namespace
}  // namespace seqslam
