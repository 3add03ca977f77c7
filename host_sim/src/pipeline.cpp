#include "seqslam_sim/pipeline.h"

#include "seqslam_sim/world.h"

namespace seqslam::sim {

namespace {
// floor(a / 2^16) for a signed Q.16 product, also for negative values.
int64_t floor_q16(int64_t a) {
  return a >= 0 ? a >> 16 : -((-a + 65535) >> 16);
}
}  // namespace

PipelineOutput apply_pipeline(const uint8_t* frame, int width, int height,
                              const hal::PipelineMapping& m) {
  const size_t n = static_cast<size_t>(m.xmax) * m.ymax;
  std::vector<uint32_t> sum(n, 0);
  std::vector<uint32_t> count(n, 0);
  for (int y = 0; y < height; ++y) {
    for (int x = 0; x < width; ++x) {
      const int64_t u = floor_q16(int64_t{m.a11.raw()} * x + int64_t{m.a12.raw()} * y) + m.bx;
      const int64_t v = floor_q16(int64_t{m.a21.raw()} * x + int64_t{m.a22.raw()} * y) + m.by;
      if (u < 0 || v < 0 || u >= m.xmax || v >= m.ymax) continue;
      const size_t i = static_cast<size_t>(v) * m.xmax + static_cast<size_t>(u);
      sum[i] += frame[raster_index(x, y, width)];
      ++count[i];
    }
  }
  PipelineOutput out;
  out.pixels.assign(n, 0);
  for (size_t i = 0; i < n; ++i) {
    if (count[i] == 0) continue;
    ++out.covered;
    out.pixels[i] = static_cast<uint8_t>((sum[i] + count[i] / 2) / count[i]);
  }
  return out;
}

}  // namespace seqslam::sim
