// The SD card of the benchmark images that time a step with the card in it
// (seqslam_bench_board: the board's localiser; seqslam_bench_mapping: the explorer): a RAM
// card in external memory (hal::FakeBlockDevice) under TimedCard and a CountingBlockDevice.
// A step's time on the board is its instructions at 72 MHz (one a cycle) plus the SD-on-SPI
// model's time for its card requests (hal/sd_card_model.h, defaults: 25 MHz;
// docs/card_model.md). docs/performance.md explains the figures.
#pragma once

#include <stdint.h>

#include "bench_report.h"
#include "seqslam/hal/counting_block_device.h"
#include "seqslam/hal/sd_card_model.h"

namespace seqslam::bench {

inline constexpr uint64_t kCpuHz = 72000000;

// The instructions spent inside the card driver (here the RAM card's copying) belong to the
// card's time, which the SD model prices as bus time (a driver shifting bytes over SPI waits
// for the bus: its work hides in the transfer), so they are taken out of the CPU figures.
class TimedCard final : public hal::BlockDevice {
 public:
  explicit TimedCard(hal::BlockDevice& device) : device_(device) {}
  uint64_t instructions() const { return instructions_; }

 private:
  uint32_t do_block_count() const override { return device_.block_count(); }
  Status do_read(uint32_t first, uint32_t count, uint8_t* out) override {
    const uint64_t t0 = now();
    const Status s = device_.read(first, count, out);
    instructions_ += now() - t0;
    return s;
  }
  Status do_write(uint32_t first, uint32_t count, const uint8_t* data) override {
    const uint64_t t0 = now();
    const Status s = device_.write(first, count, data);
    instructions_ += now() - t0;
    return s;
  }
  Status do_sync() override { return device_.sync(); }

  hal::BlockDevice& device_;
  uint64_t instructions_ = 0;
};

// What one measured stretch cost: instructions without the card driver's, and the card's
// requests.
struct CardCost {
  uint64_t instructions = 0;
  hal::CardCounters card{};
};

// The counts of two stretches together.
hal::CardCounters plus(const hal::CardCounters& a, const hal::CardCounters& b);
// A stretch's time on the board: instructions at 72 MHz + the card model's time.
uint64_t card_step_ns(const CardCost& c);

// Measures stretches: start(), the measured calls, then stop() adds their cost to *into.
// start() reads the instruction counter last and stop() first, so only the calls' own few
// instructions (return, argument set-up) fall between the two counts besides the measured.
class CardMeter {
 public:
  CardMeter(const hal::CountingBlockDevice& card, const TimedCard& timed)
      : card_(card), timed_(timed) {}
  void start() {
    card0_ = card_.counters();
    driver0_ = timed_.instructions();
    t0_ = now();
  }
  void stop(CardCost* into) {
    const uint64_t t = now() - t0_;
    into->instructions += t - (timed_.instructions() - driver0_);
    into->card = plus(into->card, card_.since(card0_));
  }

 private:
  const hal::CountingBlockDevice& card_;
  const TimedCard& timed_;
  hal::CardCounters card0_{};
  uint64_t driver0_ = 0;
  uint64_t t0_ = 0;
};

// Mean and largest cost of a set of steps.
struct StepStats {
  uint32_t steps = 0;
  uint64_t instructions_sum = 0;
  uint64_t instructions_max = 0;
  uint64_t card_bytes_sum = 0;  // blocks read and written x 512
  uint64_t card_bytes_max = 0;
  uint64_t card_requests_sum = 0;  // read, write and sync requests
  uint64_t card_requests_max = 0;
  uint64_t ns_sum = 0;  // instructions at 72 MHz + the card model
  uint64_t ns_max = 0;
  uint64_t card_ns_max = 0;  // the card's part of the slowest step
};

// One step of `instructions` (the card driver's taken out) and the card requests `c`.
// Inline: the board bench's step() inlined it when it was its own, and the harness's
// instructions between the counter reads depend on that (docs/performance.md, "Counts that
// move without a code change").
inline void add_step(StepStats& s, uint64_t instructions, const hal::CardCounters& c) {
  const uint64_t bytes = (static_cast<uint64_t>(c.blocks_read) + c.blocks_written) * 512u;
  const uint64_t requests =
      static_cast<uint64_t>(c.read_requests) + c.write_requests + c.sync_requests;
  const uint64_t card_ns = hal::card_time_ns(c);
  const uint64_t ns = instructions * 1000000000u / kCpuHz + card_ns;
  ++s.steps;
  s.instructions_sum += instructions;
  s.card_bytes_sum += bytes;
  s.card_requests_sum += requests;
  s.ns_sum += ns;
  if (instructions > s.instructions_max) s.instructions_max = instructions;
  if (bytes > s.card_bytes_max) s.card_bytes_max = bytes;
  if (requests > s.card_requests_max) s.card_requests_max = requests;
  if (ns > s.ns_max) {
    s.ns_max = ns;
    s.card_ns_max = card_ns;
  }
}
// "  name: N steps, instructions mean ... max ...; card bytes ...; ms at 72 MHz + SPI card ..."
void print_step_stats(const char* name, const StepStats& s);
// "\"name\": {\"steps\": N, \"instructions_per_step\": ...}" and ", " unless `last`.
void print_step_stats_json(const char* name, const StepStats& s, bool last);

}  // namespace seqslam::bench
