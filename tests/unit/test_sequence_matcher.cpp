// The diagonal matcher: the incremental update equals direct summation exactly (also while
// the library grows, shrinks, and after reset), the confidence direction, and bad input.
#include "seqslam/sequence_matcher.h"

#include "synthetic.h"
#include "test.h"

namespace seqslam {
namespace {

constexpr uint32_t kPlaces = 120;
constexpr uint32_t kSteps = 70;
constexpr uint16_t kSeq = 8;
// One in UQ16.16 raw units (the confidence's format; its resolution is 1 / kConfidenceOne).
constexpr double kConfidenceOne = static_cast<double>(UQ16_16::from_int(1).raw());

struct History {
  uint16_t rows[kSteps][kPlaces];
  uint32_t sizes[kSteps];
};

// Direct eq. 4.12 over the stored rows: valid iff all S diagonal cells exist.
bool direct_cost(const History& h, uint32_t i, uint32_t j, uint32_t first, uint32_t* cost) {
  if (i < first + kSeq - 1 || j < kSeq - 1u) return false;
  uint32_t c = 0;
  for (uint32_t k = 0; k < kSeq; ++k) {
    if (j - k >= h.sizes[i - k]) return false;
    c += h.rows[i - k][j - k];
  }
  *cost = c;
  return true;
}

TEST(DiagonalMatcher, IncrementalEqualsDirectSummation) {
  static DiagonalMatcherStorage<kPlaces, kSeq> storage;
  static History history;
  static uint32_t d[kPlaces];
  SequenceConfig cfg;
  cfg.seq_len = kSeq;
  cfg.window = 10;
  cfg.exclusion = 5;
  DiagonalMatcher m;
  ASSERT_EQ(m.configure(cfg, 512, storage.buffers()), Status::kOk);
  LocalNormaliser norm;
  ASSERT_EQ(norm.configure(cfg.window, cfg.sigma_min, 512), Status::kOk);
  test::Rng rng(30);
  uint32_t n = 40;
  uint32_t first = 0;  // first step after the last reset
  for (uint32_t i = 0; i < kSteps; ++i) {
    // The library mostly grows by one (loop-closure mode), sometimes jumps or shrinks.
    const uint32_t r = rng.below(10);
    if (r < 6) n = n < kPlaces ? n + 1 : n;
    if (r == 7) n = n + 5 < kPlaces ? n + 5 : kPlaces;
    if (r == 8) n = n > 10 ? n - 3 : n;
    if (i == 45) {
      m.reset();
      first = i;
    }
    for (uint32_t j = 0; j < n; ++j)
      d[j] = 30000 + rng.below(20000);
    for (uint32_t j = 0; j < n; ++j) {
      if ((j + 7) % 60 == i % 60) d[j] = rng.below(8000);  // a planted diagonal
    }
    norm.normalise_row(d, n, history.rows[i]);
    history.sizes[i] = n;
    Match out;
    ASSERT_EQ(m.step(Span<const uint32_t>(d, n), &out), Status::kOk);
    EXPECT_EQ(out.query, i - first);
    int32_t best = -1;
    uint32_t best_cost = 0;
    for (uint32_t j = 0; j < n; ++j) {
      uint32_t c = 0;
      const bool valid = direct_cost(history, i, j, first, &c);
      ASSERT_EQ(m.full_sequence(j), valid) << "step " << i << " place " << j;
      if (!valid) continue;
      ASSERT_EQ(m.cost(j), c) << "step " << i << " place " << j;
      if (best < 0 || c < best_cost) best = static_cast<int32_t>(j), best_cost = c;
    }
    // The confidence shift: S times the smallest normalised difference since the reset.
    uint16_t min_value = 0xFFFF;
    for (uint32_t k = first; k <= i; ++k) {
      for (uint32_t j = 0; j < history.sizes[k]; ++j) {
        if (history.rows[k][j] < min_value) min_value = history.rows[k][j];
      }
    }
    EXPECT_EQ(m.confidence_offset(), kSeq * static_cast<uint32_t>(min_value));
    EXPECT_EQ(out.place, best);
    if (best >= 0) {
      EXPECT_EQ(out.cost + m.confidence_offset(), best_cost);
    }
    if (best >= 0 && out.runner_up >= 0) {
      const int32_t gap = out.runner_up - best;
      EXPECT_GT(gap < 0 ? -gap : gap, static_cast<int32_t>(cfg.exclusion));
      EXPECT_GE(out.runner_up_cost, out.cost);
      const double c = static_cast<double>(out.cost) / out.runner_up_cost;
      EXPECT_NEAR(out.confidence.raw() / kConfidenceOne, c, 1.0 / kConfidenceOne);
    }
  }
}

// Rows where place j matches query i at j = i + offset (low difference), plus an optional
// equally good second diagonal (perceptual aliasing).
void planted_row(test::Rng& rng, uint32_t i, uint32_t n, uint32_t offset, int32_t alias_offset,
                 uint32_t* d) {
  for (uint32_t j = 0; j < n; ++j) {
    d[j] = 40000 + rng.below(10000);
    if (j == i + offset) d[j] = 10000 + rng.below(3000);
    if (alias_offset >= 0 && j == i + static_cast<uint32_t>(alias_offset)) {
      d[j] = 10000 + rng.below(3000);
    }
  }
}

TEST(DiagonalMatcher, UniqueDiagonalIsConfidentAliasIsNot) {
  static DiagonalMatcherStorage<200, 30> storage;
  static uint32_t d[200];
  SequenceConfig cfg;  // S = 30, W = 50, R = 10, threshold 0.85
  DiagonalMatcher m;
  ASSERT_EQ(m.configure(cfg, 512, storage.buffers()), Status::kOk);
  test::Rng rng(31);
  Match out;
  for (uint32_t i = 0; i < 60; ++i) {
    planted_row(rng, i, 200, 40, -1, d);
    ASSERT_EQ(m.step(Span<const uint32_t>(d, 200), &out), Status::kOk);
    if (i < 29) {
      EXPECT_EQ(out.place, -1) << "no full sequence before S steps";
      EXPECT_FALSE(out.localised);
    }
  }
  EXPECT_EQ(out.place, 59 + 40);
  EXPECT_TRUE(out.localised);
  EXPECT_LT(out.confidence.raw(), UQ16_16::from_ratio(1, 2).raw());  // smaller = more certain

  // Same, but a second identical-looking diagonal 100 places away: ambiguous.
  m.reset();
  for (uint32_t i = 0; i < 60; ++i) {
    planted_row(rng, i, 200, 20, 120, d);
    ASSERT_EQ(m.step(Span<const uint32_t>(d, 200), &out), Status::kOk);
  }
  EXPECT_TRUE(out.place == 59 + 20 || out.place == 59 + 120);
  EXPECT_GT(out.confidence.raw(), UQ16_16::from_ratio(85, 100).raw());
  EXPECT_FALSE(out.localised);
}

TEST(DiagonalMatcher, NoRunnerUpMeansNotLocalised) {
  static DiagonalMatcherStorage<50, 5> storage;
  uint32_t d[12];
  SequenceConfig cfg;
  cfg.seq_len = 5;
  cfg.window = 0;
  cfg.exclusion = 20;  // every place is within R of the best
  DiagonalMatcher m;
  ASSERT_EQ(m.configure(cfg, 512, storage.buffers()), Status::kOk);
  test::Rng rng(32);
  Match out;
  for (uint32_t i = 0; i < 8; ++i) {
    planted_row(rng, i, 12, 0, -1, d);
    ASSERT_EQ(m.step(Span<const uint32_t>(d, 12), &out), Status::kOk);
  }
  EXPECT_GE(out.place, 0);
  EXPECT_EQ(out.runner_up, -1);
  EXPECT_EQ(out.confidence.raw(), UQ16_16::from_int(1).raw());
  EXPECT_FALSE(out.localised);
}

TEST(DiagonalMatcher, EmptyLibraryGivesNoMatch) {
  static DiagonalMatcherStorage<10, 3> storage;
  SequenceConfig cfg;
  cfg.seq_len = 3;
  DiagonalMatcher m;
  ASSERT_EQ(m.configure(cfg, 512, storage.buffers()), Status::kOk);
  Match out;
  for (int i = 0; i < 5; ++i) {
    ASSERT_EQ(m.step(Span<const uint32_t>(), &out), Status::kOk);
    EXPECT_EQ(out.place, -1);
  }
}

TEST(DiagonalMatcher, BadConfigurationAndInput) {
  static DiagonalMatcherStorage<10, 4> storage;
  DiagonalMatcher m;
  Match out;
  uint32_t d[11] = {};
  EXPECT_EQ(m.step(Span<const uint32_t>(d, 3), &out), Status::kFailedPrecondition);
  SequenceConfig cfg;
  cfg.seq_len = 0;
  EXPECT_EQ(m.configure(cfg, 512, storage.buffers()), Status::kOutOfRange);
  cfg.seq_len = kMaxSeqLen + 1;
  EXPECT_EQ(m.configure(cfg, 512, storage.buffers()), Status::kOutOfRange);
  cfg = SequenceConfig{};
  cfg.window = 1;
  EXPECT_EQ(m.configure(cfg, 512, storage.buffers()), Status::kOutOfRange);
  cfg.window = 300;
  EXPECT_EQ(m.configure(cfg, 512, storage.buffers()), Status::kOutOfRange);
  cfg = SequenceConfig{};
  cfg.sigma_min = UQ8_8::from_int(0);
  EXPECT_EQ(m.configure(cfg, 512, storage.buffers()), Status::kInvalidArgument);
  cfg = SequenceConfig{};
  cfg.threshold = UQ16_16::from_ratio(3, 2);
  EXPECT_EQ(m.configure(cfg, 512, storage.buffers()), Status::kOutOfRange);
  cfg = SequenceConfig{};  // S = 30 but a ring of 20 entries: not even one place fits
  uint16_t ring[20];
  uint32_t cost[10];
  uint8_t run[10];
  const DiagonalMatcherBuffers tiny{Span<uint16_t>(ring, 20), Span<uint32_t>(cost, 10),
                                    Span<uint8_t>(run, 10)};
  EXPECT_EQ(m.configure(cfg, 512, tiny), Status::kResourceExhausted);
  cfg.seq_len = 4;
  EXPECT_EQ(m.configure(cfg, 0, storage.buffers()), Status::kOutOfRange);
  ASSERT_EQ(m.configure(cfg, 512, storage.buffers()), Status::kOk);
  EXPECT_EQ(m.capacity(), 10u);
  EXPECT_EQ(m.step(Span<const uint32_t>(d, 11), &out), Status::kOutOfRange);  // library full
  EXPECT_EQ(m.steps(), 0u);
  EXPECT_EQ(m.step(Span<const uint32_t>(d, 10), &out), Status::kOk);
}

}  // namespace
}  // namespace seqslam
