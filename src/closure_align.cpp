#include "seqslam/closure_align.h"

#include "seqslam/difference.h"
#include "seqslam/fixmath.h"

namespace seqslam {

namespace {

uint32_t min_u32(uint32_t a, uint32_t b) {
  return a < b ? a : b;
}

}  // namespace

Status align_closure(PlaceLibrary& library, uint32_t current, uint32_t matched, uint32_t known,
                     const ClosureAlignConfig& config, Span<uint8_t> scratch,
                     ClosureAlignment* out) {
  if (out == nullptr || config.length == 0 || config.length > kMaxAlignLength ||
      config.max_offset > kMaxAlignOffset) {
    return Status::kInvalidArgument;
  }
  const ImageSize size = library.image_size();
  if (current >= library.size() || known > current || matched >= known) {
    return Status::kOutOfRange;
  }
  const uint32_t pixels = size.pixels();
  if (config.max_shift >= size.width || scratch.data() == nullptr || scratch.size() < pixels) {
    return Status::kInvalidArgument;
  }
  const uint32_t length = min_u32(min_u32(config.length, current + 1), matched + 1);
  // The candidates are the contiguous offsets k in [lo, hi]: matched + k - (length - 1) >= 0
  // and matched + k < known; k = 0 always qualifies (length <= matched + 1, matched < known).
  const int32_t reach = config.max_offset;
  const int32_t lo = -static_cast<int32_t>(min_u32(matched + 1 - length, config.max_offset));
  const int32_t hi = static_cast<int32_t>(min_u32(known - 1 - matched, config.max_offset));
  // P(k), indexed by k + reach; <= kMaxAlignLength * 255 * kMaxPixels fits 64 bits easily.
  uint64_t profile[2 * kMaxAlignOffset + 1] = {};
  for (uint32_t t = 0; t < length; ++t) {
    // The current pass's image, copied: the next read may evict it from a card cache.
    ImageView view{};
    Status s = library.image(current - t, &view);
    if (s != Status::kOk) return s;
    for (uint32_t i = 0; i < pixels; ++i)
      scratch[i] = view.pixels[i];
    const ImageView query{scratch.data(), size};
    for (int32_t k = lo; k <= hi; ++k) {
      const uint32_t place = static_cast<uint32_t>(static_cast<int64_t>(matched) + k) - t;
      s = library.image(place, &view);
      if (s != Status::kOk) return s;
      const Result<uint32_t> d = shift_tolerant_sad(view, query, config.max_shift);
      if (!d.ok()) return d.status();
      profile[k + reach] += d.value();
    }
  }
  // The smallest sum, candidates in the order 0, -1, +1, -2, +2, ... (strict "<").
  int32_t best = 0;
  for (int32_t k = 1; k <= reach; ++k) {
    for (int32_t sign = -1; sign <= 1; sign += 2) {
      const int32_t c = sign * k;
      if (c >= lo && c <= hi && profile[c + reach] < profile[best + reach]) best = c;
    }
  }
  int32_t fraction = 0;
  if (best > lo && best < hi) {
    // |l - r| <= 2^38 here, well inside parabola_vertex_q16's range.
    fraction = parabola_vertex_q16(static_cast<int64_t>(profile[best - 1 + reach]),
                                   static_cast<int64_t>(profile[best + reach]),
                                   static_cast<int64_t>(profile[best + 1 + reach]));
  }
  out->place = static_cast<uint32_t>(static_cast<int64_t>(matched) + best);
  out->fraction = Q15_16::from_raw(fraction);
  out->offset = Q15_16::from_raw(best * 65536 + fraction);
  out->compared = length;
  out->candidates = static_cast<uint32_t>(hi - lo + 1);
  return Status::kOk;
}

}  // namespace seqslam
