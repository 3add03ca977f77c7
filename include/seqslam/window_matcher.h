// The diagonal matcher restricted to a window of diagonals: what the head board runs while it
// knows roughly where it is (docs/firmware.md, "Localising on a whole route").
//
// Both runs of a route are sampled every 20 cm, so while the robot follows the taught route
// its place advances one library place per step: the true place lies on a diagonal
// d = place - step of the difference matrix, and odometry says which diagonals are possible.
// The matcher keeps the sequence costs of a window of `width` consecutive diagonals
// [first, first + width) only, so its memory and its work per step depend on the window, not on
// the library's length M:
//
//   per step: the raw differences of the band of places the window's diagonals cross this
//             step, widened by W/2 on each side for the local normalisation (width + W places);
//   memory:   a ring of the last S normalised differences, a cost and a run length per slot
//             (2 S + 5 bytes a slot, WindowMatcherStorage).
//
// The arithmetic is the diagonal matcher's (sequence_matcher.h), term for term: the same
// normalised values (each place's normalisation window is clipped to the library as in the
// whole row, normalise.h), the same incremental sums and run lengths (a diagonal's run ends at
// a step where it has no place, e.g. before place 0 or past the library's end), the same
// offset rule (S times the smallest normalised value this matcher has computed since reset)
// and the same tie rules (lowest place). So a window that covers every diagonal gives exactly
// the diagonal matcher's answers (tests/unit/test_window_matcher.cpp). A narrower window
// differs in what it cannot see: a place outside it is never the answer, and the confidence's
// runner-up is the best sequence outside +-R *within the window*, not in the whole library.
//
// Moving the window (place()) keeps the history of the diagonals that stay in it; a diagonal
// that enters starts with no history and has a full sequence S steps later.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/normalise.h"
#include "seqslam/sequence_matcher.h"
#include "seqslam/span.h"
#include "seqslam/status.h"

namespace seqslam {

struct WindowMatcherBuffers {
  Span<uint16_t> ring;  // >= seq_len * slots: the last S normalised values of each slot
  Span<uint32_t> cost;  // >= slots
  Span<uint8_t> run;    // >= slots
};

// Storage for a window of up to kSlots diagonals and sequences up to kSeqLen, for static
// allocation: `static WindowMatcherStorage<48, 30> storage;` (2 S + 5 bytes a slot).
template <uint16_t kSlots, uint16_t kSeqLen>
struct WindowMatcherStorage {
  static_assert(kSlots > 0 && kSeqLen > 0 && kSeqLen <= kMaxSeqLen, "bad window capacity");
  static constexpr size_t kBytes =
      sizeof(uint16_t) * kSeqLen * kSlots + sizeof(uint32_t) * kSlots + sizeof(uint8_t) * kSlots;
  uint16_t ring[kSeqLen * kSlots];
  uint32_t cost[kSlots];
  uint8_t run[kSlots];

  WindowMatcherBuffers buffers() {
    return {Span<uint16_t>(ring, kSeqLen * kSlots), Span<uint32_t>(cost, kSlots),
            Span<uint8_t>(run, kSlots)};
  }
};

// A range of library places [first, first + count); count 0 = none.
struct PlaceBand {
  uint32_t first = 0;
  uint32_t count = 0;
};

class WindowMatcher {
 public:
  // Adopts the configuration and buffers and resets (window empty: place() it). `pixels` as
  // for DiagonalMatcher. Statuses of check_sequence_config, kOutOfRange for pixels outside
  // 1..kMaxPixels, kResourceExhausted if the buffers hold no slot for this seq_len.
  Status configure(const SequenceConfig& config, uint32_t pixels,
                   const WindowMatcherBuffers& buffers);

  // Forgets all history (every slot empty, step 0, smallest value seen reset); the window
  // keeps its position.
  void reset();

  // A step without a query (the route search pauses the window while its relocalisation scan
  // runs): every run ends, as for a step whose places all lie outside the library; the step
  // counter advances.
  void skip();

  // Sets the window to diagonals [first, first + width). Diagonals in both the old and the
  // new window keep their history; the others start empty. kOutOfRange (nothing changed) if
  // width is 0 or above slots(), or first + width overflows int32.
  Status place(int32_t first, uint32_t width);

  // The places whose raw differences the next step() needs when the library offers `places`
  // places: the window's places this step, widened by W/2 each side, clipped to the library.
  PlaceBand band(uint32_t places) const;

  // One query: `band_differences` holds the raw differences (SAD units) of exactly the places
  // band(places) returned, in order. Updates every slot of the window. `out` gets the best
  // full sequence among the diagonals [search_first, search_last] (clipped to the window) and
  // its confidence against the best full sequence more than R places away anywhere in the
  // window (Match fields as DiagonalMatcher::step; place -1 when no diagonal in the search
  // range has a full sequence). kFailedPrecondition before configure(); kInvalidArgument if
  // band_differences is not band(places) long (nothing changes then).
  Status step(uint32_t places, Span<const uint32_t> band_differences, int32_t search_first,
              int32_t search_last, Match* out);

  uint32_t slots() const { return slots_; }
  int32_t first() const { return first_; }
  uint32_t width() const { return width_; }
  uint32_t steps() const { return steps_; }
  const SequenceConfig& config() const { return config_; }
  // The diagonal (place - step) of a library place at the current step (the next step()).
  int32_t diagonal_of(int32_t place) const { return place - static_cast<int32_t>(steps_); }
  // Whether diagonal d has a full sequence after the last step, and its stored cost.
  bool full_sequence(int32_t d) const;
  uint32_t cost(int32_t d) const;
  // Diagonal d's sequence cost over its last `steps` values (1..S) after the last step:
  // UINT32_MAX unless d is in the window with a run of at least that many steps.
  uint32_t recent_cost(int32_t d, uint32_t steps) const;
  // The normalisation's offset B (UQ5.11): the value of a difference at its window's mean.
  uint16_t value_offset() const { return normaliser_.offset_raw(); }
  // The smallest normalised value computed since reset (0xFFFF before the first value).
  uint16_t min_value() const { return min_value_; }
  // Back to step `step` with every slot empty (the smallest value seen is kept): the route
  // search replays the steps since then from its query history to give the window's new
  // diagonals their history at once (RouteSearch, "re-seeding").
  void rewind(uint32_t step);
  // S times the smallest normalised value computed since reset (0 before the first value).
  uint32_t confidence_offset() const {
    return min_value_ == 0xFFFF ? 0u : static_cast<uint32_t>(config_.seq_len) * min_value_;
  }

 private:
  uint32_t slot(int32_t d) const;
  bool in_window(int32_t d) const {
    return d >= first_ && static_cast<uint32_t>(d - first_) < width_;
  }
  void clear_slot(uint32_t s);
  // Best full sequence in [lo, hi] (lowest diagonal on ties), or `kNone`.
  int32_t best_in(int32_t lo, int32_t hi, bool skip_near, int32_t centre) const;

  static constexpr int32_t kNone = INT32_MIN;

  SequenceConfig config_{};
  WindowMatcherBuffers buffers_{};
  LocalNormaliser normaliser_{};
  uint32_t slots_ = 0;
  int32_t first_ = 0;
  uint32_t width_ = 0;
  uint32_t steps_ = 0;
  uint16_t min_value_ = 0xFFFF;
  bool configured_ = false;
};

}  // namespace seqslam
