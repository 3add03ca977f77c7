// The evaluation engine (seqslam_tools/evaluation.h) behind `seqslam run`, `eval` and `sweep`:
//  - its matches equal the firmware's Localiser stepped query by query (bit-exact confidence),
//    for several configurations and thread counts;
//  - ranges, ground-truth specifications (identity, poses of simulated runs, CSV files);
//  - the difference-matrix cache (hits, and damaged files never trusted);
//  - its PR summary equals evaluate_pr over the same records.
// All on the corridor data at 32x16 (111 + 111 images) and two tiny simulated runs.
#include "seqslam_tools/evaluation.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "seqslam/heuristic_matcher.h"
#include "seqslam/preprocess.h"
#include "seqslam/tangent_distance.h"

#include "seqslam/seqslam.h"
#include "seqslam_sim/lab.h"
#include "seqslam_sim/scenario.h"
#include "seqslam_tools/core_run.h"
#include "seqslam_tools/ground_truth.h"
#include "seqslam_tools/pr_metrics.h"
#include "seqslam_tools/q_format.h"
#include "test_util.h"

namespace seqslam::tools {
namespace {

namespace fs = std::filesystem;
using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

constexpr double kPi = 3.14159265358979323846;
constexpr uint32_t kCorridorImages = 111;

std::string ref_dir() {
  return test::corridor_dir() + "/ref";
}
std::string query_dir() {
  return test::corridor_dir() + "/query";
}

// The settings these tests were written with: the corridor's 32x16 with HE (the defaults
// before issue 33), the rest the defaults.
EvalConfig corridor_config() {
  EvalConfig c;
  c.localiser.image_size = ImageSize{32, 16};
  c.localiser.preprocess.method = Preprocessing::kHistEq;
  return c;
}

// The corridor pair at 32x16, loaded once for the whole suite.
class EvalCorridor : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    auto lib = load_input(ref_dir(), 32, 16);
    auto qry = load_input(query_dir(), 32, 16);
    ASSERT_TRUE(lib.ok()) << lib.error();
    ASSERT_TRUE(qry.ok()) << qry.error();
    library_ = new InputSequence(std::move(lib).value());
    query_ = new InputSequence(std::move(qry).value());
  }
  static void TearDownTestSuite() {
    delete library_;
    delete query_;
    library_ = nullptr;
    query_ = nullptr;
  }
  void SetUp() override {
    ASSERT_NE(library_, nullptr);
    ASSERT_NE(query_, nullptr);
  }
  static const InputSequence& library() { return *library_; }
  static const InputSequence& query() { return *query_; }

 private:
  static InputSequence* library_;
  static InputSequence* query_;
};
InputSequence* EvalCorridor::library_ = nullptr;
InputSequence* EvalCorridor::query_ = nullptr;

// The firmware's Localiser stepped over the queries (teach every library image first): the
// full core Match of every step.
std::vector<Match> localiser_steps(const std::vector<GrayImage>& library,
                                   const std::vector<GrayImage>& queries,
                                   const LocaliserConfig& c) {
  constexpr uint32_t kPlaces = 128;
  auto lib_storage = std::make_unique<PlaceLibraryStorage<kPlaces, kMaxPixels>>();
  auto matcher_storage = std::make_unique<DiagonalMatcherStorage<kPlaces, kMaxSeqLen>>();
  std::vector<uint32_t> differences(kPlaces);
  std::vector<Match> out;
  PlaceLibrary places;
  if (library.size() > kPlaces || lib_storage->attach(places, c.image_size) != Status::kOk) {
    ADD_FAILURE() << "library storage";
    return out;
  }
  Localiser localiser;
  const ConfigCheck cfg = localiser.configure(c, places, matcher_storage->buffers(),
                                              Span<uint32_t>(differences.data(), kPlaces));
  if (!cfg.ok()) {
    ADD_FAILURE() << config_issue_text(cfg.issue);
    return out;
  }
  for (size_t i = 0; i < library.size(); ++i) {
    const Status s = localiser.teach(library[i].view(), Pose2{}, static_cast<uint32_t>(i));
    if (s != Status::kOk) {
      ADD_FAILURE() << "teach " << i << ": " << status_name(s);
      return out;
    }
  }
  for (const GrayImage& img : queries) {
    Match m;
    const Status s = localiser.localise(img.view(), &m);
    if (s != Status::kOk) {
      ADD_FAILURE() << "localise " << out.size() << ": " << status_name(s);
      return out;
    }
    out.push_back(m);
  }
  return out;
}

struct Setting {
  Preprocessing method;
  uint16_t seq_len;
  uint16_t window;
  uint8_t max_shift;
  uint32_t threshold_percent;
};

LocaliserConfig config_of(const Setting& s) {
  LocaliserConfig c;
  c.image_size = ImageSize{32, 16};
  c.preprocess.method = s.method;
  c.sequence.seq_len = s.seq_len;
  c.sequence.window = s.window;
  c.max_shift = s.max_shift;
  c.sequence.threshold = UQ16_16::from_ratio(s.threshold_percent, 100);
  return c;
}

std::string describe(const Setting& s) {
  return std::string(preprocessing_name(s.method)) + " S=" + std::to_string(s.seq_len) +
         " W=" + std::to_string(s.window) + " shift=" + std::to_string(int{s.max_shift}) + " C=0." +
         std::to_string(s.threshold_percent);
}

void expect_same_matches(const EvalResult& a, const EvalResult& b, const std::string& what) {
  ASSERT_EQ(a.matches.size(), b.matches.size()) << what;
  for (size_t q = 0; q < a.matches.size(); ++q) {
    const QueryResult& x = a.matches[q];
    const QueryResult& y = b.matches[q];
    EXPECT_EQ(x.query, y.query) << what << " q=" << q;
    EXPECT_EQ(x.library, y.library) << what << " q=" << q;
    EXPECT_EQ(x.runner_up, y.runner_up) << what << " q=" << q;
    EXPECT_EQ(x.confidence, y.confidence) << what << " q=" << q;  // bit-exact
    EXPECT_EQ(x.accepted, y.accepted) << what << " q=" << q;
    EXPECT_EQ(x.has_truth, y.has_truth) << what << " q=" << q;
    EXPECT_EQ(x.correct, y.correct) << what << " q=" << q;
  }
}

// ---------------------------------------------------------------------------------------
// 1b. The other matchers and the tangent-distance metric behind the same engine.

TEST_F(EvalCorridor, SlopeAtUnitVelocityEqualsDiagonal) {
  EvalConfig config = corridor_config();
  config.localiser = config_of({Preprocessing::kHistEq, 10, 50, 0, 85});
  const auto diagonal = evaluate(library(), query(), config, nullptr);
  ASSERT_TRUE(diagonal.ok()) << diagonal.error();
  config.localiser.matcher = LocaliserMatcher::kSlope;
  config.localiser.slope.vmin = UQ8_8::from_int(1);
  config.localiser.slope.vmax = UQ8_8::from_int(1);
  config.localiser.slope.vsteps = 1;
  const auto slope = evaluate(library(), query(), config, nullptr);
  ASSERT_TRUE(slope.ok()) << slope.error();
  expect_same_matches(diagonal.value(), slope.value(), "slope v=1");
  // With its default velocities it is a different matcher (it must differ somewhere).
  config.localiser.slope = SlopeConfig{};
  const auto search = evaluate(library(), query(), config, nullptr);
  ASSERT_TRUE(search.ok()) << search.error();
  size_t differ = 0;
  for (size_t q = 0; q < search.value().matches.size(); ++q) {
    differ += search.value().matches[q].confidence != diagonal.value().matches[q].confidence;
  }
  EXPECT_GT(differ, 0u);
}

