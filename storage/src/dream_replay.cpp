#include "seqslam/storage/dream_replay.h"

namespace seqslam::storage {

Status DreamReplay::open(hal::BlockDevice& device, Span<uint8_t> buffer, DreamProblem* problem) {
  pending_ = false;
  ended_ = false;
  configured_ = false;
  latched_ = false;
  skipped_places_ = 0;
  bad_records_ = 0;
  return reader_.open(device, buffer, problem);
}

Status DreamReplay::read_item(DreamItem* out) {
  for (;;) {
    const Status s = reader_.next(out);
    if (s == Status::kDataLoss || s == Status::kResourceExhausted) {
      ++bad_records_;  // damaged or invalid: skipped, counted, never repaired
      continue;
    }
    if (s == Status::kOk && out->type == DreamRecord::kTruth) continue;  // not sensor data
    if (s == Status::kOutOfRange) ended_ = true;
    return s;
  }
}

Status DreamReplay::do_next(hal::SensorSnapshot* out) {
  latched_ = false;
  if (pending_ && item_.type == DreamRecord::kReducedPlace) {
    // Delivered as the last step and not captured (e.g. a distance trigger on a recording
    // without odometry): skipped, so the replay moves on instead of repeating it forever.
    pending_ = false;
    ++skipped_places_;
  }
  for (;;) {
    if (!pending_) {
      if (ended_) return Status::kOutOfRange;
      SEQSLAM_TRY(read_item(&item_));
    }
    pending_ = false;
    if (item_.type == DreamRecord::kSnapshot) {
      current_ = item_.snapshot;
      *out = current_;
      return Status::kOk;
    }
    if (item_.type == DreamRecord::kReducedPlace) {
      // No sensors were recorded: the place itself is the step. Keep it for capture().
      current_ = hal::SensorSnapshot{};
      current_.sequence = item_.place.index;
      current_.timestamp_us = item_.place.timestamp_us;
      current_.flags = hal::SensorSnapshot::kHasHead;
      current_.head_pan = item_.place.head_pan;
      current_.head_tilt = item_.place.head_tilt;
      pending_ = true;
      *out = current_;
      return Status::kOk;
    }
    ++skipped_places_;  // a full-recording place the firmware did not capture
  }
}

Status DreamReplay::do_configure(const hal::PipelineMapping& mapping) {
  if (mapping != header().mapping) return Status::kFailedPrecondition;
  configured_ = true;
  return Status::kOk;
}

Status DreamReplay::do_capture() {
  if (!configured_) return Status::kFailedPrecondition;
  latched_ = false;
  if (!pending_) {
    if (ended_) return Status::kUnavailable;
    const Status s = read_item(&item_);
    if (s == Status::kOutOfRange) return Status::kUnavailable;
    if (s != Status::kOk) return s;
    pending_ = true;
  }
  const bool place = item_.type == DreamRecord::kPlace || item_.type == DreamRecord::kReducedPlace;
  const bool here =
      item_.type == DreamRecord::kReducedPlace ||
      (item_.type == DreamRecord::kPlace && item_.place.bus_sequence == current_.sequence);
  if (!place || !here) return Status::kUnavailable;  // nothing recorded at this moment
  pending_ = false;
  frame_.sequence = item_.place.index;
  frame_.timestamp_us = item_.place.timestamp_us;
  frame_.size = item_.place.size;
  frame_.gray = item_.place.gray;
  frame_.yuv = item_.place.yuv;
  latched_ = true;
  return Status::kOk;
}

Status DreamReplay::do_read(hal::Frame* out) {
  if (!latched_) return Status::kUnavailable;
  *out = frame_;
  return Status::kOk;
}

}  // namespace seqslam::storage
