#include "seqslam/difference.h"

#include "seqslam/fixmath.h"

namespace seqslam {

namespace {

Status check_pair(ImageView a, ImageView b) {
  if (a.pixels == nullptr || b.pixels == nullptr) return Status::kInvalidArgument;
  if (a.size != b.size) return Status::kInvalidArgument;
  return check_image_size(a.size);
}

inline uint32_t absdiff(uint32_t a, uint32_t b) {
  return a > b ? a - b : b - a;
}
inline uint32_t umax(uint32_t a, uint32_t b) {
  return a > b ? a : b;
}

// SAD of a against b shifted by dx columns, over the overlap only.
uint32_t shifted_sad(ImageView a, ImageView b, int32_t dx) {
  const uint32_t w = a.size.width;
  const uint32_t h = a.size.height;
  const uint32_t shift = static_cast<uint32_t>(dx >= 0 ? dx : -dx);
  const uint32_t a0 = dx >= 0 ? shift : 0;
  const uint32_t b0 = dx >= 0 ? 0 : shift;
  uint32_t total = 0;
  for (uint32_t y = 0; y < h; ++y) {
    const uint8_t* ra = a.pixels + y * w + a0;
    const uint8_t* rb = b.pixels + y * w + b0;
    for (uint32_t x = 0; x + shift < w; ++x)
      total += absdiff(ra[x], rb[x]);
  }
  return total;
}

}  // namespace

Result<uint32_t> sad(ImageView a, ImageView b) {
  SEQSLAM_TRY(check_pair(a, b));
  uint32_t total = 0;
  const uint32_t n = a.size.pixels();
  for (uint32_t i = 0; i < n; ++i)
    total += absdiff(a.pixels[i], b.pixels[i]);
  return total;
}

Result<UQ8_8> mad(ImageView a, ImageView b) {
  const Result<uint32_t> r = sad(a, b);
  if (!r.ok()) return r.status();
  // SAD <= 255 * 2^14, so SAD * 256 fits 32 bits.
  return UQ8_8::from_raw(static_cast<uint16_t>(div_round_u32(r.value() * 256u, a.size.pixels())));
}

Result<uint32_t> shift_tolerant_sad(ImageView a, ImageView b, uint8_t max_shift) {
  SEQSLAM_TRY(check_pair(a, b));
  const uint32_t w = a.size.width;
  if (max_shift >= w) return Status::kOutOfRange;
  // Best ratio SAD_dx / (w - |dx|) by cross-multiplication (exact). Candidates in the order
  // 0, -1, +1, -2, +2, ... so a strict "<" keeps the tie-break documented in the header.
  uint32_t best_sad = shifted_sad(a, b, 0);
  uint32_t best_cols = w;
  for (int32_t k = 1; k <= max_shift; ++k) {
    for (int32_t sign = -1; sign <= 1; sign += 2) {
      const uint32_t v = shifted_sad(a, b, sign * k);
      const uint32_t cols = w - static_cast<uint32_t>(k);
      if (static_cast<uint64_t>(v) * best_cols < static_cast<uint64_t>(best_sad) * cols) {
        best_sad = v;
        best_cols = cols;
      }
    }
  }
  // Scale to the full area: SAD * w / cols, rounded.
  return static_cast<uint32_t>((static_cast<uint64_t>(best_sad) * w + best_cols / 2) / best_cols);
}

Result<Q15_16> subpixel_shift(ImageView a, ImageView b, uint8_t max_shift) {
  SEQSLAM_TRY(check_pair(a, b));
  const uint32_t w = a.size.width;
  const uint32_t h = a.size.height;
  if (max_shift >= w || max_shift > kMaxSubpixelShift) return Status::kOutOfRange;
  // Mean per shift in UQ16.16 grey levels (<= 255 * 2^16), rounded; sad <= 255 * 2^14, so
  // sad * 2^16 needs 64 bits. Indexed by dx + max_shift.
  uint32_t mean[2 * kMaxSubpixelShift + 1];
  for (int32_t dx = -static_cast<int32_t>(max_shift); dx <= max_shift; ++dx) {
    const uint64_t n = static_cast<uint64_t>(w - static_cast<uint32_t>(dx < 0 ? -dx : dx)) * h;
    const uint64_t v = (static_cast<uint64_t>(shifted_sad(a, b, dx)) << 16) + n / 2;
    mean[dx + max_shift] = static_cast<uint32_t>(v / n);
  }
  // The minimum, candidates in the order 0, -1, +1, -2, +2, ... (strict "<").
  int32_t best = 0;
  for (int32_t k = 1; k <= max_shift; ++k) {
    for (int32_t sign = -1; sign <= 1; sign += 2) {
      if (mean[sign * k + max_shift] < mean[best + max_shift]) best = sign * k;
    }
  }
  int64_t result = static_cast<int64_t>(best) * 65536;
  if (best > -static_cast<int32_t>(max_shift) && best < max_shift) {
    // Vertex of the parabola through the minimum and its neighbours (|l - r| < 2^24).
    result += parabola_vertex_q16(mean[best - 1 + max_shift], mean[best + max_shift],
                                  mean[best + 1 + max_shift]);
  }
  return Q15_16::from_raw(static_cast<int32_t>(result));
}

uint32_t pixel_sum(const uint8_t* pixels, uint32_t count) {
  uint32_t total = 0;
  for (uint32_t i = 0; i < count; ++i)
    total += pixels[i];
  return total;
}

namespace {

// Register blocking of sad_many, tuned on RV32IMC (instructions per library pixel at 32x16,
// M = 450, from make bench): 16 query pixels x 2 images per pass 3.79; 16 x 1 3.85; 16 x 3
// 3.83; 16 x 4 3.80; 12 x 4 3.88; 20 x 1 3.95 (512 is not a multiple of 20); 24 x 1 4.02
// (the compiler spills query pixels). 16 + 2 sums + pointers fill the 27 free registers.
constexpr uint32_t kBlockPixels = 16;
constexpr uint32_t kImagesPerPass = 2;

// Adds sum_{k<N} max(q[k], image_j[offset + k]) to out[j] for every image j, with the N query
// pixels held in registers for the whole pass over the library: per library pixel one load,
// one compare(-and-move) and one add; per image and block a load and store of out[j]. Two
// images per iteration share the loop overhead.
template <uint32_t N>
void max_sums_block(const uint8_t* query, const uint8_t* images, uint32_t count, uint32_t stride,
                    uint32_t* out) {
  uint32_t q[N];
#pragma GCC unroll 32
  for (uint32_t k = 0; k < N; ++k)
    q[k] = query[k];
  const uint8_t* img = images;
  uint32_t j = 0;
  constexpr uint32_t kImages = kImagesPerPass;
  for (; j + kImages <= count; j += kImages, img += kImages * stride) {
    uint32_t s[kImages];
#pragma GCC unroll 8
    for (uint32_t i = 0; i < kImages; ++i)
      s[i] = out[j + i];
#pragma GCC unroll 32
    for (uint32_t k = 0; k < N; ++k) {
#pragma GCC unroll 8
      for (uint32_t i = 0; i < kImages; ++i)
        s[i] += umax(q[k], img[i * stride + k]);
    }
#pragma GCC unroll 8
    for (uint32_t i = 0; i < kImages; ++i)
      out[j + i] = s[i];
  }
  for (; j < count; ++j, img += stride) {
    uint32_t s = out[j];
#pragma GCC unroll 32
    for (uint32_t k = 0; k < N; ++k)
      s += umax(q[k], img[k]);
    out[j] = s;
  }
}

}  // namespace

void sad_many(const uint8_t* query, const uint8_t* images, const uint32_t* image_sums,
              uint32_t count, uint32_t pixels, uint32_t* out) {
  for (uint32_t j = 0; j < count; ++j)
    out[j] = 0;
  uint32_t b = 0;
  for (; b + kBlockPixels <= pixels; b += kBlockPixels) {
    max_sums_block<kBlockPixels>(query + b, images + b, count, pixels, out);
  }
  // Tail (pixels not a multiple of the block, e.g. 25x20 = 500), one pixel at a time.
  for (; b < pixels; ++b)
    max_sums_block<1>(query + b, images + b, count, pixels, out);
  const uint32_t query_sum = pixel_sum(query, pixels);
  for (uint32_t j = 0; j < count; ++j)
    out[j] = 2 * out[j] - query_sum - image_sums[j];
}

}  // namespace seqslam
