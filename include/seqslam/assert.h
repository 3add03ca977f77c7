// Invariant checks. Bad *input* returns a Status; SEQSLAM_ASSERT is only for conditions that
// can be false when this library has a bug. It traps: on the host the process aborts via
// __builtin_trap (loud under the sanitizers and in gtest), on the target the core executes
// the trap instruction (ebreak on RISC-V), which the board's trap handler records.
#pragma once

#define SEQSLAM_ASSERT(cond) \
  do {                       \
    if (!(cond)) {           \
      __builtin_trap();      \
    }                        \
  } while (false)
