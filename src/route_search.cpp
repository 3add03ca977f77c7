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
    case RouteIssue::kJumpStepsZero:
      return "route.jump_steps must be at least 1";
  }
  return "unknown route search issue";
}

RouteIssue check_route_settings(const RouteSearchConfig& config, const SequenceConfig& sequence) {
  if (config.window % 2 == 0 || config.window < 2u * sequence.exclusion + 3u) {
    return RouteIssue::kWindowOutOfRange;
  }
  if (config.lost_after == 0) return RouteIssue::kLostAfterZero;
  if (config.scan_places == 0) return RouteIssue::kScanPlacesZero;
  if (config.scan_seq_len == 0) return RouteIssue::kScanSeqLenOutOfRange;
  if (config.start < -1) return RouteIssue::kStartOutOfRange;
  if (config.jump_steps == 0) return RouteIssue::kJumpStepsZero;
  return RouteIssue::kNone;
}

Status route_issue_status(RouteIssue issue) {
  switch (issue) {
    case RouteIssue::kNone:
      return Status::kOk;
    case RouteIssue::kLostAfterZero:
    case RouteIssue::kScanPlacesZero:
    case RouteIssue::kJumpStepsZero:
      return Status::kInvalidArgument;
    case RouteIssue::kStorageTooSmall:
      return Status::kResourceExhausted;
    default:
      return Status::kOutOfRange;
  }
}

Status RouteSearch::check(const RouteSearchConfig& config, const SequenceConfig& sequence,
                          const RouteSearchBuffers& buffers, RouteIssue* issue) {
  RouteIssue found = check_route_settings(config, sequence);
  const uint32_t seq = sequence.seq_len == 0 ? 1u : sequence.seq_len;
  const uint32_t scan_seq = config.scan_seq_len == 0    ? 1u
                            : config.scan_seq_len < seq ? config.scan_seq_len
                                                        : seq;
  size_t slots = buffers.window.ring.size() / seq;
  if (buffers.window.cost.size() < slots) slots = buffers.window.cost.size();
  if (buffers.window.run.size() < slots) slots = buffers.window.run.size();
  const uint32_t h = sequence.window / 2u;
  const uint32_t widest = config.window > kProbeSlots ? config.window : kProbeSlots;
  const SequenceScanBuffers& sb = buffers.scan;
  if (found == RouteIssue::kNone && config.window > slots) {
    found = RouteIssue::kWindowOutOfRange;
  } else if (found == RouteIssue::kNone &&
             (buffers.band.size() < widest + 2u * h ||
              sb.raw.size() < static_cast<size_t>(scan_seq) * (2u * h + 1u) ||
              sb.raw_high.size() < static_cast<size_t>(scan_seq) * scan_high_words(2u * h + 1u) ||
              sb.rows.size() < scan_seq || sb.ends.size() < scan_seq + kMaxScanChunk + h + 1u ||
              sb.ranked.size() < 2u * static_cast<size_t>(sequence.exclusion) + 2u)) {
    found = RouteIssue::kStorageTooSmall;
  }
  if (issue != nullptr) *issue = found;
  return route_issue_status(found);
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
  if (s == Status::kOk) s = probe_.configure(sequence, pixels, buffers.probe);
  if (s != Status::kOk) return s;
  config_ = config;
  sequence_ = sequence;
  band_ = buffers.band;
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
  probe_.stop();
  history_->clear();
  tracking_ = config_.start >= 0;
  prediction_ = tracking_ ? config_.start : 0;  // step 0: the diagonal is the place
  since_fix_ = 0;
  probation_ = false;
  quota_ = 0;
  reseed_next_ = reseed_end_ = 0;
  replayed_ = 0;
  news_ = ScanNews{};
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
  // What the caller left of the work between the last step and this one, first: the answers
  // do not depend on how it was sliced. (Every call makes progress: it replays a step,
  // streams, loads the scan's query images, completes the scan or ends the share on an error.)
  while (pending() > 0)
    work(library, UINT32_MAX);
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

uint32_t RouteSearch::replay_pending() const {
  uint32_t n = reseed_end_ - reseed_next_;
  if (probe_.active() && probe_.next_step() < window_.steps()) {
    n += window_.steps() - probe_.next_step();
  }
  return n;
}

// Replays part of one past step from the query history: the window's re-seeding first, then
// the candidate's catch-up. The step's band is compared up to `budget` places a call (into
// band_, which nothing else uses between steps) and applied when complete. A history or
// library error ends what it was for: the window keeps the history of the steps replayed
// after it (its runs start again there), the candidate is dropped.
Status RouteSearch::replay(PlaceLibrary& library, uint32_t budget, uint32_t* done) {
  *done = 0;
  const bool window = reseed_next_ < reseed_end_;
  const uint32_t t = window ? reseed_next_ : probe_.next_step();
  const uint8_t* pixels = nullptr;
  uint32_t places = 0;
  Status s = history_->get(t, &pixels, &places);
  PlaceBand band;
  if (s == Status::kOk) {
    band = window ? window_.band(places) : probe_.band(places);
    const uint32_t left = band.count - replayed_;
    const uint32_t n = budget < left ? budget : left;
    if (n > 0) {
      s = library.differences(ImageView{pixels, library.image_size()}, band.first + replayed_, n,
                              band_.data() + replayed_);
    }
    if (s == Status::kOk) {
      replayed_ += n;
      *done = n;
      if (replayed_ < band.count) return Status::kOk;  // the rest in the next call
    }
  }
  replayed_ = 0;
  const Span<const uint32_t> d(band_.data(), band.count);
  if (window) {
    Match none;  // an empty search range: the replayed step gives no answer
    if (s == Status::kOk) s = window_.step(places, d, 1, 0, &none);
    if (s != Status::kOk) window_.rewind(t + 1);
    ++reseed_next_;
    return s;
  }
  if (s == Status::kOk) s = probe_.add(places, d);
  if (s != Status::kOk) drop();
  return s;
}

uint32_t RouteSearch::work(PlaceLibrary& library, uint32_t budget) {
  if (budget == 0) budget = 1;
  if (replay_pending() > 0) {
    uint32_t done = 0;
    const Status s = replay(library, budget, &done);
    if (s != Status::kOk) news_.status = s;
    return done;
  }
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
    judge(result);
  }
  return streamed;
}

