#include "seqslam_tools/evaluation.h"

#include "seqslam/storage/run_config.h"
#include "seqslam_tools/core_run.h"
#include "seqslam_tools/host_session.h"
#include "seqslam_tools/json_text.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <limits>
#include <memory>
#include <sstream>
#include <thread>

#include <sys/resource.h>

#include "seqslam/difference.h"
#include "seqslam/preprocess.h"
#include "seqslam/sequence_matcher.h"
#include "seqslam/storage/run_config.h"
#include "seqslam/tangent_distance.h"
#include "seqslam_tools/core_run.h"
#include "seqslam_tools/dataset.h"
#include "seqslam_tools/dream_images.h"
#include "seqslam_tools/host_session.h"
#include "seqslam_tools/output_file.h"
#include "seqslam_tools/parallel.h"
#include "seqslam_tools/q_format.h"
#include "seqslam_tools/reduce.h"
#include "seqslam_tools/sad_simd.h"

namespace seqslam::tools {

namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

constexpr double kPi = 3.14159265358979323846;

double ms_since(Clock::time_point t) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t).count();
}

bool parse_u64(const std::string& s, uint64_t* out) {
  if (s.empty() || s.size() > 18) return false;
  uint64_t v = 0;
  for (const char c : s) {
    if (c < '0' || c > '9') return false;
    v = v * 10 + static_cast<uint64_t>(c - '0');
  }
  *out = v;
  return true;
}

PoseD to_pose_d(const Pose2& p) {
  PoseD d;
  d.x = to_double(p.x);
  d.y = to_double(p.y);
  d.heading = to_radians(p.heading);
  return d;
}

// True when `path` is a file whose first block carries the dream recording's log kind.
bool is_dream_file(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return false;
  char block[64] = {};
  in.read(block, sizeof block);
  const std::string head(block, static_cast<size_t>(in.gcount()));
  return head.find("SQDREAM1") != std::string::npos;
}

// [first, last) of a source of `size` items, or an error naming the flag text.
Outcome<std::pair<uint32_t, uint32_t>> clamp_range(const IndexRange& r, size_t size,
                                                   const std::string& path) {
  const int64_t last = r.last < 0 ? static_cast<int64_t>(size) : r.last;
  if (r.first < 0 || r.first >= static_cast<int64_t>(size) || last > static_cast<int64_t>(size) ||
      last <= r.first) {
    return Error{path + ": range " + std::to_string(r.first) + ":" +
                 (r.last < 0 ? std::string() : std::to_string(r.last)) + " does not fit its " +
                 std::to_string(size) + " images"};
  }
  return std::pair<uint32_t, uint32_t>{static_cast<uint32_t>(r.first), static_cast<uint32_t>(last)};
}

uint64_t fnv1a(uint64_t h, const void* data, size_t n) {
  const auto* p = static_cast<const uint8_t*>(data);
  for (size_t i = 0; i < n; ++i) {
    h ^= p[i];
    h *= 0x100000001B3ull;
  }
  return h;
}

constexpr char kCacheMagic[8] = {'S', 'Q', 'D', 'I', 'F', 'F', '0', '2'};

// The file: this header, then the matrix. `values` (FNV-1a of the matrix bytes) makes a
// damaged file a cache miss instead of wrong results.
struct CacheHeader {
  char magic[8];
  uint64_t key;
  uint32_t queries;
  uint32_t library;
  uint64_t values;
};

uint64_t values_hash(const std::vector<uint32_t>& d) {
  return fnv1a(0xCBF29CE484222325ull, d.data(), d.size() * sizeof(uint32_t));
}

bool read_cache(const std::string& file, uint64_t key, uint32_t q, uint32_t l,
                std::vector<uint32_t>* out) {
  std::ifstream in(file, std::ios::binary);
  if (!in) return false;
  CacheHeader h{};
  in.read(reinterpret_cast<char*>(&h), sizeof h);
  if (!in || std::memcmp(h.magic, kCacheMagic, 8) != 0 || h.key != key || h.queries != q ||
      h.library != l) {
    return false;
  }
  out->resize(static_cast<size_t>(q) * l);
  in.read(reinterpret_cast<char*>(out->data()),
          static_cast<std::streamsize>(out->size() * sizeof(uint32_t)));
  return static_cast<bool>(in) && in.peek() == std::char_traits<char>::eof() &&
         values_hash(*out) == h.values;
}

// Written to a temporary file of this process's own and renamed (OutputFile), so an
// interrupted or failed write never leaves a cache file that looks complete, nor a
// temporary. A cache that cannot be written is no error: the matrix is computed next time.
void write_cache(const std::string& file, uint64_t key, uint32_t q, uint32_t l,
                 const std::vector<uint32_t>& d) {
  std::error_code ec;
  fs::create_directories(fs::path(file).parent_path(), ec);
  OutputFile out;
  if (!out.open(file).empty()) return;
  CacheHeader h{};
  std::memcpy(h.magic, kCacheMagic, 8);
  h.key = key;
  h.queries = q;
  h.library = l;
  h.values = values_hash(d);
  out.write(&h, sizeof h);
  out.write(d.data(), d.size() * sizeof(uint32_t));
  (void)out.commit();
}

