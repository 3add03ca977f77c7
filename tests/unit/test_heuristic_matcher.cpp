// The greedy heuristic matcher (Algorithm 1): the true place on a synthetic route, the
// threshold's "unknown place", the guard window and k on hand-made distance profiles, the
// anytime query, trails leaving the library, bad configuration, and a cross-check against the
// rule evaluated plainly over a full distance table.
#include "seqslam/heuristic_matcher.h"

#include "seqslam/difference.h"
#include "seqslam/place_library.h"
#include "synthetic.h"
#include "test.h"

namespace seqslam {
namespace {

constexpr uint32_t kTableSteps = 40;
constexpr uint32_t kTablePlaces = 80;

// Distances from a table d[query][place], counting evaluations; can be told to fail.
class TableDistance final : public PlaceDistance {
 public:
  uint32_t d[kTableSteps][kTablePlaces] = {};
  uint32_t evaluations = 0;
  uint32_t fail_at = 0xFFFFFFFFu;  // evaluation number that returns kUnavailable

  void fill(uint32_t value) {
    for (auto& row : d) {
      for (uint32_t& v : row)
        v = value;
    }
  }

 private:
  Status do_distance(uint32_t query, uint32_t place, uint32_t* out) override {
    if (query >= kTableSteps || place >= kTablePlaces) return Status::kOutOfRange;
    if (evaluations++ == fail_at) return Status::kUnavailable;
    *out = d[query][place];
    return Status::kOk;
  }
};

HeuristicConfig table_config(uint16_t k, uint16_t guard, uint16_t seq_len) {
  HeuristicConfig c;
  c.candidates = k;
  c.guard = guard;
  c.seq_len = seq_len;
  c.threshold = UQ8_8::from_int(100);  // with pixels = 16: distances below 1600 pass
  c.exclusion = 2;
  return c;
}
constexpr uint32_t kTablePixels = 16;

// Synthetic route: library places 0..kPlaces-1 as rendered images (in a PlaceLibrary over RAM
// images, the same interface as the SD-card store), query images rendered with an appearance
// change; the distance is the plain SAD.
constexpr uint16_t kW = 16;
constexpr uint16_t kH = 8;
constexpr uint32_t kPlaces = 60;
constexpr uint32_t kQueries = 12;

class LibraryDistance final : public PlaceDistance {
 public:
  PlaceLibrary* library = nullptr;
  uint8_t queries[kQueries][kW * kH] = {};

