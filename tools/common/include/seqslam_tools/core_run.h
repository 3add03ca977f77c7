// Runs the fixed-point localiser (the firmware's code) over a library and a query image
// sequence on the PC: teach every library image, then localise each query image in order.
// Shared by seqslam-demo and the simulator's evaluation so both measure the same thing.
// run_core() searches the whole library every step (the PC's reference); run_route() runs the
// route search exactly as the head board's firmware configures it (firmware/app: its storage,
// its query history capacity), for `seqslam run` / `eval --search route`.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "seqslam/localiser.h"
#include "seqslam/storage/run_config.h"
#include "seqslam_tools/image_io.h"
#include "seqslam_tools/outcome.h"
#include "seqslam_tools/pr_metrics.h"

namespace seqslam::tools {

// Largest library and sequence length the host runs support.
inline constexpr uint32_t kCoreRunMaxPlaces = 4000;
inline constexpr uint16_t kCoreRunMaxSeq = 100;

struct CoreMatch {
  int32_t place = -1;       // best library place; -1 until a full sequence exists
  double confidence = 1.0;  // best / runner-up sequence cost (smaller = surer)
  bool localised = false;   // confidence below the configured threshold
};

// The run configuration of a localiser configuration: repeat mode on every frame (the
// library is taught, then every query image is a place of the run), the image size as a plain
// reduction.
storage::RunConfig repeat_config(const LocaliserConfig& config);

// All images must be config.image_size. Errors: invalid configuration (named), too many
// library images, a core failure (status named).
Outcome<std::vector<CoreMatch>> run_core(const std::vector<GrayImage>& library,
                                         const std::vector<GrayImage>& queries,
                                         const LocaliserConfig& config);

// The head board firmware's capacities for the route search (firmware/app/app.h), which
// run_route() uses: a configuration above them is refused, as the firmware refuses it.
struct RouteCapacity {
  uint16_t max_seq_len;       // S (profile::kMaxSeqLen)
  uint16_t max_scan_seq_len;  // the scan's sequence, min(route.scan_seq_len, S)
  uint16_t max_norm_window;   // W
  uint16_t max_exclusion;     // R
  uint16_t window_slots;      // route.window
  uint32_t query_steps;       // the query history's steps (profile::kQuerySteps)
};
RouteCapacity route_capacity();

// Why the firmware's route search cannot run `config` ("" when it can): a matcher other than
// the diagonal one, or what the firmware's own check (storage::check_run_config with
// profile::kRunLimits) refuses for it in teach and repeat mode: max_shift > 0, settings above
// route_capacity(). Messages name the setting, its value and the limit. Does not repeat
// check_localiser_config (run_route() does both).
std::string route_search_refusal(const LocaliserConfig& config);

struct RouteRunOptions {
  // Keep the library's per-place metadata (poses and pixel sums) in RAM, as the PC's full
  // search does; false: none, as the head board (the sums are computed as images stream).
  // The results are the same either way (tested).
  bool library_ram = false;
};

struct RouteCoreMatch {
  Match match;         // the Localiser's answer (place -1: none; localised: the board's decision)
  RouteStepInfo info;  // what the route search did at this step (Localiser::route_step())
};

// The route search over `library` and `queries` (raw images of config.image_size): a
// Localiser configured with the RouteSearch overload on profile::RouteStorage and a
// RamQueryHistory of profile::kQuerySteps steps (the firmware keeps the same images on the card),
// config.route as given (route.start: a library position or -1), one localise() per query.
// Errors: an invalid configuration or one the firmware refuses (named), an empty library,
// an image of another size, a core failure (status named).
Outcome<std::vector<RouteCoreMatch>> run_route(const std::vector<GrayImage>& library,
                                               const std::vector<GrayImage>& queries,
                                               const LocaliserConfig& config,
                                               const RouteRunOptions& options = {});

// Precision/recall of `matches` against ground truth `is_correct(query, place)`. Queries
// without a candidate (place < 0: no full sequence yet) are not records. The recall
// denominator is the number of queries that have a candidate and, when `has_match` is given,
// a correct place to find at all (novel places cannot be recalled).
template <typename IsCorrect, typename HasMatch>
PrSummary score_matches(const std::vector<CoreMatch>& matches, IsCorrect is_correct,
                        HasMatch has_match) {
  std::vector<MatchRecord> records;
  size_t denominator = 0;
  for (size_t q = 0; q < matches.size(); ++q) {
    if (matches[q].place < 0) continue;
    MatchRecord r;
    r.query = static_cast<uint32_t>(q);
    r.reference = matches[q].place;
    r.confidence = matches[q].confidence;
    r.correct = is_correct(r.query, static_cast<uint32_t>(matches[q].place));
    records.push_back(r);
    if (has_match(r.query)) ++denominator;
  }
  return evaluate_pr(records, denominator);
}

}  // namespace seqslam::tools
