// Append-only record logs: round trip, sessions, damage, faults and power loss.
#include "seqslam/storage/record_log.h"

#include "seqslam/hal/fake_block_device.h"
#include "seqslam/storage/bytes.h"
#include "synthetic.h"
#include "test.h"

namespace seqslam::storage {
namespace {

constexpr LogKind kKind{{'S', 'Q', 'T', 'E', 'S', 'T', '0', '1'}, 3};
constexpr LogKind kOtherKind{{'S', 'Q', 'O', 'T', 'H', 'E', 'R', '1'}, 3};

// Payload of record i: its length and contents follow from i, so a reader can check both.
uint32_t payload_size(uint32_t i) {
  return (i * 97u) % 1500u + (i % 3 == 0 ? 0u : 5u);
}
uint8_t payload_byte(uint32_t i, uint32_t k) {
  return static_cast<uint8_t>(i * 31u + k * 7u);
}

struct Disk {
  static constexpr uint32_t kBlocks = 400;
  uint8_t bytes[kBlocks * hal::kBlockSize];
  hal::FakeBlockDevice device{Span<uint8_t>(bytes, sizeof bytes)};
  Disk() {
    for (uint8_t& b : bytes)
      b = 0xEE;  // not zeros: stale contents must not matter
  }
};

Status write_records(LogWriter& w, uint32_t first, uint32_t count) {
  static uint8_t payload[2000];
  for (uint32_t i = first; i < first + count; ++i) {
    const uint32_t n = payload_size(i);
    for (uint32_t k = 0; k < n; ++k)
      payload[k] = payload_byte(i, k);
    const ByteSpan part{payload, n};
    const Status s = w.append(static_cast<uint8_t>(i % 7), &part, 1);
    if (s != Status::kOk) return s;
  }
  return Status::kOk;
}

// Reads the log and checks every record against the generator; returns how many were read.
uint32_t read_all(hal::BlockDevice& device, LogProblem* end, uint32_t* damaged = nullptr) {
  static uint8_t buffer[4096];
  LogReader r;
  uint8_t header[16];
  uint32_t header_size = 0;
  EXPECT_EQ(r.open(device, kKind, header, sizeof header, &header_size,
                   Span<uint8_t>(buffer, sizeof buffer)),
            Status::kOk);
  uint32_t count = 0;
  RecordView v;
  for (;;) {
    const Status s = r.next(&v);
    if (s == Status::kDataLoss) {
      if (damaged != nullptr) ++*damaged;
      continue;
    }
    if (s != Status::kOk) {
      EXPECT_EQ(s, Status::kOutOfRange);
      break;
    }
    const uint32_t i = v.sequence;
    EXPECT_EQ(v.type, i % 7);
    EXPECT_EQ(v.payload_size, payload_size(i));
    for (uint32_t k = 0; k < v.payload_size; ++k) {
      if (v.payload[k] != payload_byte(i, k)) {
        ADD_FAILURE() << "record " << i << " byte " << k;
        break;
      }
    }
    ++count;
  }
  *end = r.end_problem();
  return count;
}

TEST(RecordLog, RoundTripAcrossBlocks) {
  static Disk disk;
  LogWriter w;
  const uint8_t header[5] = {1, 2, 3, 4, 5};
  ASSERT_EQ(w.create(disk.device, kKind, header, 5), Status::kOk);
  ASSERT_EQ(write_records(w, 0, 60), Status::kOk);
  LogProblem end = LogProblem::kNone;
  EXPECT_EQ(read_all(disk.device, &end), 60u);
  EXPECT_EQ(end, LogProblem::kEndClean);
  EXPECT_EQ(w.records(), 60u);
  // One sync per record plus the header's: every record is durable when append returns.
  EXPECT_EQ(disk.device.syncs(), 61u);
}

TEST(RecordLog, NewSessionIgnoresStaleRecords) {
  static Disk disk;
  LogWriter w;
  ASSERT_EQ(w.create(disk.device, kKind, nullptr, 0), Status::kOk);
  ASSERT_EQ(write_records(w, 0, 80), Status::kOk);
  const uint32_t first_session = w.session();
  // A shorter recording over the longer one: same record sizes, so stale records sit exactly
  // where the reader looks next.
  ASSERT_EQ(w.create(disk.device, kKind, nullptr, 0), Status::kOk);
  EXPECT_EQ(w.session(), first_session + 1);
  ASSERT_EQ(write_records(w, 0, 30), Status::kOk);
  LogProblem end = LogProblem::kNone;
  EXPECT_EQ(read_all(disk.device, &end), 30u);
  EXPECT_EQ(end, LogProblem::kEndClean);
  // A log of another kind over it: a new session, and the old records fail its CRC seed.
  LogWriter other;
  ASSERT_EQ(other.create(disk.device, kOtherKind, nullptr, 0), Status::kOk);
  LogReader r;
  uint8_t buffer[64];
  EXPECT_EQ(r.open(disk.device, kKind, nullptr, 0, nullptr, Span<uint8_t>(buffer, 64)),
            Status::kDataLoss);
}

TEST(RecordLog, DamagedRecordInTheMiddleIsReportedNotHidden) {
  static Disk disk;
  LogWriter w;
  ASSERT_EQ(w.create(disk.device, kKind, nullptr, 0), Status::kOk);
  ASSERT_EQ(write_records(w, 0, 40), Status::kOk);
  // Flip one byte inside record 20's payload.
  static uint8_t buffer[4096];
  LogReader r;
  ASSERT_EQ(r.open(disk.device, kKind, nullptr, 0, nullptr, Span<uint8_t>(buffer, sizeof buffer)),
            Status::kOk);
  RecordView v;
  uint64_t offset = 0;
  for (int i = 0; i <= 20; ++i) {
    ASSERT_EQ(r.next(&v), Status::kOk);
    offset = v.offset;
  }
  disk.bytes[offset + 30] ^= 0x40;
  LogProblem end = LogProblem::kNone;
  uint32_t damaged = 0;
  EXPECT_EQ(read_all(disk.device, &end, &damaged), 39u);
  EXPECT_EQ(damaged, 1u);
  EXPECT_EQ(end, LogProblem::kEndClean);
}

TEST(RecordLog, BadHeadersAndLimits) {
  static Disk disk;
  uint8_t buffer[64];
  LogReader r;
  LogProblem p = LogProblem::kNone;
  // Nothing written yet: not a log.
  EXPECT_EQ(r.open(disk.device, kKind, nullptr, 0, nullptr, Span<uint8_t>(buffer, 64), &p),
            Status::kDataLoss);
  EXPECT_EQ(p, LogProblem::kWrongKind);
  LogWriter w;
  ASSERT_EQ(w.create(disk.device, kKind, nullptr, 0), Status::kOk);
  // Version mismatch.
  const LogKind newer{{'S', 'Q', 'T', 'E', 'S', 'T', '0', '1'}, 4};
  EXPECT_EQ(r.open(disk.device, newer, nullptr, 0, nullptr, Span<uint8_t>(buffer, 64), &p),
            Status::kFailedPrecondition);
  EXPECT_EQ(p, LogProblem::kVersion);
  // Damaged header.
  disk.bytes[20] ^= 1;
  EXPECT_EQ(r.open(disk.device, kKind, nullptr, 0, nullptr, Span<uint8_t>(buffer, 64), &p),
            Status::kDataLoss);
  EXPECT_EQ(p, LogProblem::kHeaderChecksum);
  disk.bytes[20] ^= 1;
  // Header too large, record too large, record larger than the reader's buffer.
  static uint8_t big[kMaxRecordBytes];
  EXPECT_EQ(w.create(disk.device, kKind, big, 600, &p), Status::kInvalidArgument);
  EXPECT_EQ(p, LogProblem::kHeaderSize);
  ASSERT_EQ(w.create(disk.device, kKind, nullptr, 0), Status::kOk);
  const ByteSpan huge{big, kMaxRecordBytes};
  EXPECT_EQ(w.append(1, &huge, 1, &p), Status::kInvalidArgument);
  EXPECT_EQ(p, LogProblem::kRecordTooLarge);
  const ByteSpan mid{big, 100};
  ASSERT_EQ(w.append(1, &mid, 1), Status::kOk);
  ASSERT_EQ(w.append(2, &mid, 1), Status::kOk);
  const ByteSpan tiny{big, 3};
  ASSERT_EQ(w.append(3, &tiny, 1), Status::kOk);
  ASSERT_EQ(r.open(disk.device, kKind, nullptr, 0, nullptr, Span<uint8_t>(buffer, 64)),
            Status::kOk);
  RecordView v;
  EXPECT_EQ(r.next(&v), Status::kResourceExhausted);  // 120 bytes > 64-byte buffer
  EXPECT_EQ(r.end_problem(), LogProblem::kRecordTooLarge);
  EXPECT_EQ(r.next(&v), Status::kResourceExhausted);
  ASSERT_EQ(r.next(&v), Status::kOk);  // the small one is still read
  EXPECT_EQ(v.type, 3);
  EXPECT_EQ(r.next(&v), Status::kOutOfRange);
}

TEST(RecordLog, FullDeviceAndWriteErrors) {
  static uint8_t bytes[8 * hal::kBlockSize];
  hal::FakeBlockDevice device{Span<uint8_t>(bytes, sizeof bytes)};
  LogWriter w;
  ASSERT_EQ(w.create(device, kKind, nullptr, 0), Status::kOk);
  static uint8_t payload[1000] = {};
  const ByteSpan part{payload, sizeof payload};
  LogProblem p = LogProblem::kNone;
  uint32_t written = 0;
  Status s = Status::kOk;
  while ((s = w.append(1, &part, 1, &p)) == Status::kOk)
    ++written;
  EXPECT_EQ(s, Status::kResourceExhausted);
  EXPECT_EQ(p, LogProblem::kFull);
  EXPECT_EQ(written, 3u);  // 7 data blocks = 3584 bytes = 3 records of 1020 bytes
  // A failing write: the error is reported and the writer stops.
  ASSERT_EQ(w.create(device, kKind, nullptr, 0), Status::kOk);
  hal::BlockFaults faults;
  faults.fail_write = device.writes() + 2;
  device.set_faults(faults);
  EXPECT_EQ(w.append(1, &part, 1, &p), Status::kDataLoss);
  EXPECT_EQ(p, LogProblem::kDeviceError);
  EXPECT_EQ(w.append(1, &part, 1), Status::kFailedPrecondition);
}

// Cuts the power at every byte count a write call ends on, and at every byte of the last
// blocks written; each time, exactly the records completed before the cut must come back.
TEST(RecordLog, PowerLossLosesAtMostTheRecordBeingWritten) {
  static Disk disk;
  constexpr uint32_t kRecords = 24;
  // Dry run: the byte count at which each record's last byte reached the device. A record's
  // last write call rewrites the block holding its last byte from the block's start, so that
  // byte lands (end - 1) % 512 + 1 bytes into the final 512-byte write.
  uint64_t complete_at[kRecords] = {};
  {
    LogWriter w;
    ASSERT_EQ(w.create(disk.device, kKind, nullptr, 0), Status::kOk);
    for (uint32_t i = 0; i < kRecords; ++i) {
      ASSERT_EQ(write_records(w, i, 1), Status::kOk);
      complete_at[i] = disk.device.bytes_written() - hal::kBlockSize +
                       (w.end_offset() - 1) % hal::kBlockSize + 1;
    }
  }
  const uint64_t total = disk.device.bytes_written();
  uint32_t tried = 0;
  uint32_t lost = 0;
  for (uint64_t cut = 0; cut <= total; ++cut) {
    // Every write boundary (multiple of 512) plus every byte of the last 1.5 blocks.
    if (cut % hal::kBlockSize != 0 && cut + 768 < total) continue;
    static Disk d;
    for (uint8_t& b : d.bytes)
      b = 0xEE;
    d.device = hal::FakeBlockDevice(Span<uint8_t>(d.bytes, sizeof d.bytes));
    // The same starting state as the dry run: the previous session's header is absent.
    hal::BlockFaults faults;
    faults.power_cut_after_byte = cut;
    d.device.set_faults(faults);
    LogWriter w;
    if (w.create(d.device, kKind, nullptr, 0) == Status::kOk) (void)write_records(w, 0, kRecords);
    d.device.restore_power();
    d.device.set_faults(hal::BlockFaults{});
    uint32_t complete = 0;
    while (complete < kRecords && complete_at[complete] <= cut)
      ++complete;
    LogProblem end = LogProblem::kNone;
    LogReader probe;
    uint8_t tiny[1];
    const bool has_header =
        probe.open(d.device, kKind, nullptr, 0, nullptr, Span<uint8_t>(tiny, 1)) == Status::kOk;
    const uint32_t recovered = has_header ? read_all(d.device, &end) : 0;
    ++tried;
    if (recovered != complete) {
      ++lost;
      ADD_FAILURE() << "cut after byte " << static_cast<uint32_t>(cut) << ": " << recovered
                    << " records recovered, " << complete << " were complete";
    }
  }
  EXPECT_EQ(lost, 0u) << "of " << tried << " cuts";
  EXPECT_GT(tried, 700u);
}

}  // namespace
}  // namespace seqslam::storage
