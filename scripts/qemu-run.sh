#!/usr/bin/env bash
# Run a bare-metal RV32 ELF on QEMU's "virt" machine and exit with the program's status.
#
#   qemu-run.sh [--disk FILE] prog.elf [args...]
#   qemu-run.sh prog.elf --disk FILE [args...]
#                                      (other arguments after the ELF are ignored: the board
#                                       has no command line)
#
# --disk FILE (or SEQSLAM_QEMU_DISK=FILE; --disk wins) attaches FILE as a raw virtio-blk
# disk, read-write: the firmware's writes land in the file (seqslam::board::
# VirtioBlockDevice, hal/board/qemu_virt). Its size should be a multiple of 512 bytes.
# The virtio-mmio transports are always switched to version 2 ("modern",
# -global virtio-mmio.force-legacy=false), which is what the driver speaks; without a disk
# the transports are empty and the driver's init() reports kUnavailable.
#
# The board's exit device (SiFive test finisher) turns seqslam::board::exit(code) into
# QEMU's exit status; a trap exits with 3. -icount shift=0 makes minstret and the whole run
# deterministic (one instruction per virtual nanosecond).
#
# Environment:
#   SEQSLAM_QEMU           QEMU binary (default qemu-system-riscv32)
#   SEQSLAM_QEMU_TIMEOUT   wall-clock limit in seconds (default 600); on expiry prints a
#                          message and exits 124
#   SEQSLAM_QEMU_DISK      disk-image file to attach (see --disk); empty or unset: no disk.
#                          A name that is not a regular file is an error (exit 2).
# This script is CMAKE_CROSSCOMPILING_EMULATOR for the target build, so ctest runs target
# test executables through it.
set -u

usage() {
  echo "usage: $(basename "$0") [--disk FILE] prog.elf [--disk FILE] [args ignored]" >&2
  exit 2
}

disk=${SEQSLAM_QEMU_DISK:-}
if [ $# -ge 1 ] && [ "$1" = "--disk" ]; then
  [ $# -ge 2 ] || usage
  disk=$2
  shift 2
fi
if [ $# -lt 1 ]; then
  usage
fi
elf=$1
if [ $# -ge 2 ] && [ "$2" = "--disk" ]; then
  [ $# -ge 3 ] || usage
  disk=$3
fi

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
disk_args=()
if [ -n "$disk" ]; then
  if [ ! -f "$disk" ]; then
    echo "qemu-run.sh: disk image is not a regular file: $disk" \
         "(SEQSLAM_QEMU_DISK / --disk)" >&2
    exit 2
  fi
  # QEMU option values escape a comma by doubling it.
  disk_args=(-drive "file=${disk//,/,,},if=none,format=raw,id=seqslam_disk"
             -device virtio-blk-device,drive=seqslam_disk)
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
          -global virtio-mmio.force-legacy=false "${disk_args[@]}" \
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
