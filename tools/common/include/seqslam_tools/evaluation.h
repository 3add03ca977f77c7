// Offline evaluation of the localiser on a library and a query sequence: the engine behind
// `seqslam run`, `eval`, `sweep` and `report` (docs/seqslam_eval.md).
//
// Inputs are dream recordings, image directories or index files, optionally cut to a range.
// The evaluation runs the firmware's fixed-point core: every image is preprocessed by the
// core, the difference matrix (query x library, raw SAD as the core computes it) is filled
// in parallel by the core's difference kernel, and the core's DiagonalMatcher then takes one
// step per query, exactly as Localiser::localise would (tested equal). The matrix can be
// cached on disk and re-used for other matcher settings, as DreamViewer did.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "seqslam/heuristic_matcher.h"
#include "seqslam/localiser.h"
#include "seqslam/slope_matcher.h"
#include "seqslam_tools/ground_truth.h"
#include "seqslam_tools/image_io.h"
#include "seqslam_tools/outcome.h"
#include "seqslam_tools/pr_metrics.h"

namespace seqslam::tools {

// A half-open index range [first, last) of a sequence; last < 0 means "to the end".
struct IndexRange {
  int64_t first = 0;
  int64_t last = -1;
  bool whole() const { return first == 0 && last < 0; }
};
// Parses "a:b", "a:" or ":b" (decimal, a < b). Errors name the flag text.
Outcome<IndexRange> parse_index_range(const std::string& text);

struct PoseD {
  double x = 0.0;
  double y = 0.0;
  double heading = 0.0;  // radians
};

struct InputSequence {
  std::string source;              // the path as given
  std::string kind;                // "dream", "directory" or "index"
  std::vector<GrayImage> images;   // all of the evaluation size
  std::vector<std::string> names;  // image file, or "place N" for dream recordings
  uint32_t offset = 0;             // index in the source of images[0] (the range's start)
  uint32_t source_size = 0;        // images in the whole source
  std::vector<PoseD> truth;        // true poses (simulated dream recordings), else empty
  std::vector<PoseD> odometry;     // odometry poses (full dream recordings), else empty
};

// Loads `path` (a dream recording, a directory of images sorted by name, or an index file
// with one image path per line) cut to `range`, at width x height. Images of other sizes are
// reduced by the pixel pipeline's area-averaging model; a dream recording must already be of
// that size (its images are the robot's, after the FPGA). Errors name the file (and line).
Outcome<InputSequence> load_input(const std::string& path, int width, int height,
                                  const IndexRange& range = {});

// Ground truth for a pair, from a specification:
//   identity:TOL  - query i matches library i-TOL .. i+TOL (indices in the sources);
//   poses:METRES  - library places whose true position lies within METRES of the query's
//                   (and whose heading is within 60 degrees); both inputs need true poses;
//   FILE          - a CSV as tests/data/corridor/ground_truth.csv (source indices).
// The result is indexed by positions in the (ranged) inputs. A CSV naming a query or a
// library index beyond the sources is an error naming the file and the index (syntax errors
// name the line).
Outcome<GroundTruth> resolve_ground_truth(const std::string& spec, const InputSequence& library,
                                          const InputSequence& query);

// The matcher's name as the settings table gives it ("diagonal", "heuristic", "slope"), and
// back (false for anything else).
const char* matcher_name(LocaliserMatcher m);
bool parse_matcher(const std::string& name, LocaliserMatcher* out);

// The image difference: MAD (the core's SAD, the default) or the tangent distance (the
// core's two-sided TD of blurred images with default_td_sigma(), as its per-pixel RMS in SAD
// units: rms * pixels, so the matchers' normalisation and sigma_min keep their meaning).
// kTangentNoScaling ("td-noscale") leaves the scaling tangent out (tangent_distance.h
// TangentSet: for places 20 cm apart it makes neighbours alike).
enum class MetricKind : uint8_t { kMad = 0, kTangent = 1, kTangentNoScaling = 2 };
const char* metric_name(MetricKind m);
bool parse_metric(const std::string& name, MetricKind* out);

struct EvalConfig {
  // The image, preprocessing, max shift, S, W, R, threshold, the matcher (localiser.matcher)
  // and its own settings: the run configuration's (storage/run_config.h), as the session
  // takes them.
  LocaliserConfig localiser{};
  MetricKind metric = MetricKind::kMad;
  // Heuristic only. false: one stream of disjoint sequences, as the firmware runs it; every
  // step reports the anytime best. true: the 2015 thesis's protocol [A 4.3.1]: a fresh run of
  // S steps (reset, greedy scan, trails) for every query q >= S-1 over queries q-S+1..q, whose
  // final answer is recorded at q - the same sequences the diagonal matcher scores at q.
  bool heuristic_every_start = false;
  unsigned threads = 0;        // 0 = all cores
  std::string cache_dir;       // "" = no difference-matrix cache
  bool keep_matrices = false;  // fill EvalResult::differences and sequence_costs (reports)
  // Working memory of evaluate() (see eval_memory()): the difference matrix is computed in
  // bands of band_rows query rows, each consumed by the matcher and overwritten by the next.
  // 0 = automatic: the whole matrix when it is kept (keep_matrices) or cached (cache_dir) and
  // fits max_memory, else the largest band up to kAutoBandRows that fits. A plan over
  // max_memory is refused with the figure it needs. Every plan gives the same results.
  uint32_t band_rows = 0;
  uint64_t max_memory = uint64_t{4} << 30;
};
inline constexpr uint32_t kAutoBandRows = 1024;

struct QueryResult {
  uint32_t query = 0;    // position in the query input
  int32_t library = -1;  // best library position; -1: no full sequence yet
  int32_t runner_up = -1;
  double confidence = 1.0;  // best / runner-up (smaller = surer)
  bool accepted = false;    // confidence < threshold
  bool has_truth = false;   // the ground truth lists a correct place for this query
  bool correct = false;     // library is one of them
};

struct EvalTiming {
  double load_ms = 0.0;
  double preprocess_ms = 0.0;
  double differences_ms = 0.0;
  double match_ms = 0.0;
  double total_ms = 0.0;
  bool matrix_from_cache = false;
};

struct EvalResult {
  EvalConfig config;
  uint32_t library_size = 0;
  uint32_t query_size = 0;
  std::vector<QueryResult> matches;  // one per query
  bool has_ground_truth = false;
  PrSummary summary;  // when has_ground_truth
  // With keep_matrices: query-major query_size x library_size.
  std::vector<uint32_t> differences;  // raw SAD of the preprocessed images
  std::vector<float> sequence_costs;  // the matcher's cost(j) / S in grey levels; NaN = none
  EvalTiming timing;
  uint32_t band_rows = 0;      // query rows per band (query_size: the whole matrix)
  uint64_t planned_bytes = 0;  // eval_memory(...).total() of the plan that ran
};

// What evaluate() holds, in bytes, for L library and Q query images with bands of band_rows
// query rows (band_rows >= Q: the whole matrix):
//   images  = (L + Q) x pixels            preprocessed images (+ (L + Q) x sizeof(TangentImage)
//                                         with a tangent metric)
//   rows    = min(band_rows, Q) x L x 4   the difference rows
//   matcher = S x L x 2 + L x 5 + Q x sizeof(QueryResult)   matcher state and results
//   kept    = Q x L x 8                   keep_matrices (reports): differences and costs
// Not counted: the loaded input images (held by the caller, (L + Q) x source pixels).
struct EvalMemory {
  uint64_t images = 0;
  uint64_t rows = 0;
  uint64_t matcher = 0;
  uint64_t kept = 0;
  uint64_t total() const { return images + rows + matcher + kept; }
};
EvalMemory eval_memory(uint32_t library_size, uint32_t query_size, const EvalConfig& config,
                       uint32_t band_rows);
// The band evaluate() will use (query_size = the whole matrix), or why none fits
// config.max_memory, with the figure it needs.
Outcome<uint32_t> plan_band_rows(uint32_t library_size, uint32_t query_size,
                                 const EvalConfig& config);

// Called as the bands are computed (banded plans only): query rows done so far, and all.
using EvalProgress = std::function<void(uint32_t done, uint32_t total)>;

// Runs the evaluation. `truth` may be null (run without metrics). Errors: bad configuration
// (named), sizes that differ, a library larger than kEvalMaxPlaces.
inline constexpr uint32_t kEvalMaxPlaces = 1u << 20;
Outcome<EvalResult> evaluate(const InputSequence& library, const InputSequence& query,
                             const EvalConfig& config, const GroundTruth* truth,
                             const EvalProgress& progress = {});

// The two halves of evaluate(), for sweeps that re-use one difference matrix across matcher
// settings: difference_matrix() preprocesses and fills the query-major matrix (raw SAD; from
// or into config.cache_dir when set); evaluate_matrix() runs the matcher over it. The matrix
// depends only on the inputs, the image size, the preprocessing and max_shift.
struct DifferenceMatrix {
  uint32_t library_size = 0;
  uint32_t query_size = 0;
  std::vector<uint32_t> values;  // query-major
  EvalTiming timing;             // preprocess_ms, differences_ms, matrix_from_cache
};
Outcome<DifferenceMatrix> difference_matrix(const InputSequence& library,
                                            const InputSequence& query, const EvalConfig& config);
Outcome<EvalResult> evaluate_matrix(const DifferenceMatrix& matrix, const EvalConfig& config,
                                    const GroundTruth* truth);

// The JSON document of `seqslam eval` (schema in docs/seqslam_eval.md). The members of
// `extra` (e.g. the reference comparison, the route search's counts) come before "matches".
std::string eval_json(const EvalResult& r, const InputSequence& library, const InputSequence& query,
                      const nlohmann::ordered_json& extra = nlohmann::ordered_json::object());

}  // namespace seqslam::tools
