// Board smoke test, linked like firmware (firmware.ld): console, counters, stack paint,
// memory report, external memory. Prints the numbers it checks; exits 0 only if they are
// sane. Deliberately free of soft-float (symbol_check_board_smoke).
#include "seqslam/board/board.h"

namespace {

namespace board = ::seqslam::board;

int g_failures = 0;

void check(bool ok, const char* what) {
  if (!ok) {
    board::console_print("board_smoke: CHECK FAILED: ");
    board::console_print(what);
    board::console_print("\n");
    ++g_failures;
  }
}

void print_line(const char* label, uint64_t value) {
  board::console_print(label);
  board::console_print_u64(value);
  board::console_print("\n");
}

SEQSLAM_BOARD_EXTMEM uint32_t g_external[1024];
SEQSLAM_BOARD_EXTDATA uint32_t g_external_init[4] = {1, 2, 3, 4};

// Uses about `depth` * 64 bytes of stack.
__attribute__((noinline)) uint32_t burn_stack(uint32_t depth) {
  volatile uint32_t frame[16];
  frame[0] = depth;
  frame[15] = depth;
  return depth == 0 ? 0 : burn_stack(depth - 1) + frame[0] + frame[15];
}

}  // namespace

int main() {
  board::console_print("board_smoke: hello from ");
  board::console_print_hex32(0x80000000u);
  board::console_print("\n");

  // Instruction counter: a fixed loop retires a fixed number of instructions.
  const uint64_t t0 = board::instructions_retired();
  volatile uint32_t sink = 0;
  for (uint32_t i = 0; i < 1000; ++i) {
    sink = sink + i;
  }
  const uint64_t t1 = board::instructions_retired();
  const uint64_t empty0 = board::instructions_retired();
  const uint64_t empty1 = board::instructions_retired();
  print_line("board_smoke: instructions for a 1000-iteration loop: ", t1 - t0);
  print_line("board_smoke: instructions between two counter reads: ", empty1 - empty0);
  check(t1 - t0 >= 3000 && t1 - t0 < 20000, "loop instruction count");  // -O2 ... -O0

  // Stack high water grows when the stack is used.
  const uint32_t before = board::stack_high_water_bytes();
  check(burn_stack(40) > 0, "burn_stack");
  const uint32_t after = board::stack_high_water_bytes();
  print_line("board_smoke: stack high water before: ", before);
  print_line("board_smoke: stack high water after 40 frames: ", after);
  print_line("board_smoke: stack size: ", board::stack_size_bytes());
  check(after >= before + 40 * 64 && after < board::stack_size_bytes(), "stack high water");

  // External memory: zeroed, writable, initialised data loaded.
  bool zero = true;
  for (uint32_t i = 0; i < 1024; ++i) {
    zero = zero && g_external[i] == 0;
    g_external[i] = i;
  }
  check(zero, "extmem zeroed");
  check(g_external[1023] == 1023, "extmem writable");
  check(g_external_init[0] == 1 && g_external_init[3] == 4, "extdata loaded");

  const board::MemoryUsage m = board::memory_usage();
  print_line("board_smoke: text bytes: ", m.text_bytes);
  print_line("board_smoke: rodata bytes: ", m.rodata_bytes);
  print_line("board_smoke: data bytes: ", m.data_bytes);
  print_line("board_smoke: bss bytes: ", m.bss_bytes);
  print_line("board_smoke: stack bytes: ", m.stack_bytes);
  print_line("board_smoke: RAM used bytes: ", m.ram_used_bytes);
  print_line("board_smoke: RAM capacity bytes: ", m.ram_capacity_bytes);
  print_line("board_smoke: extmem used bytes: ", m.extmem_used_bytes);
  print_line("board_smoke: extmem capacity bytes: ", m.extmem_capacity_bytes);
  check(m.ram_capacity_bytes == 65456, "firmware RAM capacity");
  check(m.ram_used_bytes <= m.ram_capacity_bytes, "RAM used within capacity");
  check(m.ram_used_bytes >=
            m.text_bytes + m.rodata_bytes + m.data_bytes + m.bss_bytes + m.stack_bytes,
        "RAM used covers all sections");
  check(m.stack_bytes == board::stack_size_bytes(), "stack size");
  check(m.extmem_used_bytes >= sizeof g_external + sizeof g_external_init, "extmem used");
  check(m.extmem_capacity_bytes == 16u * 1024u * 1024u, "extmem capacity");

  // Console formatting.
  board::console_print("board_smoke: formats ");
  board::console_print_i64(INT64_MIN);
  board::console_print(" ");
  board::console_print_u64(UINT64_MAX);
  board::console_print(" ");
  board::console_print_i64(0);
  board::console_print(" ");
  board::console_print_hex32(0xdeadbeefu);
  board::console_print("\n");

  board::console_print(g_failures == 0 ? "board_smoke: PASS\n" : "board_smoke: FAIL\n");
  return g_failures == 0 ? 0 : 1;
}
