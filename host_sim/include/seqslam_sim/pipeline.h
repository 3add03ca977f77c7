// The FPGA pixel pipeline in software, bit-exact to its definition (hal/pixel_buffer.h):
// every camera pixel (x, y) goes to superpixel (floor(A (x, y)) + b) when that lies inside
// xmax x ymax, and each superpixel is the mean of the pixels that landed on it, rounded to
// nearest (ties up). A superpixel that no camera pixel reaches reads 0 here (the hardware
// would keep whatever the buffer held); check_mapping() does not rule that out, so
// covered_superpixels() tells.
#pragma once

#include <cstdint>
#include <vector>

#include "seqslam/hal/pixel_buffer.h"

namespace seqslam::sim {

struct PipelineOutput {
  std::vector<uint8_t> pixels;  // xmax * ymax, row-major
  uint32_t covered = 0;         // superpixels that received at least one camera pixel
};

// `frame` is width x height 8-bit grey. The mapping must pass hal::check_mapping.
PipelineOutput apply_pipeline(const uint8_t* frame, int width, int height,
                              const hal::PipelineMapping& mapping);

}  // namespace seqslam::sim
