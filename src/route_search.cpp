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
  probation_ = false;  // (candidate_ means nothing without it)
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

bool RouteSearch::uncertain() const {
  // While a scan's answer is carried the window cannot have fixes yet: that alone is not
  // doubt. A jump is, until a later scan confirms it.
  return !tracking_ || probation_ || (!carrying_ && since_fix_ >= config_.lost_after);
}

Status RouteSearch::step(PlaceLibrary& library, ImageView query, uint32_t places, Match* out,
                         RouteStepInfo* info) {
  if (!configured_) return Status::kFailedPrecondition;
  if (query.pixels == nullptr || query.size.pixels() != pixels_) return Status::kInvalidArgument;
  if (places > library.size()) return Status::kOutOfRange;
  const uint32_t i = window_.steps();
  // Relocalising: a scan runs, or is due and has the rows it needs. The window then pauses:
  // its band alone takes most of a step's card time, and a window that has lost the route
  // has nothing to say (docs/firmware.md, "Localising on a whole route").
  const bool relocalising = scan_.running() || (uncertain() && i + 1 >= scan_.config().seq_len);
  RouteStepInfo inf;
  inf.tracking = tracking_;
  inf.probation = probation_;
  inf.prediction = prediction_;
  inf.search_radius = radius();
  Match m;
  if (relocalising) {
    const Status s = history_->put(i, query.pixels, places);
    if (s != Status::kOk) return s;
    window_.skip();
    ++since_fix_;
    // The answer is carried, never a fix: a confirming scan's, else the prediction's, else
    // (odometry has run off the library) a candidate's on probation.
    m.query = i;
    if (!(carrying_ && carry(carried_, i, places, &m)) && tracking_) {
      const int32_t step = static_cast<int32_t>(i);
      const int32_t n = static_cast<int32_t>(places);
      if (prediction_ + step >= 0 && prediction_ + step < n) {
        m.place = prediction_ + step;
      } else if (probation_ && candidate_ + step >= 0 && candidate_ + step < n) {
        m.place = candidate_ + step;
      }
    }
    m.localised = false;
    inf.carried = m.place >= 0;
    inf.paused = true;
  } else {
    SEQSLAM_TRY(track(library, query, places, i, &m, &inf));
  }
  // A confident scan that completes is the full search's verdict at its anchor, carried along
  // its diagonal to this step: this step's answer. It is a fix when it confirms the prediction;
  // a jump is not, until a later scan agrees (see run_scan).
  const ScanOutcome outcome =
      relocalising ? run_scan(library, i, places, &inf) : ScanOutcome::kNone;
  if ((outcome == ScanOutcome::kConfirmed || outcome == ScanOutcome::kJumped) &&
      carry(carried_, i, places, &m)) {
    m.localised = outcome == ScanOutcome::kConfirmed;
    inf.fix = m.localised;
    inf.carried = !m.localised;
  }
  if (out != nullptr) *out = m;
  if (info != nullptr) *info = inf;
  return Status::kOk;
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

RouteSearch::ScanOutcome RouteSearch::run_scan(PlaceLibrary& library, uint32_t step,
                                               uint32_t places, RouteStepInfo* info) {
  if (!scan_.running()) {
    // Nothing to scan yet (loop closure: the library's recent places are not searched).
    if (places == 0) return ScanOutcome::kNone;
    // Fails only when the history lacks the rows (after a history error): try again later.
    if (scan_.start(step, *history_) != Status::kOk) return ScanOutcome::kNone;
  }
  info->scan_running = true;
  uint32_t streamed = 0;
  // (A scan whose rows all had empty libraries completed at its start.)
  if (scan_.running()) {
    info->scan_status = scan_.advance(library, *history_, config_.scan_places, &streamed);
  }
  info->scan_streamed = streamed;
  if (!scan_.complete()) return ScanOutcome::kNone;
  info->scan_completed = true;
  const ScanResult result = scan_.result();
  scan_.stop();
  // Not confident: the next uncertain step restarts it.
  if (!result.match.localised) return ScanOutcome::kNone;
  const int32_t anchor = static_cast<int32_t>(result.match.query);
  const int32_t diagonal = result.match.place - anchor;
  const uint32_t since_anchor = step - result.match.query;
  const int32_t gap = diagonal > prediction_ ? diagonal - prediction_ : prediction_ - diagonal;
  // When the scan moves or confirms the prediction the window restarts empty (it paused): the
  // scan's answer is carried until it has full sequences again.
  if (tracking_ && gap <= static_cast<int32_t>(radius())) {
    // The global answer confirms the prediction: a fix at the anchor, and the end of a jump's
    // probation (the candidate elsewhere is dropped).
    if (since_anchor < since_fix_) since_fix_ = since_anchor;
    probation_ = false;
    carried_ = result.match;
    carrying_ = true;
    return ScanOutcome::kConfirmed;
  }
  if (probation_) {
    const int32_t cgap = diagonal > candidate_ ? diagonal - candidate_ : candidate_ - diagonal;
    if (cgap <= static_cast<int32_t>(radius_after(step - candidate_anchor_))) {
      // A second confident scan agrees with the candidate: the jump is confirmed, a fix.
      prediction_ = diagonal;
      since_fix_ = since_anchor;
      probation_ = false;
      carried_ = result.match;
      carrying_ = true;
      return ScanOutcome::kConfirmed;
    }
  }
  // Elsewhere (or the first answer of an unknown start). The full search can be wrong too (a
  // scan's shorter sequence that still holds places not in the library can look like known
  // ones), and a wrong jump throws away a prediction that odometry may still carry well: so a
  // jump is a candidate on probation until a later scan agrees with it (relocalising takes two
  // scans: precision before speed, as a false fix becomes a false loop closure). Meanwhile the
  // answer stays the prediction carried by odometry; with no prediction yet (an unknown
  // start) the candidate becomes the prediction and the scan's answer is carried.
  candidate_ = diagonal;
  candidate_anchor_ = result.match.query;
  probation_ = true;
  info->scan_jumped = true;
  if (tracking_) return ScanOutcome::kCandidate;
  prediction_ = diagonal;
  tracking_ = true;
  since_fix_ = since_anchor;
  carried_ = result.match;
  carrying_ = true;
  return ScanOutcome::kJumped;
}

}  // namespace seqslam
