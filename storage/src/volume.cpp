#include "seqslam/storage/volume.h"

#include "seqslam/messages.h"
#include "seqslam/storage/bytes.h"

namespace seqslam::storage {

namespace {

constexpr uint8_t kMagic[8] = {'S', 'Q', 'S', 'L', 'V', 'O', 'L', '1'};
constexpr uint32_t kEntryBytes = 32;
constexpr uint32_t kTableOffset = 16;
constexpr uint32_t kCrcOffset = hal::kBlockSize - 4;
static_assert(kTableOffset + kVolumeMaxFiles * kEntryBytes <= kCrcOffset, "table must fit");

bool valid_name(const char* name) {
  uint32_t n = 0;
  for (; n < kVolumeNameBytes && name[n] != '\0'; ++n) {
    const char c = name[n];
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') ||
                    c == '.' || c == '_' || c == '-';
    if (!ok) return false;
  }
  return n > 0 && n < kVolumeNameBytes;
}

bool same_name(const char* a, const char* b) {
  for (uint32_t i = 0; i < kVolumeNameBytes; ++i) {
    if (a[i] != b[i]) return false;
    if (a[i] == '\0') return true;
  }
  return true;
}

Status fail(VolumeProblem* out, VolumeProblem p, Status s) {
  if (out != nullptr) *out = p;
  return s;
}

// Names unique and valid, sizes non-zero, ranges inside the device and disjoint (the format
// places them in order, but a table read from disk is checked the same way).
bool table_ok(const VolumeFile* files, uint32_t count, uint32_t blocks) {
  if (count > kVolumeMaxFiles) return false;
  for (uint32_t i = 0; i < count; ++i) {
    const VolumeFile& f = files[i];
    if (!valid_name(f.name) || f.block_count == 0 || f.first_block == 0) return false;
    if (f.first_block >= blocks || f.block_count > blocks - f.first_block) return false;
    for (uint32_t k = 0; k < i; ++k) {
      const VolumeFile& g = files[k];
      if (same_name(f.name, g.name)) return false;
      const bool disjoint = f.first_block + f.block_count <= g.first_block ||
                            g.first_block + g.block_count <= f.first_block;
      if (!disjoint) return false;
    }
  }
  return true;
}

}  // namespace

const char* volume_problem_text(VolumeProblem p) {
#if !SEQSLAM_MESSAGE_TEXTS
  return message_code("VP", static_cast<uint32_t>(p));
#endif
  switch (p) {
    case VolumeProblem::kNone:
      return "volume is valid";
    case VolumeProblem::kDeviceError:
      return "the block device failed to read or write the file table (block 0)";
    case VolumeProblem::kNoVolume:
      return "block 0 is not a seqslam volume (magic SQSLVOL1 missing); format it first";
    case VolumeProblem::kVersion:
      return "the volume was written by another format version";
    case VolumeProblem::kChecksum:
      return "the file table (block 0) is damaged: checksum mismatch";
    case VolumeProblem::kBadTable:
      return "the file table is invalid: bad or duplicate names, empty or overlapping files, "
             "files beyond the device, or more than 15 files";
    case VolumeProblem::kNotFound:
      return "no file of that name on the volume";
    case VolumeProblem::kTooLarge:
      return "the files do not fit on the device";
  }
  return "unknown volume problem";
}

Status Volume::format(hal::BlockDevice& device, const VolumeFile* files, uint32_t count,
                      VolumeProblem* problem) {
  if ((files == nullptr && count > 0) || count > kVolumeMaxFiles) {
    return fail(problem, VolumeProblem::kBadTable, Status::kInvalidArgument);
  }
  VolumeFile placed[kVolumeMaxFiles];
  uint64_t next = 1;
  for (uint32_t i = 0; i < count; ++i) {
    placed[i] = files[i];
    placed[i].first_block = static_cast<uint32_t>(next);
    next += files[i].block_count;
    if (next > device.block_count()) {
      return fail(problem, VolumeProblem::kTooLarge, Status::kResourceExhausted);
    }
  }
  if (!table_ok(placed, count, device.block_count())) {
    return fail(problem, VolumeProblem::kBadTable, Status::kInvalidArgument);
  }
  uint8_t block[hal::kBlockSize] = {};
  ByteWriter w(block, sizeof block);
  w.bytes(kMagic, sizeof kMagic);
  w.u16(kVolumeVersion);
  w.u16(static_cast<uint16_t>(count));
  w.u32(0);
  for (uint32_t i = 0; i < count; ++i) {
    w.bytes(reinterpret_cast<const uint8_t*>(placed[i].name), kVolumeNameBytes);
    w.u32(placed[i].first_block);
    w.u32(placed[i].block_count);
    w.zeros(kEntryBytes - kVolumeNameBytes - 8);
  }
  ByteWriter crc(block + kCrcOffset, 4);
  crc.u32(crc32(block, kCrcOffset));
  Status s = device.write(0, 1, block);
  if (s == Status::kOk) s = device.sync();
  if (s != Status::kOk) return fail(problem, VolumeProblem::kDeviceError, s);
  return fail(problem, VolumeProblem::kNone, Status::kOk);
}

Status Volume::mount(hal::BlockDevice& device, VolumeProblem* problem) {
  device_ = nullptr;
  count_ = 0;
  uint8_t block[hal::kBlockSize] = {};
  const Status s = device.read(0, 1, block);
  if (s != Status::kOk) return fail(problem, VolumeProblem::kDeviceError, s);
  for (uint32_t i = 0; i < sizeof kMagic; ++i) {
    if (block[i] != kMagic[i]) return fail(problem, VolumeProblem::kNoVolume, Status::kDataLoss);
  }
  ByteReader r(block, sizeof block);
  r.skip(sizeof kMagic);
  const uint16_t version = r.u16();
  const uint16_t count = r.u16();
  ByteReader crc(block + kCrcOffset, 4);
  if (crc.u32() != crc32(block, kCrcOffset)) {
    return fail(problem, VolumeProblem::kChecksum, Status::kDataLoss);
  }
  if (version != kVolumeVersion) {
    return fail(problem, VolumeProblem::kVersion, Status::kFailedPrecondition);
  }
  if (count > kVolumeMaxFiles) return fail(problem, VolumeProblem::kBadTable, Status::kDataLoss);
  VolumeFile files[kVolumeMaxFiles];
  for (uint32_t i = 0; i < count; ++i) {
    ByteReader e(block + kTableOffset + i * kEntryBytes, kEntryBytes);
    const uint8_t* name = e.bytes(kVolumeNameBytes);
    for (uint32_t k = 0; k < kVolumeNameBytes; ++k)
      files[i].name[k] = static_cast<char>(name[k]);
    files[i].first_block = e.u32();
    files[i].block_count = e.u32();
  }
  if (!table_ok(files, count, device.block_count())) {
    return fail(problem, VolumeProblem::kBadTable, Status::kDataLoss);
  }
  for (uint32_t i = 0; i < count; ++i)
    files_[i] = files[i];
  count_ = count;
  device_ = &device;
  return fail(problem, VolumeProblem::kNone, Status::kOk);
}

Status Volume::open(const char* name, Region* out, VolumeProblem* problem) const {
  if (name == nullptr || out == nullptr) return Status::kInvalidArgument;
  if (device_ == nullptr) return Status::kFailedPrecondition;
  for (uint32_t i = 0; i < count_; ++i) {
    if (same_name(files_[i].name, name)) {
      *out = Region(*device_, files_[i].first_block, files_[i].block_count);
      return fail(problem, VolumeProblem::kNone, Status::kOk);
    }
  }
  return fail(problem, VolumeProblem::kNotFound, Status::kNotFound);
}

}  // namespace seqslam::storage
