// A volume: named, fixed-size files on a block device (the SD card, or a disk image).
//
// Block 0 holds the file table; every file is a contiguous range of blocks fixed when the
// volume is formatted. Files are used as append-only logs (record_log.h), so there is no
// allocation at run time and nothing to corrupt but the data being written. The layout is
// specified in docs/dream_format.md ("Volume").
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/hal/block_device.h"
#include "seqslam/status.h"

namespace seqslam::storage {

inline constexpr uint32_t kVolumeMaxFiles = 15;
inline constexpr uint32_t kVolumeNameBytes = 16;  // including the terminating NUL
inline constexpr uint16_t kVolumeVersion = 1;

struct VolumeFile {
  char name[kVolumeNameBytes] = {};  // NUL-terminated, [A-Za-z0-9._-], 1..15 characters
  uint32_t first_block = 0;
  uint32_t block_count = 0;
};

// A window onto blocks [first, first + count) of another device: a file seen as a device.
class Region final : public hal::BlockDevice {
 public:
  Region() = default;
  Region(hal::BlockDevice& device, uint32_t first, uint32_t count)
      : device_(&device), first_(first), count_(count) {}

 private:
  uint32_t do_block_count() const override { return device_ == nullptr ? 0 : count_; }
  Status do_read(uint32_t first, uint32_t count, uint8_t* out) override {
    return device_->read(first_ + first, count, out);
  }
  Status do_write(uint32_t first, uint32_t count, const uint8_t* data) override {
    return device_->write(first_ + first, count, data);
  }
  Status do_sync() override { return device_ == nullptr ? Status::kOk : device_->sync(); }

  hal::BlockDevice* device_ = nullptr;
  uint32_t first_ = 0;
  uint32_t count_ = 0;
};

// Why a volume could not be used (volume_problem_text gives the sentence).
enum class VolumeProblem : uint8_t {
  kNone = 0,
  kDeviceError,  // the device failed to read or write block 0
  kNoVolume,     // block 0 does not start with the volume magic
  kVersion,      // a volume format this code does not know
  kChecksum,     // the file table is damaged
  kBadTable,     // bad names, overlapping files, files beyond the device, too many files
  kNotFound,     // no file of that name
  kTooLarge,     // the files do not fit on the device
};
const char* volume_problem_text(VolumeProblem p);

class Volume {
 public:
  // Writes a new file table: `files` are placed one after the other from block 1 in the given
  // order (first_block is ignored and assigned). Existing file contents are not erased: logs
  // written later start new sessions and ignore stale records (record_log.h).
  // kInvalidArgument (kBadTable) for bad names / duplicates / zero-sized files or more than
  // kVolumeMaxFiles, kResourceExhausted (kTooLarge) if they do not fit, device errors.
  static Status format(hal::BlockDevice& device, const VolumeFile* files, uint32_t count,
                       VolumeProblem* problem = nullptr);

  // Reads and checks the file table. kDataLoss for a damaged table (kNoVolume, kChecksum,
  // kBadTable), kFailedPrecondition for another version, device errors (kDeviceError).
  Status mount(hal::BlockDevice& device, VolumeProblem* problem = nullptr);

  // The file called `name` as a device of its own. kNotFound if absent,
  // kFailedPrecondition before mount().
  Status open(const char* name, Region* out, VolumeProblem* problem = nullptr) const;

  uint32_t file_count() const { return count_; }
  const VolumeFile& file(uint32_t i) const { return files_[i]; }

 private:
  hal::BlockDevice* device_ = nullptr;
  VolumeFile files_[kVolumeMaxFiles] = {};
  uint32_t count_ = 0;
};

}  // namespace seqslam::storage
