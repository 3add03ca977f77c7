// The `state` file: a run's saved state (state_io.h), from which a stopped run is continued
// (docs/firmware.md, "Continuing an explore run"). A record log (record_log.h) of kind
// SQSTATE1: the header holds the owner's layout key (e.g. the application's capacities and
// settings, so a state saved by another build or configuration is refused before any of it
// is restored); kChunk records carry the state's bytes in order; the last record, kEnd, holds
// their count and CRC-32.
//
// A state is all or nothing. Opening reads the whole file first and refuses (kDataLoss) a
// state without its end record (a power cut while saving), with a damaged or missing record,
// or whose bytes do not match the end record; only then does reading start. Saving starts a
// new session of the log, so the previous state is gone from the first write on: a cut while
// saving leaves no state, never half of one (the library, map and graph files are separate
// and untouched by it).
#pragma once

#include <stdint.h>

#include "seqslam/hal/block_device.h"
#include "seqslam/state_io.h"
#include "seqslam/storage/record_log.h"

namespace seqslam::storage {

inline constexpr LogKind kStateKind{{'S', 'Q', 'S', 'T', 'A', 'T', 'E', '1'}, 1};
inline constexpr const char* kStateFile = "state";
// State bytes per record.
inline constexpr uint32_t kStateChunk = 480;

// What went wrong with a state file (state_problem_text gives the sentence).
enum class StateProblem : uint8_t {
  kNone = 0,
  kLog,         // the record log (log_problem() says what)
  kKey,         // saved by another build or configuration (another layout key)
  kIncomplete,  // no end record: saving was interrupted
  kMismatch,    // the bytes do not match the end record (count or CRC), or a record is foreign
  kOverrun,     // the owner asked for more bytes than the state holds
  kSaveFailed,  // the card failed while saving (write())
};
const char* state_problem_text(StateProblem p);

class StateFileWriter final : public StateSink {
 public:
  // Starts a new state on `device` for owners of layout `key`. Log statuses.
  Status create(hal::BlockDevice& device, uint32_t key, LogProblem* problem = nullptr);
  // Buffers the bytes; every full chunk is appended. The first error sticks; before
  // create() and after finish(): kFailedPrecondition.
  Status write(const uint8_t* data, uint32_t size) override;
  // Appends the last chunk and the end record: only now is the state complete.
  Status finish();
  uint64_t bytes() const { return total_; }
  LogProblem log_problem() const { return log_problem_; }

 private:
  Status append_chunk();

  LogWriter log_{};
  uint8_t chunk_[kStateChunk] = {};
  uint32_t fill_ = 0;
  uint64_t total_ = 0;
  uint32_t crc_ = 0;
  Status status_ = Status::kFailedPrecondition;
  LogProblem log_problem_ = LogProblem::kNone;
};

class StateFileReader final : public StateSource {
 public:
  // Checks the whole state (see the top of this file), then positions at its first byte.
  // kDataLoss (kIncomplete, kMismatch, kLog), kFailedPrecondition (kKey; kLog: kVersion),
  // device errors (kLog).
  Status open(hal::BlockDevice& device, uint32_t key, StateProblem* problem = nullptr);
  // The next `size` bytes of the state; kDataLoss past its end (kOverrun) or when the card
  // changed since open().
  Status read(uint8_t* data, uint32_t size) override;
  // Whether every byte has been read: a state longer than its owner reads is not its own.
  bool at_end() const { return read_ == total_; }
  uint64_t bytes() const { return total_; }
  StateProblem problem() const { return problem_; }
  LogProblem log_problem() const { return log_problem_; }

 private:
  Status fail(StateProblem p, Status s, StateProblem* out);
  Status next_chunk();

  LogReader log_{};
  uint8_t buffer_[kRecordOverhead + kStateChunk] = {};
  const uint8_t* chunk_ = nullptr;
  uint32_t chunk_size_ = 0;
  uint32_t chunk_pos_ = 0;
  uint64_t total_ = 0;
  uint64_t read_ = 0;
  bool open_ = false;
  StateProblem problem_ = StateProblem::kNone;
  LogProblem log_problem_ = LogProblem::kNone;
};

}  // namespace seqslam::storage