TEST_F(EvalCorridor, HeuristicEqualsTheCoreMatcherOnTheMatrix) {
  EvalConfig config = corridor_config();
  config.localiser = config_of({Preprocessing::kHistEq, 10, 50, 0, 85});
  config.localiser.matcher = LocaliserMatcher::kHeuristic;
  const auto matrix = difference_matrix(library(), query(), config);
  ASSERT_TRUE(matrix.ok()) << matrix.error();
  const auto r = evaluate_matrix(matrix.value(), config, nullptr);
  ASSERT_TRUE(r.ok()) << r.error();
  // The core's HeuristicMatcher fed the same distances by hand.
  struct Table final : PlaceDistance {
    explicit Table(const DifferenceMatrix& d) : d_(d) {}
    Status do_distance(uint32_t q, uint32_t p, uint32_t* out) override {
      *out = d_.values[size_t{q} * d_.library_size + p];
      return Status::kOk;
    }
    const DifferenceMatrix& d_;
  } table(matrix.value());
  HeuristicConfig hc;
  hc.seq_len = 10;
  hc.exclusion = config.localiser.sequence.exclusion;
  HeuristicMatcher m;
  ASSERT_EQ(m.configure(hc, 512), Status::kOk);
  size_t found = 0;
  for (uint32_t q = 0; q < matrix.value().query_size; ++q) {
    HeuristicMatch h;
    ASSERT_EQ(m.step(table, matrix.value().library_size, &h), Status::kOk);
    EXPECT_EQ(r.value().matches[q].library, h.place) << q;
    EXPECT_EQ(r.value().matches[q].confidence, to_double(h.confidence)) << q;
    found += h.place >= 0;
  }
  EXPECT_GT(found, 0u);
}

TEST_F(EvalCorridor, HeuristicEveryStartIsAFreshRunPerSequence) {
  // The 2015 thesis's protocol: the answer at q is a fresh run over queries q-S+1..q.
  EvalConfig config = corridor_config();
  config.localiser = config_of({Preprocessing::kHistEq, 10, 50, 0, 85});
  config.localiser.matcher = LocaliserMatcher::kHeuristic;
  config.heuristic_every_start = true;
  config.localiser.heuristic.threshold = UQ8_8::from_raw(0xFFFF);  // forced answers
  const auto matrix = difference_matrix(library(), query(), config);
  ASSERT_TRUE(matrix.ok()) << matrix.error();
  const GroundTruth truth = identity_ground_truth(kCorridorImages, kCorridorImages, 2);
  const auto r = evaluate_matrix(matrix.value(), config, &truth);
  ASSERT_TRUE(r.ok()) << r.error();
  const DifferenceMatrix& d = matrix.value();
  struct Shifted final : PlaceDistance {
    Shifted(const DifferenceMatrix& dm, uint32_t f) : d_(dm), first_(f) {}
    Status do_distance(uint32_t q, uint32_t p, uint32_t* out) override {
      *out = d_.values[size_t{first_ + q} * d_.library_size + p];
      return Status::kOk;
    }
    const DifferenceMatrix& d_;
    uint32_t first_;
  };
  HeuristicConfig hc = config.localiser.heuristic;
  hc.seq_len = 10;
  hc.exclusion = config.localiser.sequence.exclusion;
  size_t differ_from_stream = 0;
  for (uint32_t q = 0; q < d.query_size; ++q) {
    const QueryResult& got = r.value().matches[q];
    if (q < 9) {
      EXPECT_EQ(got.library, -1) << q;  // no full sequence yet
      continue;
    }
    HeuristicMatcher m;  // a new matcher: nothing carried over
    ASSERT_EQ(m.configure(hc, 512), Status::kOk);
    Shifted table(d, q - 9);
    HeuristicMatch h;
    for (int i = 0; i < 10; ++i)
      ASSERT_EQ(m.step(table, d.library_size, &h), Status::kOk);
    ASSERT_TRUE(h.complete);
    EXPECT_GE(h.place, 0) << q;  // no threshold: always an answer
    EXPECT_EQ(got.library, h.place) << q;
    EXPECT_EQ(got.confidence, to_double(h.confidence)) << q;
    differ_from_stream += q % 10 != 9;  // the stream would report partial sequences there
  }
  EXPECT_GT(differ_from_stream, 0u);
  // Every query with a full sequence is in the recall denominator.
  EXPECT_EQ(r.value().summary.queries, kCorridorImages - 9);
}

TEST_F(EvalCorridor, HeuristicUnknownCountsInTheRecallDenominator) {
  // A candidate threshold nothing passes: every answer is -1 (unknown place); the queries
  // with a full sequence still count, so recall is 0 rather than undefined.
  EvalConfig config = corridor_config();
  config.localiser = config_of({Preprocessing::kHistEq, 10, 50, 0, 85});
  config.localiser.matcher = LocaliserMatcher::kHeuristic;
  config.localiser.heuristic.threshold = UQ8_8::from_raw(0);
  const GroundTruth truth = identity_ground_truth(kCorridorImages, kCorridorImages, 2);
  const auto r = evaluate(library(), query(), config, &truth);
  ASSERT_TRUE(r.ok()) << r.error();
  for (const QueryResult& m : r.value().matches)
    EXPECT_EQ(m.library, -1);
  EXPECT_EQ(r.value().summary.queries, kCorridorImages - 9);
  EXPECT_EQ(r.value().summary.top1, 0.0);
}

