// The emulated board's SD card: a virtio-blk disk on QEMU's RISC-V "virt" machine, backed by
// a raw disk-image file on the host (scripts/qemu-run.sh attaches SEQSLAM_QEMU_DISK).
//
// Design
// ------
// Transport: virtio-mmio *version 2* ("modern", virtio 1.x). QEMU 7.2 presents its
//   virtio-mmio transports as legacy (version 1) unless started with
//   `-global virtio-mmio.force-legacy=false`; scripts/qemu-run.sh always passes that. A
//   legacy transport is detected and reported by init() (kUnavailable, reason() says which
//   option is missing) rather than driven.
// Probe: the eight transports at 0x10001000 + i * 0x1000 are scanned in order; the first
//   with magic "virt", version 2 and device ID 2 (block) is used. QEMU plugs the first
//   -device into the highest slot, so a single disk is normally found in slot 7.
// Features: VIRTIO_F_VERSION_1 (required), and, when the device offers them,
//   VIRTIO_BLK_F_FLUSH (sync() sends VIRTIO_BLK_T_FLUSH), VIRTIO_BLK_F_RO (write() returns
//   kResourceExhausted without asking the device) and VIRTIO_BLK_F_SIZE_MAX (caps the
//   request size). Nothing else (no event index, no indirect descriptors, no multi-queue).
// Queue: one split virtqueue (queue 0) of kQueueSize = 4 entries; a request is a chain of
//   three descriptors (16-byte header, data, 1-byte status; a flush has no data) and only
//   one request is in flight, so descriptor 0 is always the head. The descriptor table,
//   the available and used rings, the request header, the status byte and the bounce
//   buffer are members of this object (no heap), aligned as the virtio 1.x split queue
//   requires (16 / 2 / 4 bytes). Make the object static: the device keeps the rings'
//   addresses until the next init() or a reset.
// Completion: polling, no interrupts. The available ring carries VIRTQ_AVAIL_F_NO_INTERRUPT
//   and the driver spins on the used ring's index, at most poll_limit reads per request
//   (constructor argument; kDefaultPollLimit is about 12 s of wall-clock time under
//   QEMU). On expiry the device is reset, so that it can never write into a buffer the
//   caller has reclaimed, the device stops being ready() and the call returns
//   kUnavailable; init() brings it back.
// Ordering: MMIO registers are accessed through volatile pointers. `fence rw,rw` orders
//   the descriptors, the header and the caller's data before the store that publishes the
//   available index; `fence iorw,iorw` orders that store before the QueueNotify register
//   write; after the used index moves, `fence rw,rw` orders it before the used element,
//   the status byte and the data are read. All fences are also compiler barriers ("memory"
//   clobber).
// Data: requests carry the caller's buffer directly (zero copy) when it is kDmaAlignment
//   (4-byte) aligned, as SD host DMA engines commonly require; virtio itself would accept
//   any address, the rule keeps firmware buffers honest. Any other buffer goes through a
//   one-block bounce buffer, one request per block. Long transfers are split into requests
//   of at most max_request_blocks() blocks (kMaxRequestBlocks = 128, i.e. 64 KiB, or less
//   if the device sets size_max).
// Capacity: the config space's `capacity` (512-byte sectors, read under the config
//   generation counter). A disk of 2^32 or more sectors (2 TiB) is clamped to 2^32 - 1
//   blocks, since BlockDevice counts blocks in 32 bits.
//
// Statuses (in addition to the argument checks of BlockDevice::read/write)
//   init():  kOk; kUnavailable - no virtio-blk device, a legacy transport, missing
//            VIRTIO_F_VERSION_1, features refused, queue unusable (reason() says which).
//   read()/write(): kUnavailable - a request timed out, now or earlier (the device was
//            reset; block_count() keeps its value until the next init()); kDataLoss - the
//            device answered VIRTIO_BLK_S_IOERR / UNSUPP (the device stays ready), or the
//            used ring was inconsistent (the device is reset, as on a timeout); write()
//            also kResourceExhausted on a read-only disk.
//   sync():  kOk after a successful flush, or at once (no request) when the device does
//            not offer VIRTIO_BLK_F_FLUSH: such a device has no volatile write cache, every
//            write is durable when it completes (QEMU offers FLUSH unless the drive runs
//            with cache=writethrough or directsync, whose writes complete only once
//            durable); kUnavailable when not ready(); kDataLoss if the flush failed.
// Before a successful init() block_count() is 0, so read()/write() return kOutOfRange
// from the interface's argument check without reaching this driver.
//
// Cost (RV32IMC -O3, measured by tests/support/virtio_block_test.cpp, which prints them):
//   driver work ~172 instructions per read request and ~175 per write request, the same
//   on every run: per block 172 / 175 for one-block calls, 1.4 for 128-block requests;
//   the bounce buffer adds ~2 490 per block (byte-wise memcpy of an unaligned buffer).
//   Waiting adds 4 instructions per poll and depends on the host: from a few hundred to
//   tens of thousands of polls per request (1 000 - 80 000 instructions) under QEMU.
// Determinism: the wait lasts as long as the host's I/O does, so instruction counts of
//   code that does I/O differ between runs even under -icount shift=0; everything except
//   the wait (the "without waiting" figures) is identical on every run, and code that does
//   no I/O is unaffected. (Sleeping in wfi until the device's interrupt line rises, with
//   no handler, was tried: it makes the counts exact, as QEMU's icount clock stands still
//   while the hart sleeps, but only while no timer is armed - an armed CLINT timeout lets
//   idle wall-clock time into minstret - so such a wait cannot be bounded. Not used.)
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/hal/block_device.h"
#include "seqslam/status.h"

