// A self-contained HTML report of an evaluation (the successor of the 2015 thesis's
// DreamViewer): what was run, how well, and where and why the matcher fails
// (docs/seqslam_report.md).
//
// The page works offline: CSS and the self-test script are inline, images are PNG data URIs
// (stb_image_write), charts are inline SVG generated here. Sections, in order (element ids):
//   sec-summary       inputs, configuration, metrics and timing of every run;
//   sec-matrices      runs[0]'s difference matrix and sequence-cost matrix as heat maps
//                     (viridis, dark = similar / cheap; NaN costs grey), library across, query
//                     down, with runs[0]'s matches and, given options.truth, the correct places;
//   sec-pr            PR curves of all runs overlaid; precision and recall against the
//                     confidence threshold, the configured thresholds marked;
//   sec-time          per run: library place found against query index, confidence over time;
//   sec-trajectories  true and odometry poses of both inputs (metres, equal axes), runs[0]'s
//                     accepted wrong matches as lines from the query to the matched place;
//   sec-pairs         image pairs of chosen queries: query, match, a correct place.
// Match markers everywhere: filled = accepted (confidence < threshold), ring = not accepted;
// green = correct, red = wrong, orange = no ground truth for the query.
//
// Heat map size: n = max(library, query) places; n > 1000 is reduced by the integer factor
// ceil(n / 1000) (each pixel the minimum of its block, so a matching diagonal survives), a
// smaller matrix is enlarged by floor(640 / n) (at most 16, nearest neighbour), and a side
// that would still be under 120 px is stretched by a further integer factor. Image pairs are
// enlarged by floor(256 / width) (1..16), nearest neighbour.
//
// Opening the page with the fragment #selftest (file:///.../report.html#selftest) runs a check
// in the browser after loading and writes its findings into <pre id="selftest">, ending with
// "selftest: PASS" or "selftest: FAIL" (used by tests/host/report/browser_test.sh).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "seqslam_tools/evaluation.h"
#include "seqslam_tools/ground_truth.h"
#include "seqslam_tools/outcome.h"

namespace seqslam::tools {

// One evaluation to show; several are overlaid (e.g. preprocessing none / HE / PN on the same
// inputs). All runs must have the same library and query sizes.
struct ReportRun {
  std::string label;  // e.g. "he"; escaped in the page
  const EvalResult* result = nullptr;
};

struct ReportOptions {
  std::string title;  // "" = "SeqSLAM evaluation"
  // Queries (positions in the query input) whose image pairs to show. Empty: chosen from
  // runs[0]: the most and the least confident match, a few correct (spread over the run), the
  // most confident wrong ones, a few not accepted. Positions beyond the input are listed as
  // skipped.
  std::vector<uint32_t> pair_queries;
  // The full ground truth (positions in the ranged inputs, as resolve_ground_truth returns),
  // optional: draws every correct place on the matrices and the match chart and shows a correct
  // library image next to wrong matches. Without it only each match's correct/wrong status
  // (QueryResult::has_truth / correct) is shown.
  const GroundTruth* truth = nullptr;
};

// The whole HTML document (UTF-8). runs[0] must hold the matrices (EvalConfig::keep_matrices:
// differences and sequence_costs of query_size x library_size). Errors: no runs, a null result,
// runs[0] without matrices, runs of different sizes, inputs whose image counts differ from
// the runs' sizes.
Outcome<std::string> render_report(const std::vector<ReportRun>& runs, const InputSequence& library,
                                   const InputSequence& query, const ReportOptions& options);

// Writes `html` to `path`; false and a message naming the file on failure.
bool write_report(const std::string& path, const std::string& html, std::string* error);

}  // namespace seqslam::tools
