#include "seqslam/pixel_pipeline.h"

namespace seqslam {

Status area_reduce(ImageView src, MutableImageView dst, Span<uint32_t> scratch) {
  if (src.pixels == nullptr || dst.pixels == nullptr) return Status::kInvalidArgument;
  if (src.size.width == 0 || src.size.height == 0) return Status::kInvalidArgument;
  SEQSLAM_TRY(check_image_size(dst.size));
  if (dst.size.width > src.size.width || dst.size.height > src.size.height) {
    return Status::kInvalidArgument;
  }
  // 255 * 2^24 < 2^32: sums cannot overflow.
  if (src.size.pixels() > (1u << 24)) return Status::kOutOfRange;
  const uint32_t n = dst.size.pixels();
  if (scratch.size() < 2u * n) return Status::kResourceExhausted;

  uint32_t* sums = scratch.data();
  uint32_t* counts = scratch.data() + n;
  for (uint32_t i = 0; i < 2u * n; ++i)
    scratch[i] = 0;

  const uint32_t sw = src.size.width;
  const uint32_t sh = src.size.height;
  const uint32_t dw = dst.size.width;
  const uint32_t dh = dst.size.height;
  for (uint32_t y = 0; y < sh; ++y) {
    const uint32_t v = y * dh / sh;
    const uint8_t* row = src.pixels + y * sw;
    uint32_t* sum_row = sums + v * dw;
    uint32_t* count_row = counts + v * dw;
    for (uint32_t x = 0; x < sw; ++x) {
      const uint32_t u = x * dw / sw;
      sum_row[u] += row[x];
      count_row[u] += 1;
    }
  }
  // Every superpixel receives at least one pixel because dst is not larger than src.
  for (uint32_t i = 0; i < n; ++i) {
    dst.pixels[i] = static_cast<uint8_t>((sums[i] + counts[i] / 2) / counts[i]);
  }
  return Status::kOk;
}

}  // namespace seqslam
