#include "seqslam/route_search.h"

#include "seqslam/assert.h"
#include "seqslam/messages.h"

namespace seqslam {

const char* route_issue_text(RouteIssue issue) {
#if !SEQSLAM_MESSAGE_TEXTS
  return message_code("RI", static_cast<uint32_t>(issue));
#endif
  switch (issue) {
    case RouteIssue::kNone:
      return "route search settings are valid";
    case RouteIssue::kWindowOutOfRange:
      return "route.window must be odd, at least 2 * exclusion + 3 and at most the window slots";
    case RouteIssue::kLostAfterZero:
      return "route.lost_after must be at least 1";
    case RouteIssue::kScanPlacesZero:
      return "route.scan_places must be at least 1";
    case RouteIssue::kScanSeqLenOutOfRange:
      return "route.scan_seq_len must be at least 1";
    case RouteIssue::kStartOutOfRange:
      return "route.start must be a place (>= 0) or -1 (unknown)";
    case RouteIssue::kStorageTooSmall:
      return "route search buffers too small for seq_len, window and exclusion";
  }
  return "unknown route search issue";
}

Status RouteSearch::check(const RouteSearchConfig& config, const SequenceConfig& sequence,
                          const RouteSearchBuffers& buffers, RouteIssue* issue) {
  RouteIssue found = RouteIssue::kNone;
  Status status = Status::kOk;
  const uint32_t seq = sequence.seq_len == 0 ? 1u : sequence.seq_len;
  const uint32_t scan_seq = config.scan_seq_len == 0    ? 1u
                            : config.scan_seq_len < seq ? config.scan_seq_len
                                                        : seq;
  size_t slots = buffers.window.ring.size() / seq;
  if (buffers.window.cost.size() < slots) slots = buffers.window.cost.size();
  if (buffers.window.run.size() < slots) slots = buffers.window.run.size();
  const uint32_t h = sequence.window / 2u;
  const SequenceScanBuffers& sb = buffers.scan;
  if (config.window % 2 == 0 || config.window < 2u * sequence.exclusion + 3u ||
      config.window > slots) {
    found = RouteIssue::kWindowOutOfRange;
    status = Status::kOutOfRange;
  } else if (config.lost_after == 0) {
    found = RouteIssue::kLostAfterZero;
    status = Status::kInvalidArgument;
  } else if (config.scan_places == 0) {
    found = RouteIssue::kScanPlacesZero;
    status = Status::kInvalidArgument;
  } else if (config.scan_seq_len == 0) {
    found = RouteIssue::kScanSeqLenOutOfRange;
    status = Status::kOutOfRange;
  } else if (config.start < -1) {
    found = RouteIssue::kStartOutOfRange;
    status = Status::kOutOfRange;
  } else if (buffers.band.size() < config.window + 2u * h ||
             sb.raw.size() < static_cast<size_t>(scan_seq) * (2u * h + 1u) ||
             sb.raw_high.size() < static_cast<size_t>(scan_seq) * scan_high_words(2u * h + 1u) ||
             sb.rows.size() < scan_seq || sb.ends.size() < scan_seq + kMaxScanChunk + h + 1u ||
             sb.ranked.size() < 2u * static_cast<size_t>(sequence.exclusion) + 2u) {
    found = RouteIssue::kStorageTooSmall;
    status = Status::kResourceExhausted;
  }
  if (issue != nullptr) *issue = found;
  return status;
}

Status RouteSearch::configure(const RouteSearchConfig& config, const SequenceConfig& sequence,
                              uint32_t pixels, const RouteSearchBuffers& buffers,
                              QueryHistory& history, RouteIssue* issue) {
  configured_ = false;
  Status s = check_sequence_config(sequence);
  if (s != Status::kOk) return s;
  s = check(config, sequence, buffers, issue);
  if (s != Status::kOk) return s;
  if (history.pixels() != pixels) {
    if (issue != nullptr) *issue = RouteIssue::kStorageTooSmall;
    return Status::kInvalidArgument;
  }
  s = window_.configure(sequence, pixels, buffers.window);
  SequenceConfig scan_sequence = sequence;
  scan_sequence.seq_len = scan_seq_len(config, sequence);
  if (s == Status::kOk) s = scan_.configure(scan_sequence, pixels, buffers.scan);
  if (s != Status::kOk) return s;
  config_ = config;
  sequence_ = sequence;
  buffers_ = buffers;
  history_ = &history;
  pixels_ = pixels;
  configured_ = true;
  reset();
  return Status::kOk;
}

void RouteSearch::reset() {
  if (!configured_) return;
  window_.reset();
  scan_.stop();
  history_->clear();
  tracking_ = config_.start >= 0;
  prediction_ = tracking_ ? config_.start : 0;  // step 0: the diagonal is the place
  since_fix_ = 0;
  carrying_ = false;
  confirmed_ = false;
  probation_ = false;  // (candidate_ means nothing without it)
  quota_ = 0;
  news_ = ScanNews{};
  place_window();
}

uint16_t RouteSearch::radius() const {
  return radius_after(since_fix_);
}

uint16_t RouteSearch::radius_after(uint32_t places) const {
  const uint32_t half = (config_.window - 1u) / 2u;
  const uint64_t grown =
      config_.slack + ((static_cast<uint64_t>(config_.growth.raw()) * places) >> 8);
  return static_cast<uint16_t>(grown < half ? grown : half);
}

void RouteSearch::place_window() {
  const int32_t half = static_cast<int32_t>((config_.window - 1u) / 2u);
  // Predictions are places minus steps: far from the int32 limits for any real route.
  const Status s = window_.place(prediction_ - half, config_.window);
  SEQSLAM_ASSERT(s == Status::kOk);
}

Status RouteSearch::step(PlaceLibrary& library, ImageView query, uint32_t places, Match* out,
                         RouteStepInfo* info) {
  if (!configured_) return Status::kFailedPrecondition;
  if (query.pixels == nullptr || query.size.pixels() != pixels_) return Status::kInvalidArgument;
  if (places > library.size()) return Status::kOutOfRange;
  // What the caller left of the last step's share of the scan, first: the answers do not
  // depend on how the share was sliced. (Every call makes progress: it streams, loads the
  // scan's query images, completes the scan or ends the share on an error.)
  while (quota_ > 0)
    work(library, quota_);
  const uint32_t i = window_.steps();
  RouteStepInfo inf;
  inf.scan_running = news_.running;
  inf.scan_completed = news_.completed;
  inf.scan_jumped = news_.jumped;
  inf.scan_streamed = news_.streamed;
  inf.scan_status = news_.status;
  inf.tracking = tracking_;
  inf.probation = probation_;
  inf.prediction = prediction_;
  inf.search_radius = radius();
  Match m;
  SEQSLAM_TRY(track(library, query, places, i, &m, &inf));
  news_ = ScanNews{};
  // The next scan anchors at this step as soon as the last one has completed. (Nothing to
  // scan in an empty library; loop closure: the library's recent places are not searched.)
  // A start fails only when the history lacks the rows (after a history error): next step.
  if (!scan_.running() && places > 0 && i + 1 >= scan_.config().seq_len) {
    (void)scan_.start(i, *history_);
  }
  quota_ = scan_.running() ? config_.scan_places : 0u;
  if (out != nullptr) *out = m;
  if (info != nullptr) *info = inf;
  return Status::kOk;
}

uint32_t RouteSearch::work(PlaceLibrary& library, uint32_t budget) {
  if (quota_ == 0 || !scan_.running()) {
    quota_ = 0;
    return 0;
  }
  uint32_t streamed = 0;
  const Status s = scan_.advance(library, *history_, budget < quota_ ? budget : quota_, &streamed);
  news_.running = true;
  news_.streamed += streamed;
  // A card error: the scan retries (or, after a history error, restarts) at the next step.
  if (s != Status::kOk) news_.status = s;
  quota_ = s != Status::kOk || streamed >= quota_ ? 0u : quota_ - streamed;
  if (scan_.complete()) {
    quota_ = 0;
    news_.completed = true;
    const ScanResult result = scan_.result();
    scan_.stop();
    judge(result, window_.steps() - 1u);
  }
  return streamed;
}

// A tracking step: the window's band, the history, the window's answer within the search
// radius; a fix moves the prediction. Storage errors leave everything as it was.
Status RouteSearch::track(PlaceLibrary& library, ImageView query, uint32_t places, uint32_t i,
                          Match* out, RouteStepInfo* inf) {
  place_window();
  const PlaceBand band = window_.band(places);
  if (band.count > 0) {
    SEQSLAM_TRY(library.differences(query, band.first, band.count, buffers_.band.data()));
  }
  Status s = history_->put(i, query.pixels, places);
  if (s != Status::kOk) return s;
  const uint16_t r = inf->search_radius;
  Match m;
  s = window_.step(places, Span<const uint32_t>(buffers_.band.data(), band.count), prediction_ - r,
                   prediction_ + r, &m);
  SEQSLAM_ASSERT(s == Status::kOk);  // the band was sized by band() and checked at configure
  // No prediction, or one a scan has not confirmed yet: a local confidence proves nothing.
  if (!tracking_ || probation_) m.localised = false;
  if (m.localised) {
    prediction_ = m.place - static_cast<int32_t>(i);
    since_fix_ = 0;
    inf->fix = true;
  } else {
    ++since_fix_;
  }
  // The window has full sequences again, or the carried place ran off the library.
  if (carrying_ && (m.place >= 0 || !carry(carried_, i, places, &m))) carrying_ = false;
  if (carrying_) {
    m.localised = false;  // carried by odometry, not measured at this step
    inf->carried = true;
  }
  // A jump since the last step: the confirming scan's answer carried along its diagonal is
  // this step's fix (carried_ was confident: m.localised).
  if (confirmed_ && !m.localised && carry(carried_, i, places, &m)) {
    inf->fix = true;
    inf->carried = false;
  }
  confirmed_ = false;
  *out = m;
  return Status::kOk;
}

// `from` (a scan's answer at its anchor step) moved along its diagonal to `step`; false (and
// *out unchanged) if its place is not among the library's `places` then.
bool RouteSearch::carry(const Match& from, uint32_t step, uint32_t places, Match* out) {
  const int32_t moved = static_cast<int32_t>(step - from.query);
  const int32_t place = from.place + moved;
  if (from.place < 0 || place < 0 || place >= static_cast<int32_t>(places)) return false;
  const int32_t ru = from.runner_up;
  *out = from;
  out->query = step;
  out->place = place;
  out->runner_up = ru >= 0 && ru + moved < static_cast<int32_t>(places) ? ru + moved : -1;
  return true;
}

// A completed scan's verdict (docs/firmware.md, "Localising on a whole route"). A confident
// answer near the candidate on probation confirms it if anchored scan_seq_len steps after it
// (a jump, once the prediction is lost); one near the prediction keeps it; one elsewhere is a
// new candidate, which moves an unknown prediction (an unknown start) at once.
void RouteSearch::judge(const ScanResult& result, uint32_t step) {
  if (!result.match.localised) return;
  const uint32_t anchor = result.match.query;
  const int32_t diagonal = result.match.place - static_cast<int32_t>(anchor);
  const uint32_t since_anchor = step - anchor;
  const int32_t gap = diagonal > prediction_ ? diagonal - prediction_ : prediction_ - diagonal;
  const int32_t cgap = diagonal > candidate_ ? diagonal - candidate_ : candidate_ - diagonal;
  const bool at_prediction = tracking_ && gap <= static_cast<int32_t>(radius());
  if (probation_ && cgap <= static_cast<int32_t>(radius_after(step - candidate_anchor_))) {
    // Evidence of its own: a scan that shares no query image with the candidate's (two that
    // share most of them are fooled together).
    if (anchor < candidate_anchor_ + scan_.config().seq_len) return;
    // A prediction the window still confirms is not given up.
    if (!at_prediction && tracking_ && since_fix_ < config_.lost_after) return;
    if (!at_prediction) {  // the jump: the window restarts there, the scan's answer carried
      prediction_ = diagonal;
      carrying_ = true;
    }
    since_fix_ = since_anchor;
  } else if (at_prediction) {
    // The global answer agrees with the prediction: it is not lost, and a candidate
    // elsewhere is dropped. (Not a fix of its own: the scan's shorter sequence is more
    // easily fooled than the window's, docs/accuracy.md.)
    if (since_anchor < since_fix_) since_fix_ = since_anchor;
    probation_ = false;
    return;
  } else {
    // Elsewhere: the full search can be wrong too (a shorter sequence that holds places not
    // in the library can look like known ones), and a wrong jump throws away a prediction
    // that odometry may still carry well; so a candidate waits on probation for a later
    // scan, unless there is no prediction yet (an unknown start).
    candidate_ = diagonal;
    candidate_anchor_ = anchor;
    probation_ = true;
    news_.jumped = true;
    if (tracking_) return;
    prediction_ = diagonal;
    tracking_ = true;
    since_fix_ = since_anchor;
    carried_ = result.match;
    carrying_ = true;
    return;
  }
  probation_ = false;
  carried_ = result.match;
  confirmed_ = true;
}

}  // namespace seqslam
