// Ground truth: which reference images are a correct match for each query image.
//
// File format (CSV, as tests/data/corridor/ground_truth.csv):
//   query_index,matching_reference_indices      <- header, required, first line
//   0,0 1 2                                      <- query 0 matches references 0, 1 and 2
//   1,                                           <- query 1 has no correct match
// * Line ends may be LF or CRLF; a UTF-8 byte-order mark before the header is ignored.
// * Whitespace around the header, around each field and around each index is ignored;
//   whitespace-only lines are ignored.
// * Each row has exactly two comma-separated fields. The first is the query index (a decimal
//   number, at most kMaxGroundTruthQuery); the second holds zero or more decimal reference
//   indices separated by spaces or tabs. Numbers are unsigned decimal digits only (no sign) and
//   must fit uint32_t.
// * A query index may appear at most once; rows may come in any order. Queries absent from
//   the file have an empty set, i.e. no reference is correct for them.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include <string>
#include <string_view>
#include <vector>

#include "seqslam_tools/outcome.h"

namespace seqslam::tools {

inline constexpr uint32_t kMaxGroundTruthQuery = 10'000'000;

struct GroundTruth {
  // matches[q] = the correct reference indices for query q, ascending, without duplicates.
  // Size is (largest query index in the file) + 1.
  std::vector<std::vector<uint32_t>> matches;

  // True when `reference` is listed for `query`; false for queries beyond matches.size().
  bool is_correct(uint32_t query, uint32_t reference) const;
  // True when the query has at least one correct reference.
  bool has_match(uint32_t query) const;
};

using LoadedGroundTruth = Outcome<GroundTruth>;

// Reads and parses a ground-truth file. Errors read "path:line: what is wrong".
LoadedGroundTruth load_ground_truth(const std::string& path);

// Parses ground-truth text; `source_name` starts error messages in place of a path.
LoadedGroundTruth parse_ground_truth(std::string_view text, const std::string& source_name);

// Ground truth for two traverses recorded in step: query i matches references
// i - tolerance .. i + tolerance, clipped to [0, references). A query with no reference in
// that range (i >= references + tolerance) gets an empty set. matches.size() == queries.
GroundTruth identity_ground_truth(size_t queries, size_t references, uint32_t tolerance);

}  // namespace seqslam::tools
