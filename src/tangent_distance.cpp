#include "seqslam/tangent_distance.h"

#include "seqslam/assert.h"
#include "seqslam/fixmath.h"
#include "seqslam/wide_int.h"

namespace seqslam {
namespace {

constexpr int kQ = 56;  // fraction bits of the scaled elimination
constexpr int kInvQ = 50;

// round(n / d), ties away from zero, d > 0.
Int128 div_round128(Int128 n, Int128 d) {
  const Int128 half = d.sar(1);
  return n.negative() ? -((-n + half).div(d)) : (n + half).div(d);
}

// exp(-t) for t >= 0, both Q.56: exp(-t/64)^64 with a Taylor series to the 20th power on
// [0, 0.625]; about 2^-48 relative.
Int128 exp_neg_q56(Int128 t) {
  const Int128 u = t.sar(6);
  Int128 sum = Int128(1).shl(kQ);
  Int128 term = sum;
  for (int n = 1; n <= 20; ++n) {
    term = div_round128(-detail::shift_round(term * u, kQ), Int128(n));
    sum = sum + term;
  }
  for (int i = 0; i < 6; ++i)
    sum = detail::shift_round(sum * sum, kQ);
  return sum;
}

int bit_length(uint64_t v) {
  int n = 0;
  while (v != 0) {
    ++n;
    v >>= 1;
  }
  return n;
}

// ceil(n / 2) for any sign.
int ceil_half(int n) {
  return n >= 0 ? (n + 1) / 2 : -((-n) / 2);
}

bool kernel_valid(const BlurKernel& k) {
  if (k.radius > kMaxBlurRadius) return false;
  uint32_t sum = k.weight[0];
  for (int i = 1; i <= k.radius; ++i)
    sum += 2u * k.weight[i];
  return sum == (1u << kBlurShift);
}

uint32_t clampi(int32_t v, uint32_t n) {
  if (v < 0) return 0;
  if (v >= static_cast<int32_t>(n)) return n - 1;
  return static_cast<uint32_t>(v);
}

Status check_size(ImageSize size) {
  return check_image_size(size);
}

// Exact blur into out (no validation).
void blur_into(ImageView image, const BlurKernel& kernel, UQ8_8* out) {
  const uint32_t w = image.size.width;
  const uint32_t h = image.size.height;
  const int32_t r = kernel.radius;
  uint16_t tmp[kMaxPixels];
  for (uint32_t y = 0; y < h; ++y) {
    const uint8_t* row = image.pixels + y * w;
    for (uint32_t x = 0; x < w; ++x) {
      uint32_t acc = kernel.weight[0] * static_cast<uint32_t>(row[x]);
      for (int32_t k = 1; k <= r; ++k) {
        const int32_t xi = static_cast<int32_t>(x);
        acc += kernel.weight[k] * (static_cast<uint32_t>(row[clampi(xi - k, w)]) +
                                   static_cast<uint32_t>(row[clampi(xi + k, w)]));
      }
      // value * 4096 -> UQ8.8, rounded to nearest.
      tmp[y * w + x] = static_cast<uint16_t>((acc + (1u << (kBlurShift - 9))) >> (kBlurShift - 8));
    }
  }
  for (uint32_t y = 0; y < h; ++y) {
    for (uint32_t x = 0; x < w; ++x) {
      uint32_t acc = kernel.weight[0] * static_cast<uint32_t>(tmp[y * w + x]);
      for (int32_t k = 1; k <= r; ++k) {
        const int32_t yi = static_cast<int32_t>(y);
        acc += kernel.weight[k] * (static_cast<uint32_t>(tmp[clampi(yi - k, h) * w + x]) +
                                   static_cast<uint32_t>(tmp[clampi(yi + k, h) * w + x]));
      }
      out[y * w + x] =
          UQ8_8::from_raw(static_cast<uint16_t>((acc + (1u << (kBlurShift - 1))) >> kBlurShift));
    }
  }
}

int gram_index(int i, int j) {
  if (i > j) {
    const int t = i;
    i = j;
    j = t;
  }
  // Row-major upper triangle of a 4x4 matrix.
  static constexpr int kRowStart[4] = {0, 4, 7, 9};
  return kRowStart[i] + (j - i);
}

}  // namespace

Result<BlurKernel> make_blur_kernel(UQ8_8 sigma) {
  const uint32_t s = sigma.raw();
  if (s > 512) return Status::kOutOfRange;
  BlurKernel k;
  if (s == 0) return k;
  k.radius = static_cast<uint8_t>((s + 127) / 128);  // ceil(2 sigma)
  Int128 g[kMaxBlurRadius + 1];
  Int128 total;
  for (int i = 0; i <= k.radius; ++i) {
    // t = i^2 / (2 sigma^2) = i^2 * 2^15 / s^2 in Q.56.
    const Int128 t = Int128(i * i).shl(15 + kQ).div(Int128(static_cast<int64_t>(s) * s));
    g[i] = t > Int128(40).shl(kQ) ? Int128() : exp_neg_q56(t);
    total = total + (i == 0 ? g[i] : g[i] + g[i]);
  }
  uint32_t side = 0;
  for (int i = 1; i <= k.radius; ++i) {
    k.weight[i] = static_cast<uint16_t>(div_round128(g[i].shl(kBlurShift), total).low64());
    side += 2u * k.weight[i];
  }
  k.weight[0] = static_cast<uint16_t>((1u << kBlurShift) - side);
  return k;
}

Status gaussian_blur(ImageView image, const BlurKernel& kernel, UQ8_8* out) {
  if (image.pixels == nullptr || out == nullptr || !kernel_valid(kernel))
    return Status::kInvalidArgument;
  const Status st = check_size(image.size);
  if (!ok(st)) return st;
  blur_into(image, kernel, out);
  return Status::kOk;
}

Status prepare_tangent_image(ImageView image, const BlurKernel& kernel, TangentImage* out,
                             uint8_t tangents) {
  if (image.pixels == nullptr || out == nullptr || !kernel_valid(kernel) ||
      (tangents & ~kAllTangents) != 0)
    return Status::kInvalidArgument;
  const Status st = check_size(image.size);
  if (!ok(st)) return st;
  const uint32_t w = image.size.width;
  const uint32_t h = image.size.height;
  out->size = image.size;
  blur_into(image, kernel, out->blurred);
  const int64_t dmax = static_cast<int64_t>(w > h ? w : h);
  for (uint32_t y = 0; y < h; ++y) {
    const int32_t yi = static_cast<int32_t>(y);
    const int64_t y2 = 2 * static_cast<int64_t>(y) - (static_cast<int64_t>(h) - 1);
    for (uint32_t x = 0; x < w; ++x) {
      const int32_t xi = static_cast<int32_t>(x);
      const int64_t x2 = 2 * static_cast<int64_t>(x) - (static_cast<int64_t>(w) - 1);
      // Twice the derivative in UQ8.8 raw units: derivative = dxr / 512.
      const int32_t dxr = static_cast<int32_t>(out->blurred[y * w + clampi(xi + 1, w)].raw()) -
                          static_cast<int32_t>(out->blurred[y * w + clampi(xi - 1, w)].raw());
      const int32_t dyr = static_cast<int32_t>(out->blurred[clampi(yi + 1, h) * w + x].raw()) -
                          static_cast<int32_t>(out->blurred[clampi(yi - 1, h) * w + x].raw());
      const uint32_t i = y * w + x;
      // Q8.7 raw = value * 128 = dxr / 4.
      out->tangent[0][i] = Q8_7::from_raw(static_cast<int16_t>(div_round_i32(dxr, 4)));
      out->tangent[1][i] = Q8_7::from_raw(static_cast<int16_t>(div_round_i32(dyr, 4)));
      // rotation v dx - u dy and scaling u dx + v dy, u = x2 / D, v = y2 / D:
      // raw = (y2 dxr - x2 dyr) / (4 D).
      out->tangent[2][i] =
          Q8_7::from_raw(static_cast<int16_t>(div_round(y2 * dxr - x2 * dyr, 4 * dmax)));
      out->tangent[3][i] =
          Q8_7::from_raw(static_cast<int16_t>(div_round(x2 * dxr + y2 * dyr, 4 * dmax)));
    }
  }
  const uint32_t n = w * h;
  for (int a = 0; a < kTangentCount; ++a) {
    if ((tangents & (1u << a)) != 0) continue;
    for (uint32_t i = 0; i < n; ++i)
      out->tangent[a][i] = Q8_7{};
  }
  for (int a = 0; a < kTangentCount; ++a) {
    for (int b = a; b < kTangentCount; ++b) {
      int64_t acc = 0;
      for (uint32_t i = 0; i < n; ++i)
        acc += static_cast<int32_t>(out->tangent[a][i].raw()) * out->tangent[b][i].raw();
      out->gram[gram_index(a, b)] = acc;
    }
  }
  return Status::kOk;
}

Result<TangentDistance> tangent_distance(const TangentImage& a, const TangentImage& b) {
  if (a.size != b.size || a.size.pixels() == 0 || a.size.pixels() > kMaxPixels)
    return Status::kInvalidArgument;
  const uint32_t n = a.size.pixels();
  constexpr int kN = 2 * kTangentCount;
  // Raw sums: cross Gram (Q.14), g = M^T d (Q.15), ||d||^2 (Q.16).
  int64_t cross[kTangentCount][kTangentCount] = {};
  int64_t g[kN] = {};
  int64_t dd = 0;
  for (uint32_t i = 0; i < n; ++i) {
    const int64_t d =
        static_cast<int64_t>(a.blurred[i].raw()) - static_cast<int64_t>(b.blurred[i].raw());
    dd += d * d;
    int64_t la[kTangentCount];
    int64_t lb[kTangentCount];
    for (int k = 0; k < kTangentCount; ++k) {
      la[k] = a.tangent[k][i].raw();
      lb[k] = b.tangent[k][i].raw();
      g[k] += la[k] * d;
      g[kTangentCount + k] -= lb[k] * d;
    }
    for (int p = 0; p < kTangentCount; ++p)
      for (int q = 0; q < kTangentCount; ++q)
        cross[p][q] += la[p] * lb[q];
  }
  TangentDistance out;
  out.plain_squared = Q47_16::from_raw(dd);
  if (dd == 0) {
    out.squared = Q47_16::from_raw(0);
    out.rms = UQ8_8::from_raw(0);
    return out;
  }
  // G = M^T M with M = [L_A, -L_B] (raw Q.14).
  int64_t gm[kN][kN];
  for (int p = 0; p < kTangentCount; ++p) {
    for (int q = 0; q < kTangentCount; ++q) {
      gm[p][q] = a.gram[gram_index(p, q)];
      gm[kTangentCount + p][kTangentCount + q] = b.gram[gram_index(p, q)];
      gm[p][kTangentCount + q] = -cross[p][q];
      gm[kTangentCount + q][p] = -cross[p][q];
    }
  }
  // Exact power-of-two scaling: column i by 2^-e_i so G_ii lands in [1/4, 1]; d by 2^-f.
  int e[kN];
  bool used[kN];
  for (int i = 0; i < kN; ++i) {
    used[i] = gm[i][i] > 0;
    e[i] = used[i] ? ceil_half(bit_length(static_cast<uint64_t>(gm[i][i])) - 14) : 0;
  }
  const int f = ceil_half(bit_length(static_cast<uint64_t>(dd)) - 16);
  // The augmented matrix [G g; g^T s] in Q.56, lower triangle used.
  constexpr int kA = kN + 1;
  Int128 m[kA][kA];
  for (int i = 0; i < kN; ++i) {
    for (int j = 0; j <= i; ++j) {
      if (!used[i] || !used[j]) {
        m[i][j] = i == j ? Int128(1).shl(kQ) : Int128();
        continue;
      }
      m[i][j] = Int128(gm[i][j]).shl(kQ - 14 - e[i] - e[j]);  // shift in [10, 54]
    }
    if (used[i]) {
      // Levenberg-Marquardt / Tikhonov: diag *= (1 + 2^-10).
      m[i][i] = m[i][i] + detail::shift_round(m[i][i], kTdLambdaShift);
      m[kN][i] = Int128(g[i]).shl(kQ - 15 - e[i] - f);
    } else {
      m[kN][i] = Int128();
    }
  }
  m[kN][kN] = Int128(dd).shl(kQ - 16 - 2 * f);
  // Symmetric Gaussian elimination of the first kN pivots; the last pivot is then the
  // regularised distance s - g^T (G + lambda diag G)^-1 g (scaled).
  for (int k = 0; k < kN; ++k) {
    const Int128 p = m[k][k];
    SEQSLAM_ASSERT(p > Int128(0));
    const Int128 inv = Int128(1).shl(kQ + kInvQ).div(p);  // Q.50
    Int128 mult[kA];
    for (int i = k + 1; i < kA; ++i)
      mult[i] = detail::shift_round(m[i][k] * inv, kInvQ);  // Q.56
    for (int i = k + 1; i < kA; ++i)
      for (int j = k + 1; j <= i; ++j)
        m[i][j] = m[i][j] - detail::shift_round(mult[i] * m[j][k], kQ);
  }
  Int128 td = m[kN][kN];
  if (td.negative()) td = Int128();
  int64_t td_raw = detail::shift_round(td, kQ - 16 - 2 * f).low64_signed();
  if (td_raw > dd) td_raw = dd;
  out.squared = Q47_16::from_raw(td_raw);
  const uint64_t mean = static_cast<uint64_t>(div_round(td_raw, static_cast<int64_t>(n)));
  out.rms = UQ8_8::from_raw(static_cast<uint16_t>(isqrt64(mean)));
  return out;
}

}  // namespace seqslam
