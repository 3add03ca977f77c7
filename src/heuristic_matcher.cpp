#include "seqslam/heuristic_matcher.h"

#include "seqslam/messages.h"
#include "seqslam/sequence_matcher.h"

namespace seqslam {

namespace {

uint32_t add_sat(uint32_t a, uint32_t b) {
  const uint32_t s = a + b;
  return s < a ? 0xFFFFFFFFu : s;
}

// A candidate set under construction (the greedy scan), kept on the stack so that a failed
// distance evaluation leaves the matcher untouched.
struct Greedy {
  uint32_t start[kMaxHeuristicCandidates];
  uint32_t sum[kMaxHeuristicCandidates];
  uint16_t count = 0;
  uint16_t k = 0;

  // Offers a finished local minimum; keeps the k smallest distances (ties: smaller place, and
  // minima arrive in increasing place order, so an equal distance never displaces).
  void offer(uint32_t place, uint32_t d) {
    if (count < k) {
      start[count] = place;
      sum[count] = d;
      ++count;
      return;
    }
    uint16_t worst = 0;
    for (uint16_t i = 1; i < count; ++i) {
      if (sum[i] > sum[worst] || (sum[i] == sum[worst] && start[i] > start[worst])) worst = i;
    }
    if (d < sum[worst]) {
      start[worst] = place;
      sum[worst] = d;
    }
  }