TEST_F(EvalCorridor, TangentMetricMatrixIsTheCoreDistance) {
  // td: all four tangents; td-noscale: without the scaling tangent (TangentSet).
  const std::pair<MetricKind, uint8_t> metrics[] = {
      {MetricKind::kTangent, kAllTangents},
      {MetricKind::kTangentNoScaling, kTangentsWithoutScaling}};
  std::vector<std::vector<uint32_t>> seen;
  for (const auto& [metric, tangents] : metrics) {
    EvalConfig config = corridor_config();
    config.localiser = config_of({Preprocessing::kHistEq, 10, 50, 0, 85});
    config.metric = metric;
    std::vector<GrayImage> lib(library().images.begin(), library().images.begin() + 12);
    std::vector<GrayImage> qry(query().images.begin(), query().images.begin() + 9);
    InputSequence l = library(), q = query();
    l.images = lib;
    q.images = qry;
    const auto matrix = difference_matrix(l, q, config);
    ASSERT_TRUE(matrix.ok()) << matrix.error();
    const auto kernel = make_blur_kernel(default_td_sigma(ImageSize{32, 16}));
    ASSERT_TRUE(kernel.ok());
    auto prepared = [&, set = tangents](const GrayImage& g) {
      std::vector<uint8_t> pp(512);
      EXPECT_EQ(preprocess(config.localiser.preprocess, g.view(),
                           MutableImageView{pp.data(), ImageSize{32, 16}}),
                Status::kOk);
      auto t = std::make_unique<TangentImage>();
      EXPECT_EQ(prepare_tangent_image(ImageView{pp.data(), ImageSize{32, 16}}, kernel.value(),
                                      t.get(), set),
                Status::kOk);
      return t;
    };
    for (uint32_t i = 0; i < qry.size(); ++i) {
      const auto a = prepared(qry[i]);
      for (uint32_t j = 0; j < lib.size(); ++j) {
        const auto b = prepared(lib[j]);
        const auto td = tangent_distance(*a, *b);
        ASSERT_TRUE(td.ok());
        const uint32_t want =
            static_cast<uint32_t>((uint64_t{td.value().rms.raw()} * 512 + 128) >> 8);
        EXPECT_EQ(matrix.value().values[size_t{i} * lib.size() + j], want) << i << "," << j;
      }
    }
    seen.push_back(matrix.value().values);
    // And the metric is part of the cache key: MAD gives another matrix.
    config.metric = MetricKind::kMad;
    const auto mad = difference_matrix(l, q, config);
    ASSERT_TRUE(mad.ok());
    seen.push_back(mad.value().values);
  }
  EXPECT_NE(seen[0], seen[1]);  // td vs mad
  EXPECT_NE(seen[0], seen[2]);  // td vs td-noscale
  EXPECT_EQ(std::string(metric_name(MetricKind::kTangentNoScaling)), "td-noscale");
  MetricKind parsed = MetricKind::kMad;
  EXPECT_TRUE(parse_metric("td-noscale", &parsed));
  EXPECT_EQ(parsed, MetricKind::kTangentNoScaling);
  EXPECT_FALSE(parse_metric("td-noscal", &parsed));
}

// ---------------------------------------------------------------------------------------
// 1. The engine equals the Localiser stepped query by query.

TEST_F(EvalCorridor, EngineEqualsLocaliserStepByStep) {
  const Setting settings[] = {
      {Preprocessing::kHistEq, 30, 50, 0, 85},    {Preprocessing::kHistEq, 10, 0, 2, 85},
      {Preprocessing::kPatchNorm, 10, 50, 0, 90}, {Preprocessing::kPatchNorm, 30, 0, 2, 85},
      {Preprocessing::kNone, 30, 50, 2, 95},      {Preprocessing::kNone, 10, 0, 0, 85},
  };
  for (const Setting& s : settings) {
    const std::string what = describe(s);
    EvalConfig config = corridor_config();
    config.localiser = config_of(s);
    config.threads = 1;
    const auto one = evaluate(library(), query(), config, nullptr);
    ASSERT_TRUE(one.ok()) << what << ": " << one.error();
    config.threads = 2;
    const auto two = evaluate(library(), query(), config, nullptr);
    ASSERT_TRUE(two.ok()) << what << ": " << two.error();
    expect_same_matches(one.value(), two.value(), what + " threads 1 vs 2");

    const std::vector<Match> steps =
        localiser_steps(library().images, query().images, config.localiser);
    const auto core = run_core(library().images, query().images, config.localiser);
    ASSERT_TRUE(core.ok()) << what << ": " << core.error();
    const EvalResult& r = one.value();
    ASSERT_EQ(r.matches.size(), kCorridorImages) << what;
    ASSERT_EQ(steps.size(), kCorridorImages) << what;
    ASSERT_EQ(core.value().size(), kCorridorImages) << what;
    EXPECT_EQ(r.library_size, kCorridorImages);
    EXPECT_EQ(r.query_size, kCorridorImages);
    size_t with_place = 0, with_runner_up = 0, accepted = 0, rejected = 0;
    for (size_t q = 0; q < kCorridorImages; ++q) {
      const QueryResult& e = r.matches[q];
      const Match& m = steps[q];
      const CoreMatch& cm = core.value()[q];
      EXPECT_EQ(e.query, q) << what;
      EXPECT_EQ(e.library, m.place) << what << " q=" << q;
      EXPECT_EQ(e.runner_up, m.runner_up) << what << " q=" << q;
      EXPECT_EQ(e.confidence, to_double(m.confidence)) << what << " q=" << q;
      EXPECT_EQ(e.accepted, m.localised) << what << " q=" << q;
      EXPECT_EQ(e.library, cm.place) << what << " q=" << q;
      EXPECT_EQ(e.confidence, cm.confidence) << what << " q=" << q;
      EXPECT_EQ(e.accepted, cm.localised) << what << " q=" << q;
      EXPECT_FALSE(e.has_truth);  // no ground truth given
      EXPECT_FALSE(e.correct);
      // A full sequence exists exactly from query S-1 on.
      EXPECT_EQ(e.library >= 0, q + 1 >= s.seq_len) << what << " q=" << q;
      with_place += e.library >= 0;
      with_runner_up += e.runner_up >= 0;
      accepted += e.accepted;
      rejected += e.library >= 0 && !e.accepted;
    }
    // Not vacuous: places, runner-ups, accepted and rejected matches all occur.
    EXPECT_EQ(with_place, kCorridorImages + 1 - s.seq_len) << what;
    EXPECT_GT(with_runner_up, 0u) << what;
    EXPECT_GT(accepted, 0u) << what;
    EXPECT_GT(rejected, 0u) << what;
  }
}

TEST_F(EvalCorridor, EvaluateRejectsBadConfigurationAndSizes) {
  EvalConfig config = corridor_config();
  config.localiser.sequence.seq_len = 0;
  auto r = evaluate(library(), query(), config, nullptr);
  ASSERT_FALSE(r.ok());
  EXPECT_THAT(r.error(), HasSubstr("seq_len"));

  config = corridor_config();
  config.localiser.image_size = ImageSize{16, 8};  // the inputs are 32x16
  r = evaluate(library(), query(), config, nullptr);
  ASSERT_FALSE(r.ok());
  EXPECT_THAT(r.error(), HasSubstr("16x8"));

  InputSequence empty;
  empty.source = "empty";
  r = evaluate(empty, query(), corridor_config(), nullptr);
  ASSERT_FALSE(r.ok());
}

// ---------------------------------------------------------------------------------------
// 1c. Bands: the difference matrix a band of query rows at a time gives the results of the
//     whole matrix, for every matcher and metric, whatever the band.

