// A procedural corridor for firmware images that must run without recorded data (the
// minimal firmware's self-check and the benchmark): the grey level seen at a world column
// and image row, with an illumination change. Deterministic integer arithmetic only.
#pragma once

#include <stdint.h>

#include "seqslam/image.h"

namespace seqslam::firmware {

inline uint32_t hash32(uint32_t x) {
  x ^= x >> 16;
  x *= 0x7FEB352Du;
  x ^= x >> 15;
  x *= 0x846CA68Bu;
  x ^= x >> 16;
  return x;
}

// Renders the 2-D view of a camera whose left edge is at world column `column`:
// objects a few columns wide with their own vertical extent, plus per-pixel noise.
// gain_q8 / offset model the light; noise_seed varies the sensor noise between runs.
inline void render_scene(uint32_t column, ImageSize size, int32_t gain_q8, int32_t offset,
                         uint32_t noise_seed, uint8_t* out) {
  for (uint32_t x = 0; x < size.width; ++x) {
    const uint32_t object = (column + x) / 3;  // objects are 3 columns wide
    const uint32_t h = hash32(object);
    const int32_t base = 40 + static_cast<int32_t>(h % 170);
    const uint32_t top = (h >> 8) % size.height;
    const uint32_t bottom = top + 1 + (h >> 16) % (size.height - top);
    const int32_t shade = static_cast<int32_t>((h >> 24) % 100) - 50;
    for (uint32_t y = 0; y < size.height; ++y) {
      int32_t v = base + (y >= top && y < bottom ? shade : 0);
      v = v * gain_q8 / 256 + offset;
      v += static_cast<int32_t>(hash32(noise_seed ^ (column + x) * 131u ^ y * 7919u) % 9) - 4;
      out[y * size.width + x] = static_cast<uint8_t>(v < 0 ? 0 : (v > 255 ? 255 : v));
    }
  }
}

}  // namespace seqslam::firmware
