// The SD card as the core of the robot sees it: a device of 512-byte blocks.
//
// Public non-virtual methods check arguments and define the statuses; implementations
// override the private do_* functions (the Pigweed pattern). There is no heap: devices are
// static objects passed by reference, and the protected destructor stops anyone deleting
// through this interface. Implementations: hal/board/qemu_virt (virtio-blk over a disk-image
// file), hal/host (a file on the PC), hal/fake (RAM with a fault schedule, for tests).
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/status.h"

namespace seqslam::hal {

inline constexpr uint32_t kBlockSize = 512;

class BlockDevice {
 public:
  // Number of 512-byte blocks.
  uint32_t block_count() const { return do_block_count(); }
  uint64_t capacity_bytes() const { return static_cast<uint64_t>(block_count()) * kBlockSize; }

  // Reads blocks [first, first + count) into `out` (count * 512 bytes). Returns
  //   kInvalidArgument - out is null or count is 0;
  //   kOutOfRange      - the range runs past block_count();
  //   kUnavailable     - the device did not answer (e.g. no card);
  //   kDataLoss        - the device reported a read error.
  Status read(uint32_t first, uint32_t count, uint8_t* out) {
    const Status s = check(first, count, out);
    return s != Status::kOk ? s : do_read(first, count, out);
  }

  // Writes blocks [first, first + count) from `data`. Statuses as read(), and
  //   kResourceExhausted - the device is full or write-protected;
  //   kDataLoss          - the write failed; the blocks' contents are undefined.
  // A write that is cut by a power loss leaves a prefix of the new bytes followed by the old
  // bytes (see docs/dream_format.md for what the recordings rely on).
  Status write(uint32_t first, uint32_t count, const uint8_t* data) {
    const Status s = check(first, count, data);
    return s != Status::kOk ? s : do_write(first, count, data);
  }

  // Makes every completed write durable. kUnavailable / kDataLoss from the device.
  Status sync() { return do_sync(); }

 protected:
  BlockDevice() = default;
  ~BlockDevice() = default;
  BlockDevice(const BlockDevice&) = default;
  BlockDevice& operator=(const BlockDevice&) = default;

 private:
  Status check(uint32_t first, uint32_t count, const void* buffer) const {
    if (buffer == nullptr || count == 0) return Status::kInvalidArgument;
    const uint32_t blocks = do_block_count();
    if (first >= blocks || count > blocks - first) return Status::kOutOfRange;
    return Status::kOk;
  }

  virtual uint32_t do_block_count() const = 0;
  virtual Status do_read(uint32_t first, uint32_t count, uint8_t* out) = 0;
  virtual Status do_write(uint32_t first, uint32_t count, const uint8_t* data) = 0;
  virtual Status do_sync() = 0;
};

}  // namespace seqslam::hal
