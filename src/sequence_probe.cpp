#include "seqslam/sequence_probe.h"

namespace seqslam {

namespace {
constexpr int32_t kHalf = static_cast<int32_t>(kProbeSlots / 2u);
}  // namespace

Status SequenceProbe::configure(const SequenceConfig& config, uint32_t pixels,
                                const SequenceProbeBuffers& buffers) {
  active_ = false;
  SequenceConfig one = config;
  one.seq_len = 1;  // the window gives each step's values; the sums are the probe's
  const Status s = matcher_.configure(one, pixels, buffers.window);
  if (s != Status::kOk) return s;
  if (matcher_.slots() < kProbeSlots || buffers.sum.size() < kProbeSlots) {
    return Status::kResourceExhausted;
  }
  sum_ = buffers.sum;
  return Status::kOk;
}

void SequenceProbe::start(int32_t centre, uint32_t first) {
  matcher_.rewind(first);
  const Status s = matcher_.place(centre - kHalf, kProbeSlots);
  for (uint32_t k = 0; k < kProbeSlots; ++k)
    sum_[k] = 0;
  alive_ = (1u << kProbeSlots) - 1u;
  centre_ = centre;
  first_ = first;
  active_ = s == Status::kOk;
}

Status SequenceProbe::add(uint32_t places, Span<const uint32_t> band_differences) {
  if (!active_) return Status::kFailedPrecondition;
  Match none;  // an empty search range: the probe's answer is best()
  SEQSLAM_TRY(matcher_.step(places, band_differences, 1, 0, &none));
  for (uint32_t k = 0; k < kProbeSlots; ++k) {
    const int32_t d = centre_ - kHalf + static_cast<int32_t>(k);
    if (matcher_.full_sequence(d)) {
      sum_[k] += matcher_.cost(d);  // this step's value (< 2^16; S of them fit 32 bits)
    } else {
      alive_ &= ~(1u << k);  // no place in the library this step: not followed further
    }
  }
  return Status::kOk;
}

ProbeBest SequenceProbe::best(uint32_t radius) const {
  ProbeBest b;
  if (!active_ || steps() == 0) return b;
  const uint32_t r = radius < static_cast<uint32_t>(kHalf) ? radius : kHalf;
  uint32_t best = kProbeSlots;
  for (uint32_t k = kHalf - r; k <= kHalf + r; ++k) {
    if ((alive_ >> k & 1u) != 0 && (best == kProbeSlots || sum_[k] < sum_[best])) best = k;
  }
  if (best == kProbeSlots) return b;
  b.found = true;
  b.diagonal = centre_ - kHalf + static_cast<int32_t>(best);
  b.cost = sum_[best];
  b.local = UINT32_MAX;
  for (uint32_t k = 0; k < kProbeSlots; ++k) {
    const uint32_t gap = k > best ? k - best : best - k;
    if (gap >= 2 && (alive_ >> k & 1u) != 0 && sum_[k] < b.local) b.local = sum_[k];
  }
  return b;
}

}  // namespace seqslam
