// The settings' values as text: exact decimals of fixed-point values, image sizes, the
// preprocessing's names, wheel constants (seqslam_tools/setting_text.h).
#include "seqslam_tools/setting_text.h"

#include <cinttypes>
#include <cstdio>
#include <string>
#include <vector>

#include "seqslam/hal/pixel_buffer.h"
#include "seqslam_tools/q_format.h"
#include "seqslam_tools/wxh.h"

namespace seqslam::cli {

namespace {

__extension__ typedef unsigned __int128 U128;
__extension__ typedef __int128 I128;

U128 pow10(unsigned n) {
  U128 p = 1;
  for (unsigned i = 0; i < n; ++i)
    p *= 10;
  return p;
}

// round(mag / 2^shift), ties to even (as printf and most decimal printers round exact
// binary values).
U128 round_shift(U128 mag, unsigned shift) {
  if (shift == 0) return mag;
  U128 q = mag >> shift;
  const U128 r = mag - (q << shift);
  const U128 half = U128{1} << (shift - 1);
  if (r > half || (r == half && (q & 1) != 0)) ++q;
  return q;
}

// round(a / b), ties up.
U128 round_div(U128 a, U128 b) {
  return (a + b / 2) / b;
}

std::string u128_text(U128 v) {
  if (v == 0) return "0";
  std::string s;
  while (v > 0) {
    s.insert(s.begin(), static_cast<char>('0' + static_cast<int>(v % 10)));
    v /= 10;
  }
  return s;
}

// Sign, then scaled / 10^decimals with `decimals` digits after the point.
std::string decimal_text(bool negative, U128 scaled, unsigned decimals) {
  const U128 scale = pow10(decimals);
  std::string out = negative && scaled != 0 ? "-" : "";
  out += u128_text(scaled / scale);
  if (decimals > 0) {
    std::string frac = u128_text(scaled % scale);
    out += '.';
    out += std::string(decimals - frac.size(), '0');
    out += frac;
  }
  return out;
}

std::string format_scaled(I128 num, unsigned shift, unsigned decimals) {
  const bool negative = num < 0;
  const U128 mag = negative ? static_cast<U128>(-num) : static_cast<U128>(num);
  return decimal_text(negative, round_shift(mag * pow10(decimals), shift), decimals);
}

}  // namespace

bool parse_wheel_constants(const std::string& text, OdometryConfig* out) {
  double v[3] = {0, 0, 0};
  char tail = 0;
  if (std::sscanf(text.c_str(), "%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &tail) != 3 ||
      !(v[0] > 0 && v[1] > 0 && v[2] > 0 && v[0] < 16 && v[1] < 16 && v[2] < 100)) {
    return false;
  }
  out->circumference_left = tools::from_double<Q31_32>(v[0]);
  out->circumference_right = tools::from_double<Q31_32>(v[1]);
  out->track_width = tools::from_double<Q31_32>(v[2]);
  return true;
}

std::string wheel_constants_text(const OdometryConfig& c) {
  char buf[96];
  std::snprintf(buf, sizeof buf, "%.9f,%.9f,%.9f", tools::to_double(c.circumference_left),
                tools::to_double(c.circumference_right), tools::to_double(c.track_width));
  return buf;
}

std::string parse_image_size(const std::string& text, uint16_t* width, uint16_t* height) {
  uint32_t w = 0;
  uint32_t h = 0;
  if (!tools::split_wxh(text, &w, &h))
    return "'" + text + "' is not an image size WxH (e.g. 32x16)";
  if (w == 0 || h == 0) return "'" + text + "': width and height must be at least 1 pixel";
  if (static_cast<uint64_t>(w) * h > hal::kPixelBufferCapacity) {
    return "'" + text + "' has " + std::to_string(static_cast<uint64_t>(w) * h) +
           " pixels; the FPGA pixel buffer holds at most " +
           std::to_string(hal::kPixelBufferCapacity) + " (W * H <= 512)";
  }
  *width = static_cast<uint16_t>(w);
  *height = static_cast<uint16_t>(h);
  return {};
}

std::string parse_decimal(const std::string& text, int64_t* num, int64_t* den) {
  size_t i = 0;
  bool negative = false;
  if (i < text.size() && (text[i] == '-' || text[i] == '+')) {
    negative = text[i] == '-';
    ++i;
  }
  int64_t n = 0;
  int64_t d = 1;
  int digits = 0;
  bool point = false;
  for (; i < text.size(); ++i) {
    const char c = text[i];
    if (c == '.' && !point) {
      point = true;
      continue;
    }
    if (c < '0' || c > '9') return "'" + text + "' is not a decimal number";
    if (++digits > 18) return "'" + text + "' has too many digits (at most 18)";
    n = n * 10 + (c - '0');
    if (point) d *= 10;
  }
  if (digits == 0) return "'" + text + "' is not a decimal number";
  *num = negative ? -n : n;
  *den = d;
  return {};
}

namespace {
constexpr int kPreprocessingCount = 7;  // Preprocessing's values 0..6
}  // namespace

std::vector<std::string> preprocessing_names() {
  std::vector<std::string> names;
  names.reserve(kPreprocessingCount);
  for (int i = 0; i < kPreprocessingCount; ++i)
    names.emplace_back(preprocessing_name(static_cast<Preprocessing>(i)));
  return names;
}

bool parse_preprocessing(const std::string& name, Preprocessing* out) {
  for (int i = 0; i < kPreprocessingCount; ++i) {
    if (name == preprocessing_name(static_cast<Preprocessing>(i))) {
      *out = static_cast<Preprocessing>(i);
      return true;
    }
  }
  return false;
}

std::string parse_threshold(const std::string& text, UQ16_16* threshold) {
  int64_t num = 0;
  int64_t den = 1;
  const std::string error = parse_decimal(text, &num, &den);
  if (!error.empty()) return error;
  if (num < 0 || num > den) return "'" + text + "' is not within 0..1";
  *threshold = UQ16_16::from_ratio(num, den);
  return {};
}

std::string parse_route_growth(const std::string& text, UQ8_8* growth) {
  int64_t num = 0;
  int64_t den = 1;
  const std::string error = parse_decimal(text, &num, &den);
  if (!error.empty()) return error;
  // The raw value from_ratio rounds to, without its saturation (num * 256 needs 128 bits).
  const I128 raw = num < 0 ? -1 : (static_cast<I128>(num) * 256 + den / 2) / den;
  if (raw < 0 || raw > UQ8_8::max().raw()) {
    return "'" + text + "' is not within 0.." + shortest_decimal(UQ8_8::max().raw(), 8) +
           " places per place (UQ8.8, steps of 1/256)";
  }
  if (num > 0 && raw == 0) {
    return "'" + text +
           "' is below half the smallest step of UQ8.8 (1/256 = 0.00390625) and would be stored "
           "as 0: give 0 for a search radius that does not grow";
  }
  *growth = UQ8_8::from_ratio(num, den);
  return {};
}

std::string parse_route_start(const std::string& text, int32_t* start) {
  if (text == "unknown") {
    *start = -1;
    return {};
  }
  int64_t num = 0;
  int64_t den = 1;
  const std::string error = parse_decimal(text, &num, &den);
  if (!error.empty() || den != 1 || text.find('.') != std::string::npos) {
    return "'" + text + "' is not a library place (a whole number) or 'unknown'";
  }
  if (num < INT32_MIN || num > INT32_MAX) {
    return "'" + text + "' is out of range (library places are 0..2147483647)";
  }
  *start = static_cast<int32_t>(num);
  return {};
}

std::string fixed_decimal(int64_t raw, unsigned frac_bits, unsigned decimals) {
  return format_scaled(raw, frac_bits, decimals);
}

std::string exact_decimal(int64_t raw, unsigned frac_bits) {
  std::string s = fixed_decimal(raw, frac_bits, frac_bits);
  while (s.find('.') != std::string::npos && (s.back() == '0' || s.back() == '.'))
    s.pop_back();
  return s;
}

std::string shortest_decimal(int64_t raw, unsigned frac_bits) {
  const bool negative = raw < 0;
  const U128 mag = negative ? static_cast<U128>(-static_cast<I128>(raw)) : static_cast<U128>(raw);
  for (unsigned k = 0; k < 18; ++k) {
    const U128 scale = pow10(k);
    const U128 scaled = round_shift(mag * scale, frac_bits);
    // Read back as the library does: round(scaled / 10^k * 2^F).
    if (round_div(scaled << frac_bits, scale) == mag) return decimal_text(negative, scaled, k);
  }
  return fixed_decimal(raw, frac_bits, 18);
}

std::string angle_degrees(uint32_t bam, unsigned decimals) {
  const int32_t signed_bam = static_cast<int32_t>(bam);
  return format_scaled(static_cast<I128>(signed_bam) * 360, 32, decimals);
}

}  // namespace seqslam::cli
