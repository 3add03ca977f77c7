// Scripted stand-ins for the SpinalCord and the pixel buffer, for tests of code that uses the
// live HAL (the firmware with real sensors). Freestanding, no heap.
//
// FakeSpinalCord plays a caller-owned script of snapshots and follows a fault schedule: drop
// every Nth snapshot (the consumer sees a gap in the bus sequence, as with a real lossy bus),
// report one as damaged (kDataLoss), or say "nothing yet" (kUnavailable) once before a given
// snapshot, as a live bus polled too early does.
// FakePixelBuffer asks a caller-supplied function for each frame (e.g. to render the scene at
// the position the bus reports), and can fail every Nth capture (kUnavailable: no frame).
#pragma once

#include <stdint.h>

#include "seqslam/hal/pixel_buffer.h"
#include "seqslam/hal/spinal_cord.h"
#include "seqslam/span.h"

namespace seqslam::hal {

struct SensorFaults {
  uint32_t drop_every = 0;                  // drop snapshots with (index + 1) % drop_every == 0
  uint32_t damaged_index = 0xFFFFFFFFu;     // report this script index as damaged
  uint32_t not_ready_before = 0xFFFFFFFFu;  // one kUnavailable before this script index
};

class FakeSpinalCord final : public SpinalCord {
 public:
  explicit FakeSpinalCord(Span<const SensorSnapshot> script, const SensorFaults& faults = {})
      : script_(script), faults_(faults) {}

  // The snapshot most recently delivered (what the robot "is at").
  const SensorSnapshot& current() const { return current_; }
  uint32_t dropped() const { return dropped_; }

 private:
  Status do_next(SensorSnapshot* out) override {
    for (;;) {
      if (next_ >= script_.size()) return Status::kOutOfRange;
      const uint32_t i = next_;
      if (i == faults_.not_ready_before && !waited_) {
        waited_ = true;
        return Status::kUnavailable;
      }
      ++next_;
      current_ = script_[i];  // the robot moved, whether or not the snapshot arrives
      if (faults_.drop_every != 0 && (i + 1) % faults_.drop_every == 0) {
        ++dropped_;
        continue;
      }
      if (i == faults_.damaged_index) return Status::kDataLoss;
      *out = current_;
      return Status::kOk;
    }
  }

  Span<const SensorSnapshot> script_;
  SensorFaults faults_;
  SensorSnapshot current_{};
  uint32_t next_ = 0;
  uint32_t dropped_ = 0;
  bool waited_ = false;
};

class FakePixelBuffer final : public PixelBuffer {
 public:
  // Fills `gray` (size.pixels() bytes) with frame number `frame`; false = no frame.
  using Source = bool (*)(void* context, uint32_t frame, ImageSize size, uint8_t* gray);

  FakePixelBuffer(Source source, void* context, Span<uint8_t> buffer, uint32_t fail_every = 0)
      : source_(source), context_(context), buffer_(buffer), fail_every_(fail_every) {}

  uint32_t captures() const { return captures_; }

 private:
  Status do_configure(const PipelineMapping& mapping) override {
    if (mapping.size().pixels() > buffer_.size()) return Status::kFailedPrecondition;
    size_ = mapping.size();
    configured_ = true;
    return Status::kOk;
  }
  Status do_capture() override {
    if (!configured_) return Status::kFailedPrecondition;
    latched_ = false;
    ++captures_;
    if (fail_every_ != 0 && captures_ % fail_every_ == 0) return Status::kUnavailable;
    if (!source_(context_, frame_, size_, buffer_.data())) return Status::kUnavailable;
    frame_number_ = frame_++;
    latched_ = true;
    return Status::kOk;
  }
  Status do_read(Frame* out) override {
    if (!latched_) return Status::kUnavailable;
    out->sequence = frame_number_;
    out->timestamp_us = 0;
    out->size = size_;
    out->gray = buffer_.data();
    out->yuv = nullptr;
    return Status::kOk;
  }

  Source source_;
  void* context_;
  Span<uint8_t> buffer_;
  uint32_t fail_every_;
  ImageSize size_{};
  uint32_t captures_ = 0;
  uint32_t frame_ = 0;
  uint32_t frame_number_ = 0;
  bool configured_ = false;
  bool latched_ = false;
};

}  // namespace seqslam::hal
