#include "seqslam_tools/settings_cli.h"

#include <cstdint>
#include <string>

#include "seqslam_tools/setting_text.h"
#include "seqslam_tools/wxh.h"

namespace seqslam::cli {

namespace {

__extension__ typedef __int128 I128;

using storage::Setting;
using storage::SettingFormat;

I128 pow2(unsigned bits) {
  return static_cast<I128>(1) << bits;
}

// num / den rounded to the nearest integer, ties away from zero (as Fixed::from_ratio).
I128 round_ratio(I128 num, I128 den) {
  return num < 0 ? -((-num + den / 2) / den) : (num + den / 2) / den;
}

std::string range_text(const Setting& s, const std::string& lo, const std::string& hi) {
  return lo + ".." + hi + (s.unit != nullptr ? std::string(" ") + s.unit : std::string());
}

// Decimal digits with an optional '-', no leading zeros (so "010" is not read as 10, nor as
// octal 8).
bool canonical_whole(const std::string& text) {
  const size_t start = !text.empty() && text[0] == '-' ? 1 : 0;
  if (text.size() == start) return false;
  for (size_t i = start; i < text.size(); ++i) {
    if (text[i] < '0' || text[i] > '9') return false;
  }
  return text[start] != '0' || text.size() == start + 1;
}

// A whole number within [s.min, s.max].
std::string parse_whole(const std::string& text, const Setting& s, int64_t* out) {
  int64_t num = 0;
  int64_t den = 1;
  const std::string range = range_text(s, std::to_string(s.min), std::to_string(s.max));
  if (!canonical_whole(text) || !parse_decimal(text, &num, &den).empty() || den != 1) {
    return "'" + text + "' is not a whole number within " + range +
           " (decimal digits, no leading zeros)";
  }
  if (num < s.min || num > s.max) return "'" + text + "' is not within " + range;
  *out = num;
  return {};
}

template <typename T>
std::string parse_unsigned(const std::string& text, const Setting& s, T* out) {
  int64_t v = 0;
  std::string error = parse_whole(text, s, &v);
  if (error.empty()) *out = static_cast<T>(v);
  return error;
}

// The value of a name among s.names (an enum), or -1.
int name_index(const std::string& text, const Setting& s) {
  for (uint8_t i = 0; i < s.name_count; ++i) {
    if (text == s.names[i]) return i;
  }
  return -1;
}

std::string names_text(const Setting& s, const char* separator) {
  std::string out;
  for (uint8_t i = 0; i < s.name_count; ++i) {
    if (i > 0) out += separator;
    out += s.names[i];
  }
  return out;
}

std::string parse_name(const std::string& text, const Setting& s, uint8_t* out) {
  const int i = name_index(text, s);
  if (i < 0 || i < s.min || i > s.max) {
    return "'" + text + "' is not one of " + names_text(s, ", ");
  }
  *out = static_cast<uint8_t>(i);
  return {};
}

// Bit names separated by commas; an empty set is refused (the range's minimum is 1).
std::string parse_flags(const std::string& text, const Setting& s, uint8_t* out) {
  uint8_t bits = 0;
  size_t start = 0;
  while (start <= text.size()) {
    const size_t comma = text.find(',', start);
    const std::string name =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    const int i = name_index(name, s);
    if (i < 0) return "'" + name + "' is not one of " + names_text(s, ", ");
    bits = static_cast<uint8_t>(bits | (1u << i));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (bits < s.min) return "give at least one of " + names_text(s, ", ");
  *out = bits;
  return {};
}

std::string flags_text(uint8_t bits, const Setting& s) {
  std::string out;
  for (uint8_t i = 0; i < s.name_count; ++i) {
    if ((bits & (1u << i)) == 0) continue;
    if (!out.empty()) out += ',';
    out += s.names[i];
  }
  return out.empty() ? "(none)" : out;
}

// "X,Y" in metres to whole millimetres, each within [s.min, s.max] mm.
std::string parse_millimetres(const std::string& text, const Setting& s, int32_t* out) {
  int64_t num = 0;
  int64_t den = 1;
  const std::string error = parse_decimal(text, &num, &den);
  if (!error.empty()) return error;
  const I128 scaled = static_cast<I128>(num) * 1000;
  if (scaled % den != 0) return "'" + text + "' is finer than a millimetre";
  const I128 mm = scaled / den;
  if (mm < s.min || mm > s.max) return "'" + text + "' is out of range";
  *out = static_cast<int32_t>(mm);
  return {};
}

std::string metres_text(int32_t mm) {
  const std::string sign = mm < 0 ? "-" : "";
  const int64_t a = mm < 0 ? -static_cast<int64_t>(mm) : mm;
  std::string frac = std::to_string(a % 1000);
  frac = std::string(3 - frac.size(), '0') + frac;
  while (!frac.empty() && frac.back() == '0')
    frac.pop_back();
  return sign + std::to_string(a / 1000) + (frac.empty() ? "" : "." + frac);
}

}  // namespace

namespace setting_text {

std::string fixed_range_text(const Setting& s, unsigned frac_bits) {
  // A range that starts at the smallest step above 0 reads "above 0".
  return s.min == 1 ? "above 0 and at most " + fixed_text(s.max, frac_bits) +
                          (s.unit != nullptr ? std::string(" ") + s.unit : std::string())
                    : range_text(s, fixed_text(s.min, frac_bits), fixed_text(s.max, frac_bits));
}

std::string parse_fixed(const std::string& text, const Setting& s, unsigned frac_bits,
                        const char* format, int64_t* raw) {
  int64_t num = 0;
  int64_t den = 1;
  const std::string range = fixed_range_text(s, frac_bits);
  if (const std::string e = parse_decimal(text, &num, &den); !e.empty()) {
    return e + " (" + range + ")";
  }
  const I128 v = round_ratio(static_cast<I128>(num) * pow2(frac_bits), den);
  if (v < s.min || v > s.max) {
    return "'" + text + "' is not " + (s.min == 1 ? "" : "within ") + range + " (" + format +
           ", steps of 1/" + std::to_string(uint64_t{1} << frac_bits) + ")";
  }
  if (v == 0 && num != 0) {
    return "'" + text + "' is below half the smallest step of " + format + " (1/" +
           std::to_string(uint64_t{1} << frac_bits) + " = " + fixed_decimal(1, frac_bits, frac_bits) +
           ") and would be stored as 0";
  }
  *raw = static_cast<int64_t>(v);
  return {};
}

std::string fixed_text(int64_t raw, unsigned frac_bits) {
  return shortest_decimal(raw, frac_bits);
}

std::string parse(const std::string& text, const Setting& s, uint8_t* out) {
  if (s.format == SettingFormat::kFlags) return parse_flags(text, s, out);
  return parse_unsigned(text, s, out);
}
std::string parse(const std::string& text, const Setting&, bool* out) {
  if (text != "yes" && text != "no") return "'" + text + "' is not yes or no";
  *out = text == "yes";
  return {};
}
std::string parse(const std::string& text, const Setting& s, uint16_t* out) {
  return parse_unsigned(text, s, out);
}
std::string parse(const std::string& text, const Setting& s, uint32_t* out) {
  return parse_unsigned(text, s, out);
}
std::string parse(const std::string& text, const Setting& s, int32_t* out) {
  if (s.format == SettingFormat::kPlace && (text == "unknown" || text == "-1")) {
    *out = -1;
    return {};
  }
  int64_t v = 0;
  Setting places = s;
  if (s.format == SettingFormat::kPlace) places.min = 0;
  std::string error = parse_whole(text, places, &v);
  if (!error.empty() && s.format == SettingFormat::kPlace) {
    return "'" + text + "' is not a library place (a whole number within 0.." +
           std::to_string(s.max) + ") or 'unknown'";
  }
  if (error.empty()) *out = static_cast<int32_t>(v);
  return error;
}

// Degrees, rounded to a binary angle (2^32 a turn) as Angle::from_degrees rounds, within
// [s.min, s.max] before any wrap.
std::string parse(const std::string& text, const Setting& s, Angle* out) {
  int64_t num = 0;
  int64_t den = 1;
  const std::string range = range_text(s, text_of_degrees(static_cast<uint32_t>(s.min)),
                                       text_of_degrees(static_cast<uint32_t>(s.max)));
  if (const std::string e = parse_decimal(text, &num, &den); !e.empty()) {
    return e + " (" + range + ")";
  }
  const I128 bam = round_ratio(static_cast<I128>(num) * pow2(32), static_cast<I128>(den) * 360);
  if (bam < s.min || bam > s.max) return "'" + text + "' is not within " + range;
  if (bam == 0 && num != 0) return "'" + text + "' is below the smallest angle step";
  *out = Angle{static_cast<uint32_t>(bam)};
  return {};
}

std::string text_of_degrees(uint32_t bam) {
  // The shortest decimal that reads back as the same binary angle.
  // bam / 2^32 of a turn as degrees in [0, 360): fixed_decimal of bam * 360 with 32 bits.
  const int64_t scaled = static_cast<int64_t>(bam) * 360;
  for (unsigned decimals = 0; decimals < 12; ++decimals) {
    std::string t = fixed_decimal(scaled, 32, decimals);
    while (t.find('.') != std::string::npos && (t.back() == '0' || t.back() == '.'))
      t.pop_back();
    int64_t num = 0;
    int64_t den = 1;
    if (!parse_decimal(t, &num, &den).empty()) continue;
    const I128 back =
        round_ratio(static_cast<I128>(num) * pow2(32), static_cast<I128>(den) * 360);
    if (static_cast<uint32_t>(back) == bam) return t;
  }
  return fixed_decimal(scaled, 32, 12);
}

std::string parse(const std::string& text, const Setting& s, storage::TriggerMode* out) {
  uint8_t v = 0;
  std::string error = parse_name(text, s, &v);
  if (error.empty()) *out = static_cast<storage::TriggerMode>(v);
  return error;
}
std::string parse(const std::string& text, const Setting& s, LocaliserMatcher* out) {
  uint8_t v = 0;
  std::string error = parse_name(text, s, &v);
  if (error.empty()) *out = static_cast<LocaliserMatcher>(v);
  return error;
}
std::string parse(const std::string& text, const Setting&, hal::PipelineMapping* out) {
  uint16_t w = 0;
  uint16_t h = 0;
  std::string error = parse_image_size(text, &w, &h);
  if (error.empty()) *out = hal::PipelineMapping::reduction(w, h);
  return error;
}
std::string parse(const std::string& text, const Setting&, PreprocessConfig* out) {
  Preprocessing p = Preprocessing::kNone;
  if (!parse_preprocessing(text, &p)) {
    std::string names;
    for (const std::string& n : preprocessing_names())
      names += (names.empty() ? "" : ", ") + n;
    return "'" + text + "' is not one of " + names;
  }
  out->method = p;
  return {};
}
std::string parse(const std::string& text, const Setting&, OdometryConfig* out) {
  OdometryConfig c = *out;
  if (!parse_wheel_constants(text, &c)) {
    return "'" + text +
           "': wants LEFT,RIGHT,TRACK in metres: circumferences above 0 and below 16, the "
           "track above 0 and below 100 (e.g. what seqslam slam --calibration-out wrote)";
  }
  *out = c;
  return {};
}
std::string parse(const std::string& text, const Setting& s, storage::MapOrigin* out) {
  const size_t comma = text.find(',');
  if (comma == std::string::npos) return "'" + text + "' is not X,Y in metres";
  storage::MapOrigin o;
  std::string error = parse_millimetres(text.substr(0, comma), s, &o.x_mm);
  if (error.empty()) error = parse_millimetres(text.substr(comma + 1), s, &o.y_mm);
  if (error.empty()) *out = o;
  return error;
}
std::string parse(const std::string& text, const Setting& s, storage::MapSize* out) {
  uint32_t a = 0;
  uint32_t b = 0;
  if (!tools::split_wxh(text, &a, &b) || a < s.min || b < s.min || a > s.max || b > s.max) {
    return "'" + text + "' is not WxH cells, each " + std::to_string(s.min) + ".." +
           std::to_string(s.max);
  }
  out->width = static_cast<uint16_t>(a);
  out->height = static_cast<uint16_t>(b);
  return {};
}

std::string text(uint8_t v, const Setting& s) {
  if (s.format == SettingFormat::kFlags) return flags_text(v, s);
  return std::to_string(v);
}
std::string text(uint16_t v, const Setting&) {
  return std::to_string(v);
}
std::string text(uint32_t v, const Setting&) {
  return std::to_string(v);
}
std::string text(int32_t v, const Setting& s) {
  if (s.format == SettingFormat::kPlace && v == -1) return "unknown";
  return std::to_string(v);
}
std::string text(bool v, const Setting&) {
  return v ? "yes" : "no";
}
std::string text(Angle v, const Setting&) {
  return text_of_degrees(v.bam);
}
std::string text(storage::TriggerMode v, const Setting& s) {
  const auto i = static_cast<uint8_t>(v);
  return i < s.name_count ? s.names[i] : std::to_string(i);
}
std::string text(LocaliserMatcher v, const Setting& s) {
  const auto i = static_cast<uint8_t>(v);
  return i < s.name_count ? s.names[i] : std::to_string(i);
}
std::string text(const hal::PipelineMapping& v, const Setting&) {
  return std::to_string(v.xmax) + "x" + std::to_string(v.ymax);
}
std::string text(const PreprocessConfig& v, const Setting&) {
  return preprocessing_name(v.method);
}
std::string text(const OdometryConfig& v, const Setting&) {
  return shortest_decimal(v.circumference_left.raw(), 32) + "," +
         shortest_decimal(v.circumference_right.raw(), 32) + "," +
         shortest_decimal(v.track_width.raw(), 32);
}
std::string text(const storage::MapOrigin& v, const Setting&) {
  return metres_text(v.x_mm) + "," + metres_text(v.y_mm);
}
std::string text(const storage::MapSize& v, const Setting&) {
  return std::to_string(v.width) + "x" + std::to_string(v.height);
}

bool expressible(const hal::PipelineMapping& v) {
  return v == hal::PipelineMapping::reduction(v.xmax, v.ymax);
}
bool expressible(const PreprocessConfig& v) {
  const PatchNormConfig& p = v.patch;
  const PatchNormConfig d;
  return p.patch_width == d.patch_width && p.patch_height == d.patch_height &&
         p.epsilon == d.epsilon && p.gain == d.gain;
}
bool expressible(const OdometryConfig& v) {
  const OdometryConfig d;
  return v.ticks_per_revolution == d.ticks_per_revolution && v.counter_bits == d.counter_bits &&
         v.max_ticks_per_update == d.max_ticks_per_update;
}

std::string whole_range_text(const Setting& s) {
  if (s.format == SettingFormat::kPlace) return "PLACE|unknown";
  return std::to_string(s.min) + ".." + std::to_string(s.max);
}

std::string names_range_text(const Setting& s) {
  return names_text(s, "|");
}

const char* type_name(const Setting& s, const char* fallback) {
  if (s.format == SettingFormat::kFlags) return "NAME,...";
  if (s.format == SettingFormat::kPlace) return "PLACE|unknown";
  if (s.name_count > 0) return "NAME";
  return fallback;
}

}  // namespace setting_text

std::string unused_note(uint16_t scope, const storage::RunConfig& c) {
  using namespace storage;
  const bool explore = (c.modes & kModeExplore) != 0;
  const bool repeat = (c.modes & kModeRepeat) != 0;
  const bool teach = (c.modes & kModeTeach) != 0;
  if ((scope & kScopeHeuristic) != 0 && c.matcher != LocaliserMatcher::kHeuristic) {
    return "(not used: matcher " + std::string(kMatcherNames[static_cast<uint8_t>(c.matcher) % 3]) +
           ")";
  }
  if ((scope & kScopeRoute) != 0) {
    if (explore) return "(not used: explore runs the full search)";
    if (c.matcher != LocaliserMatcher::kDiagonal) return "(not used: not the diagonal matcher)";
    if (!repeat) return "(not used: no repeat mode)";
  }
  if ((scope & (kScopeMap | kScopeExplore)) != 0 && !explore) return "(not used: explore only)";
  if ((scope & kScopeLoop) != 0 && !(teach && repeat)) {
    return "(not used: loop closure is teach + repeat or explore)";
  }
  return {};
}

}  // namespace seqslam::cli
