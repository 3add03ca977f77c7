// Board benchmark firmware (seqslam_bench_board): the head board's localiser as it ships (the
// application's route search and heuristic matcher, their capacities from app.h) with the
// library and the query history on an SD card, for M = 100, 450, 1 000 and 5 000 places
// (bench_board.h). Its localisation state is in the 65 456-byte RAM as on the board; only the
// RAM card (the SD card's contents) is in external memory.
//
// Output: human-readable lines, then a JSON summary between BEGIN_SUMMARY_JSON and
// END_SUMMARY_JSON that scripts/run-bench.sh writes to build/bench/board/summary.json;
// `make bench` merges it into build/bench/summary.json as "board" (scripts/bench-summary.py).
#include "bench_board.h"
#include "bench_report.h"

namespace {

using seqslam::bench::print;
using seqslam::bench::print_u;

constexpr uint32_t kSizes[] = {100, 450, 1000, 5000};
constexpr int kRuns = sizeof kSizes / sizeof kSizes[0];
seqslam::bench::BoardFigures g_figures[kRuns];

}  // namespace

int main() {
  using namespace seqslam;
  print("seqslam benchmark, board image (seqslam_bench_board): the head board's localiser ");
  print("(route search, heuristic) with the application's defaults (RV32IMC under QEMU, ");
  print("-icount)\nlibrary, query history and results on an SD card on SPI at 25 MHz ");
  print("(docs/card_model.md; a RAM card in EXTERNAL memory); localiser RAM ");
  print_u(bench::board_localiser_ram_bytes());
  print(" bytes at every M; relocalisation works up to ");
  print_u(bench::board_capacity_places());
  print(" places\n\n");
  for (int i = 0; i < kRuns; ++i) {
    if (!bench::run_board(kSizes[i], &g_figures[i])) {
      print("board benchmark failed\n");
      return 1;
    }
    bench::print_board(g_figures[i]);
  }
  const bench::MemoryReport mem = bench::memory_report();
  bench::print_memory(mem);
  print(" (the card)\n");

  bench::print_json_begin();
  bench::print_json_config_end();
  print(",\n  \"board\": {\"cpu_hz\": 72000000, \"card\": \"SD on SPI at 25 MHz\", ");
  print("\"ram_bytes\": ");
  print_u(bench::board_localiser_ram_bytes());
  print(", \"board_capacity_places\": ");
  print_u(bench::board_capacity_places());
  print(",\n    \"steps\": [\n");
  for (int i = 0; i < kRuns; ++i)
    bench::print_board_json(g_figures[i], i == kRuns - 1);
  print("    ]},\n  ");
  bench::print_memory_json(mem, "the SD card's contents (a RAM card)");
  bench::print_json_end();
  return 0;
}
