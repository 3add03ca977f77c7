// Append-only logs of checksummed records on a block device: the container of recordings
// ("dream sequences"), place libraries, maps, graphs and result files (docs/dream_format.md).
//
// Block 0 of the device holds a header: the log kind (8-byte magic), its format version, a
// kind-specific payload and a session number. Blocks 1 and 2 are the commit slots (container
// format 2, below). Records follow from byte 1536, packed:
//
//   u16 0xA55A | u8 type | u8 flags | u32 length | u32 session | u32 sequence | payload | u32 crc
//
// (little-endian; length counts all of it; the CRC-32 covers everything before it).
//
// Knowing where the log ends. After each record the writer commits it: it writes the number
// of records and the end offset, with the session and a CRC, to commit slot 1 + records % 2,
// then syncs. A commit cut by a power loss damages only the slot being written; the other
// still holds the previous commit. So the reader knows how many records the log held a moment
// ago, whatever happened to the blocks after: a file cut at any point, or a block zeroed
// anywhere before the committed end, is reported as lost records (kDamagedRecord, then
// kEndTruncated) instead of reading as a clean end. At most the one record written after the
// last commit can vanish unreported, which is what a power cut while writing it looks like.
// Container format 2 is marked by bit 15 of the stored version (kind.version | 0x8000), so a
// reader of format 1 refuses it as another version; format-1 logs (records from byte 512, no
// commit slots) are still read, without that knowledge (end_known() is false).
//
// Power loss. The writer keeps the partly filled last block in RAM and, after each record,
// writes every block the record touched (rewriting the last block with the same leading
// bytes plus the new ones), then syncs. A write cut by a power loss leaves a prefix of new
// bytes and the old bytes after it, so records completed before the cut keep their bytes and
// at most the record being written is lost. A new log gets session = previous session + 1;
// records (and commit slots) of an older session left behind on the device fail the session
// check, so they are never misread as new data.
//
// Reading. The reader walks the records and stops at the first one that is not a complete
// record of this session with the next sequence number. It then looks for a valid record of
// this session further on (up to the committed end; nothing can follow beyond it; in a
// format-1 log within one maximum record length): if there is one, it reports kDataLoss for the
// damaged stretch, counts the records lost and can continue. Otherwise the log ends there: with
// kEndTruncated (kDataLoss once) if records the log committed are missing, else cleanly or with a
// damaged tail (a record cut by a power loss).
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/hal/block_device.h"
#include "seqslam/span.h"
#include "seqslam/status.h"

namespace seqslam::storage {

inline constexpr uint32_t kLogHeaderPayloadMax = 492;
inline constexpr uint32_t kRecordHeaderBytes = 16;
inline constexpr uint32_t kRecordOverhead = kRecordHeaderBytes + 4;
inline constexpr uint32_t kMaxRecordBytes = 65536;
// Container format 2 (commit slots): bit 15 of the stored version. Bit 14: the device had
// room for the commit slots and records when the log was made (a run configuration is a
// header-only log in one block), so a file now shorter than that was cut.
inline constexpr uint16_t kLogFormat2 = 0x8000;
inline constexpr uint16_t kLogHasRecords = 0x4000;
// Byte offset of the first record: after the header and the two commit slots (format 2), or
// after the header alone (format 1, read only).
inline constexpr uint32_t kFirstRecordOffset = 3 * hal::kBlockSize;
inline constexpr uint32_t kFirstRecordOffsetV1 = hal::kBlockSize;

struct LogKind {
  uint8_t magic[8];
  uint16_t version;
};

// What went wrong, or how a log ended (log_problem_text gives the sentence).
enum class LogProblem : uint8_t {
  kNone = 0,
  kDeviceError,        // the device failed a read, write or sync
  kTooSmall,           // the device cannot hold a header
  kWrongKind,          // the header's magic is not this kind (e.g. not a dream file)
  kVersion,            // another format version of this kind
  kHeaderChecksum,     // the header block is damaged
  kHeaderSize,         // header payload larger than kLogHeaderPayloadMax
  kFull,               // no room for the record
  kRecordTooLarge,     // a record beyond kMaxRecordBytes or the reader's buffer
  kEndClean,           // end: no further record of this session
  kEndDamagedTail,     // end: the last record is incomplete or damaged (power cut while writing)
  kDamagedRecord,      // a damaged record in the middle; valid records follow
  kEndTruncated,       // end: committed records missing, or no intact commit (cut or damaged)
  kCommitSlotDamaged,  // a commit slot is zeros or another session's (damaged_commit_slot())
};
const char* log_problem_text(LogProblem p);

// A gather list entry for writing a record in pieces (e.g. a fixed part and the pixels).
struct ByteSpan {
  const uint8_t* data;
  size_t size;
};

class LogWriter {
 public:
  // Starts a new log on `device`, writing the header with `header` (<= 492 bytes) and a
  // session one above that of a valid header of the same kind already there (else 1).
  // kInvalidArgument / kResourceExhausted (kHeaderSize, kTooSmall), device errors.
  Status create(hal::BlockDevice& device, const LogKind& kind, const uint8_t* header,
                uint32_t header_size, LogProblem* problem = nullptr);

