// The SD card of the benchmark images that time a step with the card in it (bench_card.h).
#include "bench_card.h"

#include "seqslam/hal/sd_card_model.h"

namespace seqslam::bench {

hal::CardCounters plus(const hal::CardCounters& a, const hal::CardCounters& b) {
  hal::CardCounters s;
  s.read_requests = a.read_requests + b.read_requests;
  s.multi_read_requests = a.multi_read_requests + b.multi_read_requests;
  s.blocks_read = a.blocks_read + b.blocks_read;
  s.write_requests = a.write_requests + b.write_requests;
  s.multi_write_requests = a.multi_write_requests + b.multi_write_requests;
  s.blocks_written = a.blocks_written + b.blocks_written;
  s.sync_requests = a.sync_requests + b.sync_requests;
  s.failed_requests = a.failed_requests + b.failed_requests;
  return s;
}

uint64_t card_step_ns(const CardCost& c) {
  return c.instructions * 1000000000u / kCpuHz + hal::card_time_ns(c.card);
}

namespace {

void print_ms(uint64_t ns) {
  print_fixed(ns, 1000000, 2);
}

}  // namespace

void print_step_stats(const char* name, const StepStats& s) {
  print("  ");
  print(name);
  print(": ");
  print_u(s.steps);
  print(" steps, instructions mean ");
  print_u(s.steps == 0 ? 0 : s.instructions_sum / s.steps);
  print(" max ");
  print_u(s.instructions_max);
  print("; card bytes mean ");
  print_u(s.steps == 0 ? 0 : s.card_bytes_sum / s.steps);
  print(" max ");
  print_u(s.card_bytes_max);
  print(", requests mean ");
  print_fixed(s.card_requests_sum, s.steps == 0 ? 1 : s.steps, 1);
  print(" max ");
  print_u(s.card_requests_max);
  print("; ms at 72 MHz + SPI card mean ");
  print_ms(s.steps == 0 ? 0 : s.ns_sum / s.steps);
  print(" max ");
  print_ms(s.ns_max);
  print(" (card ");
  print_ms(s.card_ns_max);
  print(")\n");
}

void print_step_stats_json(const char* name, const StepStats& s, bool last) {
  print("\"");
  print(name);
  print("\": {\"steps\": ");
  print_u(s.steps);
  print(", \"instructions_per_step\": ");
  print_u(s.steps == 0 ? 0 : s.instructions_sum / s.steps);
  print(", \"instructions_per_step_max\": ");
  print_u(s.instructions_max);
  print(", \"card_bytes_per_step\": ");
  print_u(s.steps == 0 ? 0 : s.card_bytes_sum / s.steps);
  print(", \"card_bytes_per_step_max\": ");
  print_u(s.card_bytes_max);
  print(", \"card_requests_per_step\": ");
  print_fixed(s.card_requests_sum, s.steps == 0 ? 1 : s.steps, 2);
  print(", \"card_requests_per_step_max\": ");
  print_u(s.card_requests_max);
  print(", \"step_ms_at_72mhz\": ");
  print_fixed(s.steps == 0 ? 0 : s.ns_sum / s.steps, 1000000, 3);
  print(", \"step_ms_at_72mhz_max\": ");
  print_fixed(s.ns_max, 1000000, 3);
  print(", \"card_ms_of_slowest_step\": ");
  print_fixed(s.card_ns_max, 1000000, 3);
  print(last ? "}" : "}, ");
}

}  // namespace seqslam::bench
