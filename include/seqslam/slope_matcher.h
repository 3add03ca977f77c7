// Slope search: the sequence matcher of time-sampled SeqSLAM (OpenSeqSLAM, spec section 8).
//
// Without odometry the query and the library are sampled in time, so the query may move
// through the library faster or slower than one place per step. For each library place j and
// each velocity v in [vmin, vmax] the trajectory ending at (i, j) is the straight line that
// moves back v library places per query step:
//
//   T_i(j, v) = sum_{k=0}^{S-1} D+(i-k, j - o_v(k)),   o_v(k) = round(v k)   (half up, below)
//   P_i(j)    = min_v T_i(j, v) over the velocities whose trajectory is full,
//   best j    = argmin P_i(j)
//
// A trajectory is full iff all its S cells exist: the S rows since the last reset, each cell
// inside its row (the library may grow or shrink between steps) and j - o_v(S-1) >= 0 (a
// trajectory that would leave the library has no cost). A place has a cost iff at least one of
// its trajectories is full. With vmin = vmax = 1 this is the diagonal matcher exactly
// (sequence_matcher.h, tests/unit/test_slope_matcher.cpp).
//
// Confidence: exactly the diagonal matcher's rule (sequence_matcher.h): best over best outside
// +-R, both shifted by S times the smallest normalised difference seen since the last reset
// (every term of every full trajectory has been seen, so the shifted costs stay >= 0 and 0.85
// keeps its meaning); 1.0 without a runner-up. Ties go to the lowest place, and for one place
// to the slowest velocity.
//
// Velocities are UQ8_8 values. The search uses vsteps of them, evenly spaced and each rounded
// to UQ8_8 (half up): v_s = vmin + round((vmax - vmin) s / (vsteps - 1)), s = 0..vsteps-1
// (vsteps = 1 needs vmin = vmax). The library index of step i-k is j - o_v(k) with
//   o_v(k) = ceil(v k - 1/2) = floor((2 raw(v) k + 255) / 512),
// i.e. round(j - v k) with ties rounded up, computed exactly in integers (o_v(k) = k for v = 1).
// Defaults (OpenSeqSLAM): vmin = 0.8, vmax = 1.2, vsteps = 5 -> raw 205, 231, 256, 282, 307
// (0.801, 0.902, 1.0, 1.102, 1.199).
//
// Cost per step, M places, V = vsteps: normalisation O(M) (as the diagonal matcher), then for
// each velocity S offsets and, for each place in its valid range, S loads and adds:
// O(M V S) additions (M = 450, V = 5, S = 30: 67 500), against O(M) for the incremental
// diagonal. There is no incremental form: a slope-v trajectory ending at j is not the previous
// step's trajectory ending at j - v when v is not an integer. The best/runner-up scan is O(M).
// Stack: S x 4 bytes of row indices.
//
// Memory (caller-owned, see SlopeMatcherStorage): the ring of the last S normalised rows
// (S x M x 2 bytes, as the diagonal matcher), 4 M bytes of costs, M bytes of best velocity
// index; the object holds the S row lengths. Costs are sums of at most kMaxSeqLen UQ5.11
// values (< 2^23).
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/limits.h"
#include "seqslam/normalise.h"
#include "seqslam/sequence_matcher.h"
#include "seqslam/span.h"
#include "seqslam/status.h"

namespace seqslam {

// Most velocities searched per step.
inline constexpr uint8_t kMaxVelocitySteps = 32;
// Largest velocity (library places per query step), UQ8_8 raw: 4.0.
inline constexpr uint16_t kMaxVelocityRaw = 4 * 256;

struct SlopeConfig {
  SequenceConfig seq{};                    // S, W, sigma_min, R, threshold
  UQ8_8 vmin = UQ8_8::from_ratio(8, 10);   // > 0
  UQ8_8 vmax = UQ8_8::from_ratio(12, 10);  // >= vmin, <= 4.0
  uint8_t vsteps = 5;                      // 1..kMaxVelocitySteps; 1 needs vmin == vmax
};

struct SlopeMatcherBuffers {
  Span<uint16_t> ring;     // >= seq_len * places
  Span<uint32_t> cost;     // >= places
  Span<uint8_t> velocity;  // >= places
};

// Storage for up to kPlaces library places and sequences up to kSeqLen, for static
// allocation: `static SlopeMatcherStorage<450, 30> storage;`.
template <uint32_t kPlaces, uint16_t kSeqLen>
struct SlopeMatcherStorage {
  static_assert(kPlaces > 0 && kSeqLen > 0 && kSeqLen <= kMaxSeqLen, "bad matcher capacity");
  static constexpr size_t kBytes =
      sizeof(uint16_t) * kSeqLen * kPlaces + sizeof(uint32_t) * kPlaces + sizeof(uint8_t) * kPlaces;
  uint16_t ring[kSeqLen * kPlaces];
  uint32_t cost[kPlaces];
  uint8_t velocity[kPlaces];

