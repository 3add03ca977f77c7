// A block device that counts what passes through it: wrap the card (or any BlockDevice) in a
// CountingBlockDevice and hand the wrapper to the code that uses the card; every request it
// forwards is counted, so a caller can state the card traffic of a piece of work (e.g. one
// localisation step) and turn it into card time with sd_card_model.h.
//
// Why a decorator: one implementation counts the fake card in tests, the disk-image file on
// the PC and the virtio disk on the emulated board alike, without touching any driver.
//
// What is counted (CardCounters):
//   - a request is one call of read() / write() / sync() that passed BlockDevice's argument
//     check and was handed to the wrapped device. On the SD card in SPI mode a read or write
//     request of n blocks is one command: CMD17 / CMD24 for n = 1, CMD18 / CMD25 for n > 1
//     (sd_card_model.h), hence the separate counts of multi-block requests;
//   - blocks are counted per request as the request's block count, whether it succeeded or
//     not (a failed request may have moved any part of it; the model charges it in full,
//     an upper bound);
//   - failed_requests counts the requests of every kind that the wrapped device answered
//     with anything but kOk; they are also in the request and block counts.
// Not counted: calls rejected by BlockDevice's own argument check (null buffer, count 0, a
// range past block_count()): they return kInvalidArgument / kOutOfRange before reaching
// this class, and no command would reach a card either.
//
// Width: every counter is a uint32_t and wraps modulo 2^32; difference() is exact as long
// as fewer than 2^32 of a count happen between the two snapshots. An SD card on SPI at
// 25 MHz moves at most about 6 070 blocks a second (515 bus bytes of 320 ns each), so
// blocks_read wraps after 8 days of nothing but reading and the request counts later still:
// per-step and per-run figures are exact, lifetime totals are not (add deltas into wider
// sums if you need them). 32 bits rather than 64 because the board firmware has almost no
// RAM or code to spare: uint64_t counters cost it 160 bytes more.
//
// Freestanding (no libc, no heap, no floating point), header-only: builds for host and target.
// The object holds a pointer to the wrapped device, which must outlive it (both are normally
// static objects of the board's main).
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/hal/block_device.h"
#include "seqslam/status.h"

namespace seqslam::hal {

// A snapshot of the counts of one CountingBlockDevice (all zero after construction or
// reset_counters()). Plain data: copy it to remember a moment, subtract two with difference().
struct CardCounters {
  uint32_t read_requests = 0;         // read() calls forwarded (single- and multi-block)
  uint32_t multi_read_requests = 0;   // of those, the ones of 2 or more blocks (CMD18)
  uint32_t blocks_read = 0;           // 512-byte blocks asked for by the read requests
  uint32_t write_requests = 0;        // write() calls forwarded
  uint32_t multi_write_requests = 0;  // of those, the ones of 2 or more blocks (CMD25)
  uint32_t blocks_written = 0;        // 512-byte blocks handed over by the write requests
  uint32_t sync_requests = 0;         // sync() calls forwarded
  uint32_t failed_requests = 0;       // requests of any kind the device did not answer kOk
};

constexpr bool operator==(const CardCounters& a, const CardCounters& b) {
  return a.read_requests == b.read_requests && a.multi_read_requests == b.multi_read_requests &&
         a.write_requests == b.write_requests && a.multi_write_requests == b.multi_write_requests &&
         a.sync_requests == b.sync_requests && a.blocks_read == b.blocks_read &&
         a.blocks_written == b.blocks_written && a.failed_requests == b.failed_requests;
}
constexpr bool operator!=(const CardCounters& a, const CardCounters& b) {
  return !(a == b);
}

// What happened between two snapshots of the same device: later - earlier, field by field,
// modulo 2^32 (exact even if a counter wrapped in between, as long as fewer than 2^32 counts
// happened). `earlier` must have been taken first and no reset_counters() may lie between them;
// otherwise the fields are meaningless (wrapped) values.
constexpr CardCounters difference(const CardCounters& later, const CardCounters& earlier) {
  CardCounters d;
  d.read_requests = later.read_requests - earlier.read_requests;
  d.multi_read_requests = later.multi_read_requests - earlier.multi_read_requests;
  d.write_requests = later.write_requests - earlier.write_requests;
  d.multi_write_requests = later.multi_write_requests - earlier.multi_write_requests;
  d.sync_requests = later.sync_requests - earlier.sync_requests;
  d.blocks_read = later.blocks_read - earlier.blocks_read;
  d.blocks_written = later.blocks_written - earlier.blocks_written;
  d.failed_requests = later.failed_requests - earlier.failed_requests;
  return d;
}

class CountingBlockDevice final : public BlockDevice {
 public:
  // Counts the requests forwarded to `device`, which must outlive this object. constexpr, so
  // a static CountingBlockDevice is initialised at compile time (no constructor ordering
  // between it and the static device it wraps).
  explicit constexpr CountingBlockDevice(BlockDevice& device) : device_(&device) {}
  ~CountingBlockDevice() = default;
  // Not copyable: two copies would split one device's counts.
  CountingBlockDevice(const CountingBlockDevice&) = delete;
  CountingBlockDevice& operator=(const CountingBlockDevice&) = delete;

  // The counts since construction or the last reset_counters().
  const CardCounters& counters() const { return counters_; }
  // The counts since `mark`, an earlier counters() snapshot (see difference()).
  CardCounters since(const CardCounters& mark) const { return difference(counters_, mark); }
  // Sets every count to zero. Snapshots taken before are no longer comparable with later ones.
  void reset_counters() { counters_ = CardCounters{}; }

  // The wrapped device (e.g. to call its own init() or read its driver counters).
  BlockDevice& device() const { return *device_; }

 private:
  // block_count(), and so the argument check of read()/write(), is the wrapped device's.
  uint32_t do_block_count() const override { return device_->block_count(); }

  Status do_read(uint32_t first, uint32_t count, uint8_t* out) override {
    ++counters_.read_requests;
    if (count > 1) ++counters_.multi_read_requests;
    counters_.blocks_read += count;
    return counted(device_->read(first, count, out));
  }

  Status do_write(uint32_t first, uint32_t count, const uint8_t* data) override {
    ++counters_.write_requests;
    if (count > 1) ++counters_.multi_write_requests;
    counters_.blocks_written += count;
    return counted(device_->write(first, count, data));
  }

  Status do_sync() override {
    ++counters_.sync_requests;
    return counted(device_->sync());
  }

  // Passes the device's status through unchanged, counting it if it is a failure.
  Status counted(Status s) {
    if (s != Status::kOk) ++counters_.failed_requests;
    return s;
  }

  BlockDevice* device_;
  CardCounters counters_{};
};

}  // namespace seqslam::hal
