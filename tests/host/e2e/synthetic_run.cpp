#include "synthetic_run.h"

#include <vector>

#include "seqslam/odometry.h"
#include "seqslam/spatial_trigger.h"

namespace seqslam::test {

storage::DreamHeader synthetic_run_header() {
  storage::DreamHeader h;
  h.variant = storage::DreamVariant::kFull;
  h.mapping = hal::PipelineMapping::reduction(32, 16);
  h.infrared_count = 3;
  for (uint16_t i = 0; i < 3; ++i) {
    h.infrared[i] = storage::InfraredMount{200, static_cast<int16_t>(150 - 150 * i),
                                           static_cast<uint16_t>(16384 - 16384 * i), 40, 800};
  }
  return h;
}

storage::RunConfig synthetic_run_config(uint8_t modes) {
  storage::RunConfig c;
  c.modes = modes;
  c.mapping = synthetic_run_header().mapping;
  return c;
}

uint32_t write_synthetic_run(hal::BlockDevice& device, const RunWorld& world, const RunOptions& o) {
  storage::DreamWriter writer;
  if (writer.create(device, synthetic_run_header()) != Status::kOk) return 0;
  Odometry odometry;
  if (odometry.configure(OdometryConfig{}) != Status::kOk) return 0;
  SpatialTrigger trigger;
  Rng noise(o.noise_seed);
  std::vector<uint8_t> image(512);
  uint32_t places = 0;
  uint32_t left = o.start_count;
  uint32_t right = o.start_count;
  for (uint32_t step = 0; places < o.places && step < 1000000; ++step) {
    if (step > 0) {
      left += o.ticks_per_step;
      right += o.ticks_per_step;
    }
    hal::SensorSnapshot s;
    s.sequence = step;
    s.timestamp_us = step * 10000u;
    s.flags = hal::SensorSnapshot::kHasEncoders | hal::SensorSnapshot::kHasInfrared |
              hal::SensorSnapshot::kHasHead;
    s.encoder_left = left;
    s.encoder_right = right;
    s.head_tilt = -1820;  // 10 degrees down
    s.infrared_count = 3;
    s.infrared_mm[0] = static_cast<uint16_t>(300 + step % 50);
    s.infrared_mm[1] = 0;
    s.infrared_mm[2] = static_cast<uint16_t>(500 - step % 70);
    // A lossy bus drops the snapshot: nothing is recorded, the robot still moves.
    if (o.drop_every != 0 && step % o.drop_every == o.drop_every - 1) continue;
    if (writer.snapshot(s) != Status::kOk) return 0;
    if (step == 0) {
      odometry.reset(Pose2{}, left, right);
    } else if (odometry.update(left, right) != Status::kOk) {
      return 0;
    }
    const Pose2 pose = odometry.pose();
    if (!trigger.update(pose)) continue;
    // The camera's left edge at the true position, one world column per 10 cm.
    constexpr int64_t kColumnWidth = Q31_32::from_ratio(1, 10).raw();  // 10 cm in Q31.32
    const int64_t column = pose.x.raw() / kColumnWidth;
    world.render(static_cast<uint32_t>(column), 1, 0, 32, o.gain_q8, o.offset, o.noise, noise,
                 image.data());
    storage::DreamPlace p;
    p.index = places;
    p.bus_sequence = s.sequence;
    p.timestamp_us = s.timestamp_us;
    p.encoder_left = left;
    p.encoder_right = right;
    p.pose = pose;
    p.head_tilt = s.head_tilt;
    p.infrared_count = 3;
    for (int i = 0; i < 3; ++i)
      p.infrared_mm[i] = s.infrared_mm[i];
    p.size = ImageSize{32, 16};
    p.gray = image.data();
    if (writer.place(p) != Status::kOk) return 0;
    ++places;
  }
  return places;
}

}  // namespace seqslam::test
