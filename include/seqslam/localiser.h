// The localiser: preprocessing, the place library, differences and a sequence matcher wired
// together for the two uses of the 2025 thesis.
//
//  - Teach and repeat: teach() stores the places of a library run; localise() matches each
//    place of a later query run against the whole library.
//  - Loop closure in a single run: observe() matches each new place against the run's own
//    earlier places, leaving out the most recent ones (they look alike because they are
//    neighbours, not because the robot came back), then adds it to the library.
//
// The sequence matcher is chosen by LocaliserConfig::matcher:
//  - kDiagonal (default): the diagonal matcher (sequence_matcher.h), one difference row of the
//    whole library per step, locally normalised, a sliding sequence ending at every step.
//  - kSlope: OpenSeqSLAM's trajectories at velocities vmin..vmax (slope_matcher.h) over the
//    same difference rows, for time-sampled runs without odometry; given to the configure()
//    overload that takes a SlopeMatcher.
//  - kHeuristic: the 2015 thesis's greedy Algorithm 1 (heuristic_matcher.h) over disjoint
//    sequences of S steps. Only the distances it asks for are computed (all M places at the
//    first step of a sequence, at most k afterwards), straight from the library's images
//    (which may be on the card), with the same difference as the diagonal path (SAD, or the
//    shift-tolerant SAD when max_shift > 0). The matcher's state is caller-owned and given to
//    the configure() overload that takes a HeuristicMatcher: code that never calls it (the
//    head board's firmware, docs/firmware.md) links none of the heuristic code.
//
// How the diagonal matcher searches is chosen by the configure() overload:
//  - the whole library every step (DiagonalMatcher; the PC tools' reference, docs/accuracy.md);
//  - the route search (route_search.h: a window of diagonals around the odometry's prediction,
//    and a relocalisation scan spread over steps when lost), whose memory and work per step do
//    not grow with the library: what the head board runs (docs/firmware.md).
//
// All memory is caller-owned or a member sized at compile time; no heap.
#pragma once

#include <stdint.h>

#include "seqslam/difference.h"
#include "seqslam/heuristic_matcher.h"
#include "seqslam/image.h"
#include "seqslam/place_library.h"
#include "seqslam/preprocess.h"
#include "seqslam/query_history.h"
#include "seqslam/route_search.h"
#include "seqslam/sequence_matcher.h"
#include "seqslam/slope_matcher.h"
#include "seqslam/span.h"
#include "seqslam/status.h"

namespace seqslam {

// Which sequence matcher the localiser runs (stored on the card as one byte: keep the values).
enum class LocaliserMatcher : uint8_t {
  kDiagonal = 0,   // sequence_matcher.h
  kHeuristic = 1,  // heuristic_matcher.h
  kSlope = 2,      // slope_matcher.h
};

struct LocaliserConfig {
  // Image size after the pixel pipeline and the preprocessing: the defaults chosen on every
  // real pair (12x10, HE then PN; docs/accuracy.md, "Choosing the defaults"). The thesis's
  // "standard" 32x16 and "filling" 25x20 work the same way.
  ImageSize image_size{12, 10};
  PreprocessConfig preprocess{Preprocessing::kHistEqPatchNorm, PatchNormConfig{}};
  // Horizontal shift tolerance of the image difference in pixels; 0 = plain MAD (fast path).
  uint8_t max_shift = 0;
  SequenceConfig sequence{};
  // Loop-closure mode only: the newest places not matched against (50 places = 10 m).
  uint16_t recent_exclusion = 50;
  LocaliserMatcher matcher = LocaliserMatcher::kDiagonal;
  // The heuristic matcher's own settings: candidates (k), threshold (candidate threshold,
  // grey levels per pixel) and guard. Its seq_len and exclusion are NOT used: S and R are
  // sequence.seq_len and sequence.exclusion, as for the diagonal matcher (and as seqslam eval
  // does), and the decision threshold is sequence.threshold. Validated whichever matcher is
  // selected, like recent_exclusion, so a stored configuration is checked in full.
  HeuristicConfig heuristic{};
  // The route search's settings (route_search.h): used by the configure() overload that takes
  // a RouteSearch, validated whichever overload is called.
  RouteSearchConfig route{};
  // The slope matcher's velocities (vmin, vmax, vsteps); its `seq` is NOT used (S, W, R and
  // the threshold are `sequence`'s). Validated whichever matcher is selected.
  SlopeConfig slope{};
};

// Which setting is wrong, for messages that name the problem.
enum class ConfigIssue : uint8_t {
  kNone = 0,
  kImageSizeZero,
  kImageTooLarge,
  kPreprocessingInvalid,
  kSeqLenOutOfRange,
  kWindowOutOfRange,
  kSigmaMinZero,
  kThresholdOutOfRange,
  kMaxShiftOutOfRange,
  kRecentExclusionZero,
  kLibraryMismatch,
  kStorageTooSmall,
  kMatcherUnknown,
  kHeuristicCandidatesOutOfRange,
  kHeuristicGuardZero,
  kHeuristicMatcherMissing,
  kRouteWindowOutOfRange,
  kRouteLostAfterZero,
  kRouteScanPlacesZero,
  kRouteStartOutOfRange,
  kRouteStorageTooSmall,
  kRouteHeuristic,
  kRouteMaxShift,
  kRouteScanSeqLenOutOfRange,
  kHeuristicHistoryMissing,
  kHeuristicNotSelected,
  kSlopeOutOfRange,
  kSlopeMatcherMissing,
  kSlopeNotSelected,
  kRouteJumpStepsZero,
};

// A sentence naming the setting and its valid range, e.g.
// "sequence.seq_len must be 1..100".
const char* config_issue_text(ConfigIssue issue);

struct ConfigCheck {
  Status status = Status::kOk;
  ConfigIssue issue = ConfigIssue::kNone;
  constexpr bool ok() const { return status == Status::kOk; }
};

// Validates a configuration on its own (no storage involved).
ConfigCheck check_localiser_config(const LocaliserConfig& config);

class Localiser {
 public:
  // Adopts the configuration, the library (configured for config.image_size, possibly
  // already holding places) and the matcher buffers; `differences` is scratch for one
  // difference row and must hold at least library.capacity() values. On failure the
  // localiser is unconfigured and the check says why: check_localiser_config's issues,
  // kLibraryMismatch (kInvalidArgument) if the library was set up for another image size,
  // kStorageTooSmall (kResourceExhausted) if the matcher buffers or the difference scratch
  // hold fewer places than the library. This overload runs the diagonal matcher only:
  // config.matcher == kHeuristic is refused with kHeuristicMatcherMissing (kResourceExhausted).
  ConfigCheck configure(const LocaliserConfig& config, PlaceLibrary& library,
                        const DiagonalMatcherBuffers& matcher_buffers, Span<uint32_t> differences);