// The shortest decimal that converts back to the same Q16.16 value (0.85, not 0.850006).
std::string q16_decimal(UQ16_16 v) {
  for (int digits = 1; digits <= 10; ++digits) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.*f", digits, to_double(v));
    if (from_double<UQ16_16>(std::strtod(buf, nullptr)) == v) {
      std::string t = buf;
      while (t.size() > 1 && t.back() == '0' && t[t.size() - 2] != '.')
        t.pop_back();
      return t;
    }
  }
  return std::to_string(to_double(v));
}


}  // namespace

Outcome<IndexRange> parse_index_range(const std::string& text) {
  const size_t colon = text.find(':');
  if (colon == std::string::npos || text.find(':', colon + 1) != std::string::npos) {
    return Error{"range '" + text + "': expected FIRST:LAST (either may be empty)"};
  }
  IndexRange r;
  uint64_t v = 0;
  const std::string a = text.substr(0, colon);
  const std::string b = text.substr(colon + 1);
  if (!a.empty()) {
    if (!parse_u64(a, &v)) return Error{"range '" + text + "': '" + a + "' is not an index"};
    r.first = static_cast<int64_t>(v);
  }
  if (!b.empty()) {
    if (!parse_u64(b, &v)) return Error{"range '" + text + "': '" + b + "' is not an index"};
    r.last = static_cast<int64_t>(v);
    if (r.last <= r.first) return Error{"range '" + text + "': LAST must be above FIRST"};
  }
  return r;
}

Outcome<InputSequence> load_input(const std::string& path, int width, int height,
                                  const IndexRange& range) {
  const auto target = check_reduce_target(width, height);
  if (!target) return Error{target.error()};
  InputSequence in;
  in.source = path;
  std::error_code ec;
  if (fs::is_regular_file(path, ec) && is_dream_file(path)) {
    in.kind = "dream";
    auto dream = load_dream_places(path);
    if (!dream) return Error{dream.error()};
    const DreamPlaces& d = dream.value();
    if (d.images.empty()) return Error{path + ": the recording has no places"};
    if (d.images[0].width != width || d.images[0].height != height) {
      return Error{path + ": recorded at " + std::to_string(d.images[0].width) + "x" +
                   std::to_string(d.images[0].height) +
                   " (after the robot's pixel pipeline); use --size " +
                   std::to_string(d.images[0].width) + "x" + std::to_string(d.images[0].height)};
    }
    const auto r = clamp_range(range, d.images.size(), path);
    if (!r) return Error{r.error()};
    in.offset = r.value().first;
    in.source_size = static_cast<uint32_t>(d.images.size());
    const bool has_odometry = d.snapshots > 0;
    for (uint32_t i = r.value().first; i < r.value().second; ++i) {
      in.images.push_back(d.images[i]);
      in.names.push_back("place " + std::to_string(i));
      if (d.has_truth) in.truth.push_back(to_pose_d(d.truth[i]));
      if (has_odometry) in.odometry.push_back(to_pose_d(d.odometry[i]));
    }
    return in;
  }
  const ImageList list = list_images(path);
  if (!list) return Error{list.error()};
  in.kind = fs::is_directory(path, ec) ? "directory" : "index";
  const auto r = clamp_range(range, list.value().size(), path);
  if (!r) return Error{r.error()};
  in.offset = r.value().first;
  in.source_size = static_cast<uint32_t>(list.value().size());
  const uint32_t n = r.value().second - r.value().first;
  in.images.resize(n);
  in.names.resize(n);
  std::vector<std::string> errors(n);
  parallel_for(n, resolve_threads(0), [&](size_t k) {
    const std::string& file = list.value()[in.offset + k];
    in.names[k] = file;
    const LoadedImage img = load_gray(file);
    if (!img) {
      errors[k] = img.error();
      return;
    }
    ReducedImage red = reduce_to(img.value(), width, height);
    if (!red) {
      errors[k] = file + ": " + red.error();
      return;
    }
    in.images[k] = std::move(red).value();
  });
  for (const std::string& e : errors) {
    if (!e.empty()) return Error{e};
  }
  return in;
}

