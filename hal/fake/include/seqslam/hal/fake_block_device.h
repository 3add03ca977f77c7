// A block device in caller-owned RAM that behaves like an SD card, including its failures:
// writes are whole 512-byte blocks inside the capacity (the interface checks that), and a
// fault schedule can fail the Nth write or read, or cut the power after the Kth byte written
// (the write in progress keeps a prefix of its new bytes; everything after fails until
// restore_power()). For tests of recordings, persistence and power loss, on host and target.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/hal/block_device.h"
#include "seqslam/span.h"

namespace seqslam::hal {

struct BlockFaults {
  static constexpr uint64_t kNever = ~uint64_t{0};
  uint64_t fail_write = 0;                 // 1-based index of a write call that fails (kDataLoss,
                                           // nothing written); 0 = none
  uint64_t fail_read = 0;                  // 1-based index of a read call that fails; 0 = none
  uint64_t power_cut_after_byte = kNever;  // total bytes written before the power goes
};

class FakeBlockDevice final : public BlockDevice {
 public:
  // `storage` holds the card's contents; its size / 512 is the capacity in blocks.
  explicit FakeBlockDevice(Span<uint8_t> storage) : storage_(storage) {}

  void set_faults(const BlockFaults& faults) { faults_ = faults; }
  // Power back on (contents as left by the cut); counters keep counting.
  void restore_power() { powered_ = true; }
  bool powered() const { return powered_; }

  uint64_t writes() const { return writes_; }
  uint64_t reads() const { return reads_; }
  uint64_t syncs() const { return syncs_; }
  uint64_t bytes_written() const { return bytes_written_; }
  Span<uint8_t> contents() const { return storage_; }

 private:
  uint32_t do_block_count() const override {
    return static_cast<uint32_t>(storage_.size()) / kBlockSize;
  }

  Status do_read(uint32_t first, uint32_t count, uint8_t* out) override {
    if (!powered_) return Status::kUnavailable;
    ++reads_;
    if (faults_.fail_read != 0 && reads_ == faults_.fail_read) return Status::kDataLoss;
    const size_t base = static_cast<size_t>(first) * kBlockSize;
    __builtin_memcpy(out, storage_.data() + base, static_cast<size_t>(count) * kBlockSize);
    return Status::kOk;
  }

  Status do_write(uint32_t first, uint32_t count, const uint8_t* data) override {
    if (!powered_) return Status::kUnavailable;
    ++writes_;
    if (faults_.fail_write != 0 && writes_ == faults_.fail_write) return Status::kDataLoss;
    const size_t base = static_cast<size_t>(first) * kBlockSize;
    const uint64_t n = static_cast<uint64_t>(count) * kBlockSize;
    // A power cut after byte K keeps a prefix of this write: the bytes up to K land, the
    // rest of this write and everything after is lost. One copy, not a byte loop with a test
    // per byte (that loop was three quarters of a fuzzer's time).
    const uint64_t room = faults_.power_cut_after_byte > bytes_written_
                              ? faults_.power_cut_after_byte - bytes_written_
                              : 0;
    const uint64_t landed = n < room ? n : room;
    __builtin_memcpy(storage_.data() + base, data, static_cast<size_t>(landed));
    bytes_written_ += landed;
    if (landed < n) {
      powered_ = false;
      return Status::kUnavailable;
    }
    return Status::kOk;
  }

  Status do_sync() override {
    if (!powered_) return Status::kUnavailable;
    ++syncs_;
    return Status::kOk;
  }

  Span<uint8_t> storage_;
  BlockFaults faults_{};
  uint64_t writes_ = 0;
  uint64_t reads_ = 0;
  uint64_t syncs_ = 0;
  uint64_t bytes_written_ = 0;
  bool powered_ = true;
};

}  // namespace seqslam::hal
