// Where along the matched pass a loop closure's current place lies (issue 7; docs/mapping.md,
// "Closure alignment along the pass").
//
// The sequence matcher's answer is the library place whose *sequence* of plain image
// differences best fits the current one. Between two passes of the same route the robot's
// heading differs by a few degrees, which shifts every image sideways by a column or two; the
// plain differences then prefer a place up to three places (60 cm) behind or ahead of the
// right one (seen on the simulator's explore runs: 0.22 m RMS along the route, up to 0.6 m).
// A closure edge that claims "same position" pulls the two passes together with that error.
//
// align_closure() re-examines the neighbourhood of the matched place with shift-tolerant
// differences: for each candidate offset k in [-max_offset, max_offset] it sums
//   P(k) = sum_{t < L} shift_tolerant_sad(image(matched + k - t), image(current - t), max_shift)
// over the last L places (the current one and L - 1 before it, compared along the diagonal as
// the matcher does), takes the smallest P (ties to the smallest |k|, then negative k) and
// refines it to a fraction of a place by the vertex of the parabola through it and its two
// neighbours (parabola_vertex_q16, fixmath.h). The caller turns the answer into a closure
// edge from `place` to the current node with dx = fraction x the place spacing (the
// capture distance, 20 cm on Myon). On the explore runs (seed 1, L = 15, max_offset 5,
// max_shift 2) the along-route error of the closures falls from 0.22 to 0.10 m RMS.
//
// Candidates: a place p = matched + k qualifies when p < known (the places the caller lets
// closures reach: not the current run's most recent ones) and its sequence p - L' + 1 .. p
// exists, where L' = min(L, current + 1, matched + 1) is the length actually compared; the
// matched place itself always qualifies. The fraction is refined only when both neighbours
// of the best candidate qualified; at the search's ends it is 0.
//
// Cost: L' x (2 max_offset + 1) shift-tolerant differences, each (2 max_shift + 1) SADs
// over the overlap; L' x (2 max_offset + 2) image reads from the library (the current image
// is copied to `scratch` because a read may evict it from a card-backed image cache).
#pragma once

#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/fixmath.h"
#include "seqslam/place_library.h"
#include "seqslam/span.h"
#include "seqslam/status.h"

namespace seqslam {

// Bounds of the configuration (the profile lives on the stack: 8 bytes per candidate).
inline constexpr uint8_t kMaxAlignOffset = 8;
inline constexpr uint8_t kMaxAlignLength = 64;

struct ClosureAlignConfig {
  uint8_t length = 15;     // L: places compared along the diagonal, 1..kMaxAlignLength
  uint8_t max_offset = 5;  // places searched each way of the matched one, 0..kMaxAlignOffset
  uint8_t max_shift = 2;   // columns each image pair may be shifted (shift_tolerant_sad)
};

struct ClosureAlignment {
  uint32_t place = 0;       // the library place the current one lies nearest to
  Q15_16 fraction{};        // how far past `place` (towards place + 1), in places, [-1/2, 1/2]
  Q15_16 offset{};          // place + fraction - matched: the whole correction, in places
  uint32_t compared = 0;    // L': places compared per candidate
  uint32_t candidates = 0;  // candidates that qualified (1 .. 2 max_offset + 1)
};

// Aligns the closure between library places `matched` and `current` (current image already
// in the library, e.g. appended by Localiser::observe). `scratch` holds one image (at least
// image_size().pixels() bytes). Returns:
//   kInvalidArgument   - null `out`, length 0 or > kMaxAlignLength, max_offset >
//                        kMaxAlignOffset, max_shift >= the image width, or scratch too small;
//   kOutOfRange        - current >= library.size() (an unconfigured library is empty),
//                        known > current, or matched >= known;
//   the library's storage errors (kDataLoss, kUnavailable) as they come.
// On any error *out is left unchanged.
Status align_closure(PlaceLibrary& library, uint32_t current, uint32_t matched, uint32_t known,
                     const ClosureAlignConfig& config, Span<uint8_t> scratch,
                     ClosureAlignment* out);

// A distance in places as metres along the route: places x spacing (the capture distance),
// rounded to nearest 2^-32 m. |places| < 2^15 and spacing < 2^16 m keep it exact.
inline Q31_32 along_route(Q15_16 places, Q31_32 spacing) {
  return Q31_32::from_raw(mul_shift_round(places.raw(), spacing.raw(), 16));
}

}  // namespace seqslam
