// "WxH" sizes in the tools' options (--size 32x16, --grid-size 1600x1600): read one way, by
// every tool (seqslam, seqslam-sim, seqslam-demo), strictly. sscanf("%dx%d") took
// "32x16junk", "+32x16" and " 32x16", and overflowed on long numbers; this does not.
// Header only: seqslam-demo uses it without CLI11.
#pragma once

#include <cstdint>
#include <string>

namespace seqslam::tools {

// Splits "WxH" (or "WXH") into two decimal whole numbers: digits only (no sign, space,
// decimal point or suffix), each 1 to 6 digits, so nothing can overflow. False for anything
// else ("32x16junk", "-1x5", "3.5x2", "x16", "32x"). Ranges and zero are the caller's to
// check (its message names them).
inline bool split_wxh(const std::string& text, uint32_t* w, uint32_t* h) {
  const size_t x = text.find_first_of("xX");
  if (x == std::string::npos) return false;
  const auto number = [&text](size_t from, size_t to, uint32_t* out) {
    if (to <= from || to - from > 6) return false;
    uint32_t v = 0;
    for (size_t i = from; i < to; ++i) {
      const char c = text[i];
      if (c < '0' || c > '9') return false;
      v = v * 10 + static_cast<uint32_t>(c - '0');
    }
    *out = v;
    return true;
  };
  uint32_t a = 0;
  uint32_t b = 0;
  if (!number(0, x, &a) || !number(x + 1, text.size(), &b)) return false;
  *w = a;
  *h = b;
  return true;
}

}  // namespace seqslam::tools
