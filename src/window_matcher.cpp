#include "seqslam/window_matcher.h"

namespace seqslam {

Status WindowMatcher::configure(const SequenceConfig& config, uint32_t pixels,
                                const WindowMatcherBuffers& buffers) {
  Status s = check_sequence_config(config);
  if (s != Status::kOk) return s;
  LocalNormaliser normaliser;
  s = normaliser.configure(config.window, config.sigma_min, pixels);
  if (s != Status::kOk) return s;
  size_t slots = buffers.ring.size() / config.seq_len;
  if (buffers.cost.size() < slots) slots = buffers.cost.size();
  if (buffers.run.size() < slots) slots = buffers.run.size();
  if (slots == 0) return Status::kResourceExhausted;
  if (slots > 0xFFFFu) slots = 0xFFFFu;  // a window is at most 65 535 diagonals
  config_ = config;
  buffers_ = buffers;
  normaliser_ = normaliser;
  slots_ = static_cast<uint32_t>(slots);
  first_ = 0;
  width_ = 0;
  configured_ = true;
  reset();
  return Status::kOk;
}

void WindowMatcher::reset() {
  for (uint32_t s = 0; s < slots_; ++s)
    clear_slot(s);
  steps_ = 0;
  min_value_ = 0xFFFF;
}

void WindowMatcher::clear_slot(uint32_t s) {
  buffers_.run[s] = 0;
  buffers_.cost[s] = 0;
}

void WindowMatcher::skip() {
  for (uint32_t s = 0; s < slots_; ++s)
    clear_slot(s);
  ++steps_;
}

void WindowMatcher::rewind(uint32_t step) {
  for (uint32_t s = 0; s < slots_; ++s)
    clear_slot(s);
  steps_ = step;
}

uint32_t WindowMatcher::recent_cost(int32_t d, uint32_t steps) const {
  if (!configured_ || !in_window(d) || steps == 0 || steps > config_.seq_len || steps > steps_) {
    return UINT32_MAX;
  }
  const uint32_t s = slot(d);
  if (buffers_.run[s] < steps) return UINT32_MAX;
  uint32_t sum = 0;
  for (uint32_t t = steps_ - steps; t < steps_; ++t)
    sum += buffers_.ring[static_cast<size_t>(t % config_.seq_len) * slots_ + s];
  return sum;
}

uint32_t WindowMatcher::slot(int32_t d) const {
  const int32_t n = static_cast<int32_t>(slots_);
  const int32_t r = d % n;
  return static_cast<uint32_t>(r < 0 ? r + n : r);
}

Status WindowMatcher::place(int32_t first, uint32_t width) {
  if (width == 0 || width > slots_) return Status::kOutOfRange;
  if (static_cast<int64_t>(first) + width - 1 > INT32_MAX) return Status::kOutOfRange;
  // Slots of diagonals that enter: empty (a slot may have held a diagonal slots() away).
  for (uint32_t k = 0; k < width; ++k) {
    const int32_t d = first + static_cast<int32_t>(k);
    if (!in_window(d)) clear_slot(slot(d));
  }
  first_ = first;
  width_ = width;
  return Status::kOk;
}

PlaceBand WindowMatcher::band(uint32_t places) const {
  if (width_ == 0 || places == 0) return {};
  const int64_t lo = static_cast<int64_t>(steps_) + first_;
  const int64_t hi = lo + width_ - 1;
  if (hi < 0 || lo >= places) return {};
  const uint32_t lo_p = lo < 0 ? 0u : static_cast<uint32_t>(lo);
  const uint32_t hi_p = hi >= places ? places - 1 : static_cast<uint32_t>(hi);
  const uint32_t h = config_.window / 2u;
  const uint32_t first = lo_p >= h ? lo_p - h : 0u;
  const uint32_t last = places - 1 - hi_p >= h ? hi_p + h : places - 1;
  return {first, last - first + 1};
}

bool WindowMatcher::full_sequence(int32_t d) const {
  return configured_ && in_window(d) && buffers_.run[slot(d)] == config_.seq_len;
}

uint32_t WindowMatcher::cost(int32_t d) const {
  return in_window(d) ? buffers_.cost[slot(d)] : 0u;
}

int32_t WindowMatcher::best_in(int32_t lo, int32_t hi, bool skip_near, int32_t centre) const {
  const int32_t r = static_cast<int32_t>(config_.exclusion);
  int32_t best = kNone;
  uint32_t best_cost = 0xFFFFFFFFu;
  for (int32_t d = lo; d <= hi; ++d) {
    if (skip_near && d >= centre - r && d <= centre + r) continue;
    const uint32_t s = slot(d);
    // Strict "<" in ascending order: ties go to the lowest diagonal, i.e. the lowest place,
    // as in DiagonalMatcher.
    if (buffers_.run[s] == config_.seq_len && buffers_.cost[s] < best_cost) {
      best = d;
      best_cost = buffers_.cost[s];
    }
    if (d == INT32_MAX) break;
  }
  return best;
}

Status WindowMatcher::step(uint32_t places, Span<const uint32_t> band_differences,
                           int32_t search_first, int32_t search_last, Match* out) {
  if (!configured_) return Status::kFailedPrecondition;
  if (places > static_cast<uint32_t>(INT32_MAX)) return Status::kOutOfRange;
  const PlaceBand band = this->band(places);
  if (band_differences.size() != band.count) return Status::kInvalidArgument;
  const uint32_t i = steps_;
  const uint8_t full = static_cast<uint8_t>(config_.seq_len);
  uint16_t* ring = buffers_.ring.data() + static_cast<size_t>(i % config_.seq_len) * slots_;
  uint32_t* cost = buffers_.cost.data();
  uint8_t* run = buffers_.run.data();
  uint16_t min_value = min_value_;

  // Diagonals of the window whose place is outside the library this step end their run (the
  // diagonal matcher has no cell there either); the others are updated below.
  const int64_t lo = static_cast<int64_t>(i) + first_;
  for (uint32_t k = 0; k < width_; ++k) {
    const int64_t p = lo + k;
    if (p < 0 || p >= places) clear_slot(slot(first_ + static_cast<int32_t>(k)));
  }
  if (band.count > 0) {
    const uint32_t lo_p = lo < 0 ? 0u : static_cast<uint32_t>(lo);
    const int64_t hi = lo + width_ - 1;
    const uint32_t hi_p = hi >= places ? places - 1 : static_cast<uint32_t>(hi);
    normaliser_.for_each_descending(
        band_differences.data(), band.count, lo_p - band.first, hi_p - band.first,
        [&](uint32_t j, uint16_t value) {
          const uint32_t place = band.first + j;
          const uint32_t s = slot(static_cast<int32_t>(place) - static_cast<int32_t>(i));
          // run[s] is the diagonal's run up to the previous step, where its place was
          // place - 1; it is 0 if that place did not exist (then place == 0 or the diagonal
          // just entered the window).
          const uint8_t prev = run[s];
          uint32_t c = value;
          uint8_t r = 1;
          if (prev == full) {
            c += cost[s] - ring[s];  // ring[s] still holds the value of step i - S
            r = full;
          } else if (prev > 0) {
            c += cost[s];
            r = static_cast<uint8_t>(prev + 1);
          }
          ring[s] = value;
          cost[s] = c;
          run[s] = r;
          if (value < min_value) min_value = value;
        });
  }
  min_value_ = min_value;

  Match m;
  m.query = i;
  const int32_t last = first_ + static_cast<int32_t>(width_) - 1;
  const int32_t slo = search_first > first_ ? search_first : first_;
  const int32_t shi = search_last < last ? search_last : last;
  const int32_t best = width_ > 0 && slo <= shi ? best_in(slo, shi, false, 0) : kNone;
  if (best != kNone) {
    const uint32_t offset = confidence_offset();
    m.place = best + static_cast<int32_t>(i);
    m.cost = cost[slot(best)] - offset;
    const int32_t second = best_in(first_, last, true, best);
    if (second != kNone) {
      m.runner_up = second + static_cast<int32_t>(i);
      m.runner_up_cost = cost[slot(second)] - offset;
      m.confidence = confidence_ratio(m.cost, m.runner_up_cost);
      m.localised = m.confidence < config_.threshold;
    }
  }
  ++steps_;
  if (out != nullptr) *out = m;
  return Status::kOk;
}

}  // namespace seqslam
