// The greedy heuristic online matcher (2015 thesis, section 5.3.1, Algorithm 1), designed for
// the 72 MHz / 64 KB head board: instead of a difference matrix it follows at most k places.
//
// A sequence is S consecutive query images. Per sequence:
//  1. Greedy "take the best, leave the rest" (first query image of the sequence, offset 0):
//     the distance to every library place 0..M-1 is evaluated once, in place order, through
//     the PlaceDistance interface (SAD units, like difference.h: MAD, later tangent distance).
//     Guard-window rule, exactly: a place j with d(j) < threshold * A starts a tracked
//     minimum m = j; while the scan is inside the guard window (j' <= m + guard) a strictly
//     smaller distance moves the minimum there and re-centres the window (the window slides
//     while distances keep decreasing); the first place beyond m + guard (or the library end)
//     finishes m as a local minimum, and that place may start the next tracked minimum. So
//     every finished minimum is a strict minimum of [m, m + guard] and consecutive minima are
//     more than `guard` places apart. Of all finished minima the k with the smallest distance
//     are kept (ties: the smaller place wins). Unlike line 12 of the pseudocode, a tracked
//     minimum is started whether or not the candidate set is full, so the set of minima does
//     not depend on k (k only truncates it).
//  2. Follow the trail (offsets 1..S-1): for each candidate with start place p the distance of
//     query image `offset` to place p + offset is added to its sum. A trail that would leave
//     the library (p + offset >= the number of places given to that step) is DROPPED: it can
//     no longer be a full sequence and is never reported again.
//  3. After the S-th image the candidate with the smallest sum (ties: smaller start) is the
//     answer; place = start + S - 1 (the library place of the last query image, as the diagonal
//     matcher reports the end of its sequence), or -1 ("unknown place") when no place was
//     below the threshold at offset 0 or every trail was dropped.
//
// A step budget (HeuristicConfig::scan_places, for the head board): the greedy scan of the
// first image may be spread over several steps, scan_places library places a step, with the
// first image (query step `first`) kept by the PlaceDistance provider. The steps during the
// scan only advance it; its candidate set so far is the anytime answer (`scanning`, never a
// final answer). Once it completes, each later step compares its image with every
// candidate's place start + (step - first) - one library place per step along the trail, as
// both runs are sampled every 20 cm - until S images (the first and S - 1 on the trails)
// have been compared: the steps the scan took are skipped, not compared. With scan_places 0
// (the default) the scan takes one step and this is exactly Algorithm 1 as above.
//
// Sequences are DISJOINT: the step after a sequence ends starts the next one with a new greedy
// scan. Overlapping sequences (a new one starting at every step) would need a greedy O(M) scan
// every step plus S live candidate sets (S k trails, S k distance evaluations a step), i.e. at
// least the diagonal matcher's O(M) per step and S times the memory - the budget the heuristic
// exists to avoid on the head board. Disjoint sequences give a final answer every S images and
// an anytime answer (current()) in between.
//
// Cost per query image: offset 0: M distance evaluations + O(M + k) bookkeeping; offsets
// 1..S-1: at most k distance evaluations + O(k). Averaged over a sequence (M + (S-1) k) / S
// evaluations a step. Memory: O(k) fixed-size members (kMaxHeuristicCandidates), no
// difference matrix, nothing caller-owned; the stack holds one candidate set (step() commits
// only on success).
//
// Confidence (same direction as the diagonal matcher: smaller is more certain, in [0, 1]):
// best sum / smallest sum among the other live candidates whose current place is more than R
// places from the best's, rounded to UQ16.16; exactly 1.0 when there is no such candidate (or
// its sum is 0). The sums are raw distances (no local normalisation and no offset shift), so
// the ratio has the diagonal matcher's meaning but not its scale: tune its threshold
// separately. Candidates are guard-separated local minima of the first image, so with
// R < guard every other candidate is a runner-up.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/limits.h"
#include "seqslam/status.h"

namespace seqslam {

// The largest k (candidates followed per sequence): the size of the matcher's member arrays.
inline constexpr uint16_t kMaxHeuristicCandidates = 16;

// Distance between a query image and a library place, in SAD units (smaller = more alike).
// `query` is the matcher's step index since reset (HeuristicMatcher::query()), so an
// implementation may keep several query images; `place` < the place count given to step().
// The images may live on the SD card (PlaceImages); storage errors are returned and make
// step() fail without changing the matcher.
class PlaceDistance {
 public:
  Status distance(uint32_t query, uint32_t place, uint32_t* out) {
    if (out == nullptr) return Status::kInvalidArgument;
    return do_distance(query, place, out);
  }
  // out[i] = distance(query, first + i) for i < count: the greedy scan's batched form, so an
  // implementation can stream the library (the default asks one place at a time).
  Status distances(uint32_t query, uint32_t first, uint32_t count, uint32_t* out) {
    if (out == nullptr) return Status::kInvalidArgument;
    return do_distances(query, first, count, out);
  }

 protected:
  PlaceDistance() = default;
  ~PlaceDistance() = default;
  PlaceDistance(const PlaceDistance&) = default;
  PlaceDistance& operator=(const PlaceDistance&) = default;