Outcome<GroundTruth> resolve_ground_truth(const std::string& spec, const InputSequence& library,
                                          const InputSequence& query) {
  GroundTruth gt;
  gt.matches.resize(query.images.size());
  const auto lib_size = static_cast<int64_t>(library.images.size());
  auto add_source = [&](size_t q, int64_t source_index) {
    const int64_t pos = source_index - library.offset;
    if (pos >= 0 && pos < lib_size) gt.matches[q].push_back(static_cast<uint32_t>(pos));
  };
  if (spec.rfind("identity:", 0) == 0) {
    uint64_t tol = 0;
    if (!parse_u64(spec.substr(9), &tol) || tol > 100000) {
      return Error{"ground truth '" + spec +
                   "': expected identity:TOL with TOL a whole number within 0..100000"};
    }
    for (size_t q = 0; q < query.images.size(); ++q) {
      const int64_t sq = static_cast<int64_t>(q + query.offset);
      for (int64_t s = sq - static_cast<int64_t>(tol); s <= sq + static_cast<int64_t>(tol); ++s) {
        add_source(q, s);
      }
    }
    return gt;
  }
  if (spec.rfind("poses:", 0) == 0) {
    char* end = nullptr;
    const std::string m = spec.substr(6);
    const double metres = std::strtod(m.c_str(), &end);
    if (m.empty() || end == m.c_str() || *end != '\0' || !(metres > 0.0) || metres > 1000.0) {
      return Error{"ground truth '" + spec +
                   "': expected poses:METRES with METRES above 0 and at most 1000"};
    }
    for (const InputSequence* s : {&library, &query}) {
      if (s->truth.empty()) {
        return Error{"ground truth '" + spec + "': " + s->source +
                     " has no true poses (only simulated dream recordings carry them)"};
      }
    }
    for (size_t q = 0; q < query.images.size(); ++q) {
      const PoseD& a = query.truth[q];
      for (size_t j = 0; j < library.images.size(); ++j) {
        const PoseD& b = library.truth[j];
        const double turn = std::fabs(std::remainder(a.heading - b.heading, 2 * kPi));
        if (turn <= 60.0 * kPi / 180.0 && std::hypot(a.x - b.x, a.y - b.y) <= metres) {
          gt.matches[q].push_back(static_cast<uint32_t>(j));
        }
      }
    }
    return gt;
  }
  const LoadedGroundTruth file = load_ground_truth(spec);
  if (!file) return Error{file.error()};
  const GroundTruth& f = file.value();
  if (f.matches.size() > query.source_size) {
    return Error{spec + ": names query " + std::to_string(f.matches.size() - 1) + " but " +
                 query.source + " has " + std::to_string(query.source_size) +
                 " images (ground truth of another run?)"};
  }
  for (size_t sq = 0; sq < f.matches.size(); ++sq) {
    for (const uint32_t ref : f.matches[sq]) {
      if (ref >= library.source_size) {
        return Error{spec + ": query " + std::to_string(sq) + " names library image " +
                     std::to_string(ref) + " but " + library.source + " has " +
                     std::to_string(library.source_size) + " (ground truth of another run?)"};
      }
    }
  }
  for (size_t q = 0; q < query.images.size(); ++q) {
    const size_t sq = q + query.offset;
    if (sq >= f.matches.size()) continue;
    for (const uint32_t ref : f.matches[sq])
      add_source(q, ref);
  }
  return gt;
}

const char* matcher_name(LocaliserMatcher m) {
  const auto i = static_cast<size_t>(m);
  return i < std::size(storage::kMatcherNames) ? storage::kMatcherNames[i] : "?";
}

bool parse_matcher(const std::string& name, LocaliserMatcher* out) {
  for (size_t i = 0; i < std::size(storage::kMatcherNames); ++i) {
    if (name == storage::kMatcherNames[i]) {
      *out = static_cast<LocaliserMatcher>(i);
      return true;
    }
  }
  return false;
}

const char* metric_name(MetricKind m) {
  switch (m) {
    case MetricKind::kTangent:
      return "td";
    case MetricKind::kTangentNoScaling:
      return "td-noscale";
    case MetricKind::kMad:
      break;
  }
  return "mad";
}

bool parse_metric(const std::string& name, MetricKind* out) {
  if (name == "mad") {
    *out = MetricKind::kMad;
  } else if (name == "td") {
    *out = MetricKind::kTangent;
  } else if (name == "td-noscale") {
    *out = MetricKind::kTangentNoScaling;
  } else {
    return false;
  }
  return true;
}

