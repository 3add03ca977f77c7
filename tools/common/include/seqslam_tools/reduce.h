// Downsampling host images exactly as the robot's FPGA pixel pipeline does.
//
// reduce_to() is a thin owner of buffers around the core's seqslam::area_reduce (see
// include/seqslam/pixel_pipeline.h): every source pixel is averaged, with weight 1, into the
// superpixel (floor(x * w / W), floor(y * h / H)), rounding to nearest, ties up. Only
// reduction is supported (no upscaling), and the target must fit the core's kMaxPixels.
#pragma once

#include "seqslam/image.h"
#include "seqslam_tools/image_io.h"
#include "seqslam_tools/outcome.h"

namespace seqslam::tools {

using ReducedImage = Outcome<GrayImage>;

// Checks a requested target size without an image: both sides positive and width * height
// within the core's kMaxPixels (seqslam::check_image_size). Errors read like reduce_to's,
// e.g. "cannot reduce to 64x64: OUT_OF_RANGE: the target has 4096 pixels, ...".
Outcome<seqslam::ImageSize> check_reduce_target(int width, int height);

// Reduces `src` to width x height with seqslam::area_reduce. Errors carry the core's status
// name and a sentence, e.g.
//   "cannot reduce 160x120 to 200x100: INVALID_ARGUMENT: the pixel pipeline only reduces; ..."
// An equal size returns a copy of `src`.
ReducedImage reduce_to(const GrayImage& src, int width, int height);

}  // namespace seqslam::tools
