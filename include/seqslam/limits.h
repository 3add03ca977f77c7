// Compile-time capacities of the core. Every buffer the core uses is sized from these, and
// every budget derived from them is static_assert-ed where the buffer is declared.
#pragma once

#include <stdint.h>

// The largest image (in pixels) the core accepts. The target default is the FPGA pixel
// buffer (xmax * ymax <= 512); host builds raise it so 64x32 images work. Set with the CMake
// cache variable SEQSLAM_MAX_PIXELS.
#ifndef SEQSLAM_MAX_PIXELS
#define SEQSLAM_MAX_PIXELS 512
#endif

namespace seqslam {

inline constexpr uint32_t kMaxPixels = SEQSLAM_MAX_PIXELS;
// Longest sequence (S) the matchers accept.
inline constexpr uint16_t kMaxSeqLen = 100;
// Largest local-normalisation window (W). The online cost offset sqrt(W) must stay below 16
// so a normalised difference fits the UQ5.11 storage format (see normalise.h).
inline constexpr uint16_t kMaxWindow = 255;
// Largest image side: the pixel pipeline addresses at most 16-bit coordinates.
inline constexpr uint16_t kMaxImageSide = 4096;

static_assert(kMaxPixels >= 16, "SEQSLAM_MAX_PIXELS must allow at least a 4x4 image");
// Differences are sums of absolute differences (SAD <= 255 * kMaxPixels < 2^22). The local
// normaliser forms n * sum(SAD^2) over n <= kMaxWindow + 1 values in uint64:
// 2^8 * 2^8 * 2^44 = 2^60, which leaves headroom.
static_assert(kMaxPixels <= (1u << 14), "SEQSLAM_MAX_PIXELS too large for the normaliser sums");

}  // namespace seqslam
