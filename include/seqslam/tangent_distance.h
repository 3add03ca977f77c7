// Tangent distance (2015 thesis section 3.2.2, eqs. 3.13-3.18; Simard et al. 2000) in fixed
// point.
//
// Pipeline per image (once per library image, once per query):
//   1. separable Gaussian blur, integer kernel weights summing to 2^12, borders clamped;
//   2. four tangent vectors (Lie operators) of the blurred image from clamped central
//      differences dx = (B(x+1) - B(x-1)) / 2, dy likewise:
//        L1 = dx (horizontal translation), L2 = dy (vertical translation),
//        L3 = v dx - u dy (rotation about the image centre), L4 = u dx + v dy (scaling),
//      with centred, normalised coordinates u = (2x - (w-1)) / D, v = (2y - (h-1)) / D,
//      D = max(w, h), so |u|, |v| < 1 and every tangent stays below 255 in magnitude;
//   3. the 4x4 Gram matrix L^T L of its own tangents.
// Per pair: the two-sided distance  TD(A, B) = min_{a,b} ||(A + L_A a) - (B + L_B b)||^2
// over the *blurred* images (the tangents linearise the blurred image, so the distance is
// taken where the linearisation holds). It is solved in closed form through the normal
// equations of the 8 unknowns c = (a, b): with M = [L_A, -L_B], d = A - B, G = M^T M,
// g = M^T d,  TD = ||d||^2 - g^T G^-1 g  (the same minimum eqs. 3.17/3.18 give via their
// 4x4 Schur complements).
//
// Near-singular systems: G is singular whenever a tangent is zero (flat image) and
// ill-conditioned when L_A ~ L_B (the usual case: similar images). The solver therefore
// (a) drops every column with a zero tangent (exactly), and (b) adds a Tikhonov /
// Levenberg-Marquardt term relative to the diagonal: G + lambda diag(G), lambda = 2^-10
// (kTdLambdaShift). The result is the exact minimum of
//   ||d + M c||^2 + lambda sum_i G_ii c_i^2,
// so  TD_true <= TD <= ||d||^2  always holds, it is invariant to scaling of the tangents,
// and the condition number of the scaled system is below 2^15. Flat images give exactly
// the plain squared difference; identical images give 0.
//
// Formats: blurred pixels UQ8.8; tangents Q8.7 (int16, |value| < 255, resolution 1/128);
// Gram entries Q.14 in int64; squared distances Q47.16 (int64, exact for the plain
// difference). Internally the 9x9 augmented system [G g; g^T ||d||^2] is scaled exactly by
// powers of two to a unit diagonal range [1/4, 1] and eliminated in Q.56 with 128-bit
// intermediates (8 Int128 divisions per pair).
//
// Accuracy (tests/unit/test_tangent_distance.cpp, against double precision):
//   blur: |error| <= 1/256 grey (two roundings to 1/512) against the exact integer kernel;
//   kernel weights within (radius + 1) / 4096 of the exact normalised Gaussian;
//   tangents: <= 3/256 against a fully double pipeline (blur error + 0.5 LSB of Q8.7);
//   distance: |TD - TD_double| <= 2^-30 ||d||^2 + 2^-15 for the same prepared images.
//
// Only the two-sided variant is implemented (use it wherever both images are prepared: the
// library image's tangents are stored once, the query's once per frame). The one-sided
// variant with orthonormalised query tangents is not implemented.
//
// Cost per pair (32x16): ~12 multiply-accumulates per pixel plus a fixed 9x9 elimination.
#pragma once

#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/image.h"
#include "seqslam/limits.h"
#include "seqslam/status.h"

