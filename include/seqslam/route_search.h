// Localising on a whole route with memory and work per step that do not grow with the route
// (the head board's search; docs/firmware.md, "Localising on a whole route").
//
// Three parts, all exact pieces of the diagonal matcher, running side by side at every step:
//  - tracking (window_matcher.h): only the diagonals odometry allows are searched: a window
//    of `window` diagonals centred on the prediction (the diagonal of the last fix; one
//    library place per step along it). The answer is the best full sequence within `slack +
//    growth x places since the last fix` of the prediction, its runner-up the best more than
//    R places away anywhere in the window. A fix needs more than the ratio: its minimum must
//    be sharp (its cost below `sharpness` times that of the best diagonal 2..R places away,
//    both of which must exist: a place known to +-1, not a blur along the corridor) and its
//    sequence must still match at its end (the mean of its last `tail_steps` values below
//    `tail_level` times the normalisation's mean: a route that has left the library is not a
//    fix for the S - tail steps its sequence still remembers). A fix moves the prediction.
//  - the scan (sequence_scan.h): the full search at one anchor step over the whole library
//    with a sequence of scan_seq_len, streamed in the time between places and started again
//    at the latest step as soon as it completes (ceil(M / scan_places) steps a scan). A
//    confident scan near the prediction confirms it; one elsewhere names a candidate.
//  - the candidate (sequence_probe.h): a second hypothesis, followed with odometry along its
//    diagonals from the scan's first query image on (caught up from the query history, then
//    one step a place), while the window keeps tracking the prediction. The evidence decides:
//    once it has `jump_steps` steps, the candidate wins if its cost over them is below
//    `jump_ratio` times the prediction's over the same steps (and its minimum is sharp); it
//    is dropped as soon as the prediction explains them better, after `lost_after` steps, or
//    when a scan confirms the prediction. While it is followed the window's answers are not
//    fixes ("not sure"). When it wins, its answer is this step's fix, the prediction moves
//    there and the window is re-seeded: its new diagonals replay the last S steps from the
//    query history (between places, in slices, before the scan's share), so it tracks with
//    full sequences at once. With no
//    prediction (an unknown start) the first candidate with jump_steps of sharp evidence wins.
//    One candidate is followed at a time (a newer confident scan elsewhere waits until it is
//    decided).
//    Past the library's end the prediction has no places: a candidate is then not disputed
//    (a loop route is found again at its start this way; the library does not know its loops).
//
// Per step: (window + W) library images read and differenced, (9 + W) more while a candidate
// is followed, plus the scan's scan_places x scan_seq_len differences and reads, and after a
// jump S replayed steps of (window + W) differences each; RAM: the window's 2 S + 5 bytes a
// diagonal, its band of (window + W) differences, the scan's buffers (~2 KB at scan_seq_len =
// 10, W = 50, and its query images where they are kept in RAM), the candidate's 56 bytes, the
// query history's RAM part and the route search's own state: all independent of the
// library's length.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/image.h"
#include "seqslam/place_library.h"
#include "seqslam/query_history.h"
#include "seqslam/sequence_matcher.h"
#include "seqslam/sequence_probe.h"
#include "seqslam/sequence_scan.h"
#include "seqslam/span.h"
#include "seqslam/status.h"
#include "seqslam/window_matcher.h"