namespace {

// The inputs of a difference matrix, preprocessed once: library and query images back to
// back (as the firmware's library stores them), and for tangent distance every image's
// tangents (the library's are what the robot would store).
struct Prepared {
  uint32_t library_size = 0;
  uint32_t query_size = 0;
  uint32_t pixels = 0;
  std::vector<uint8_t> lib;
  std::vector<uint8_t> qry;
  std::vector<TangentImage> tangents;  // library then query; tangent metrics only
  double preprocess_ms = 0.0;
};

bool is_tangent(MetricKind m) {
  return m == MetricKind::kTangent || m == MetricKind::kTangentNoScaling;
}

Outcome<Prepared> prepare(const InputSequence& library, const InputSequence& query,
                          const EvalConfig& config) {
  const LocaliserConfig& c = config.localiser;
  const ConfigCheck check = check_localiser_config(c);
  if (!check.ok())
    return Error{std::string("invalid configuration: ") + config_issue_text(check.issue)};
  const auto L = static_cast<uint32_t>(library.images.size());
  const auto Q = static_cast<uint32_t>(query.images.size());
  if (L == 0 || Q == 0) return Error{"nothing to evaluate: an input has no images"};
  if (L > kEvalMaxPlaces)
    return Error{"the library has more than " + std::to_string(kEvalMaxPlaces) + " images"};
  const uint32_t pixels = c.image_size.pixels();
  for (const InputSequence* s : {&library, &query}) {
    for (size_t i = 0; i < s->images.size(); ++i) {
      if (s->images[i].width != c.image_size.width || s->images[i].height != c.image_size.height) {
        return Error{s->source + ": image " + std::to_string(i) + " is not " +
                     std::to_string(c.image_size.width) + "x" +
                     std::to_string(c.image_size.height)};
      }
    }
  }
  const unsigned threads = resolve_threads(config.threads);
  const auto t = Clock::now();
  Prepared p;
  p.library_size = L;
  p.query_size = Q;
  p.pixels = pixels;
  p.lib.resize(static_cast<size_t>(L) * pixels);
  p.qry.resize(static_cast<size_t>(Q) * pixels);
  std::vector<std::string> errors(static_cast<size_t>(L) + Q);
  parallel_for(static_cast<size_t>(L) + Q, threads, [&](size_t i) {
    const bool is_lib = i < L;
    const GrayImage& img = is_lib ? library.images[i] : query.images[i - L];
    uint8_t* out = is_lib ? &p.lib[i * pixels] : &p.qry[(i - L) * pixels];
    const Status s = preprocess(c.preprocess, img.view(), MutableImageView{out, c.image_size});
    if (s != Status::kOk) errors[i] = std::string("preprocessing failed: ") + status_name(s);
  });
  for (const std::string& e : errors) {
    if (!e.empty()) return Error{e};
  }
  if (is_tangent(config.metric)) {
    const auto kernel = make_blur_kernel(default_td_sigma(c.image_size));
    if (!kernel.ok()) return Error{"tangent distance: no blur kernel for this size"};
    p.tangents.resize(static_cast<size_t>(L) + Q);
    parallel_for(p.tangents.size(), threads, [&](size_t i) {
      const uint8_t* px = i < L ? &p.lib[i * pixels] : &p.qry[(i - L) * pixels];
      const Status st = prepare_tangent_image(
          ImageView{px, c.image_size}, kernel.value(), &p.tangents[i],
          config.metric == MetricKind::kTangent ? kAllTangents : kTangentsWithoutScaling);
      if (st != Status::kOk)
        errors[i] = std::string("tangent preparation failed: ") + status_name(st);
    });
    for (const std::string& e : errors) {
      if (!e.empty()) return Error{e};
    }
  }
  p.preprocess_ms = ms_since(t);
  return p;
}

// Rows q0 .. q0 + rows - 1 of the query-major difference matrix into out (rows x L), in
// parallel: the SIMD kernel (same sums as the core's sad_many) 16 query rows per job, so each
// library chunk it loads serves 16 rows; the core's kernels for max_shift > 0 and tangents.
void fill_rows(const Prepared& p, const EvalConfig& config, uint32_t q0, uint32_t rows,
               uint32_t* out) {
  const LocaliserConfig& c = config.localiser;
  const unsigned threads = resolve_threads(config.threads);
  const uint32_t L = p.library_size;
  const size_t pixels = p.pixels;
  if (is_tangent(config.metric)) {
    // The two-sided distance of every pair, as its RMS in SAD units.
    parallel_for(rows, threads, [&](size_t i) {
      const TangentImage& q = p.tangents[L + q0 + i];
      for (uint32_t j = 0; j < L; ++j) {
        const auto td = tangent_distance(q, p.tangents[j]);
        const uint64_t rms = td.ok() ? td.value().rms.raw() : 0xFFFFu;
        out[i * L + j] = static_cast<uint32_t>((rms * pixels + 128) >> 8);
      }
    });
  } else if (c.max_shift == 0) {
    constexpr size_t kRowsPerJob = 16;
    parallel_for((rows + kRowsPerJob - 1) / kRowsPerJob, threads, [&](size_t b) {
      const size_t first = b * kRowsPerJob;
      const auto n = static_cast<uint32_t>(std::min<size_t>(kRowsPerJob, rows - first));
      sad_rows(&p.qry[(q0 + first) * pixels], n, p.lib.data(), L, p.pixels, &out[first * L], L);
    });
  } else {
    parallel_for(rows, threads, [&](size_t i) {
      const ImageView a{&p.qry[(q0 + i) * pixels], c.image_size};
      for (uint32_t j = 0; j < L; ++j) {
        const ImageView b{&p.lib[j * pixels], c.image_size};
        out[i * L + j] = shift_tolerant_sad(a, b, c.max_shift).value();
      }
    });
  }
}

// Rows of the difference matrix as the matchers take them: row(q) is valid until the next
// call. Each matcher step asks for its own query's row; the heuristic's every-start protocol
// also goes back up to S - 1 rows.
using RowSource = std::function<const uint32_t*(uint32_t q)>;

// Matcher state and per-query results, the memory every plan has besides the matrix.
uint64_t matcher_bytes(uint32_t L, uint32_t Q, const EvalConfig& config) {
  const uint64_t S = config.localiser.sequence.seq_len;
  return S * L * sizeof(uint16_t) + uint64_t{L} * (sizeof(uint32_t) + sizeof(uint8_t)) +
         uint64_t{Q} * sizeof(QueryResult);
}

}  // namespace

