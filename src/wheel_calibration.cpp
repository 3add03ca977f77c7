// Wheel calibration from loop closures (see wheel_calibration.h for the model and method).
#include "seqslam/wheel_calibration.h"

#include "seqslam/fixmath.h"
#include "seqslam/wide_int.h"

namespace seqslam {
namespace {

// 2 pi in Q31.32, and 1 / (2 pi) turns per radian in Q0.32 (binary angle units per radian
// divided by 2^32).
constexpr int64_t kTwoPiQ32 = 26986075409;
constexpr int64_t kTurnsPerRadianQ32 = 683565276;
constexpr int64_t kOne = int64_t{1} << 32;
constexpr int64_t kPerMille = 1000;

int64_t mul(int64_t a, int64_t b) {
  return mul_shift_round(a, b, 32);
}
int64_t abs64(int64_t v) {
  return v < 0 ? -v : v;
}

int64_t radians_of_bam(int32_t bam) {
  return mul(bam, kTwoPiQ32);
}
Angle bam_of_radians(int64_t rad) {
  return Angle{static_cast<uint32_t>(static_cast<uint64_t>(mul(rad, kTurnsPerRadianQ32)))};
}

// The replayed chain at one node: heading (radians), position (metres), the heading's
// derivatives by delta and tau (radians per per mille) and the prefix sums of those (at each
// edge's middle) times the edge's translation.
enum : int { kTheta, kX, kY, kA, kB, kGdx, kGdy, kGtx, kGty, kValues };

struct Params {
  int64_t delta;  // per mille, Q31.32
  int64_t tau;    // per mille, Q31.32
};

struct Normal {
  int64_t h00 = 0, h01 = 0, h11 = 0;  // J^T W J
  int64_t g0 = 0, g1 = 0;             // J^T W r
  int64_t cost = 0;                   // r^T W r
  int64_t position = 0;               // sum of squared position residuals
  uint32_t used = 0;
  uint32_t skipped = 0;
};

// The normal matrix with the prior on its diagonal, and its determinant / 2^32 (Q31.32), for
// Cramer's rule with 128-bit products. `scale` <= 0: singular.
struct Regularised {
  int64_t h00, h01, h11;
  Int128 scale;
};

Regularised regularised(const Normal& n, int64_t prior) {
  Regularised r{n.h00 + prior, n.h01, n.h11 + prior, Int128(0)};
  r.scale = (Int128(r.h00) * Int128(r.h11) - Int128(r.h01) * Int128(r.h01)).sar(32);
  return r;
}

// One odometry edge replayed with the corrected constants (see the header's model).
// Returns false for a break (not an odometry step): the chain then jumps by the measurement
// as it is, with no derivative.
bool replay_edge(const PoseGraphEdge& e, const Params& p, int64_t track, int64_t max_step,
                 int64_t* v) {
  const int64_t dx = int64_t{e.dx.raw()} * 256;  // Q7.24 -> Q31.32
  const int64_t dy = int64_t{e.dy.raw()} * 256;
  const int32_t bam = signed_diff(e.dtheta, Angle{});
  const bool step =
      abs64(dx) <= max_step && abs64(dy) <= max_step && bam > -(1 << 30) && bam < (1 << 30);
  if (!step) {
    const SinCos sc = sincos(bam_of_radians(v[kTheta]));
    const int64_t c = int64_t{sc.cos.raw()} * 4, s = int64_t{sc.sin.raw()} * 4;  // Q1.30->Q.32
    v[kX] += mul(c, dx) - mul(s, dy);
    v[kY] += mul(s, dx) + mul(c, dy);
    v[kTheta] += radians_of_bam(bam);
    return false;
  }
  // Chord length (Q.24 -> Q.32), turn, and the arc's path length s = chord (1 + dtheta^2/24).
  const int64_t dx24 = e.dx.raw(), dy24 = e.dy.raw();
  const int64_t chord =
      static_cast<int64_t>(isqrt64(static_cast<uint64_t>(dx24 * dx24 + dy24 * dy24))) << 8;
  const int64_t turn = radians_of_bam(bam);
  const int64_t path = chord + mul(chord, mul(turn, turn) / 24);
  // s' = s + delta b dtheta / 4;  dtheta' = (dtheta + delta s / b) / (1 + tau).
  const int64_t per_delta = div_sat<Q31_32>(Q31_32::from_raw(path),
                                            Q31_32::from_raw(track * kPerMille))
                                .raw();  // s / b radians per per mille of delta
  const int64_t one_tau = kOne + p.tau / kPerMille;
  const int64_t path2 = path + mul(mul(p.delta, track), turn) / (4 * kPerMille);
  const int64_t turn2 =
      div_sat<Q31_32>(Q31_32::from_raw(turn + mul(p.delta, per_delta)), Q31_32::from_raw(one_tau))
          .raw();
  const int64_t d_delta =
      div_sat<Q31_32>(Q31_32::from_raw(per_delta), Q31_32::from_raw(one_tau)).raw();
  const int64_t d_tau =
      -div_sat<Q31_32>(Q31_32::from_raw(turn2), Q31_32::from_raw(one_tau * kPerMille)).raw();
  const int64_t chord2 = path2 - mul(path2, mul(turn2, turn2) / 24);
  const SinCos sc = sincos(bam_of_radians(v[kTheta] + turn2 / 2));
  const int64_t tx = mul(chord2, int64_t{sc.cos.raw()} * 4);
  const int64_t ty = mul(chord2, int64_t{sc.sin.raw()} * 4);
  const int64_t a_mid = v[kA] + d_delta / 2, b_mid = v[kB] + d_tau / 2;
  v[kGdx] += mul(a_mid, tx);
  v[kGdy] += mul(a_mid, ty);
  v[kGtx] += mul(b_mid, tx);
  v[kGty] += mul(b_mid, ty);
  v[kA] += d_delta;
  v[kB] += d_tau;
  v[kX] += tx;
  v[kY] += ty;
  v[kTheta] += turn2;
  return true;
}

// A closure's residual and derivatives, added to the normal equations.
void add_closure(const WheelCalibrationSlot& s, const int64_t* hi, int64_t heading_weight,
                 Normal* n) {
  const int64_t* lo = s.at_lo;
  const SinCos sc = sincos(bam_of_radians(lo[kTheta]));
  const int64_t c = int64_t{sc.cos.raw()} * 4, sn = int64_t{sc.sin.raw()} * 4;
  const int64_t dx = hi[kX] - lo[kX], dy = hi[kY] - lo[kY];
  const int64_t r[3] = {
      mul(c, dx) + mul(sn, dy) - s.z.dx.raw(), mul(c, dy) - mul(sn, dx) - s.z.dy.raw(),
      radians_of_bam(signed_diff(bam_of_radians(hi[kTheta] - lo[kTheta]), s.z.dtheta))};
  // d r / d q: R(-theta_lo) J ((G_hi - G_lo) - A_lo d) for the position, A_hi - A_lo for the
  // heading (q = delta with A, G_delta; q = tau with B, G_tau).
  int64_t j[2][3];
  for (int q = 0; q < 2; ++q) {
    const int a = q == 0 ? kA : kB, gx = q == 0 ? kGdx : kGtx, gy = q == 0 ? kGdy : kGty;
    const int64_t vx = hi[gx] - lo[gx] - mul(lo[a], dx);
    const int64_t vy = hi[gy] - lo[gy] - mul(lo[a], dy);
    j[q][0] = mul(sn, vx) - mul(c, vy);
    j[q][1] = mul(sn, vy) + mul(c, vx);
    j[q][2] = hi[a] - lo[a];
  }
  for (int k = 0; k < 3; ++k) {
    const int64_t w = k == 2 ? heading_weight : kOne;
    const int64_t wr = mul(w, r[k]), wj0 = mul(w, j[0][k]);
    n->h00 += mul(wj0, j[0][k]);
    n->h01 += mul(wj0, j[1][k]);
    n->h11 += mul(mul(w, j[1][k]), j[1][k]);
    n->g0 += mul(wr, j[0][k]);
    n->g1 += mul(wr, j[1][k]);
    n->cost += mul(wr, r[k]);
  }
  n->position += mul(r[0], r[0]) + mul(r[1], r[1]);
  ++n->used;
}

// One replay of the chain at `p`, with the normal equations of every usable closure.
Normal replay(const PoseGraph& graph, const WheelCalibrationConfig& config, const Params& p,
              Span<WheelCalibrationSlot> slots, uint32_t* breaks) {
  Normal n;
  int64_t v[kValues] = {};
  const int64_t heading_weight = int64_t{config.heading_weight.raw()} << 16;
  const uint32_t nodes = graph.node_count();
  uint32_t next_hi = 0, next_lo = 0;
  uint16_t segment = 0;
  *breaks = 0;
  for (uint32_t node = 0; node < nodes; ++node) {
    for (; next_hi < slots.size() && slots[next_hi].hi == node; ++next_hi) {
      if (slots[next_hi].segment == segment) {
        add_closure(slots[next_hi], v, heading_weight, &n);
      } else {
        ++n.skipped;
      }
    }
    for (; next_lo < slots.size() && slots[slots[next_lo].by_lo].lo == node; ++next_lo) {
      WheelCalibrationSlot& s = slots[slots[next_lo].by_lo];
      for (int k = 0; k < kValues; ++k)
        s.at_lo[k] = v[k];
      s.segment = segment;
    }
    if (node + 1 == nodes) break;
    if (!replay_edge(graph.edge(node).value(), p, config.track_width.raw(), config.max_step.raw(),
                     v)) {
      ++*breaks;
      ++segment;
    }
  }
  return n;
}

// Reads the closures into the slots, each running from its older node to its newer, ordered
// by the newer one, with the permutation by the older one in `by_lo`.
void load_closures(const PoseGraph& graph, Span<WheelCalibrationSlot> slots) {
  const uint32_t first = graph.node_count() > 0 ? graph.node_count() - 1 : 0;
  for (uint32_t i = 0; i < slots.size(); ++i) {
    const PoseGraphEdge e = graph.edge(first + i).value();
    WheelCalibrationSlot s{};
    const RelativePose2 z{Q31_32::from_raw(int64_t{e.dx.raw()} * 256),
                          Q31_32::from_raw(int64_t{e.dy.raw()} * 256), e.dtheta};
    if (e.from < e.to) {
      s.lo = e.from;
      s.hi = e.to;
      s.z = z;
    } else {
      // The older node seen from the newer one, inverted.
      s.lo = e.to;
      s.hi = e.from;
      s.z = relative_pose(Pose2{z.dx, z.dy, z.dtheta}, Pose2{});
    }
    // Insertion by `hi` (closures arrive in this order from the explorer: linear).
    uint32_t k = i;
    for (; k > 0 && slots[k - 1].hi > s.hi; --k)
      slots[k] = slots[k - 1];
    slots[k] = s;
  }
  for (uint32_t i = 0; i < slots.size(); ++i) {
    uint32_t k = i;
    for (; k > 0 && slots[slots[k - 1].by_lo].lo > slots[i].lo; --k) {
      slots[k].by_lo = slots[k - 1].by_lo;
    }
    slots[k].by_lo = static_cast<uint16_t>(i);
  }
}

bool config_ok(const WheelCalibrationConfig& c) {
  return c.track_width.raw() > 0 && c.track_width <= Q31_32::from_int(100) &&
         c.max_step.raw() > 0 && c.max_step <= Q31_32::from_int(16) && c.iterations >= 1 &&
         c.iterations <= 20 && c.max_sigma_difference.raw() > 0 && c.max_sigma_track.raw() > 0 &&
         c.max_difference.raw() > 0 && c.max_difference <= Q31_32::from_ratio(1, 10) &&
         c.max_track.raw() > 0 && c.max_track <= Q31_32::from_ratio(1, 2) &&
         c.correlated_closures >= 1 && c.correlated_closures <= 1000;
}

// sqrt of a non-negative Q31.32 value, Q31.32.
int64_t sqrt_q32(int64_t v) {
  if (v <= 0) return 0;
  const uint64_t u = static_cast<uint64_t>(v);
  if (u < (uint64_t{1} << 32)) return static_cast<int64_t>(isqrt64(u << 32));
  return static_cast<int64_t>(isqrt64(u)) << 16;
}

}  // namespace

Status calibrate_wheels(const PoseGraph& graph, const WheelCalibrationConfig& config,
                        Span<WheelCalibrationSlot> scratch, WheelCalibrationResult* out) {
  if (out == nullptr || !config_ok(config) || !graph.configured()) return Status::kInvalidArgument;
  const uint32_t closures = graph.closure_count();
  if (scratch.size() < closures) return Status::kInvalidArgument;
  *out = WheelCalibrationResult{};
  Span<WheelCalibrationSlot> slots(scratch.data(), closures);
  load_closures(graph, slots);
  const int64_t prior = int64_t{config.prior_weight.raw()} << 16;
  Params p{0, 0};
  Normal n;
  for (uint32_t it = 0; it <= config.iterations; ++it) {
    n = replay(graph, config, p, slots, &out->breaks);
    if (it == 0) {
      out->closures_used = n.used;
      out->closures_skipped = n.skipped;
      if (n.used > 0) out->rms_before = Q31_32::from_raw(sqrt_q32(n.position / n.used));
      if (n.used < config.min_closures) return Status::kFailedPrecondition;
    }
    if (it == config.iterations) break;  // the last replay only measures
    // (H + prior) step = -(g + prior p).
    const Regularised h = regularised(n, prior);
    if (!(h.scale > Int128(0))) return Status::kOutOfRange;
    const int64_t g0 = n.g0 + mul(prior, p.delta), g1 = n.g1 + mul(prior, p.tau);
    const Int128 num0 = Int128(h.h11) * Int128(g0) - Int128(h.h01) * Int128(g1);
    const Int128 num1 = Int128(h.h00) * Int128(g1) - Int128(h.h01) * Int128(g0);
    p.delta -= static_cast<int64_t>(num0.div(h.scale).low64());
    p.tau -= static_cast<int64_t>(num1.div(h.scale).low64());
    out->iterations = it + 1;
  }
  out->correction.difference = Q31_32::from_raw(p.delta / kPerMille);
  out->correction.track = Q31_32::from_raw(p.tau / kPerMille);
  if (n.used > 0) out->rms_after = Q31_32::from_raw(sqrt_q32(n.position / n.used));
  // Formal variances: s^2 (H^-1)_ii with s^2 the residual variance per component.
  const Regularised h = regularised(n, prior);
  const uint32_t dof = 3 * n.used > 2 ? 3 * n.used - 2 : 1;
  const int64_t s2 = n.cost / dof * config.correlated_closures;
  if (!(h.scale > Int128(0))) return Status::kOutOfRange;
  const int64_t var_delta = static_cast<int64_t>((Int128(s2) * Int128(h.h11)).div(h.scale).low64());
  const int64_t var_tau = static_cast<int64_t>((Int128(s2) * Int128(h.h00)).div(h.scale).low64());
  out->sigma_difference = Q31_32::from_raw(sqrt_q32(var_delta) / kPerMille);
  out->sigma_track = Q31_32::from_raw(sqrt_q32(var_tau) / kPerMille);
  const bool separable = out->sigma_difference <= config.max_sigma_difference &&
                         out->sigma_track <= config.max_sigma_track;
  const bool plausible = abs64(out->correction.difference.raw()) <= config.max_difference.raw() &&
                         abs64(out->correction.track.raw()) <= config.max_track.raw();
  return separable && plausible ? Status::kOk : Status::kOutOfRange;
}

OdometryConfig apply_wheel_correction(const OdometryConfig& base, const WheelCorrection& c) {
  OdometryConfig out = base;
  const int64_t half = c.difference.raw() / 2;
  out.circumference_left =
      Q31_32::from_raw(base.circumference_left.raw() + mul(base.circumference_left.raw(), -half));
  out.circumference_right =
      Q31_32::from_raw(base.circumference_right.raw() + mul(base.circumference_right.raw(), half));
  out.track_width =
      Q31_32::from_raw(base.track_width.raw() + mul(base.track_width.raw(), c.track.raw()));
  return out;
}

}  // namespace seqslam
