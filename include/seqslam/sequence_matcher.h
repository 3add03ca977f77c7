// The diagonal sequence matcher of spatially sampled SeqSLAM (2025 thesis, section 4.4).
//
// Because both runs are sampled every 20 cm, a query sequence and its true library sequence
// advance one place per step together: the cost of "query i is at library place j" is the sum
// along the diagonal of the normalised difference matrix (eq. 4.12)
//
//   P_i(j) = sum_{k=0}^{S-1} D+(i-k, j-k),   best j = argmin P_i(j)       (eq. 4.13)
//
// and the confidence is the best cost over the best cost outside +-R of it (eqs. 4.14-4.16):
// C = P(best) / min_{|j - best| > R} P(j), in [0, 1]; smaller is more certain.
//
// Positive costs online (docs/normalisation.md). Every normalised difference is stored with
// the offset B = sqrt(W), which makes it >= 0 by construction (normalise.h), so the running
// sums can never go negative or overflow. For the confidence ratio the costs are then shifted
// by S times the smallest normalised difference seen since the last reset: the batch tools
// shift the whole matrix by its global minimum, and this is the same rule restricted to the
// part of the matrix an online system has seen. Every term of a current sum has been seen,
// so the shifted costs stay >= 0; argmin is unaffected (a constant per sequence); and the
// confidence keeps the scale the thesis's threshold (about 0.85) was chosen on.
//
// Incremental update (per new query the work grows with M, not M x S):
//   P_i(j) = P_{i-1}(j-1) + D+(i, j) - D+(i-S, j-S)
// using a ring of the last S normalised rows. A per-place run length (how many consecutive
// diagonal cells end at (i, j), capped at S) says when the subtraction is due and when P_i(j)
// covers a full sequence, so the library may grow between steps (loop-closure mode) and the
// matcher can be reset at any time. Places are visited from the last to the first so the ring
// row, P and the run lengths are updated in place.
//
// Memory (caller-owned, see DiagonalMatcherStorage): S x M x 2 bytes of ring, 4 M bytes of
// costs, M bytes of run lengths. All integer arithmetic: P is a sum of at most kMaxSeqLen
// UQ5.11 values (< 2^23).
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/limits.h"
#include "seqslam/normalise.h"
#include "seqslam/span.h"
#include "seqslam/state_io.h"
#include "seqslam/status.h"

namespace seqslam {

struct SequenceConfig {
  uint16_t seq_len = 30;                             // S, 1..kMaxSeqLen
  uint16_t window = 50;                              // W, 0 (off) or 2..kMaxWindow
  UQ8_8 sigma_min = UQ8_8::from_int(1);              // grey levels (MAD), > 0 if W > 0
  uint16_t exclusion = 10;                           // R, places
  UQ16_16 threshold = UQ16_16::from_ratio(85, 100);  // localised iff confidence < this
};

// The result of one step.
struct Match {
  uint32_t query = 0;      // step index since the last reset
  int32_t place = -1;      // best library place (the end of the best sequence); -1: none
  uint32_t cost = 0;       // P(place) as the confidence sees it (shifted, see above), UQ.11
  int32_t runner_up = -1;  // best place with |j - place| > R; -1: none
  uint32_t runner_up_cost = 0;
  // cost / runner_up_cost; exactly 1.0 when there is no runner-up (nothing to compare with is
  // treated as maximally ambiguous) or the runner-up's shifted cost is 0.
  UQ16_16 confidence = UQ16_16::from_int(1);
  bool localised = false;  // place >= 0 and confidence < threshold
};

struct DiagonalMatcherBuffers {
  Span<uint16_t> ring;  // >= seq_len * places
  Span<uint32_t> cost;  // >= places
  Span<uint8_t> run;    // >= places
};

// Storage for up to kPlaces library places and sequences up to kSeqLen, for static
// allocation: `static DiagonalMatcherStorage<450, 30> storage;`.
template <uint32_t kPlaces, uint16_t kSeqLen>
struct DiagonalMatcherStorage {
  static_assert(kPlaces > 0 && kSeqLen > 0 && kSeqLen <= kMaxSeqLen, "bad matcher capacity");
  static constexpr size_t kBytes =
      sizeof(uint16_t) * kSeqLen * kPlaces + sizeof(uint32_t) * kPlaces + sizeof(uint8_t) * kPlaces;
  uint16_t ring[kSeqLen * kPlaces];
  uint32_t cost[kPlaces];
  uint8_t run[kPlaces];

