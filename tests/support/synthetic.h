// Deterministic synthetic routes for tests on host and target (freestanding, no heap).
//
// The "world" is a strip of columns, each with its own vertical grey profile built from a
// few random bars (doors, desks, windows); a camera at place p sees the columns
// [p * step, p * step + width). Consecutive places therefore overlap and look alike, like a
// robot moving along a corridor, and two renderings of the same place differ only by the
// appearance change (gain, offset, noise, horizontal offset) given to render().
// Repeated segments (`alias_period`) model perceptual aliasing: identical desks.
#pragma once

#include <stddef.h>
#include <stdint.h>

namespace seqslam::test {

// SplitMix64: tiny, good enough for test data, identical on every platform.
class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}
  uint64_t next64() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  uint32_t next32() { return static_cast<uint32_t>(next64() >> 32); }
  // Uniform in [0, n), n > 0 (modulo bias is irrelevant here).
  uint32_t below(uint32_t n) { return next32() % n; }
  // Uniform in [lo, hi].
  int32_t range(int32_t lo, int32_t hi) {
    return lo + static_cast<int32_t>(below(static_cast<uint32_t>(hi - lo + 1)));
  }

 private:
  uint64_t state_;
};

template <uint32_t kMaxColumns, uint32_t kMaxHeight>
class SyntheticWorld {
 public:
  // columns: strip length; height: image height; alias_period: if > 0, the texture repeats
  // with this period in columns (perfect aliasing), else every column is unique.
  void generate(uint64_t seed, uint32_t columns, uint32_t height, uint32_t alias_period = 0) {
    columns_ = columns < kMaxColumns ? columns : kMaxColumns;
    height_ = height < kMaxHeight ? height : kMaxHeight;
    Rng rng(seed);
    uint32_t bar_left = 0;
    uint32_t base = 128;
    for (uint32_t x = 0; x < columns_; ++x) {
      if (alias_period > 0 && x >= alias_period) {
        for (uint32_t y = 0; y < height_; ++y)
          strip_[y][x] = strip_[y][x - alias_period];
        continue;
      }
      if (bar_left == 0) {  // a new object: width 1..6 columns, its own profile
        bar_left = 1 + rng.below(6);
        base = 40 + rng.below(180);
        top_ = rng.below(height_);
        bottom_ = top_ + rng.below(height_ - top_) + 1;
        shade_ = static_cast<int32_t>(rng.below(120)) - 60;
      }
      --bar_left;
      for (uint32_t y = 0; y < height_; ++y) {
        int32_t v =
            static_cast<int32_t>(base) + (y >= top_ && y < bottom_ ? shade_ : 0) + rng.range(-6, 6);
        strip_[y][x] = clamp8(v);
      }
    }
  }

  uint32_t columns() const { return columns_; }

  // Renders the view at `place` (first column place * step + dx) into out (width x height_)
  // with appearance change v' = v * gain_q8 / 256 + offset + noise in [-noise, noise].
  // Columns beyond the strip wrap around.
  void render(uint32_t place, uint32_t step, int32_t dx, uint32_t width, int32_t gain_q8,
              int32_t offset, int32_t noise, Rng& rng, uint8_t* out) const {
    for (uint32_t y = 0; y < height_; ++y) {
      for (uint32_t x = 0; x < width; ++x) {
        const int64_t col = static_cast<int64_t>(place) * step + dx + x;
        const uint32_t c = static_cast<uint32_t>(((col % columns_) + columns_) % columns_);
        int32_t v = strip_[y][c] * gain_q8 / 256 + offset;
        if (noise > 0) v += rng.range(-noise, noise);
        out[y * width + x] = clamp8(v);
      }
    }
  }

 private:
  static uint8_t clamp8(int32_t v) { return static_cast<uint8_t>(v < 0 ? 0 : (v > 255 ? 255 : v)); }

  uint8_t strip_[kMaxHeight][kMaxColumns] = {};
  uint32_t columns_ = 0;
  uint32_t height_ = 0;
  uint32_t top_ = 0;
  uint32_t bottom_ = 0;
  int32_t shade_ = 0;
};

}  // namespace seqslam::test
