#include "seqslam/localiser.h"

#include "seqslam/assert.h"
#include "seqslam/messages.h"

namespace seqslam {

const char* config_issue_text(ConfigIssue issue) {
#if !SEQSLAM_MESSAGE_TEXTS
  return message_code("CI", static_cast<uint32_t>(issue));
#endif
  switch (issue) {
    case ConfigIssue::kNone:
      return "configuration is valid";
    case ConfigIssue::kImageSizeZero:
      return "image_size width and height must be at least 1";
    case ConfigIssue::kImageTooLarge:
      return "image_size width * height exceeds SEQSLAM_MAX_PIXELS (the compile-time capacity)";
    case ConfigIssue::kPreprocessingInvalid:
      return "preprocess: unknown method, or patch size 0, a 1-pixel patch, or gain 0";
    case ConfigIssue::kSeqLenOutOfRange:
      return "sequence.seq_len must be 1..100 (kMaxSeqLen)";
    case ConfigIssue::kWindowOutOfRange:
      return "sequence.window must be 0 (off) or 2..255 (kMaxWindow)";
    case ConfigIssue::kSigmaMinZero:
      return "sequence.sigma_min must be > 0 when the window is on";
    case ConfigIssue::kThresholdOutOfRange:
      return "sequence.threshold must be within 0..1";
    case ConfigIssue::kMaxShiftOutOfRange:
      return "max_shift must be smaller than the image width";
    case ConfigIssue::kRecentExclusionZero:
      return "recent_exclusion must be at least 1";
    case ConfigIssue::kLibraryMismatch:
      return "the place library is not configured for image_size";
    case ConfigIssue::kStorageTooSmall:
      return "matcher buffers or difference scratch hold fewer places than the library";
    case ConfigIssue::kMatcherUnknown:
      return "matcher must be diagonal (0), heuristic (1) or slope (2)";
    case ConfigIssue::kHeuristicCandidatesOutOfRange:
      return "heuristic.candidates (k) must be 1..16";
    case ConfigIssue::kHeuristicGuardZero:
      return "heuristic.guard must be at least 1";
    case ConfigIssue::kHeuristicMatcherMissing:
      return "matcher heuristic needs a HeuristicMatcher given to Localiser::configure";
    case ConfigIssue::kRouteWindowOutOfRange:
      return route_issue_text(RouteIssue::kWindowOutOfRange);
    case ConfigIssue::kRouteLostAfterZero:
      return route_issue_text(RouteIssue::kLostAfterZero);
    case ConfigIssue::kRouteScanPlacesZero:
      return route_issue_text(RouteIssue::kScanPlacesZero);
    case ConfigIssue::kRouteStartOutOfRange:
      return route_issue_text(RouteIssue::kStartOutOfRange);
    case ConfigIssue::kRouteScanSeqLenOutOfRange:
      return route_issue_text(RouteIssue::kScanSeqLenOutOfRange);
    case ConfigIssue::kRouteStorageTooSmall:
      return route_issue_text(RouteIssue::kStorageTooSmall);
    case ConfigIssue::kRouteJumpStepsZero:
      return route_issue_text(RouteIssue::kJumpStepsZero);
    case ConfigIssue::kRouteHeuristic:
      return "the route search runs the diagonal matcher only";
    case ConfigIssue::kRouteMaxShift:
      return "the route search uses the plain SAD: max_shift must be 0";
    case ConfigIssue::kHeuristicNotSelected:
      return "the HeuristicMatcher overload needs matcher heuristic";
    case ConfigIssue::kHeuristicHistoryMissing:
      return "heuristic.scan_places > 0 needs a query history for the scan's first image";
    case ConfigIssue::kSlopeOutOfRange:
      return "slope: vmin must be above 0 and at most vmax <= 4, vsteps 1..32 (1 needs vmin == "
             "vmax)";
    case ConfigIssue::kSlopeMatcherMissing:
      return "matcher slope needs a SlopeMatcher given to Localiser::configure";
    case ConfigIssue::kSlopeNotSelected:
      return "the SlopeMatcher overload needs matcher slope";
  }
  return "unknown configuration issue";
}

namespace {
ConfigIssue route_config_issue(RouteIssue issue);
}  // namespace

ConfigCheck check_localiser_config(const LocaliserConfig& c) {
  const Status size = check_image_size(c.image_size);
  if (size == Status::kInvalidArgument) return {size, ConfigIssue::kImageSizeZero};
  if (size != Status::kOk) return {size, ConfigIssue::kImageTooLarge};
  const Status pre = check_preprocess_config(c.preprocess);
  if (pre != Status::kOk) return {pre, ConfigIssue::kPreprocessingInvalid};
  const SequenceConfig& s = c.sequence;
  if (s.seq_len == 0 || s.seq_len > kMaxSeqLen) {
    return {Status::kOutOfRange, ConfigIssue::kSeqLenOutOfRange};
  }
  if (s.window == 1 || s.window > kMaxWindow) {
    return {Status::kOutOfRange, ConfigIssue::kWindowOutOfRange};
  }
  if (s.window > 0 && s.sigma_min.raw() == 0) {
    return {Status::kInvalidArgument, ConfigIssue::kSigmaMinZero};
  }
  if (s.threshold > UQ16_16::from_int(1)) {
    return {Status::kOutOfRange, ConfigIssue::kThresholdOutOfRange};
  }
  if (c.max_shift >= c.image_size.width) {
    return {Status::kOutOfRange, ConfigIssue::kMaxShiftOutOfRange};
  }
  if (c.recent_exclusion == 0) return {Status::kInvalidArgument, ConfigIssue::kRecentExclusionZero};
  if (c.matcher != LocaliserMatcher::kDiagonal && c.matcher != LocaliserMatcher::kHeuristic &&
      c.matcher != LocaliserMatcher::kSlope) {
    return {Status::kOutOfRange, ConfigIssue::kMatcherUnknown};
  }
  // The slope matcher's velocities (its S, W, R and threshold are `sequence`'s, checked
  // above): check_slope_config's rules, here so that images without the slope matcher do not
  // link its code.
  const SlopeConfig& v = c.slope;
  if (v.vsteps == 0 || v.vsteps > kMaxVelocitySteps || v.vmin.raw() == 0 ||
      v.vmax.raw() > kMaxVelocityRaw || v.vmin > v.vmax || (v.vsteps == 1 && v.vmin != v.vmax)) {
    return {Status::kOutOfRange, ConfigIssue::kSlopeOutOfRange};
  }
  // The heuristic's own settings (its S is sequence.seq_len, checked above; any candidate
  // threshold is valid, 0 accepting nothing).
  if (c.heuristic.candidates == 0 || c.heuristic.candidates > kMaxHeuristicCandidates) {
    return {Status::kOutOfRange, ConfigIssue::kHeuristicCandidatesOutOfRange};
  }
  if (c.heuristic.guard == 0) return {Status::kInvalidArgument, ConfigIssue::kHeuristicGuardZero};
  // The route settings that do not depend on storage (RouteSearch::check does the rest). A
  // window too narrow for R matters only where the route search runs (RouteSearch::check and
  // the firmware's run check): the full search's R may be larger than the board's.
  SequenceConfig any_exclusion = s;
  any_exclusion.exclusion = 0;
  const RouteIssue route = check_route_settings(c.route, any_exclusion);
  if (route != RouteIssue::kNone) return {route_issue_status(route), route_config_issue(route)};
  return {};
}

namespace {

ConfigIssue route_config_issue(RouteIssue issue) {
  switch (issue) {
    case RouteIssue::kWindowOutOfRange:
      return ConfigIssue::kRouteWindowOutOfRange;
    case RouteIssue::kLostAfterZero:
      return ConfigIssue::kRouteLostAfterZero;
    case RouteIssue::kScanPlacesZero:
      return ConfigIssue::kRouteScanPlacesZero;
    case RouteIssue::kStartOutOfRange:
      return ConfigIssue::kRouteStartOutOfRange;
    case RouteIssue::kScanSeqLenOutOfRange:
      return ConfigIssue::kRouteScanSeqLenOutOfRange;
    case RouteIssue::kJumpStepsZero:
      return ConfigIssue::kRouteJumpStepsZero;
    case RouteIssue::kStorageTooSmall:
    case RouteIssue::kNone:
      break;
  }
  return ConfigIssue::kRouteStorageTooSmall;
}

}  // namespace

// What every overload checks first; leaves the localiser unconfigured.
ConfigCheck Localiser::adopt(const LocaliserConfig& config, PlaceLibrary& library) {
  library_ = nullptr;
  heuristic_ = nullptr;
  slope_ = nullptr;
  history_ = nullptr;
  route_ = nullptr;
  step_fn_ = nullptr;
  differences_ = Span<uint32_t>();
  const ConfigCheck check = check_localiser_config(config);
  if (!check.ok()) return check;
  if (library.capacity() == 0 || library.image_size() != config.image_size) {
    return {Status::kInvalidArgument, ConfigIssue::kLibraryMismatch};
  }
  return {};
}

ConfigCheck Localiser::configure(const LocaliserConfig& config, PlaceLibrary& library,
                                 const DiagonalMatcherBuffers& matcher_buffers,
                                 Span<uint32_t> differences) {
  const ConfigCheck check = adopt(config, library);
  if (!check.ok()) return check;
  if (config.matcher != LocaliserMatcher::kDiagonal) {
    return {Status::kResourceExhausted, config.matcher == LocaliserMatcher::kSlope
                                            ? ConfigIssue::kSlopeMatcherMissing
                                            : ConfigIssue::kHeuristicMatcherMissing};
  }
  const Status s = matcher_.configure(config.sequence, config.image_size.pixels(), matcher_buffers);
  if (s != Status::kOk) return {s, ConfigIssue::kStorageTooSmall};
  if (matcher_.capacity() < library.capacity() || differences.size() < library.capacity()) {
    return {Status::kResourceExhausted, ConfigIssue::kStorageTooSmall};
  }
  config_ = config;
  library_ = &library;
  differences_ = differences;
  step_fn_ = &Localiser::full_step;
  return {};
}

ConfigCheck Localiser::configure(const LocaliserConfig& config, PlaceLibrary& library,
                                 HeuristicMatcher& heuristic, QueryHistory* history) {
  const ConfigCheck check = adopt(config, library);
  if (!check.ok()) return check;
  if (config.matcher != LocaliserMatcher::kHeuristic) {
    return {Status::kInvalidArgument, ConfigIssue::kHeuristicNotSelected};
  }
  if (config.heuristic.scan_places != 0 &&
      (history == nullptr || history->pixels() != config.image_size.pixels())) {
    return {Status::kInvalidArgument, ConfigIssue::kHeuristicHistoryMissing};
  }
  HeuristicConfig hc = config.heuristic;
  hc.seq_len = config.sequence.seq_len;
  hc.exclusion = config.sequence.exclusion;
  // Cannot fail: check_localiser_config validated k, the guard, S and the image size.
  const Status s = heuristic.configure(hc, config.image_size.pixels());
  SEQSLAM_ASSERT(s == Status::kOk);
  config_ = config;
  library_ = &library;
  heuristic_ = &heuristic;
  history_ = history;
  if (history_ != nullptr) history_->clear();
  step_fn_ = &Localiser::heuristic_step;
  return check;
}

ConfigCheck Localiser::configure(const LocaliserConfig& config, PlaceLibrary& library,
                                 RouteSearch& route, const RouteSearchBuffers& buffers,
                                 QueryHistory& history) {
  const ConfigCheck check = adopt(config, library);
  if (!check.ok()) return check;
  if (config.matcher != LocaliserMatcher::kDiagonal) {
    return {Status::kInvalidArgument, ConfigIssue::kRouteHeuristic};
  }
  if (config.max_shift != 0) return {Status::kInvalidArgument, ConfigIssue::kRouteMaxShift};
  RouteIssue issue = RouteIssue::kNone;
  const Status s = route.configure(config.route, config.sequence, config.image_size.pixels(),
                                   buffers, history, &issue);
  if (s != Status::kOk) return {s, route_config_issue(issue)};
  config_ = config;
  library_ = &library;
  route_ = &route;
  route_info_ = RouteStepInfo{};
  step_fn_ = &Localiser::route_step;
  return {};
}

ConfigCheck Localiser::configure(const LocaliserConfig& config, PlaceLibrary& library,
                                 SlopeMatcher& slope, const SlopeMatcherBuffers& buffers,
                                 Span<uint32_t> differences) {
  const ConfigCheck check = adopt(config, library);
  if (!check.ok()) return check;
  if (config.matcher != LocaliserMatcher::kSlope) {
    return {Status::kInvalidArgument, ConfigIssue::kSlopeNotSelected};
  }
  SlopeConfig sc = config.slope;
  sc.seq = config.sequence;
  const Status s = slope.configure(sc, config.image_size.pixels(), buffers);
  if (s != Status::kOk) return {s, ConfigIssue::kStorageTooSmall};
  if (slope.capacity() < library.capacity() || differences.size() < library.capacity()) {
    return {Status::kResourceExhausted, ConfigIssue::kStorageTooSmall};
  }
  config_ = config;
  library_ = &library;
  slope_ = &slope;
  differences_ = differences;
  step_fn_ = &Localiser::slope_step;
  return {};
}

Status Localiser::route_step(Localiser& self, uint32_t places, Match* out) {
  Match m;
  const Status s =
      self.route_->step(*self.library_, ImageView{self.query_, self.config_.image_size}, places, &m,
                        &self.route_info_);
  if (s == Status::kOk && out != nullptr) *out = m;
  return s;
}

void Localiser::reset_sequence() {
  if (step_fn_ == &Localiser::full_step) matcher_.reset();
  if (slope_ != nullptr) slope_->reset();
  if (heuristic_ != nullptr) heuristic_->reset();
  if (history_ != nullptr) history_->clear();
  if (route_ != nullptr) route_->reset();
}

Status Localiser::prepare(ImageView raw) {
  if (library_ == nullptr) return Status::kFailedPrecondition;
  if (raw.pixels == nullptr || raw.size != config_.image_size) return Status::kInvalidArgument;
  return preprocess(config_.preprocess, raw, MutableImageView{query_, config_.image_size});
}

Status Localiser::match(uint32_t places, Match* out) {
  // Set by every configure() overload that succeeded (prepare() refused the others).
  return step_fn_(*this, places, out);
}

Status Localiser::difference_row(uint32_t places) {
  const ImageView query{query_, config_.image_size};
  uint32_t* differences = differences_.data();
  if (config_.max_shift == 0) return library_->differences(query, places, differences);
  for (uint32_t j = 0; j < places; ++j) {
    ImageView place;
    SEQSLAM_TRY(library_->image(j, &place));
    // Cannot fail: sizes were checked at configure() and prepare().
    differences[j] = shift_tolerant_sad(query, place, config_.max_shift).value();
  }
  return Status::kOk;
}

Status Localiser::full_step(Localiser& self, uint32_t places, Match* out) {
  SEQSLAM_TRY(self.difference_row(places));
  Match m;
  const Status s =
      self.matcher_.step(Span<const uint32_t>(self.differences_.data(), places), &m);
  if (s == Status::kOk && out != nullptr) *out = m;
  return s;
}

Status Localiser::slope_step(Localiser& self, uint32_t places, Match* out) {
  SEQSLAM_TRY(self.difference_row(places));
  Match m;
  const Status s = self.slope_->step(Span<const uint32_t>(self.differences_.data(), places), &m);
  if (s == Status::kOk && out != nullptr) *out = m;
  return s;
}

// Field meanings for the heuristic: localise() in localiser.h. A partial candidate set (the
// scan still running) is never a fix. Inlined: the board's image has one caller.
__attribute__((always_inline)) inline Match Localiser::heuristic_match(const HeuristicMatch& hm,
                                                                       UQ16_16 threshold) {
  Match m;
  m.query = hm.query;
  m.place = hm.place;
  m.cost = hm.sum;
  m.runner_up = hm.runner_up;
  m.runner_up_cost = hm.runner_up_sum;
  m.confidence = hm.confidence;
  m.localised = hm.place >= 0 && !hm.scanning && hm.confidence < threshold;
  return m;
}

Status Localiser::localise_differences(Span<const uint32_t> differences, Match* out) {
  if (library_ == nullptr) return Status::kFailedPrecondition;
  Match m;
  Status s = Status::kFailedPrecondition;
  if (step_fn_ == &Localiser::full_step) {
    s = matcher_.step(differences, &m);
  } else if (slope_ != nullptr) {
    s = slope_->step(differences, &m);
  }
  if (s == Status::kOk && out != nullptr) *out = m;
  return s;
}

Status Localiser::localise_distances(PlaceDistance& distances, uint32_t places, Match* out) {
  if (library_ == nullptr || heuristic_ == nullptr) return Status::kFailedPrecondition;
  HeuristicMatch hm;
  const Status s = heuristic_->step(distances, places, &hm);
  if (s == Status::kOk && out != nullptr) *out = heuristic_match(hm, config_.sequence.threshold);
  return s;
}


namespace {

// The distances the heuristic asks for, computed on demand between the current preprocessed
// query and library place j as read through the library's image store (RAM or the card): the
// same values the diagonal path puts in its difference row (SAD, or the shift-tolerant SAD).
// It holds only the current query image, so it answers only for the matcher's current step.
class LibraryDistance final : public PlaceDistance {
 public:
  LibraryDistance(PlaceLibrary& library, ImageView query, uint8_t max_shift, uint32_t step,
                  QueryHistory* history)
      : library_(library),
        query_(query),
        max_shift_(max_shift),
        step_(step),
        history_(history) {}