  // Appends a record of `type` made of the concatenated `parts`, writes it and syncs.
  // kFailedPrecondition before create(); kResourceExhausted (kFull) if it does not fit,
  // kInvalidArgument (kRecordTooLarge) beyond kMaxRecordBytes; device errors (kDeviceError:
  // the record may be partly on the device; later appends are refused until create()).
  Status append(uint8_t type, const ByteSpan* parts, uint32_t part_count,
                LogProblem* problem = nullptr);

  // Continues the log on `device` instead of starting a new one (e.g. teaching more places
  // into a stored library): reads it to its end with `buffer` (at least its largest record
  // plus kRecordOverhead), then appends after its last complete record, in its session, with
  // the next sequence number; a record cut by a power loss after it is overwritten. Returns
  // the reader's errors (kDataLoss: kWrongKind, kHeaderChecksum, kRecordTooLarge ...), and
  // kDataLoss (kDamagedRecord, kEndTruncated) for a log that lost records: continuing it
  // would hide the loss. kFailedPrecondition (kVersion) for a format-1 log (it does not say
  // where it ends).
  Status reopen(hal::BlockDevice& device, const LogKind& kind, Span<uint8_t> buffer,
                LogProblem* problem = nullptr);

  uint32_t session() const { return session_; }
  uint32_t records() const { return sequence_; }
  uint64_t end_offset() const { return end_; }
  uint64_t capacity_bytes() const { return capacity_; }

 private:
  Status put(const uint8_t* data, size_t size);
  Status flush_tail();
  Status commit();

  hal::BlockDevice* device_ = nullptr;
  uint32_t seed_ = 0;  // CRC seed derived from the log kind
  uint64_t capacity_ = 0;
  uint64_t end_ = 0;     // byte offset of the next record
  uint64_t cursor_ = 0;  // write position while a record is being put
  uint32_t session_ = 0;
  uint32_t sequence_ = 0;
  uint32_t tail_block_ = 0;  // block held in tail_
  bool failed_ = false;
  uint8_t tail_[hal::kBlockSize] = {};
};

struct RecordView {
  uint8_t type = 0;
  uint8_t flags = 0;
  uint32_t sequence = 0;
  uint64_t offset = 0;  // byte offset of the record in the log
  const uint8_t* payload = nullptr;
  uint32_t payload_size = 0;
};

// The commit slot (1 or 2; 0: none) of the format-2 log of `kind` on `device` that must hold
// a commit of the log's session, the log having committed a record (commit k goes to slot
// 1 + k % 2), but is all zeros or an intact commit of another session: damage, never a
// commit cut by a power loss (whose first bytes are this session's). LogReader reads such a
// log with the other slot (one commit older) and does not tell; the host tools ask here and
// report kCommitSlotDamaged. A function of its own so the board, which reports nothing of it,
// links none of it. 0 as well for a log that cannot be opened.
uint32_t damaged_commit_slot(hal::BlockDevice& device, const LogKind& kind);

class LogReader {
 public:
  // Opens the log on `device`: checks the header and copies its payload to `header` (up to
  // `header_capacity` bytes; *header_size gets the stored size). `buffer` receives each
  // record and bounds the largest readable record. kDataLoss (kWrongKind, kHeaderChecksum),
  // kFailedPrecondition (kVersion), device errors.
  Status open(hal::BlockDevice& device, const LogKind& kind, uint8_t* header,
              uint32_t header_capacity, uint32_t* header_size, Span<uint8_t> buffer,
              LogProblem* problem = nullptr);

