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
// `tiny`: 0 to 39 bytes, so a block holds up to 14 records.
uint32_t payload_size(uint32_t i, bool tiny = false) {
  if (tiny) return (i * 7u) % 40u;
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

Status write_records(LogWriter& w, uint32_t first, uint32_t count, bool tiny = false) {
  static uint8_t payload[2000];
  for (uint32_t i = first; i < first + count; ++i) {
    const uint32_t n = payload_size(i, tiny);
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
  // Two syncs per record (its blocks, then its commit) plus the header's and the first
  // commit's: every record is durable and committed when append returns.
  EXPECT_EQ(disk.device.syncs(), 122u);
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
  EXPECT_EQ(written, 2u);  // 5 data blocks = 2560 bytes = 2 records of 1020 bytes
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
// Continuing a stored log (a library taught over several runs): the records appended after
// reopen() follow the old ones in the same session, also after a power cut interrupted a
// record (it is overwritten); a log that lost records is not continued.
TEST(RecordLog, ReopenContinuesTheLog) {
  static Disk disk;
  static uint8_t buffer[4096];
  LogWriter w;
  ASSERT_EQ(w.create(disk.device, kKind, nullptr, 0), Status::kOk);
  ASSERT_EQ(write_records(w, 0, 25), Status::kOk);
  const uint32_t session = w.session();
  LogWriter again;
  LogProblem lp = LogProblem::kVersion;
  ASSERT_EQ(again.reopen(disk.device, kKind, Span<uint8_t>(buffer), &lp), Status::kOk);
  EXPECT_EQ(lp, LogProblem::kNone);
  EXPECT_EQ(again.session(), session);
  EXPECT_EQ(again.records(), 25u);
  EXPECT_EQ(again.end_offset(), w.end_offset());
  ASSERT_EQ(write_records(again, 25, 35), Status::kOk);
  LogProblem end = LogProblem::kNone;
  EXPECT_EQ(read_all(disk.device, &end), 60u);
  EXPECT_EQ(end, LogProblem::kEndClean);

  // A power cut in the middle of record 60: reopened after 59, the next record overwrites it.
  hal::BlockFaults faults;
  faults.power_cut_after_byte = disk.device.bytes_written() + 300;
  disk.device.set_faults(faults);
  EXPECT_NE(write_records(again, 60, 1), Status::kOk);
  disk.device.restore_power();
  disk.device.set_faults(hal::BlockFaults{});
  EXPECT_EQ(read_all(disk.device, &end), 60u);
  EXPECT_EQ(end, LogProblem::kEndDamagedTail);
  LogWriter third;
  ASSERT_EQ(third.reopen(disk.device, kKind, Span<uint8_t>(buffer)), Status::kOk);
  EXPECT_EQ(third.records(), 60u);
  ASSERT_EQ(write_records(third, 60, 10), Status::kOk);
  EXPECT_EQ(read_all(disk.device, &end), 70u);
  EXPECT_EQ(end, LogProblem::kEndClean);

  // Not a log of lost records: one damaged in the middle.
  LogReader r;
  ASSERT_EQ(r.open(disk.device, kKind, nullptr, 0, nullptr, Span<uint8_t>(buffer)), Status::kOk);
  RecordView v;
  for (int i = 0; i <= 20; ++i)
    ASSERT_EQ(r.next(&v), Status::kOk);
  disk.bytes[v.offset + 30] ^= 0x40;
  LogWriter fourth;
  EXPECT_EQ(fourth.reopen(disk.device, kKind, Span<uint8_t>(buffer), &lp), Status::kDataLoss);
  EXPECT_EQ(lp, LogProblem::kDamagedRecord);
  EXPECT_EQ(write_records(fourth, 70, 1), Status::kFailedPrecondition);
  // Nor one of another kind, nor one whose records do not fit the buffer.
  disk.bytes[v.offset + 30] ^= 0x40;
  EXPECT_EQ(fourth.reopen(disk.device, kOtherKind, Span<uint8_t>(buffer), &lp), Status::kDataLoss);
  EXPECT_EQ(lp, LogProblem::kWrongKind);
  EXPECT_EQ(fourth.reopen(disk.device, kKind, Span<uint8_t>(buffer, 64), &lp), Status::kDataLoss);
  EXPECT_EQ(lp, LogProblem::kRecordTooLarge);
}

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
      // The record's blocks, then its commit slot (one more block).
      complete_at[i] = disk.device.bytes_written() - 2 * hal::kBlockSize +
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

// What a reader got back from a damaged log: the records read (each checked against the
// generator by read_all), whether it reported a loss, and how it ended.
struct Readback {
  bool opened = false;
  uint32_t records = 0;
  uint32_t damaged = 0;  // kDataLoss results (damaged stretches, a truncated end)
  uint32_t lost = 0;     // records the reader says it lost
  LogProblem end = LogProblem::kNone;
  uint32_t damaged_slot = 0;  // damaged_commit_slot()
};

Readback read_back(hal::BlockDevice& device, bool tiny) {
  static uint8_t buffer[4096];
  Readback out;
  LogReader r;
  if (r.open(device, kKind, nullptr, 0, nullptr, Span<uint8_t>(buffer, sizeof buffer)) !=
      Status::kOk) {
    return out;
  }
  out.opened = true;
  out.damaged_slot = damaged_commit_slot(device, kKind);
  RecordView v;
  for (uint32_t calls = 0; calls < 10000; ++calls) {  // bounded: a hang fails the test
    const Status s = r.next(&v);
    if (s == Status::kDataLoss) {
      ++out.damaged;
      continue;
    }
    if (s != Status::kOk) break;
    if (v.payload_size != payload_size(v.sequence, tiny) ||
        (v.payload_size > 0 &&
         v.payload[v.payload_size / 2] != payload_byte(v.sequence, v.payload_size / 2))) {
      ADD_FAILURE() << "record " << v.sequence << " misread";
    }
    ++out.records;
  }
  out.lost = r.lost_records();
  out.end = r.end_problem();
  return out;
}

// Every block-aligned cut and every zeroed block of a committed log: the records that are
// still intact come back, and whatever is missing is reported (kDataLoss, lost_records),
// never read as a clean end. The records are 5 to 1500 bytes, so a block holds up to ~9 of
// them (the old reader looked only 4 sequence numbers ahead and missed such gaps).
TEST(RecordLog, EveryCutAndEveryZeroedBlockIsReported) {
  static Disk disk;
  static Disk copy;
  for (const bool tiny : {true, false}) {
    LogWriter w;
    ASSERT_EQ(w.create(disk.device, kKind, nullptr, 0), Status::kOk);
    ASSERT_EQ(write_records(w, 0, tiny ? 100 : 24, tiny), Status::kOk);
    const uint32_t records = w.records();
    const uint32_t blocks =
        static_cast<uint32_t>((w.end_offset() + hal::kBlockSize - 1) / hal::kBlockSize);
    uint32_t cases = 0;
    for (uint32_t b = 0; b < blocks; ++b) {
      // A cut after block b - 1: the file holds blocks 0 .. b - 1.
      hal::FakeBlockDevice cut(Span<uint8_t>(disk.bytes, static_cast<size_t>(b) * 512));
      const Readback c = read_back(cut, tiny);
      if (b > 0) {
        EXPECT_TRUE(c.opened) << "cut at block " << b;
        EXPECT_LT(c.records, records) << "cut at block " << b;
        EXPECT_GT(c.damaged, 0u) << "cut at block " << b << " read as " << log_problem_text(c.end);
        // Cut inside the commit slots: the loss is reported, its size is not known.
        if (b >= 3) {
          EXPECT_EQ(c.records + c.lost, records) << "cut at block " << b;
        }
        ++cases;
      }
      // Block b zeroed.
      for (uint32_t k = 0; k < sizeof disk.bytes; ++k)
        copy.bytes[k] = disk.bytes[k];
      for (uint32_t k = 0; k < hal::kBlockSize; ++k)
        copy.bytes[b * hal::kBlockSize + k] = 0;
      const Readback z = read_back(copy.device, tiny);
      ++cases;
      if (b == 0) {
        EXPECT_FALSE(z.opened);  // the header: the log is refused, not read as empty
        continue;
      }
      ASSERT_TRUE(z.opened) << "block " << b;
      EXPECT_EQ(z.records + z.lost, records) << "zeroed block " << b;
      if (b * hal::kBlockSize >= kFirstRecordOffset) {  // a block holding record bytes
        EXPECT_LT(z.records, records) << "zeroed block " << b;
        EXPECT_GT(z.damaged, 0u) << "zeroed block " << b << " lost records silently";
      } else {  // a commit slot: the other one still holds a commit, nothing is lost
        EXPECT_EQ(z.records, records) << "zeroed commit slot " << b;
        // ... but the damage is reported (issue 34: it was neither used nor reported).
        EXPECT_EQ(z.damaged_slot, b) << "zeroed commit slot " << b;
      }
      if (b >= 3) {
        EXPECT_EQ(z.damaged_slot, 0u) << "zeroed block " << b;
      }
    }
    EXPECT_EQ(cases, 2 * blocks - 1);
  }
}

// Which commit slot is damage (issue 34): a zeroed or foreign slot once both hold commits;
// not a slot the log has not written yet, nor one a power cut interrupted. Both slots zeroed:
// the end is unknown, and no count of lost records is made up (it was 2^32 - records).
TEST(RecordLog, ADamagedCommitSlotIsReported) {
  static Disk disk;
  static Disk copy;
  const auto with = [](uint32_t slot, uint8_t value, uint32_t bytes) {
    for (uint32_t k = 0; k < sizeof disk.bytes; ++k)
      copy.bytes[k] = disk.bytes[k];
    for (uint32_t k = 0; k < bytes; ++k)
      copy.bytes[slot * hal::kBlockSize + k] = value;
    return read_back(copy.device, true);
  };
  LogWriter w;
  ASSERT_EQ(w.create(disk.device, kKind, nullptr, 0), Status::kOk);
  // No record yet: slot 2 was never written this session (stale 0xEE bytes, or zeros).
  EXPECT_EQ(with(2, 0, hal::kBlockSize).damaged_slot, 0u);
  EXPECT_EQ(with(2, 0xEE, hal::kBlockSize).damaged_slot, 0u);
  ASSERT_EQ(write_records(w, 0, 5, true), Status::kOk);  // commits 0..5: 5 is in slot 2
  EXPECT_EQ(read_back(disk.device, true).damaged_slot, 0u);
  Readback r = with(2, 0, hal::kBlockSize);
  EXPECT_EQ(r.damaged_slot, 2u);
  EXPECT_EQ(r.records, 5u);
  EXPECT_EQ(r.end, LogProblem::kEndClean);
  EXPECT_EQ(with(1, 0, hal::kBlockSize).damaged_slot, 1u);
  // A commit cut by a power loss: its first bytes new (this session's), the rest old.
  EXPECT_EQ(with(2, 0x5A, 6).damaged_slot, 0u);
  // An intact commit of another session in slot 1 (another log's block put back).
  static Disk older;
  LogWriter o;
  ASSERT_EQ(o.create(older.device, kKind, nullptr, 0), Status::kOk);
  ASSERT_EQ(o.create(older.device, kKind, nullptr, 0), Status::kOk);  // the next session
  ASSERT_EQ(write_records(o, 0, 2, true), Status::kOk);               // commit 2 in slot 1
  for (uint32_t k = 0; k < sizeof disk.bytes; ++k)
    copy.bytes[k] = disk.bytes[k];
  for (uint32_t k = 0; k < hal::kBlockSize; ++k)
    copy.bytes[hal::kBlockSize + k] = older.bytes[hal::kBlockSize + k];
  EXPECT_EQ(read_back(copy.device, true).damaged_slot, 1u);
  // Both slots zeroed: the end is unknown; the records read are reported as they are.
  for (uint32_t k = 0; k < sizeof disk.bytes; ++k)
    copy.bytes[k] = disk.bytes[k];
  for (uint32_t k = hal::kBlockSize; k < 3 * hal::kBlockSize; ++k)
    copy.bytes[k] = 0;
  r = read_back(copy.device, true);
  EXPECT_EQ(r.records, 5u);
  EXPECT_EQ(r.end, LogProblem::kEndTruncated);
  EXPECT_EQ(r.lost, 0u);
}

// A format-1 log (records from byte 512, no commit slots; written before the commit slots
// existed) is still read, without knowing its end.
TEST(RecordLog, ReadsAFormatOneLog) {
  static Disk disk;
  // Build the format-1 layout by hand: the header with the plain version, one record.
  LogWriter w;
  ASSERT_EQ(w.create(disk.device, kKind, nullptr, 0), Status::kOk);
  ASSERT_EQ(write_records(w, 0, 3), Status::kOk);
  // Move the records from byte 1536 to byte 512 and rewrite the header as format 1.
  for (uint32_t k = 0; k < 3 * hal::kBlockSize; ++k)
    disk.bytes[hal::kBlockSize + k] = disk.bytes[kFirstRecordOffset + k];
  ByteWriter version(disk.bytes + 8, 2);
  version.u16(kKind.version);
  ByteWriter crc(disk.bytes + hal::kBlockSize - 4, 4);
  crc.u32(crc32(disk.bytes, hal::kBlockSize - 4));
  static uint8_t buffer[4096];
  LogReader r;
  ASSERT_EQ(r.open(disk.device, kKind, nullptr, 0, nullptr, Span<uint8_t>(buffer, sizeof buffer)),
            Status::kOk);
  EXPECT_FALSE(r.end_known());
  RecordView v;
  for (uint32_t i = 0; i < 3; ++i) {
    ASSERT_EQ(r.next(&v), Status::kOk);
    EXPECT_EQ(v.payload_size, payload_size(i));
  }
  EXPECT_EQ(r.next(&v), Status::kOutOfRange);
}

// A device whose reads fail from some block on, while it still claims its old size (a file
// truncated while it is read): the reader reports the error once and ends, so a caller that
// skips kDataLoss records cannot loop forever (seqslam results once did).
class FailingTail final : public hal::BlockDevice {
 public:
  FailingTail(hal::BlockDevice& inner, uint32_t first_bad) : inner_(inner), bad_(first_bad) {}

 private:
  uint32_t do_block_count() const override { return inner_.block_count(); }
  Status do_read(uint32_t first, uint32_t count, uint8_t* out) override {
    if (first + count > bad_) return Status::kDataLoss;
    return inner_.read(first, count, out);
  }
  Status do_write(uint32_t, uint32_t, const uint8_t*) override { return Status::kDataLoss; }
  Status do_sync() override { return Status::kOk; }
  hal::BlockDevice& inner_;
  uint32_t bad_;
};

TEST(RecordLog, AFailingDeviceEndsTheLogInsteadOfLooping) {
  static Disk disk;
  LogWriter w;
  ASSERT_EQ(w.create(disk.device, kKind, nullptr, 0), Status::kOk);
  ASSERT_EQ(write_records(w, 0, 30), Status::kOk);
  FailingTail failing(disk.device, 8);
  static uint8_t buffer[4096];
  LogReader r;
  ASSERT_EQ(r.open(failing, kKind, nullptr, 0, nullptr, Span<uint8_t>(buffer, sizeof buffer)),
            Status::kOk);
  RecordView v;
  uint32_t read = 0, errors = 0, calls = 0;
  for (; calls < 1000; ++calls) {
    const Status s = r.next(&v);
    if (s == Status::kOk) {
      ++read;
    } else if (s == Status::kOutOfRange) {
      break;
    } else {
      ++errors;
    }
  }
  EXPECT_LT(calls, 1000u);
  EXPECT_EQ(errors, 1u);
  EXPECT_GT(read, 0u);
  EXPECT_LT(read, 30u);
  EXPECT_EQ(r.end_problem(), LogProblem::kDeviceError);
}

}  // namespace
}  // namespace seqslam::storage