TEST_F(EvalCorridor, BandsGiveTheWholeMatrixResults) {
  const GroundTruth truth = identity_ground_truth(kCorridorImages, kCorridorImages, 2);
  struct Case {
    const char* name;
    LocaliserMatcher matcher;
    MetricKind metric;
    uint8_t max_shift;
    bool every_start;
  };
  const Case cases[] = {
      {"diagonal mad", LocaliserMatcher::kDiagonal, MetricKind::kMad, 0, false},
      {"diagonal mad shift 1", LocaliserMatcher::kDiagonal, MetricKind::kMad, 1, false},
      {"diagonal td", LocaliserMatcher::kDiagonal, MetricKind::kTangent, 0, false},
      {"slope mad", LocaliserMatcher::kSlope, MetricKind::kMad, 0, false},
      {"heuristic stream", LocaliserMatcher::kHeuristic, MetricKind::kMad, 0, false},
      {"heuristic every start", LocaliserMatcher::kHeuristic, MetricKind::kMad, 0, true},
  };
  for (const Case& c : cases) {
    EvalConfig config = corridor_config();
    config.localiser = config_of({Preprocessing::kHistEq, 10, 10, c.max_shift, 85});
    config.localiser.matcher = c.matcher;
    config.metric = c.metric;
    config.heuristic_every_start = c.every_start;
    const auto matrix = difference_matrix(library(), query(), config);
    ASSERT_TRUE(matrix.ok()) << matrix.error();
    const auto whole = evaluate_matrix(matrix.value(), config, &truth);
    ASSERT_TRUE(whole.ok()) << whole.error();
    EXPECT_EQ(whole.value().band_rows, kCorridorImages);
    // 1 row, a band that does not divide 111, one short of the whole, and automatic.
    for (const uint32_t band : {1u, 7u, 110u, 0u}) {
      config.band_rows = band;
      std::vector<uint32_t> seen;
      const auto banded = evaluate(library(), query(), config, &truth,
                                   [&](uint32_t done, uint32_t) { seen.push_back(done); });
      ASSERT_TRUE(banded.ok()) << banded.error();
      const std::string what = std::string(c.name) + ", band " + std::to_string(band);
      expect_same_matches(whole.value(), banded.value(), what);
      EXPECT_EQ(banded.value().summary.recall_at_100_precision,
                whole.value().summary.recall_at_100_precision)
          << what;
      // The every-start heuristic needs S rows a band; automatic bands take all 111 rows.
      const uint32_t expected_rows =
          band == 0 ? kCorridorImages : (c.every_start ? std::max(band, 10u) : band);
      EXPECT_EQ(banded.value().band_rows, expected_rows) << what;
      ASSERT_FALSE(seen.empty()) << what;
      EXPECT_EQ(seen.back(), kCorridorImages) << what << ": progress ends at every row";
      EXPECT_TRUE(std::is_sorted(seen.begin(), seen.end())) << what;
    }
  }
}

TEST(EvalPlan, MemoryFormulaAndRefusalWithTheFigure) {
  EvalConfig config = corridor_config();
  config.localiser.image_size = ImageSize{32, 16};
  config.localiser.sequence.seq_len = 30;
  // 30 000 x 30 000 places: the whole matrix alone would be 3.6 GB.
  constexpr uint32_t kPlaces = 30000;
  const EvalMemory whole = eval_memory(kPlaces, kPlaces, config, kPlaces);
  EXPECT_EQ(whole.images, uint64_t{2} * kPlaces * 512);
  EXPECT_EQ(whole.rows, uint64_t{kPlaces} * kPlaces * 4);
  EXPECT_EQ(whole.matcher, uint64_t{30} * kPlaces * 2 + uint64_t{kPlaces} * 5 +
                               uint64_t{kPlaces} * sizeof(QueryResult));
  EXPECT_EQ(whole.kept, 0u);
  const EvalMemory band = eval_memory(kPlaces, kPlaces, config, 1024);
  EXPECT_EQ(band.rows, uint64_t{1024} * kPlaces * 4);
  EXPECT_EQ(band.total(), band.images + band.rows + band.matcher);

  // Automatic: bands of 1 024 rows, 153 MB, inside the default limit.
  auto plan = plan_band_rows(kPlaces, kPlaces, config);
  ASSERT_TRUE(plan.ok()) << plan.error();
  EXPECT_EQ(plan.value(), kAutoBandRows);
  // A tighter limit halves the band until it fits: 64 MiB leaves room for 256 rows.
  config.max_memory = uint64_t{64} << 20;
  plan = plan_band_rows(kPlaces, kPlaces, config);
  ASSERT_TRUE(plan.ok()) << plan.error();
  EXPECT_EQ(plan.value(), 256u);
  EXPECT_LE(eval_memory(kPlaces, kPlaces, config, 256).total(), config.max_memory);
  EXPECT_GT(eval_memory(kPlaces, kPlaces, config, 512).total(), config.max_memory);
  // An explicit band over the limit, and a limit below the smallest band: refused with the
  // figure needed.
  config.band_rows = 4096;
  plan = plan_band_rows(kPlaces, kPlaces, config);
  ASSERT_FALSE(plan.ok());
  EXPECT_THAT(plan.error(), HasSubstr("needs 501 MiB"));
  EXPECT_THAT(plan.error(), HasSubstr("limit is 64 MiB"));
  config.band_rows = 0;
  config.max_memory = uint64_t{16} << 20;
  plan = plan_band_rows(kPlaces, kPlaces, config);
  ASSERT_FALSE(plan.ok());
  EXPECT_THAT(plan.error(), HasSubstr("smallest band needs 33 MiB"));
  // A report keeps the whole matrix: no band, and a clear refusal when it does not fit.
  config = corridor_config();
  config.keep_matrices = true;
  plan = plan_band_rows(kPlaces, kPlaces, config);
  ASSERT_FALSE(plan.ok());
  EXPECT_THAT(plan.error(), HasSubstr("whole matrix needs"));
  config.band_rows = 100;
  plan = plan_band_rows(1000, 1000, config);
  ASSERT_FALSE(plan.ok());
  EXPECT_THAT(plan.error(), HasSubstr("--band must be 0"));
  config.band_rows = 0;
  plan = plan_band_rows(1000, 1000, config);
  ASSERT_TRUE(plan.ok()) << plan.error();
  EXPECT_EQ(plan.value(), 1000u);
}

// ---------------------------------------------------------------------------------------
// 2. Ranges.

TEST(EvalRange, ParsesTheThreeForms) {
  auto r = parse_index_range("3:7");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r.value().first, 3);
  EXPECT_EQ(r.value().last, 7);
  EXPECT_FALSE(r.value().whole());
  r = parse_index_range("4:");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r.value().first, 4);
  EXPECT_LT(r.value().last, 0);
  r = parse_index_range(":9");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_EQ(r.value().first, 0);
  EXPECT_EQ(r.value().last, 9);
  r = parse_index_range("0:");
  ASSERT_TRUE(r.ok()) << r.error();
  EXPECT_TRUE(r.value().whole());
}

TEST(EvalRange, RejectsMalformedRangesWithMessages) {
  struct Case {
    const char* text;
    const char* message;
  };
  const Case cases[] = {
      {"5:3", "LAST must be above FIRST"}, {"5:5", "LAST must be above FIRST"},
      {"x:1", "'x' is not an index"},      {"1:y", "'y' is not an index"},
      {"-1:3", "'-1' is not an index"},    {"1", "expected FIRST:LAST"},
      {"1:2:3", "expected FIRST:LAST"},    {"", "expected FIRST:LAST"},
      {" 1:3", "is not an index"},
  };
  for (const Case& c : cases) {
    const auto r = parse_index_range(c.text);
    ASSERT_FALSE(r.ok()) << c.text;
    EXPECT_THAT(r.error(), HasSubstr(std::string("'") + c.text + "'")) << c.text;
    EXPECT_THAT(r.error(), HasSubstr(c.message)) << c.text;
  }
}

