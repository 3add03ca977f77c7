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

// The same angle read as unsigned: turns in [0, 1) and radians in [0, 2 pi) (the simulator's
// ground-truth files keep this range).
constexpr double unsigned_turns(Angle a) {
  return static_cast<double>(a.bam) / 4294967296.0;
}
constexpr double to_unsigned_radians(Angle a) {
  return unsigned_turns(a) * 6.283185307179586;
}

namespace detail {
// `radians` as a fraction of a turn in [0, 1) (any value: wrapped to one turn).
inline double wrapped_turns(double radians) {
  const double turns = radians / 6.283185307179586;
  return turns - std::floor(turns);
}
}  // namespace detail

// The nearest binary angle to `radians` (any value: wrapped to one turn).
inline Angle angle_from_radians(double radians) {
  return Angle{static_cast<uint32_t>(
      static_cast<uint64_t>(std::llround(detail::wrapped_turns(radians) * 4294967296.0)))};
}

// The nearest 16-bit binary angle (1/65536 turn, as the dream header's infrared mounts store
// it) to `radians`, rounded directly to 16 bits (not via the 32-bit angle, which could round
// twice).
inline uint16_t angle16_from_radians(double radians) {
  return static_cast<uint16_t>(std::llround(detail::wrapped_turns(radians) * 65536.0) & 0xFFFF);
}

}  // namespace seqslam::tools
