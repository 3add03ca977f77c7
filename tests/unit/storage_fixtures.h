// Shared fixtures for the storage tests: a fake SD card in static memory and deterministic
// dream content.
#pragma once

#include <stdint.h>

#include "seqslam/hal/fake_block_device.h"
#include "seqslam/storage/dream.h"

namespace seqslam::test {

template <uint32_t kBlocks>
struct FakeCard {
  uint8_t bytes[kBlocks * hal::kBlockSize];
  hal::FakeBlockDevice device{Span<uint8_t>(bytes, sizeof bytes)};
  void reset(uint8_t fill = 0xEE) {
    for (uint8_t& b : bytes)
      b = fill;
    device = hal::FakeBlockDevice(Span<uint8_t>(bytes, sizeof bytes));
  }
};

// Grey level of pixel k of place i: every place is distinct and checkable.
inline uint8_t place_pixel(uint32_t i, uint32_t k) {
  return static_cast<uint8_t>(i * 13u + k * 5u + (k >> 4));
}

inline storage::DreamHeader dream_header(storage::DreamVariant variant, bool colour = false) {
  storage::DreamHeader h;
  h.variant = variant;
  h.colour = colour ? storage::ColourFormat::kYuv422 : storage::ColourFormat::kNone;
  h.mapping = hal::PipelineMapping::reduction(32, 16);
  h.infrared_count = 3;
  for (uint32_t i = 0; i < 3; ++i) {
    h.infrared[i] = storage::InfraredMount{static_cast<int16_t>(100 * i), -50,
                                           static_cast<uint16_t>(i * 8192), 40, 800};
  }
  return h;
}

// Snapshot number i of a recording (encoders advance 23 ticks per 10 ms and wrap).
inline hal::SensorSnapshot snapshot(uint32_t i) {
  hal::SensorSnapshot s;
  s.sequence = 1000 + i;
  s.timestamp_us = 10000u * i;
  s.flags = hal::SensorSnapshot::kHasEncoders | hal::SensorSnapshot::kHasInfrared |
            hal::SensorSnapshot::kHasHead;
  s.encoder_left = 0xFFFFF000u + 23u * i;
  s.encoder_right = 0xFFFFF100u + 23u * i;
  s.head_pan = static_cast<int16_t>(i * 3);
  s.head_tilt = -1820;
  s.infrared_count = 3;
  for (uint32_t k = 0; k < 3; ++k)
    s.infrared_mm[k] = static_cast<uint16_t>(100 + i + k);
  return s;
}

}  // namespace seqslam::test
