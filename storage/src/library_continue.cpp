// Teaching more places into a stored library (a run continued from the card). Its own
// translation unit so that load() keeps a single caller where the board links it: seeing
// this second caller, GCC splits load() into a clone that costs the board 20 bytes.
#include "seqslam/storage/library_store.h"

namespace seqslam::storage {

namespace {

Status fail(LibraryProblem* out, LibraryProblem p, Status s) {
  if (out != nullptr) *out = p;
  return s;
}

}  // namespace

Status StoredPlaceImages::load_for_teaching(hal::BlockDevice& metadata, hal::BlockDevice& images,
                                            const LibraryConfig& expected, Span<uint8_t> cache,
                                            const PlaceLibraryBuffers& buffers,
                                            PlaceLibrary& library, LibraryProblem* problem) {
  Status s = load(metadata, images, expected, cache, buffers, library, problem);
  if (s != Status::kOk) return s;
  uint8_t record[kRecordOverhead + kPlaceRecordBytes];
  s = meta_.reopen(metadata, kLibraryKind, Span<uint8_t>(record), &log_problem_);
  if (s != Status::kOk) return fail(problem, LibraryProblem::kLog, s);
  // The images file's partly filled last block, as write_image_bytes() keeps it; bytes of a
  // place a power cut interrupted are cleared.
  const uint64_t end = hal::kBlockSize + static_cast<uint64_t>(stored_) * pixels_;
  tail_block_ = static_cast<uint32_t>(end / hal::kBlockSize);
  s = images.read(tail_block_, 1, tail_);
  if (s != Status::kOk) {
    tail_block_ = 0xFFFFFFFFu;
    return fail(problem, LibraryProblem::kImagesDevice, s);
  }
  for (uint32_t i = static_cast<uint32_t>(end % hal::kBlockSize); i < hal::kBlockSize; ++i)
    tail_[i] = 0;
  writable_ = true;
  return fail(problem, LibraryProblem::kNone, Status::kOk);
}

}  // namespace seqslam::storage