EvalMemory eval_memory(uint32_t library_size, uint32_t query_size, const EvalConfig& config,
                       uint32_t band_rows) {
  const uint64_t L = library_size;
  const uint64_t Q = query_size;
  const uint64_t B = std::min<uint64_t>(band_rows, Q);
  EvalMemory m;
  m.images = (L + Q) * config.localiser.image_size.pixels();
  if (is_tangent(config.metric)) m.images += (L + Q) * sizeof(TangentImage);
  m.rows = B * L * sizeof(uint32_t);
  m.matcher = matcher_bytes(library_size, query_size, config);
  // keep_matrices copies the differences and adds a float cost per cell (whole matrix only).
  if (config.keep_matrices) m.kept = Q * L * (sizeof(uint32_t) + sizeof(float));
  return m;
}

Outcome<uint32_t> plan_band_rows(uint32_t library_size, uint32_t query_size,
                                 const EvalConfig& config) {
  const uint32_t Q = query_size;
  const auto mib = [](uint64_t bytes) { return std::to_string((bytes + (1u << 20) - 1) >> 20); };
  const auto needs = [&](uint32_t rows) {
    const EvalMemory m = eval_memory(library_size, query_size, config, rows);
    return "needs " + mib(m.total()) + " MiB (images " + mib(m.images) + ", difference rows " +
           mib(m.rows) + " for a band of " + std::to_string(std::min(rows, Q)) +
           " query rows, matcher and results " + mib(m.matcher) +
           (m.kept ? ", kept matrices " + mib(m.kept) : std::string()) + ") but the limit is " +
           mib(config.max_memory) + " MiB (--max-memory)";
  };
  const auto fits = [&](uint32_t rows) {
    return eval_memory(library_size, query_size, config, rows).total() <= config.max_memory;
  };
  // The every-start heuristic re-reads the S - 1 rows before each query: a band holds them.
  const uint32_t min_rows =
      config.localiser.matcher == LocaliserMatcher::kHeuristic && config.heuristic_every_start
          ? std::min(Q, static_cast<uint32_t>(config.localiser.sequence.seq_len))
          : 1;
  if (config.band_rows != 0) {
    const uint32_t rows = std::min(std::max(config.band_rows, min_rows), Q);
    if (config.keep_matrices && rows < Q)
      return Error{"a report keeps the whole matrix: --band must be 0 or at least the " +
                   std::to_string(Q) + " query images"};
    if (!fits(rows)) return Error{"the evaluation " + needs(rows)};
    return rows;
  }
  // The whole matrix only where it is kept (reports) or cached; bands are smaller and, with
  // the band warm in cache for the matcher, faster (docs/seqslam_eval.md "Speed").
  if (config.keep_matrices || !config.cache_dir.empty()) {
    if (fits(Q)) return Q;
    if (config.keep_matrices) return Error{"the report's whole matrix " + needs(Q)};
  }
  uint32_t rows = std::min(kAutoBandRows, Q);
  while (rows > min_rows && !fits(rows))
    rows /= 2;
  rows = std::max(rows, min_rows);
  if (!fits(rows)) return Error{"the smallest band " + needs(rows)};
  return rows;
}

Outcome<DifferenceMatrix> difference_matrix(const InputSequence& library,
                                            const InputSequence& query, const EvalConfig& config) {
  auto prepared = prepare(library, query, config);
  if (!prepared) return Error{prepared.error()};
  const Prepared& p = prepared.value();
  const LocaliserConfig& c = config.localiser;
  const uint32_t L = p.library_size;
  const uint32_t Q = p.query_size;
  DifferenceMatrix m;
  m.library_size = L;
  m.query_size = Q;
  m.timing.preprocess_ms = p.preprocess_ms;

  // The matrix, from the cache or computed in parallel.
  const auto t = Clock::now();
  uint64_t key = 0xCBF29CE484222325ull;
  key = fnv1a(key, p.lib.data(), p.lib.size());
  key = fnv1a(key, p.qry.data(), p.qry.size());
  key = fnv1a(key, &c.image_size.width, sizeof c.image_size.width);
  key = fnv1a(key, &c.image_size.height, sizeof c.image_size.height);
  key = fnv1a(key, &c.max_shift, sizeof c.max_shift);
  key = fnv1a(key, &config.metric, sizeof config.metric);
  char name[40];
  std::snprintf(name, sizeof name, "diff-%016llx.bin", static_cast<unsigned long long>(key));
  const std::string cache_file = config.cache_dir.empty() ? "" : config.cache_dir + "/" + name;
  std::vector<uint32_t>& d = m.values;
  if (!cache_file.empty() && read_cache(cache_file, key, Q, L, &d)) {
    m.timing.matrix_from_cache = true;
  } else {
    d.assign(static_cast<size_t>(Q) * L, 0);
    fill_rows(p, config, 0, Q, d.data());
    if (!cache_file.empty()) write_cache(cache_file, key, Q, L, d);
  }
  m.timing.differences_ms = ms_since(t);
  return m;
}

