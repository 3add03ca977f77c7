#include "seqslam_tools/ground_truth.h"

#include <algorithm>
#include <string>
#include <utility>
#include <vector>

#include "file_util.h"

namespace seqslam::tools {
namespace {

constexpr uint64_t kMaxGroundTruthBytes = uint64_t{256} << 20;
constexpr std::string_view kHeaderQuery = "query_index";
constexpr std::string_view kHeaderMatches = "matching_reference_indices";

// Parses an unsigned decimal uint32. On failure returns false and a reason.
bool parse_u32(std::string_view token, const char* what, uint32_t* out, std::string* error) {
  const std::string shown = "'" + detail::printable(token, 30) + "'";
  if (token.empty()) {
    *error = std::string(what) + " is empty";
    return false;
  }
  if (token.front() == '-' && token.size() > 1 && detail::is_digit(token[1])) {
    *error = std::string(what) + " " + shown + " is negative";
    return false;
  }
  uint64_t value = 0;
  for (const char c : token) {
    if (!detail::is_digit(c)) {
      *error = std::string(what) + " " + shown + " is not a non-negative decimal integer";
      return false;
    }
    value = value * 10 + static_cast<uint64_t>(c - '0');
    if (value > 0xffffffffu) {
      *error = std::string(what) + " " + shown + " does not fit in 32 bits";
      return false;
    }
  }
  *out = static_cast<uint32_t>(value);
  return true;
}

}  // namespace

bool GroundTruth::is_correct(uint32_t query, uint32_t reference) const {
  if (query >= matches.size()) return false;
  const std::vector<uint32_t>& refs = matches[query];
  return std::find(refs.begin(), refs.end(), reference) != refs.end();
}

bool GroundTruth::has_match(uint32_t query) const {
  return query < matches.size() && !matches[query].empty();
}

LoadedGroundTruth parse_ground_truth(std::string_view text, const std::string& source_name) {
  // A UTF-8 byte-order mark (spreadsheet exports) is not part of the header.
  if (text.substr(0, 3) == "\xEF\xBB\xBF") text.remove_prefix(3);
  const std::vector<std::string_view> lines = detail::split_lines(text);
  auto where = [&](size_t index) { return source_name + ":" + std::to_string(index + 1) + ": "; };
  const std::string expected_header = std::string(kHeaderQuery) + "," + std::string(kHeaderMatches);

  if (lines.empty() || detail::trim(lines[0]).empty()) {
    return Error{where(0) + "missing header; expected '" + expected_header + "'"};
  }
  {
    const std::string_view header = detail::trim(lines[0]);
    const size_t comma = header.find(',');
    const bool good = comma != std::string_view::npos &&
                      detail::trim(header.substr(0, comma)) == kHeaderQuery &&
                      detail::trim(header.substr(comma + 1)) == kHeaderMatches;
    if (!good) {
      return Error{where(0) + "bad header '" + detail::printable(header) + "'; expected '" +
                   expected_header + "'"};
    }
  }

  GroundTruth truth;
  std::vector<size_t> defined_on_line;  // by query: 0 = not yet seen, else 1-based line
  for (size_t i = 1; i < lines.size(); ++i) {
    const std::string_view line = detail::trim(lines[i]);
    if (line.empty()) continue;
    const size_t fields = static_cast<size_t>(std::count(line.begin(), line.end(), ',')) + 1;
    if (fields != 2) {
      return Error{where(i) + "expected 2 comma-separated fields (query index, reference " +
                   "indices), found " + std::to_string(fields)};
    }
    const size_t comma = line.find(',');
    std::string error;
    uint32_t query = 0;
    if (!parse_u32(detail::trim(line.substr(0, comma)), "query index", &query, &error)) {
      return Error{where(i) + error};
    }
    if (query > kMaxGroundTruthQuery) {
      return Error{where(i) + "query index " + std::to_string(query) + " is absurd (more than " +
                   std::to_string(kMaxGroundTruthQuery) + ")"};
    }
    if (query < defined_on_line.size() && defined_on_line[query] != 0) {
      return Error{where(i) + "duplicate query index " + std::to_string(query) +
                   " (first given on line " + std::to_string(defined_on_line[query]) + ")"};
    }

    std::vector<uint32_t> refs;
    std::string_view rest = line.substr(comma + 1);
    while (!rest.empty()) {
      size_t start = 0;
      while (start < rest.size() && detail::is_space(rest[start]))
        ++start;
      size_t end = start;
      while (end < rest.size() && !detail::is_space(rest[end]))
        ++end;
      if (end > start) {
        uint32_t ref = 0;
        if (!parse_u32(rest.substr(start, end - start), "reference index", &ref, &error)) {
          return Error{where(i) + error};
        }
        refs.push_back(ref);
      }
      rest.remove_prefix(end);
    }
    std::sort(refs.begin(), refs.end());
    refs.erase(std::unique(refs.begin(), refs.end()), refs.end());

    if (query >= truth.matches.size()) {
      truth.matches.resize(size_t{query} + 1);
      defined_on_line.resize(size_t{query} + 1, 0);
    }
    truth.matches[query] = std::move(refs);
    defined_on_line[query] = i + 1;
  }
  return Outcome<GroundTruth>(std::move(truth));
}

LoadedGroundTruth load_ground_truth(const std::string& path) {
  Outcome<std::string> text = detail::read_file_text(path, kMaxGroundTruthBytes);
  if (!text) return Error{text.error()};
  return parse_ground_truth(text.value(), path);
}

GroundTruth identity_ground_truth(size_t queries, size_t references, uint32_t tolerance) {
  GroundTruth truth;
  truth.matches.resize(queries);
  // Reference indices are uint32_t; larger reference counts cannot be named anyway.
  const uint64_t ref_count = std::min<uint64_t>(references, uint64_t{0xffffffffu} + 1);
  for (size_t q = 0; q < queries; ++q) {
    const uint64_t lo = q > tolerance ? q - tolerance : 0;
    const uint64_t hi = std::min<uint64_t>(uint64_t{q} + tolerance + 1, ref_count);  // exclusive
    for (uint64_t r = lo; r < hi; ++r)
      truth.matches[q].push_back(static_cast<uint32_t>(r));
  }
  return truth;
}

}  // namespace seqslam::tools