 private:
  Status do_distance(uint32_t query, uint32_t place, uint32_t* out) override {
    if (query >= kQueries) return Status::kOutOfRange;
    ImageView image;
    const Status s = library->image(place, &image);
    if (s != Status::kOk) return s;
    const Result<uint32_t> r = sad(ImageView{queries[query], ImageSize{kW, kH}}, image);
    if (!r.ok()) return r.status();
    *out = r.value();
    return Status::kOk;
  }
};

struct Route {
  test::SyntheticWorld<200, kH> world;
  test::SyntheticWorld<200, kH> other;  // a place the library never saw
  PlaceLibraryStorage<kPlaces, kW * kH> storage;
  PlaceLibrary library;
  LibraryDistance distance;
  uint8_t image[kW * kH];
};

Route g_route;

// Builds the library from world seed 5 and queries of places first..first+count-1 (or of the
// unrelated world when `unknown`).
void build_route(uint32_t first, uint32_t count, bool unknown) {
  Route& r = g_route;
  r.world.generate(5, 200, kH);
  r.other.generate(77, 200, kH);
  ASSERT_EQ(r.storage.attach(r.library, ImageSize{kW, kH}), Status::kOk);
  test::Rng rng(6);
  for (uint32_t p = 0; p < kPlaces; ++p) {
    r.world.render(p, 3, 0, kW, 256, 0, 3, rng, r.image);
    ASSERT_EQ(r.library.add(ImageView{r.image, ImageSize{kW, kH}}, Pose2{}, p), Status::kOk);
  }
  r.distance.library = &r.library;
  for (uint32_t i = 0; i < count; ++i) {
    const auto& w = unknown ? r.other : r.world;
    w.render(first + i, 3, 0, kW, 240, 8, 4, rng, r.distance.queries[i]);
  }
}

TEST(HeuristicMatcher, FindsTheTruePlaceOnASyntheticRoute) {
  build_route(23, 10, false);
  HeuristicConfig cfg;
  cfg.candidates = 4;
  cfg.guard = 4;
  cfg.seq_len = 10;
  cfg.threshold = UQ8_8::from_int(40);
  HeuristicMatcher m;
  ASSERT_EQ(m.configure(cfg, kW * kH), Status::kOk);
  HeuristicMatch out;
  for (uint32_t i = 0; i < 10; ++i) {
    ASSERT_EQ(m.step(g_route.distance, kPlaces, &out), Status::kOk);
    EXPECT_EQ(out.complete, i == 9);
  }
  EXPECT_EQ(out.start, 23);
  EXPECT_EQ(out.place, 23 + 9);
  EXPECT_LT(out.confidence.raw(), UQ16_16::from_int(1).raw());
  EXPECT_EQ(m.next_offset(), 0u);  // disjoint: the next step starts a new sequence
}

TEST(HeuristicMatcher, UnknownPlaceGivesMinusOneWithATightThreshold) {
  build_route(0, 10, true);
  HeuristicConfig cfg;
  cfg.candidates = 4;
  cfg.guard = 4;
  cfg.seq_len = 10;
  cfg.threshold = UQ8_8::from_int(12);  // MAD of 12 grey levels: the true place passes (above)
  HeuristicMatcher m;
  ASSERT_EQ(m.configure(cfg, kW * kH), Status::kOk);
  HeuristicMatch out;
  for (uint32_t i = 0; i < 10; ++i)
    ASSERT_EQ(m.step(g_route.distance, kPlaces, &out), Status::kOk);
  EXPECT_TRUE(out.complete);
  EXPECT_EQ(out.place, -1);
  EXPECT_EQ(out.start, -1);
  EXPECT_EQ(out.candidates, 0u);
  // The same threshold accepts the known route (so the -1 above is the threshold's doing).
  build_route(23, 10, false);
  ASSERT_EQ(m.configure(cfg, kW * kH), Status::kOk);
  for (uint32_t i = 0; i < 10; ++i)
    ASSERT_EQ(m.step(g_route.distance, kPlaces, &out), Status::kOk);
  EXPECT_EQ(out.place, 23 + 9);
  // And a loose threshold matches the unknown route somewhere (a wrong place).
  build_route(0, 10, true);
  cfg.threshold = UQ8_8::from_int(255);
  ASSERT_EQ(m.configure(cfg, kW * kH), Status::kOk);
  for (uint32_t i = 0; i < 10; ++i)
    ASSERT_EQ(m.step(g_route.distance, kPlaces, &out), Status::kOk);
  EXPECT_GE(out.place, 0);
}

TEST(HeuristicMatcher, GuardWindowKeepsOneCandidatePerLocalMinimum) {
  static TableDistance t;
  t.fill(5000);  // above the threshold (1600)
  // A broad valley 2..8 with its minimum at 5 and a shoulder at 8 (within the guard of 5),
  // then a second valley at 14..16 (minimum 15), an isolated dip at 30.
  const uint32_t profile[][2] = {{2, 1500}, {3, 1200},  {4, 900},  {5, 500},   {6, 700},  {7, 650},
                                 {8, 600},  {14, 1000}, {15, 800}, {16, 1100}, {30, 1400}};
  for (const auto& p : profile)
    t.d[0][p[0]] = p[1];
  HeuristicMatcher m;
  ASSERT_EQ(m.configure(table_config(8, 3, 5), kTablePixels), Status::kOk);
  HeuristicMatch out;
  ASSERT_EQ(m.step(t, kTablePlaces, &out), Status::kOk);
  EXPECT_EQ(t.evaluations, kTablePlaces);  // the greedy step sees every place once
  ASSERT_EQ(m.candidate_count(), 3u);
  EXPECT_EQ(m.candidate_start(0), 5u);
  EXPECT_EQ(m.candidate_sum(0), 500u);
  EXPECT_EQ(m.candidate_start(1), 15u);
  EXPECT_EQ(m.candidate_start(2), 30u);
  EXPECT_EQ(out.start, 5);
  EXPECT_EQ(out.offset, 0u);
  EXPECT_FALSE(out.complete);

  // With guard 1 the window has left minimum 5 by place 7, so 7..8 form a second minimum (8).
  ASSERT_EQ(m.configure(table_config(8, 1, 5), kTablePixels), Status::kOk);
  ASSERT_EQ(m.step(t, kTablePlaces, &out), Status::kOk);
  ASSERT_EQ(m.candidate_count(), 4u);
  EXPECT_EQ(m.candidate_start(0), 5u);
  EXPECT_EQ(m.candidate_start(1), 8u);
  EXPECT_EQ(m.candidate_start(2), 15u);
  EXPECT_EQ(m.candidate_start(3), 30u);
}

TEST(HeuristicMatcher, KLimitsTheCandidates) {
  static TableDistance t;
  t.fill(5000);
  // Four isolated minima: 10 (400), 25 (900), 40 (300), 55 (700).
  t.d[0][10] = 400;
  t.d[0][25] = 900;
  t.d[0][40] = 300;
  t.d[0][55] = 700;
  HeuristicMatcher m;
  ASSERT_EQ(m.configure(table_config(3, 4, 5), kTablePixels), Status::kOk);
  HeuristicMatch out;
  ASSERT_EQ(m.step(t, kTablePlaces, &out), Status::kOk);
  ASSERT_EQ(m.candidate_count(), 3u);  // the 4th best minimum (25, 900) is dropped
  EXPECT_EQ(m.candidate_start(0), 10u);
  EXPECT_EQ(m.candidate_start(1), 40u);
  EXPECT_EQ(m.candidate_start(2), 55u);
  // The following steps evaluate only the k trails.
  t.evaluations = 0;
  for (int i = 0; i < 4; ++i)
    ASSERT_EQ(m.step(t, kTablePlaces, &out), Status::kOk);
  EXPECT_EQ(t.evaluations, 4u * 3u);
  EXPECT_TRUE(out.complete);
  EXPECT_EQ(out.start, 40);

  ASSERT_EQ(m.configure(table_config(4, 4, 5), kTablePixels), Status::kOk);
  ASSERT_EQ(m.step(t, kTablePlaces, &out), Status::kOk);
  EXPECT_EQ(m.candidate_count(), 4u);
}

TEST(HeuristicMatcher, AnytimeQueryReportsTheCurrentBest) {
  static TableDistance t;
  t.fill(5000);
  t.d[0][10] = 100;  // candidate A leads after the first image ...
  t.d[0][40] = 300;  // ... candidate B second
  for (uint32_t o = 1; o < 6; ++o) {
    t.d[o][10 + o] = 400;
    t.d[o][40 + o] = 150;  // ... but B's trail is better: it overtakes at offset 2
  }
  HeuristicMatcher m;
  ASSERT_EQ(m.configure(table_config(4, 3, 6), kTablePixels), Status::kOk);
  EXPECT_EQ(m.current().place, -1);  // before the first step
  HeuristicMatch out;
  ASSERT_EQ(m.step(t, kTablePlaces, &out), Status::kOk);
  EXPECT_EQ(m.current().place, 10);
  EXPECT_EQ(m.current().sum, 100u);
  ASSERT_EQ(m.step(t, kTablePlaces, &out), Status::kOk);  // A 500, B 450
  HeuristicMatch now = m.current();
  EXPECT_EQ(now.place, 41);
  EXPECT_EQ(now.start, 40);
  EXPECT_EQ(now.sum, 450u);
  EXPECT_EQ(now.offset, 1u);
  EXPECT_FALSE(now.complete);
  EXPECT_EQ(now.runner_up, 11);
  EXPECT_EQ(now.runner_up_sum, 500u);
  EXPECT_EQ(now.confidence.raw(), UQ16_16::from_ratio(450, 500).raw());
  for (int i = 0; i < 4; ++i)
    ASSERT_EQ(m.step(t, kTablePlaces, &out), Status::kOk);
  EXPECT_TRUE(out.complete);
  EXPECT_EQ(out.place, 45);
  EXPECT_EQ(out.sum, 300u + 5u * 150u);
  EXPECT_EQ(m.current().place, 45);  // the answer stays readable until the next step
  // The runner-up must be more than R away: with R = 30 the two are not compared.
  HeuristicConfig cfg = table_config(4, 3, 6);
  cfg.exclusion = 30;
  ASSERT_EQ(m.configure(cfg, kTablePixels), Status::kOk);
  for (int i = 0; i < 6; ++i)
    ASSERT_EQ(m.step(t, kTablePlaces, &out), Status::kOk);
  EXPECT_EQ(out.runner_up, -1);
  EXPECT_EQ(out.confidence.raw(), UQ16_16::from_int(1).raw());
}

TEST(HeuristicMatcher, TrailsLeavingTheLibraryAreDropped) {
  static TableDistance t;
  t.fill(5000);
  t.d[0][20] = 900;
  t.d[0][76] = 100;  // best first image, but 76 + 5 runs past the 80 places
  for (uint32_t o = 1; o < 6; ++o) {
    t.d[o][20 + o] = 900;
    if (76 + o < kTablePlaces) t.d[o][76 + o] = 100;
  }
  HeuristicMatcher m;
  ASSERT_EQ(m.configure(table_config(4, 2, 6), kTablePixels), Status::kOk);
  HeuristicMatch out;
  for (uint32_t o = 0; o < 6; ++o) {
    ASSERT_EQ(m.step(t, kTablePlaces, &out), Status::kOk);
    if (o <= 3) {
      EXPECT_EQ(out.start, 76) << "offset " << o;
      EXPECT_EQ(out.candidates, 2u);
    } else {
      EXPECT_EQ(out.start, 20) << "offset " << o;  // 76's trail left at offset 4
      EXPECT_EQ(out.candidates, 1u);
    }
  }
  EXPECT_EQ(out.place, 25);
  EXPECT_EQ(out.sum, 6u * 900u);
  // Only the trail that leaves: the sequence ends unknown.
  t.d[6][20] = 5000;
  t.d[6][76] = 100;
  for (uint32_t o = 1; o < 6; ++o) {
    if (76 + o < kTablePlaces) t.d[6 + o][76 + o] = 100;
  }
  for (uint32_t o = 0; o < 6; ++o)
    ASSERT_EQ(m.step(t, kTablePlaces, &out), Status::kOk);
  EXPECT_TRUE(out.complete);
  EXPECT_EQ(out.place, -1);
  EXPECT_EQ(out.candidates, 0u);
}

TEST(HeuristicMatcher, BadConfigurationAndFailingDistances) {
  static TableDistance t;
  HeuristicMatcher m;
  HeuristicMatch out;
  EXPECT_EQ(m.step(t, kTablePlaces, &out), Status::kFailedPrecondition);
  HeuristicIssue issue = HeuristicIssue::kNone;
  HeuristicConfig c = table_config(0, 3, 5);
  EXPECT_EQ(check_heuristic_config(c, 16, &issue), Status::kOutOfRange);
  EXPECT_EQ(issue, HeuristicIssue::kCandidatesOutOfRange);
  EXPECT_EQ(m.configure(c, 16), Status::kOutOfRange);
  c = table_config(kMaxHeuristicCandidates + 1, 3, 5);
  EXPECT_EQ(check_heuristic_config(c, 16, &issue), Status::kOutOfRange);
  EXPECT_EQ(issue, HeuristicIssue::kCandidatesOutOfRange);
  c = table_config(3, 0, 5);
  EXPECT_EQ(check_heuristic_config(c, 16, &issue), Status::kOutOfRange);
  EXPECT_EQ(issue, HeuristicIssue::kGuardZero);
  c = table_config(3, 3, 0);
  EXPECT_EQ(check_heuristic_config(c, 16, &issue), Status::kOutOfRange);
  EXPECT_EQ(issue, HeuristicIssue::kSeqLenOutOfRange);
  c = table_config(3, 3, kMaxSeqLen + 1);
  EXPECT_EQ(check_heuristic_config(c, 16, &issue), Status::kOutOfRange);
  EXPECT_EQ(issue, HeuristicIssue::kSeqLenOutOfRange);
  c = table_config(3, 3, 5);
  EXPECT_EQ(check_heuristic_config(c, 0, &issue), Status::kOutOfRange);
  EXPECT_EQ(issue, HeuristicIssue::kPixelsOutOfRange);
  EXPECT_EQ(check_heuristic_config(c, kMaxPixels + 1, &issue), Status::kOutOfRange);
  EXPECT_EQ(issue, HeuristicIssue::kPixelsOutOfRange);
  EXPECT_EQ(
      check_heuristic_config(table_config(kMaxHeuristicCandidates, 1, kMaxSeqLen), 16, &issue),
      Status::kOk);
  EXPECT_EQ(issue, HeuristicIssue::kNone);
  EXPECT_EQ(m.step(t, kTablePlaces, &out), Status::kFailedPrecondition);  // still unconfigured

  // A failing distance (storage) leaves the matcher untouched; the step can be retried.
  t.fill(5000);
  t.d[0][10] = 100;
  t.d[1][11] = 100;
  ASSERT_EQ(m.configure(table_config(3, 3, 5), kTablePixels), Status::kOk);
  t.evaluations = 0;
  t.fail_at = 40;
  out.place = 1234;
  EXPECT_EQ(m.step(t, kTablePlaces, &out), Status::kUnavailable);
  EXPECT_EQ(out.place, 1234);
  EXPECT_EQ(m.query(), 0u);
  EXPECT_EQ(m.candidate_count(), 0u);
  t.fail_at = 0xFFFFFFFFu;
  ASSERT_EQ(m.step(t, kTablePlaces, &out), Status::kOk);
  EXPECT_EQ(out.start, 10);
  t.evaluations = 0;
  t.fail_at = 0;
  EXPECT_EQ(m.step(t, kTablePlaces, &out), Status::kUnavailable);
  EXPECT_EQ(m.query(), 1u);
  EXPECT_EQ(m.candidate_sum(0), 100u);
  t.fail_at = 0xFFFFFFFFu;
  ASSERT_EQ(m.step(t, kTablePlaces, &out), Status::kOk);
  EXPECT_EQ(out.sum, 200u);
  EXPECT_EQ(out.place, 11);
}

// ---- Cross-check: the rule of the header evaluated plainly over the whole table. ----

struct Expected {
  int32_t start = -1;
  uint32_t sum = 0;
  int32_t runner_start = -1;
  uint32_t runner_sum = 0;
  uint32_t live = 0;
};

// Query rows first..first+offset of one sequence over `places` places.
// `from`: the first trail offset compared (1, or K - 1 when the first image's scan took K >= 2
// steps; offsets 1..from-1 are skipped).
Expected brute_force(const TableDistance& t, uint32_t first, uint32_t offset, uint32_t places,
                     const HeuristicConfig& c, uint32_t pixels, uint32_t from = 1) {
  const uint32_t* d0 = t.d[first];
  const uint64_t limit = static_cast<uint64_t>(c.threshold.raw()) * pixels;
  // The guard-window minima, walked segment by segment.
  uint32_t minima[kTablePlaces];
  uint32_t n = 0;
  uint32_t p = 0;
  while (true) {
    uint32_t s = p;
    while (s < places && (static_cast<uint64_t>(d0[s]) << 8) >= limit)
      ++s;
    if (s >= places) break;
    uint32_t mpos = s;
    bool moved = true;
    while (moved) {
      moved = false;
      for (uint32_t j = mpos + 1; j <= mpos + c.guard && j < places; ++j) {
        if (d0[j] < d0[mpos]) {
          mpos = j;
          moved = true;
          break;
        }
      }
    }
    minima[n++] = mpos;
    p = mpos + c.guard + 1;
  }
  // The k smallest first distances (ties: smaller place), by repeated selection.
  bool chosen[kTablePlaces] = {};
  uint32_t picked[kMaxHeuristicCandidates];
  uint32_t npicked = 0;
  for (uint32_t r = 0; r < c.candidates && r < n; ++r) {
    uint32_t best = n;
    for (uint32_t i = 0; i < n; ++i) {
      if (chosen[i]) continue;
      if (best == n || d0[minima[i]] < d0[minima[best]]) best = i;
    }
    chosen[best] = true;
    picked[npicked++] = minima[best];
  }
  // Direct trail sums of the candidates still inside the library.
  Expected e;
  uint32_t sums[kMaxHeuristicCandidates];
  bool live[kMaxHeuristicCandidates];
  for (uint32_t i = 0; i < npicked; ++i) {
    live[i] = picked[i] + offset < places;
    sums[i] = 0;
    if (!live[i]) continue;
    ++e.live;
    for (uint32_t o = 0; o <= offset; ++o) {
      if (o == 0 || o >= from) sums[i] += t.d[first + o][picked[i] + o];
    }
  }
  for (uint32_t i = 0; i < npicked; ++i) {
    if (!live[i]) continue;
    const int32_t s = static_cast<int32_t>(picked[i]);
    if (e.start < 0 || sums[i] < e.sum || (sums[i] == e.sum && s < e.start)) {
      e.start = s;
      e.sum = sums[i];
    }
  }
  for (uint32_t i = 0; i < npicked && e.start >= 0; ++i) {
    const int32_t s = static_cast<int32_t>(picked[i]);
    const int32_t gap = s > e.start ? s - e.start : e.start - s;
    if (!live[i] || gap <= static_cast<int32_t>(c.exclusion)) continue;
    if (e.runner_start < 0 || sums[i] < e.runner_sum ||
        (sums[i] == e.runner_sum && s < e.runner_start)) {
      e.runner_start = s;
      e.runner_sum = sums[i];
    }
  }
  return e;
}

TEST(HeuristicMatcher, MatchesThePlainRuleOnRandomData) {
  static TableDistance t;
  test::Rng rng(2015);
  uint32_t sequences_with_answer = 0;
  uint32_t sequences_without = 0;
  for (uint32_t trial = 0; trial < 24; ++trial) {
    // Rough random profiles with plateaus (ties) and planted low trails.
    for (uint32_t i = 0; i < kTableSteps; ++i) {
      uint32_t v = 1000 + rng.below(2000);
      for (uint32_t j = 0; j < kTablePlaces; ++j) {
        if (rng.below(3) != 0)
          v = 200 + rng.below(30) * 100 + (rng.below(4) == 0 ? rng.below(100) : 0);
        t.d[i][j] = v;
      }
      for (uint32_t j = 0; j < kTablePlaces; ++j) {
        if ((j + 13 * trial) % 37 == i % 37) t.d[i][j] = rng.below(8) * 50;
      }
    }
    HeuristicConfig c;
    c.candidates = static_cast<uint16_t>(1 + rng.below(kMaxHeuristicCandidates));
    c.guard = static_cast<uint16_t>(1 + rng.below(8));
    c.seq_len = static_cast<uint16_t>(1 + rng.below(9));
    c.threshold = UQ8_8::from_raw(static_cast<uint16_t>(rng.below(200 * 256)));
    c.exclusion = static_cast<uint16_t>(rng.below(12));
    HeuristicMatcher m;
    ASSERT_EQ(m.configure(c, kTablePixels), Status::kOk);
    const uint32_t places = trial % 4 == 0 ? kTablePlaces - rng.below(20) : kTablePlaces;
    for (uint32_t i = 0; i < kTableSteps; ++i) {
      HeuristicMatch out;
      ASSERT_EQ(m.step(t, places, &out), Status::kOk);
      const uint32_t offset = i % c.seq_len;
      const Expected e = brute_force(t, i - offset, offset, places, c, kTablePixels);
      ASSERT_EQ(out.offset, offset) << "trial " << trial << " step " << i;
      ASSERT_EQ(out.start, e.start) << "trial " << trial << " step " << i;
      ASSERT_EQ(out.candidates, e.live) << "trial " << trial << " step " << i;
      if (offset + 1 == c.seq_len) {
        ASSERT_TRUE(out.complete);
        if (e.start >= 0) {
          ++sequences_with_answer;
        } else {
          ++sequences_without;
        }
      }
      if (e.start < 0) {
        ASSERT_EQ(out.place, -1);
        continue;
      }
      ASSERT_EQ(out.place, e.start + static_cast<int32_t>(offset));
      ASSERT_EQ(out.sum, e.sum);
      ASSERT_EQ(out.runner_up,
                e.runner_start < 0 ? -1 : e.runner_start + static_cast<int32_t>(offset))
          << "trial " << trial << " step " << i;
      if (e.runner_start < 0 || e.runner_sum == 0) {
        ASSERT_EQ(out.confidence.raw(), UQ16_16::from_int(1).raw());
        continue;
      }
      ASSERT_EQ(out.runner_up_sum, e.runner_sum);
      // confidence * runner_up_sum is sum * 2^16 to within half a runner_up_sum.
      const uint64_t lhs = static_cast<uint64_t>(out.confidence.raw()) * e.runner_sum;
      const uint64_t rhs = static_cast<uint64_t>(e.sum) << 16;
      const uint64_t diff = lhs > rhs ? lhs - rhs : rhs - lhs;
      ASSERT_LE(diff, e.runner_sum / 2u + 1u);
    }
  }
  // Both outcomes were exercised.
  EXPECT_GT(sequences_with_answer, 10u);
  EXPECT_GT(sequences_without, 0u);
}

// With a step budget the first image's greedy scan takes K = ceil(places / budget) steps:
// meanwhile the answer is partial (`scanning`, never complete); afterwards every answer equals
// the plain rule with the trail offsets before K - 1 skipped; no step evaluates more than the
// budget plus one distance per candidate; a failing distance mid-scan changes nothing.
TEST(HeuristicMatcher, ABudgetedScanEqualsTheRuleWithItsStepsSkipped) {
  static TableDistance t;
  test::Rng rng(91);
  uint32_t sequences = 0, answered = 0;
  for (uint32_t trial = 0; trial < 30; ++trial) {
    for (uint32_t i = 0; i < kTableSteps; ++i) {
      for (uint32_t j = 0; j < kTablePlaces; ++j)
        t.d[i][j] = 200 + rng.below(30) * 100;
      for (uint32_t j = 0; j < kTablePlaces; ++j) {
        if ((j + 7 * trial) % 29 == i % 29) t.d[i][j] = rng.below(8) * 50;
      }
    }
    HeuristicConfig c = table_config(static_cast<uint16_t>(1 + rng.below(6)),
                                     static_cast<uint16_t>(1 + rng.below(5)),
                                     static_cast<uint16_t>(2 + rng.below(6)));
    c.scan_places = static_cast<uint16_t>(1 + rng.below(40));
    HeuristicMatcher m;
    ASSERT_EQ(m.configure(c, kTablePixels), Status::kOk);
    const uint32_t places = kTablePlaces - rng.below(10);
    const uint32_t scan_steps = (places + c.scan_places - 1) / c.scan_places;
    const uint32_t from = scan_steps >= 2 ? scan_steps - 1 : 1;
    uint32_t first = 0;
    for (uint32_t i = 0; i < kTableSteps; ++i) {
      if (i == 5 && trial % 3 == 0) {  // a failure mid-scan is retried with the same answer
        t.fail_at = t.evaluations;
        HeuristicMatch before = m.current();
        EXPECT_EQ(m.step(t, places, nullptr), Status::kUnavailable);
        const HeuristicMatch after = m.current();
        EXPECT_EQ(after.query, before.query);
        EXPECT_EQ(after.place, before.place);
        t.fail_at = 0xFFFFFFFFu;
      }
      if (m.next_offset() == 0) first = i;
      const uint32_t evaluations = t.evaluations;
      HeuristicMatch out;
      ASSERT_EQ(m.step(t, places, &out), Status::kOk);
      EXPECT_LE(t.evaluations - evaluations, c.scan_places + c.candidates);
      const uint32_t offset = i - first;
      ASSERT_EQ(out.offset, offset);
      if (offset + 1 < scan_steps) {
        EXPECT_TRUE(out.scanning) << "trial " << trial << " step " << i;
        EXPECT_FALSE(out.complete);
        continue;
      }
      ASSERT_FALSE(out.scanning) << "trial " << trial << " step " << i;
      const Expected e = brute_force(t, first, offset, places, c, kTablePixels, from);
      ASSERT_EQ(out.start, e.start) << "trial " << trial << " step " << i;
      ASSERT_EQ(out.candidates, e.live);
      if (e.start >= 0) {
        ASSERT_EQ(out.sum, e.sum) << "trial " << trial << " step " << i;
        ++answered;
      }
      const uint32_t trails = offset == 0 ? 0 : offset - from + 1;
      ASSERT_EQ(out.complete, trails + 1 >= c.seq_len) << "trial " << trial << " step " << i;
      if (out.complete) ++sequences;
    }
  }
  EXPECT_GT(sequences, 30u);
  EXPECT_GT(answered, 100u);
}

}  // namespace
}  // namespace seqslam