namespace seqslam {

struct RouteSearchConfig {
  // Diagonals the window keeps (odd: the prediction and (window - 1) / 2 either side); at
  // least 2 R + 3 so that a runner-up can exist, at most the window storage's slots.
  uint16_t window = 25;
  // Places either side of the prediction the answer may be right after a fix ...
  uint16_t slack = 2;
  // ... growing by this many places per place travelled without a fix (odometry's drift along
  // the route between two runs: 1/20 = 5 %).
  UQ8_8 growth = UQ8_8::from_ratio(1, 20);
  // The longest a candidate is followed (>= 1; at least jump_steps, S if longer): steps of its
  // evidence after which it is dropped unless it has won.
  uint16_t lost_after = 30;
  // Library places the scan streams per step (>= 1): its share of the time between places
  // (each costs scan_seq_len differences and the place's image from the card;
  // docs/performance.md, "The time between places").
  uint16_t scan_places = 1024;
  // The scan's sequence length (>= 1; S if longer): the full search it computes is over this
  // many steps.
  // Shorter than S because the scan compares every library place with each of them (its time
  // and card reads grow with it) and keeps a ring of differences per row (its RAM grows with
  // it); a shorter sequence is more easily fooled, which is why a jump waits for a second
  // scan that shares none of its images, and why the window, which confirms where the robot
  // is, keeps S.
  uint16_t scan_seq_len = 10;
  // The library place the run starts at (teach and repeat: 0, the route's start), or -1 when
  // unknown: then nothing is localised until a scan has found the place.
  int32_t start = 0;
  // Steps of evidence a candidate needs before it may win (>= 1; S if longer), and the ratio of its cost
  // over them to the prediction's below which it wins (0.5: half as far from the query images).
  uint16_t jump_steps = 14;
  UQ16_16 jump_ratio = UQ16_16::from_ratio(1, 2);
  // A candidate no prediction disputes (an unknown start, a prediction past the library's
  // end) must match its query images on its own: its mean value over its evidence below this
  // times the normalisation's offset B (0.8: a mean z-score below -sqrt(W) / 5; 0: no test).
  UQ16_16 match_level = UQ16_16::from_ratio(4, 5);
  // A fix's cost over the lowest of the diagonals 2..R away must be below this (0: no test).
  UQ16_16 sharpness = UQ16_16::from_ratio(17, 20);
  // A fix's last tail_steps normalised values (0: no test; S if longer) must average below tail_level
  // times the normalisation's offset B (the value of a difference at its window's mean).
  uint16_t tail_steps = 5;
  UQ16_16 tail_level = UQ16_16::from_ratio(9, 10);
};

// Which setting is wrong (check_route_search_config).
enum class RouteIssue : uint8_t {
  kNone = 0,
  kWindowOutOfRange,      // window even, < 2 R + 3, or above the storage's slots
  kLostAfterZero,         // lost_after 0
  kScanPlacesZero,        // scan_places 0
  kScanSeqLenOutOfRange,  // scan_seq_len 0
  kStartOutOfRange,       // start < -1
  kStorageTooSmall,       // band or scan buffers too small for this configuration
  kJumpStepsZero,         // jump_steps 0
};
const char* route_issue_text(RouteIssue issue);
// The settings on their own (no storage): the first issue, or kNone; and the status an issue
// is reported with (kOk for kNone).
RouteIssue check_route_settings(const RouteSearchConfig& config, const SequenceConfig& sequence);
Status route_issue_status(RouteIssue issue);

// The scan's sequence length for these settings: scan_seq_len, at most S.
constexpr uint16_t scan_seq_len(const RouteSearchConfig& route, const SequenceConfig& sequence) {
  return route.scan_seq_len < sequence.seq_len ? route.scan_seq_len : sequence.seq_len;
}

struct RouteSearchBuffers {
  WindowMatcherBuffers window;
  Span<uint32_t> band;  // >= window + 2 (W / 2): one step's raw differences
  SequenceScanBuffers scan;
  SequenceProbeBuffers probe;  // the candidate's (sequence_probe.h)
};

// Storage for windows up to kSlots diagonals, S up to kSeqLen, scans up to kScanSeqLen, W up
// to kWindow and R up to kExclusion, for static allocation; the scan keeps its query images in
// RAM for images up to kScanPixels pixels (0: it reads them from the history every chunk).
template <uint16_t kSlots, uint16_t kSeqLen, uint16_t kScanSeqLen, uint16_t kWindow,
          uint16_t kExclusion, uint32_t kScanPixels = 0>
struct RouteSearchStorage {
  using Scan = SequenceScanStorage<kScanSeqLen, kWindow, kExclusion, kScanPixels>;
  using Probe = SequenceProbeStorage;
  WindowMatcherStorage<kSlots, kSeqLen> window;
  uint32_t band[kSlots + 2u * (kWindow / 2u)];
  Scan scan;
  Probe probe;
  static constexpr size_t kBytes = WindowMatcherStorage<kSlots, kSeqLen>::kBytes +
                                   sizeof(uint32_t) * (kSlots + 2u * (kWindow / 2u)) +
                                   Scan::kBytes + Probe::kBytes;
  RouteSearchBuffers buffers() {
    return {window.buffers(), Span<uint32_t>(band, kSlots + 2u * (kWindow / 2u)), scan.buffers(),
            probe.buffers()};
  }
};

// What the search did at a step, beside its answer (for the firmware's counters and tests).
struct RouteStepInfo {
  bool tracking = false;        // a prediction exists (the start was known, or a scan found it)
  bool probation = false;       // a candidate (a scan's place elsewhere) is being followed
  int32_t prediction = 0;       // the predicted diagonal (place - step) during this step
  uint16_t search_radius = 0;   // places either side of the prediction the answer could be
  bool fix = false;             // this step's answer was a fix (confident, within the radius)
  bool carried = false;         // the answer is the candidate's: it won (a jump) at this step
  // The scan's work since the previous step (the previous step's share):
  bool scan_running = false;    // the scan ran
  bool scan_completed = false;  // ... and completed
  bool scan_jumped = false;     // ... confidently elsewhere: a candidate (a jump)
  uint32_t scan_streamed = 0;   // library places it streamed
  Status scan_status = Status::kOk;  // the scan's storage error this step, if any
};

class RouteSearch {
 public:
  // Checks the route settings against `sequence` and the buffers. kOk or the issue's status.
  static Status check(const RouteSearchConfig& config, const SequenceConfig& sequence,
                      const RouteSearchBuffers& buffers, RouteIssue* issue = nullptr);

