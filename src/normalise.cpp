#include "seqslam/normalise.h"

#include "seqslam/fixmath.h"

namespace seqslam {

Status LocalNormaliser::configure(uint16_t window, UQ8_8 sigma_min, uint32_t pixels) {
  if (window == 1 || window > kMaxWindow) return Status::kOutOfRange;
  if (pixels == 0 || pixels > kMaxPixels) return Status::kOutOfRange;
  if (window > 0 && sigma_min.raw() == 0) return Status::kInvalidArgument;
  window_ = window;
  half_ = static_cast<uint16_t>(window / 2);
  // floor(sqrt(W) * 2^11) = isqrt(W * 2^22); W <= 255 keeps the product below 2^30.
  offset_ = static_cast<uint16_t>(isqrt32(static_cast<uint32_t>(window) << 22));
  pixels_ = pixels;
  // sigma_min in SAD units (MAD * A), at least 1 so the denominator is never zero.
  const uint32_t s = div_round_u32(static_cast<uint32_t>(sigma_min.raw()) * pixels, 256);
  sigma_min_sad_ = s > 0 ? s : 1;
  return Status::kOk;
}

void LocalNormaliser::normalise_row(const uint32_t* d, uint32_t n, uint16_t* out) const {
  for_each_descending(d, n, [out](uint32_t j, uint16_t v) { out[j] = v; });
}

}  // namespace seqslam
