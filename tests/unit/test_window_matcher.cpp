// The windowed diagonal matcher: a window that covers every diagonal answers exactly as the
// diagonal matcher (also while the library grows and shrinks, and after reset); a narrow,
// moving window keeps the direct sums of eq. 4.12 for the diagonals it has held S steps, and
// answers from its search range with a runner-up from the window; its last L values
// (recent_cost) are the direct sums over those steps; rewound and replayed (the route search's
// re-seeding) it holds exactly what it would have held; the route search's probe (a one-step
// window) sums exactly the window's values; bands and bad input.
#include "seqslam/window_matcher.h"

#include "seqslam/sequence_matcher.h"
#include "seqslam/sequence_probe.h"
#include "synthetic.h"
#include "test.h"

namespace seqslam {
namespace {

constexpr uint32_t kPlaces = 120;
constexpr uint32_t kSteps = 80;
constexpr uint16_t kSeq = 8;

// A row of raw differences with a planted low diagonal (place = step + 7, wrapping) and a
// weaker second one, so best and runner-up both move.
void fill_row(test::Rng& rng, uint32_t i, uint32_t n, uint32_t* d) {
  for (uint32_t j = 0; j < n; ++j) {
    d[j] = 30000 + rng.below(20000);
    if ((j + 60 - 7) % 60 == i % 60) d[j] = rng.below(8000);
    if ((j + 60 - 40) % 60 == i % 60) d[j] = 12000 + rng.below(8000);
  }
}

// The band's differences from a whole row (what a caller streaming only the band computes).
Span<const uint32_t> band_of(const uint32_t* row, PlaceBand band) {
  return Span<const uint32_t>(row + band.first, band.count);
}

TEST(WindowMatcher, CoveringWindowEqualsTheDiagonalMatcher) {
  static DiagonalMatcherStorage<kPlaces, kSeq> diag_storage;
  // Every diagonal that can have a place: d in [-(steps), places - 1].
  static WindowMatcherStorage<kPlaces + kSteps, kSeq> win_storage;
  static uint32_t d[kPlaces];
  SequenceConfig cfg;
  cfg.seq_len = kSeq;
  cfg.window = 10;
  cfg.exclusion = 5;
  DiagonalMatcher full;
  WindowMatcher win;
  ASSERT_EQ(full.configure(cfg, 512, diag_storage.buffers()), Status::kOk);
  ASSERT_EQ(win.configure(cfg, 512, win_storage.buffers()), Status::kOk);
  ASSERT_EQ(win.place(-static_cast<int32_t>(kSteps), kPlaces + kSteps), Status::kOk);
  test::Rng rng(41);
  uint32_t n = 40;
  uint32_t compared = 0;
  for (uint32_t i = 0; i < kSteps; ++i) {
    // The library mostly grows by one (loop-closure mode), sometimes jumps or shrinks.
    const uint32_t r = rng.below(10);
    if (r < 6) n = n < kPlaces ? n + 1 : n;
    if (r == 7) n = n + 5 < kPlaces ? n + 5 : kPlaces;
    if (r == 8) n = n > 10 ? n - 3 : n;
    if (i == 50) {
      full.reset();
      win.reset();  // diagonals are counted from the new step 0; the window still covers all
    }
    fill_row(rng, i, n, d);
    Match a;
    Match b;
    ASSERT_EQ(full.step(Span<const uint32_t>(d, n), &a), Status::kOk);
    const PlaceBand band = win.band(n);
    ASSERT_EQ(band.first, 0u);
    ASSERT_EQ(band.count, n);
    ASSERT_EQ(win.step(n, band_of(d, band), INT32_MIN, INT32_MAX, &b), Status::kOk);
    EXPECT_EQ(b.query, a.query);
    EXPECT_EQ(b.place, a.place) << "step " << i;
    EXPECT_EQ(b.cost, a.cost) << "step " << i;
    EXPECT_EQ(b.runner_up, a.runner_up) << "step " << i;
    EXPECT_EQ(b.runner_up_cost, a.runner_up_cost) << "step " << i;
    EXPECT_EQ(b.confidence.raw(), a.confidence.raw()) << "step " << i;
    EXPECT_EQ(b.localised, a.localised) << "step " << i;
    EXPECT_EQ(win.confidence_offset(), full.confidence_offset());
    if (a.place >= 0) ++compared;
  }
  EXPECT_GT(compared, 40u);  // the comparison covered real answers, not only "none"
}

// Direct eq. 4.12 over stored normalised rows for diagonal d at step i: valid iff all S cells
// exist and the diagonal has been in the window since step i - S + 1.
struct Rows {
  uint16_t v[kSteps][kPlaces];
  uint32_t n[kSteps];
  int32_t first[kSteps];  // window at that step
  uint32_t width[kSteps];
};

bool direct(const Rows& h, uint32_t i, int32_t d, uint32_t* cost) {
  if (i + 1 < kSeq) return false;
  uint32_t c = 0;
  for (uint32_t k = 0; k < kSeq; ++k) {
    const uint32_t step = i - k;
    const int64_t p = static_cast<int64_t>(step) + d;
    if (p < 0 || p >= h.n[step]) return false;
    if (d < h.first[step] || d >= h.first[step] + static_cast<int32_t>(h.width[step])) return false;
    c += h.v[step][p];
  }
  *cost = c;
  return true;
}

TEST(WindowMatcher, NarrowMovingWindowKeepsDirectSumsAndSearchesItsRange) {
  static WindowMatcherStorage<24, kSeq> storage;
  static Rows rows;
  static uint32_t d[kPlaces];
  SequenceConfig cfg;
  cfg.seq_len = kSeq;
  cfg.window = 10;
  cfg.exclusion = 4;
  LocalNormaliser norm;
  ASSERT_EQ(norm.configure(cfg.window, cfg.sigma_min, 512), Status::kOk);
  WindowMatcher win;
  ASSERT_EQ(win.configure(cfg, 512, storage.buffers()), Status::kOk);
  test::Rng rng(42);
  int32_t first = -6;
  uint32_t width = 17;
  uint16_t min_value = 0xFFFF;
  uint32_t answers = 0;
  for (uint32_t i = 0; i < kSteps; ++i) {
    // The window drifts by -2..+2 diagonals now and then and changes width; it runs off the
    // library's start early on (negative places) and its end at the last steps.
    if (i % 9 == 4) first += static_cast<int32_t>(rng.below(5)) - 2;
    if (i % 13 == 6) width = 12 + rng.below(13);
    if (i >= 70) first = static_cast<int32_t>(kPlaces) - static_cast<int32_t>(i) - 5;
    ASSERT_EQ(win.place(first, width), Status::kOk);
    const uint32_t n = kPlaces;
    fill_row(rng, i, n, d);
    norm.normalise_row(d, n, rows.v[i]);
    rows.n[i] = n;
    rows.first[i] = first;
    rows.width[i] = width;
    const PlaceBand band = win.band(n);
    // The band is the window's places widened by W/2 = 5 each side, clipped to the library.
    const int64_t lo = static_cast<int64_t>(i) + first;
    const int64_t hi = lo + width - 1;
    const int64_t want_first = lo - 5 < 0 ? 0 : lo - 5;
    const int64_t want_last = hi + 5 >= n ? n - 1 : hi + 5;
    ASSERT_EQ(band.first, static_cast<uint32_t>(want_first)) << "step " << i;
    ASSERT_EQ(band.count, static_cast<uint32_t>(want_last - want_first + 1)) << "step " << i;
    const int32_t search_first = first + 3;
    const int32_t search_last = first + 9;
    Match m;
    ASSERT_EQ(win.step(n, band_of(d, band), search_first, search_last, &m), Status::kOk);
    for (int32_t k = 0; k < static_cast<int32_t>(width); ++k) {
      const int64_t p = static_cast<int64_t>(i) + first + k;
      if (p >= 0 && p < n && rows.v[i][p] < min_value) min_value = rows.v[i][p];
    }
    ASSERT_EQ(win.confidence_offset(), kSeq * static_cast<uint32_t>(min_value));
    int32_t best = INT32_MIN;
    uint32_t best_cost = 0;
    for (int32_t dd = first; dd < first + static_cast<int32_t>(width); ++dd) {
      uint32_t c = 0;
      const bool valid = direct(rows, i, dd, &c);
      ASSERT_EQ(win.full_sequence(dd), valid) << "step " << i << " diagonal " << dd;
      if (!valid) continue;
      ASSERT_EQ(win.cost(dd), c) << "step " << i << " diagonal " << dd;
      if (dd >= search_first && dd <= search_last && (best == INT32_MIN || c < best_cost)) {
        best = dd;
        best_cost = c;
      }
    }
    if (best == INT32_MIN) {
      EXPECT_EQ(m.place, -1) << "step " << i;
      continue;
    }
    ++answers;
    EXPECT_EQ(m.place, best + static_cast<int32_t>(i)) << "step " << i;
    EXPECT_EQ(m.cost + win.confidence_offset(), best_cost);
    int32_t second = INT32_MIN;
    uint32_t second_cost = 0;
    for (int32_t dd = first; dd < first + static_cast<int32_t>(width); ++dd) {
      uint32_t c = 0;
      if (dd >= best - 4 && dd <= best + 4) continue;
      if (direct(rows, i, dd, &c) && (second == INT32_MIN || c < second_cost)) {
        second = dd;
        second_cost = c;
      }
    }
    if (second == INT32_MIN) {
      EXPECT_EQ(m.runner_up, -1);
      EXPECT_FALSE(m.localised);
    } else {
      EXPECT_EQ(m.runner_up, second + static_cast<int32_t>(i)) << "step " << i;
      EXPECT_EQ(m.runner_up_cost + win.confidence_offset(), second_cost);
      EXPECT_EQ(m.confidence.raw(), confidence_ratio(m.cost, m.runner_up_cost).raw());
    }
  }
  EXPECT_GT(answers, 30u);
}

// recent_cost(d, L): the sum of diagonal d's last L normalised values (eq. 4.12 over L
// steps), UINT32_MAX where its run is shorter; checked against the direct sums of a whole
// normalised row, for every L and every diagonal of a window that drifts.
TEST(WindowMatcher, RecentCostIsTheDirectSumOfTheLastSteps) {
  static WindowMatcherStorage<24, kSeq> storage;
  static Rows rows;
  static uint32_t d[kPlaces];
  SequenceConfig cfg;
  cfg.seq_len = kSeq;
  cfg.window = 10;
  cfg.exclusion = 4;
  LocalNormaliser norm;
  ASSERT_EQ(norm.configure(cfg.window, cfg.sigma_min, 512), Status::kOk);
  WindowMatcher win;
  ASSERT_EQ(win.configure(cfg, 512, storage.buffers()), Status::kOk);
  test::Rng rng(45);
  int32_t first = -3;
  uint32_t checked = 0, missing = 0;
  for (uint32_t i = 0; i < 60; ++i) {
    if (i % 7 == 3) first += static_cast<int32_t>(rng.below(5)) - 2;
    ASSERT_EQ(win.place(first, 20), Status::kOk);
    fill_row(rng, i, kPlaces, d);
    norm.normalise_row(d, kPlaces, rows.v[i]);
    Match m;
    ASSERT_EQ(win.step(kPlaces, band_of(d, win.band(kPlaces)), 1, 0, &m), Status::kOk);
    EXPECT_EQ(m.place, -1);  // an empty search range
    for (int32_t dd = first; dd < first + 20; ++dd) {
      // The diagonal's run: steps back from i while it had a place and stayed in the window.
      uint32_t run = 0;
      uint32_t sum = 0;
      uint32_t sums[kSeq + 1] = {};
      for (uint32_t k = 0; k <= i && k < kSeq; ++k) {
        const int64_t p = static_cast<int64_t>(i - k) + dd;
        const int32_t f = k == 0 ? first : rows.first[i - k];
        if (p < 0 || p >= kPlaces || dd < f || dd >= f + 20) break;
        sum += rows.v[i - k][p];
        sums[++run] = sum;
      }
      for (uint32_t len = 1; len <= kSeq; ++len) {
        if (len <= run) {
          EXPECT_EQ(win.recent_cost(dd, len), sums[len]) << i << " " << dd << " " << len;
          ++checked;
        } else {
          EXPECT_EQ(win.recent_cost(dd, len), UINT32_MAX) << i << " " << dd << " " << len;
          ++missing;
        }
      }
    }
    rows.first[i] = first;
  }
  EXPECT_EQ(win.recent_cost(first, 0), UINT32_MAX);
  EXPECT_EQ(win.recent_cost(first, kSeq + 1), UINT32_MAX);
  EXPECT_EQ(win.recent_cost(first - 1, 1), UINT32_MAX);  // outside the window
  EXPECT_GT(checked, 5000u);
  EXPECT_GT(missing, 100u);
}

// Re-seeding: a window moved to new diagonals, rewound S steps and given those steps' rows
// again holds exactly the costs, runs and answers of a window that was there all along.
TEST(WindowMatcher, RewoundAndReplayedEqualsHavingBeenThere) {
  static WindowMatcherStorage<24, kSeq> there_storage, moved_storage;
  static uint32_t rows[kSteps][kPlaces];
  SequenceConfig cfg;
  cfg.seq_len = kSeq;
  cfg.window = 10;
  cfg.exclusion = 4;
  WindowMatcher there, moved;
  ASSERT_EQ(there.configure(cfg, 512, there_storage.buffers()), Status::kOk);
  ASSERT_EQ(moved.configure(cfg, 512, moved_storage.buffers()), Status::kOk);
  test::Rng rng(46);
  constexpr uint32_t kJump = 40;
  ASSERT_EQ(there.place(20, 21), Status::kOk);
  ASSERT_EQ(moved.place(-30, 21), Status::kOk);  // elsewhere until the jump
  for (uint32_t i = 0; i < kSteps; ++i) {
    fill_row(rng, i, kPlaces, rows[i]);
    Match a, b;
    ASSERT_EQ(there.step(kPlaces, band_of(rows[i], there.band(kPlaces)), 22, 28, &a), Status::kOk);
    ASSERT_EQ(moved.step(kPlaces, band_of(rows[i], moved.band(kPlaces)), 22, 28, &b), Status::kOk);
    if (i == kJump) {
      moved.rewind(i + 1 - kSeq);
      ASSERT_EQ(moved.place(20, 21), Status::kOk);
      for (uint32_t t = i + 1 - kSeq; t <= i; ++t) {
        Match none;
        ASSERT_EQ(moved.step(kPlaces, band_of(rows[t], moved.band(kPlaces)), 1, 0, &none),
                  Status::kOk);
      }
      ASSERT_EQ(moved.steps(), there.steps());
    }
    if (i < kJump) continue;
    for (int32_t dd = 20; dd < 41; ++dd) {
      ASSERT_EQ(moved.full_sequence(dd), there.full_sequence(dd)) << i << " " << dd;
      if (there.full_sequence(dd)) {
        ASSERT_EQ(moved.cost(dd), there.cost(dd)) << i << " " << dd;
      }
    }
    if (i > kJump) {  // (the replayed minimum differs from the one seen elsewhere before)
      EXPECT_EQ(a.place, b.place) << i;
      EXPECT_EQ(a.runner_up, b.runner_up) << i;
    }
  }
}

// The route search's probe (a one-step window of kProbeSlots diagonals and their sums):
// after L steps each sum is the window's recent_cost over L steps for that diagonal, its best
// the lowest within the radius, its sharpness the lowest 2 or more diagonals away; a diagonal
// that runs off the library is no longer followed.
TEST(SequenceProbe, SumsAreTheWindowsValuesOverItsSteps) {
  static WindowMatcherStorage<24, kSeq> storage;
  static SequenceProbeStorage probe_storage;
  static uint32_t d[kPlaces];
  SequenceConfig cfg;
  cfg.seq_len = kSeq;
  cfg.window = 10;
  cfg.exclusion = 4;
  WindowMatcher win;
  SequenceProbe probe;
  ASSERT_EQ(win.configure(cfg, 512, storage.buffers()), Status::kOk);
  ASSERT_EQ(probe.configure(cfg, 512, probe_storage.buffers()), Status::kOk);
  test::Rng rng(47);
  constexpr int32_t kCentre = 7;  // fill_row's planted diagonal
  ASSERT_EQ(win.place(kCentre - 10, 21), Status::kOk);
  constexpr uint32_t kFirst = 20;
  for (uint32_t i = 0; i < kFirst + kSeq; ++i) {
    fill_row(rng, i, kPlaces, d);
    Match m;
    ASSERT_EQ(win.step(kPlaces, band_of(d, win.band(kPlaces)), 1, 0, &m), Status::kOk);
    if (i == kFirst) probe.start(kCentre, kFirst);
    if (i < kFirst) continue;
    ASSERT_EQ(probe.next_step(), i);
    ASSERT_EQ(probe.add(kPlaces, band_of(d, probe.band(kPlaces))), Status::kOk);
    const uint32_t steps = i + 1 - kFirst;
    ASSERT_EQ(probe.steps(), steps);
    const ProbeBest b = probe.best(2);
    ASSERT_TRUE(b.found);
    uint32_t best = UINT32_MAX, local = UINT32_MAX;
    int32_t at = 0;
    for (int32_t dd = kCentre - 2; dd <= kCentre + 2; ++dd) {
      if (win.recent_cost(dd, steps) < best) best = win.recent_cost(dd, steps), at = dd;
    }
    for (int32_t dd = kCentre - 4; dd <= kCentre + 4; ++dd) {
      if ((dd > at ? dd - at : at - dd) >= 2 && win.recent_cost(dd, steps) < local) {
        local = win.recent_cost(dd, steps);
      }
    }
    EXPECT_EQ(b.diagonal, at) << i;
    EXPECT_EQ(b.cost, best) << i;
    EXPECT_EQ(b.local, local) << i;
  }
  EXPECT_EQ(probe.best(2).diagonal, kCentre);  // the planted diagonal is the best
  // Near the library's end: diagonals whose place leaves the library are dropped, the probe
  // answers from those that still have every step.
  probe.start(static_cast<int32_t>(kPlaces) - 3 - static_cast<int32_t>(probe.next_step()),
              probe.next_step());
  for (uint32_t k = 0; k < 3; ++k) {
    fill_row(rng, k, kPlaces, d);
    ASSERT_EQ(probe.add(kPlaces, band_of(d, probe.band(kPlaces))), Status::kOk);
  }
  const ProbeBest end = probe.best(4);
  ASSERT_TRUE(end.found);
  EXPECT_LE(end.diagonal + static_cast<int32_t>(probe.next_step()) - 1,
            static_cast<int32_t>(kPlaces) - 1);
  probe.stop();
  EXPECT_FALSE(probe.best(4).found);
  EXPECT_EQ(probe.add(kPlaces, Span<const uint32_t>()), Status::kFailedPrecondition);
  static WindowMatcherStorage<4, 1> small;
  static uint32_t sums[kProbeSlots];
  EXPECT_EQ(probe.configure(cfg, 512, SequenceProbeBuffers{small.buffers(), Span<uint32_t>(sums)}),
            Status::kResourceExhausted);
}

TEST(WindowMatcher, WindowOutsideTheLibraryHasNoAnswer) {
  static WindowMatcherStorage<16, 4> storage;
  SequenceConfig cfg;
  cfg.seq_len = 4;
  cfg.window = 6;
  WindowMatcher win;
  ASSERT_EQ(win.configure(cfg, 512, storage.buffers()), Status::kOk);
  uint32_t d[20];
  test::Rng rng(43);
  // Past the library's end: places 30.. of a 20-place library.
  ASSERT_EQ(win.place(30, 10), Status::kOk);
  for (uint32_t i = 0; i < 6; ++i) {
    fill_row(rng, i, 20, d);
    EXPECT_EQ(win.band(20).count, 0u);
    Match m;
    ASSERT_EQ(win.step(20, Span<const uint32_t>(), INT32_MIN, INT32_MAX, &m), Status::kOk);
    EXPECT_EQ(m.place, -1);
  }
  // Before its start: diagonals far below -step.
  ASSERT_EQ(win.place(-100, 10), Status::kOk);
  EXPECT_EQ(win.band(20).count, 0u);
  // An empty library.
  ASSERT_EQ(win.place(0, 10), Status::kOk);
  EXPECT_EQ(win.band(0).count, 0u);
  Match m;
  ASSERT_EQ(win.step(0, Span<const uint32_t>(), INT32_MIN, INT32_MAX, &m), Status::kOk);
  EXPECT_EQ(m.place, -1);
}

TEST(WindowMatcher, BadConfigurationAndInput) {
  static WindowMatcherStorage<8, 4> storage;
  WindowMatcher win;
  Match m;
  uint32_t d[20] = {};
  EXPECT_EQ(win.step(20, Span<const uint32_t>(d, 20), 0, 0, &m), Status::kFailedPrecondition);
  SequenceConfig cfg;
  cfg.seq_len = 0;
  EXPECT_EQ(win.configure(cfg, 512, storage.buffers()), Status::kOutOfRange);
  cfg = SequenceConfig{};
  cfg.seq_len = 4;
  EXPECT_EQ(win.configure(cfg, 0, storage.buffers()), Status::kOutOfRange);
  uint16_t ring[3];
  uint32_t cost[8];
  uint8_t run[8];
  EXPECT_EQ(win.configure(cfg, 512,
                          WindowMatcherBuffers{Span<uint16_t>(ring, 3), Span<uint32_t>(cost, 8),
                                               Span<uint8_t>(run, 8)}),
            Status::kResourceExhausted);
  ASSERT_EQ(win.configure(cfg, 512, storage.buffers()), Status::kOk);
  EXPECT_EQ(win.slots(), 8u);
  EXPECT_EQ(win.place(0, 0), Status::kOutOfRange);
  EXPECT_EQ(win.place(0, 9), Status::kOutOfRange);
  EXPECT_EQ(win.place(INT32_MAX - 2, 4), Status::kOutOfRange);
  ASSERT_EQ(win.place(2, 8), Status::kOk);
  // A band of the wrong length changes nothing.
  const PlaceBand band = win.band(20);
  ASSERT_GT(band.count, 1u);
  EXPECT_EQ(win.step(20, Span<const uint32_t>(d, band.count - 1), 0, 100, &m),
            Status::kInvalidArgument);
  EXPECT_EQ(win.steps(), 0u);
  EXPECT_EQ(win.step(static_cast<uint32_t>(INT32_MAX) + 1u, Span<const uint32_t>(), 0, 1, &m),
            Status::kOutOfRange);
}

}  // namespace
}  // namespace seqslam
