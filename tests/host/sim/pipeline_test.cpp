// The pixel pipeline model (host_sim/include/seqslam_sim/pipeline.h) against its definition
// evaluated independently: superpixel (u, v) = floor(A (x, y)) + b with the exact Q15.16 raw
// entries (as rationals raw / 2^16, evaluated in double where they are exact), and each
// superpixel the mean of its pixels rounded to nearest, ties up, in exact integer arithmetic.
// Stated bound: exact equality of every superpixel and of the covered count.
#include <cmath>
#include <cstdint>
#include <vector>

#include <gtest/gtest.h>

#include "seqslam/hal/pixel_buffer.h"
#include "seqslam_sim/pipeline.h"
#include "seqslam_sim/rng.h"
#include "seqslam_tools/q_format.h"

namespace seqslam::sim {
namespace {

constexpr int kW = 346;
constexpr int kH = 271;

struct Reference {
  std::vector<uint8_t> pixels;
  uint32_t covered = 0;
};

Reference reference(const std::vector<uint8_t>& frame, const hal::PipelineMapping& m) {
  const size_t n = static_cast<size_t>(m.xmax) * m.ymax;
  std::vector<uint64_t> sum(n, 0), count(n, 0);
  // Each entry is raw / 2^16, and raw * x + raw * y is below 2^16 * 16 * 346 * 2 < 2^53 in
  // magnitude: a * x + b * y is exact in double, so std::floor sees the exact rational.
  const double a11 = tools::to_double(m.a11), a12 = tools::to_double(m.a12),
               a21 = tools::to_double(m.a21), a22 = tools::to_double(m.a22);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      const double u = std::floor(a11 * x + a12 * y) + m.bx;
      const double v = std::floor(a21 * x + a22 * y) + m.by;
      if (u < 0.0 || v < 0.0 || u >= m.xmax || v >= m.ymax) continue;
      const size_t i = static_cast<size_t>(v) * m.xmax + static_cast<size_t>(u);
      sum[i] += frame[static_cast<size_t>(y) * kW + static_cast<size_t>(x)];
      ++count[i];
    }
  }
  Reference r;
  r.pixels.assign(n, 0);
  for (size_t i = 0; i < n; ++i) {
    if (count[i] == 0) continue;
    ++r.covered;
    // round(sum / count), ties up: floor((2 sum + count) / (2 count)).
    r.pixels[i] = static_cast<uint8_t>((2 * sum[i] + count[i]) / (2 * count[i]));
  }
  return r;
}

std::vector<std::vector<uint8_t>> test_frames() {
  std::vector<std::vector<uint8_t>> frames;
  const size_t n = static_cast<size_t>(kW) * kH;
  Rng rng(346271);
  std::vector<uint8_t> noise(n);
  for (uint8_t& p : noise)
    p = static_cast<uint8_t>(rng.below(256));
  frames.push_back(noise);
  // 0/1 and 254/255 checkerboards: superpixels with an even pixel count average to x.5
  // (the tie), and the top of the range must not overflow.
  std::vector<uint8_t> low(n), high(n);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      low[static_cast<size_t>(y) * kW + static_cast<size_t>(x)] = static_cast<uint8_t>((x + y) & 1);
      high[static_cast<size_t>(y) * kW + static_cast<size_t>(x)] =
          static_cast<uint8_t>(254 + ((x + y) & 1));
    }
  }
  frames.push_back(low);
  frames.push_back(high);
  // A gradient (smooth, like a real image).
  std::vector<uint8_t> ramp(n);
  for (int y = 0; y < kH; ++y) {
    for (int x = 0; x < kW; ++x) {
      ramp[static_cast<size_t>(y) * kW + static_cast<size_t>(x)] =
          static_cast<uint8_t>((x * 255 / (kW - 1) + y * 3) % 256);
    }
  }
  frames.push_back(ramp);
  return frames;
}

// Compares for every test frame; returns the covered count (the same for every frame).
uint32_t expect_matches_reference(const hal::PipelineMapping& m) {
  EXPECT_EQ(hal::check_mapping(m), Status::kOk);
  uint32_t covered = 0;
  int frame_index = 0;
  for (const std::vector<uint8_t>& frame : test_frames()) {
    const PipelineOutput out = apply_pipeline(frame.data(), kW, kH, m);
    const Reference ref = reference(frame, m);
    EXPECT_EQ(out.covered, ref.covered) << "frame " << frame_index;
    EXPECT_EQ(out.pixels.size(), ref.pixels.size());
    if (out.pixels.size() != ref.pixels.size()) return 0;
    int wrong = 0;
    for (size_t i = 0; i < ref.pixels.size() && wrong < 5; ++i) {
      if (out.pixels[i] != ref.pixels[i]) {
        ADD_FAILURE() << "frame " << frame_index << " superpixel (" << i % m.xmax << ", "
                      << i / m.xmax << "): " << int{out.pixels[i]} << " vs reference "
                      << int{ref.pixels[i]};
        ++wrong;
      }
    }
    covered = ref.covered;
    ++frame_index;
  }
  return covered;
}

