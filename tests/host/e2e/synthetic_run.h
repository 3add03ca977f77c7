// Synthetic robot runs written as full dream recordings, for end-to-end tests of the
// firmware application: a straight drive along a corridor of the synthetic world, sampled as
// the robot samples it - 10 ms snapshots of integer wheel ticks (0.3 m/s, counters wrapping),
// and an image whenever the core's odometry and 20 cm spatial trigger fire, rendered at the
// true position (one world column = 10 cm, the camera sees 32 columns).
#pragma once

#include <cstdint>

#include "seqslam/hal/block_device.h"
#include "seqslam/storage/dream.h"
#include "seqslam/storage/run_config.h"
#include "synthetic.h"

namespace seqslam::test {

using RunWorld = SyntheticWorld<2048, 16>;

struct RunOptions {
  uint32_t places = 100;  // stop after this many captures
  int32_t gain_q8 = 256;  // illumination change of the images
  int32_t offset = 0;
  int32_t noise = 3;
  uint64_t noise_seed = 1;
  uint32_t ticks_per_step = 23;        // wheel ticks per 10 ms (0.3 m/s)
  uint32_t start_count = 0xFFFFF000u;  // encoder counters wrap during the run
  uint32_t drop_every = 0;             // drop every Nth snapshot (0 = none): a lossy bus
};

// Writes the run to `device` as a full dream recording; returns the number of places written
// (options.places on success) or 0 on a storage error.
uint32_t write_synthetic_run(hal::BlockDevice& device, const RunWorld& world,
                             const RunOptions& options);

// The header the runs use (32x16 superpixels, default wheels, three infrared sensors).
storage::DreamHeader synthetic_run_header();

// The run configuration's defaults with the runs' mapping (32x16) and the given modes.
storage::RunConfig synthetic_run_config(uint8_t modes);

}  // namespace seqslam::test
