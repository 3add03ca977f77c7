// The FPGA pixel pipeline's downsampling model ("superpixels"), in software.
//
// On the head board the FPGA maps every camera pixel (x, y) to a superpixel and averages all
// camera pixels that land in it. For a plain reduction from W x H to w x h the mapping is
//   u = floor(x * w / W),  v = floor(y * h / H)
// and superpixel (u, v) is the mean of the camera pixels mapped to it, rounded to nearest
// (ties up). Every camera pixel contributes to exactly one superpixel, with weight 1, as in
// the hardware; there are no fractional weights. Host tools reduce recorded or public images
// with this same function so the PC sees what the robot sees.
#pragma once

#include <stdint.h>

#include "seqslam/image.h"
#include "seqslam/span.h"

namespace seqslam {

// Reduces `src` (any size up to 65535 x 65535) into `dst` (its size is the target size).
// `scratch` must hold at least 2 * dst.size.pixels() words (sums and counts).
// Returns:
//   kInvalidArgument - a null buffer, an empty source, or dst larger than src in either
//                      dimension (the pipeline only reduces);
//   kOutOfRange      - dst exceeds kMaxPixels or src exceeds 2^24 pixels;
//   kResourceExhausted - scratch too small.
// On failure dst is left untouched.
Status area_reduce(ImageView src, MutableImageView dst, Span<uint32_t> scratch);

}  // namespace seqslam