// A tracking step: the window's band, the history, the window's answer within the search
// radius, the candidate's evidence; a fix moves the prediction. Storage errors before the
// answer leave everything as it was.
Status RouteSearch::track(PlaceLibrary& library, ImageView query, uint32_t places, uint32_t i,
                          Match* out, RouteStepInfo* inf) {
  place_window();
  const PlaceBand band = window_.band(places);
  if (band.count > 0) {
    SEQSLAM_TRY(library.differences(query, band.first, band.count, band_.data()));
  }
  Status s = history_->put(i, query.pixels, places);
  if (s != Status::kOk) return s;
  const uint16_t r = inf->search_radius;
  Match m;
  s = window_.step(places, Span<const uint32_t>(band_.data(), band.count),
                   prediction_ - r, prediction_ + r, &m);
  SEQSLAM_ASSERT(s == Status::kOk);  // the band was sized by band() and checked at configure
  qualify(i, &m);
  // No prediction, or a candidate disputes it: a local confidence proves nothing.
  if (!tracking_ || probation_) m.localised = false;
  if (probe_.active() && probe_.next_step() == i) {
    const PlaceBand pb = probe_.band(places);
    s = pb.count > 0 ? library.differences(query, pb.first, pb.count, band_.data())
                     : Status::kOk;
    if (s == Status::kOk) {
      s = probe_.add(places, Span<const uint32_t>(band_.data(), pb.count));
    }
    if (s == Status::kOk) {
      decide(i, &m, inf);
    } else {
      drop();  // a card error: the candidate's evidence is incomplete
    }
  }
  if (!inf->fix) {
    if (m.localised) {
      prediction_ = m.place - static_cast<int32_t>(i);
      since_fix_ = 0;
      inf->fix = true;
    } else {
      ++since_fix_;
    }
  }
  *out = m;
  return Status::kOk;
}

// Whether the window's confident answer is a fix: both diagonals 2 places away exist, the
// minimum is sharp against every diagonal 2..R away, and the sequence still matches at its end.
// The sharpness enters the confidence (scaled so that `sharpness` meets the threshold), so a
// blunt answer also ranks as a doubtful one.
void RouteSearch::qualify(uint32_t i, Match* m) const {
  if (m->place < 0) return;
  const int32_t best = m->place - static_cast<int32_t>(i);
  if (config_.sharpness.raw() != 0) {
    const uint32_t offset = window_.confidence_offset();
    const int32_t r = static_cast<int32_t>(sequence_.exclusion);
    uint32_t low = UINT32_MAX;
    for (int32_t k = 2; k <= r; ++k) {
      for (int32_t d = best - k; d <= best + k; d += 2 * k) {
        if (window_.full_sequence(d)) {
          const uint32_t c = window_.cost(d) - offset;
          if (c < low) low = c;
        } else if (k == 2) {
          low = 0;  // a neighbour is missing: the place is not known to +-1
        }
      }
    }
    const UQ16_16 local = on_scale(confidence_ratio(m->cost, low), config_.sharpness);
    if (local > m->confidence) m->confidence = local;
    m->localised = m->runner_up >= 0 && m->confidence < sequence_.threshold;
  }
  const uint32_t tail = config_.tail_steps < sequence_.seq_len ? config_.tail_steps
                                                                : sequence_.seq_len;
  if (m->localised && tail > 0 &&
      !below(window_.recent_cost(best, tail), tail, config_.tail_level)) {
    m->localised = false;
    m->confidence = sequence_.threshold;  // ranks after every fix (and reads as not one)
  }
}