TEST(SimPipeline, PlainReductionsMatchTheDefinition) {
  const uint16_t sizes[][2] = {{32, 16}, {25, 20}, {12, 10}};
  for (const auto& s : sizes) {
    SCOPED_TRACE(std::to_string(s[0]) + "x" + std::to_string(s[1]));
    const hal::PipelineMapping m = hal::PipelineMapping::reduction(s[0], s[1]);
    // The plain reduction reaches every superpixel.
    EXPECT_EQ(expect_matches_reference(m), uint32_t{s[0]} * s[1]);
  }
}

TEST(SimPipeline, HandComputedExample) {
  // 5x2 -> 2x1 with A = diag(2/5, 1/2): columns 0..2 -> u = 0 (0, 0.4, 0.8), 3..4 -> u = 1.
  const uint8_t frame[10] = {10, 20, 30, 40, 50, 11, 21, 31, 41, 51};
  hal::PipelineMapping m;
  m.a11 = Q15_16::from_ratio(2, 5);
  m.a22 = Q15_16::from_ratio(1, 2);
  m.xmax = 2;
  m.ymax = 1;
  const PipelineOutput out = apply_pipeline(frame, 5, 2, m);
  ASSERT_EQ(out.pixels.size(), 2u);
  EXPECT_EQ(out.pixels[0], 21);  // (10+20+30+11+21+31)/6 = 20.5 -> 21 (ties up)
  EXPECT_EQ(out.pixels[1], 46);  // (40+50+41+51)/4 = 45.5 -> 46
  EXPECT_EQ(out.covered, 2u);
  // Shifted right by one superpixel: u = 0 is uncovered and reads 0.
  m.bx = 1;
  m.xmax = 3;
  const PipelineOutput shifted = apply_pipeline(frame, 5, 2, m);
  ASSERT_EQ(shifted.pixels.size(), 3u);
  EXPECT_EQ(shifted.pixels[0], 0);
  EXPECT_EQ(shifted.pixels[1], 21);
  EXPECT_EQ(shifted.pixels[2], 46);
  EXPECT_EQ(shifted.covered, 2u);
}

TEST(SimPipeline, RotatedShearedMappingWithOffsets) {
  hal::PipelineMapping m;
  // About 8 degrees of rotation with a shear and a different scale per axis; offsets that
  // push part of the frame out of the buffer and leave some superpixels uncovered.
  m.a11 = Q15_16::from_raw(5710);  // 0.0871
  m.a12 = Q15_16::from_raw(1203);  // 0.0184
  m.a21 = Q15_16::from_raw(-803);  // -0.0123
  m.a22 = Q15_16::from_raw(3989);  // 0.0609
  m.bx = -2;
  m.by = 3;
  m.xmax = 32;
  m.ymax = 16;
  const uint32_t covered = expect_matches_reference(m);
  EXPECT_GT(covered, 100u);
  EXPECT_LT(covered, 512u);  // some uncovered: those read 0
}

TEST(SimPipeline, NegativeEntriesMirrorTheFrame) {
  // Mirrored in both axes: u = floor(-a x) + 31 with negative products (floor towards -inf).
  hal::PipelineMapping m;
  m.a11 = Q15_16::from_raw(-6061);  // -32/346, rounded
  m.a12 = Q15_16::from_raw(0);
  m.a21 = Q15_16::from_raw(0);
  m.a22 = Q15_16::from_raw(-3870);  // -16/271, rounded
  m.bx = 32;
  m.by = 16;
  m.xmax = 32;
  m.ymax = 16;
  EXPECT_EQ(expect_matches_reference(m), 512u);
  // And a rotation by about 180 + 20 degrees with odd raw values and offsets.
  hal::PipelineMapping r;
  r.a11 = Q15_16::from_raw(-5695);
  r.a12 = Q15_16::from_raw(2073);
  r.a21 = Q15_16::from_raw(-1037);
  r.a22 = Q15_16::from_raw(-2849);
  r.bx = 30;
  r.by = 21;
  r.xmax = 25;
  r.ymax = 20;
  const uint32_t covered = expect_matches_reference(r);
  EXPECT_GT(covered, 50u);
  EXPECT_LT(covered, 500u);
}

}  // namespace
}  // namespace seqslam::sim
