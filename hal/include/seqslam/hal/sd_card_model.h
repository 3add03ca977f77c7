// The time an SD card in SPI mode needs for the traffic counted by a CountingBlockDevice:
// bytes on the SPI bus (commands, responses, data tokens) at the bus clock, plus the time the
// card itself takes (read access before data, programming busy after writes). Integer
// nanoseconds only, constexpr, freestanding: usable on the target and in static_asserts.
// docs/card_model.md explains the model, its sources and what it leaves out.
//
// Sources: SD Specifications Part 1, Physical Layer Simplified Specification (SD Card
// Association; section numbers of version 9.10 unless stated):
//   7.3.1.1 every command is 6 bytes;  7.3.2.1 R1 is 1 byte;  7.3.2.2 R1b = R1 + busy;
//   7.3.2.3 R2 (the answer to CMD13 SEND_STATUS) is 2 bytes;
//   7.3.3.2 a data token is a start byte, the 512 data bytes and a 16-bit CRC (515 bytes);
//           CMD25 blocks end with a 'Stop Tran' token, CMD18 with CMD12 (R1b, 7.3.1.3);
//   7.3.3.1 every written block is answered by a 1-byte data response token;
//   7.2.2   the CRC bytes are on the bus even in the default CRC-off mode (only ignored);
//   7.2.4   after programming "the host should check the results ... using CMD13";
//   7.5.4   Timing Values (8-clock units: NCR 0/1..8 between command and response,
//           NWR >= 1 before a written block, NBR 0..1 after a Stop Tran token, NCS/NEC >= 0
//           around chip select; NAC see below) - in the simplified specification up to
//           version 4.10, removed from it since 6.00; the same table is Table 5-5 of
//           SanDisk's SD Card Product Manual 2.2;
//   4.6.2.1 read access: for SDHC/SDXC only a timeout, 100 ms, for the first block and
//           between the blocks of a multiple read; 5.3.3: TAAC/NSAC are fixed (1 ms / 0)
//           and "should not" be used;
//   4.6.2.2 write busy: for SDHC at most 250 ms, per block gap and after the last block
//           (SDXC up to 500 ms); R2W_FACTOR is fixed (x4) and not to be used;
//   4.16.1.1 Application Performance Class A1: >= 1500 random 4 KiB reads and >= 500
//           random 4 KiB writes per second, >= 10 MB/s sustained sequential writing;
//   7.2.15  in SPI mode the host shall treat the card as Speed Class 0 (no guarantee).
// So the specification bounds the card's own times only by timeouts 200 to 10 000 times the
// typical values; the defaults below are typical values with the reasoning next to them,
// and every number is a parameter for a user to replace with a measurement of their card.
//
// The model, for counters C and timing T (all sums saturate at UINT64_MAX):
//   bus bytes = C.read_requests        * (select + command + ncr + r1)             CMD17/18
//             + C.multi_read_requests  * (command + ncr + r1 + stop_read_extra)    CMD12
//             + C.blocks_read          * (data_token + 512 + crc)
//             + C.write_requests       * (select + command + ncr + r1)             CMD24/25
//             + C.write_requests * status_after_write * (select + command + ncr + r2) CMD13
//             + C.multi_write_requests * stop_tran                                 Stop Tran
//             + C.blocks_written       * (nwr + data_token + 512 + crc + data_response)
//             + C.sync_requests        * sync
//   card ns   = C.read_requests * read_access_ns
//             + (C.blocks_read - C.read_requests) * read_next_block_ns   (0 if negative)
//             + C.write_requests * write_request_busy_ns
//             + C.blocks_written * write_block_busy_ns
//             + C.sync_requests * sync_busy_ns
//   time ns   = round(bus bytes * 8 * 1e9 / spi_clock_hz) + card ns
// A request of n blocks is one single-block command (CMD17 / CMD24) for n = 1 and one
// multiple-block command (CMD18 + CMD12 / CMD25 + Stop Tran) for n > 1: the per-request
// terms apply per request, the per-block terms per block. Failed requests are charged in
// full (the counters include them; an upper bound). Waits are charged as time, not rounded
// up to whole polled bytes (at most 320 ns each at 25 MHz).
//
// With the defaults (25 MHz: 320 ns per byte, exact):
//   per read request 495.44 us, +5.44 us if multi-block, per block read 174.80 us
//     -> one single-block read 670.24 us, one 100-block read 17 980.88 us;
//   per write request 1 011.20 us, +0.64 us if multi-block, per block written 215.44 us
//     -> one single-block write 1 226.64 us;   per sync 0.32 us.
#pragma once

#include <stdint.h>

#include "seqslam/hal/block_device.h"
#include "seqslam/hal/counting_block_device.h"

