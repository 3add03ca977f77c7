// Image preprocessing against illumination change (2025 thesis, section 4.1, Table 3).
//
// All functions take an input view and an output view of the same size; the output may be
// the input (in place). They return:
//   kInvalidArgument - a null buffer, input and output sizes differ, or a bad PN parameter;
//   kOutOfRange      - the image is larger than kMaxPixels (see check_image_size);
// and leave the output untouched on failure.
#pragma once

#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/image.h"
#include "seqslam/status.h"

namespace seqslam {

enum class Preprocessing : uint8_t {
  kNone = 0,
  kHistEq = 1,             // HE: histogram equalisation (the thesis's best indoors)
  kPatchNorm = 2,          // PN: patch normalisation (SeqSLAM's original)
  kInvGamma = 3,           // iGK: inverse gamma 1/0.45 (linearises the camera's gamma)
  kHistEqPatchNorm = 4,    // HE then PN
  kInvGammaPatchNorm = 5,  // iGK then PN
  kInvGammaHistEq = 6,     // iGK then HE
};
// "none", "he", "pn", "igk", "he-pn", "igk-pn", "igk-he".
const char* preprocessing_name(Preprocessing p);

struct PatchNormConfig {
  // Patch size in pixels. The image is split into max(1, W / patch_width) columns and
  // max(1, H / patch_height) rows of patches with boundaries at floor(k * W / columns), so a
  // remainder widens the last patches instead of leaving a sliver (25 px / 4 -> 4,4,4,4,4,5).
  uint8_t patch_width = 4;
  uint8_t patch_height = 4;
  // Added to the patch standard deviation (grey levels): p' = (p - mean) / (std + epsilon).
  // A zero-variance patch (a white wall) maps to mid-grey instead of dividing by zero.
  UQ8_8 epsilon = UQ8_8::from_int(1);
  // Output scaling back to 8 bits: out = clamp(round(128 + gain * p'), 0, 255), i.e. gain is
  // grey levels per standard deviation (32: +-4 sigma spans the whole range).
  UQ8_8 gain = UQ8_8::from_int(32);
};

struct PreprocessConfig {
  Preprocessing method = Preprocessing::kHistEq;
  PatchNormConfig patch;
};

// kInvalidArgument for an unknown method, a patch dimension of 0, a 1-pixel patch or a zero
// gain; kOk otherwise.
Status check_preprocess_config(const PreprocessConfig& config);

// Applies config.method.
Status preprocess(const PreprocessConfig& config, ImageView in, MutableImageView out);

// HE, eq. 4.3: r' = round(255 * cdf(r)), cdf(r) = (pixels <= r) / pixels. Exact integers.
Status equalise_histogram(ImageView in, MutableImageView out);

// PN, eq. 4.1, with the scaling described in PatchNormConfig. Patch mean and standard
// deviation are exact integer sums; the standard deviation is an integer square root at
// 1/256 grey-level resolution. Agrees with the double-precision formula to within one grey
// level (differences only where the exact value is within ~1e-3 of a rounding tie).
Status patch_normalise(const PatchNormConfig& config, ImageView in, MutableImageView out);

// iGK, eq. 4.4: r' = round(255 * (r / 255)^(1 / 0.45)), from a 256-entry table that
// tests/unit/test_preprocess.cpp checks entry by entry against the double formula.
Status inverse_gamma(ImageView in, MutableImageView out);

}  // namespace seqslam
