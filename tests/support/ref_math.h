// Double-precision reference maths for test oracles, identical on the host and on the
// bare-metal target (where there is no libm; doubles are libgcc soft-float, which is exact
// IEEE 754 arithmetic, so both sides compute bit-identical results).
//
// Header-only and freestanding: only <stdint.h>, no math builtins (they would call libm).
// Not fast, not for production code: the fixed-point core never includes this.
//
// Accuracy: largest error against glibc's <cmath> over 2 million random arguments each
// (design bound in brackets); tests/support/test_ref_math.cpp enforces the tolerances that
// target-side tests may rely on.
//   ref_fabs, ref_floor, ref_round   exact
//   ref_sqrt                         1 ulp relative (Newton from an upper bound)
//   ref_sin, ref_cos                 1.1e-16 absolute for |x| <= 1e4 [3e-16]; tested to 2e-15
//                                    for |x| <= 1e4. Degrades beyond |x| ~ 1.6e6, where the
//                                    Cody-Waite reduction stops being exact; NaN for
//                                    |x| > 2^50
//   ref_atan2                        4.4e-16 absolute; tested to 1e-15
//   ref_exp                          2.2e-16 relative (1 ulp) for normal results; tested to
//                                    1e-15
//   ref_log                          2.2e-16 relative; tested to 1e-15
//   ref_pow(x, y), x >= 0            2.2e-16 relative for normal results (log x and y log x
//                                    are carried in double-double); tested to 1e-13 for
//                                    x in [0, 1], y in [0.4, 2.5] and to 2e-15 for
//                                    x in [1e-100, 1e100], y in [-3, 3]. x < 0 gives NaN.
// Special values: NaN in gives NaN out; infinities and zeros follow C99 Annex F where it
// matters for tests (exp(-inf)=0, log(0)=-inf, pow(0, y>0)=0, atan2 signed zeros).
#pragma once

#include <stdint.h>