  // The heuristic matcher (config.matcher must be kHeuristic, else kHeuristicNotSelected):
  // `heuristic` holds its state, is configured here with S and R from config.sequence, and
  // must outlive the localiser's use. Each overload configures one search, so an image links
  // only the searches it configures (the head board: the route search and the heuristic).
  // With config.heuristic.scan_places > 0 (the first image's scan spread over steps) the
  // first image is read back on later steps from `history` (the head board's is on the card),
  // where every query is put: required then (kHeuristicHistoryMissing), else may be null.
  ConfigCheck configure(const LocaliserConfig& config, PlaceLibrary& library,
                        HeuristicMatcher& heuristic, QueryHistory* history = nullptr);

  // The route search (route_search.h) instead of the whole library: `route` is configured
  // here with config.route and config.sequence on `buffers` and `history` and must outlive the
  // localiser's use. Diagonal matcher only (kRouteHeuristic for the heuristic); route issues
  // (kRoute*) as RouteSearch::check names them. No difference row: last_differences() is then
  // null.
  ConfigCheck configure(const LocaliserConfig& config, PlaceLibrary& library, RouteSearch& route,
                        const RouteSearchBuffers& buffers, QueryHistory& history);

  // The slope matcher (config.matcher must be kSlope, else kSlopeNotSelected) on `buffers`,
  // with `differences` as for the diagonal overload (kStorageTooSmall likewise): `slope` is
  // configured here with config.slope's velocities and config.sequence, and must outlive the
  // localiser's use.
  ConfigCheck configure(const LocaliserConfig& config, PlaceLibrary& library, SlopeMatcher& slope,
                        const SlopeMatcherBuffers& buffers, Span<uint32_t> differences);

  // Teach: preprocess `raw` and append it to the library. kFailedPrecondition when not
  // configured, kInvalidArgument for a null image or one not of config.image_size,
  // kResourceExhausted when the library is full.
  Status teach(ImageView raw, const Pose2& pose, uint32_t capture);

  // Repeat: preprocess `raw` and take one matcher step against the whole library.
  // Statuses as teach() (except kResourceExhausted); storage errors of a library on the card
  // pass through (the matcher is then unchanged).
  //
  // With the heuristic matcher the Match is its answer after this step (the anytime answer
  // inside a sequence, the sequence's final answer at its last step):
  //   query      - step index since the last reset (as for the diagonal matcher);
  //   place      - the best trail's library place now (start + offset); -1 when no place was
  //                below the candidate threshold at the sequence's first step, or every trail
  //                left the library (unknown place). Unlike the diagonal matcher it answers
  //                from the first step of a sequence on (a partial sum);
  //   cost       - that trail's distance sum over the sequence so far, in raw SAD units
  //                (saturating; no local normalisation, no offset: not on the diagonal
  //                matcher's UQ.11 scale, and growing within a sequence);
  //   runner_up, runner_up_cost - the best other trail more than R places away, its sum;
  //   confidence - cost / runner_up_cost (1.0 without a runner-up), smaller = more certain;
  //   localised  - place >= 0 and confidence < sequence.threshold (tune that threshold for
  //                the heuristic separately: heuristic_matcher.h).
  Status localise(ImageView raw, Match* out);