TEST_F(EvalCorridor, WholeInputIsDescribed) {
  EXPECT_EQ(library().kind, "directory");
  EXPECT_EQ(library().source, ref_dir());
  EXPECT_EQ(library().offset, 0u);
  EXPECT_EQ(library().source_size, kCorridorImages);
  ASSERT_EQ(library().images.size(), kCorridorImages);
  ASSERT_EQ(library().names.size(), kCorridorImages);
  EXPECT_THAT(library().names[5], HasSubstr("0000005.jpg"));
  EXPECT_TRUE(library().truth.empty());
  EXPECT_TRUE(library().odometry.empty());
  for (const GrayImage& img : library().images) {
    EXPECT_EQ(img.width, 32);
    EXPECT_EQ(img.height, 16);
    EXPECT_TRUE(img.valid());
  }
}

TEST_F(EvalCorridor, RangesSelectTheRightImages) {
  struct Case {
    IndexRange range;
    uint32_t first, count;
  };
  const Case cases[] = {{{10, 20}, 10, 10},
                        {{100, -1}, 100, 11},
                        {{0, 5}, 0, 5},
                        {{110, 111}, 110, 1},
                        {{0, 111}, 0, 111}};
  for (const Case& c : cases) {
    const auto in = load_input(query_dir(), 32, 16, c.range);
    ASSERT_TRUE(in.ok()) << in.error();
    const InputSequence& s = in.value();
    EXPECT_EQ(s.offset, c.first);
    EXPECT_EQ(s.source_size, kCorridorImages);
    ASSERT_EQ(s.images.size(), c.count);
    ASSERT_EQ(s.names.size(), c.count);
    for (uint32_t k = 0; k < c.count; ++k) {
      EXPECT_EQ(s.images[k].pixels, query().images[c.first + k].pixels) << c.first + k;
      EXPECT_EQ(s.names[k], query().names[c.first + k]);
    }
  }
  // Ranges that do not fit name the input and its size.
  for (const IndexRange r : {IndexRange{105, 120}, IndexRange{111, -1}, IndexRange{200, 300}}) {
    const auto in = load_input(query_dir(), 32, 16, r);
    ASSERT_FALSE(in.ok()) << r.first;
    EXPECT_THAT(in.error(), HasSubstr(query_dir()));
    EXPECT_THAT(in.error(), HasSubstr("111 images"));
  }
}

TEST_F(EvalCorridor, RangedEvaluationEqualsLocaliserOnTheSameImages) {
  const auto lib = load_input(ref_dir(), 32, 16, IndexRange{5, 80});
  const auto qry = load_input(query_dir(), 32, 16, IndexRange{20, 70});
  ASSERT_TRUE(lib.ok() && qry.ok());
  EvalConfig config = corridor_config();
  config.localiser.sequence.seq_len = 10;
  const auto r = evaluate(lib.value(), qry.value(), config, nullptr);
  ASSERT_TRUE(r.ok()) << r.error();
  const std::vector<GrayImage> lib_images(library().images.begin() + 5,
                                          library().images.begin() + 80);
  const std::vector<GrayImage> qry_images(query().images.begin() + 20, query().images.begin() + 70);
  const std::vector<Match> steps = localiser_steps(lib_images, qry_images, config.localiser);
  ASSERT_EQ(r.value().matches.size(), 50u);
  ASSERT_EQ(steps.size(), 50u);
  EXPECT_EQ(r.value().library_size, 75u);
  for (size_t q = 0; q < 50; ++q) {
    EXPECT_EQ(r.value().matches[q].query, q);  // positions in the ranged input
    EXPECT_EQ(r.value().matches[q].library, steps[q].place) << q;
    EXPECT_EQ(r.value().matches[q].runner_up, steps[q].runner_up) << q;
    EXPECT_EQ(r.value().matches[q].confidence, to_double(steps[q].confidence)) << q;
  }
}

// ---------------------------------------------------------------------------------------
// 3. Ground-truth specifications.

TEST_F(EvalCorridor, IdentityGroundTruthWholeInputs) {
  const auto gt = resolve_ground_truth("identity:2", library(), query());
  ASSERT_TRUE(gt.ok()) << gt.error();
  ASSERT_EQ(gt.value().matches.size(), kCorridorImages);
  EXPECT_THAT(gt.value().matches[0], ElementsAre(0u, 1u, 2u));
  EXPECT_THAT(gt.value().matches[50], ElementsAre(48u, 49u, 50u, 51u, 52u));
  EXPECT_THAT(gt.value().matches[110], ElementsAre(108u, 109u, 110u));
  const auto zero = resolve_ground_truth("identity:0", library(), query());
  ASSERT_TRUE(zero.ok()) << zero.error();
  EXPECT_THAT(zero.value().matches[7], ElementsAre(7u));
}

TEST_F(EvalCorridor, IdentityGroundTruthTranslatesRangedIndices) {
  const auto lib = load_input(ref_dir(), 32, 16, IndexRange{5, 30});
  const auto qry = load_input(query_dir(), 32, 16, IndexRange{10, 20});
  ASSERT_TRUE(lib.ok() && qry.ok());
  const auto gt = resolve_ground_truth("identity:2", lib.value(), qry.value());
  ASSERT_TRUE(gt.ok()) << gt.error();
  ASSERT_EQ(gt.value().matches.size(), 10u);
  // Query position q is source 10 + q; it matches sources 8+q .. 12+q = positions 3+q .. 7+q.
  for (uint32_t q = 0; q < 10; ++q) {
    EXPECT_THAT(gt.value().matches[q], ElementsAre(3 + q, 4 + q, 5 + q, 6 + q, 7 + q)) << q;
  }
  // Near and beyond the library's end: query range 20:40 (sources), library 5:30.
  const auto late = load_input(query_dir(), 32, 16, IndexRange{20, 40});
  ASSERT_TRUE(late.ok());
  const auto gt2 = resolve_ground_truth("identity:2", lib.value(), late.value());
  ASSERT_TRUE(gt2.ok()) << gt2.error();
  ASSERT_EQ(gt2.value().matches.size(), 20u);
  EXPECT_THAT(gt2.value().matches[0], ElementsAre(13u, 14u, 15u, 16u, 17u));  // source 20
  EXPECT_THAT(gt2.value().matches[10], ElementsAre(23u, 24u));                // source 30
  EXPECT_THAT(gt2.value().matches[11], ElementsAre(24u));                     // source 31
  EXPECT_THAT(gt2.value().matches[12], IsEmpty());                            // source 32
  EXPECT_FALSE(gt2.value().has_match(15));
}

TEST_F(EvalCorridor, CorridorCsvAsShippedAndRanged) {
  const std::string csv = test::corridor_dir() + "/ground_truth.csv";
  const auto file = load_ground_truth(csv);
  ASSERT_TRUE(file.ok()) << file.error();
  const auto gt = resolve_ground_truth(csv, library(), query());
  ASSERT_TRUE(gt.ok()) << gt.error();
  EXPECT_EQ(gt.value().matches, file.value().matches);

  const auto lib = load_input(ref_dir(), 32, 16, IndexRange{5, 30});
  const auto qry = load_input(query_dir(), 32, 16, IndexRange{10, 40});
  ASSERT_TRUE(lib.ok() && qry.ok());
  const auto ranged = resolve_ground_truth(csv, lib.value(), qry.value());
  ASSERT_TRUE(ranged.ok()) << ranged.error();
  ASSERT_EQ(ranged.value().matches.size(), 30u);
  size_t empty = 0;
  for (uint32_t q = 0; q < 30; ++q) {
    std::vector<uint32_t> want;
    for (const uint32_t ref : file.value().matches[q + 10]) {
      if (ref >= 5 && ref < 30) want.push_back(ref - 5);
    }
    EXPECT_EQ(ranged.value().matches[q], want) << q;
    empty += want.empty();
  }
  EXPECT_GT(empty, 0u);  // the translation was exercised at the library's end
  EXPECT_THAT(ranged.value().matches[0], ElementsAre(3u, 4u, 5u, 6u, 7u));
}