namespace seqslam::board {

class VirtioBlockDevice final : public hal::BlockDevice {
 public:
  // virtio-mmio transports of the virt machine.
  static constexpr uintptr_t kMmioBase = 0x10001000u;
  static constexpr uintptr_t kMmioStride = 0x1000u;
  static constexpr uint32_t kMmioSlots = 8;
  // Entries of the one virtqueue (a power of two >= 3 descriptors).
  static constexpr uint16_t kQueueSize = 4;
  // Largest request in blocks (64 KiB); the device's size_max may lower it.
  static constexpr uint32_t kMaxRequestBlocks = 128;
  // Buffers aligned to this go to the device directly, others through the bounce buffer.
  static constexpr uint32_t kDmaAlignment = 4;
  // Used-ring reads per request before giving up: 4 instructions each, about 80 million
  // per second of wall-clock time under QEMU on our machines, so roughly 12 s.
  static constexpr uint32_t kDefaultPollLimit = 1000000000u;

  // What the driver has done since construction (not reset by init()).
  struct Counters {
    uint32_t requests;        // requests handed to the device (read, write, flush)
    uint32_t bounced_blocks;  // blocks copied through the bounce buffer
    uint64_t polls;           // used-ring reads spent waiting for completions
  };

  constexpr VirtioBlockDevice() = default;
  explicit constexpr VirtioBlockDevice(uint32_t poll_limit)
      : poll_limit_(poll_limit == 0 ? 1 : poll_limit) {}
  ~VirtioBlockDevice() = default;
  VirtioBlockDevice(const VirtioBlockDevice&) = delete;
  VirtioBlockDevice& operator=(const VirtioBlockDevice&) = delete;

  // Probes the transports, resets and sets up the device, reads the capacity. May be
  // called again (e.g. after a timeout); each call resets the device first. On failure
  // returns kUnavailable, block_count() is 0 and reason() says why.
  Status init();

  // True after a successful init() until a timeout or ring error resets the device.
  bool ready() const { return ready_; }
  // Why the last init() or transfer failed, or "ready" / "not initialised". Never null.
  // What the device said, without the "virtio-blk" the caller prints before it (RAM: every
  // byte of text is counted on the board).
  const char* reason() const { return reason_; }

  // Slot (0..7) and register base of the device in use; -1 / 0 when none was found.
  int slot() const { return slot_; }
  uintptr_t base_address() const { return base_; }
  // Negotiated device properties (valid after a successful init()).
  bool flush_supported() const { return flush_; }
  bool read_only() const { return read_only_; }
  uint64_t capacity_sectors() const { return capacity_sectors_; }
  uint32_t max_request_blocks() const { return max_request_blocks_; }

  const Counters& counters() const { return counters_; }

 private:
  // virtio 1.x split virtqueue, little-endian (as is RV32).
  struct Descriptor {
    uint64_t addr;
    uint32_t len;
    uint16_t flags;
    uint16_t next;
  };
  struct AvailRing {
    uint16_t flags;
    uint16_t idx;
    uint16_t ring[kQueueSize];
    uint16_t used_event;
  };
  struct UsedElem {
    uint32_t id;
    uint32_t len;
  };
  struct UsedRing {
    uint16_t flags;
    uint16_t idx;
    UsedElem ring[kQueueSize];
    uint16_t avail_event;
  };
  struct RequestHeader {
    uint32_t type;
    uint32_t reserved;
    uint64_t sector;
  };

  uint32_t do_block_count() const override { return block_count_; }
  Status do_read(uint32_t first, uint32_t count, uint8_t* out) override;
  Status do_write(uint32_t first, uint32_t count, const uint8_t* data) override;
  Status do_sync() override;

  Status setup(uintptr_t base);
  Status fail_setup(const char* why);
  Status transfer(uint32_t type, uint32_t first, uint32_t count, uint8_t* buffer);
  Status request(uint32_t type, uint32_t sector, uint8_t* data, uint32_t bytes);
  void give_up(const char* why);

  // Shared with the device (DMA). Descriptor table first: 16-byte alignment.
  alignas(16) Descriptor desc_[kQueueSize] = {};
  UsedRing used_ = {};
  AvailRing avail_ = {};
  RequestHeader header_ = {};
  uint8_t status_byte_ = 0;
  alignas(kDmaAlignment) uint8_t bounce_[hal::kBlockSize] = {};

  // Driver state.
  const char* reason_ = "not initialised";
  uintptr_t base_ = 0;
  uint64_t capacity_sectors_ = 0;
  Counters counters_ = {};
  uint32_t block_count_ = 0;
  uint32_t max_request_blocks_ = kMaxRequestBlocks;
  uint32_t poll_limit_ = kDefaultPollLimit;
  uint16_t last_used_ = 0;
  int slot_ = -1;
  bool ready_ = false;
  bool flush_ = false;
  bool read_only_ = false;
};

}  // namespace seqslam::board