namespace seqslam::hal {

// The card and bus parameters of the model. Byte counts are whole bytes on the SPI bus
// (8 clocks each); times are nanoseconds the card spends before it sends data or while it
// holds the data line busy. Defaults: an SDHC card on SPI at 25 MHz, typical values where
// the specification gives only timeouts (see each field and docs/card_model.md).
struct SdSpiTiming {
  // SPI clock. 25 MHz is the default-speed maximum (CSD TRAN_SPEED 32h, 5.3.2). Valid
  // 1 .. 4 294 967 295 Hz; 0 makes any non-empty transfer take UINT64_MAX ns (never ends).
  uint32_t spi_clock_hz = 25000000;

  // -- Bytes per command --------------------------------------------------------------
  // Host convention around each chip-select transaction: one 0xFF byte after CS falls
  // (waiting for the card to be ready) and one after CS rises (so the card releases DO).
  // The specification only requires NCS, NEC >= 0 (7.5.4).
  uint32_t select_bytes = 2;
  uint32_t command_bytes = 6;  // 7.3.1.1
  // Bytes between a command and its response, NCR: at most 8 (7.5.4). The maximum is
  // taken: it costs 2.24 us per command at 25 MHz, small against the card's own times.
  uint32_t ncr_bytes = 8;
  uint32_t r1_bytes = 1;  // 7.3.2.1 (CMD17/18/24/25, CMD12's R1b without its busy)
  uint32_t r2_bytes = 2;  // 7.3.2.3 (CMD13)
  // Ending a multiple-block read (CMD12, R1b): one byte of the interrupted block that
  // drivers discard after the command, and one byte of R1b busy polled.
  uint32_t stop_read_extra_bytes = 2;
  // Ending a multiple-block write: the Stop Tran token (7.3.3.2) and NBR <= 1 byte (7.5.4).
  uint32_t stop_tran_bytes = 2;
  // 1: a CMD13 SEND_STATUS after every write request, as 7.2.4 recommends; 0: none.
  uint32_t status_after_write = 1;
  // sync(): SPI mode has no flush command (the card cache of 4.17 is off unless the host
  // enables it); a driver's sync waits for the card to be ready, one polled byte, because
  // the busy time itself is already charged to the writes.
  uint32_t sync_bytes = 1;

  // -- Bytes per data block -----------------------------------------------------------
  uint32_t data_token_bytes = 1;     // start block token (7.3.3.2)
  uint32_t crc_bytes = 2;            // CRC16 after the 512 bytes (7.3.3.2, sent even if off)
  uint32_t nwr_bytes = 1;            // before each written block, NWR >= 1 (7.5.4)
  uint32_t data_response_bytes = 1;  // after each written block (7.3.3.1)