  // Orders by start place (insertion sort, k <= 16).
  void sort() {
    for (uint16_t i = 1; i < count; ++i) {
      const uint32_t s = start[i];
      const uint32_t v = sum[i];
      uint16_t j = i;
      while (j > 0 && start[j - 1] > s) {
        start[j] = start[j - 1];
        sum[j] = sum[j - 1];
        --j;
      }
      start[j] = s;
      sum[j] = v;
    }
  }
};

}  // namespace

const char* heuristic_issue_text(HeuristicIssue issue) {
#if !SEQSLAM_MESSAGE_TEXTS
  return message_code("HI", static_cast<uint32_t>(issue));
#endif
  switch (issue) {
    case HeuristicIssue::kNone:
      return "ok";
    case HeuristicIssue::kCandidatesOutOfRange:
      return "heuristic.candidates must be 1..16 (kMaxHeuristicCandidates)";
    case HeuristicIssue::kGuardZero:
      return "heuristic.guard must be >= 1";
    case HeuristicIssue::kSeqLenOutOfRange:
      return "heuristic.seq_len must be 1..100 (kMaxSeqLen)";
    case HeuristicIssue::kPixelsOutOfRange:
      return "heuristic pixels must be 1..kMaxPixels";
  }
  return "unknown";
}

Status check_heuristic_config(const HeuristicConfig& c, uint32_t pixels, HeuristicIssue* issue) {
  HeuristicIssue found = HeuristicIssue::kNone;
  if (c.candidates == 0 || c.candidates > kMaxHeuristicCandidates) {
    found = HeuristicIssue::kCandidatesOutOfRange;
  } else if (c.guard == 0) {
    found = HeuristicIssue::kGuardZero;
  } else if (c.seq_len == 0 || c.seq_len > kMaxSeqLen) {
    found = HeuristicIssue::kSeqLenOutOfRange;
  } else if (pixels == 0 || pixels > kMaxPixels) {
    found = HeuristicIssue::kPixelsOutOfRange;
  }
  if (issue != nullptr) *issue = found;
  return found == HeuristicIssue::kNone ? Status::kOk : Status::kOutOfRange;
}

Status HeuristicMatcher::configure(const HeuristicConfig& config, uint32_t pixels) {
  SEQSLAM_TRY(check_heuristic_config(config, pixels));
  config_ = config;
  threshold_area_ = static_cast<uint64_t>(config.threshold.raw()) * pixels;
  configured_ = true;
  reset();
  return Status::kOk;
}

void HeuristicMatcher::reset() {
  count_ = 0;
  steps_ = 0;
  first_ = 0;
  trails_ = 0;
  scanning_ = false;
  tracking_ = false;
  sequence_done_ = true;
  stepped_ = false;
  for (uint16_t i = 0; i < kMaxHeuristicCandidates; ++i) {
    start_[i] = 0;
    sum_[i] = 0;
  }
}

namespace {

// Where the greedy scan is (copied in, committed only when the whole step succeeded).
struct ScanCursor {
  uint32_t next = 0;
  uint32_t min_place = 0;
  uint32_t min_d = 0;
  bool tracking = false;
};

// The greedy rule (header: the exact rule) over places [cur.next, end) of the first image.
Status greedy_scan(PlaceDistance& distance, uint32_t first, uint32_t end, uint16_t guard,
                   uint64_t threshold_area, ScanCursor* cur, Greedy* g) {
  constexpr uint32_t kBatch = 16;
  uint32_t d[kBatch];
  while (cur->next < end) {
    const uint32_t n = end - cur->next < kBatch ? end - cur->next : kBatch;
    SEQSLAM_TRY(distance.distances(first, cur->next, n, d));
    for (uint32_t i = 0; i < n; ++i) {
      const uint32_t j = cur->next + i;
      if (cur->tracking && j - cur->min_place <= guard) {
        if (d[i] < cur->min_d) {
          cur->min_place = j;
          cur->min_d = d[i];
        }
        continue;
      }
      if (cur->tracking) {
        g->offer(cur->min_place, cur->min_d);
        cur->tracking = false;
      }
      if ((static_cast<uint64_t>(d[i]) << 8) < threshold_area) {
        cur->tracking = true;
        cur->min_place = j;
        cur->min_d = d[i];
      }
    }
    cur->next += n;
  }
  return Status::kOk;
}

}  // namespace

Status HeuristicMatcher::step(PlaceDistance& distance, uint32_t places, HeuristicMatch* out) {
  if (!configured_) return Status::kFailedPrecondition;
  if (places > 0x7FFFFFFFu) places = 0x7FFFFFFFu;  // places are reported as int32
  // Work on copies; commit at the end, so a failed distance leaves the matcher untouched.
  const bool starting = sequence_done_;
  const uint32_t first = starting ? steps_ : first_;
  const uint32_t offset = steps_ - first;
  Greedy g;
  g.k = config_.candidates;
  for (uint16_t i = 0; !starting && i < count_; ++i) {
    g.start[i] = start_[i];
    g.sum[i] = sum_[i];
  }
  g.count = starting ? 0 : count_;
  ScanCursor cur;
  uint32_t scan_places = starting ? places : scan_places_;
  bool scanning = starting || scanning_;
  if (!starting) cur = ScanCursor{scan_next_, min_place_, min_d_, tracking_};
  uint16_t trails = starting ? 0 : trails_;
  if (scanning) {
    // 1. The first image's greedy scan, scan_places a step if budgeted.
    uint32_t end = scan_places;
    if (config_.scan_places != 0 && end - cur.next > config_.scan_places) {
      end = cur.next + config_.scan_places;
    }
    SEQSLAM_TRY(greedy_scan(distance, first, end, config_.guard, threshold_area_, &cur, &g));
    if (cur.next == scan_places) {
      if (cur.tracking) g.offer(cur.min_place, cur.min_d);
      scanning = false;
    }
    g.sort();
  }
  if (!scanning && offset > 0) {
    // 2. Follow the trails at this step's offset; a trail leaving the library is dropped
    // (order is kept).
    Greedy t;
    for (uint16_t i = 0; i < g.count; ++i) {
      const uint32_t p = g.start[i] + offset;
      if (p >= places) continue;
      uint32_t d = 0;
      SEQSLAM_TRY(distance.distance(steps_, p, &d));
      t.start[t.count] = g.start[i];
      t.sum[t.count] = add_sat(g.sum[i], d);
      ++t.count;
    }
    for (uint16_t i = 0; i < t.count; ++i) {
      g.start[i] = t.start[i];
      g.sum[i] = t.sum[i];
    }
    g.count = t.count;
    ++trails;
  }
  // Commit.
  for (uint16_t i = 0; i < g.count; ++i) {
    start_[i] = g.start[i];
    sum_[i] = g.sum[i];
  }
  count_ = g.count;
  first_ = first;
  scanning_ = scanning;
  scan_places_ = scan_places;
  scan_next_ = cur.next;
  min_place_ = cur.min_place;
  min_d_ = cur.min_d;
  tracking_ = cur.tracking;
  trails_ = trails;
  sequence_done_ = !scanning && trails + 1u >= config_.seq_len;
  ++steps_;
  stepped_ = true;
  if (out != nullptr) *out = current();
  return Status::kOk;
}

HeuristicMatch HeuristicMatcher::current() const {
  HeuristicMatch m;
  if (!stepped_) return m;
  m.query = steps_ - 1;
  m.offset = static_cast<uint16_t>(steps_ - 1 - first_);
  m.complete = !scanning_ && trails_ + 1u >= config_.seq_len;
  m.scanning = scanning_;
  m.candidates = count_;
  if (count_ == 0) return m;
  uint16_t best = 0;
  for (uint16_t i = 1; i < count_; ++i) {
    // Strictly smaller only: candidates are ordered by start, so ties keep the smaller start.
    if (sum_[i] < sum_[best]) best = i;
  }
  m.start = static_cast<int32_t>(start_[best]);
  m.place = static_cast<int32_t>(start_[best] + m.offset);
  m.sum = sum_[best];
  const uint32_t r = config_.exclusion;
  uint16_t second = count_;
  for (uint16_t i = 0; i < count_; ++i) {
    const uint32_t gap =
        start_[i] > start_[best] ? start_[i] - start_[best] : start_[best] - start_[i];
    if (gap <= r) continue;
    if (second == count_ || sum_[i] < sum_[second]) second = i;
  }
  if (second == count_) return m;
  m.runner_up = static_cast<int32_t>(start_[second] + m.offset);
  m.runner_up_sum = sum_[second];
  m.confidence = confidence_ratio(m.sum, m.runner_up_sum);
  return m;
}

}  // namespace seqslam