TEST_F(EvalCorridor, CsvBeyondTheInputsIsAnErrorNamingTheFile) {
  test::TempDir dir;
  const std::string query_beyond = dir.file("query_beyond.csv");
  test::write_file(query_beyond, "query_index,matching_reference_indices\n0,0 1\n111,110\n");
  auto gt = resolve_ground_truth(query_beyond, library(), query());
  ASSERT_FALSE(gt.ok());
  EXPECT_THAT(gt.error(), HasSubstr(query_beyond));
  EXPECT_THAT(gt.error(), HasSubstr("111"));

  const std::string lib_beyond = dir.file("library_beyond.csv");
  test::write_file(lib_beyond, "query_index,matching_reference_indices\n0,0 1\n3,2 111\n");
  gt = resolve_ground_truth(lib_beyond, library(), query());
  ASSERT_FALSE(gt.ok());
  EXPECT_THAT(gt.error(), HasSubstr(lib_beyond));
  EXPECT_THAT(gt.error(), HasSubstr("111"));

  // Judged against the sources, not the ranges: source index 50 is fine with a range 0:10.
  const auto lib = load_input(ref_dir(), 32, 16, IndexRange{0, 10});
  ASSERT_TRUE(lib.ok());
  const std::string in_source = dir.file("in_source.csv");
  test::write_file(in_source, "query_index,matching_reference_indices\n0,50\n");
  gt = resolve_ground_truth(in_source, lib.value(), query());
  ASSERT_TRUE(gt.ok()) << gt.error();
  EXPECT_THAT(gt.value().matches[0], IsEmpty());

  const std::string missing = dir.file("missing.csv");
  gt = resolve_ground_truth(missing, library(), query());
  ASSERT_FALSE(gt.ok());
  EXPECT_THAT(gt.error(), HasSubstr(missing));

  const std::string bad = dir.file("bad.csv");
  test::write_file(bad, "query_index,matching_reference_indices\n0,0 x\n");
  gt = resolve_ground_truth(bad, library(), query());
  ASSERT_FALSE(gt.ok());
  EXPECT_THAT(gt.error(), HasSubstr(bad + ":2"));
}

TEST_F(EvalCorridor, BadSpecsAndPosesWithoutPoses) {
  for (const char* spec : {"identity:", "identity:x", "identity:-1", "poses:", "poses:0",
                           "poses:-2", "poses:abc", "poses:1m"}) {
    const auto gt = resolve_ground_truth(spec, library(), query());
    ASSERT_FALSE(gt.ok()) << spec;
    EXPECT_THAT(gt.error(), HasSubstr(spec));
  }
  const auto gt = resolve_ground_truth("poses:1.5", library(), query());
  ASSERT_FALSE(gt.ok());
  EXPECT_THAT(gt.error(), HasSubstr("no true poses"));
  EXPECT_THAT(gt.error(), HasSubstr(ref_dir()));
}

// Two tiny simulated runs along the same 2 m of the lab's south lane (different seeds, so
// different drives), rendered with a small camera: dream recordings with true poses.
class EvalPoses : public ::testing::Test {
 protected:
  static sim::RunSpec spec(const std::string& name, uint64_t seed, bool backwards = false) {
    sim::RunSpec s;
    s.name = name;
    s.seed = seed;
    const sim::Point2 a{6.0, sim::lab::kSouthLane}, b{8.0, sim::lab::kSouthLane};
    s.legs = {sim::Leg{backwards ? std::vector<sim::Point2>{b, a} : std::vector<sim::Point2>{a, b},
                       false}};
    s.camera.width = 87;
    s.camera.height = 68;
    s.mapping.a11 = Q15_16::from_ratio(32, 87);
    s.mapping.a22 = Q15_16::from_ratio(16, 68);
    return s;
  }
  static void SetUpTestSuite() {
    dir_ = new test::TempDir();
    summaries_ = new sim::RunSummary[3];
    ASSERT_EQ(sim::generate_run(spec("lib", 1), dir_->path(), &summaries_[0]), "");
    ASSERT_EQ(sim::generate_run(spec("qry", 2), dir_->path(), &summaries_[1]), "");
    ASSERT_EQ(sim::generate_run(spec("back", 3, true), dir_->path(), &summaries_[2]), "");
  }
  static void TearDownTestSuite() {
    delete[] summaries_;
    delete dir_;
    summaries_ = nullptr;
    dir_ = nullptr;
  }
  static test::TempDir* dir_;
  static sim::RunSummary* summaries_;
};
test::TempDir* EvalPoses::dir_ = nullptr;
sim::RunSummary* EvalPoses::summaries_ = nullptr;