 private:
  virtual Status do_distance(uint32_t query, uint32_t place, uint32_t* out) = 0;
  virtual Status do_distances(uint32_t query, uint32_t first, uint32_t count, uint32_t* out) {
    for (uint32_t i = 0; i < count; ++i) {
      SEQSLAM_TRY(do_distance(query, first + i, out + i));
    }
    return Status::kOk;
  }
};

struct HeuristicConfig {
  uint16_t candidates = 5;  // k, 1..kMaxHeuristicCandidates
  // A place may become a candidate iff its distance < threshold * A (A = pixels): grey levels
  // per pixel (MAD units), UQ8.8. 0 accepts nothing (every sequence is "unknown").
  UQ8_8 threshold = UQ8_8::from_int(40);
  uint16_t guard = 5;       // guard window, places past the tracked minimum, >= 1
  uint16_t seq_len = 10;    // S, 1..kMaxSeqLen
  uint16_t exclusion = 10;  // R, places, for the confidence's runner-up
  // Library places the first image's greedy scan evaluates per step; 0 = all in the first
  // step (see "A step budget" above).
  uint16_t scan_places = 0;
};

// Which setting check_heuristic_config rejected.
enum class HeuristicIssue : uint8_t {
  kNone = 0,
  kCandidatesOutOfRange,  // candidates 0 or > kMaxHeuristicCandidates
  kGuardZero,             // guard 0
  kSeqLenOutOfRange,      // seq_len 0 or > kMaxSeqLen
  kPixelsOutOfRange,      // pixels 0 or > kMaxPixels
};

// Short stable text of an issue, e.g. "heuristic.candidates must be 1..16".
const char* heuristic_issue_text(HeuristicIssue issue);

// kOutOfRange for every issue above (and *issue names it when not null; kNone on kOk).
Status check_heuristic_config(const HeuristicConfig& config, uint32_t pixels,
                              HeuristicIssue* issue = nullptr);

// The matcher's answer after a step (or at any time through current()).
struct HeuristicMatch {
  uint32_t query = 0;      // step index of the last step since reset
  uint16_t offset = 0;     // steps since the sequence's first image (0..S-1 without a budget)
  bool complete = false;   // S images compared: `place` is the sequence's final answer
  bool scanning = false;   // the first image's greedy scan is not finished: a partial answer
  int32_t start = -1;      // best candidate's place at offset 0; -1: none (unknown place)
  int32_t place = -1;      // start + offset: the best trail's place now; -1: none
  uint32_t sum = 0;        // its distance sum over offsets 0..offset (SAD units, saturating)
  int32_t runner_up = -1;  // current place of the best candidate more than R away; -1: none
  uint32_t runner_up_sum = 0;
  UQ16_16 confidence = UQ16_16::from_int(1);  // sum / runner_up_sum, see above
  uint16_t candidates = 0;                    // live candidates (trails not dropped)
};

class HeuristicMatcher {
 public:
  // Adopts the configuration for images of `pixels` pixels and resets. Statuses of
  // check_heuristic_config (nothing changes then).
  Status configure(const HeuristicConfig& config, uint32_t pixels);

  // Forgets the current sequence: the next step is offset 0 (a greedy scan), query() 0.
  void reset();

  // One query image. `places` is the library size M for this step (the library may grow
  // between steps; a scan spread over steps scans the size of its first step). Offset 0
  // evaluates distance(query(), j) for j = 0..M-1 (with a budget: scan_places of them, and
  // the rest on later steps as distance(first, j)), later steps distance(query(), start +
  // offset) per live candidate. Returns kFailedPrecondition before
  // configure(); a PlaceDistance error is returned unchanged and leaves the matcher and *out
  // untouched (the step may be retried). On kOk *out (if not null) equals current().
  Status step(PlaceDistance& distance, uint32_t places, HeuristicMatch* out);

  // Anytime query, no distance evaluations (O(k)): the best candidate so far with its partial
  // sum, after the last step. Before the first step: query 0, place -1.
  HeuristicMatch current() const;

  const HeuristicConfig& config() const { return config_; }
  // Step index the next step() will pass to PlaceDistance.
  uint32_t query() const { return steps_; }
  // Offset the next step() will have in its sequence (0: it starts a new sequence).
  uint16_t next_offset() const {
    return sequence_done_ || !stepped_ ? 0 : static_cast<uint16_t>(steps_ - first_);
  }
  // Whether the current sequence's greedy scan is still running.
  bool scanning() const { return scanning_; }
  // The live candidates of the current sequence, ordered by start place.
  uint16_t candidate_count() const { return count_; }
  uint32_t candidate_start(uint16_t i) const { return start_[i]; }
  uint32_t candidate_sum(uint16_t i) const { return sum_[i]; }

 private:
  HeuristicConfig config_{};
  uint64_t threshold_area_ = 0;  // threshold.raw() * pixels: d passes iff d * 256 < this
  uint32_t start_[kMaxHeuristicCandidates] = {};
  uint32_t sum_[kMaxHeuristicCandidates] = {};
  uint16_t count_ = 0;
  uint32_t steps_ = 0;
  uint32_t first_ = 0;   // step of the current sequence's first image
  uint16_t trails_ = 0;  // images compared along the trails so far
  // The greedy scan of the first image while it runs over several steps.
  uint32_t scan_next_ = 0;    // next library place
  uint32_t scan_places_ = 0;  // library size it scans (of its first step)
  uint32_t min_place_ = 0;    // the tracked minimum ...
  uint32_t min_d_ = 0;
  bool tracking_ = false;  // ... if any
  bool scanning_ = false;
  bool sequence_done_ = true;  // the next step starts a new sequence
  bool stepped_ = false;       // a step happened since reset
  bool configured_ = false;
};

}  // namespace seqslam
