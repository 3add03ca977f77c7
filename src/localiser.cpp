#include "seqslam/localiser.h"

namespace seqslam {

const char* config_issue_text(ConfigIssue issue) {
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
  }
  return "unknown configuration issue";
}

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
  return {};
}

ConfigCheck Localiser::configure(const LocaliserConfig& config, PlaceLibrary& library,
                                 const DiagonalMatcherBuffers& matcher_buffers,
                                 Span<uint32_t> differences) {
  library_ = nullptr;
  const ConfigCheck check = check_localiser_config(config);
  if (!check.ok()) return check;
  if (library.capacity() == 0 || library.image_size() != config.image_size) {
    return {Status::kInvalidArgument, ConfigIssue::kLibraryMismatch};
  }
  const Status s = matcher_.configure(config.sequence, config.image_size.pixels(), matcher_buffers);
  if (s != Status::kOk) return {s, ConfigIssue::kStorageTooSmall};
  if (matcher_.capacity() < library.capacity() || differences.size() < library.capacity()) {
    return {Status::kResourceExhausted, ConfigIssue::kStorageTooSmall};
  }
  config_ = config;
  library_ = &library;
  differences_ = differences;
  return {};
}

Status Localiser::prepare(ImageView raw) {
  if (library_ == nullptr) return Status::kFailedPrecondition;
  if (raw.pixels == nullptr || raw.size != config_.image_size) return Status::kInvalidArgument;
  return preprocess(config_.preprocess, raw, MutableImageView{query_, config_.image_size});
}

Status Localiser::match(uint32_t places, Match* out) {
  const ImageView query{query_, config_.image_size};
  if (config_.max_shift == 0) {
    const Status s = library_->differences(query, places, differences_.data());
    if (s != Status::kOk) return s;
  } else {
    for (uint32_t j = 0; j < places; ++j) {
      ImageView place;
      const Status s = library_->image(j, &place);
      if (s != Status::kOk) return s;
      // Cannot fail: sizes were checked at configure() and prepare().
      differences_[j] = shift_tolerant_sad(query, place, config_.max_shift).value();
    }
  }
  return matcher_.step(Span<const uint32_t>(differences_.data(), places), out);
}

Status Localiser::teach(ImageView raw, const Pose2& pose, uint32_t capture) {
  if (library_ != nullptr && library_->full()) return Status::kResourceExhausted;
  const Status s = prepare(raw);
  if (s != Status::kOk) return s;
  return library_->add(ImageView{query_, config_.image_size}, pose, capture);
}

Status Localiser::localise(ImageView raw, Match* out) {
  const Status s = prepare(raw);
  if (s != Status::kOk) return s;
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
