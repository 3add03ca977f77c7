// A candidate place followed along its diagonals, step by step: the route search's second
// hypothesis (route_search.h; docs/firmware.md, "Localising on a whole route").
//
// When the relocalisation scan names a place away from the odometry's prediction, the route
// search must decide between the two from the evidence of the next places, while its window
// keeps tracking the prediction. The probe is the candidate's evidence: for kProbeSlots
// consecutive diagonals centred on the candidate's (d = place - step), the sum of the
// normalised differences over every step since `first`, the first query image of the scan
// that named it. Its values are exactly the window matcher's (a window matcher of
// kProbeSlots diagonals with a sequence of one step computes them: the same band, the same
// local normalisation, the same code), so after L steps the sums are L-step sequence costs,
// directly comparable with the main window's last L values at the prediction
// (WindowMatcher::recent_cost). Its steps before it began are caught up from the query
// history (read back from the card), then it grows by one step a place.
//
// Memory: a sum per diagonal and the one-step window matcher's 7 bytes a diagonal
// (SequenceProbeStorage: 99 bytes), whatever the library. Work per step: kProbeSlots + W
// library images differenced.
#pragma once

#include <stdint.h>

#include "seqslam/sequence_matcher.h"
#include "seqslam/span.h"
#include "seqslam/status.h"
#include "seqslam/window_matcher.h"

namespace seqslam {

// Diagonals a probe follows: the candidate's and 4 either side, so that its best can move by
// the slack (2) and still be compared with diagonals 2 places away (its sharpness).
inline constexpr uint32_t kProbeSlots = 9;

// The probe's best diagonal within a radius of its centre.
struct ProbeBest {
  bool found = false;
  int32_t diagonal = 0;
  uint32_t cost = 0;   // the diagonal's sum over steps() steps (UQ.11 units, no offset)
  uint32_t local = 0;  // the lowest sum of a diagonal >= 2 away from it (0xFFFFFFFF: none)
};

// Caller-owned: a one-step window of kProbeSlots diagonals and a sum per diagonal.
struct SequenceProbeBuffers {
  WindowMatcherBuffers window;
  Span<uint32_t> sum;  // >= kProbeSlots
};

// The probe's storage: a one-step window matcher of kProbeSlots diagonals and their sums.
struct SequenceProbeStorage {
  WindowMatcherStorage<kProbeSlots, 1> window;
  uint32_t sum[kProbeSlots];
  static constexpr size_t kBytes = WindowMatcherStorage<kProbeSlots, 1>::kBytes + 4 * kProbeSlots;
  SequenceProbeBuffers buffers() { return {window.buffers(), Span<uint32_t>(sum, kProbeSlots)}; }
};

class SequenceProbe {
 public:
  // Adopts W and sigma_min of `config` for images of `pixels` pixels on `buffers` (its S is
  // the probe's longest evidence). The window matcher's statuses; kResourceExhausted for
  // buffers of fewer than kProbeSlots diagonals.
  Status configure(const SequenceConfig& config, uint32_t pixels,
                   const SequenceProbeBuffers& buffers);

  // Follows the diagonals centred on `centre` with evidence from step `first` on (the next
  // add() must be of step `first`).
  void start(int32_t centre, uint32_t first);
  void stop() { active_ = false; }
  bool active() const { return active_; }

  // The places whose raw differences add() needs for the next step against a library of
  // `places` places (the diagonals' places widened by W/2 each side, clipped; count 0: no
  // diagonal of the probe has a place in the library then).
  PlaceBand band(uint32_t places) const { return matcher_.band(places); }
  // The next step's evidence, as WindowMatcher::step (a diagonal whose place is outside the
  // library ends its run and is not followed further). kFailedPrecondition unless active.
  Status add(uint32_t places, Span<const uint32_t> band_differences);

  // The best diagonal within `radius` of the centre that has had a place at every step since
  // `first`, with its sharpness (the lowest such sum 2 or more diagonals away).
  ProbeBest best(uint32_t radius) const;

  int32_t centre() const { return centre_; }
  uint32_t first() const { return first_; }
  uint32_t next_step() const { return matcher_.steps(); }
  uint32_t steps() const { return matcher_.steps() - first_; }  // L: the steps summed

 private:
  WindowMatcher matcher_{};
  Span<uint32_t> sum_{};
  uint32_t alive_ = 0;  // bit k: diagonal centre - 4 + k has had a place at every step
  int32_t centre_ = 0;
  uint32_t first_ = 0;
  bool active_ = false;
};

}  // namespace seqslam