  // -- The card's own time, nanoseconds -----------------------------------------------
  // Read access before the first block of a request (NAC). Spec: a 100 ms timeout only
  // (4.6.2.1). Typical: A1 cards read >= 1500 random 4 KiB units per second (4.16.1.1),
  // <= 667 us each including the transfer; 500 us is left for the access.
  uint32_t read_access_ns = 500000;
  // Access before each further block of a multiple-block read (NAC between blocks; 4.6.2.1
  // gives the same timeout). Cards stream consecutive blocks from a page buffer; an
  // estimate of 10 us (a 10 MB/s read rate, Table 4-62's class-10 Pr, allows 51.2 us per
  // block all-in).
  uint32_t read_next_block_ns = 10000;
  // Programming busy once per write request: after the single block of a CMD24 or the
  // Stop Tran token of a CMD25. Spec: at most 250 ms (4.6.2.2). Typical: of order 1 ms
  // (A1's 500 random 4 KiB writes per second allow 2 ms per request).
  uint32_t write_request_busy_ns = 1000000;
  // Busy after each written block's data response (the block gap of 4.6.2.2, 250 ms max).
  // Typical: 50 us (10 MB/s sustained writing, A1 / Speed Class 10, is 51.2 us per block).
  uint32_t write_block_busy_ns = 50000;
  // Extra busy per sync(); 0 with the cache off (a cache flush may take up to 1 s, 4.17).
  uint32_t sync_busy_ns = 0;
};

namespace card_model_detail {

inline constexpr uint64_t kSaturated = ~uint64_t{0};

constexpr uint64_t add(uint64_t a, uint64_t b) {
  uint64_t r = 0;
  return __builtin_add_overflow(a, b, &r) ? kSaturated : r;
}

constexpr uint64_t mul(uint64_t a, uint64_t b) {
  uint64_t r = 0;
  return __builtin_mul_overflow(a, b, &r) ? kSaturated : r;
}

}  // namespace card_model_detail

// Nanoseconds to clock `bytes` bytes over SPI at `clock_hz`: bytes * 8e9 / clock_hz,
// rounded to the nearest nanosecond (halves up), exact for every input (no intermediate
// overflow); saturates at UINT64_MAX, which is also the result for clock_hz = 0.
// At 25 MHz: 320 ns per byte.
constexpr uint64_t spi_bytes_ns(uint64_t bytes, uint32_t clock_hz) {
  using card_model_detail::add;
  using card_model_detail::kSaturated;
  using card_model_detail::mul;
  if (clock_hz == 0) return bytes == 0 ? 0 : kSaturated;
  constexpr uint64_t kBitNsPerHz = 8000000000u;  // 8 bits * 1e9 ns/s
  // With bytes = q * f + r (r < f < 2^32): bytes * 8e9 / f = q * 8e9 + r * 8e9 / f. r * 8e9
  // can pass 2^64, so split once more: r * 8 = q2 * f + r2 (q2 < 8, r2 < f), and
  // r * 8e9 / f = q2 * 1e9 + r2 * 1e9 / f with r2 * 1e9 < 2^62. Only the last term is
  // rounded, so the result is bytes * 8e9 / f rounded to nearest, for every input.
  const uint64_t q = bytes / clock_hz;
  const uint64_t r_bits = (bytes % clock_hz) * 8u;  // < 2^35
  const uint64_t q2 = r_bits / clock_hz;            // < 8
  const uint64_t r2 = r_bits % clock_hz;            // < 2^32
  const uint64_t fraction = (r2 * 1000000000u + clock_hz / 2) / clock_hz;
  return add(add(mul(q, kBitNsPerHz), q2 * 1000000000u), fraction);
}

// Bytes the counted traffic puts on the SPI bus (formula above). Saturates at UINT64_MAX.
constexpr uint64_t card_bus_bytes(const CardCounters& c, const SdSpiTiming& t) {
  using card_model_detail::add;
  using card_model_detail::mul;
  const uint64_t command = uint64_t{t.select_bytes} + t.command_bytes + t.ncr_bytes + t.r1_bytes;
  const uint64_t stop_read =
      uint64_t{t.command_bytes} + t.ncr_bytes + t.r1_bytes + t.stop_read_extra_bytes;
  const uint64_t status = t.status_after_write == 0 ? 0
                                                    : uint64_t{t.select_bytes} + t.command_bytes +
                                                          t.ncr_bytes + t.r2_bytes;
  const uint64_t block_read = uint64_t{t.data_token_bytes} + kBlockSize + t.crc_bytes;
  const uint64_t block_written =
      uint64_t{t.nwr_bytes} + t.data_token_bytes + kBlockSize + t.crc_bytes + t.data_response_bytes;
  uint64_t bytes = mul(c.read_requests, command);
  bytes = add(bytes, mul(c.multi_read_requests, stop_read));
  bytes = add(bytes, mul(c.blocks_read, block_read));
  bytes = add(bytes, mul(c.write_requests, add(command, status)));
  bytes = add(bytes, mul(c.multi_write_requests, t.stop_tran_bytes));
  bytes = add(bytes, mul(c.blocks_written, block_written));
  bytes = add(bytes, mul(c.sync_requests, t.sync_bytes));
  return bytes;
}

// Nanoseconds the card itself takes for the counted traffic: read access and programming
// busy (formula above). Counters with fewer blocks read than read requests (not produced
// by CountingBlockDevice) charge no between-block access. Saturates at UINT64_MAX.
constexpr uint64_t card_wait_ns(const CardCounters& c, const SdSpiTiming& t) {
  using card_model_detail::add;
  using card_model_detail::mul;
  const uint64_t further_blocks =
      c.blocks_read > c.read_requests ? c.blocks_read - c.read_requests : 0;
  uint64_t ns = mul(c.read_requests, t.read_access_ns);
  ns = add(ns, mul(further_blocks, t.read_next_block_ns));
  ns = add(ns, mul(c.write_requests, t.write_request_busy_ns));
  ns = add(ns, mul(c.blocks_written, t.write_block_busy_ns));
  ns = add(ns, mul(c.sync_requests, t.sync_busy_ns));
  return ns;
}

// Modelled card time of the counted traffic in nanoseconds: bus time of card_bus_bytes()
// (rounded once, to the nearest ns) plus card_wait_ns(). 0 for zero counters. Never
// decreases when a counter grows, provided read_next_block_ns <= read_access_ns (true for
// the defaults; otherwise one more read request over the same blocks could cost less).
// Saturates at UINT64_MAX (584 years). E.g. with the defaults one single-block read is
// 670 240 ns and one 100-block read 17 980 880 ns.
constexpr uint64_t card_time_ns(const CardCounters& c, const SdSpiTiming& t = SdSpiTiming{}) {
  return card_model_detail::add(spi_bytes_ns(card_bus_bytes(c, t), t.spi_clock_hz),
                                card_wait_ns(c, t));
}

// SD commands the counted traffic sends: one per read or write request (CMD17/18/24/25),
// one CMD12 per multiple-block read, one CMD13 per write request when status_after_write
// is set. sync() sends none. Saturates at UINT64_MAX.
constexpr uint64_t card_commands(const CardCounters& c, const SdSpiTiming& t = SdSpiTiming{}) {
  using card_model_detail::add;
  uint64_t n = add(c.read_requests, c.multi_read_requests);
  n = add(n, c.write_requests);
  if (t.status_after_write != 0) n = add(n, c.write_requests);
  return n;
}

}  // namespace seqslam::hal