namespace {

// The distances the heuristic asks for, from the difference matrix (the robot would compute
// only those); `first` maps the matcher's step index (from 0 after a reset) to the query.
class MatrixDistance final : public PlaceDistance {
 public:
  MatrixDistance(const RowSource& rows, uint32_t l, uint32_t q)
      : rows_(rows), library_size_(l), query_size_(q) {}
  uint32_t first = 0;

 private:
  Status do_distance(uint32_t query, uint32_t place, uint32_t* out) override {
    const uint64_t q = uint64_t{first} + query;
    if (q >= query_size_ || place >= library_size_) return Status::kOutOfRange;
    // The scan asks for every place of one row in turn: fetch the row once per query (this is
    // the only reader of `rows_`, so the pointer stays valid until it moves).
    if (q != row_query_) {
      row_ = rows_(static_cast<uint32_t>(q));
      row_query_ = q;
    }
    *out = row_[place];
    return Status::kOk;
  }
  const RowSource& rows_;
  uint32_t library_size_;
  uint32_t query_size_;
  uint64_t row_query_ = std::numeric_limits<uint64_t>::max();
  const uint32_t* row_ = nullptr;
};

// One query's answer into the result, scored against the truth.
void record_match(EvalResult& r, const GroundTruth* truth, uint32_t q, const Match& m) {
  QueryResult& qr = r.matches[q];
  qr.query = q;
  qr.library = m.place;
  qr.runner_up = m.runner_up;
  qr.confidence = to_double(m.confidence);
  qr.accepted = m.localised;
  if (truth != nullptr) {
    qr.has_truth = truth->has_match(q);
    qr.correct = m.place >= 0 && truth->is_correct(q, static_cast<uint32_t>(m.place));
  }
}

// The sequence costs of one step (keep_matrices): cost(j) / S in grey levels, NaN where no
// full sequence ends at j. Normalised differences are Q5.11 grey-level z-scores plus sqrt(W).
template <class Matcher>
void keep_costs(EvalResult& r, uint32_t q, uint32_t L, uint16_t seq_len, const Matcher& m) {
  const double cost_scale = 1.0 / (2048.0 * seq_len);
  float* row = &r.sequence_costs[static_cast<size_t>(q) * L];
  for (uint32_t j = 0; j < L; ++j) {
    if (m.full_sequence(j)) row[j] = static_cast<float>(m.cost(j) * cost_scale);
  }
}

// The heuristic over the matrix: one stream of disjoint sequences, or (every_start) a fresh
// run of S steps for every query q >= S-1 whose final answer is recorded at q.
std::string heuristic_rows(Localiser& localiser, const RowSource& rows, uint32_t L, uint32_t Q,
                           bool every_start, const GroundTruth* truth, EvalResult& r) {
  MatrixDistance distance(rows, L, Q);
  const uint32_t S = localiser.config().sequence.seq_len;
  const auto step = [&](Match* out) -> std::string {
    const Status st = localiser.localise_distances(distance, L, out);
    return st == Status::kOk ? "" : std::string("matcher step failed: ") + status_name(st);
  };
  if (!every_start) {
    // Every step reports the anytime answer (the best trail so far).
    for (uint32_t q = 0; q < Q; ++q) {
      Match out;
      const std::string e = step(&out);
      if (!e.empty()) return e;
      record_match(r, truth, q, out);
    }
    return {};
  }
  for (uint32_t q = 0; q < S - 1 && q < Q; ++q)
    record_match(r, truth, q, Match{});  // no full sequence yet
  for (uint32_t q = S - 1; q < Q; ++q) {
    localiser.reset_sequence();
    distance.first = q - (S - 1);
    Match out;
    for (uint32_t i = 0; i < S; ++i) {
      const std::string e = step(&out);
      if (!e.empty()) return e;
    }
    record_match(r, truth, q, out);
  }
  return {};
}

// Precision and recall over the recorded answers. The 2025 thesis: the recall denominator is
// every query with a full sequence; the heuristic's -1 after a full sequence is "unknown
// place": counted, never correct.
void score_rows(EvalResult& r, uint32_t seq_len, bool declines) {
  r.has_ground_truth = true;
  std::vector<MatchRecord> records;
  size_t denominator = 0;
  for (const QueryResult& qr : r.matches) {
    const bool full = qr.library >= 0 || (declines && qr.query + 1 >= seq_len);
    if (!full) continue;
    ++denominator;
    if (qr.library >= 0) {
      records.push_back(MatchRecord{qr.query, qr.library, qr.confidence, qr.correct});
    }
  }
  r.summary = evaluate_pr(records, denominator);
}

// Runs the configured matcher over rows 0 .. Q-1 of a difference matrix: the session's
// localiser (the firmware's wiring, storage on the heap, a library of L places whose images
// stay with the matrix) takes one step per query row, as Localiser::localise would after
// computing that row; with keep_matrices also the sequence costs. r.timing.match_ms is the
// wall time of the whole run, rows included.
std::string match_rows(const RowSource& rows, uint32_t L, uint32_t Q, const EvalConfig& config,
                       const GroundTruth* truth, EvalResult* result) {
  const auto start = Clock::now();
  const LocaliserConfig& c = config.localiser;
  EvalResult& r = *result;
  if (config.keep_matrices)
    r.sequence_costs.assign(static_cast<size_t>(Q) * L, std::numeric_limits<float>::quiet_NaN());
  r.matches.resize(Q);
  HostSession host;
  HostSessionOptions options;
  options.search = session::Search::kFull;
  options.places = L;
  options.library_ram = false;
  options.library_images = false;
  const std::string e = host.configure(repeat_config(c), options);
  if (!e.empty()) return "matcher " + e;
  Localiser& localiser = host.session().localiser();
  if (c.matcher == LocaliserMatcher::kHeuristic) {
    const std::string h =
        heuristic_rows(localiser, rows, L, Q, config.heuristic_every_start, truth, r);
    if (!h.empty()) return h;
  } else {
    for (uint32_t q = 0; q < Q; ++q) {
      Match out;
      const Status st = localiser.localise_differences(Span<const uint32_t>(rows(q), L), &out);
      if (st != Status::kOk) return std::string("matcher step failed: ") + status_name(st);
      record_match(r, truth, q, out);
      if (!config.keep_matrices) continue;
      if (localiser.slope() != nullptr) {
        keep_costs(r, q, L, c.sequence.seq_len, *localiser.slope());
      } else {
        keep_costs(r, q, L, c.sequence.seq_len, localiser.matcher());
      }
    }
  }
  r.timing.match_ms = ms_since(start);
  if (truth != nullptr) {
    score_rows(r, c.sequence.seq_len, c.matcher == LocaliserMatcher::kHeuristic);
  }
  return "";
}

// A result before matching: what was evaluated and the memory plan that runs it.
EvalResult new_result(const EvalConfig& config, uint32_t L, uint32_t Q, uint32_t band_rows) {
  EvalResult r;
  r.config = config;
  r.library_size = L;
  r.query_size = Q;
  r.band_rows = band_rows;
  r.planned_bytes = eval_memory(L, Q, config, band_rows).total();
  return r;
}

}  // namespace

