#include "seqslam/storage/state_file.h"

#include "seqslam/storage/bytes.h"

namespace seqslam::storage {

namespace {

constexpr uint8_t kChunkRecord = 1;
constexpr uint8_t kEndRecord = 2;
constexpr uint32_t kEndPayload = 12;  // u64 bytes, u32 CRC-32

}  // namespace

const char* state_problem_text(StateProblem p) {
  switch (p) {
    case StateProblem::kNone:
      return "ok";
    case StateProblem::kLog:
      return "the state file's record log is unreadable";
    case StateProblem::kKey:
      return "the state was saved by another build or configuration";
    case StateProblem::kIncomplete:
      return "the state is incomplete (saving was interrupted)";
    case StateProblem::kMismatch:
      return "the state's bytes do not match its end record";
    case StateProblem::kOverrun:
      return "the state is shorter than what restores it";
    case StateProblem::kSaveFailed:
      return "the card failed while the state was saved";
  }
  return "unknown state problem";
}

Status StateFileWriter::create(hal::BlockDevice& device, uint32_t key, LogProblem* problem) {
  uint8_t header[4];
  ByteWriter w(header, sizeof header);
  w.u32(key);
  fill_ = 0;
  total_ = 0;
  crc_ = 0;
  status_ = log_.create(device, kStateKind, header, sizeof header, &log_problem_);
  if (problem != nullptr) *problem = log_problem_;
  return status_;
}

Status StateFileWriter::append_chunk() {
  const ByteSpan part{chunk_, fill_};
  status_ = log_.append(kChunkRecord, &part, 1, &log_problem_);
  fill_ = 0;
  return status_;
}

Status StateFileWriter::write(const uint8_t* data, uint32_t size) {
  if (status_ != Status::kOk) return status_;
  crc_ = crc32_update(crc_, data, size);
  total_ += size;
  while (size > 0) {
    const uint32_t n = kStateChunk - fill_ < size ? kStateChunk - fill_ : size;
    for (uint32_t i = 0; i < n; ++i)
      chunk_[fill_ + i] = data[i];
    fill_ += n;
    data += n;
    size -= n;
    if (fill_ == kStateChunk && append_chunk() != Status::kOk) return status_;
  }
  return Status::kOk;
}

Status StateFileWriter::finish() {
  if (status_ == Status::kOk && fill_ > 0) (void)append_chunk();
  if (status_ != Status::kOk) return status_;
  uint8_t end[kEndPayload];
  ByteWriter w(end, sizeof end);
  w.u32(static_cast<uint32_t>(total_));
  w.u32(static_cast<uint32_t>(total_ >> 32));
  w.u32(crc_);
  const ByteSpan part{end, sizeof end};
  const Status s = log_.append(kEndRecord, &part, 1, &log_problem_);
  status_ = Status::kFailedPrecondition;  // complete (or failed): nothing more to write
  return s;
}

Status StateFileReader::fail(StateProblem p, Status s, StateProblem* out) {
  problem_ = p;
  if (out != nullptr) *out = p;
  open_ = false;
  return s;
}

Status StateFileReader::open(hal::BlockDevice& device, uint32_t key, StateProblem* problem) {
  open_ = false;
  total_ = 0;
  read_ = 0;
  // Pass 1: the whole state, its chunks against the end record.
  uint8_t header[4];
  uint32_t header_size = 0;
  Status s = log_.open(device, kStateKind, header, sizeof header, &header_size,
                       Span<uint8_t>(buffer_), &log_problem_);
  if (s != Status::kOk) return fail(StateProblem::kLog, s, problem);
  ByteReader h(header, sizeof header);
  if (header_size != sizeof header || h.u32() != key) {
    return fail(StateProblem::kKey, Status::kFailedPrecondition, problem);
  }
  uint64_t bytes = 0;
  uint32_t crc = 0;
  bool ended = false;
  for (;;) {
    RecordView v;
    s = log_.next(&v);
    if (s == Status::kOutOfRange) break;
    if (s != Status::kOk) {
      log_problem_ = log_.end_problem();
      return fail(StateProblem::kLog, s == Status::kResourceExhausted ? Status::kDataLoss : s,
                  problem);
    }
    if (ended) return fail(StateProblem::kMismatch, Status::kDataLoss, problem);
    if (v.type == kChunkRecord && v.payload_size > 0 && v.payload_size <= kStateChunk) {
      crc = crc32_update(crc, v.payload, v.payload_size);
      bytes += v.payload_size;
      continue;
    }
    if (v.type != kEndRecord || v.payload_size != kEndPayload) {
      return fail(StateProblem::kMismatch, Status::kDataLoss, problem);
    }
    ByteReader r(v.payload, v.payload_size);
    const uint64_t low = r.u32();
    const uint64_t total = low | static_cast<uint64_t>(r.u32()) << 32;
    if (total != bytes || r.u32() != crc) {
      return fail(StateProblem::kMismatch, Status::kDataLoss, problem);
    }
    ended = true;
  }
  if (!ended) return fail(StateProblem::kIncomplete, Status::kDataLoss, problem);
  // Pass 2: from the start again, for read().
  s = log_.open(device, kStateKind, header, sizeof header, &header_size, Span<uint8_t>(buffer_),
                &log_problem_);
  if (s != Status::kOk) return fail(StateProblem::kLog, s, problem);
  total_ = bytes;
  chunk_ = nullptr;
  chunk_size_ = 0;
  chunk_pos_ = 0;
  problem_ = StateProblem::kNone;
  if (problem != nullptr) *problem = StateProblem::kNone;
  open_ = true;
  return Status::kOk;
}

Status StateFileReader::next_chunk() {
  RecordView v;
  const Status s = log_.next(&v);
  if (s != Status::kOk || v.type != kChunkRecord || v.payload_size == 0 ||
      v.payload_size > kStateChunk) {
    open_ = false;
    problem_ = StateProblem::kMismatch;
    return Status::kDataLoss;
  }
  chunk_ = v.payload;
  chunk_size_ = v.payload_size;
  chunk_pos_ = 0;
  return Status::kOk;
}

Status StateFileReader::read(uint8_t* data, uint32_t size) {
  if (!open_) return Status::kDataLoss;
  if (size > total_ - read_) {
    problem_ = StateProblem::kOverrun;
    return Status::kDataLoss;
  }
  while (size > 0) {
    if (chunk_pos_ == chunk_size_) {
      SEQSLAM_TRY(next_chunk());
    }
    const uint32_t n = chunk_size_ - chunk_pos_ < size ? chunk_size_ - chunk_pos_ : size;
    for (uint32_t i = 0; i < n; ++i)
      data[i] = chunk_[chunk_pos_ + i];
    chunk_pos_ += n;
    data += n;
    size -= n;
    read_ += n;
  }
  return Status::kOk;
}

}  // namespace seqslam::storage
