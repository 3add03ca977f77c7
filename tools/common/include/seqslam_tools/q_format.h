// Host conversions between the core's fixed-point formats and doubles, for tools and scoring
// (never the core: it has no floating point). One place for the scale factors instead of
// 2^32, 65536 and 2^24 literals spelled out at every use; the names say the unit.
#pragma once

#include <stdint.h>

#include <cmath>

#include "seqslam/fixed.h"
#include "seqslam/fixmath.h"

namespace seqslam::tools {

// The value of any Fixed<Rep, F> (Q31.32 metres, Q7.24 edge offsets, UQ16.16 weights, ...).
template <typename Rep, int F>
constexpr double to_double(Fixed<Rep, F> v) {
  return static_cast<double>(v.raw()) / static_cast<double>(uint64_t{1} << F);
}

// The nearest Fixed<Rep, F> to v (no range check: the caller's options bound v).
template <typename Q>
Q from_double(double v) {
  return Q::from_raw(static_cast<decltype(Q{}.raw())>(
      std::llround(v * static_cast<double>(uint64_t{1} << Q::kFracBits))));
}

// A binary angle as signed turns in [-1/2, 1/2), degrees and radians.
constexpr double signed_turns(Angle a) {
  return static_cast<int32_t>(a.bam) / 4294967296.0;
}
constexpr double to_degrees(Angle a) {
  return signed_turns(a) * 360.0;
}
constexpr double to_radians(Angle a) {
  return signed_turns(a) * 6.283185307179586;
}

// The nearest binary angle to `radians` (any value: wrapped to one turn).
inline Angle angle_from_radians(double radians) {
  double turns = radians / 6.283185307179586;
  turns -= std::floor(turns);
  return Angle{static_cast<uint32_t>(static_cast<uint64_t>(std::llround(turns * 4294967296.0)))};
}

}  // namespace seqslam::tools