  SlopeMatcherBuffers buffers() {
    return {Span<uint16_t>(ring, kSeqLen * kPlaces), Span<uint32_t>(cost, kPlaces),
            Span<uint8_t>(velocity, kPlaces)};
  }
};

// Checks a slope configuration alone: the statuses of check_sequence_config, then
//   kOutOfRange      - vsteps 0 or > kMaxVelocitySteps; vmin 0; vmax > 4.0;
//   kInvalidArgument - vmin > vmax; vsteps 1 with vmin != vmax.
Status check_slope_config(const SlopeConfig& config);

// Velocity s (0..vsteps-1) of a valid configuration as a UQ8_8 raw value (see above).
uint16_t slope_velocity_raw(const SlopeConfig& config, uint32_t s);

// o_v(k) for a UQ8_8 raw velocity: round(v k), ties up (so j - o is round(j - v k) half up).
constexpr uint32_t slope_offset(uint32_t velocity_raw, uint32_t k) {
  return (2u * velocity_raw * k + 255u) / 512u;
}

class SlopeMatcher {
 public:
  // Adopts the configuration and buffers and resets. `pixels` is the image area A. Returns
  // the statuses of check_slope_config, kOutOfRange for pixels outside 1..kMaxPixels, and
  // kResourceExhausted if the buffers hold fewer than one place for this seq_len.
  Status configure(const SlopeConfig& config, uint32_t pixels, const SlopeMatcherBuffers& buffers);

  // Forgets the query history: the next S-1 steps produce no match.
  void reset();

  // One query, as DiagonalMatcher::step: raw differences (SAD units) to the places the query
  // may match, normalised inside exactly as the diagonal matcher does. Returns
  // kFailedPrecondition before configure(), kOutOfRange if more places are given than the
  // buffers hold (nothing is changed then). `out` always describes this step.
  Status step(Span<const uint32_t> differences, Match* out);

  uint32_t capacity() const { return capacity_; }
  uint32_t steps() const { return steps_; }
  const SlopeConfig& config() const { return config_; }
  // Costs of the last step as stored (each term includes the offset B), for reports:
  // cost(j) = P_i(j), valid iff full_sequence(j).
  uint32_t cost(uint32_t place) const { return buffers_.cost[place]; }
  bool full_sequence(uint32_t place) const {
    return place < places_ && buffers_.velocity[place] != kNoVelocity;
  }
  // The velocity (UQ8_8 raw) of place j's cheapest full trajectory; valid iff full_sequence(j).
  uint16_t velocity_raw(uint32_t place) const { return velocity_[buffers_.velocity[place]]; }
  // Index s of that velocity (0..vsteps-1); valid iff full_sequence(j).
  uint8_t velocity_index(uint32_t place) const { return buffers_.velocity[place]; }
  // What the confidence subtracts from stored costs: S times the smallest normalised
  // difference seen since the last reset (0 before the first step).
  uint32_t confidence_offset() const {
    return min_value_ == 0xFFFF ? 0u : static_cast<uint32_t>(config_.seq.seq_len) * min_value_;
  }
  uint32_t places() const { return places_; }

 private:
  static constexpr uint8_t kNoVelocity = 0xFF;
  static constexpr uint32_t kNoPlace = 0xFFFFFFFFu;

  SlopeConfig config_{};
  SlopeMatcherBuffers buffers_{};
  LocalNormaliser normaliser_{};
  uint32_t capacity_ = 0;
  uint32_t places_ = 0;                 // number of places in the last step
  uint32_t steps_ = 0;                  // steps since reset
  uint32_t row_size_[kMaxSeqLen] = {};  // places of the row in each ring slot
  uint16_t velocity_[kMaxVelocitySteps] = {};
  uint16_t min_value_ = 0xFFFF;  // smallest D+ since reset
  bool configured_ = false;
};

}  // namespace seqslam