UQ16_16 RouteSearch::on_scale(UQ16_16 ratio, UQ16_16 limit) const {
  if (limit.raw() == 0) return UQ16_16::from_raw(UINT32_MAX);  // nothing is below a limit of 0
  const uint64_t v = static_cast<uint64_t>(ratio.raw()) * sequence_.threshold.raw() / limit.raw();
  return UQ16_16::from_raw(v > UINT32_MAX ? UINT32_MAX : static_cast<uint32_t>(v));
}

bool RouteSearch::below(uint32_t sum, uint32_t steps, UQ16_16 level) const {
  return sum != UINT32_MAX && (static_cast<uint64_t>(sum) << 16) <
                                  static_cast<uint64_t>(window_.value_offset()) * steps * level.raw();
}

void RouteSearch::drop() {
  if (reseed_next_ >= reseed_end_) replayed_ = 0;  // a catch-up in progress ends with it
  probe_.stop();
  probation_ = false;
}

// The candidate's evidence against the prediction's over the same steps (docs/firmware.md,
// "What the scans decide"). Sums are compared as the confidence compares costs: less the
// window's offset (that many times the smallest value seen).
void RouteSearch::decide(uint32_t i, Match* m, RouteStepInfo* inf) {
  const uint32_t steps = probe_.steps();
  const ProbeBest b = probe_.best(config_.slack);
  if (!b.found || steps > life()) {
    drop();
    return;
  }
  if (steps < needed()) return;
  // A known start is not disputed before the window has had its first full sequence.
  if (tracking_ && i + 1 < sequence_.seq_len) return;
  const uint32_t least = window_.min_value() == 0xFFFF ? 0u : window_.min_value();
  const uint32_t offset = steps * least;
  uint32_t held = UINT32_MAX;  // the prediction's best over the same steps
  int32_t held_at = 0;
  if (tracking_) {
    const int32_t r = static_cast<int32_t>(radius());
    for (int32_t d = prediction_ - r; d <= prediction_ + r; ++d) {
      const uint32_t c = window_.recent_cost(d, steps);
      if (c < held) {
        held = c;
        held_at = d;
      }
    }
  }
  // The window's smallest value need not bound the candidate's (computed elsewhere).
  const uint32_t cost = b.cost > offset ? b.cost - offset : 0u;
  const UQ16_16 ratio =
      held == UINT32_MAX ? UQ16_16::from_raw(0) : confidence_ratio(cost, held - offset);
  const bool sharp = config_.sharpness.raw() == 0 ||
                     confidence_ratio(cost, b.local > offset ? b.local - offset : 0u) <
                         config_.sharpness;
  // Uncontested (no prediction, or one past the library's end), the candidate must match on
  // its own: the best of a library is not always a good match.
  const bool matches = held != UINT32_MAX || config_.match_level.raw() == 0 ||
                       below(b.cost, steps, config_.match_level);
  if (ratio < config_.jump_ratio && sharp && matches) {
    // The candidate wins: the prediction moves there, and the window replays the last S
    // steps from the history between places, so that it tracks with full sequences at once.
    m->place = b.diagonal + static_cast<int32_t>(i);
    m->cost = cost;
    m->runner_up = held == UINT32_MAX ? -1 : held_at + static_cast<int32_t>(i);
    m->runner_up_cost = held == UINT32_MAX ? 0u : held - offset;
    // On the threshold's scale: a jump just below its ratio ranks as a fix just below the
    // threshold.
    m->confidence = on_scale(ratio, config_.jump_ratio);
    m->localised = true;
    inf->fix = true;
    inf->carried = true;
    prediction_ = b.diagonal;
    tracking_ = true;
    since_fix_ = 0;
    drop();
    const uint32_t from = i + 1 >= sequence_.seq_len ? i + 1 - sequence_.seq_len : 0u;
    window_.rewind(from);
    place_window();
    reseed_next_ = from;
    reseed_end_ = i + 1;
    return;
  }
  if (!(ratio < UQ16_16::from_int(1))) drop();  // the prediction explains the steps better
}

// A completed scan's verdict: a confident answer near the prediction confirms it (a candidate
// is dropped); one elsewhere becomes the candidate, unless one is being followed already.
void RouteSearch::judge(const ScanResult& result) {
  if (!result.match.localised) return;
  const uint32_t anchor = result.match.query;
  const int32_t diagonal = result.match.place - static_cast<int32_t>(anchor);
  const int32_t gap = diagonal > prediction_ ? diagonal - prediction_ : prediction_ - diagonal;
  if (tracking_ && gap <= static_cast<int32_t>(radius())) {
    drop();
    return;
  }
  if (probe_.active()) return;
  // Its evidence from the scan's first query image on, but no more steps than it may be
  // followed for by the next step (a slow scan completes many steps after its anchor).
  const uint32_t next = window_.steps();
  uint32_t first = anchor + 1 - scan_.config().seq_len;
  if (next + 1 > first + life()) first = next + 1 - life();
  probe_.start(diagonal, first);
  probation_ = true;
  news_.jumped = true;
}

}  // namespace seqslam