TEST_F(EvalPoses, PosesGroundTruthFromTruePoses) {
  ASSERT_NE(summaries_, nullptr);
  const auto lib = load_input(dir_->file("lib.dream"), 32, 16);
  const auto qry = load_input(dir_->file("qry.dream"), 32, 16);
  ASSERT_TRUE(lib.ok()) << lib.error();
  ASSERT_TRUE(qry.ok()) << qry.error();
  EXPECT_EQ(lib.value().kind, "dream");
  const sim::RunSummary& ls = summaries_[0];
  const sim::RunSummary& qs = summaries_[1];
  ASSERT_GE(ls.places.size(), 5u);
  ASSERT_EQ(lib.value().images.size(), ls.places.size());
  ASSERT_EQ(qry.value().images.size(), qs.places.size());
  ASSERT_EQ(lib.value().truth.size(), ls.places.size());
  ASSERT_EQ(qry.value().truth.size(), qs.places.size());
  EXPECT_EQ(lib.value().odometry.size(), ls.places.size());  // full recordings
  EXPECT_EQ(lib.value().names[3], "place 3");
  // The recorded true poses are the simulator's (fixed point: within 1e-6 m / 1e-6 rad).
  for (size_t i = 0; i < ls.places.size(); ++i) {
    EXPECT_NEAR(lib.value().truth[i].x, ls.places[i].truth.x, 1e-6) << i;
    EXPECT_NEAR(lib.value().truth[i].y, ls.places[i].truth.y, 1e-6) << i;
    EXPECT_NEAR(std::remainder(lib.value().truth[i].heading - ls.places[i].truth.heading, 2 * kPi),
                0.0, 1e-6)
        << i;
  }
  for (const double metres : {0.15, 0.5, 1.0}) {
    const auto gt =
        resolve_ground_truth("poses:" + std::to_string(metres), lib.value(), qry.value());
    ASSERT_TRUE(gt.ok()) << gt.error();
    ASSERT_EQ(gt.value().matches.size(), qs.places.size());
    size_t pairs = 0;
    for (size_t q = 0; q < qs.places.size(); ++q) {
      for (uint32_t j = 0; j < ls.places.size(); ++j) {
        const double d = std::hypot(qs.places[q].truth.x - ls.places[j].truth.x,
                                    qs.places[q].truth.y - ls.places[j].truth.y);
        if (std::fabs(d - metres) < 1e-5) continue;  // too close to the edge to judge
        // One lane, one direction: headings agree, the distance alone decides.
        EXPECT_EQ(gt.value().is_correct(static_cast<uint32_t>(q), j), d <= metres)
            << "q=" << q << " j=" << j << " d=" << d << " r=" << metres;
        pairs += d <= metres;
      }
    }
    EXPECT_GT(pairs, 0u) << metres;
  }
  // Ranged: positions relative to the ranges, the same pairs.
  const auto lib2 = load_input(dir_->file("lib.dream"), 32, 16, IndexRange{2, -1});
  const auto qry2 = load_input(dir_->file("qry.dream"), 32, 16, IndexRange{1, 4});
  ASSERT_TRUE(lib2.ok() && qry2.ok());
  EXPECT_EQ(lib2.value().offset, 2u);
  EXPECT_EQ(lib2.value().source_size, ls.places.size());
  EXPECT_EQ(lib2.value().images[0].pixels, lib.value().images[2].pixels);
  const auto whole = resolve_ground_truth("poses:0.5", lib.value(), qry.value());
  const auto ranged = resolve_ground_truth("poses:0.5", lib2.value(), qry2.value());
  ASSERT_TRUE(whole.ok() && ranged.ok());
  ASSERT_EQ(ranged.value().matches.size(), 3u);
  for (uint32_t q = 0; q < 3; ++q) {
    std::vector<uint32_t> want;
    for (const uint32_t j : whole.value().matches[q + 1]) {
      if (j >= 2) want.push_back(j - 2);
    }
    EXPECT_EQ(ranged.value().matches[q], want) << q;
  }
  // The same lane driven the other way: near in position, but headings 180 degrees apart.
  const auto back = load_input(dir_->file("back.dream"), 32, 16);
  ASSERT_TRUE(back.ok()) << back.error();
  const auto opposite = resolve_ground_truth("poses:1", lib.value(), back.value());
  ASSERT_TRUE(opposite.ok()) << opposite.error();
  size_t near = 0;
  for (size_t q = 0; q < summaries_[2].places.size(); ++q) {
    EXPECT_FALSE(opposite.value().has_match(static_cast<uint32_t>(q))) << q;
    for (const sim::PlaceTruth& p : ls.places) {
      near += std::hypot(summaries_[2].places[q].truth.x - p.truth.x,
                         summaries_[2].places[q].truth.y - p.truth.y) <= 1.0;
    }
  }
  EXPECT_GT(near, 0u);
  // Poses on one side only: an error naming the input without them.
  const auto images = load_input(query_dir(), 32, 16, IndexRange{0, 3});
  ASSERT_TRUE(images.ok());
  const auto bad = resolve_ground_truth("poses:0.5", lib.value(), images.value());
  ASSERT_FALSE(bad.ok());
  EXPECT_THAT(bad.error(), HasSubstr("no true poses"));
  EXPECT_THAT(bad.error(), HasSubstr(query_dir()));
}

// ---------------------------------------------------------------------------------------
// 4. The difference-matrix cache.

std::vector<fs::path> cache_files(const std::string& dir) {
  std::vector<fs::path> out;
  for (const auto& e : fs::directory_iterator(dir))
    out.push_back(e.path());
  std::sort(out.begin(), out.end());
  return out;
}

class EvalCache : public EvalCorridor {
 protected:
  void SetUp() override {
    EvalCorridor::SetUp();
    config_.localiser.sequence.seq_len = 10;
    config_.threads = 2;
    const auto plain = evaluate(library(), query(), config_, nullptr);
    ASSERT_TRUE(plain.ok()) << plain.error();
    plain_ = plain.value();
    ASSERT_FALSE(plain_.timing.matrix_from_cache);
    config_.cache_dir = dir_.path() + "/cache";  // created by evaluate()
    const auto first = evaluate(library(), query(), config_, nullptr);
    ASSERT_TRUE(first.ok()) << first.error();
    EXPECT_FALSE(first.value().timing.matrix_from_cache);
    expect_same_matches(first.value(), plain_, "first cached run");
    const auto files = cache_files(config_.cache_dir);
    ASSERT_EQ(files.size(), 1u);  // one matrix, no temporary left behind
    file_ = files[0].string();
    EXPECT_EQ(files[0].extension(), ".bin");
    file_size_ = fs::file_size(file_);
    // At least the matrix: 111 x 111 values of 4 bytes.
    EXPECT_GE(file_size_, uint64_t{kCorridorImages} * kCorridorImages * 4);
  }
  // Evaluates with the cache; the results must equal the uncached ones.
  bool evaluate_cached(const std::string& what) {
    const auto r = evaluate(library(), query(), config_, nullptr);
    EXPECT_TRUE(r.ok()) << what << ": " << r.error();
    if (!r.ok()) return false;
    expect_same_matches(r.value(), plain_, what);
    return r.value().timing.matrix_from_cache;
  }

  test::TempDir dir_;
  EvalConfig config_ = corridor_config();
  EvalResult plain_;
  std::string file_;
  uint64_t file_size_ = 0;
};

TEST_F(EvalCache, SecondRunReadsTheMatrix) {
  EXPECT_TRUE(evaluate_cached("second run"));
  // Other matcher settings re-use the same matrix.
  config_.localiser.sequence.window = 0;
  config_.localiser.sequence.threshold = UQ16_16::from_ratio(1, 2);
  config_.cache_dir.clear();
  const auto plain = evaluate(library(), query(), config_, nullptr);
  ASSERT_TRUE(plain.ok());
  plain_ = plain.value();
  config_.cache_dir = dir_.path() + "/cache";
  EXPECT_TRUE(evaluate_cached("other matcher settings"));
  EXPECT_EQ(cache_files(config_.cache_dir).size(), 1u);
  // Another difference setting is another matrix.
  config_.localiser.max_shift = 1;
  config_.cache_dir.clear();
  const auto shifted = evaluate(library(), query(), config_, nullptr);
  ASSERT_TRUE(shifted.ok());
  plain_ = shifted.value();
  config_.cache_dir = dir_.path() + "/cache";
  EXPECT_FALSE(evaluate_cached("max_shift 1, first"));
  EXPECT_EQ(cache_files(config_.cache_dir).size(), 2u);
  EXPECT_TRUE(evaluate_cached("max_shift 1, second"));
}

TEST_F(EvalCache, TruncatedFileIsRecomputed) {
  for (const uint64_t keep :
       {file_size_ - 1, file_size_ - 4, file_size_ / 2, uint64_t{12}, uint64_t{0}}) {
    fs::resize_file(file_, keep);
    EXPECT_FALSE(evaluate_cached("truncated to " + std::to_string(keep))) << keep;
    EXPECT_EQ(fs::file_size(file_), file_size_) << "rewritten";
    EXPECT_TRUE(evaluate_cached("after rewriting")) << keep;
  }
}

