// A simulated drive for odometry tests: a ~92 m closed loop (two 39.5 m corridors joined by
// 5 m ends and four 90-degree turns of 0.5 m radius, with a gentle steering wobble and
// varying speed), sampled every 10 ms into cumulative wheel-encoder ticks.
#pragma once

#include <stdint.h>

#include "ref_math.h"

namespace seqslam::test {

struct WheelTicks {
  int64_t left;
  int64_t right;
};

class LoopDrive {
 public:
  static constexpr double kTicksPerRev = 4096.0;
  static constexpr double kCircLeft = 0.532;
  static constexpr double kCircRight = 0.53227;
  static constexpr double kTrack = 0.474;

  // Advances one 10 ms step; returns false after the loop is complete.
  bool step(WheelTicks* ticks) {
    if (segment_ >= kSegments) return false;
    // Speed varies smoothly between 0.15 and 0.45 m/s.
    const double v = 0.3 + 0.15 * ref_sin(0.05 * static_cast<double>(steps_));
    const double ds = v * 0.01;
    const Segment& seg = kRoute[segment_];
    double curvature = seg.curvature;
    if (curvature == 0.0) {
      // Wobble on straights: +-0.3 rad/m curvature, averaging out.
      curvature = 0.3 * ref_sin(0.7 * along_);
    }
    left_ += ds * (1.0 - curvature * kTrack / 2.0) / kCircLeft * kTicksPerRev;
    right_ += ds * (1.0 + curvature * kTrack / 2.0) / kCircRight * kTicksPerRev;
    along_ += ds;
    distance_ += ds;
    if (along_ >= seg.length) {
      along_ = 0.0;
      ++segment_;
    }
    ++steps_;
    ticks->left = static_cast<int64_t>(ref_floor(left_));
    ticks->right = static_cast<int64_t>(ref_floor(right_));
    return true;
  }
  double distance() const { return distance_; }
  uint32_t steps() const { return steps_; }

 private:
  struct Segment {
    double length;     // metres of the centre path
    double curvature;  // 1/m, positive = left
  };
  static constexpr int kSegments = 8;
  static constexpr double kQuarter = kPi / 4.0;  // 90 degrees at 0.5 m radius = pi/4 m
  static constexpr Segment kRoute[kSegments] = {
      {39.5, 0.0}, {kQuarter, 2.0}, {5.0, 0.0}, {kQuarter, 2.0},
      {39.5, 0.0}, {kQuarter, 2.0}, {5.0, 0.0}, {kQuarter, 2.0},
  };
  int segment_ = 0;
  double along_ = 0.0;
  double distance_ = 0.0;
  double left_ = 0.0;
  double right_ = 0.0;
  uint32_t steps_ = 0;
};

// Double-precision midpoint integration of the same ticks (the oracle).
struct ReferenceOdometry {
  double x = 0.0;
  double y = 0.0;
  double phi = 0.0;
  void update(int64_t dl_ticks, int64_t dr_ticks) {
    const double dl =
        LoopDrive::kCircLeft * static_cast<double>(dl_ticks) / LoopDrive::kTicksPerRev;
    const double dr =
        LoopDrive::kCircRight * static_cast<double>(dr_ticks) / LoopDrive::kTicksPerRev;
    const double dc = (dl + dr) / 2.0;
    const double dphi = (dr - dl) / LoopDrive::kTrack;
    x += dc * ref_cos(phi + dphi / 2.0);
    y += dc * ref_sin(phi + dphi / 2.0);
    phi += dphi;
  }
};

}  // namespace seqslam::test