  // Adopts the settings, buffers and history for images of `pixels` pixels and resets.
  // Statuses of check() and of the matchers' configure().
  Status configure(const RouteSearchConfig& config, const SequenceConfig& sequence, uint32_t pixels,
                   const RouteSearchBuffers& buffers, QueryHistory& history,
                   RouteIssue* issue = nullptr);

  // Back to the start of a run: step 0, no history, the configured start.
  void reset();

  // Up to `budget` library places of the work between the last step and the next: first the
  // past steps the window's re-seeding or the candidate's catch-up replays from the query
  // history (up to `budget` places of a replayed step's band a call), then the scan's share
  // of the last step (what is left of its scan_places; replays do not shorten it, so a scan
  // keeps the pace the run checks count on), applying a completed scan's verdict. The
  // library places compared. Called in slices between sensor snapshots; what is left when
  // the next step comes, that step does first. Errors are the next step's info.scan_status.
  uint32_t work(PlaceLibrary& library, uint32_t budget);
  // Work left before the next step: library places of the last step's share not streamed
  // yet, plus one for each past step still to replay.
  uint32_t pending() const { return quota_ + replay_pending(); }

  // One query (already preprocessed) against the first `places` places of `library`.
  // Library and history errors before the step's answer pass through with nothing changed
  // (kFailedPrecondition before configure(), kInvalidArgument for a query of another size).
  // A scan's storage error does not fail the step: info->scan_status says it.
  Status step(PlaceLibrary& library, ImageView query, uint32_t places, Match* out,
              RouteStepInfo* info = nullptr);

  uint32_t steps() const { return window_.steps(); }
  const WindowMatcher& window() const { return window_; }
  const SequenceScan& scan() const { return scan_; }
  const RouteSearchConfig& config() const { return config_; }
  bool tracking() const { return tracking_; }
  int32_t prediction() const { return prediction_; }

 private:
  uint16_t radius() const;
  uint16_t radius_after(uint32_t places) const;  // the search radius that many places after a fix
  void place_window();
  Status track(PlaceLibrary& library, ImageView query, uint32_t places, uint32_t step, Match* out,
               RouteStepInfo* info);
  // The window's answer as a fix or not: sharpness, the sequence's end, both neighbours.
  void qualify(uint32_t i, Match* m) const;
  // `ratio` on the threshold's scale: `limit` becomes the threshold.
  UQ16_16 on_scale(UQ16_16 ratio, UQ16_16 limit) const;
  // A sum of `steps` normalised values averages below `level` times the offset B (false for
  // UINT32_MAX: no such sum).
  bool below(uint32_t sum, uint32_t steps, UQ16_16 level) const;
  // The candidate's evidence against the prediction's after step i: it wins, is dropped or
  // waits.
  void decide(uint32_t i, Match* m, RouteStepInfo* info);
  void drop();
  // The steps of evidence a candidate needs (jump_steps, at most S) and the most it is
  // followed for (lost_after, at least the former, at most S).
  uint32_t needed() const {
    return config_.jump_steps < sequence_.seq_len ? config_.jump_steps : sequence_.seq_len;
  }
  uint32_t life() const {
    const uint32_t n = needed();
    const uint32_t l = config_.lost_after > n ? config_.lost_after : n;
    return l < sequence_.seq_len ? l : sequence_.seq_len;
  }
  // A completed scan's verdict, between steps.
  void judge(const ScanResult& result);
  uint32_t replay_pending() const;
  // Up to `budget` places of the band of one past step of the window's re-seeding or the
  // candidate's catch-up (work()); the step is applied when its band is complete. *done: the
  // places compared.
  Status replay(PlaceLibrary& library, uint32_t budget, uint32_t* done);

  RouteSearchConfig config_{};
  SequenceConfig sequence_{};
  Span<uint32_t> band_{};  // one step's raw differences (RouteSearchBuffers::band)
  QueryHistory* history_ = nullptr;
  WindowMatcher window_{};
  SequenceScan scan_{};
  SequenceProbe probe_{};  // the candidate (probation_ while it is followed)
  uint32_t pixels_ = 0;
  bool configured_ = false;
  bool tracking_ = false;
  bool probation_ = false;
  int32_t prediction_ = 0;  // diagonal of the last fix (place - step)
  uint32_t since_fix_ = 0;  // steps since the last fix (or since the start)
  uint32_t quota_ = 0;      // library places of the last step's share not streamed yet
  uint32_t reseed_next_ = 0;  // the window's re-seeding: the next step to replay ...
  uint32_t reseed_end_ = 0;   // ... up to (not including) this one
  uint32_t replayed_ = 0;     // band places of the step being replayed compared so far
  // The scan's work since the last step (RouteStepInfo's scan_* fields).
  struct ScanNews {
    uint32_t streamed = 0;
    Status status = Status::kOk;
    bool running = false;
    bool completed = false;
    bool jumped = false;
  } news_{};
};

}  // namespace seqslam
