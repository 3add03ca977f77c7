// SpinalCord: Myon's body sensor bus, which delivers a snapshot of the sensors every 10 ms.
//
// The localiser needs the wheel encoders (odometry), the infrared distance sensors (the grid
// map) and the head orientation. A snapshot carries a bus sequence number and a timestamp so
// the consumer can see missing and late snapshots: the HAL reports them and never invents
// data to fill a gap.
#pragma once

#include <stdint.h>

#include "seqslam/status.h"

namespace seqslam::hal {

inline constexpr uint32_t kMaxInfrared = 8;
inline constexpr uint32_t kSnapshotPeriodUs = 10000;

struct SensorSnapshot {
  enum Flags : uint8_t {
    kHasEncoders = 1u << 0,
    kHasInfrared = 1u << 1,
    kHasHead = 1u << 2,
  };
  uint32_t sequence = 0;      // bus counter, +1 per 10 ms period (a gap = missed snapshots)
  uint32_t timestamp_us = 0;  // bus time in microseconds (wraps after 71.6 minutes)
  uint8_t flags = 0;          // which of the fields below hold data
  uint8_t infrared_count = 0;
  uint32_t encoder_left = 0;  // raw wheel counters; they wrap (see OdometryConfig)
  uint32_t encoder_right = 0;
  int16_t head_pan = 0;  // head orientation, 1/65536 of a turn (0 = straight ahead)
  int16_t head_tilt = 0;
  uint16_t infrared_mm[kMaxInfrared] = {};  // distances in mm; 0 = no echo / out of range
};

class SpinalCord {
 public:
  // The next snapshot in bus order. Returns
  //   kOk          - *out is the next snapshot; out->sequence tells whether any were missed
  //                  (sequence - previous sequence - 1 of them);
  //   kUnavailable - no new snapshot yet (poll again at the next tick);
  //   kOutOfRange  - the stream has ended (a replayed recording is exhausted);
  //   kDataLoss    - the bus delivered a damaged snapshot (it is skipped, not repaired).
  Status next(SensorSnapshot* out) {
    if (out == nullptr) return Status::kInvalidArgument;
    return do_next(out);
  }

 protected:
  SpinalCord() = default;
  ~SpinalCord() = default;
  SpinalCord(const SpinalCord&) = default;
  SpinalCord& operator=(const SpinalCord&) = default;

 private:
  virtual Status do_next(SensorSnapshot* out) = 0;
};

// How late a snapshot may be before the application counts it as late: one full period.
inline constexpr uint32_t kLateSnapshotUs = 2 * kSnapshotPeriodUs;

}  // namespace seqslam::hal