  // The next complete record (its payload lives in the buffer until the next call).
  //   kOk          - *out is valid;
  //   kOutOfRange  - the log has ended; end_problem() says how (kEndClean, kEndDamagedTail,
  //                  kEndTruncated);
  //   kDataLoss    - damaged or missing records in the middle (kDamagedRecord at
  //                  problem_offset(); lost_records() counts them): the next call continues
  //                  after them; or (once) the log ends before its committed end
  //                  (kEndTruncated): the next call returns kOutOfRange;
  //   kResourceExhausted - a record larger than the buffer (kRecordTooLarge); the next call
  //                  skips it;
  //   device errors.
  Status next(RecordView* out);

  // Random access: the complete, intact record of this log's session at byte `offset` (where
  // a writer appended it: its end_offset() just before the append), whatever its sequence
  // number. Its type goes to *type and its payload, which must be exactly prefix.size() +
  // rest.size() bytes, to `prefix` then `rest` (streamed: no record buffer needed; e.g. a
  // tile's coordinates and its cells). The block cache is dropped first,
  // so blocks a writer on the same device changed since are read afresh. kDataLoss when there
  // is no such record there (damaged, another session, another size), kFailedPrecondition
  // before open(), kInvalidArgument for a null `type`, device errors. next() is unaffected.
  Status read_at(uint64_t offset, uint8_t* type, Span<uint8_t> prefix, Span<uint8_t> rest);

  uint32_t session() const { return session_; }
  uint32_t records_read() const { return expected_; }
  // Whether the log records where it ends (format 2), and what it last committed: records
  // and the byte offset after them. A record written after that commit may follow.
  bool end_known() const { return end_known_; }
  uint32_t committed_records() const { return committed_records_; }
  uint64_t committed_end() const { return committed_end_; }
  // Records skipped as damaged or missing so far (kDamagedRecord, kEndTruncated).
  uint32_t lost_records() const { return lost_; }
  LogProblem end_problem() const { return problem_; }
  uint64_t problem_offset() const { return problem_offset_; }
  // Byte offset just after the last complete record (where a writer would continue).
  uint64_t end_offset() const { return offset_; }

 private:
  struct RecordHead {
    uint32_t length = 0;
    uint32_t sequence = 0;
  };
  // How many consecutive damaged records a resynchronisation may skip.
  static constexpr uint32_t kMaxSkippedRecords = 4;

  Status read_bytes(uint64_t offset, uint8_t* out, uint32_t size);
  bool session_header_at(uint64_t offset, RecordHead* head, Status* device_status);
  bool record_at(uint64_t offset, uint32_t sequence, uint32_t* length, bool* fits,
                 Status* device_status);
  Status read_commits();
  Status resynchronise();

  hal::BlockDevice* device_ = nullptr;
  uint32_t seed_ = 0;
  Span<uint8_t> buffer_{};
  uint64_t capacity_ = 0;
  uint64_t offset_ = 0;
  uint32_t session_ = 0;
  uint32_t expected_ = 0;
  uint32_t committed_records_ = 0;
  uint64_t committed_end_ = 0;
  uint32_t lost_ = 0;
  bool end_known_ = false;
  bool slots_missing_ = false;  // made with room for records, but no intact commit slot
  bool ended_ = false;
  LogProblem problem_ = LogProblem::kNone;
  uint64_t problem_offset_ = 0;
  uint32_t cached_block_ = 0xFFFFFFFFu;
  uint8_t cache_[hal::kBlockSize] = {};
};

}  // namespace seqslam::storage
