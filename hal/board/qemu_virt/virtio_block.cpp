// virtio-blk over virtio-mmio (version 2) for QEMU's virt board. Design: virtio_block.h.
#include "seqslam/board/virtio_block.h"

namespace seqslam::board {
namespace {

// virtio-mmio registers (virtio 1.x, section 4.2.2), byte offsets from the slot base.
constexpr uint32_t kRegMagic = 0x000;
constexpr uint32_t kRegVersion = 0x004;
constexpr uint32_t kRegDeviceId = 0x008;
constexpr uint32_t kRegDeviceFeatures = 0x010;
constexpr uint32_t kRegDeviceFeaturesSel = 0x014;
constexpr uint32_t kRegDriverFeatures = 0x020;
constexpr uint32_t kRegDriverFeaturesSel = 0x024;
constexpr uint32_t kRegQueueSel = 0x030;
constexpr uint32_t kRegQueueNumMax = 0x034;
constexpr uint32_t kRegQueueNum = 0x038;
constexpr uint32_t kRegQueueReady = 0x044;
constexpr uint32_t kRegQueueNotify = 0x050;
constexpr uint32_t kRegStatus = 0x070;
constexpr uint32_t kRegQueueDescLow = 0x080;
constexpr uint32_t kRegQueueDescHigh = 0x084;
constexpr uint32_t kRegQueueDriverLow = 0x090;
constexpr uint32_t kRegQueueDriverHigh = 0x094;
constexpr uint32_t kRegQueueDeviceLow = 0x0a0;
constexpr uint32_t kRegQueueDeviceHigh = 0x0a4;
constexpr uint32_t kRegConfigGeneration = 0x0fc;
constexpr uint32_t kRegConfig = 0x100;

constexpr uint32_t kMagic = 0x74726976u;  // "virt", little-endian
constexpr uint32_t kVersionLegacy = 1;
constexpr uint32_t kVersionModern = 2;
constexpr uint32_t kDeviceIdBlock = 2;

// Device status bits.
constexpr uint32_t kStatusAcknowledge = 1;
constexpr uint32_t kStatusDriver = 2;
constexpr uint32_t kStatusDriverOk = 4;
constexpr uint32_t kStatusFeaturesOk = 8;
constexpr uint32_t kStatusNeedsReset = 64;
constexpr uint32_t kStatusFailed = 128;

// Feature bits: low word (select 0) and high word (select 1).
constexpr uint32_t kFeatureBlkSizeMax = 1u << 1;
constexpr uint32_t kFeatureBlkRo = 1u << 5;
constexpr uint32_t kFeatureBlkFlush = 1u << 9;
constexpr uint32_t kFeatureHighVersion1 = 1u << (32 - 32);  // VIRTIO_F_VERSION_1 = bit 32

// virtio-blk config space: capacity (u64 sectors) at 0, size_max (u32) at 8.
constexpr uint32_t kConfigCapacityLow = 0;
constexpr uint32_t kConfigCapacityHigh = 4;
constexpr uint32_t kConfigSizeMax = 8;

// Descriptor flags, available-ring flags.
constexpr uint16_t kDescNext = 1;
constexpr uint16_t kDescWrite = 2;
constexpr uint16_t kAvailNoInterrupt = 1;

// Request types and status values.
constexpr uint32_t kTypeIn = 0;
constexpr uint32_t kTypeOut = 1;
constexpr uint32_t kTypeFlush = 4;
constexpr uint8_t kBlkStatusOk = 0;
constexpr uint8_t kBlkStatusIoErr = 1;
constexpr uint8_t kBlkStatusUnsupported = 2;
constexpr uint8_t kStatusNotWritten = 0xFF;  // preset; the device overwrites it

// Bounded waits inside init() (register handshakes, not I/O).
constexpr uint32_t kSetupRetries = 1000;

uint32_t mmio_read(uintptr_t base, uint32_t offset) {
  return *reinterpret_cast<const volatile uint32_t*>(base + offset);
}

void mmio_write(uintptr_t base, uint32_t offset, uint32_t value) {
  *reinterpret_cast<volatile uint32_t*>(base + offset) = value;
}

// Memory-to-memory ordering between the CPU and the device's DMA.
inline void fence_memory() {
  __asm__ volatile("fence rw, rw" ::: "memory");
}

// Also orders memory accesses against device-register (I/O) accesses.
inline void fence_io() {
  __asm__ volatile("fence iorw, iorw" ::: "memory");
}

uint32_t address_of(const volatile void* p) {
  return static_cast<uint32_t>(reinterpret_cast<uintptr_t>(p));
}

void write_queue_address(uintptr_t base, uint32_t low_reg, uint32_t high_reg,
                         const volatile void* p) {
  mmio_write(base, low_reg, address_of(p));
  mmio_write(base, high_reg, 0);  // RV32: every address is below 4 GiB
}

void copy_bytes(uint8_t* dst, const uint8_t* src, uint32_t n) {
  __builtin_memcpy(dst, src, n);
}

}  // namespace

Status VirtioBlockDevice::init() {
  // Reset a device we were using before, so it forgets the rings.
  if (base_ != 0) {
    mmio_write(base_, kRegStatus, 0);
  }
  ready_ = false;
  block_count_ = 0;
  capacity_sectors_ = 0;
  base_ = 0;
  slot_ = -1;
  flush_ = false;
  read_only_ = false;

  bool saw_legacy_block = false;
  for (uint32_t i = 0; i < kMmioSlots; ++i) {
    const uintptr_t base = kMmioBase + i * kMmioStride;
    if (mmio_read(base, kRegMagic) != kMagic || mmio_read(base, kRegDeviceId) != kDeviceIdBlock) {
      continue;
    }
    const uint32_t version = mmio_read(base, kRegVersion);
    if (version == kVersionLegacy) {
      saw_legacy_block = true;
      continue;
    }
    if (version != kVersionModern) {
      continue;
    }
    slot_ = static_cast<int>(i);
    return setup(base);
  }
  reason_ = saw_legacy_block ? "legacy transport only (QEMU: virtio-mmio.force-legacy=false)"
                             : "no device (scripts/qemu-run.sh --disk)";
  return Status::kUnavailable;
}

Status VirtioBlockDevice::fail_setup(const char* why) {
  mmio_write(base_, kRegStatus, mmio_read(base_, kRegStatus) | kStatusFailed);
  reason_ = why;
  block_count_ = 0;
  return Status::kUnavailable;
}

// Device initialisation, virtio 1.x section 3.1.1.
Status VirtioBlockDevice::setup(uintptr_t base) {
  base_ = base;
  mmio_write(base, kRegStatus, 0);
  uint32_t tries = 0;
  while (mmio_read(base, kRegStatus) != 0) {
    if (++tries == kSetupRetries) {
      return fail_setup("did not complete its reset");
    }
  }
  uint32_t status = kStatusAcknowledge;
  mmio_write(base, kRegStatus, status);
  status |= kStatusDriver;
  mmio_write(base, kRegStatus, status);

  mmio_write(base, kRegDeviceFeaturesSel, 0);
  const uint32_t offered_low = mmio_read(base, kRegDeviceFeatures);
  mmio_write(base, kRegDeviceFeaturesSel, 1);
  const uint32_t offered_high = mmio_read(base, kRegDeviceFeatures);
  if ((offered_high & kFeatureHighVersion1) == 0) {
    return fail_setup("does not offer VIRTIO_F_VERSION_1");
  }
  const uint32_t accepted_low =
      offered_low & (kFeatureBlkFlush | kFeatureBlkRo | kFeatureBlkSizeMax);
  mmio_write(base, kRegDriverFeaturesSel, 0);
  mmio_write(base, kRegDriverFeatures, accepted_low);
  mmio_write(base, kRegDriverFeaturesSel, 1);
  mmio_write(base, kRegDriverFeatures, kFeatureHighVersion1);
  status |= kStatusFeaturesOk;
  mmio_write(base, kRegStatus, status);
  if ((mmio_read(base, kRegStatus) & kStatusFeaturesOk) == 0) {
    return fail_setup("refused the feature set");
  }
  flush_ = (accepted_low & kFeatureBlkFlush) != 0;
  read_only_ = (accepted_low & kFeatureBlkRo) != 0;

  // Queue 0.
  mmio_write(base, kRegQueueSel, 0);
  if (mmio_read(base, kRegQueueReady) != 0) {
    return fail_setup("queue 0 is already in use after reset");
  }
  if (mmio_read(base, kRegQueueNumMax) < kQueueSize) {
    return fail_setup("queue 0 is missing or smaller than 4 entries");
  }
  for (Descriptor& d : desc_) {
    d = Descriptor{};
  }
  avail_ = AvailRing{};
  avail_.flags = kAvailNoInterrupt;
  used_ = UsedRing{};
  last_used_ = 0;
  fence_io();
  mmio_write(base, kRegQueueNum, kQueueSize);
  write_queue_address(base, kRegQueueDescLow, kRegQueueDescHigh, desc_);
  write_queue_address(base, kRegQueueDriverLow, kRegQueueDriverHigh, &avail_);
  write_queue_address(base, kRegQueueDeviceLow, kRegQueueDeviceHigh, &used_);
  mmio_write(base, kRegQueueReady, 1);

  // Configuration: retry while the generation counter shows a concurrent change.
  uint32_t size_max = 0;
  uint64_t capacity = 0;
  for (tries = 0;; ++tries) {
    if (tries == kSetupRetries) {
      return fail_setup("configuration never became stable");
    }
    const uint32_t generation = mmio_read(base, kRegConfigGeneration);
    const uint32_t low = mmio_read(base, kRegConfig + kConfigCapacityLow);
    const uint32_t high = mmio_read(base, kRegConfig + kConfigCapacityHigh);
    size_max = mmio_read(base, kRegConfig + kConfigSizeMax);
    if (mmio_read(base, kRegConfigGeneration) == generation) {
      capacity = (static_cast<uint64_t>(high) << 32) | low;
      break;
    }
  }
  max_request_blocks_ = kMaxRequestBlocks;
  if ((accepted_low & kFeatureBlkSizeMax) != 0) {
    if (size_max < hal::kBlockSize) {
      return fail_setup("size_max is below one 512-byte block");
    }
    if (size_max / hal::kBlockSize < max_request_blocks_) {
      max_request_blocks_ = size_max / hal::kBlockSize;
    }
  }

  status |= kStatusDriverOk;
  mmio_write(base, kRegStatus, status);
  if ((mmio_read(base, kRegStatus) & (kStatusNeedsReset | kStatusFailed)) != 0) {
    return fail_setup("reported an error while starting");
  }
  capacity_sectors_ = capacity;
  block_count_ = capacity > 0xFFFFFFFFu ? 0xFFFFFFFFu : static_cast<uint32_t>(capacity);
  ready_ = true;
  reason_ = "ready";
  return Status::kOk;
}

// Resets the device so it stops using the rings and the caller's buffer.
void VirtioBlockDevice::give_up(const char* why) {
  mmio_write(base_, kRegStatus, 0);
  ready_ = false;
  reason_ = why;
}

// One request of `bytes` at `sector`, data descriptor omitted when data is null.
Status VirtioBlockDevice::request(uint32_t type, uint32_t sector, uint8_t* data, uint32_t bytes) {
  header_.type = type;
  header_.reserved = 0;
  header_.sector = sector;
  status_byte_ = kStatusNotWritten;

  // Chain: 0 header (device reads) -> [1 data (device writes for reads)] -> 2 status.
  desc_[0].addr = address_of(&header_);
  desc_[0].len = sizeof(RequestHeader);
  desc_[0].flags = kDescNext;
  desc_[0].next = data != nullptr ? 1 : 2;
  if (data != nullptr) {
    desc_[1].addr = address_of(data);
    desc_[1].len = bytes;
    desc_[1].flags = static_cast<uint16_t>(kDescNext | (type == kTypeIn ? kDescWrite : 0));
    desc_[1].next = 2;
  }
  desc_[2].addr = address_of(&status_byte_);
  desc_[2].len = 1;
  desc_[2].flags = kDescWrite;
  desc_[2].next = 0;

  const uint16_t avail_idx = avail_.idx;
  avail_.ring[avail_idx % kQueueSize] = 0;  // head of the chain
  fence_memory();                           // descriptors, header, data before the index
  *static_cast<volatile uint16_t*>(&avail_.idx) = static_cast<uint16_t>(avail_idx + 1);
  fence_io();  // the index before the notification
  mmio_write(base_, kRegQueueNotify, 0);
  ++counters_.requests;

  const volatile uint16_t* used_idx = &used_.idx;
  const uint16_t expected = last_used_;
  uint32_t budget = poll_limit_;
  while (*used_idx == expected) {
    if (--budget == 0) {
      counters_.polls += poll_limit_;
      const bool needs_reset = (mmio_read(base_, kRegStatus) & kStatusNeedsReset) != 0;
      give_up(needs_reset ? "needs a reset (reset; call init())"
                          : "did not complete a request in time (reset; call init())");
      return Status::kUnavailable;
    }
  }
  counters_.polls += poll_limit_ - budget + 1;
  fence_memory();  // the used index before the used element, status byte and data
  last_used_ = static_cast<uint16_t>(expected + 1);

  const volatile UsedElem& done = used_.ring[expected % kQueueSize];
  if (done.id != 0 || *used_idx != last_used_) {
    give_up("unexpected used-ring entry (reset; call init())");
    return Status::kDataLoss;
  }
  switch (*static_cast<const volatile uint8_t*>(&status_byte_)) {
    case kBlkStatusOk:
      return Status::kOk;
    case kBlkStatusIoErr:
      reason_ = "VIRTIO_BLK_S_IOERR";
      return Status::kDataLoss;
    case kBlkStatusUnsupported:
      reason_ = "VIRTIO_BLK_S_UNSUPP";
      return Status::kDataLoss;
    default:
      reason_ = "no request status";
      return Status::kDataLoss;
  }
}

// Splits [first, first + count) into requests; bounce-buffers unaligned buffers.
Status VirtioBlockDevice::transfer(uint32_t type, uint32_t first, uint32_t count, uint8_t* buffer) {
  if (!ready_) {
    return Status::kUnavailable;
  }
  const bool direct = (reinterpret_cast<uintptr_t>(buffer) & (kDmaAlignment - 1)) == 0;
  while (count > 0) {
    uint32_t blocks = 1;
    Status s = Status::kOk;
    if (direct) {
      blocks = count < max_request_blocks_ ? count : max_request_blocks_;
      s = request(type, first, buffer, blocks * hal::kBlockSize);
    } else {
      if (type == kTypeOut) {
        copy_bytes(bounce_, buffer, hal::kBlockSize);
      }
      s = request(type, first, bounce_, hal::kBlockSize);
      if (s == Status::kOk && type == kTypeIn) {
        copy_bytes(buffer, bounce_, hal::kBlockSize);
      }
      ++counters_.bounced_blocks;
    }
    if (s != Status::kOk) {
      return s;
    }
    first += blocks;
    count -= blocks;
    buffer += blocks * hal::kBlockSize;
  }
  return Status::kOk;
}

Status VirtioBlockDevice::do_read(uint32_t first, uint32_t count, uint8_t* out) {
  return transfer(kTypeIn, first, count, out);
}

Status VirtioBlockDevice::do_write(uint32_t first, uint32_t count, const uint8_t* data) {
  if (ready_ && read_only_) {
    reason_ = "disk is read-only (VIRTIO_BLK_F_RO)";
    return Status::kResourceExhausted;
  }
  // The device only reads this buffer (no VIRTQ_DESC_F_WRITE); the bounce path only
  // reads from it too.
  return transfer(kTypeOut, first, count, const_cast<uint8_t*>(data));
}

Status VirtioBlockDevice::do_sync() {
  if (!ready_) {
    return Status::kUnavailable;
  }
  if (!flush_) {
    return Status::kOk;
  }
  return request(kTypeFlush, 0, nullptr, 0);
}

}  // namespace seqslam::board
