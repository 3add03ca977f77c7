#!/usr/bin/env bash
# Installs the Debian packages the build needs, if any is missing. Idempotent and quiet when
# everything is present. Needs root (or sudo) only when something must be installed.
set -euo pipefail
packages=(
  cmake make g++            # host build
  libgtest-dev              # GoogleTest (host tests)
  libstb-dev                # stb_image / stb_image_write (host image I/O: JPEG, BMP, writing)
  libpng-dev                # libpng: PNG reading with chunk CRCs and Adler-32 checked
  libjpeg-dev               # libjpeg(-turbo): JPEGs checked for corrupt data before decoding
  libcli11-dev              # command-line parsing of the seqslam tool
  libhwy-dev                # Highway: run-time dispatched SIMD (the evaluation's SAD kernel)
  nlohmann-json3-dev        # nlohmann/json: the figures JSON of seqslam slam (host tools only)
  libbenchmark-dev          # Google Benchmark: host micro-benchmarks (make bench-eval)
  pkg-config
  clang libclang-rt-14-dev  # libFuzzer targets (preset fuzz)
  gcc-riscv64-unknown-elf   # RV32IMC cross compiler (multilib) and binutils
  qemu-system-misc          # qemu-system-riscv32: runs target tests and benchmarks
  chromium                  # headless browser: the HTML report's browser test (tests/host/report)
)
missing=()
for p in "${packages[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
[ ${#missing[@]} -eq 0 ] && exit 0

echo "install-deps: installing ${missing[*]}"
if [ "$(id -u)" -eq 0 ]; then
  sudo=()
elif command -v sudo >/dev/null 2>&1; then
  sudo=(sudo)
else
  echo "install-deps: not root and no sudo; run: apt-get install -y ${missing[*]}" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
"${sudo[@]}" apt-get update -q
"${sudo[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
