// QEMU "virt" board support: UART console, test-finisher exit, counters, memory report and
// the C++ half of the trap handler (crt0.S has the vector).
#include "seqslam/board/board.h"

// Linker-script symbols (qemu_virt_sections.ld). Only their addresses mean anything.
extern "C" {
extern const char __ram_origin[];
extern const char __ram_length[];
extern const char __extmem_origin[];
extern const char __extmem_length[];
extern const char __text_start[];
extern const char __text_end[];
extern const char __rodata_start[];
extern const char __rodata_end[];
extern const char __data_start[];
extern const char __data_end[];
extern const char __bss_start[];
extern const char __bss_end[];
extern const char __stack_bottom[];
extern const char __stack_top[];
extern const char __extdata_start[];
extern const char __extmem_end[];

// Called from crt0.S.
[[noreturn]] void seqslam_board_exit(int code);
[[noreturn]] void seqslam_board_trap(uint32_t mcause, uint32_t mepc, uint32_t mtval);
}

namespace seqslam::board {
namespace {

// NS16550A on the virt machine.
constexpr uintptr_t kUartBase = 0x10000000u;
constexpr uintptr_t kUartThr = 0;  // transmit holding register
constexpr uintptr_t kUartLsr = 5;  // line status register
constexpr uint8_t kUartLsrThre = 0x20;

// SiFive test finisher.
constexpr uintptr_t kFinisherBase = 0x100000u;
constexpr uint32_t kFinisherPass = 0x5555u;
constexpr uint32_t kFinisherFail = 0x3333u;

volatile uint8_t* uart_reg(uintptr_t offset) {
  return reinterpret_cast<volatile uint8_t*>(kUartBase + offset);
}

void uart_put(char c) {
  while ((*uart_reg(kUartLsr) & kUartLsrThre) == 0) {
  }
  *uart_reg(kUartThr) = static_cast<uint8_t>(c);
}

uint32_t addr(const char* symbol) {
  return reinterpret_cast<uintptr_t>(symbol);
}

uint32_t span(const char* begin, const char* end) {
  return addr(end) - addr(begin);
}

const char* trap_cause_name(uint32_t mcause) {
  if ((mcause & 0x80000000u) != 0) {
    return "interrupt";
  }
  switch (mcause) {
    case 0:
      return "instruction address misaligned";
    case 1:
      return "instruction access fault";
    case 2:
      return "illegal instruction";
    case 3:
      return "breakpoint: __builtin_trap or SEQSLAM_ASSERT";
    case 4:
      return "load address misaligned";
    case 5:
      return "load access fault";
    case 6:
      return "store address misaligned";
    case 7:
      return "store access fault (stack overflow into the guard?)";
    case 11:
      return "environment call from M-mode";
    default:
      return "unknown";
  }
}

}  // namespace

void console_write(const char* data, size_t size) {
  for (size_t i = 0; i < size; ++i) {
    uart_put(data[i]);
  }
}

void console_print(const char* text) {
  if (text == nullptr) {
    text = "(null)";
  }
  for (; *text != '\0'; ++text) {
    uart_put(*text);
  }
}

// Digits are produced with one 64-bit division per digit only while the value does not
// fit 32 bits; the code is kept small (it is in every firmware image), not fast.
void console_print_u64(uint64_t v) {
  char buf[20];  // 18446744073709551615 has 20 digits
  size_t n = 0;
  while (v > 0xffffffffu) {
    const uint64_t q = v / 10u;  // libgcc __udivdi3
    buf[n++] = static_cast<char>('0' + static_cast<uint32_t>(v - q * 10u));
    v = q;
  }
  uint32_t low = static_cast<uint32_t>(v);
  do {
    buf[n++] = static_cast<char>('0' + low % 10u);
    low /= 10u;
  } while (low != 0);
  while (n > 0) {
    uart_put(buf[--n]);
  }
}

void console_print_i64(int64_t v) {
  // Two's complement negation in unsigned arithmetic also handles INT64_MIN.
  const uint64_t magnitude = v < 0 ? 0u - static_cast<uint64_t>(v) : static_cast<uint64_t>(v);
  if (v < 0) {
    uart_put('-');
  }
  console_print_u64(magnitude);
}

void console_print_hex32(uint32_t v) {
  static const char kDigits[] = "0123456789abcdef";
  uart_put('0');
  uart_put('x');
#pragma GCC unroll 1
  for (int shift = 28; shift >= 0; shift -= 4) {
    uart_put(kDigits[(v >> shift) & 0xFu]);
  }
}

void exit(int code) {
  uint32_t value = kFinisherPass;
  if (code != 0) {
    const uint32_t status = (code > 0 && code <= 255) ? static_cast<uint32_t>(code) : 255u;
    value = (status << 16) | kFinisherFail;
  }
  *reinterpret_cast<volatile uint32_t*>(kFinisherBase) = value;
  for (;;) {
    __asm__ volatile("wfi");
  }
}

uint64_t instructions_retired() {
  uint32_t hi;
  uint32_t lo;
  uint32_t hi_again;
  do {
    __asm__ volatile("csrr %0, minstreth" : "=r"(hi));
    __asm__ volatile("csrr %0, minstret" : "=r"(lo));
    __asm__ volatile("csrr %0, minstreth" : "=r"(hi_again));
  } while (hi != hi_again);
  return (static_cast<uint64_t>(hi) << 32) | lo;
}

// The region, i.e. __stack_size rounded up to the 16-byte alignment of the stack pointer.
uint32_t stack_size_bytes() {
  return span(__stack_bottom, __stack_top);
}

uint32_t stack_high_water_bytes() {
  const uint32_t top = addr(__stack_top);
  // Via integers: the symbols are declared as char arrays but are 32-byte aligned.
  const volatile uint32_t* word = reinterpret_cast<const volatile uint32_t*>(addr(__stack_bottom));
  const volatile uint32_t* const end = reinterpret_cast<const volatile uint32_t*>(top);
  while (word < end && *word == kStackPaint) {
    ++word;
  }
  return top - reinterpret_cast<uintptr_t>(word);
}

MemoryUsage memory_usage() {
  MemoryUsage m{};
  m.text_bytes = span(__text_start, __text_end);
  m.rodata_bytes = span(__rodata_start, __rodata_end);
  m.data_bytes = span(__data_start, __data_end);
  m.bss_bytes = span(__bss_start, __bss_end);
  m.stack_bytes = stack_size_bytes();
  m.ram_used_bytes = span(__ram_origin, __stack_top);
  m.ram_capacity_bytes = addr(__ram_length);
  m.extmem_used_bytes = span(__extdata_start, __extmem_end);
  m.extmem_capacity_bytes = addr(__extmem_length);
  return m;
}

}  // namespace seqslam::board

void seqslam_board_exit(int code) {
  seqslam::board::exit(code);
}

void seqslam_board_trap(uint32_t mcause, uint32_t mepc, uint32_t mtval) {
  using namespace seqslam::board;  // NOLINT(google-build-using-namespace)
  console_print("\nTRAP mcause=");
  console_print_hex32(mcause);
  console_print(" mepc=");
  console_print_hex32(mepc);
  console_print(" mtval=");
  console_print_hex32(mtval);
  console_print(" (");
  console_print(trap_cause_name(mcause));
  console_print(")\n");
  seqslam::board::exit(kTrapExitCode);
}
