// Differential-drive odometry from wheel encoder ticks, integrated with the midpoint (RK2)
// rule of the 2025 thesis (eqs. 6.3-6.6), in fixed point.
//
//   dL = U_L * dTicks_L / N,  dR = U_R * dTicks_R / N          (eq. 4.11, per wheel)
//   dc = (dR + dL) / 2,       dphi = (dR - dL) / L
//   x += dc * cos(phi + dphi/2);  y += dc * sin(phi + dphi/2);  phi += dphi
//
// Number formats, chosen so a 92 m loop of 10 ms steps stays within micrometres of a
// double-precision integration (tests/unit/test_odometry.cpp measures it):
// - Position: Q31.32 metres (int64). Per-step rounding 2^-33 m.
// - Heading: an unsigned Q0.64 fraction of a turn, so it wraps at 360 degrees by integer
//   overflow, exactly. The per-tick heading increments U/(N L 2 pi) are pre-computed in the
//   same format (relative error ~1e-15), so heading never drifts from arithmetic.
// - Per-tick wheel travel: Q16.48 metres.
// Sine and cosine come from sincos() (max error 1e-9).
#pragma once

#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/fixmath.h"
#include "seqslam/state_io.h"
#include "seqslam/status.h"

namespace seqslam {

// A planar pose: position in metres, heading counter-clockwise from +x.
struct Pose2 {
  Q31_32 x;
  Q31_32 y;
  Angle heading;
};
template <class Io>
void persist(Io& io, Pose2& p) {
  io.field(p.x);
  io.field(p.y);
  io.field(p.heading);
}

struct OdometryConfig {
  // Encoder resolution (Myon: 4096 ticks per wheel revolution).
  uint32_t ticks_per_revolution = 4096;
  // Wheel circumferences in metres, remeasured in the 2025 thesis (section 6.5).
  Q31_32 circumference_left = Q31_32::from_ratio(532, 1000);
  Q31_32 circumference_right = Q31_32::from_ratio(53227, 100000);
  // Distance between the wheels' contact points, metres.
  Q31_32 track_width = Q31_32::from_ratio(474, 1000);
  // Width of the encoder counters in bits (1..32); counts wrap modulo 2^bits.
  uint8_t counter_bits = 32;
  // The largest plausible change of one counter between two updates. A larger jump is
  // treated as a corrupted snapshot (see Odometry::update). Must be below half the counter
  // range, or a wrap could not be told from a jump.
  uint32_t max_ticks_per_update = 4096;
};

class Odometry {
 public:
  // Validates and adopts `config`, then waits for reset(). Returns:
  //   kInvalidArgument - zero ticks per revolution, a non-positive circumference or track
  //                      width, counter_bits outside 1..32, or max_ticks_per_update == 0;
  //   kOutOfRange      - ticks_per_revolution > 2^20, a circumference > 16 m, a track width
  //                      > 100 m, max_ticks_per_update >= 2^(counter_bits-1), or limits so
  //                      large that one update could move a wheel by more than 2^14 m or turn
  //                      the robot by half a turn or more (the signed heading increment and
  //                      the midpoint angle would be ambiguous).
  // On failure the previous configuration and pose are kept.
  Status configure(const OdometryConfig& config);

  // Starts integrating from `start`, taking the given raw counter readings as the reference.
  void reset(const Pose2& start, uint32_t left_count, uint32_t right_count);

  // Integrates one snapshot of the raw (wrapping) counters. Returns:
  //   kFailedPrecondition - configure() and reset() have not both succeeded;
  //   kOutOfRange         - a counter moved by more than max_ticks_per_update: the snapshot
  //                         is ignored (pose and reference counts unchanged), so one corrupted
  //                         reading is skipped. If the jump was real (e.g. after a long gap),
  //                         call resync() to accept the new counts without motion.
  Status update(uint32_t left_count, uint32_t right_count);

  // Takes the given counts as the new reference without moving the pose.
  void resync(uint32_t left_count, uint32_t right_count);

  Pose2 pose() const;
  // Heading as a Q0.64 fraction of a turn (full precision, for tests and diagnostics).
  uint64_t heading_turns_q64() const { return heading_q64_; }
  // Total path length of the wheel-base centre, metres (sum of |dc|).
  Q31_32 distance_travelled() const { return Q31_32::from_raw(travelled_); }
  bool ready() const { return configured_ && started_; }

  // The pose and the counters' reference, to continue a stopped run (state_io.h); the
  // configuration is configure()'s. A refused state leaves it waiting for reset().
  template <class Io>
  void state(Io& io) {
    io.tag(state_tag("ODOM"));
    io.field(last_left_);
    io.field(last_right_);
    io.field(x_);
    io.field(y_);
    io.field(heading_q64_);
    io.field(travelled_);
    io.field(started_);
    if (Io::kReading && !io.ok()) started_ = false;
  }

 private:
  int32_t tick_delta(uint32_t now, uint32_t before) const;

  OdometryConfig config_{};
  int64_t metres_per_tick_left_q48_ = 0;
  int64_t metres_per_tick_right_q48_ = 0;
  uint64_t turns_per_tick_left_q64_ = 0;
  uint64_t turns_per_tick_right_q64_ = 0;
  uint32_t last_left_ = 0;
  uint32_t last_right_ = 0;
  int64_t x_ = 0;  // Q31.32 metres
  int64_t y_ = 0;  // Q31.32 metres
  uint64_t heading_q64_ = 0;
  int64_t travelled_ = 0;  // Q31.32 metres
  bool configured_ = false;
  bool started_ = false;
};

}  // namespace seqslam