Outcome<EvalResult> evaluate_matrix(const DifferenceMatrix& matrix, const EvalConfig& config,
                                    const GroundTruth* truth) {
  const ConfigCheck check = check_localiser_config(config.localiser);
  if (!check.ok())
    return Error{std::string("invalid configuration: ") + config_issue_text(check.issue)};
  const uint32_t L = matrix.library_size;
  const uint32_t Q = matrix.query_size;
  if (matrix.values.size() != static_cast<size_t>(Q) * L || L == 0) {
    return Error{"difference matrix of the wrong size"};
  }
  EvalResult r = new_result(config, L, Q, Q);
  r.timing = matrix.timing;
  if (config.keep_matrices) r.differences = matrix.values;
  const RowSource rows = [&](uint32_t q) { return &matrix.values[static_cast<size_t>(q) * L]; };
  const std::string e = match_rows(rows, L, Q, config, truth, &r);
  if (!e.empty()) return Error{e};
  r.timing.total_ms = r.timing.preprocess_ms + r.timing.differences_ms + r.timing.match_ms;
  return r;
}

Outcome<EvalResult> evaluate(const InputSequence& library, const InputSequence& query,
                             const EvalConfig& config, const GroundTruth* truth,
                             const EvalProgress& progress) {
  const auto L = static_cast<uint32_t>(library.images.size());
  const auto Q = static_cast<uint32_t>(query.images.size());
  if (L == 0 || Q == 0) return Error{"nothing to evaluate: an input has no images"};
  const auto band = plan_band_rows(L, Q, config);
  if (!band) return Error{band.error()};
  if (band.value() >= Q && (config.keep_matrices || !config.cache_dir.empty())) {
    // The whole matrix, kept for a report or cached (as sweeps use it).
    const auto matrix = difference_matrix(library, query, config);
    if (!matrix) return Error{matrix.error()};
    return evaluate_matrix(matrix.value(), config, truth);
  }
  // Bands of B query rows: only B x L differences live at a time (eval_memory()).
  auto prepared = prepare(library, query, config);
  if (!prepared) return Error{prepared.error()};
  const Prepared& p = prepared.value();
  const uint32_t B = band.value();
  EvalResult r = new_result(config, L, Q, B);
  r.timing.preprocess_ms = p.preprocess_ms;
  std::vector<uint32_t> rows(static_cast<size_t>(B) * L);
  uint32_t first = 0;
  uint32_t end = 0;  // rows [first, end) are in the band
  // The every-start heuristic goes back S - 1 rows: its new band starts that far back (the
  // plan gives it at least S rows). The other matchers never go back.
  const bool goes_back =
      config.localiser.matcher == LocaliserMatcher::kHeuristic && config.heuristic_every_start;
  const uint32_t back = goes_back ? std::min(B - 1, config.localiser.sequence.seq_len - 1u) : 0;
  const RowSource source = [&](uint32_t q) {
    if (q < first || q >= end) {
      first = q >= end && q >= back ? q - back : q;
      end = std::min(Q, first + B);
      const auto t = Clock::now();
      fill_rows(p, config, first, end - first, rows.data());
      r.timing.differences_ms += ms_since(t);
      if (progress) progress(first, Q);
    }
    return &rows[static_cast<size_t>(q - first) * L];
  };
  const std::string e = match_rows(source, L, Q, config, truth, &r);
  if (!e.empty()) return Error{e};
  if (progress) progress(Q, Q);
  r.timing.match_ms -= r.timing.differences_ms;  // match_rows timed the fills too
  r.timing.total_ms = r.timing.preprocess_ms + r.timing.differences_ms + r.timing.match_ms;
  return r;
}

