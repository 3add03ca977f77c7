// Spatial sampling: a capture each time the robot has moved a fixed Euclidean distance since
// the previous capture (2025 thesis, section 4.4.1). Two runs of a route are thereby sampled
// at (nearly) the same places whatever their speed, so their image sequences can be compared
// along the diagonal of the difference matrix, without time warping or slope search.
#pragma once

#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/odometry.h"
#include "seqslam/state_io.h"
#include "seqslam/status.h"

namespace seqslam {

class SpatialTrigger {
 public:
  // Default spacing: 20 cm.
  static constexpr Q31_32 kDefaultSpacing = Q31_32::from_ratio(1, 5);
  // Largest spacing: 1 km.
  static constexpr Q31_32 kMaxSpacing = Q31_32::from_int(1000);

  // kInvalidArgument for a spacing <= 0, kOutOfRange above kMaxSpacing. Re-arms the trigger.
  Status configure(Q31_32 spacing);

  // Re-arms: the next update() captures (a run starts with a place at its first pose).
  void reset();

  // Feed every odometry pose (every 10 ms). Returns true when a capture is due: on the first
  // pose after reset(), then whenever the straight-line distance from the pose of the last
  // capture reaches the spacing. The capture pose becomes the new reference, so the spacing
  // is measured from where the image was actually taken (overshoot does not accumulate into
  // the next interval's target, and each place's recorded pose is its capture pose).
  bool update(const Pose2& pose);

  Q31_32 spacing() const { return spacing_; }
  uint32_t captures() const { return captures_; }
  const Pose2& last_capture() const { return last_; }

  // The last capture's pose and the count, to continue a stopped run (state_io.h). A refused
  // state re-arms it (reset()).
  template <class Io>
  void state(Io& io) {
    io.tag(state_tag("TRIG"));
    io.field(last_);
    io.field(captures_);
    io.field(armed_);
    if (Io::kReading && !io.ok()) reset();
  }

 private:
  Q31_32 spacing_ = kDefaultSpacing;
  Pose2 last_{};
  uint32_t captures_ = 0;
  bool armed_ = true;
};

}  // namespace seqslam
