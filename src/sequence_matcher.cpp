#include "seqslam/sequence_matcher.h"

namespace seqslam {

Status check_sequence_config(const SequenceConfig& c) {
  if (c.seq_len == 0 || c.seq_len > kMaxSeqLen) return Status::kOutOfRange;
  if (c.window == 1 || c.window > kMaxWindow) return Status::kOutOfRange;
  if (c.threshold > UQ16_16::from_int(1)) return Status::kOutOfRange;
  if (c.window > 0 && c.sigma_min.raw() == 0) return Status::kInvalidArgument;
  return Status::kOk;
}

Status DiagonalMatcher::configure(const SequenceConfig& config, uint32_t pixels,
                                  const DiagonalMatcherBuffers& buffers) {
  Status s = check_sequence_config(config);
  if (s != Status::kOk) return s;
  LocalNormaliser normaliser;
  s = normaliser.configure(config.window, config.sigma_min, pixels);
  if (s != Status::kOk) return s;
  size_t capacity = buffers.ring.size() / config.seq_len;
  if (buffers.cost.size() < capacity) capacity = buffers.cost.size();
  if (buffers.run.size() < capacity) capacity = buffers.run.size();
  if (capacity == 0) return Status::kResourceExhausted;
  if (capacity > 0x7FFFFFFFu) capacity = 0x7FFFFFFFu;  // places are reported as int32
  config_ = config;
  buffers_ = buffers;
  normaliser_ = normaliser;
  capacity_ = static_cast<uint32_t>(capacity);
  configured_ = true;
  reset();
  return Status::kOk;
}

void DiagonalMatcher::reset() {
  for (uint32_t j = 0; j < capacity_; ++j) {
    buffers_.run[j] = 0;
    buffers_.cost[j] = 0;
  }
  places_ = 0;
  steps_ = 0;
  min_value_ = 0xFFFF;
}

bool DiagonalMatcher::state_valid() const {
  if (!configured_ || places_ > capacity_) return false;
  for (uint32_t j = 0; j < capacity_; ++j) {
    if (buffers_.run[j] > config_.seq_len) return false;
  }
  return true;
}

Status DiagonalMatcher::step(Span<const uint32_t> differences, Match* out) {
  if (!configured_) return Status::kFailedPrecondition;
  if (differences.size() > capacity_) return Status::kOutOfRange;
  const uint32_t n = static_cast<uint32_t>(differences.size());
  const uint32_t seq_len = config_.seq_len;
  const uint8_t full = static_cast<uint8_t>(seq_len);
  // The ring row of this step currently holds the row of step - S.
  uint16_t* row = buffers_.ring.data() + static_cast<size_t>(steps_ % seq_len) * capacity_;
  uint32_t* cost = buffers_.cost.data();
  uint8_t* run = buffers_.run.data();

  // Places that existed last step but not now (the library shrank) lose their sequences.
  for (uint32_t j = n; j < places_; ++j) {
    run[j] = 0;
    cost[j] = 0;
  }
  // From the last place down: cost[j - 1] and run[j - 1] still hold the previous step's
  // values, and row[j - S] still holds D+(step - S, j - S). The best full sequence is
  // tracked on the way (ties go to the lowest place, as the scan is descending).
  uint16_t min_value = min_value_;
  int32_t best = -1;
  uint32_t best_cost = 0xFFFFFFFFu;
  normaliser_.for_each_descending(differences.data(), n, [&](uint32_t j, uint16_t value) {
    uint32_t c = value;
    uint8_t r = 1;
    if (j > 0) {
      const uint8_t prev = run[j - 1];
      if (prev == full) {
        c += cost[j - 1] - row[j - seq_len];
        r = full;
      } else if (prev > 0) {
        c += cost[j - 1];
        r = static_cast<uint8_t>(prev + 1);
      }
    }
    row[j] = value;
    cost[j] = c;
    run[j] = r;
    if (value < min_value) min_value = value;
    if (r == full && c <= best_cost) {
      best = static_cast<int32_t>(j);
      best_cost = c;
    }
  });
  places_ = n;
  min_value_ = min_value;

  Match m;
  m.query = steps_;
  if (best >= 0) {
    const uint32_t runner_up = best_outside(static_cast<uint32_t>(best));
    finish_match(static_cast<uint32_t>(best), runner_up, &m);
  }
  ++steps_;
  *out = m;
  return Status::kOk;
}

uint32_t DiagonalMatcher::best_outside(uint32_t best) const {
  const uint32_t* cost = buffers_.cost.data();
  const uint8_t* run = buffers_.run.data();
  const uint8_t full = static_cast<uint8_t>(config_.seq_len);
  const uint32_t r = config_.exclusion;
  uint32_t second = kNoPlace;
  uint32_t second_cost = 0xFFFFFFFFu;
  // Two plain ranges either side of [best - R, best + R]; strict "<" keeps the lowest place.
  const uint32_t below = best > r ? best - r : 0;
  for (uint32_t j = 0; j < below; ++j) {
    if (run[j] == full && cost[j] < second_cost) {
      second = j;
      second_cost = cost[j];
    }
  }
  for (uint32_t j = best + r + 1; j < places_; ++j) {
    if (run[j] == full && cost[j] < second_cost) {
      second = j;
      second_cost = cost[j];
    }
  }
  return second;
}

void DiagonalMatcher::finish_match(uint32_t best, uint32_t runner_up, Match* out) const {
  // Costs as the confidence sees them: shifted by the smallest normalised difference seen
  // since reset, S times (see confidence_offset()).
  const uint32_t offset = confidence_offset();
  out->place = static_cast<int32_t>(best);
  out->cost = buffers_.cost[best] - offset;
  if (runner_up == kNoPlace) return;
  out->runner_up = static_cast<int32_t>(runner_up);
  out->runner_up_cost = buffers_.cost[runner_up] - offset;
  out->confidence = confidence_ratio(out->cost, out->runner_up_cost);
  out->localised = out->confidence < config_.threshold;
}

}  // namespace seqslam