namespace seqslam {

using Q8_7 = Fixed<int16_t, 7>;     // tangent vectors (grey levels per unit parameter)
using Q47_16 = Fixed<int64_t, 16>;  // squared distances (sum of squared grey levels)

// Kernel weights are integers summing to 2^kBlurShift.
inline constexpr int kBlurShift = 12;
// Largest kernel radius; radius = ceil(2 sigma), so sigma <= 2 pixels.
inline constexpr uint8_t kMaxBlurRadius = 4;
// Tikhonov weight lambda = 2^-kTdLambdaShift, relative to each column's squared norm.
inline constexpr int kTdLambdaShift = 10;
inline constexpr int kTangentCount = 4;

// Recommended blur width per resolution: sigma = width / 32 pixels clamped to [0.5, 2]
// (1.0 at 32x16, 0.5 at 12x10 and 16x8, 2.0 at 64x32).
constexpr UQ8_8 default_td_sigma(ImageSize size) {
  const int64_t raw = static_cast<int64_t>(size.width) * 8;  // width / 32 in UQ8.8
  return UQ8_8::from_raw(static_cast<uint16_t>(raw < 128 ? 128 : (raw > 512 ? 512 : raw)));
}

struct BlurKernel {
  uint8_t radius = 0;
  // weight[0] is the centre, weight[k] applies at offsets +-k; weight[0] + 2 sum = 4096.
  uint16_t weight[kMaxBlurRadius + 1] = {4096, 0, 0, 0, 0};
};

// The Gaussian kernel of width sigma (pixels, UQ8.8): radius ceil(2 sigma), weights
// round(4096 g_k / sum g) for k >= 1 and the centre taking the remainder, so the sum is exact.
// sigma = 0 gives the identity. kOutOfRange for sigma > 2.
Result<BlurKernel> make_blur_kernel(UQ8_8 sigma);

// out = the image blurred with the kernel (horizontal pass rounded to UQ8.8, then vertical),
// borders clamped. out must hold size.pixels() values. kInvalidArgument for null buffers or
// an invalid kernel, kOutOfRange beyond kMaxPixels. Uses kMaxPixels * 2 bytes of stack.
Status gaussian_blur(ImageView image, const BlurKernel& kernel, UQ8_8* out);

// A prepared image: everything the distance needs from one side, computed once.
struct TangentImage {
  ImageSize size;
  UQ8_8 blurred[kMaxPixels];
  Q8_7 tangent[kTangentCount][kMaxPixels];  // L1..L4 as above
  // L^T L, entries (i, j) with i <= j in the order 00 01 02 03 11 12 13 22 23 33; raw Q.14.
  int64_t gram[10];
};
// 32x16 (target, kMaxPixels = 512): 4 + 512 * 2 + 4 * 512 * 2 + 80 = 5208 bytes with padding.
static_assert(sizeof(TangentImage) <= 10 * kMaxPixels + 96, "TangentImage over budget");

// Which tangents a prepared image carries (bit i = L(i+1) above). A tangent left out is zero,
// so the distance does not move along it (its pivot is skipped as for a flat image).
// Why leave one out: the robot captures a place every 20 cm, and driving forward looks like a
// zoom of the view, so with the scaling tangent neighbouring places become nearly the same
// image and a match lands a place or two away (docs/perspective.md); rotation and shifts of
// the head are what the distance should absorb there.
enum TangentSet : uint8_t {
  kTangentShiftX = 1u << 0,
  kTangentShiftY = 1u << 1,
  kTangentRotation = 1u << 2,
  kTangentScaling = 1u << 3,
  kAllTangents = 0x0F,
  kTangentsWithoutScaling = kTangentShiftX | kTangentShiftY | kTangentRotation,
};

// Blur, tangents (those in `tangents`) and Gram matrix of an image. out is left untouched on
// failure (kInvalidArgument: null, zero size, invalid kernel or a set outside kAllTangents;
// kOutOfRange: beyond kMaxPixels).
Status prepare_tangent_image(ImageView image, const BlurKernel& kernel, TangentImage* out,
                             uint8_t tangents = kAllTangents);

struct TangentDistance {
  Q47_16 squared;        // TD(A, B), regularised as above
  Q47_16 plain_squared;  // ||A - B||^2 of the blurred images (exact): TD <= plain_squared
  UQ8_8 rms;             // floor(sqrt(round(TD / pixels))) in grey levels, comparable to MAD
};

// Two-sided tangent distance of two prepared images. kInvalidArgument if the sizes differ or
// are zero.
Result<TangentDistance> tangent_distance(const TangentImage& a, const TangentImage& b);

}  // namespace seqslam