 private:
  // The query image of `query`: this step's, or an earlier one from the history (the first
  // image of a greedy scan spread over steps).
  Status image_of(uint32_t query, ImageView* out) {
    if (query == step_) {
      *out = query_;
      return Status::kOk;
    }
    if (history_ == nullptr) return Status::kInvalidArgument;
    const uint8_t* pixels = nullptr;
    uint32_t places = 0;
    const Status s = history_->get(query, &pixels, &places);
    if (s == Status::kOk) *out = ImageView{pixels, query_.size};
    return s;
  }

  Status do_distance(uint32_t query, uint32_t place, uint32_t* out) override {
    ImageView q;
    Status s = image_of(query, &q);
    if (s != Status::kOk) return s;
    ImageView image;
    s = library_.image(place, &image);
    if (s != Status::kOk) return s;
    // Cannot fail: sizes were checked at configure() and prepare(), max_shift < width.
    *out = (max_shift_ == 0 ? sad(q, image) : shift_tolerant_sad(q, image, max_shift_)).value();
    return Status::kOk;
  }

  // The plain SAD streams the library (sad_many); the shift-tolerant one goes place by place.
  Status do_distances(uint32_t query, uint32_t first, uint32_t count, uint32_t* out) override {
    if (max_shift_ != 0) {
      for (uint32_t i = 0; i < count; ++i) {
        SEQSLAM_TRY(do_distance(query, first + i, out + i));
      }
      return Status::kOk;
    }
    ImageView q;
    SEQSLAM_TRY(image_of(query, &q));
    return library_.differences(q, first, count, out);
  }

