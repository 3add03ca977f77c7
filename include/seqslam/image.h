// Grey-level images as caller-owned pixel buffers.
//
// Images are 8-bit luminance, row-major, with no padding between rows (stride == width),
// which is how the FPGA pixel pipeline stores them (index xmax * y + x).
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/limits.h"
#include "seqslam/status.h"

namespace seqslam {

struct ImageSize {
  uint16_t width = 0;
  uint16_t height = 0;

  constexpr uint32_t pixels() const { return static_cast<uint32_t>(width) * height; }
  friend constexpr bool operator==(ImageSize a, ImageSize b) {
    return a.width == b.width && a.height == b.height;
  }
  friend constexpr bool operator!=(ImageSize a, ImageSize b) { return !(a == b); }
};

// Checks a size the *core* is asked to process (preprocessing, differences, the library):
//   kInvalidArgument - width or height is zero;
//   kOutOfRange      - width * height exceeds kMaxPixels (the compile-time capacity).
Status check_image_size(ImageSize size);

struct ImageView {
  const uint8_t* pixels = nullptr;
  ImageSize size;

  constexpr uint8_t at(uint32_t x, uint32_t y) const { return pixels[y * size.width + x]; }
};

struct MutableImageView {
  uint8_t* pixels = nullptr;
  ImageSize size;

  constexpr operator ImageView() const { return ImageView{pixels, size}; }  // NOLINT
};

}  // namespace seqslam
