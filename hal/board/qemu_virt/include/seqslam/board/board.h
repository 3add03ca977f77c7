// Board support for QEMU's RISC-V "virt" machine (RV32, bare metal, M-mode): the console
// (NS16550A UART), the exit device (SiFive test finisher), the instruction counter and the
// memory report. This is what firmware images and target test binaries run on; the core
// library (include/seqslam) never includes it.
//
// Startup (crt0.S) zeroes .bss and .extmem, paints the stack for the high-water mark, runs
// static constructors and calls main(); main's return value goes to exit(). Any trap prints
//   TRAP mcause=0x........ mepc=0x........ mtval=0x........ (<cause>)
// and exits with status 3, so __builtin_trap() / SEQSLAM_ASSERT fail loudly under QEMU.
#pragma once

#include <stddef.h>
#include <stdint.h>

// Place a large zero-initialised buffer in external memory (not counted against the
// 65 456-byte RAM budget; zeroed by crt0, not stored in the ELF file). No initialiser.
#define SEQSLAM_BOARD_EXTMEM __attribute__((section(".extmem")))
// Place initialised data (e.g. benchmark inputs) in external memory; QEMU loads it from
// the ELF file. Keep const and non-const objects in different translation units or GCC
// reports a section type conflict.
#define SEQSLAM_BOARD_EXTDATA __attribute__((section(".extdata")))

// The program's entry point, called by crt0 with no arguments; its return value is the exit
// status. Declared here because with -ffreestanding main() is an ordinary function and
// -Wmissing-declarations wants a prior declaration. Freestanding also means there is no
// implicit "return 0" at the end of main.
int main();

namespace seqslam::board {

// Status reported by the trap handler.
inline constexpr int kTrapExitCode = 3;
// Value crt0 paints into the unused stack.
inline constexpr uint32_t kStackPaint = 0x5AA5F00Du;

// Console output (UART). No newline translation.
void console_write(const char* data, size_t size);
void console_print(const char* text);  // NUL-terminated; nullptr prints "(null)"
void console_print_u64(uint64_t v);    // decimal
void console_print_i64(int64_t v);     // decimal, '-' for negative values
void console_print_hex32(uint32_t v);  // "0x" and exactly 8 lower-case hex digits

// Ends the program: QEMU exits with status 0 for code 0, with `code` for 1..255, and with
// 255 for any other value (so a failure can never turn into success).
[[noreturn]] void exit(int code);

// Instructions retired since _start (minstreth:minstret; crt0 zeroes the counter because
// QEMU's initial value varies from run to run). Deterministic under -icount shift=0
// (scripts/qemu-run.sh): the same image gives the same counts on every run. Startup with
// the default 8 KiB stack takes about 8 200 instructions (mostly the stack paint). Two
// back-to-back reads differ by about 8.
uint64_t instructions_retired();

// Size of the stack region reserved by the linker script (__stack_size).
uint32_t stack_size_bytes();
// Deepest stack use since reset: distance from the top of the stack to the lowest word that
// no longer holds the paint. Scans the region (cost ~ 4 instructions per unused word).
uint32_t stack_high_water_bytes();

// Memory map of the running image, from linker symbols. All sizes in bytes.
struct MemoryUsage {
  uint32_t text_bytes;             // code
  uint32_t rodata_bytes;           // read-only data incl. constructor tables
  uint32_t data_bytes;             // initialised data (.data, .sdata)
  uint32_t bss_bytes;              // zero-initialised data (.sbss, .bss)
  uint32_t stack_bytes;            // reserved stack
  uint32_t ram_used_bytes;         // everything placed in RAM incl. the reserved stack,
                                   // its guard and alignment padding
  uint32_t ram_capacity_bytes;     // RAM region length (65 456 for firmware.ld)
  uint32_t extmem_used_bytes;      // SEQSLAM_BOARD_EXTDATA + SEQSLAM_BOARD_EXTMEM objects
  uint32_t extmem_capacity_bytes;  // EXTMEM region length
};
MemoryUsage memory_usage();

}  // namespace seqslam::board