namespace seqslam::test {

inline constexpr double kPi = 0x1.921fb54442d18p+1;

namespace ref_math_detail {

// pi/2 split for Cody-Waite reduction: kPio2A and kPio2B have 33 significant bits, so k*A
// and k*B are exact for |k| < 2^20; kPio2C is the rest.
inline constexpr double kPio2A = 0x1.921fb54400000p+0;
inline constexpr double kPio2B = 0x1.0b4611a600000p-34;
inline constexpr double kPio2C = 0x1.3198a2e037073p-69;
inline constexpr double kTwoOverPi = 0x1.45f306dc9c883p-1;
inline constexpr double kPiHi = 0x1.921fb54442d18p+1;
inline constexpr double kPiLo = 0x1.1a62633145c07p-53;
inline constexpr double kPio2Hi = 0x1.921fb54442d18p+0;
inline constexpr double kPio2Lo = 0x1.1a62633145c07p-54;
inline constexpr double kPio4Hi = 0x1.921fb54442d18p-1;
inline constexpr double kPio4Lo = 0x1.1a62633145c07p-55;
inline constexpr double kAtanHalfHi = 0x1.dac670561bb4fp-2;  // atan(1/2)
inline constexpr double kAtanHalfLo = 0x1.a2b7f222f65e2p-56;
// ln 2 split: kLn2Hi has 40 significant bits, so k*kLn2Hi is exact for |k| < 2^13.
inline constexpr double kLn2Hi = 0x1.62e42fefa2000p-1;
inline constexpr double kLn2Lo = 0x1.9ef35793c7673p-41;
inline constexpr double kInvLn2 = 0x1.71547652b82fep+0;
inline constexpr double kSqrt2 = 0x1.6a09e667f3bcdp+0;

inline uint64_t bits_of(double x) {
  uint64_t b;
  __builtin_memcpy(&b, &x, sizeof b);
  return b;
}

inline double from_bits(uint64_t b) {
  double x;
  __builtin_memcpy(&x, &b, sizeof x);
  return x;
}

inline double quiet_nan() {
  return from_bits(0x7ff8000000000000u);
}
inline double infinity() {
  return from_bits(0x7ff0000000000000u);
}
inline bool is_nan(double x) {
  return (bits_of(x) & 0x7fffffffffffffffu) > 0x7ff0000000000000u;
}
inline bool is_inf(double x) {
  return (bits_of(x) & 0x7fffffffffffffffu) == 0x7ff0000000000000u;
}
inline bool sign_bit(double x) {
  return (bits_of(x) >> 63) != 0;
}

// 2^n for n in [-1022, 1023].
inline double pow2(int n) {
  return from_bits(static_cast<uint64_t>(n + 1023) << 52);
}

// x * 2^n without intermediate overflow, for x within a few binades of 1 (all callers).
// Results in the subnormal range are rounded once.
inline double scale_pow2(double x, int n) {
  while (n > 1023) {
    x *= pow2(1023);
    n -= 1023;
  }
  if (n < -1022) {
    if (n + 1000 < -1022) {
      return x * 0.0;  // far below the smallest subnormal
    }
    return x * pow2(n + 1000) * pow2(-1000);  // the first product is exact (normal)
  }
  return x * pow2(n);
}

// Binary exponent of a finite non-zero normal x: x in [2^e, 2^(e+1)).
inline int exponent_of(double x) {
  return static_cast<int>((bits_of(x) >> 52) & 0x7ffu) - 1023;
}

// Error-free transformations (Knuth two-sum, Dekker product with Veltkamp splitting).
struct DoubleDouble {
  double hi;
  double lo;
};

inline DoubleDouble two_sum(double a, double b) {
  const double s = a + b;
  const double bb = s - a;
  return {s, (a - (s - bb)) + (b - bb)};
}

inline DoubleDouble fast_two_sum(double a, double b) {  // requires |a| >= |b|
  const double s = a + b;
  return {s, b - (s - a)};
}

inline DoubleDouble split(double a) {  // |a| < 2^996
  const double c = 134217729.0 * a;    // 2^27 + 1
  const double hi = c - (c - a);
  return {hi, a - hi};
}

inline DoubleDouble two_prod(double a, double b) {
  const double p = a * b;
  const DoubleDouble as = split(a);
  const DoubleDouble bs = split(b);
  const double err = ((as.hi * bs.hi - p) + as.hi * bs.lo + as.lo * bs.hi) + as.lo * bs.lo;
  return {p, err};
}

// Truncation toward zero for |x| < 2^52.
inline double trunc_small(double x) {
  return static_cast<double>(static_cast<int64_t>(x));
}

// Taylor coefficients, exactly rounded at compile time (n! is exact in double up to 22!).
inline constexpr double kInvFact[] = {
    1.0,
    1.0,
    1.0 / 2.0,
    1.0 / 6.0,
    1.0 / 24.0,
    1.0 / 120.0,
    1.0 / 720.0,
    1.0 / 5040.0,
    1.0 / 40320.0,
    1.0 / 362880.0,
    1.0 / 3628800.0,
    1.0 / 39916800.0,
    1.0 / 479001600.0,
    1.0 / 6227020800.0,
    1.0 / 87178291200.0,
    1.0 / 1307674368000.0,
    1.0 / 20922789888000.0,
    1.0 / 355687428096000.0,
    1.0 / 6402373705728000.0,
    1.0 / 121645100408832000.0,
    1.0 / 2432902008176640000.0,
    1.0 / 51090942171709440000.0,
    1.0 / 1124000727777607680000.0,
};

// Signed Taylor coefficient of x^n / n! in sin (odd n) or cos (even n): the signs run
// +, -, -, +, +, -, ... so x^n has a minus sign when n mod 4 is 2 or 3.
inline constexpr double taylor_coefficient(int n) {
  return (n % 4 == 2 || n % 4 == 3) ? -kInvFact[n] : kInvFact[n];
}

// sin(r + c) for |r| <= pi/4 and a tiny correction c: Taylor to r^21 (truncation < 1e-24).
inline double sin_kernel(double r, double c) {
  const double s = r * r;
  double p = taylor_coefficient(21);
  for (int n = 19; n >= 3; n -= 2) {
    p = taylor_coefficient(n) + s * p;
  }
  // sin(r) = r + r s (-1/3! + s/5! - ...); sin(r + c) ~ sin(r) + c cos(r).
  return r + (r * s * p + c * (1.0 - 0.5 * s));
}

// cos(r + c) for |r| <= pi/4: Taylor to r^22.
inline double cos_kernel(double r, double c) {
  const double s = r * r;
  double p = taylor_coefficient(22);
  for (int n = 20; n >= 2; n -= 2) {
    p = taylor_coefficient(n) + s * p;
  }
  // cos(r) = 1 + s (-1/2! + s/4! - ...); cos(r + c) ~ cos(r) - c sin(r).
  return 1.0 + (s * p - c * r);
}

// x = k * pi/2 + (hi + lo), |hi + lo| <= ~pi/4; returns k mod 4. Requires |x| <= 2^50.
inline int reduce_pio2(double x, double& hi, double& lo) {
  const double k = ref_math_detail::trunc_small(x * kTwoOverPi + (x < 0 ? -0.5 : 0.5));
  const double r1 = x - k * kPio2A;  // exact for |k| < 2^20
  const DoubleDouble r2 = two_sum(r1, -(k * kPio2B));
  const DoubleDouble r = fast_two_sum(r2.hi, r2.lo - k * kPio2C);
  hi = r.hi;
  lo = r.lo;
  return static_cast<int>(static_cast<int64_t>(k) & 3);
}

// atan(t) for |t| <= 0.25: Taylor to t^31 (truncation < 1e-20).
inline double atan_series(double t) {
  const double z = t * t;
  double p = -1.0 / 31.0;  // t^31 has a minus sign, like t^3
  for (int n = 29; n >= 3; n -= 2) {
    const double term = 1.0 / static_cast<double>(n);
    p = (n % 4 == 3 ? -term : term) + z * p;
  }
  return t + t * z * p;
}

// atan(a) for 0 <= a <= 1, as hi + lo.
inline double atan_unit(double a) {
  if (a <= 0.25) {
    return atan_series(a);
  }
  if (a <= 0.75) {  // atan(a) = atan(1/2) + atan((a - 1/2) / (1 + a/2))
    const double t = (a - 0.5) / (1.0 + 0.5 * a);
    return kAtanHalfHi + (atan_series(t) + kAtanHalfLo);
  }
  const double t = (a - 1.0) / (1.0 + a);  // atan(a) = pi/4 + atan((a - 1) / (1 + a))
  return kPio4Hi + (atan_series(t) + kPio4Lo);
}

// exp(hi + lo) with |lo| << |hi|.
inline double exp_dd(double hi, double lo) {
  if (is_nan(hi)) {
    return hi;
  }
  if (hi > 709.8) {
    return infinity();
  }
  if (hi < -745.2) {
    return 0.0;
  }
  const double k = trunc_small(hi * kInvLn2 + (hi < 0 ? -0.5 : 0.5));
  const double r1 = hi - k * kLn2Hi;  // exact: k * kLn2Hi is exact and close to hi
  const DoubleDouble r = two_sum(r1, -(k * kLn2Lo));
  const double c = r.lo + lo;  // exp(r.hi + c) = exp(r.hi) (1 + c)
  // expm1(r) by Taylor to r^16 for |r| <= 0.35 (truncation < 1e-22).
  double p = kInvFact[16];
  for (int n = 15; n >= 2; --n) {
    p = kInvFact[n] + r.hi * p;
  }
  const double em1 = r.hi + r.hi * r.hi * p;
  const double e = 1.0 + (em1 + c * (1.0 + em1));
  return scale_pow2(e, static_cast<int>(k));
}

// log(x) as hi + lo for finite x > 0.
inline DoubleDouble log_dd(double x) {
  int e = 0;
  if (exponent_of(x) == -1023) {  // subnormal
    x *= pow2(54);
    e = -54;
  }
  e += exponent_of(x);
  double m = from_bits((bits_of(x) & 0x000fffffffffffffu) | 0x3ff0000000000000u);  // [1, 2)
  if (m > kSqrt2) {
    m *= 0.5;
    ++e;
  }
  // log(m) = 2 atanh(s), s = (m - 1) / (m + 1), |s| <= 0.1716.
  const double f = m - 1.0;  // exact
  const DoubleDouble d = two_sum(2.0, f);
  const double s = f / d.hi;
  const DoubleDouble sd = two_prod(s, d.hi);
  const double s_lo = (((f - sd.hi) - sd.lo) - s * d.lo) / d.hi;
  const double z = s * s;
  double p = 1.0 / 25.0;
  for (int n = 23; n >= 3; n -= 2) {
    p = 1.0 / static_cast<double>(n) + z * p;
  }
  const double tail = 2.0 * s * z * p + 2.0 * s_lo;
  const double ed = static_cast<double>(e);
  const DoubleDouble head = two_sum(ed * kLn2Hi, 2.0 * s);  // ed * kLn2Hi exact
  const double lo = head.lo + (ed * kLn2Lo + tail);
  return fast_two_sum(head.hi, lo);
}

}  // namespace ref_math_detail

inline double ref_fabs(double x) {
  return ref_math_detail::from_bits(ref_math_detail::bits_of(x) & 0x7fffffffffffffffu);
}

// Largest integer <= x. Exact.
inline double ref_floor(double x) {
  if (ref_math_detail::is_nan(x) || ref_fabs(x) >= 0x1p52 || x == 0.0) {
    return x;
  }
  double t = ref_math_detail::trunc_small(x);
  if (t > x) {
    t -= 1.0;
  }
  return t;
}

// Nearest integer, halfway cases away from zero (std::round). Exact.
inline double ref_round(double x) {
  if (ref_math_detail::is_nan(x) || ref_fabs(x) >= 0x1p52) {
    return x;
  }
  const double a = ref_fabs(x);
  double t = ref_floor(a);
  if (a - t >= 0.5) {  // a - t is exact
    t += 1.0;
  }
  return ref_math_detail::sign_bit(x) ? -t : t;
}

// Square root by Newton's iteration from an upper bound; stops when the iterate no longer
// decreases, which leaves it within 1 ulp of the true root.
inline double ref_sqrt(double x) {
  using namespace ref_math_detail;  // NOLINT(google-build-using-namespace)
  if (is_nan(x) || x < 0.0) {
    return quiet_nan();
  }
  if (x == 0.0 || is_inf(x)) {
    return x;
  }
  int scale = 0;
  if (x < 0x1p-1000) {  // subnormal or tiny: work on x * 2^1000
    x *= 0x1p1000;
    scale = -500;
  }
  const int e = exponent_of(x);
  double y = pow2(e / 2 + 1);  // >= sqrt(x) since x < 2^(e+1)
  for (int i = 0; i < 100; ++i) {
    const double next = 0.5 * (y + x / y);
    if (!(next < y)) {
      break;
    }
    y = next;
  }
  return scale != 0 ? y * pow2(scale) : y;
}

// sin and cos: Cody-Waite reduction by pi/2 in three parts (exact for |x| < ~1.6e6),
// the reduced argument kept as a double-double, then Taylor series on [-pi/4, pi/4].
inline double ref_sin(double x) {
  using namespace ref_math_detail;              // NOLINT(google-build-using-namespace)
  if (is_nan(x) || !(ref_fabs(x) <= 0x1p50)) {  // also infinities
    return quiet_nan();
  }
  double hi;
  double lo;
  switch (reduce_pio2(x, hi, lo)) {
    case 0:
      return sin_kernel(hi, lo);
    case 1:
      return cos_kernel(hi, lo);
    case 2:
      return -sin_kernel(hi, lo);
    default:
      return -cos_kernel(hi, lo);
  }
}

inline double ref_cos(double x) {
  using namespace ref_math_detail;              // NOLINT(google-build-using-namespace)
  if (is_nan(x) || !(ref_fabs(x) <= 0x1p50)) {  // also infinities
    return quiet_nan();
  }
  double hi;
  double lo;
  switch (reduce_pio2(x, hi, lo)) {
    case 0:
      return cos_kernel(hi, lo);
    case 1:
      return -sin_kernel(hi, lo);
    case 2:
      return -cos_kernel(hi, lo);
    default:
      return sin_kernel(hi, lo);
  }
}

// atan2(y, x) in [-pi, pi], with C99's signed zeros and infinities.
inline double ref_atan2(double y, double x) {
  using namespace ref_math_detail;  // NOLINT(google-build-using-namespace)
  if (is_nan(x) || is_nan(y)) {
    return quiet_nan();
  }
  const bool negative_y = sign_bit(y);
  const bool negative_x = sign_bit(x);
  double r;
  if (y == 0.0) {
    r = negative_x ? kPi : 0.0;
  } else if (x == 0.0) {
    r = kPio2Hi;
  } else if (is_inf(x) && is_inf(y)) {
    r = negative_x ? 3.0 * kPio4Hi : kPio4Hi;
  } else if (is_inf(x)) {
    r = negative_x ? kPi : 0.0;
  } else if (is_inf(y)) {
    r = kPio2Hi;
  } else {
    const double ax = ref_fabs(x);
    const double ay = ref_fabs(y);
    if (ay <= ax) {
      r = atan_unit(ay / ax);
    } else {
      r = (kPio2Hi - atan_unit(ax / ay)) + kPio2Lo;
    }
    if (negative_x) {
      r = (kPiHi - r) + kPiLo;
    }
  }
  return negative_y ? -r : r;
}

// e^x: reduction by ln 2 (Cody-Waite, two parts), Taylor series for expm1 on
// [-ln2/2, ln2/2], exact scaling by 2^k.
inline double ref_exp(double x) {
  return ref_math_detail::exp_dd(x, 0.0);
}

// Natural logarithm: x = 2^e m with m in (sqrt(1/2), sqrt(2)], log m = 2 atanh((m-1)/(m+1))
// by its series, everything summed in double-double.
inline double ref_log(double x) {
  using namespace ref_math_detail;  // NOLINT(google-build-using-namespace)
  if (is_nan(x) || x < 0.0) {
    return quiet_nan();
  }
  if (x == 0.0) {
    return -infinity();
  }
  if (is_inf(x)) {
    return x;
  }
  const DoubleDouble l = log_dd(x);
  return l.hi + l.lo;
}

// x^y for x >= 0 (NaN for x < 0): exp(y log x) with log x and the product in double-double.
inline double ref_pow(double x, double y) {
  using namespace ref_math_detail;  // NOLINT(google-build-using-namespace)
  if (y == 0.0 || x == 1.0) {
    return 1.0;
  }
  if (is_nan(x) || is_nan(y) || x < 0.0) {
    return quiet_nan();
  }
  if (x == 0.0) {
    return y > 0.0 ? 0.0 : infinity();
  }
  if (is_inf(x)) {
    return y > 0.0 ? infinity() : 0.0;
  }
  if (is_inf(y)) {
    return (x < 1.0) == (y > 0.0) ? 0.0 : infinity();
  }
  const DoubleDouble l = log_dd(x);
  const DoubleDouble p = two_prod(y, l.hi);
  const DoubleDouble z = fast_two_sum(p.hi, p.lo + y * l.lo);
  return exp_dd(z.hi, z.lo);
}

}  // namespace seqslam::test