std::string eval_json(const EvalResult& r, const InputSequence& library, const InputSequence& query,
                      const nlohmann::ordered_json& extra) {
  using Json = nlohmann::ordered_json;
  const LocaliserConfig& c = r.config.localiser;
  const auto input = [](const InputSequence& s) {
    return Json{{"source", s.source},
                {"kind", s.kind},
                {"images", s.images.size()},
                {"first", s.offset},
                {"source_images", s.source_size}};
  };
  Json doc;
  doc["library"] = input(library);
  doc["query"] = input(query);
  doc["config"] = Json{
      {"size", std::to_string(c.image_size.width) + "x" + std::to_string(c.image_size.height)},
      {"preprocess", preprocessing_name(c.preprocess.method)},
      {"seq_len", c.sequence.seq_len},
      {"window", c.sequence.window},
      {"exclusion", c.sequence.exclusion},
      {"threshold", json_decimal(q16_decimal(c.sequence.threshold))},
      {"max_shift", int{c.max_shift}},
      {"matcher", matcher_name(c.matcher)},
      {"metric", metric_name(r.config.metric)},
      {"engine", "fixed-point core"}};
  if (r.has_ground_truth) {
    const PrSummary& s = r.summary;
    const PrPoint op = s.at_threshold(to_double(c.sequence.threshold));
    doc["summary"] = Json{{"queries", s.queries},
                          {"recall_at_100_precision", s.recall_at_100_precision},
                          {"auc_pr", s.auc_pr},
                          {"precision_at_recall",
                           Json{{"0.5", s.precision_at_recall(0.5)},
                                {"0.85", s.precision_at_recall(0.85)}}},
                          {"max_recall", s.max_recall},
                          {"top1", s.top1},
                          {"accepted", op.accepted},
                          {"precision", op.precision},
                          {"recall", op.recall}};
  } else {
    doc["summary"] = nullptr;
  }
  doc["timing_ms"] = Json{{"load", r.timing.load_ms},
                          {"preprocess", r.timing.preprocess_ms},
                          {"differences", r.timing.differences_ms},
                          {"match", r.timing.match_ms},
                          {"total", r.timing.total_ms},
                          {"matrix_from_cache", r.timing.matrix_from_cache}};
  // What the figures above ran on: the SAD kernel's instruction set, and the process's peak
  // resident memory so far (getrusage; Linux reports KiB).
  rusage usage{};
  const long peak_kib = getrusage(RUSAGE_SELF, &usage) == 0 ? usage.ru_maxrss : -1;
  doc["host"] = Json{{"simd", sad_target_name()},
                     {"threads", resolve_threads(r.config.threads)},
                     {"band_rows", r.band_rows},
                     {"planned_bytes", r.planned_bytes},
                     {"peak_rss_kib", peak_kib}};
  for (auto it = extra.begin(); it != extra.end(); ++it)
    doc[it.key()] = it.value();
  Json matches = Json::array();
  for (const QueryResult& m : r.matches) {
    Json row{{"query", m.query + query.offset},
             {"library", m.library < 0 ? int64_t{-1} : int64_t{m.library} + library.offset},
             {"confidence", m.confidence},
             {"accepted", m.accepted}};
    if (r.has_ground_truth) {
      row["has_truth"] = m.has_truth;
      row["correct"] = m.correct;
    }
    matches.push_back(std::move(row));
  }
  doc["matches"] = std::move(matches);
  return json_text(doc, JsonNumbers::kSixDigits);
}

}  // namespace seqslam::tools
