// CLI11 validators for the host tools' numeric options (seqslam, seqslam-sim): the range an
// option accepts is written once, shown in --help (the validator's description, e.g.
// "INT:1..100") and named by the error (CLI11 prefixes the option: "--seq-len: '0' is not
// within 1..100"), so the two cannot differ. Header only: the tools that use it build with
// CLI11; the library does not.
//
//   whole(lo, hi)  a whole number in decimal ("-" allowed when lo < 0; no "+", no leading
//                  zeros, no 0x: CLI11 reads "010" as octal 8 and "0x10" as 16), within
//                  [lo, hi]. Give the bounds of the option's destination type or tighter:
//                  nothing is then converted with a wrap.
//   real(lo, hi)   a finite decimal number ("1.5", "-2", "1e-3"; not nan, inf or hexadecimal
//                  floating point) within [lo, hi].
//   finite()       a finite decimal number of any size.
#pragma once

#include <CLI/CLI.hpp>

#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>
#include <type_traits>

namespace seqslam::tools {

namespace cli_numbers_detail {

// The shortest plain decimal that reads back as v (for range descriptions: "0.001", "1000").
inline std::string number_text(double v) {
  char buf[64];
  for (int decimals = 0; decimals <= 17; ++decimals) {
    std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
    if (std::strtod(buf, nullptr) == v) break;
  }
  return buf;
}

// "[-]digits" without a leading zero (except "0" itself) and without "+".
inline bool canonical_whole(const std::string& s) {
  const size_t start = !s.empty() && s[0] == '-' ? 1 : 0;
  if (s.size() == start) return false;
  for (size_t i = start; i < s.size(); ++i) {
    if (s[i] < '0' || s[i] > '9') return false;
  }
  return !(s[start] == '0' && s.size() > start + 1);
}

// A decimal floating-point number: [+-]digits[.digits][(e|E)[+-]digits], at least one digit
// in the mantissa. No nan, inf, hexadecimal or spaces.
inline bool decimal_real(const std::string& s) {
  size_t i = 0;
  const auto digits = [&] {
    const size_t from = i;
    while (i < s.size() && s[i] >= '0' && s[i] <= '9')
      ++i;
    return i - from;
  };
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
  size_t mantissa = digits();
  if (i < s.size() && s[i] == '.') {
    ++i;
    mantissa += digits();
  }
  if (mantissa == 0) return false;
  if (i < s.size() && (s[i] == 'e' || s[i] == 'E')) {
    ++i;
    if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
    if (digits() == 0) return false;
  }
  return i == s.size();
}

}  // namespace cli_numbers_detail

// A whole number within [lo, hi] (see above). T is the option's value type or wider.
template <typename T>
CLI::Validator whole(T lo, T hi) {
  static_assert(std::is_integral<T>::value, "whole() is for integer options");
  const std::string range = std::to_string(lo) + ".." + std::to_string(hi);
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        if (!cli_numbers_detail::canonical_whole(text)) {
          return "'" + text + "' is not a whole number within " + range +
                 " (decimal digits, no leading zeros)";
        }
        bool in_range = false;
        errno = 0;
        if (text[0] != '-') {
          const unsigned long long v = std::strtoull(text.c_str(), nullptr, 10);
          if constexpr (std::is_signed<T>::value) {
            in_range = errno == 0 && hi >= 0 && v <= static_cast<unsigned long long>(hi) &&
                       (lo < 0 || v >= static_cast<unsigned long long>(lo));
          } else {
            in_range = errno == 0 && v >= lo && v <= hi;
          }
        } else if constexpr (std::is_signed<T>::value) {
          const long long v = std::strtoll(text.c_str(), nullptr, 10);
          in_range = errno == 0 && v >= lo && v <= hi;
        }
        return in_range ? std::string() : "'" + text + "' is not within " + range;
      },
      range);
}

// The whole range of the option's type T (e.g. whole_of<uint64_t>() for a seed).
template <typename T>
CLI::Validator whole_of() {
  return whole<T>(std::numeric_limits<T>::min(), std::numeric_limits<T>::max());
}

// A finite decimal number within [lo, hi] (see above).
inline CLI::Validator real(double lo, double hi) {
  const std::string range =
      cli_numbers_detail::number_text(lo) + ".." + cli_numbers_detail::number_text(hi);
  return CLI::Validator(
      [lo, hi, range](std::string& text) -> std::string {
        if (!cli_numbers_detail::decimal_real(text)) {
          return "'" + text + "' is not a finite decimal number within " + range;
        }
        const double v = std::strtod(text.c_str(), nullptr);
        if (!std::isfinite(v) || v < lo || v > hi) return "'" + text + "' is not within " + range;
        return {};
      },
      range);
}

// A finite decimal number (no nan or inf), any size a double holds.
inline CLI::Validator finite() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        if (!cli_numbers_detail::decimal_real(text) ||
            !std::isfinite(std::strtod(text.c_str(), nullptr))) {
          return "'" + text + "' is not a finite decimal number";
        }
        return {};
      },
      "finite");
}

}  // namespace seqslam::tools