  PlaceLibrary& library_;
  ImageView query_;
  uint8_t max_shift_;
  uint32_t step_;
  QueryHistory* history_;
};

}  // namespace

Status Localiser::heuristic_step(Localiser& self, uint32_t places, Match* out) {
  HeuristicMatcher& h = *self.heuristic_;
  if (self.history_ != nullptr) {
    // The first image of a budgeted scan is read back from here on later steps.
    SEQSLAM_TRY(self.history_->put(h.query(), self.query_, places));
  }
  LibraryDistance distance(*self.library_, ImageView{self.query_, self.config_.image_size},
                           self.config_.max_shift, h.query(), self.history_);
  HeuristicMatch hm;
  SEQSLAM_TRY(h.step(distance, places, &hm));
  if (out != nullptr) *out = heuristic_match(hm, self.config_.sequence.threshold);
  return Status::kOk;
}

Status Localiser::teach(ImageView raw, const Pose2& pose, uint32_t capture) {
  if (library_ != nullptr && library_->full()) return Status::kResourceExhausted;
  SEQSLAM_TRY(prepare(raw));
  return library_->add(ImageView{query_, config_.image_size}, pose, capture);
}

Status Localiser::localise(ImageView raw, Match* out) {
  SEQSLAM_TRY(prepare(raw));
  return match(library_->size(), out);
}

Status Localiser::observe(ImageView raw, const Pose2& pose, uint32_t capture, Match* out) {
  Status s = prepare(raw);
  if (s != Status::kOk) return s;
  const uint32_t size = library_->size();
  const uint32_t older = size > config_.recent_exclusion ? size - config_.recent_exclusion : 0;
  s = match(older, out);
  if (s != Status::kOk) return s;
  return library_->add(ImageView{query_, config_.image_size}, pose, capture);
}

}  // namespace seqslam
