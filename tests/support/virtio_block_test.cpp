// Target test of seqslam::board::VirtioBlockDevice (hal/board/qemu_virt/virtio_block.h)
// against a real disk-image file. Registered in tests/support/CMakeLists.txt as a chain of
// ctests:
//   virtio_block.disk_create  scripts/make-test-disk.sh writes the host pattern into a fresh
//                             image of VIRTIO_BLOCK_TEST_IMAGE_BLOCKS blocks;
//   virtio_block.qemu         this program under scripts/qemu-run.sh with SEQSLAM_QEMU_DISK
//                             set: reads the host pattern, writes the ranges in kWrites;
//   virtio_block.disk_verify  the script checks on the host that the image holds exactly
//                             the firmware's pattern in those ranges and the host pattern
//                             everywhere else.
// Run by hand it needs a fresh image each time (make-test-disk.sh create), since it checks
// the host pattern before writing:
//   scripts/make-test-disk.sh create /tmp/d.img 1000 &&
//   scripts/qemu-run.sh --disk /tmp/d.img build/target/tests/support/virtio_block_test.elf
// Built a second time with VIRTIO_BLOCK_TEST_NO_DISK (virtio_block_nodisk.qemu, no disk
// attached): init() must report kUnavailable and the program must still exit cleanly.
//
// Block contents (shared with scripts/make-test-disk.sh): 32 lines of 16 bytes,
//   "<tag><block, 8 decimal digits> L<line, 2 digits>\n"
// with tag "BLK" as the host wrote it and "WRT" where the firmware wrote.
#include "seqslam/board/virtio_block.h"
#include "seqslam/board/board.h"
#include "seqslam/status.h"
#include "test.h"
#include "test_log.h"

