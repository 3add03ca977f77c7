// Localising on a whole route with memory and work per step that do not grow with the route
// (the head board's search; docs/firmware.md, "Localising on a whole route").
//
// Two parts, both exact pieces of the diagonal matcher, running side by side at every step:
//  - tracking (window_matcher.h): only the diagonals odometry allows are searched: a window
//    of `window` diagonals centred on the prediction (the diagonal of the last fix; one
//    library place per step along it). The answer is the best full sequence within `slack +
//    growth x places since the last fix` of the prediction (the window that grows with the
//    distance travelled), its runner-up the best more than R places away anywhere in the
//    window. A confident answer is a fix: the prediction moves to its diagonal.
//  - the scan (sequence_scan.h): the full search at one anchor step, streamed through the
//    library in the time between places and started again at the latest step as soon as it
//    completes, so a second, global opinion is never more than ceil(M / scan_places) steps
//    old. Its work is the step's share, `scan_places` library places, that the caller streams
//    in slices between sensor snapshots (work()) or that the next step streams first; either
//    way the answers are the same (deterministic). A confident scan either agrees with the
//    prediction (it is not lost; not a fix of its own: a scan's shorter sequence is more
//    easily fooled than the window's) or names a place elsewhere (a candidate). A candidate
//    is on probation until a later scan, anchored at least scan_seq_len steps after it (so
//    the two share no query image), agrees; then, once the prediction has had no fix for
//    `lost_after` places, the prediction moves there (a jump: the confirming scan's answer
//    carried along is a fix). While a candidate is on probation the window's answers are not
//    fixes (two opinions disagree: the answer is "not sure"); a scan that agrees with the
//    prediction drops it, a confident scan elsewhere replaces it (one candidate is kept).
//    With no prediction (an unknown start) the first candidate moves the prediction at once,
//    still on probation. After a jump the window's new diagonals have no history: until
//    they have S steps, the answer is the scan's place carried along (not localised).
//
// Per step: (window + W) library images read and differenced, plus the scan's
// scan_places x scan_seq_len differences and reads; RAM: the window's 2 S + 5 bytes a
// diagonal, its band of (window + W) differences, the scan's buffers (~2 KB at
// scan_seq_len = 10, W = 50, and its query images where they are kept in RAM), the query
// history's RAM part and the route search's own state: all independent of the
// library's length.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/image.h"
#include "seqslam/place_library.h"
#include "seqslam/query_history.h"
#include "seqslam/sequence_matcher.h"
#include "seqslam/sequence_scan.h"
#include "seqslam/span.h"
#include "seqslam/status.h"
#include "seqslam/window_matcher.h"

namespace seqslam {

struct RouteSearchConfig {
  // Diagonals the window keeps (odd: the prediction and (window - 1) / 2 either side); at
  // least 2 R + 3 so that a runner-up can exist, at most the window storage's slots.
  uint16_t window = 33;
  // Places either side of the prediction the answer may be right after a fix ...
  uint16_t slack = 2;
  // ... growing by this many places per place travelled without a fix (odometry's drift along
  // the route between two runs: 1/20 = 5 %).
  UQ8_8 growth = UQ8_8::from_ratio(1, 20);
  // Places without a fix after which the prediction is lost (>= 1): only then may a
  // confirmed candidate move it.
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
};
const char* route_issue_text(RouteIssue issue);

// The scan's sequence length for these settings: scan_seq_len, at most S.
constexpr uint16_t scan_seq_len(const RouteSearchConfig& route, const SequenceConfig& sequence) {
  return route.scan_seq_len < sequence.seq_len ? route.scan_seq_len : sequence.seq_len;
}

struct RouteSearchBuffers {
  WindowMatcherBuffers window;
  Span<uint32_t> band;  // >= window + 2 (W / 2): one step's raw differences
  SequenceScanBuffers scan;
};

// Storage for windows up to kSlots diagonals, S up to kSeqLen, scans up to kScanSeqLen, W up
// to kWindow and R up to kExclusion, for static allocation; the scan keeps its query images in
// RAM for images up to kScanPixels pixels (0: it reads them from the history every chunk).
template <uint16_t kSlots, uint16_t kSeqLen, uint16_t kScanSeqLen, uint16_t kWindow,
          uint16_t kExclusion, uint32_t kScanPixels = 0>
struct RouteSearchStorage {
  using Scan = SequenceScanStorage<kScanSeqLen, kWindow, kExclusion, kScanPixels>;
  WindowMatcherStorage<kSlots, kSeqLen> window;
  uint32_t band[kSlots + 2u * (kWindow / 2u)];
  Scan scan;
  static constexpr size_t kBytes = WindowMatcherStorage<kSlots, kSeqLen>::kBytes +
                                   sizeof(uint32_t) * (kSlots + 2u * (kWindow / 2u)) + Scan::kBytes;
  RouteSearchBuffers buffers() {
    return {window.buffers(), Span<uint32_t>(band, kSlots + 2u * (kWindow / 2u)), scan.buffers()};
  }
};

// What the search did at a step, beside its answer (for the firmware's counters and tests).
struct RouteStepInfo {
  bool tracking = false;        // a prediction exists (the start was known, or a scan found it)
  bool probation = false;       // a scan's jump (a candidate place) awaits a later scan's word
  int32_t prediction = 0;       // the predicted diagonal (place - step) during this step
  uint16_t search_radius = 0;   // places either side of the prediction the answer could be
  bool fix = false;             // this step's answer was a fix (confident, within the radius)
  bool carried = false;         // the answer is carried (a scan's or the prediction's place)
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

  // Streams up to `budget` library places of the scan's share of the last step (what is left
  // of its scan_places), applying a completed scan's verdict; the places streamed. Called in
  // slices between sensor snapshots; what is left when the next step comes, that step streams
  // first. Errors are the next step's info.scan_status.
  uint32_t work(PlaceLibrary& library, uint32_t budget);
  // Library places of the last step's share not streamed yet.
  uint32_t pending() const { return quota_; }

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
  // A completed scan's verdict, between steps (after step `step`).
  void judge(const ScanResult& result, uint32_t step);
  static bool carry(const Match& from, uint32_t step, uint32_t places, Match* out);

  RouteSearchConfig config_{};
  SequenceConfig sequence_{};
  RouteSearchBuffers buffers_{};
  QueryHistory* history_ = nullptr;
  WindowMatcher window_{};
  SequenceScan scan_{};
  uint32_t pixels_ = 0;
  bool configured_ = false;
  bool tracking_ = false;
  int32_t prediction_ = 0;  // diagonal of the last fix (place - step)
  uint32_t since_fix_ = 0;  // steps since the last fix (or since the start)
  // After a jump: the scan's answer carried forward until the window has full sequences.
  bool carrying_ = false;
  bool confirmed_ = false;  // a scan confirmed a jump since the last step
  Match carried_{};         // the last confident scan's answer (at its anchor)
  uint32_t quota_ = 0;      // library places of the last step's share not streamed yet
  // The scan's work since the last step (RouteStepInfo's scan_* fields).
  struct ScanNews {
    uint32_t streamed = 0;
    Status status = Status::kOk;
    bool running = false;
    bool completed = false;
    bool jumped = false;
  } news_{};
  bool probation_ = false;  // a jump (candidate_) waits for a later scan to confirm it
  int32_t candidate_ = 0;   // the jump's diagonal (the prediction itself after an unknown start)
  uint32_t candidate_anchor_ = 0;  // the step its scan anchored at
};

}  // namespace seqslam
