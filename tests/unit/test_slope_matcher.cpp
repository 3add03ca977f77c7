// The slope matcher (time-sampled SeqSLAM): equal to the diagonal matcher with v = 1, equal
// to a double-precision direct search on synthetic routes at 0.8..1.2x speed, better than the
// diagonal on a 1.2x traversal, exact index rounding, and bad configuration.
#include "seqslam/slope_matcher.h"

#include "seqslam/sequence_matcher.h"
#include "synthetic.h"
#include "test.h"

#if defined(SEQSLAM_TEST_GTEST) && __has_include("reference.h")
// Host builds that link seqslam_reference also check against tools/reference.
#include <vector>

#include "reference.h"
#define SLOPE_TEST_HAS_REFERENCE 1
#endif

namespace seqslam {
namespace {

// ---- Equal to the diagonal matcher with vmin = vmax = 1 ----

TEST(SlopeMatcher, UnitVelocityEqualsDiagonalMatcher) {
  constexpr uint32_t kPlaces = 100;
  constexpr uint16_t kSeq = 7;
  static DiagonalMatcherStorage<kPlaces, kSeq> diag_storage;
  static SlopeMatcherStorage<kPlaces, kSeq> slope_storage;
  static uint32_t d[kPlaces];
  SlopeConfig cfg;
  cfg.seq.seq_len = kSeq;
  cfg.seq.window = 10;
  cfg.seq.exclusion = 5;
  cfg.vmin = UQ8_8::from_int(1);
  cfg.vmax = UQ8_8::from_int(1);
  cfg.vsteps = 1;
  DiagonalMatcher diag;
  SlopeMatcher slope;
  ASSERT_EQ(diag.configure(cfg.seq, 512, diag_storage.buffers()), Status::kOk);
  ASSERT_EQ(slope.configure(cfg, 512, slope_storage.buffers()), Status::kOk);
  test::Rng rng(60);
  uint32_t n = 30;
  uint32_t compared = 0;
  for (uint32_t i = 0; i < 60; ++i) {
    // The library mostly grows by one (loop-closure mode), sometimes jumps or shrinks.
    const uint32_t r = rng.below(10);
    if (r < 6) n = n < kPlaces ? n + 1 : n;
    if (r == 7) n = n + 5 < kPlaces ? n + 5 : kPlaces;
    if (r == 8) n = n > 10 ? n - 3 : n;
    if (i == 35) {
      diag.reset();
      slope.reset();
    }
    for (uint32_t j = 0; j < n; ++j)
      d[j] = 30000 + rng.below(20000);
    for (uint32_t j = 0; j < n; ++j) {
      if ((j + 7) % 50 == i % 50) d[j] = rng.below(8000);  // a planted diagonal
    }
    Match a;
    Match b;
    ASSERT_EQ(diag.step(Span<const uint32_t>(d, n), &a), Status::kOk);
    ASSERT_EQ(slope.step(Span<const uint32_t>(d, n), &b), Status::kOk);
    EXPECT_EQ(b.query, a.query);
    EXPECT_EQ(b.place, a.place) << "step " << i;
    EXPECT_EQ(b.cost, a.cost);
    EXPECT_EQ(b.runner_up, a.runner_up);
    EXPECT_EQ(b.runner_up_cost, a.runner_up_cost);
    EXPECT_EQ(b.confidence.raw(), a.confidence.raw());
    EXPECT_EQ(b.localised, a.localised);
    EXPECT_EQ(slope.confidence_offset(), diag.confidence_offset());
    for (uint32_t j = 0; j < kPlaces; ++j) {
      ASSERT_EQ(slope.full_sequence(j), diag.full_sequence(j)) << "step " << i << " place " << j;
      if (!diag.full_sequence(j)) continue;
      ASSERT_EQ(slope.cost(j), diag.cost(j)) << "step " << i << " place " << j;
      EXPECT_EQ(slope.velocity_raw(j), 256u);
      ++compared;
    }
  }
  EXPECT_GT(compared, 1000u);  // the comparison is not vacuous
}

// ---- Index rounding and velocity grid ----

TEST(SlopeMatcher, VelocityGridAndHalfUpOffsets) {
  SlopeConfig cfg;  // 0.8 .. 1.2 in 5 steps
  const uint16_t expected[5] = {205, 231, 256, 282, 307};
  for (uint32_t s = 0; s < 5; ++s)
    EXPECT_EQ(slope_velocity_raw(cfg, s), expected[s]) << "s " << s;
  // o_v(k) = round(v k) with ties up, so j - o = round(j - v k) half up.
  EXPECT_EQ(slope_offset(256, 9), 9u);
  EXPECT_EQ(slope_offset(128, 1), 0u);  // j - 0.5 -> j
  EXPECT_EQ(slope_offset(128, 3), 1u);  // j - 1.5 -> j - 1
  EXPECT_EQ(slope_offset(384, 1), 1u);  // j - 1.5 -> j - 1
  EXPECT_EQ(slope_offset(307, 5), 6u);  // 5.996 -> 6
  EXPECT_EQ(slope_offset(205, 5), 4u);  // 4.004 -> 4
  EXPECT_EQ(slope_offset(230, 5), 4u);  // 4.49 -> 4
  EXPECT_EQ(slope_offset(231, 5), 5u);  // 4.51 -> 5
}

// ---- Synthetic routes ----

constexpr uint32_t kWidth = 16;
constexpr uint32_t kHeight = 8;
constexpr uint32_t kPixels = kWidth * kHeight;
constexpr uint32_t kLibPlaces = 70;
constexpr uint32_t kColumnsPerPlace = 4;
constexpr uint32_t kQueries = 36;

using World = test::SyntheticWorld<512, kHeight>;

uint32_t sad(const uint8_t* a, const uint8_t* b) {
  uint32_t s = 0;
  for (uint32_t p = 0; p < kPixels; ++p)
    s += a[p] > b[p] ? static_cast<uint32_t>(a[p] - b[p]) : static_cast<uint32_t>(b[p] - a[p]);
  return s;
}

struct Route {
  uint8_t library[kLibPlaces][kPixels];
  uint32_t d[kQueries][kLibPlaces];  // raw SAD, query x library
  uint32_t truth_x8[kQueries];       // true library place of each query, in 1/8 places
};

// Library at kColumnsPerPlace columns per place; the query starts at place `start` and moves
// speed_pct / 100 places per step, with an appearance change.
void make_route(uint64_t seed, uint32_t start, uint32_t speed_pct, World& world, Route& r) {
  world.generate(seed, 512, kHeight);
  test::Rng rng(seed + 1);
  for (uint32_t j = 0; j < kLibPlaces; ++j)
    world.render(j, kColumnsPerPlace, 0, kWidth, 256, 0, 2, rng, r.library[j]);
  uint8_t q[kPixels];
  for (uint32_t i = 0; i < kQueries; ++i) {
    // Query position in 1/100 places, rendered to the nearest column.
    const uint32_t pos100 = start * 100 + speed_pct * i;
    const uint32_t col = (pos100 * kColumnsPerPlace + 50) / 100;
    r.truth_x8[i] = (pos100 * 8 + 50) / 100;
    world.render(0, 1, static_cast<int32_t>(col), kWidth, 230, 12, 4, rng, q);
    for (uint32_t j = 0; j < kLibPlaces; ++j)
      r.d[i][j] = sad(q, r.library[j]);
  }
}

// One in the raw units of the formats compared: D+ rows UQ5.11, velocities UQ8.8,
// confidences UQ16.16 (whose resolution is 1 / kConfidenceOne).
constexpr double kRowOne = static_cast<double>(UQ5_11::from_int(1).raw());
constexpr double kVelocityOne = static_cast<double>(UQ8_8::from_int(1).raw());
constexpr double kConfidenceOne = static_cast<double>(UQ16_16::from_int(1).raw());

// The double-precision direct search (what tools/reference's slope_match computes), on the
// same D+ rows converted to doubles: freestanding so it also runs on the target.
struct OracleMatch {
  int32_t place = -1;
  double confidence = 1.0;
};

OracleMatch oracle_step(const uint16_t (*rows)[kLibPlaces], uint32_t i, uint32_t seq_len,
                        const uint16_t* velocities, uint32_t vsteps, uint32_t exclusion) {
  static double cost[kLibPlaces];
  static bool valid[kLibPlaces];
  double min_value = 1e300;
  for (uint32_t k = 0; k <= i; ++k)
    for (uint32_t j = 0; j < kLibPlaces; ++j)
      if (rows[k][j] / kRowOne < min_value) min_value = rows[k][j] / kRowOne;
  for (uint32_t j = 0; j < kLibPlaces; ++j) {
    valid[j] = false;
    if (i + 1 < seq_len) continue;
    for (uint32_t s = 0; s < vsteps; ++s) {
      const double v = velocities[s] / kVelocityOne;
      double c = 0.0;
      bool ok = true;
      for (uint32_t k = 0; k < seq_len && ok; ++k) {
        // floor(j - v k + 1/2), exact in doubles for these small values.
        const double x = static_cast<double>(j) - v * k + 0.5;
        if (x < 0.0) {
          ok = false;
          break;
        }
        const uint32_t idx = static_cast<uint32_t>(x);  // x >= 0: truncation is floor
        c += rows[i - k][idx] / kRowOne;
      }
      if (ok && (!valid[j] || c < cost[j])) {
        cost[j] = c;
        valid[j] = true;
      }
    }
  }
  OracleMatch m;
  double best = 0.0;
  for (uint32_t j = 0; j < kLibPlaces; ++j) {
    if (valid[j] && (m.place < 0 || cost[j] < best)) {
      m.place = static_cast<int32_t>(j);
      best = cost[j];
    }
  }
  if (m.place < 0) return m;
  int32_t second = -1;
  double second_cost = 0.0;
  for (uint32_t j = 0; j < kLibPlaces; ++j) {
    const int32_t gap = static_cast<int32_t>(j) - m.place;
    if (!valid[j] || (gap < 0 ? -gap : gap) <= static_cast<int32_t>(exclusion)) continue;
    if (second < 0 || cost[j] < second_cost) {
      second = static_cast<int32_t>(j);
      second_cost = cost[j];
    }
  }
  const double offset = seq_len * min_value;
  if (second >= 0 && second_cost - offset > 0.0) {
    m.confidence = (best - offset) / (second_cost - offset);
  }
  return m;
}

TEST(SlopeMatcher, MatchesDoublePrecisionSearchAtSpeeds) {
  static World world;
  static Route route;
  static SlopeMatcherStorage<kLibPlaces, 10> storage;
  static uint16_t rows[kQueries][kLibPlaces];
  SlopeConfig cfg;  // vmin 0.8, vmax 1.2, 5 steps
  cfg.seq.seq_len = 10;
  cfg.seq.window = 20;
  cfg.seq.exclusion = 5;
  LocalNormaliser norm;
  ASSERT_EQ(norm.configure(cfg.seq.window, cfg.seq.sigma_min, kPixels), Status::kOk);
  uint16_t velocities[5];
  for (uint32_t s = 0; s < 5; ++s)
    velocities[s] = slope_velocity_raw(cfg, s);
  double max_error = 0.0;
  uint32_t matches = 0;
  uint32_t correct = 0;
  const uint32_t speeds[3] = {80, 100, 120};
  for (uint32_t t = 0; t < 3; ++t) {
    make_route(70 + t, 8, speeds[t], world, route);
    SlopeMatcher m;
    ASSERT_EQ(m.configure(cfg, kPixels, storage.buffers()), Status::kOk);
#if defined(SLOPE_TEST_HAS_REFERENCE)
    std::vector<std::vector<double>> ref_rows;
#endif
    for (uint32_t i = 0; i < kQueries; ++i) {
      norm.normalise_row(route.d[i], kLibPlaces, rows[i]);
      Match out;
      ASSERT_EQ(m.step(Span<const uint32_t>(route.d[i], kLibPlaces), &out), Status::kOk);
      const OracleMatch o =
          oracle_step(rows, i, cfg.seq.seq_len, velocities, cfg.vsteps, cfg.seq.exclusion);
      EXPECT_EQ(out.place, o.place) << "speed " << speeds[t] << " query " << i;
      const double err = out.confidence.raw() / kConfidenceOne - o.confidence;
      const double abs_err = err < 0 ? -err : err;
      if (abs_err > max_error) max_error = abs_err;
      EXPECT_LE(abs_err, 1.0 / kConfidenceOne) << "speed " << speeds[t] << " query " << i;
#if defined(SLOPE_TEST_HAS_REFERENCE)
      ref_rows.emplace_back();
      for (uint32_t j = 0; j < kLibPlaces; ++j)
        ref_rows.back().push_back(rows[i][j] / 2048.0);
      reference::Params p;
      p.seq_len = cfg.seq.seq_len;
      p.exclusion = cfg.seq.exclusion;
      std::vector<double> vs;
      for (uint32_t s = 0; s < 5; ++s)
        vs.push_back(velocities[s] / 256.0);
      const reference::Match r = reference::slope_match(p, ref_rows, vs).back();
      EXPECT_EQ(out.place, r.place);
      EXPECT_NEAR(out.confidence.raw() / 65536.0, r.confidence, 1.0 / 65536.0);
#endif
      if (out.place >= 0) {
        ++matches;
        const int32_t diff = out.place * 8 - static_cast<int32_t>(route.truth_x8[i]);
        if ((diff < 0 ? -diff : diff) <= 8) ++correct;
      }
    }
  }
  EXPECT_EQ(matches, 3 * (kQueries - 9));
  EXPECT_GE(correct * 10, matches * 9) << "the routes are found (within one place)";
  EXPECT_LT(max_error, 1.0 / kConfidenceOne);
  // Measured bound, reported for the record.
  EXPECT_LE(max_error * kConfidenceOne, 0.5 + 1e-6)
      << "max |confidence error| in LSB: " << max_error * kConfidenceOne;
}

TEST(SlopeMatcher, FasterTraversalFoundWithSlopesNotDiagonal) {
  static World world;
  static Route route;
  static SlopeMatcherStorage<kLibPlaces, 20> slope_storage;
  static DiagonalMatcherStorage<kLibPlaces, 20> diag_storage;
  SlopeConfig cfg;
  cfg.seq.seq_len = 20;
  cfg.seq.window = 20;
  cfg.seq.exclusion = 5;
  make_route(90, 2, 120, world, route);  // 1.2x the library's speed
  SlopeMatcher slope;
  DiagonalMatcher diag;
  ASSERT_EQ(slope.configure(cfg, kPixels, slope_storage.buffers()), Status::kOk);
  ASSERT_EQ(diag.configure(cfg.seq, kPixels, diag_storage.buffers()), Status::kOk);
  uint32_t slope_correct = 0;
  uint32_t diag_correct = 0;
  uint64_t slope_conf = 0;
  uint64_t diag_conf = 0;
  uint32_t fast = 0;
  uint32_t n = 0;
  for (uint32_t i = 0; i < kQueries; ++i) {
    Match a;
    Match b;
    ASSERT_EQ(slope.step(Span<const uint32_t>(route.d[i], kLibPlaces), &a), Status::kOk);
    ASSERT_EQ(diag.step(Span<const uint32_t>(route.d[i], kLibPlaces), &b), Status::kOk);
    if (i + 1 < cfg.seq.seq_len) continue;
    ASSERT_GE(a.place, 0);
    ASSERT_GE(b.place, 0);
    ++n;
    const int32_t t = static_cast<int32_t>(route.truth_x8[i]);
    const int32_t ea = a.place * 8 - t;
    const int32_t eb = b.place * 8 - t;
    if ((ea < 0 ? -ea : ea) <= 8) ++slope_correct;
    if ((eb < 0 ? -eb : eb) <= 8) ++diag_correct;
    slope_conf += a.confidence.raw();
    diag_conf += b.confidence.raw();
    if (slope.velocity_raw(static_cast<uint32_t>(a.place)) > 256) ++fast;
  }
  EXPECT_EQ(slope_correct, n) << "slopes find every query within one place";
  EXPECT_EQ(fast, n) << "and explain them with a velocity above 1";
  EXPECT_LT(diag_correct, n) << "the diagonal does not";
  EXPECT_LT(slope_conf, diag_conf) << "mean confidence (smaller is better)";
}

// ---- Bad configuration and input ----

TEST(SlopeMatcher, BadConfigurationAndInput) {
  static SlopeMatcherStorage<10, 4> storage;
  SlopeMatcher m;
  Match out;
  uint32_t d[11] = {};
  EXPECT_EQ(m.step(Span<const uint32_t>(d, 3), &out), Status::kFailedPrecondition);
  SlopeConfig cfg;
  cfg.seq.seq_len = 4;
  SlopeConfig bad = cfg;
  bad.vmin = UQ8_8::from_ratio(13, 10);  // vmin > vmax
  EXPECT_EQ(m.configure(bad, 512, storage.buffers()), Status::kInvalidArgument);
  bad = cfg;
  bad.vsteps = 0;
  EXPECT_EQ(m.configure(bad, 512, storage.buffers()), Status::kOutOfRange);
  bad.vsteps = kMaxVelocitySteps + 1;
  EXPECT_EQ(m.configure(bad, 512, storage.buffers()), Status::kOutOfRange);
  bad = cfg;
  bad.vmin = UQ8_8::from_int(0);
  EXPECT_EQ(m.configure(bad, 512, storage.buffers()), Status::kOutOfRange);
  bad = cfg;
  bad.vmax = UQ8_8::from_ratio(41, 10);  // above 4.0
  EXPECT_EQ(m.configure(bad, 512, storage.buffers()), Status::kOutOfRange);
  bad = cfg;
  bad.vsteps = 1;  // one velocity but vmin != vmax
  EXPECT_EQ(m.configure(bad, 512, storage.buffers()), Status::kInvalidArgument);
  bad = cfg;
  bad.seq.seq_len = 0;  // the sequence checks come first
  EXPECT_EQ(m.configure(bad, 512, storage.buffers()), Status::kOutOfRange);
  bad = cfg;
  bad.seq.sigma_min = UQ8_8::from_int(0);
  EXPECT_EQ(m.configure(bad, 512, storage.buffers()), Status::kInvalidArgument);
  // S = 30 but a ring of 20 entries: not even one place fits.
  bad = cfg;
  bad.seq.seq_len = 30;
  uint16_t ring[20];
  uint32_t cost[10];
  uint8_t velocity[10];
  const SlopeMatcherBuffers tiny{Span<uint16_t>(ring, 20), Span<uint32_t>(cost, 10),
                                 Span<uint8_t>(velocity, 10)};
  EXPECT_EQ(m.configure(bad, 512, tiny), Status::kResourceExhausted);
  const SlopeMatcherBuffers no_velocity{Span<uint16_t>(ring, 20), Span<uint32_t>(cost, 10),
                                        Span<uint8_t>()};
  EXPECT_EQ(m.configure(cfg, 512, no_velocity), Status::kResourceExhausted);
  EXPECT_EQ(m.configure(cfg, 0, storage.buffers()), Status::kOutOfRange);
  // Still unconfigured after every failure.
  EXPECT_EQ(m.step(Span<const uint32_t>(d, 3), &out), Status::kFailedPrecondition);
  ASSERT_EQ(m.configure(cfg, 512, storage.buffers()), Status::kOk);
  EXPECT_EQ(m.capacity(), 10u);
  EXPECT_EQ(m.step(Span<const uint32_t>(d, 11), &out), Status::kOutOfRange);  // library full
  EXPECT_EQ(m.steps(), 0u);
  EXPECT_EQ(m.step(Span<const uint32_t>(d, 10), &out), Status::kOk);
  EXPECT_EQ(out.place, -1);
  static_assert(SlopeMatcherStorage<10, 4>::kBytes == 2 * 4 * 10 + 4 * 10 + 10, "kBytes");
}

}  // namespace
}  // namespace seqslam
