#!/usr/bin/env bash
# Run a bare-metal RV32 ELF on QEMU's "virt" machine and exit with the program's status.
#
#   qemu-run.sh prog.elf [args...]     (arguments after the ELF are ignored: the board has
#                                       no command line)
#
# The board's exit device (SiFive test finisher) turns seqslam::board::exit(code) into
# QEMU's exit status; a trap exits with 3. -icount shift=0 makes minstret and the whole run
# deterministic (one instruction per virtual nanosecond).
#
# Environment:
#   SEQSLAM_QEMU           QEMU binary (default qemu-system-riscv32)
#   SEQSLAM_QEMU_TIMEOUT   wall-clock limit in seconds (default 600); on expiry prints a
#                          message and exits 124
# This script is CMAKE_CROSSCOMPILING_EMULATOR for the target build, so ctest runs target
# test executables through it.
set -u

if [ $# -lt 1 ]; then
  echo "usage: $(basename "$0") prog.elf [args ignored]" >&2
  exit 2
fi
elf=$1

qemu=${SEQSLAM_QEMU:-qemu-system-riscv32}
timeout_s=${SEQSLAM_QEMU_TIMEOUT:-600}

if ! command -v "$qemu" >/dev/null 2>&1; then
  echo "qemu-run.sh: '$qemu' not found. Install it (Debian: apt-get install qemu-system-misc)" \
       "or point SEQSLAM_QEMU at a qemu-system-riscv32 binary." >&2
  exit 127
fi
if ! command -v timeout >/dev/null 2>&1; then
  echo "qemu-run.sh: 'timeout' (coreutils) not found" >&2
  exit 127
fi
if [ ! -f "$elf" ]; then
  echo "qemu-run.sh: no such file: $elf" >&2
  exit 2
fi
case $timeout_s in
  ''|*[!0-9]*) echo "qemu-run.sh: SEQSLAM_QEMU_TIMEOUT must be whole seconds, got '$timeout_s'" >&2
               exit 2 ;;
esac

# stdin from /dev/null: the programs read nothing, and QEMU must not grab a terminal (it
# would switch it to raw mode, and in the background it would be stopped by SIGTTIN).
start=$SECONDS
timeout --kill-after=10 "$timeout_s" \
  "$qemu" -M virt -smp 1 -m 128M -bios none \
          -nographic -monitor none -serial stdio \
          -icount shift=0 \
          -kernel "$elf" </dev/null
status=$?

# 124/137 are also possible program statuses; only a run that lasted the limit timed out.
if { [ $status -eq 124 ] || [ $status -eq 137 ]; } && [ $((SECONDS - start)) -ge "$timeout_s" ]; then
  echo "" >&2
  echo "qemu-run.sh: TIMEOUT: $elf did not finish within ${timeout_s} s" \
       "(SEQSLAM_QEMU_TIMEOUT); killed QEMU" >&2
  exit 124
fi
exit $status