namespace {

using seqslam::Status;
using seqslam::status_name;
using seqslam::board::VirtioBlockDevice;
using seqslam::hal::kBlockSize;

void fill_bytes(uint8_t* p, uint8_t value, uint32_t n) {
  for (uint32_t i = 0; i < n; ++i) {
    p[i] = value;
  }
}

bool starts_with(const char* text, const char* prefix) {
  for (; *prefix != '\0'; ++prefix, ++text) {
    if (*text != *prefix) {
      return false;
    }
  }
  return true;
}

// A driver object that is never initialised: every call is answered by the interface's
// checks or by the driver without touching the hardware.
VirtioBlockDevice g_uninitialised;

TEST(VirtioBlockUninitialised, AnswersWithoutHardware) {
  uint8_t block[kBlockSize];
  fill_bytes(block, 0xA5, kBlockSize);
  EXPECT_FALSE(g_uninitialised.ready());
  EXPECT_STREQ(g_uninitialised.reason(), "not initialised");
  EXPECT_EQ(g_uninitialised.block_count(), 0u);
  EXPECT_EQ(g_uninitialised.read(0, 1, block), Status::kOutOfRange);
  EXPECT_EQ(g_uninitialised.write(0, 1, block), Status::kOutOfRange);
  EXPECT_EQ(g_uninitialised.sync(), Status::kUnavailable);
  EXPECT_EQ(g_uninitialised.counters().requests, 0u);
  EXPECT_EQ(block[0], 0xA5);
}

#if defined(VIRTIO_BLOCK_TEST_NO_DISK)

VirtioBlockDevice g_disk;

TEST(VirtioBlockNoDisk, InitReportsUnavailable) {
  const Status s = g_disk.init();
  EXPECT_EQ(s, Status::kUnavailable) << status_name(s);
  EXPECT_FALSE(g_disk.ready());
  EXPECT_EQ(g_disk.slot(), -1);
  EXPECT_EQ(g_disk.block_count(), 0u);
  EXPECT_TRUE(starts_with(g_disk.reason(), "no device")) << g_disk.reason();
  minitest::internal::print_raw("[ reason   ] ");
  minitest::internal::print_raw(g_disk.reason());
  minitest::internal::print_raw("\n");
}

TEST(VirtioBlockNoDisk, CallsAfterFailedInitDoNotReachTheDevice) {
  uint8_t block[kBlockSize];
  fill_bytes(block, 0x5A, kBlockSize);
  EXPECT_EQ(g_disk.read(0, 1, block), Status::kOutOfRange);
  EXPECT_EQ(g_disk.write(0, 1, block), Status::kOutOfRange);
  EXPECT_EQ(g_disk.read(0, 1, nullptr), Status::kInvalidArgument);
  EXPECT_EQ(g_disk.sync(), Status::kUnavailable);
  EXPECT_EQ(g_disk.counters().requests, 0u);
  EXPECT_EQ(block[kBlockSize - 1], 0x5A);
  // A second probe gives the same answer.
  EXPECT_EQ(g_disk.init(), Status::kUnavailable);
}

#else  // a disk is attached

constexpr uint32_t kImageBlocks = VIRTIO_BLOCK_TEST_IMAGE_BLOCKS;
constexpr uint32_t kLinesPerBlock = kBlockSize / 16;

// Writes the pattern of `block` with a three-letter tag into out[0, 512).
void fill_block(const char* tag, uint32_t block, uint8_t* out) {
  for (uint32_t line = 0; line < kLinesPerBlock; ++line) {
    uint8_t* p = out + line * 16;
    p[0] = static_cast<uint8_t>(tag[0]);
    p[1] = static_cast<uint8_t>(tag[1]);
    p[2] = static_cast<uint8_t>(tag[2]);
    uint32_t v = block;
    for (int d = 10; d >= 3; --d) {
      p[d] = static_cast<uint8_t>('0' + v % 10);
      v /= 10;
    }
    p[11] = ' ';
    p[12] = 'L';
    p[13] = static_cast<uint8_t>('0' + line / 10);
    p[14] = static_cast<uint8_t>('0' + line % 10);
    p[15] = '\n';
  }
}

void fill_blocks(const char* tag, uint32_t first, uint32_t count, uint8_t* out) {
  for (uint32_t i = 0; i < count; ++i) {
    fill_block(tag, first + i, out + i * kBlockSize);
  }
}

// Index of the first differing byte, or `n` when equal.
uint32_t first_difference(const uint8_t* a, const uint8_t* b, uint32_t n) {
  for (uint32_t i = 0; i < n; ++i) {
    if (a[i] != b[i]) {
      return i;
    }
  }
  return n;
}

struct Range {
  uint32_t first;
  uint32_t count;
};

// Every range the firmware writes ("WRT" pattern). The host check gets the same list from
// CMake (VIRTIO_BLOCK_TEST_WRITES); WrittenRangesMatchTheHostCheck compares the two.
constexpr Range kSingle{5, 1};
constexpr Range kOdd{100, 7};
constexpr Range kLong{200, 300};  // several requests of max_request_blocks()
constexpr Range kUnaligned{600, 2};
constexpr Range kEnd{kImageBlocks - 3, 3};
constexpr Range kWrites[] = {kSingle, kOdd, kLong, kUnaligned, kEnd};
static_assert(kImageBlocks > kUnaligned.first + kUnaligned.count + 3, "image too small");

// Blocks the firmware has written so far (they hold "WRT" from then on).
bool g_written[kImageBlocks];

bool written(uint32_t block) {
  return g_written[block];
}

// The largest transfer plus room for a misaligned start.
constexpr uint32_t kBufferBlocks = kLong.count;
alignas(16) uint8_t g_buffer[kBufferBlocks * kBlockSize + 16];
alignas(16) uint8_t g_expected[kBufferBlocks * kBlockSize];

VirtioBlockDevice g_disk;

bool disk_ready() {
  return g_disk.ready() || g_disk.init() == Status::kOk;
}

// Reads [first, first + count) into `buffer` and compares it block by block with what the
// image must hold now (host or firmware pattern).
void expect_contents(uint32_t first, uint32_t count, uint8_t* buffer) {
  const Status s = g_disk.read(first, count, buffer);
  ASSERT_EQ(s, Status::kOk) << status_name(s) << " " << g_disk.reason();
  for (uint32_t i = 0; i < count; ++i) {
    const uint32_t block = first + i;
    fill_block(written(block) ? "WRT" : "BLK", block, g_expected);
    const uint32_t at = first_difference(buffer + i * kBlockSize, g_expected, kBlockSize);
    ASSERT_EQ(at, kBlockSize) << "block " << block << " differs at byte " << at;
  }
}

void write_range(const Range& r, uint8_t* buffer) {
  fill_blocks("WRT", r.first, r.count, buffer);
  const Status s = g_disk.write(r.first, r.count, buffer);
  ASSERT_EQ(s, Status::kOk) << status_name(s) << " " << g_disk.reason();
  for (uint32_t i = 0; i < r.count; ++i) {
    g_written[r.first + i] = true;
  }
}

TEST(VirtioBlock, WrittenRangesMatchTheHostCheck) {
  // Formats kWrites as "first:count,..." and compares with the list the host check uses.
  char text[128];
  uint32_t n = 0;
  for (const Range& r : kWrites) {
    if (n != 0) {
      text[n++] = ',';
    }
    for (const uint32_t value : {r.first, r.count}) {
      char digits[10];
      uint32_t k = 0;
      uint32_t v = value;
      do {
        digits[k++] = static_cast<char>('0' + v % 10);
        v /= 10;
      } while (v != 0);
      while (k > 0) {
        text[n++] = digits[--k];
      }
      text[n++] = ':';
    }
    --n;  // drop the ':' after the count
  }
  text[n] = '\0';
  EXPECT_STREQ(text, VIRTIO_BLOCK_TEST_WRITES);
}

TEST(VirtioBlock, InitFindsTheDisk) {
  const Status s = g_disk.init();
  ASSERT_EQ(s, Status::kOk) << status_name(s) << " " << g_disk.reason();
  EXPECT_TRUE(g_disk.ready());
  EXPECT_STREQ(g_disk.reason(), "ready");
  EXPECT_EQ(g_disk.block_count(), kImageBlocks);
  EXPECT_EQ(g_disk.capacity_sectors(), static_cast<uint64_t>(kImageBlocks));
  EXPECT_EQ(g_disk.capacity_bytes(), static_cast<uint64_t>(kImageBlocks) * 512u);
  EXPECT_GE(g_disk.slot(), 0);
  EXPECT_LT(g_disk.slot(), 8);
  EXPECT_EQ(g_disk.base_address(),
            VirtioBlockDevice::kMmioBase +
                static_cast<uint32_t>(g_disk.slot()) * VirtioBlockDevice::kMmioStride);
  EXPECT_FALSE(g_disk.read_only());
  EXPECT_GE(g_disk.max_request_blocks(), 1u);
  EXPECT_LE(g_disk.max_request_blocks(), VirtioBlockDevice::kMaxRequestBlocks);
  seqslam::test::log_figure("virtio_block slot", g_disk.slot());
  seqslam::test::log_figure("virtio_block flush supported", g_disk.flush_supported() ? 1 : 0);
  seqslam::test::log_figure("virtio_block max request blocks", g_disk.max_request_blocks());
}

TEST(VirtioBlock, ReadsTheHostPattern) {
  ASSERT_TRUE(disk_ready());
  expect_contents(0, 1, g_buffer);                   // first block
  expect_contents(1, 4, g_buffer);                   // a short range
  expect_contents(kImageBlocks - 1, 1, g_buffer);    // last block
  expect_contents(700, 250, g_buffer);               // several requests
  expect_contents(kImageBlocks - 20, 20, g_buffer);  // up to the end
}

TEST(VirtioBlock, WritesASingleBlock) {
  ASSERT_TRUE(disk_ready());
  write_range(kSingle, g_buffer);
  expect_contents(kSingle.first, 1, g_buffer);
  expect_contents(kSingle.first - 2, 5, g_buffer);  // neighbours unchanged
}

TEST(VirtioBlock, WritesAnOddCount) {
  ASSERT_TRUE(disk_ready());
  write_range(kOdd, g_buffer);
  expect_contents(kOdd.first - 1, kOdd.count + 2, g_buffer);
}

TEST(VirtioBlock, SplitsLongTransfersIntoRequests) {
  ASSERT_TRUE(disk_ready());
  const uint32_t max = g_disk.max_request_blocks();
  const uint32_t expected_requests = (kLong.count + max - 1) / max;
  EXPECT_GT(expected_requests, 1u);
  const uint32_t before = g_disk.counters().requests;
  write_range(kLong, g_buffer);
  EXPECT_EQ(g_disk.counters().requests - before, expected_requests);
  fill_bytes(g_buffer, 0, kLong.count * kBlockSize);
  const uint32_t before_read = g_disk.counters().requests;
  expect_contents(kLong.first, kLong.count, g_buffer);
  EXPECT_EQ(g_disk.counters().requests - before_read, expected_requests);
  expect_contents(kLong.first - 1, 2, g_buffer);                // the first edge
  expect_contents(kLong.first + kLong.count - 1, 2, g_buffer);  // the last edge
  EXPECT_EQ(g_disk.counters().bounced_blocks, 0u);              // aligned buffers go direct
}

TEST(VirtioBlock, WritesAtTheEndOfTheDisk) {
  ASSERT_TRUE(disk_ready());
  write_range(kEnd, g_buffer);
  expect_contents(kEnd.first, kEnd.count, g_buffer);
  expect_contents(kImageBlocks - 1, 1, g_buffer);
  expect_contents(kEnd.first - 5, 5 + kEnd.count, g_buffer);
}

TEST(VirtioBlock, UnalignedBuffersGoThroughTheBounceBuffer) {
  ASSERT_TRUE(disk_ready());
  uint8_t* const unaligned = g_buffer + 1;
  const uint32_t bounced = g_disk.counters().bounced_blocks;
  write_range(kUnaligned, unaligned);
  EXPECT_EQ(g_disk.counters().bounced_blocks - bounced, kUnaligned.count);
  fill_bytes(g_buffer, 0, (kUnaligned.count + 2) * kBlockSize + 1);
  expect_contents(kUnaligned.first - 1, kUnaligned.count + 2, unaligned);
  EXPECT_EQ(g_disk.counters().bounced_blocks - bounced, 2 * kUnaligned.count + 2);
  expect_contents(kUnaligned.first, kUnaligned.count, g_buffer + 2);  // 2-byte aligned
}

TEST(VirtioBlock, BadArgumentsDoNotReachTheDevice) {
  ASSERT_TRUE(disk_ready());
  const VirtioBlockDevice::Counters before = g_disk.counters();
  fill_bytes(g_buffer, 0xC3, 2 * kBlockSize);
  const uint32_t n = kImageBlocks;
  struct Case {
    uint32_t first;
    uint32_t count;
    Status expected;
  };
  const Case cases[] = {
      {0, 0, Status::kInvalidArgument},      {n, 1, Status::kOutOfRange},
      {n - 1, 2, Status::kOutOfRange},       {1, 0xFFFFFFFFu, Status::kOutOfRange},
      {0xFFFFFFFFu, 1, Status::kOutOfRange}, {n + 5, 0xFFFFFFFFu - 2, Status::kOutOfRange},
  };
  for (const Case& c : cases) {
    EXPECT_EQ(g_disk.read(c.first, c.count, g_buffer), c.expected)
        << "read " << c.first << " " << c.count;
    EXPECT_EQ(g_disk.write(c.first, c.count, g_buffer), c.expected)
        << "write " << c.first << " " << c.count;
  }
  EXPECT_EQ(g_disk.read(0, 1, nullptr), Status::kInvalidArgument);
  EXPECT_EQ(g_disk.write(0, 1, nullptr), Status::kInvalidArgument);
  EXPECT_EQ(g_disk.read(n, 1, nullptr), Status::kInvalidArgument);  // null checked first
  EXPECT_EQ(g_disk.counters().requests, before.requests);
  EXPECT_EQ(g_disk.counters().polls, before.polls);
  EXPECT_EQ(g_disk.counters().bounced_blocks, before.bounced_blocks);
  EXPECT_EQ(first_difference(g_buffer, g_buffer + kBlockSize, kBlockSize), kBlockSize);
  EXPECT_EQ(g_buffer[0], 0xC3);
  EXPECT_TRUE(g_disk.ready());
}

TEST(VirtioBlock, SyncFlushes) {
  ASSERT_TRUE(disk_ready());
  const uint32_t before = g_disk.counters().requests;
  const Status s = g_disk.sync();
  EXPECT_EQ(s, Status::kOk) << status_name(s) << " " << g_disk.reason();
  EXPECT_EQ(g_disk.counters().requests - before, g_disk.flush_supported() ? 1u : 0u);
  EXPECT_TRUE(g_disk.flush_supported());  // QEMU's default cache mode (writeback)
}

// Instructions per block, whole calls (argument checks, requests, polling).
struct Cost {
  uint64_t instructions;
  uint64_t polls;
  uint32_t requests;
};

Cost measure_read(uint32_t first, uint32_t count, uint32_t per_call, uint8_t* buffer) {
  const VirtioBlockDevice::Counters c0 = g_disk.counters();
  const uint64_t t0 = seqslam::board::instructions_retired();
  for (uint32_t b = 0; b < count; b += per_call) {
    if (g_disk.read(first + b, per_call, buffer) != Status::kOk) {
      return Cost{0, 0, 0};
    }
  }
  const uint64_t t1 = seqslam::board::instructions_retired();
  const VirtioBlockDevice::Counters c1 = g_disk.counters();
  return Cost{t1 - t0, c1.polls - c0.polls, c1.requests - c0.requests};
}

Cost measure_write(uint32_t first, uint32_t count, uint32_t per_call, uint8_t* buffer) {
  const VirtioBlockDevice::Counters c0 = g_disk.counters();
  const uint64_t t0 = seqslam::board::instructions_retired();
  for (uint32_t b = 0; b < count; b += per_call) {
    if (g_disk.write(first + b, per_call, buffer + b * kBlockSize) != Status::kOk) {
      return Cost{0, 0, 0};
    }
  }
  const uint64_t t1 = seqslam::board::instructions_retired();
  const VirtioBlockDevice::Counters c1 = g_disk.counters();
  return Cost{t1 - t0, c1.polls - c0.polls, c1.requests - c0.requests};
}

// Prints instructions per block (whole calls), polls per request, and instructions per
// block without the wait. The wait loop retires 4 instructions per poll (2 for the last,
// successful one); it is the only part that depends on the host's I/O latency, so the
// third figure is the same on every run and the first two are not.
void log_cost(const char* what, const Cost& cost, uint32_t blocks) {
  char label[112];
  uint32_t n = 0;
  const auto append = [&](const char* s) {
    while (*s != '\0' && n + 1 < sizeof(label)) {
      label[n++] = *s++;
    }
    label[n] = '\0';
  };
  append("virtio_block ");
  append(what);
  const uint32_t base = n;
  append(" instructions/block");
  seqslam::test::log_figure(label,
                            static_cast<double>(cost.instructions) / static_cast<double>(blocks));
  n = base;
  append(" polls/request");
  seqslam::test::log_figure(label,
                            static_cast<double>(cost.polls) / static_cast<double>(cost.requests));
  n = base;
  append(" instructions/block without waiting");
  const uint64_t wait = 4 * cost.polls - 2 * static_cast<uint64_t>(cost.requests);
  seqslam::test::log_figure(
      label, static_cast<double>(cost.instructions - wait) / static_cast<double>(blocks));
}

TEST(VirtioBlock, MeasuresInstructionsPerBlock) {
  ASSERT_TRUE(disk_ready());
  const uint32_t max = g_disk.max_request_blocks();
  // Reads: 64 single-block calls; 256 blocks in max-size requests; 16 unaligned blocks.
  const Cost read1 = measure_read(700, 64, 1, g_buffer);
  const Cost read_max = measure_read(700, 2 * max, max, g_buffer);
  const Cost read_bounce = measure_read(700, 16, 16, g_buffer + 1);
  ASSERT_NE(read1.requests, 0u);
  ASSERT_NE(read_max.requests, 0u);
  ASSERT_NE(read_bounce.requests, 0u);
  EXPECT_EQ(read1.requests, 64u);
  EXPECT_EQ(read_max.requests, 2u);
  EXPECT_EQ(read_bounce.requests, 16u);
  // Writes rewrite the firmware pattern over kLong, so the image does not change.
  fill_blocks("WRT", kLong.first, kLong.count, g_buffer);
  const Cost write1 = measure_write(kLong.first, 64, 1, g_buffer);
  const Cost write_max = measure_write(kLong.first, 2 * max, max, g_buffer);
  fill_blocks("WRT", kLong.first, 16, g_buffer + 1);
  const Cost write_bounce = measure_write(kLong.first, 16, 16, g_buffer + 1);
  ASSERT_NE(write1.requests, 0u);
  ASSERT_NE(write_max.requests, 0u);
  ASSERT_NE(write_bounce.requests, 0u);
  log_cost("read 1-block calls", read1, 64);
  log_cost("read max-size calls", read_max, 2 * max);
  log_cost("read unaligned (bounce)", read_bounce, 16);
  log_cost("write 1-block calls", write1, 64);
  log_cost("write max-size calls", write_max, 2 * max);
  log_cost("write unaligned (bounce)", write_bounce, 16);
  expect_contents(kLong.first, kLong.count, g_buffer);
}

// A second driver object with a one-poll limit: its requests time out, it resets the
// device and refuses further requests; the main object then needs init() again (the reset
// made the device forget its rings) and finds the data intact.
VirtioBlockDevice g_impatient(1);

TEST(VirtioBlock, TimeoutResetsTheDeviceAndInitRecovers) {
  ASSERT_EQ(g_impatient.init(), Status::kOk) << g_impatient.reason();
  const Status s = g_impatient.read(0, VirtioBlockDevice::kMaxRequestBlocks, g_buffer);
  if (s == Status::kOk) {
    GTEST_SKIP() << "the device completed a 64 KiB read within one poll";
  }
  EXPECT_EQ(s, Status::kUnavailable) << status_name(s);
  EXPECT_FALSE(g_impatient.ready());
  EXPECT_TRUE(starts_with(g_impatient.reason(), "did not complete a request"))
      << g_impatient.reason();
  const uint32_t requests = g_impatient.counters().requests;
  EXPECT_EQ(g_impatient.read(0, 1, g_buffer), Status::kUnavailable);  // kept its block count
  EXPECT_EQ(g_impatient.write(0, 1, g_buffer), Status::kUnavailable);
  EXPECT_EQ(g_impatient.sync(), Status::kUnavailable);
  EXPECT_EQ(g_impatient.counters().requests, requests);

  const Status again = g_disk.init();
  ASSERT_EQ(again, Status::kOk) << status_name(again) << " " << g_disk.reason();
  expect_contents(kSingle.first, 1, g_buffer);
  expect_contents(0, 8, g_buffer);
  EXPECT_EQ(g_disk.sync(), Status::kOk);
}

#endif  // VIRTIO_BLOCK_TEST_NO_DISK

}  // namespace