TEST_F(EvalCache, ExtendedFileIsRecomputed) {
  std::vector<uint8_t> bytes = test::read_file(file_);
  bytes.push_back(0);
  test::write_file(file_, bytes);
  EXPECT_FALSE(evaluate_cached("one byte appended"));
  EXPECT_EQ(fs::file_size(file_), file_size_);
}

TEST_F(EvalCache, DamagedHeaderIsRecomputed) {
  const std::vector<uint8_t> good = test::read_file(file_);
  for (const size_t at : {size_t{0}, size_t{7}, size_t{8}, size_t{15}, size_t{16}, size_t{20}}) {
    std::vector<uint8_t> bytes = good;
    bytes[at] ^= 0x5A;
    test::write_file(file_, bytes);
    EXPECT_FALSE(evaluate_cached("header byte " + std::to_string(at) + " flipped")) << at;
  }
}

// The matrix values themselves damaged, the file's size and header intact (a bad sector, a
// bit flip): the spec says a corrupted cache file is never trusted.
// (The cache header carries a hash of the values for this.)
TEST_F(EvalCache, DamagedValuesAreNotTrusted) {
  const std::vector<uint8_t> good = test::read_file(file_);
  const size_t body = size_t{kCorridorImages} * kCorridorImages * 4;  // after the header
  ASSERT_GE(good.size(), body);
  const auto check = [&](const std::vector<uint8_t>& bytes, const std::string& what) {
    test::write_file(file_, bytes);
    const auto r = evaluate(library(), query(), config_, nullptr);
    ASSERT_TRUE(r.ok()) << r.error();
    EXPECT_FALSE(r.value().timing.matrix_from_cache) << what << ": damaged cache file trusted";
    size_t differ = 0;
    for (size_t q = 0; q < r.value().matches.size(); ++q) {
      const QueryResult& a = r.value().matches[q];
      const QueryResult& b = plain_.matches[q];
      differ += a.library != b.library || a.runner_up != b.runner_up ||
                a.confidence != b.confidence || a.accepted != b.accepted;
    }
    EXPECT_EQ(differ, 0u) << what << ": queries whose results changed";
  };
  std::vector<uint8_t> bytes = good;
  std::fill(bytes.end() - static_cast<std::ptrdiff_t>(body), bytes.end(), uint8_t{0});
  check(bytes, "every value zeroed");
  bytes = good;
  bytes[bytes.size() - body + 4 * (60 * kCorridorImages + 60) + 2] ^= 0x40;  // q 60, place 60
  check(bytes, "one value changed");
}

// ---------------------------------------------------------------------------------------
// 5. The PR summary.

void expect_same_summary(const PrSummary& a, const PrSummary& b) {
  EXPECT_EQ(a.queries, b.queries);
  EXPECT_EQ(a.records, b.records);
  EXPECT_EQ(a.accepted_total, b.accepted_total);
  EXPECT_EQ(a.recall_at_100_precision, b.recall_at_100_precision);
  EXPECT_EQ(a.auc_pr, b.auc_pr);
  EXPECT_EQ(a.max_recall, b.max_recall);
  EXPECT_EQ(a.top1, b.top1);
  ASSERT_EQ(a.curve.size(), b.curve.size());
  for (size_t i = 0; i < a.curve.size(); ++i) {
    EXPECT_EQ(a.curve[i].confidence_threshold, b.curve[i].confidence_threshold) << i;
    EXPECT_EQ(a.curve[i].precision, b.curve[i].precision) << i;
    EXPECT_EQ(a.curve[i].recall, b.curve[i].recall) << i;
    EXPECT_EQ(a.curve[i].accepted, b.curve[i].accepted) << i;
    EXPECT_EQ(a.curve[i].true_positives, b.curve[i].true_positives) << i;
  }
}

TEST_F(EvalCorridor, SummaryEqualsEvaluatePrOverTheSameRecords) {
  // Library cut to 0:60 so that later queries have no correct place: the recall denominator
  // is still every query with a candidate (a full sequence), as the 2025 thesis counts, so
  // max recall stays below 1.
  const auto lib = load_input(ref_dir(), 32, 16, IndexRange{0, 60});
  ASSERT_TRUE(lib.ok());
  for (const char* spec : {"identity:2", "identity:0"}) {
    const auto gt = resolve_ground_truth(spec, lib.value(), query());
    ASSERT_TRUE(gt.ok()) << gt.error();
    EvalConfig config = corridor_config();
    config.localiser.sequence.seq_len = 10;
    const auto r = evaluate(lib.value(), query(), config, &gt.value());
    ASSERT_TRUE(r.ok()) << r.error();
    EXPECT_TRUE(r.value().has_ground_truth);
    std::vector<MatchRecord> records;
    size_t denominator = 0, candidates = 0, correct = 0, novel = 0;
    for (uint32_t q = 0; q < r.value().matches.size(); ++q) {
      const QueryResult& m = r.value().matches[q];
      EXPECT_EQ(m.has_truth, gt.value().has_match(q)) << q;
      EXPECT_EQ(m.correct,
                m.library >= 0 && gt.value().is_correct(q, static_cast<uint32_t>(m.library)))
          << q;
      if (m.library < 0) continue;
      ++candidates;
      correct += m.correct;
      records.push_back(MatchRecord{q, m.library, m.confidence, m.correct});
      ++denominator;
      if (!gt.value().has_match(q)) ++novel;
    }
    EXPECT_EQ(denominator, candidates) << spec;
    EXPECT_GT(novel, 0u) << spec;  // the case the definition matters for
    EXPECT_GT(correct, 0u) << spec;
    EXPECT_LT(correct, candidates) << spec;
    EXPECT_EQ(r.value().summary.queries, denominator) << spec;
    expect_same_summary(r.value().summary, evaluate_pr(records, denominator));

    // The same as scoring the Localiser's own matches (core_run.h).
    const std::vector<GrayImage> lib_images(library().images.begin(),
                                            library().images.begin() + 60);
    const auto core = run_core(lib_images, query().images, config.localiser);
    ASSERT_TRUE(core.ok()) << core.error();
    const GroundTruth& truth = gt.value();
    expect_same_summary(
        r.value().summary,
        score_matches(
            core.value(), [&](uint32_t q, uint32_t p) { return truth.is_correct(q, p); },
            [](uint32_t) { return true; }));
  }
}

TEST_F(EvalCorridor, CorridorScoresAsDocumented) {
  const auto gt =
      resolve_ground_truth(test::corridor_dir() + "/ground_truth.csv", library(), query());
  ASSERT_TRUE(gt.ok()) << gt.error();
  const auto r = evaluate(library(), query(), corridor_config(), &gt.value());
  ASSERT_TRUE(r.ok()) << r.error();
  const PrSummary& s = r.value().summary;
  EXPECT_EQ(s.queries, kCorridorImages - 29);  // S = 30: the first 29 have no full sequence
  EXPECT_EQ(s.top1, 1.0);
  EXPECT_EQ(s.recall_at_100_precision, 1.0);
  // Without a ground truth: no summary, no truth flags.
  const auto bare = evaluate(library(), query(), corridor_config(), nullptr);
  ASSERT_TRUE(bare.ok());
  EXPECT_FALSE(bare.value().has_ground_truth);
  EXPECT_EQ(bare.value().summary.queries, 0u);
}

}  // namespace
}  // namespace seqslam::tools
