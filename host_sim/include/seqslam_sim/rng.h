// Deterministic random numbers for the simulator.
//
// Everything random in a simulated run derives from one 64-bit seed through SplitMix64, so a
// seed reproduces a run bit for bit on any machine and in any thread order: each consumer
// (a run, a frame's sensor noise, the furniture layout) derives its own stream with
// derive(), never shares one.
#pragma once

#include <cmath>
#include <cstdint>

namespace seqslam::sim {

class Rng {
 public:
  explicit Rng(uint64_t seed) : state_(seed) {}

  uint64_t next() {
    uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  // Uniform in [0, 1).
  double uniform() { return static_cast<double>(next() >> 11) * (1.0 / 9007199254740992.0); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  // Integer in [0, n).
  uint32_t below(uint32_t n) { return static_cast<uint32_t>(uniform() * n); }
  bool chance(double p) { return uniform() < p; }
  // Standard normal (Box-Muller; one value per call keeps streams simple to reason about).
  double normal() {
    const double u1 = 1.0 - uniform();  // (0, 1]
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }
  double normal(double mean, double sigma) { return mean + sigma * normal(); }

  // An independent stream for `tag` (e.g. a place index), without advancing this one.
  Rng derive(uint64_t tag) const {
    Rng r(state_ ^ (tag * 0xD1B54A32D192ED03ull + 0x8CB92BA72F3D8DD7ull));
    r.next();
    return r;
  }

 private:
  uint64_t state_;
};

// Hash of integer lattice coordinates to [0, 1): the basis of the procedural textures
// (identical objects get identical textures because coordinates are object-local).
inline double lattice_hash(int64_t x, int64_t y, uint32_t seed) {
  uint64_t h = static_cast<uint64_t>(x) * 0x9E3779B97F4A7C15ull ^
               static_cast<uint64_t>(y) * 0xC2B2AE3D27D4EB4Full ^ (uint64_t{seed} << 17);
  h ^= h >> 33;
  h *= 0xFF51AFD7ED558CCDull;
  h ^= h >> 33;
  h *= 0xC4CEB9FE1A85EC53ull;
  h ^= h >> 33;
  return static_cast<double>(h >> 11) * (1.0 / 9007199254740992.0);
}

// Smooth value noise in [-1, 1] at (x, y) (bilinear interpolation of lattice values with a
// smoothstep), used for wall plaster, floor wear and the like.
inline double value_noise(double x, double y, uint32_t seed) {
  const double fx = std::floor(x);
  const double fy = std::floor(y);
  const auto ix = static_cast<int64_t>(fx);
  const auto iy = static_cast<int64_t>(fy);
  double tx = x - fx;
  double ty = y - fy;
  tx = tx * tx * (3.0 - 2.0 * tx);
  ty = ty * ty * (3.0 - 2.0 * ty);
  const double a = lattice_hash(ix, iy, seed);
  const double b = lattice_hash(ix + 1, iy, seed);
  const double c = lattice_hash(ix, iy + 1, seed);
  const double d = lattice_hash(ix + 1, iy + 1, seed);
  const double v = (a + (b - a) * tx) + ((c + (d - c) * tx) - (a + (b - a) * tx)) * ty;
  return 2.0 * v - 1.0;
}

}  // namespace seqslam::sim
