#include "seqslam/storage/record_log.h"

#include "seqslam/messages.h"
#include "seqslam/storage/bytes.h"

namespace seqslam::storage {

namespace {

constexpr uint8_t kRecordMagic0 = 0x5A;
constexpr uint8_t kRecordMagic1 = 0xA5;
constexpr uint32_t kHeaderCrcOffset = hal::kBlockSize - 4;
constexpr uint32_t kHeaderPayloadOffset = 16;
static_assert(kHeaderPayloadOffset + kLogHeaderPayloadMax == kHeaderCrcOffset, "header layout");

Status fail(LogProblem* out, LogProblem p, Status s) {
  if (out != nullptr) *out = p;
  return s;
}

bool same_magic(const uint8_t* a, const uint8_t* b) {
  for (int i = 0; i < 8; ++i) {
    if (a[i] != b[i]) return false;
  }
  return true;
}

// Records are checksummed with a CRC seeded by the log kind, so a stale record of another
// kind of log left on the device can never pass as a record of this one.
uint32_t record_seed(const LogKind& kind) {
  return crc32(kind.magic, sizeof kind.magic);
}

}  // namespace

const char* log_problem_text(LogProblem p) {
#if !SEQSLAM_MESSAGE_TEXTS
  return message_code("LP", static_cast<uint32_t>(p));
#endif
  switch (p) {
    case LogProblem::kNone:
      return "ok";
    case LogProblem::kDeviceError:
      return "the block device failed a read, write or sync";
    case LogProblem::kTooSmall:
      return "the file is too small for a header block";
    case LogProblem::kWrongKind:
      return "not a log of the expected kind (wrong magic in block 0)";
    case LogProblem::kVersion:
      return "written by another format version";
    case LogProblem::kHeaderChecksum:
      return "the header block is damaged (checksum mismatch)";
    case LogProblem::kHeaderSize:
      return "header payload larger than 492 bytes";
    case LogProblem::kFull:
      return "the file is full: no room for the record";
    case LogProblem::kRecordTooLarge:
      return "record larger than the maximum (64 KiB) or than the reader's buffer";
    case LogProblem::kEndClean:
      return "end of log: no further record of this session";
    case LogProblem::kEndDamagedTail:
      return "end of log: the last record is incomplete or damaged (power cut while writing?)";
    case LogProblem::kDamagedRecord:
      return "damaged or missing records (bad checksum, length or order) followed by valid "
             "records";
    case LogProblem::kEndTruncated:
      return "the log ends before its committed end, or its commit slots are damaged: records "
             "it held are missing (file cut short or blocks damaged)";
    case LogProblem::kCommitSlotDamaged:
      return "a commit slot is damaged (zeros or another session's): where the log ends is "
             "known only from the other slot, one commit older";
  }
  return "unknown log problem";
}

// ---------------------------------------------------------------------------------------
// Writer

Status LogWriter::create(hal::BlockDevice& device, const LogKind& kind, const uint8_t* header,
                         uint32_t header_size, LogProblem* problem) {
  device_ = nullptr;
  if (header_size > kLogHeaderPayloadMax || (header == nullptr && header_size > 0)) {
    return fail(problem, LogProblem::kHeaderSize, Status::kInvalidArgument);
  }
  const uint64_t capacity = device.capacity_bytes();
  if (capacity < hal::kBlockSize) {  // a header-only log (a run configuration) fits one block
    return fail(problem, LogProblem::kTooSmall, Status::kResourceExhausted);
  }
  uint8_t block[hal::kBlockSize] = {};
  Status s = device.read(0, 1, block);
  if (s != Status::kOk) return fail(problem, LogProblem::kDeviceError, s);
  // Session: one above a valid previous header of this kind. Otherwise derived from whatever
  // block 0 held, so it is deterministic for identical devices yet unlikely to equal the
  // session of stale records behind an unreadable header.
  ByteReader old(block, sizeof block);
  old.skip(12);
  const uint32_t old_session = old.u32();
  ByteReader old_crc(block + kHeaderCrcOffset, 4);
  uint32_t session = 0;
  if (same_magic(block, kind.magic) && old_crc.u32() == crc32(block, kHeaderCrcOffset)) {
    session = old_session + 1;
  } else {
    session = crc32(block, sizeof block) | 1u;
  }
  if (session == 0) session = 1;

  for (uint8_t& b : block)
    b = 0;
  ByteWriter w(block, sizeof block);
  w.bytes(kind.magic, sizeof kind.magic);
  const uint16_t room = capacity >= kFirstRecordOffset + hal::kBlockSize ? kLogHasRecords : 0;
  w.u16(static_cast<uint16_t>(kind.version | kLogFormat2 | room));
  w.u16(static_cast<uint16_t>(header_size));
  w.u32(session);
  w.bytes(header, header_size);
  ByteWriter c(block + kHeaderCrcOffset, 4);
  c.u32(crc32(block, kHeaderCrcOffset));

  device_ = &device;
  capacity_ = capacity;
  end_ = kFirstRecordOffset;
  session_ = session;
  sequence_ = 0;
  tail_block_ = kFirstRecordOffset / hal::kBlockSize;
  for (uint8_t& b : tail_)
    b = 0;
  failed_ = false;
  seed_ = record_seed(kind);
  // The first commit (no records yet), before the header: once the new header is on the
  // device an intact commit of its session is too, so a log of this session without one was
  // damaged, not empty; a cut before the header leaves the old log's header (and its other
  // slot). A header-only log (no room for records) has no slots.
  s = room != 0 ? commit() : Status::kOk;
  if (s == Status::kOk) s = device.write(0, 1, block);
  if (s == Status::kOk) s = device.sync();
  if (s != Status::kOk) {
    device_ = nullptr;
    return fail(problem, LogProblem::kDeviceError, s);
  }
  return fail(problem, LogProblem::kNone, Status::kOk);
}

Status LogWriter::put(const uint8_t* data, size_t size) {
  while (size > 0) {
    const uint32_t block = static_cast<uint32_t>(cursor_ / hal::kBlockSize);
    const uint32_t at = static_cast<uint32_t>(cursor_ % hal::kBlockSize);
    if (block != tail_block_) {
      // The previous block is complete: it was written when it filled (below), so start the
      // new one from zeros (this also clears stale bytes beyond the end of the log).
      for (uint8_t& b : tail_)
        b = 0;
      tail_block_ = block;
    }
    const uint32_t n =
        hal::kBlockSize - at < size ? hal::kBlockSize - at : static_cast<uint32_t>(size);
    for (uint32_t i = 0; i < n; ++i)
      tail_[at + i] = data[i];
    data += n;
    size -= n;
    cursor_ += n;
    if (at + n == hal::kBlockSize) {
      SEQSLAM_TRY(device_->write(tail_block_, 1, tail_));
    }
  }
  return Status::kOk;
}

Status LogWriter::flush_tail() {
  if (cursor_ % hal::kBlockSize == 0) return Status::kOk;  // written when it filled
  return device_->write(tail_block_, 1, tail_);
}

Status LogWriter::append(uint8_t type, const ByteSpan* parts, uint32_t part_count,
                         LogProblem* problem) {
  if (device_ == nullptr || failed_) return Status::kFailedPrecondition;
  uint64_t total = kRecordOverhead;
  for (uint32_t i = 0; i < part_count; ++i) {
    if (parts[i].data == nullptr && parts[i].size > 0) return Status::kInvalidArgument;
    total += parts[i].size;
  }
  if (total > kMaxRecordBytes) {
    return fail(problem, LogProblem::kRecordTooLarge, Status::kInvalidArgument);
  }
  if (end_ > capacity_ || total > capacity_ - end_)
    return fail(problem, LogProblem::kFull, Status::kResourceExhausted);

  uint8_t head[kRecordHeaderBytes];
  ByteWriter w(head, sizeof head);
  w.u8(kRecordMagic0);
  w.u8(kRecordMagic1);
  w.u8(type);
  w.u8(0);
  w.u32(static_cast<uint32_t>(total));
  w.u32(session_);
  w.u32(sequence_);
  uint32_t crc = crc32_update(seed_, head, sizeof head);
  cursor_ = end_;
  Status s = put(head, sizeof head);
  for (uint32_t i = 0; i < part_count && s == Status::kOk; ++i) {
    crc = crc32_update(crc, parts[i].data, parts[i].size);
    s = put(parts[i].data, parts[i].size);
  }
  uint8_t tail[4];
  ByteWriter t(tail, sizeof tail);
  t.u32(crc);
  if (s == Status::kOk) s = put(tail, sizeof tail);
  if (s == Status::kOk) s = flush_tail();
  if (s == Status::kOk) s = device_->sync();
  if (s != Status::kOk) {
    failed_ = true;
    return fail(problem, LogProblem::kDeviceError, s);
  }
  end_ = cursor_;
  ++sequence_;
  s = commit();
  if (s != Status::kOk) {
    failed_ = true;  // the record is on the device; the reader sees it as written, uncommitted
    return fail(problem, LogProblem::kDeviceError, s);
  }
  return fail(problem, LogProblem::kNone, Status::kOk);
}

Status LogWriter::reopen(hal::BlockDevice& device, const LogKind& kind, Span<uint8_t> buffer,
                         LogProblem* problem) {
  device_ = nullptr;
  LogReader reader;
  uint8_t header[kLogHeaderPayloadMax];
  uint32_t header_size = 0;
  Status s = reader.open(device, kind, header, sizeof header, &header_size, buffer, problem);
  if (s != Status::kOk) return s;
  if (!reader.end_known()) return fail(problem, LogProblem::kVersion, Status::kFailedPrecondition);
  RecordView v;
  do {
    s = reader.next(&v);
  } while (s == Status::kOk);
  if (s != Status::kOutOfRange || reader.lost_records() != 0) {
    const LogProblem lp = reader.lost_records() != 0        ? LogProblem::kDamagedRecord
                          : s == Status::kResourceExhausted ? LogProblem::kRecordTooLarge
                                                            : reader.end_problem();
    return fail(
        problem, lp,
        s == Status::kOutOfRange || s == Status::kResourceExhausted ? Status::kDataLoss : s);
  }
  // The block the next record starts in, with the bytes before it; what follows (a record a
  // power cut interrupted) is cleared, as put() clears a new block.
  const uint64_t end = reader.end_offset();
  tail_block_ = static_cast<uint32_t>(end / hal::kBlockSize);
  s = device.read(tail_block_, 1, tail_);
  if (s != Status::kOk) return fail(problem, LogProblem::kDeviceError, s);
  for (uint32_t i = static_cast<uint32_t>(end % hal::kBlockSize); i < hal::kBlockSize; ++i)
    tail_[i] = 0;
  device_ = &device;
  capacity_ = device.capacity_bytes();
  end_ = end;
  session_ = reader.session();
  sequence_ = reader.records_read();
  failed_ = false;
  seed_ = record_seed(kind);
  return fail(problem, LogProblem::kNone, Status::kOk);
}

// Commit slot: u32 session | u32 records | u64 end offset | u32 CRC (seeded by the kind), in
// block 1 + records % 2 so that a cut commit leaves the previous one intact.
Status LogWriter::commit() {
  uint8_t block[hal::kBlockSize] = {};
  ByteWriter w(block, sizeof block);
  w.u32(session_);
  w.u32(sequence_);
  w.u32(static_cast<uint32_t>(end_));
  w.u32(static_cast<uint32_t>(end_ >> 32));
  w.u32(crc32_update(seed_, block, 16));
  Status s = device_->write(1 + sequence_ % 2, 1, block);
  if (s == Status::kOk) s = device_->sync();
  return s;
}

// ---------------------------------------------------------------------------------------
// Reader

Status LogReader::open(hal::BlockDevice& device, const LogKind& kind, uint8_t* header,
                       uint32_t header_capacity, uint32_t* header_size, Span<uint8_t> buffer,
                       LogProblem* problem) {
  device_ = nullptr;
  uint8_t block[hal::kBlockSize] = {};
  const Status s = device.read(0, 1, block);
  if (s != Status::kOk) return fail(problem, LogProblem::kDeviceError, s);
  if (!same_magic(block, kind.magic)) {
    return fail(problem, LogProblem::kWrongKind, Status::kDataLoss);
  }
  ByteReader c(block + kHeaderCrcOffset, 4);
  if (c.u32() != crc32(block, kHeaderCrcOffset)) {
    return fail(problem, LogProblem::kHeaderChecksum, Status::kDataLoss);
  }
  ByteReader r(block, kHeaderCrcOffset);
  r.skip(8);
  const uint16_t version = r.u16();
  const uint16_t size = r.u16();
  const uint32_t session = r.u32();
  const bool format2 = (version & kLogFormat2) != 0;
  if ((version & ~(kLogFormat2 | kLogHasRecords)) != kind.version) {
    return fail(problem, LogProblem::kVersion, Status::kFailedPrecondition);
  }
  if (size > kLogHeaderPayloadMax) {
    return fail(problem, LogProblem::kHeaderChecksum, Status::kDataLoss);
  }
  const uint32_t copy = size < header_capacity ? size : header_capacity;
  for (uint32_t i = 0; i < copy; ++i)
    header[i] = block[kHeaderPayloadOffset + i];
  if (header_size != nullptr) *header_size = size;

  device_ = &device;
  buffer_ = buffer;
  capacity_ = device.capacity_bytes();
  offset_ = format2 ? kFirstRecordOffset : kFirstRecordOffsetV1;
  session_ = session;
  expected_ = 0;
  lost_ = 0;
  ended_ = false;
  problem_ = LogProblem::kNone;
  problem_offset_ = 0;
  cached_block_ = 0xFFFFFFFFu;
  seed_ = record_seed(kind);
  end_known_ = format2;
  // Made with room for records: its slots must be there and one intact (else unknown end).
  slots_missing_ = (version & kLogHasRecords) != 0;
  committed_records_ = 0;
  committed_end_ = offset_;
  if (format2) {
    const Status commits = read_commits();
    if (commits != Status::kOk) {
      device_ = nullptr;
      return fail(problem, LogProblem::kDeviceError, commits);
    }
  }
  return fail(problem, LogProblem::kNone, Status::kOk);
}

// The later of the two commit slots that are intact and of this session (none: nothing was
// committed yet, or the device is too small for the slots).
Status LogReader::read_commits() {
  for (uint32_t slot = 1; slot <= 2; ++slot) {
    if (capacity_ < (slot + 1) * hal::kBlockSize) break;
    uint8_t bytes[20];
    SEQSLAM_TRY(read_bytes(slot * hal::kBlockSize, bytes, sizeof bytes));
    ByteReader r(bytes, sizeof bytes);
    const uint32_t session = r.u32();
    const uint32_t records = r.u32();
    uint64_t end = r.u32();
    end |= static_cast<uint64_t>(r.u32()) << 32;
    if (r.u32() != crc32_update(seed_, bytes, 16) || session != session_) continue;
    if (records >= committed_records_ && end >= kFirstRecordOffset) {
      committed_records_ = records;
      committed_end_ = end;
      slots_missing_ = capacity_ < kFirstRecordOffset;  // cut inside the slots
    }
  }
  return Status::kOk;
}

uint32_t damaged_commit_slot(hal::BlockDevice& device, const LogKind& kind) {
  LogReader reader;
  uint8_t none[1];
  if (reader.open(device, kind, nullptr, 0, nullptr, Span<uint8_t>(none, 1)) != Status::kOk ||
      !reader.end_known() || reader.committed_records() == 0) {
    return 0;
  }
  // Once a record is committed both slots hold commits of this session (commit k goes to
  // slot 1 + k % 2), so the slot without the newest commit must hold one too.
  const uint32_t other = 1 + (reader.committed_records() + 1) % 2;
  uint8_t block[hal::kBlockSize];
  if (device.read(other, 1, block) != Status::kOk) return 0;
  ByteReader r(block, 20);
  const uint32_t session = r.u32();
  const uint32_t records = r.u32();
  const uint32_t end_low = r.u32();
  const uint32_t end_high = r.u32();
  const uint32_t crc = r.u32();
  const bool intact = crc == crc32_update(record_seed(kind), block, 16);
  if (intact && session == reader.session()) return 0;  // an older commit: fine
  // A cut write of this session's commit starts with this session's bytes: zeros or an
  // intact commit of another session are not one.
  const bool zeros = (session | records | end_low | end_high | crc) == 0;
  return intact || zeros ? other : 0;
}

Status LogReader::read_bytes(uint64_t offset, uint8_t* out, uint32_t size) {
  while (size > 0) {
    const uint32_t block = static_cast<uint32_t>(offset / hal::kBlockSize);
    const uint32_t at = static_cast<uint32_t>(offset % hal::kBlockSize);
    if (block != cached_block_) {
      const Status s = device_->read(block, 1, cache_);
      if (s != Status::kOk) {
        cached_block_ = 0xFFFFFFFFu;
        return s;
      }
      cached_block_ = block;
    }
    const uint32_t n = hal::kBlockSize - at < size ? hal::kBlockSize - at : size;
    for (uint32_t i = 0; i < n; ++i)
      out[i] = cache_[at + i];
    out += n;
    size -= n;
    offset += n;
  }
  return Status::kOk;
}

// Reads the 16-byte record header at `offset` (false if it does not fit or on a device error)
// and says whether it has the record magic and this log's session.
bool LogReader::session_header_at(uint64_t offset, RecordHead* head, Status* device_status) {
  *device_status = Status::kOk;
  if (offset > capacity_ || capacity_ - offset < kRecordOverhead) return false;
  uint8_t bytes[kRecordHeaderBytes];
  *device_status = read_bytes(offset, bytes, sizeof bytes);
  if (*device_status != Status::kOk) return false;
  ByteReader r(bytes, sizeof bytes);
  const uint8_t m0 = r.u8();
  const uint8_t m1 = r.u8();
  r.skip(2);
  head->length = r.u32();
  const uint32_t session = r.u32();
  head->sequence = r.u32();
  return m0 == kRecordMagic0 && m1 == kRecordMagic1 && session == session_;
}

// Is there a complete, intact record with `sequence` at `offset`? Copies it into the buffer
// when it fits (*fits tells). The CRC is checked while streaming, whatever the buffer size.
bool LogReader::record_at(uint64_t offset, uint32_t sequence, uint32_t* length, bool* fits,
                          Status* device_status) {
  RecordHead head;
  if (!session_header_at(offset, &head, device_status)) return false;
  const uint32_t len = head.length;
  if (head.sequence != sequence || len < kRecordOverhead || len > kMaxRecordBytes ||
      len > capacity_ - offset) {
    return false;
  }
  *length = len;
  *fits = len <= buffer_.size();
  uint32_t crc = seed_;
  uint8_t chunk[64];
  for (uint32_t done = 0; done < len - 4;) {
    const uint32_t n = len - 4 - done < sizeof chunk ? len - 4 - done : sizeof chunk;
    *device_status = read_bytes(offset + done, chunk, n);
    if (*device_status != Status::kOk) return false;
    crc = crc32_update(crc, chunk, n);
    if (*fits) {
      for (uint32_t i = 0; i < n; ++i)
        buffer_[done + i] = chunk[i];
    }
    done += n;
  }
  uint8_t tail[4];
  *device_status = read_bytes(offset + len - 4, tail, 4);
  if (*device_status != Status::kOk) return false;
  ByteReader t(tail, 4);
  return t.u32() == crc;
}

Status LogReader::read_at(uint64_t offset, uint8_t* type, Span<uint8_t> prefix,
                          Span<uint8_t> rest) {
  if (device_ == nullptr) return Status::kFailedPrecondition;
  if (type == nullptr) return Status::kInvalidArgument;
  cached_block_ = 0xFFFFFFFFu;      // a writer may have rewritten the cached block
  uint64_t length = prefix.size();  // size_t is 32 bits on the target
  length += rest.size();
  length += kRecordOverhead;
  if (offset > capacity_ || capacity_ - offset < length) return Status::kDataLoss;
  uint8_t head[kRecordHeaderBytes];
  Status s = read_bytes(offset, head, sizeof head);
  if (s != Status::kOk) return s;
  ByteReader r(head, sizeof head);
  const uint8_t m0 = r.u8();
  const uint8_t m1 = r.u8();
  const uint8_t kind = r.u8();
  r.skip(1);
  const uint32_t stored_length = r.u32();
  const uint32_t session = r.u32();
  if (m0 != kRecordMagic0 || m1 != kRecordMagic1 || session != session_ ||
      stored_length != length) {
    return Status::kDataLoss;
  }
  uint32_t crc = crc32_update(seed_, head, sizeof head);
  uint64_t at = offset + kRecordHeaderBytes;
  const Span<uint8_t> parts[2] = {prefix, rest};
  for (const Span<uint8_t>& part : parts) {
    if (part.size() == 0) continue;
    s = read_bytes(at, part.data(), static_cast<uint32_t>(part.size()));
    if (s != Status::kOk) return s;
    crc = crc32_update(crc, part.data(), part.size());
    at += part.size();
  }
  uint8_t tail[4];
  s = read_bytes(at, tail, sizeof tail);
  if (s != Status::kOk) return s;
  ByteReader t(tail, sizeof tail);
  if (t.u32() != crc) return Status::kDataLoss;
  *type = kind;
  return Status::kOk;
}

Status LogReader::next(RecordView* out) {
  if (device_ == nullptr) return Status::kFailedPrecondition;
  if (out == nullptr) return Status::kInvalidArgument;
  if (ended_) return Status::kOutOfRange;
  uint32_t length = 0;
  bool fits = false;
  Status device_status = Status::kOk;
  if (record_at(offset_, expected_, &length, &fits, &device_status)) {
    const uint64_t at = offset_;
    offset_ += length;
    ++expected_;
    if (!fits) {
      problem_ = LogProblem::kRecordTooLarge;
      problem_offset_ = at;
      return Status::kResourceExhausted;
    }
    ByteReader r(buffer_.data(), length);
    r.skip(2);
    out->type = r.u8();
    out->flags = r.u8();
    out->sequence = expected_ - 1;
    out->offset = at;
    out->payload = buffer_.data() + kRecordHeaderBytes;
    out->payload_size = length - kRecordOverhead;
    return Status::kOk;
  }
  if (device_status != Status::kOk) {
    // Ends the log: a device that keeps failing (a file cut while it is read) must not make a
    // caller that skips kDataLoss loop forever.
    problem_ = LogProblem::kDeviceError;
    problem_offset_ = offset_;
    ended_ = true;
    return device_status;
  }
  return resynchronise();
}

// Not a valid record at offset_. Look for a valid successor: before the committed end any
// later record of this session up to the committed count (it can only be one this log
// wrote); in a format-1 log one of the next few sequence numbers within one maximum record
// length. Found: the records in between are damaged or missing. Not found:
// the log ends here, with records missing if it had committed more.
Status LogReader::resynchronise() {
  const uint64_t damaged = offset_;
  const bool committed = end_known_ && (expected_ < committed_records_ || slots_missing_);
  // Past the committed records of a format-2 log nothing can follow but the one record
  // written after the last commit, which would have been at offset_: no search.
  const uint64_t limit = committed    ? committed_end_ + 1
                         : end_known_ ? damaged
                                      : damaged + kMaxRecordBytes + kRecordOverhead;
  Status device_status = Status::kOk;
  for (uint64_t at = damaged + 1; at < limit && at < capacity_; ++at) {
    uint8_t first = 0;
    device_status = read_bytes(at, &first, 1);
    if (device_status != Status::kOk) break;
    if (first != kRecordMagic0) continue;  // cheap filter before decoding a header
    RecordHead head;
    if (!session_header_at(at, &head, &device_status)) {
      if (device_status != Status::kOk) break;
      continue;
    }
    const uint32_t skipped = head.sequence - expected_;
    const uint32_t most = committed ? committed_records_ - expected_ : kMaxSkippedRecords;
    if (skipped == 0 || skipped > most) continue;
    uint32_t length = 0;
    bool fits = false;
    if (record_at(at, head.sequence, &length, &fits, &device_status)) {
      offset_ = at;
      expected_ = head.sequence;
      lost_ += skipped;
      problem_ = LogProblem::kDamagedRecord;
      problem_offset_ = damaged;
      return Status::kDataLoss;
    }
  }
  ended_ = true;
  problem_offset_ = damaged;
  if (committed) {
    // Without an intact commit slot (slots_missing_) the number the log held is unknown: the
    // records read may be all of them (it counted 2^32 - 111 lost for 111 records read).
    if (expected_ < committed_records_) lost_ += committed_records_ - expected_;
    problem_ = LogProblem::kEndTruncated;
    return Status::kDataLoss;
  }
  // A header of this session at the end means a record was being written when the power
  // went (a damaged tail); anything else (zeros, stale data of an older session or of another
  // kind of log) is a clean end.
  RecordHead head;
  problem_ = session_header_at(damaged, &head, &device_status) ? LogProblem::kEndDamagedTail
                                                               : LogProblem::kEndClean;
  return Status::kOutOfRange;
}

}  // namespace seqslam::storage
