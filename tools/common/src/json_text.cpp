#include "seqslam_tools/json_text.h"

#include <cmath>
#include <cstdio>
#include <cstdlib>

namespace seqslam::tools {

namespace {

using Json = nlohmann::ordered_json;

std::string number_text(const Json& v, JsonNumbers numbers) {
  if (!v.is_number_float() || numbers == JsonNumbers::kShortest) return v.dump();
  const double d = v.get<double>();
  if (!std::isfinite(d)) return "null";
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.6g", d);
  return buf;
}

// A value on one line: objects as {"key": value, ...}, arrays as [value, ...].
std::string inline_text(const Json& v, JsonNumbers numbers) {
  if (v.is_object()) {
    std::string s = "{";
    bool first = true;
    for (auto it = v.begin(); it != v.end(); ++it) {
      s += (first ? "" : ", ") + Json(it.key()).dump() + ": " + inline_text(it.value(), numbers);
      first = false;
    }
    return s + "}";
  }
  if (v.is_array()) {
    std::string s = "[";
    for (size_t i = 0; i < v.size(); ++i)
      s += (i ? ", " : "") + inline_text(v[i], numbers);
    return s + "]";
  }
  if (v.is_number()) return number_text(v, numbers);
  return v.dump(-1, ' ', false, Json::error_handler_t::replace);
}

// A top-level member's value: an array of objects one element a line, anything else inline.
std::string member_text(const Json& v, JsonNumbers numbers) {
  if (!v.is_array() || v.empty() || !v[0].is_object()) return inline_text(v, numbers);
  std::string s = "[";
  for (size_t i = 0; i < v.size(); ++i)
    s += (i ? ",\n    " : "\n    ") + inline_text(v[i], numbers);
  return s + "\n  ]";
}

}  // namespace

std::string json_text(const Json& doc, JsonNumbers numbers) {
  if (!doc.is_object()) return inline_text(doc, numbers) + "\n";
  std::string s = "{";
  bool first = true;
  for (auto it = doc.begin(); it != doc.end(); ++it) {
    s += (first ? "\n  " : ",\n  ") + Json(it.key()).dump() + ": " +
         member_text(it.value(), numbers);
    first = false;
  }
  return s + "\n}\n";
}

double json_decimal(const std::string& text) {
  return std::strtod(text.c_str(), nullptr);
}

}  // namespace seqslam::tools
