// The host's difference kernel: sums of absolute differences of many query images against a
// library, with the best SIMD instruction set of the CPU chosen at run time (Highway's dynamic
// dispatch: AVX-512, AVX2, SSE4, SSSE3, or Highway's portable 128-bit emulation, which GCC
// compiles to SSE2 on any x86-64). The sums are exact integers, so every target gives the same
// values as the core's seqslam::sad_many, bit for bit (tests/host/tools/sad_simd_test.cpp).
//
// Host only: the board runs the core's kernel (src/difference.cpp). The evaluation
// (evaluation.cpp) uses this one for the max_shift = 0 difference matrix.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace seqslam::tools {

// out[r * out_stride + j] = SAD(query r, library image j) for r < rows, j < count. Queries and
// library images are `pixels` bytes each, stored back to back. Any pixel count (a multiple of
// the vector width is fastest). Single-threaded; callers split rows over threads.
void sad_rows(const uint8_t* queries, uint32_t rows, const uint8_t* library, uint32_t count,
              uint32_t pixels, uint32_t* out, size_t out_stride);

// Name of the instruction set sad_rows runs on this CPU ("AVX3" is AVX-512, "EMU128" is the
// portable fallback).
const char* sad_target_name();

// For tests and benchmarks: every target compiled in and supported by this CPU (Highway's
// target bits), and a way to force one (0 restores the automatic choice).
std::vector<int64_t> sad_available_targets();
void sad_force_target(int64_t target);
const char* sad_target_name(int64_t target);

}  // namespace seqslam::tools
