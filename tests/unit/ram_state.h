// A saved run state in RAM (state_io.h) for the core's tests: what a checkpoint file on the
// card is to the application. Reads past the end, and writes past the capacity, fail.
#pragma once

#include <stdint.h>

#include "seqslam/state_io.h"

namespace seqslam::test {

template <uint32_t kCapacity>
class RamState final : public StateSink, public StateSource {
 public:
  Status write(const uint8_t* data, uint32_t size) override {
    if (size > kCapacity - size_) return Status::kResourceExhausted;
    for (uint32_t i = 0; i < size; ++i)
      bytes[size_ + i] = data[i];
    size_ += size;
    return Status::kOk;
  }
  Status read(uint8_t* data, uint32_t size) override {
    if (size > size_ - pos_) return Status::kDataLoss;
    for (uint32_t i = 0; i < size; ++i)
      data[i] = bytes[pos_ + i];
    pos_ += size;
    return Status::kOk;
  }
  // Read from the start again (restoring the same state twice).
  void rewind() { pos_ = 0; }
  // Forget the end: the state as a cut-short file would hold it.
  void truncate(uint32_t size) {
    if (size < size_) size_ = size;
    pos_ = 0;
  }
  uint32_t size() const { return size_; }

  uint8_t bytes[kCapacity] = {};

 private:
  uint32_t size_ = 0;
  uint32_t pos_ = 0;
};

}  // namespace seqslam::test
