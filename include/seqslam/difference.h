// Image differences (2025 thesis eq. 4.5; OpenSeqSLAM's shift-tolerant variant, 2015 thesis
// eqs. 3.3-3.4).
//
// Difference values are kept as "SAD units": the sum of absolute differences over the full
// image area, i.e. MAD * A with A = width * height. For plain MAD this is an exact integer;
// MAD itself (eq. 4.5) is SAD / A. The local normalisation that follows is a z-score, which is
// invariant to this scale, so nothing downstream divides by A.
#pragma once

#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/image.h"
#include "seqslam/status.h"

namespace seqslam {

// Sum of absolute differences. kInvalidArgument for null buffers or different sizes,
// kOutOfRange for images beyond kMaxPixels.
Result<uint32_t> sad(ImageView a, ImageView b);

// Mean absolute difference in grey levels, UQ8.8 rounded to nearest (eq. 4.5).
Result<UQ8_8> mad(ImageView a, ImageView b);

// Horizontally shift-tolerant difference: the smallest MAD over horizontal offsets
// dx in [-max_shift, max_shift], each computed over the overlapping columns only, returned in
// SAD units of the full image (MAD_dx * A, rounded to nearest). max_shift = 0 equals sad().
// Ties between offsets go to the smallest |dx|, then to negative dx. Costs (2 max_shift + 1)
// times a plain SAD. kOutOfRange if max_shift >= width.
Result<uint32_t> shift_tolerant_sad(ImageView a, ImageView b, uint8_t max_shift);

// Where b's content lies in a, horizontally, to a fraction of a pixel: the dx in
// [-max_shift, max_shift] whose mean absolute difference of a(x + dx, y) against b(x, y) over
// the overlapping columns is smallest (ties as shift_tolerant_sad), moved to the vertex of
// the parabola through that mean and its two neighbours when both exist and the parabola
// opens upwards (so |result - dx| <= 1/2). In pixels, Q15.16, the means rounded to 2^-16 grey
// levels. What it is for: two images of one place taken with different headings differ
// mostly by such a shift (a camera turned left by h sees the scene moved right by
// h * width / hfov pixels), which gives a loop closure its heading offset (docs/mapping.md).
// Costs 2 max_shift + 1 shifted SADs. kInvalidArgument for null buffers or different sizes,
// kOutOfRange if max_shift >= width or > kMaxSubpixelShift or the images exceed kMaxPixels.
inline constexpr uint8_t kMaxSubpixelShift = 16;  // bounds the stack (4 bytes per shift)
Result<Q15_16> subpixel_shift(ImageView a, ImageView b, uint8_t max_shift);

// The matcher's hot loop: out[j] = SAD(query, image j) for `count` images stored back to back
// (image j starts at images + j * pixels), using the precomputed pixel sums of the images
// (image_sums[j] = sum of image j's pixels). Uses |q - l| = 2 max(q, l) - q - l with blocks of
// 16 query pixels held in registers, so each library pixel costs a load, a compare and an add.
// The caller guarantees valid pointers and pixels <= kMaxPixels.
void sad_many(const uint8_t* query, const uint8_t* images, const uint32_t* image_sums,
              uint32_t count, uint32_t pixels, uint32_t* out);

// Sum of the pixels of an image (what sad_many needs per library image).
uint32_t pixel_sum(const uint8_t* pixels, uint32_t count);

}  // namespace seqslam