  DiagonalMatcherBuffers buffers() {
    return {Span<uint16_t>(ring, kSeqLen * kPlaces), Span<uint32_t>(cost, kPlaces),
            Span<uint8_t>(run, kPlaces)};
  }
};

// Checks a sequence configuration alone:
//   kOutOfRange      - seq_len 0 or > kMaxSeqLen; window 1 or > kMaxWindow;
//                      threshold > 1.0;
//   kInvalidArgument - sigma_min 0 with window > 0.
Status check_sequence_config(const SequenceConfig& config);

// The confidence every matcher reports: cost / runner_up_cost rounded to nearest, in UQ16.16;
// exactly 1.0 when runner_up_cost is 0 (nothing to compare with). The callers guarantee
// cost <= runner_up_cost, so the result is in [0, 1] and the shift fits 64 bits.
inline UQ16_16 confidence_ratio(uint32_t cost, uint32_t runner_up_cost) {
  if (runner_up_cost == 0) return UQ16_16::from_int(1);
  const uint64_t ratio =
      ((static_cast<uint64_t>(cost) << 16) + runner_up_cost / 2) / runner_up_cost;
  return UQ16_16::from_raw(static_cast<uint32_t>(ratio));
}

class DiagonalMatcher {
 public:
  // Adopts the configuration and buffers and resets. `pixels` is the image area A (the
  // differences fed to step() are SAD units of such images). Returns the statuses of
  // check_sequence_config, kOutOfRange for pixels outside 1..kMaxPixels, and
  // kResourceExhausted if the buffers hold fewer than one place for this seq_len.
  Status configure(const SequenceConfig& config, uint32_t pixels,
                   const DiagonalMatcherBuffers& buffers);

  // Forgets the query history (e.g. after the robot was carried somewhere): the next S-1
  // steps produce no match.
  void reset();

  // One query: `differences[j]` is the raw difference (SAD units) between the current query
  // image and library place j, for the places the query may match (all of a separate
  // library; or the places older than the recent-exclusion gap in loop-closure mode). Places
  // may be added between steps. Returns kFailedPrecondition before configure(), kOutOfRange
  // if more places are given than the buffers hold (nothing is changed then). `out` always
  // describes this step: place -1 until some place has a full sequence of S steps.
  Status step(Span<const uint32_t> differences, Match* out);

  uint32_t capacity() const { return capacity_; }
  uint32_t steps() const { return steps_; }
  const SequenceConfig& config() const { return config_; }
  // Sequence costs of the last step as stored (each term includes the offset B), for reports:
  // cost(j) is valid iff full_sequence(j).
  uint32_t cost(uint32_t place) const { return buffers_.cost[place]; }
  // What the confidence subtracts from stored costs: S times the smallest normalised
  // difference seen since the last reset (0 before the first step).
  uint32_t confidence_offset() const {
    return min_value_ == 0xFFFF ? 0u : static_cast<uint32_t>(config_.seq_len) * min_value_;
  }
  bool full_sequence(uint32_t place) const {
    return place < places_ && buffers_.run[place] == config_.seq_len;
  }
  uint32_t places() const { return places_; }

  // The query history (the rings, costs and runs of every place the buffers hold), to
  // continue a stopped run (state_io.h). Configure with the same settings and buffers first;
  // a restored state beyond them fails the io (kDataLoss) and the matcher is reset.
  template <class Io>
  void state(Io& io) {
    io.tag(state_tag("DIAG"));
    io.field(places_);
    io.field(steps_);
    io.field(min_value_);
    io.array(buffers_.ring);
    io.array(buffers_.cost);
    io.array(buffers_.run);
    if (Io::kReading && !state_valid()) io.fail();
    if (Io::kReading && !io.ok()) reset();
  }

 private:
  bool state_valid() const;
  static constexpr uint32_t kNoPlace = 0xFFFFFFFFu;
  uint32_t best_outside(uint32_t best) const;
  void finish_match(uint32_t best, uint32_t runner_up, Match* out) const;

  SequenceConfig config_{};
  DiagonalMatcherBuffers buffers_{};
  LocalNormaliser normaliser_{};
  uint32_t capacity_ = 0;
  uint32_t places_ = 0;  // number of places in the last step
  uint32_t steps_ = 0;
  uint16_t min_value_ = 0xFFFF;  // smallest D+ since reset
  bool configured_ = false;
};

}  // namespace seqslam