  // Loop closure: preprocess `raw`, take one matcher step against the places older than
  // recent_exclusion, then append `raw` as a new place. The match is reported even when the
  // library is full (kResourceExhausted is returned then, after the match is written).
  // Both matchers: the heuristic's trails advance one place per step while the matched part
  // of the library grows by one place per step, so a trail stays inside it.
  Status observe(ImageView raw, const Pose2& pose, uint32_t capture, Match* out);

  // The PC's bulk evaluation, which computes the differences itself (a SIMD kernel over the
  // whole difference matrix, docs/architecture.md): one matcher step on a given difference row
  // of `differences.size()` places instead of a query image. The full search (the diagonal
  // overload) and the slope matcher only: kFailedPrecondition otherwise; the matcher's
  // statuses.
  Status localise_differences(Span<const uint32_t> differences, Match* out);
  // The same for the heuristic matcher: the distances it asks for come from `distances`
  // (step indices count from the last reset) over `places` library places. kFailedPrecondition
  // unless the heuristic is configured; the matcher's statuses.
  Status localise_distances(PlaceDistance& distances, uint32_t places, Match* out);

  // Forget the query history (kidnapping, a new run against the same library); with the
  // heuristic the next step starts a new sequence.
  void reset_sequence();

  // The query history, to continue a stopped run (state_io.h): the full search's matcher.
  // The heuristic's and the route search's are not saved yet: with them the io fails with
  // kFailedPrecondition.
  template <class Io>
  void state(Io& io) {
    if (heuristic_ != nullptr || route_ != nullptr) {
      io.fail_with(Status::kFailedPrecondition);
      return;
    }
    matcher_.state(io);
  }

  // The diagonal matcher (not used, and not reconfigured, while the heuristic is selected).
  const DiagonalMatcher& matcher() const { return matcher_; }
  // The heuristic matcher given to configure() while it is selected, else nullptr.
  const HeuristicMatcher* heuristic() const { return heuristic_; }
  // The slope matcher given to configure() while it is selected, else nullptr.
  const SlopeMatcher* slope() const { return slope_; }
  // The route search given to configure(), else nullptr; and what it did at the last step.
  const RouteSearch* route() const { return route_; }
  // Work between places: the route search's share of its scan (RouteSearch::work), up to
  // `budget` library places; the places streamed (0 for the other searches).
  uint32_t work(uint32_t budget) {
    return route_ != nullptr ? route_->work(*library_, budget) : 0u;
  }
  const RouteStepInfo& route_step() const { return route_info_; }
  const PlaceLibrary* library() const { return library_; }
  const LocaliserConfig& config() const { return config_; }
  // The last preprocessed query image.
  ImageView last_query() const { return ImageView{query_, config_.image_size}; }
  // The raw differences of the last step (valid for matcher().places() places; diagonal
  // matcher only: the heuristic keeps no difference row).
  const uint32_t* last_differences() const { return differences_.data(); }  // null: route

 private:
  ConfigCheck adopt(const LocaliserConfig& config, PlaceLibrary& library);
  Status prepare(ImageView raw);
  Status match(uint32_t places, Match* out);
  // One heuristic step. Reached only through step_fn_, which only the configure()
  // overload with a HeuristicMatcher sets: that keeps it (and the matcher's code) out of
  // images that never call that overload, after the linker's garbage collection.
  static Status heuristic_step(Localiser& self, uint32_t places, Match* out);
  // One route-search step, and one full-search step, reached the same way for the same
  // reason.
  static Status route_step(Localiser& self, uint32_t places, Match* out);
  static Status full_step(Localiser& self, uint32_t places, Match* out);
  static Status slope_step(Localiser& self, uint32_t places, Match* out);
  // The difference row of the current query against the first `places` places (SAD, or the
  // shift-tolerant SAD) into differences_.
  Status difference_row(uint32_t places);
  static Match heuristic_match(const HeuristicMatch& hm, UQ16_16 threshold);

  LocaliserConfig config_{};
  PlaceLibrary* library_ = nullptr;
  DiagonalMatcher matcher_{};
  HeuristicMatcher* heuristic_ = nullptr;
  SlopeMatcher* slope_ = nullptr;
  QueryHistory* history_ = nullptr;  // the heuristic's, when its scan is budgeted
  // The heuristic's or the route search's step, set by their configure() overloads.
  Status (*step_fn_)(Localiser&, uint32_t, Match*) = nullptr;
  RouteSearch* route_ = nullptr;
  RouteStepInfo route_info_{};
  Span<uint32_t> differences_{};
  uint8_t query_[kMaxPixels] = {};
};

}  // namespace seqslam
