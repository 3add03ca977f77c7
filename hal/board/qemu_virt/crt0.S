/* Startup code for the QEMU "virt" board, RV32, bare metal, M-mode.
 *
 * QEMU (-bios none) jumps here at 0x80000000 with every hart running this code; only hart 0
 * continues (the board is started with one hart anyway). Sequence:
 *   minstret = 0 -> gp, sp, mtvec -> PMP stack guard -> zero .sbss/.bss and .extmem
 *   -> paint the stack -> .preinit_array/.init_array constructors -> main(0, 0)
 *   -> seqslam_board_exit(main's result).
 * No C library: nothing else is initialised, there are no destructors and no atexit.
 */

#define STACK_PAINT 0x5AA5F00D  /* seqslam::board::kStackPaint */

/* Guard below the stack: a locked (so it binds M-mode too) NAPOT PMP entry without R/W/X
 * permission over __stack_guard .. +32 bytes. A stack overflow that writes there raises a
 * store access fault (mcause 7) instead of silently corrupting .bss. */
#define PMPCFG_L      0x80
#define PMPCFG_NAPOT  0x18

  .section .text.init, "ax", @progbits
  .global _start
  .type _start, @function
_start:
  /* Count instructions from here: QEMU's counter starts at a run-dependent value (the
   * icount clock's bias), so instructions_retired() would otherwise only be meaningful as
   * a difference. Low word, high word, low word again: a carry out of the low word between
   * the writes cannot leave the high word non-zero. */
  csrw  minstret, zero
  csrw  minstreth, zero
  csrw  minstret, zero
  .option push
  .option norelax
  la    gp, __global_pointer$
  .option pop
  csrr  t0, mhartid
  bnez  t0, .Lpark

  la    sp, __stack_top
  csrw  mscratch, zero
  la    t0, __seqslam_trap_vector
  csrw  mtvec, t0

  /* PMP guard: NAPOT encoding of a 32-byte range is (base >> 2) | 0b011; the linker
   * script aligns __stack_guard to 32 bytes. */
  la    t0, __stack_guard
  srli  t0, t0, 2
  ori   t0, t0, 0x3
  csrw  pmpaddr0, t0
  li    t0, (PMPCFG_L | PMPCFG_NAPOT)
  csrw  pmpcfg0, t0

  /* Zero-initialised data. Both ranges are 8-byte aligned by the linker script. */
  la    t0, __bss_start
  la    t1, __bss_end
1:
  bgeu  t0, t1, 2f
  sw    zero, 0(t0)
  addi  t0, t0, 4
  j     1b
2:
  la    t0, __extmem_start
  la    t1, __extmem_end
3:
  bgeu  t0, t1, 4f
  sw    zero, 0(t0)
  addi  t0, t0, 4
  j     3b
4:
  /* Paint the whole stack region up to the current sp (nothing is on the stack yet);
   * seqslam::board::stack_high_water_bytes() looks for the deepest overwritten word. */
  la    t0, __stack_bottom
  mv    t1, sp
  li    t2, STACK_PAINT
5:
  bgeu  t0, t1, 6f
  sw    t2, 0(t0)
  addi  t0, t0, 4
  j     5b
6:
  /* Static constructors (minitest registers its tests from them). The two arrays are
   * adjacent in the linker script, preinit first. */
  la    s0, __preinit_array_start
  la    s1, __init_array_end
7:
  bgeu  s0, s1, 8f
  lw    t0, 0(s0)
  jalr  t0
  addi  s0, s0, 4
  j     7b
8:
  li    a0, 0
  li    a1, 0
  call  main
  tail  seqslam_board_exit

.Lpark:
  wfi
  j     .Lpark
  .size _start, . - _start

/* Trap vector (direct mode). Nothing here returns: a trap in this firmware is always a bug
 * (ebreak from __builtin_trap / SEQSLAM_ASSERT, an illegal instruction, a bad address, a
 * stack overflow into the guard). It reloads gp and sp, because either may be the reason
 * for the trap, and reports via seqslam_board_trap(mcause, mepc, mtval), which exits with
 * status 3. A trap while reporting a trap exits immediately with status 3. The "already
 * reporting" flag lives in mscratch (0 at reset), not in RAM that a runaway stack or a
 * wild store may have overwritten. */
  .section .text.trap, "ax", @progbits
  .balign 4
  .global __seqslam_trap_vector
  .type __seqslam_trap_vector, @function
__seqslam_trap_vector:
  csrrwi t1, mscratch, 1
  bnez  t1, 1f
  .option push
  .option norelax
  la    gp, __global_pointer$
  .option pop
  la    sp, __stack_top
  csrr  a0, mcause
  csrr  a1, mepc
  csrr  a2, mtval
  call  seqslam_board_trap
1:
  li    t0, 0x100000
  li    t1, ((3 << 16) | 0x3333)
  sw    t1, 0(t0)
2:
  wfi
  j     2b
  .size __seqslam_trap_vector, . - __seqslam_trap_vector
