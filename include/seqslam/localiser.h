// The localiser: preprocessing, the place library, differences and the diagonal matcher
// wired together for the two uses of the 2025 thesis.
//
//  - Teach and repeat: teach() stores the places of a library run; localise() matches each
//    place of a later query run against the whole library.
//  - Loop closure in a single run: observe() matches each new place against the run's own
//    earlier places, leaving out the most recent ones (they look alike because they are
//    neighbours, not because the robot came back), then adds it to the library.
//
// All memory is caller-owned or a member sized at compile time; no heap.
#pragma once

#include <stdint.h>

#include "seqslam/difference.h"
#include "seqslam/image.h"
#include "seqslam/place_library.h"
#include "seqslam/preprocess.h"
#include "seqslam/sequence_matcher.h"
#include "seqslam/span.h"
#include "seqslam/status.h"

namespace seqslam {

struct LocaliserConfig {
  // Image size after the pixel pipeline (the robot default is the thesis's "standard"
  // 32x16; its recommended "filling" 25x20 works the same way).
  ImageSize image_size{32, 16};
  PreprocessConfig preprocess{};
  // Horizontal shift tolerance of the image difference in pixels; 0 = plain MAD (fast path).
  uint8_t max_shift = 0;
  SequenceConfig sequence{};
  // Loop-closure mode only: the newest places not matched against (50 places = 10 m).
  uint16_t recent_exclusion = 50;
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
  // hold fewer places than the library.
  ConfigCheck configure(const LocaliserConfig& config, PlaceLibrary& library,
                        const DiagonalMatcherBuffers& matcher_buffers, Span<uint32_t> differences);

  // Teach: preprocess `raw` and append it to the library. kFailedPrecondition when not
  // configured, kInvalidArgument for a null image or one not of config.image_size,
  // kResourceExhausted when the library is full.
  Status teach(ImageView raw, const Pose2& pose, uint32_t capture);

  // Repeat: preprocess `raw` and take one matcher step against the whole library.
  // Statuses as teach() (except kResourceExhausted).
  Status localise(ImageView raw, Match* out);

  // Loop closure: preprocess `raw`, take one matcher step against the places older than
  // recent_exclusion, then append `raw` as a new place. The match is reported even when the
  // library is full (kResourceExhausted is returned then, after the match is written).
  Status observe(ImageView raw, const Pose2& pose, uint32_t capture, Match* out);

  // Forget the query history (kidnapping, a new run against the same library).
  void reset_sequence() { matcher_.reset(); }

  const DiagonalMatcher& matcher() const { return matcher_; }
  const PlaceLibrary* library() const { return library_; }
  const LocaliserConfig& config() const { return config_; }
  // The last preprocessed query image.
  ImageView last_query() const { return ImageView{query_, config_.image_size}; }
  // The raw differences of the last step (valid for matcher().places() places).
  const uint32_t* last_differences() const { return differences_.data(); }

 private:
  Status prepare(ImageView raw);
  Status match(uint32_t places, Match* out);

  LocaliserConfig config_{};
  PlaceLibrary* library_ = nullptr;
  DiagonalMatcher matcher_{};
  Span<uint32_t> differences_{};
  uint8_t query_[kMaxPixels] = {};
};

}  // namespace seqslam
