#include "seqslam/slope_matcher.h"

namespace seqslam {

Status check_slope_config(const SlopeConfig& c) {
  SEQSLAM_TRY(check_sequence_config(c.seq));
  if (c.vsteps == 0 || c.vsteps > kMaxVelocitySteps) return Status::kOutOfRange;
  if (c.vmin.raw() == 0 || c.vmax.raw() > kMaxVelocityRaw) return Status::kOutOfRange;
  if (c.vmin > c.vmax) return Status::kInvalidArgument;
  if (c.vsteps == 1 && c.vmin != c.vmax) return Status::kInvalidArgument;
  return Status::kOk;
}

uint16_t slope_velocity_raw(const SlopeConfig& c, uint32_t s) {
  const uint32_t lo = c.vmin.raw();
  if (c.vsteps <= 1) return static_cast<uint16_t>(lo);
  const uint32_t span = static_cast<uint32_t>(c.vmax.raw()) - lo;
  const uint32_t den = c.vsteps - 1u;
  // round(span s / den), ties up.
  return static_cast<uint16_t>(lo + (2u * span * s + den) / (2u * den));
}

Status SlopeMatcher::configure(const SlopeConfig& config, uint32_t pixels,
                               const SlopeMatcherBuffers& buffers) {
  Status s = check_slope_config(config);
  if (s != Status::kOk) return s;
  LocalNormaliser normaliser;
  s = normaliser.configure(config.seq.window, config.seq.sigma_min, pixels);
  if (s != Status::kOk) return s;
  size_t capacity = buffers.ring.size() / config.seq.seq_len;
  if (buffers.cost.size() < capacity) capacity = buffers.cost.size();
  if (buffers.velocity.size() < capacity) capacity = buffers.velocity.size();
  if (capacity == 0) return Status::kResourceExhausted;
  if (capacity > 0x7FFFFFFFu) capacity = 0x7FFFFFFFu;  // places are reported as int32
  config_ = config;
  buffers_ = buffers;
  normaliser_ = normaliser;
  capacity_ = static_cast<uint32_t>(capacity);
  for (uint32_t v = 0; v < kMaxVelocitySteps; ++v) {
    velocity_[v] = v < config.vsteps ? slope_velocity_raw(config, v) : 0;
  }
  configured_ = true;
  reset();
  return Status::kOk;
}

void SlopeMatcher::reset() {
  for (uint32_t j = 0; j < capacity_; ++j) {
    buffers_.cost[j] = 0;
    buffers_.velocity[j] = kNoVelocity;
  }
  for (uint32_t k = 0; k < kMaxSeqLen; ++k)
    row_size_[k] = 0;
  places_ = 0;
  steps_ = 0;
  min_value_ = 0xFFFF;
}

Status SlopeMatcher::step(Span<const uint32_t> differences, Match* out) {
  if (!configured_) return Status::kFailedPrecondition;
  if (differences.size() > capacity_) return Status::kOutOfRange;
  const uint32_t n = static_cast<uint32_t>(differences.size());
  const uint32_t seq_len = config_.seq.seq_len;
  const uint32_t slot = steps_ % seq_len;
  uint16_t* ring = buffers_.ring.data();
  uint32_t* cost = buffers_.cost.data();
  uint8_t* vel = buffers_.velocity.data();

  // This step's row replaces the row of step - S (no longer part of any trajectory).
  uint16_t* row = ring + static_cast<size_t>(slot) * capacity_;
  uint16_t min_value = min_value_;
  normaliser_.for_each_descending(differences.data(), n, [&](uint32_t j, uint16_t value) {
    row[j] = value;
    if (value < min_value) min_value = value;
  });
  row_size_[slot] = n;
  min_value_ = min_value;
  places_ = n;

  for (uint32_t j = 0; j < n; ++j) {
    cost[j] = 0xFFFFFFFFu;
    vel[j] = kNoVelocity;
  }
  // Places beyond n (the library shrank) have no trajectory either.
  for (uint32_t j = n; j < capacity_; ++j)
    vel[j] = kNoVelocity;

  if (steps_ + 1 >= seq_len) {
    // base[k] + j indexes D+(i-k, j - o_v(k)) in the ring (unsigned wrap-around is exact:
    // j >= o_v(S-1) >= o_v(k) in the loop).
    uint32_t base[kMaxSeqLen];
    for (uint32_t v = 0; v < config_.vsteps; ++v) {
      const uint32_t vr = velocity_[v];
      const uint32_t lo = slope_offset(vr, seq_len - 1);
      uint32_t hi = n;  // j < hi: every cell inside its row
      for (uint32_t k = 0; k < seq_len; ++k) {
        const uint32_t s = (steps_ - k) % seq_len;
        const uint32_t o = slope_offset(vr, k);
        if (row_size_[s] + o < hi) hi = row_size_[s] + o;
        base[k] = s * capacity_ - o;
      }
      for (uint32_t j = lo; j < hi; ++j) {
        uint32_t c = 0;
        for (uint32_t k = 0; k < seq_len; ++k)
          c += ring[base[k] + j];
        if (c < cost[j]) {
          cost[j] = c;
          vel[j] = static_cast<uint8_t>(v);
        }
      }
    }
  }

  Match m;
  m.query = steps_;
  // Best full trajectory (strict "<" ascending: ties go to the lowest place).
  uint32_t best = kNoPlace;
  for (uint32_t j = 0; j < n; ++j) {
    if (vel[j] != kNoVelocity && (best == kNoPlace || cost[j] < cost[best])) best = j;
  }
  if (best != kNoPlace) {
    const uint32_t r = config_.seq.exclusion;
    uint32_t second = kNoPlace;
    const uint32_t below = best > r ? best - r : 0;
    for (uint32_t j = 0; j < below; ++j) {
      if (vel[j] != kNoVelocity && (second == kNoPlace || cost[j] < cost[second])) second = j;
    }
    for (uint32_t j = best + r + 1; j < n; ++j) {
      if (vel[j] != kNoVelocity && (second == kNoPlace || cost[j] < cost[second])) second = j;
    }
    // As DiagonalMatcher::finish_match.
    const uint32_t offset = confidence_offset();
    m.place = static_cast<int32_t>(best);
    m.cost = cost[best] - offset;
    if (second != kNoPlace) {
      m.runner_up = static_cast<int32_t>(second);
      m.runner_up_cost = cost[second] - offset;
      m.confidence = confidence_ratio(m.cost, m.runner_up_cost);
      m.localised = m.confidence < config_.seq.threshold;
    }
  }
  ++steps_;
  *out = m;
  return Status::kOk;
}

}  // namespace seqslam
