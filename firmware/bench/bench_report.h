// What the two benchmark images (seqslam_bench: localisation; seqslam_bench_mapping: grid,
// pose graph, mapping step, closure alignment) share: console printing, the instruction
// counter and the report of the image's own RAM use (text and JSON).
//
// Each image prints human-readable lines, then a JSON summary between BEGIN_SUMMARY_JSON
// and END_SUMMARY_JSON that scripts/run-bench.sh writes to <out-dir>/summary.json.
#pragma once

#include <stdint.h>

#include "seqslam/board/board.h"

namespace seqslam::bench {

// Inline, so a measurement costs exactly the counter reads around the measured call (an
// out-of-line wrapper would add its own instructions to every figure).
inline uint64_t now() {
  return board::instructions_retired();
}

void print(const char* s);
void print_u(uint64_t v);
// v / d with `digits` decimals, from integers.
void print_fixed(uint64_t v, uint64_t d, int digits);

// The image's RAM use, read at the end of its run (so the stack high-water mark covers every
// measurement).
struct MemoryReport {
  board::MemoryUsage mem;
  uint32_t stack_high_water;
  uint32_t static_ram;  // text + rodata + data + bss
};
MemoryReport memory_report();
// "\nRAM (65456-byte region): code ... of 65456\nexternal memory used: N bytes"; the caller
// goes on with what the external memory holds and the newline.
void print_memory(const MemoryReport& r);
// `"memory": {...}` (the last member of the summary; no comma, no newline after it).
void print_memory_json(const MemoryReport& r, const char* external_memory_note);

// "BEGIN_SUMMARY_JSON\n{\n  \"config\": {" then the image's own configuration members.
void print_json_begin();
// The board's members of "config" (target, counter), closing it: "...}".
void print_json_config_end();
// "\n}\nEND_SUMMARY_JSON\n".
void print_json_end();

}  // namespace seqslam::bench
