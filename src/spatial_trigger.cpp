#include "seqslam/spatial_trigger.h"

namespace seqslam {

Status SpatialTrigger::configure(Q31_32 spacing) {
  if (spacing.raw() <= 0) return Status::kInvalidArgument;
  if (spacing > kMaxSpacing) return Status::kOutOfRange;
  spacing_ = spacing;
  reset();
  return Status::kOk;
}

void SpatialTrigger::reset() {
  armed_ = true;
  captures_ = 0;
}

namespace {

// |a - b| of two Q31.32 values reduced to Q15.16 (resolution 15 um), capped at 2^30 (16 km)
// so its square and the sum of two squares fit an int64. The subtraction wraps instead of
// overflowing; poses are far inside +-2^30 m.
int64_t reduced_distance(int64_t a, int64_t b) {
  const int64_t d = static_cast<int64_t>(static_cast<uint64_t>(a) - static_cast<uint64_t>(b));
  const int64_t v = (d >= 0 ? d : -d) >> 16;
  const int64_t cap = int64_t{1} << 30;
  return v < cap ? v : cap;
}

}  // namespace

bool SpatialTrigger::update(const Pose2& pose) {
  if (armed_) {
    armed_ = false;
    last_ = pose;
    ++captures_;
    return true;
  }
  const int64_t dx = reduced_distance(pose.x.raw(), last_.x.raw());
  const int64_t dy = reduced_distance(pose.y.raw(), last_.y.raw());
  const int64_t s = spacing_.raw() >> 16;
  if (dx * dx + dy * dy < s * s) return false;
  last_ = pose;
  ++captures_;
  return true;
}

}  // namespace seqslam
