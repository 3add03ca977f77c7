// A RAM card that journals every write (block + bytes), for the power-cut sweeps
// (test_power_loss.cpp: a recording; test_power_loss_map.cpp: the explore mode's map and
// graph files). A writer runs once on it; any power cut is then replayed from the journal
// without running the writer again: the card as it was before the writes, writes [0, w)
// applied in full, and the first `cut` bytes of write w (a write cut by a power loss leaves
// a prefix of its new bytes and the old bytes after it).
#pragma once

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

#include "seqslam/hal/block_device.h"

namespace seqslam::test {

class JournalDevice final : public hal::BlockDevice {
 public:
  struct Write {
    uint32_t block;
    std::vector<uint8_t> data;
  };
  explicit JournalDevice(std::vector<uint8_t> initial) : bytes_(std::move(initial)) {}
  std::vector<Write> journal;
  const std::vector<uint8_t>& bytes() const { return bytes_; }

 private:
  uint32_t do_block_count() const override {
    return static_cast<uint32_t>(bytes_.size() / hal::kBlockSize);
  }
  Status do_read(uint32_t first, uint32_t count, uint8_t* out) override {
    std::copy_n(bytes_.begin() + static_cast<long>(first) * hal::kBlockSize,
                static_cast<long>(count) * hal::kBlockSize, out);
    return Status::kOk;
  }
  Status do_write(uint32_t first, uint32_t count, const uint8_t* data) override {
    for (uint32_t b = 0; b < count; ++b) {
      const uint8_t* src = data + static_cast<size_t>(b) * hal::kBlockSize;
      journal.push_back({first + b, std::vector<uint8_t>(src, src + hal::kBlockSize)});
      std::copy_n(src, hal::kBlockSize,
                  bytes_.begin() + static_cast<long>(first + b) * hal::kBlockSize);
    }
    return Status::kOk;
  }
  Status do_sync() override { return Status::kOk; }
  std::vector<uint8_t> bytes_;
};

// Applies the first `bytes` bytes of `write` to the card image `card` (all of it: kBlockSize).
inline void apply_write(std::vector<uint8_t>& card, const JournalDevice::Write& write,
                        uint32_t bytes = hal::kBlockSize) {
  std::copy_n(write.data.begin(), bytes,
              card.begin() + static_cast<long>(write.block) * hal::kBlockSize);
}

}  // namespace seqslam::test
