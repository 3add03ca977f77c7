#include "seqslam/odometry.h"

namespace seqslam {

namespace {

// floor(2^64 / (2 pi)): turns per radian in Q0.64.
constexpr uint64_t kTurnsPerRadianQ64 = 2935890503282001226u;

// Turns per tick in Q0.64 of a wheel of circumference u (Q31.32) over den = N * L (L in the
// same scale): U * (2^64 / 2 pi) / (N * L), rounded. Out of line: configure() needs it twice
// and its 128-bit arithmetic is large inline code.
__attribute__((noinline)) Int128 turns_per_tick(int64_t u, const Int128& den) {
  return (Int128(u) * Int128::from_u64(kTurnsPerRadianQ64) + den.sar(1)).div(den);
}

// Whether a per-tick value times the ticks of one update reaches the limit.
__attribute__((noinline)) bool reaches(const Int128& per_tick, uint32_t ticks,
                                       const Int128& limit) {
  return per_tick * Int128(static_cast<int64_t>(ticks)) >= limit;
}

}  // namespace

Status Odometry::configure(const OdometryConfig& c) {
  if (c.ticks_per_revolution == 0 || c.circumference_left.raw() <= 0 ||
      c.circumference_right.raw() <= 0 || c.track_width.raw() <= 0 || c.counter_bits == 0 ||
      c.counter_bits > 32 || c.max_ticks_per_update == 0) {
    return Status::kInvalidArgument;
  }
  if (c.ticks_per_revolution > (1u << 20) || c.circumference_left > Q31_32::from_int(16) ||
      c.circumference_right > Q31_32::from_int(16) || c.track_width > Q31_32::from_int(100) ||
      static_cast<uint64_t>(c.max_ticks_per_update) >= (uint64_t{1} << (c.counter_bits - 1))) {
    return Status::kOutOfRange;
  }
  const int64_t n = c.ticks_per_revolution;
  // Metres per tick in Q16.48: circumference (Q31.32, <= 2^36) * 2^16 / N.
  const int64_t left_q48 = div_round(c.circumference_left.raw() * 65536, n);
  const int64_t right_q48 = div_round(c.circumference_right.raw() * 65536, n);
  // Turns per tick in Q0.64: U / (N * L * 2 pi) = U * (2^64 / 2 pi) / (N * L), with U and L
  // in the same Q31.32 scale, so the scale cancels.
  const Int128 den = Int128(n) * Int128(c.track_width.raw());
  const Int128 left_turns = turns_per_tick(c.circumference_left.raw(), den);
  const Int128 right_turns = turns_per_tick(c.circumference_right.raw(), den);
  // Bounds that keep every per-update product inside int64 and the heading change per update
  // below half a turn, so the signed increment (and the midpoint angle) is unambiguous.
  const Int128 limit_travel = Int128(1).shl(62);  // 2^62 in Q16.48 = 2^14 m
  const Int128 half_turn = Int128(1).shl(63);     // in Q0.64
  const uint32_t m = c.max_ticks_per_update;
  if (reaches(Int128(left_q48), m, limit_travel) || reaches(Int128(right_q48), m, limit_travel) ||
      reaches(left_turns + right_turns, m, half_turn)) {
    return Status::kOutOfRange;
  }
  config_ = c;
  metres_per_tick_left_q48_ = left_q48;
  metres_per_tick_right_q48_ = right_q48;
  turns_per_tick_left_q64_ = left_turns.low64();
  turns_per_tick_right_q64_ = right_turns.low64();
  configured_ = true;
  started_ = false;
  return Status::kOk;
}

void Odometry::reset(const Pose2& start, uint32_t left_count, uint32_t right_count) {
  x_ = start.x.raw();
  y_ = start.y.raw();
  heading_q64_ = static_cast<uint64_t>(start.heading.bam) << 32;
  travelled_ = 0;
  last_left_ = left_count;
  last_right_ = right_count;
  started_ = true;
}

void Odometry::resync(uint32_t left_count, uint32_t right_count) {
  last_left_ = left_count;
  last_right_ = right_count;
}

int32_t Odometry::tick_delta(uint32_t now, uint32_t before) const {
  // Difference modulo 2^bits, sign-extended from bit (bits - 1): the shorter way round.
  const uint32_t bits = config_.counter_bits;
  const uint32_t mask = bits == 32 ? 0xFFFFFFFFu : ((1u << bits) - 1u);
  const uint32_t diff = (now - before) & mask;
  const uint32_t sign = 1u << (bits - 1);
  if ((diff & sign) != 0) return -static_cast<int32_t>((mask - diff) + 1u);
  return static_cast<int32_t>(diff);
}

Status Odometry::update(uint32_t left_count, uint32_t right_count) {
  if (!ready()) return Status::kFailedPrecondition;
  const int32_t dl_ticks = tick_delta(left_count, last_left_);
  const int32_t dr_ticks = tick_delta(right_count, last_right_);
  const int64_t limit = config_.max_ticks_per_update;
  if (dl_ticks > limit || dl_ticks < -limit || dr_ticks > limit || dr_ticks < -limit) {
    return Status::kOutOfRange;
  }
  last_left_ = left_count;
  last_right_ = right_count;

  // Wheel travel in Q16.48 metres; configure() bounded both below 2^62.
  const int64_t dl = metres_per_tick_left_q48_ * dl_ticks;
  const int64_t dr = metres_per_tick_right_q48_ * dr_ticks;
  // Heading change in Q0.64 turns, signed; below a quarter turn by configuration.
  const int64_t dphi = static_cast<int64_t>(
      turns_per_tick_right_q64_ * static_cast<uint64_t>(static_cast<int64_t>(dr_ticks)) -
      turns_per_tick_left_q64_ * static_cast<uint64_t>(static_cast<int64_t>(dl_ticks)));
  // Midpoint heading, rounded to a binary angle (2^-32 turn).
  const uint64_t mid = heading_q64_ + static_cast<uint64_t>(dphi / 2);
  const Angle mid_angle{static_cast<uint32_t>((mid + (uint64_t{1} << 31)) >> 32)};
  const SinCos sc = sincos(mid_angle);
  // dc = (dl + dr) / 2 in Q16.48; dx = dc * cos: Q16.48 * Q1.30 -> Q31.32 is a shift by 46,
  // and one more for the halving.
  const int64_t sum = dl + dr;
  x_ += mul_shift_round(sum, sc.cos.raw(), 47);
  y_ += mul_shift_round(sum, sc.sin.raw(), 47);
  heading_q64_ += static_cast<uint64_t>(dphi);
  // |dc| in Q31.32: |dl + dr| / 2 / 2^16, rounded.
  const uint64_t magnitude = static_cast<uint64_t>(sum >= 0 ? sum : -sum);
  travelled_ += static_cast<int64_t>((magnitude + (uint64_t{1} << 16)) >> 17);
  return Status::kOk;
}

Pose2 Odometry::pose() const {
  Pose2 p;
  p.x = Q31_32::from_raw(x_);
  p.y = Q31_32::from_raw(y_);
  p.heading = Angle{static_cast<uint32_t>((heading_q64_ + (uint64_t{1} << 31)) >> 32)};
  return p;
}

}  // namespace seqslam
