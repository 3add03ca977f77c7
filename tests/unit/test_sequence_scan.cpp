// The relocalisation scan: its answer at the anchor equals the diagonal matcher's (reset S - 1
// steps before the anchor) field for field, whatever the budget per call, also when the rows
// were matched against growing libraries (loop-closure mode); anytime answers are never
// "localised"; storage failures; an overwritten history; bad configuration.
#include "seqslam/sequence_scan.h"

#include "counting_images.h"
#include "seqslam/sequence_matcher.h"
#include "synthetic.h"
#include "test.h"

namespace seqslam {
namespace {

constexpr uint32_t kPlaces = 160;
constexpr uint16_t kSeq = 12;
const ImageSize kSize{16, 8};
constexpr uint32_t kPixels = 16 * 8;
constexpr uint32_t kQueries = 60;

using World = test::SyntheticWorld<kPlaces * 2 + 64, 8>;

struct Rig {
  PlaceLibraryStorage<kPlaces, kPixels> library_storage;
  test::CountingImages images;
  PlaceLibrary library;
  RamQueryHistoryStorage<kQueries, kPixels> history_storage;
  RamQueryHistory history;
  DiagonalMatcherStorage<kPlaces, kSeq> matcher_storage;
  SequenceScanStorage<kSeq, 20, 6> scan_storage;
  SequenceScanStorage<kSeq, 20, 6, kPixels> ram_scan_storage;  // query images in RAM
  uint32_t differences[kPlaces];
  uint8_t queries[kQueries][kPixels];

  // A library of the world's places and queries of a second, darker and noisier pass that
  // starts at place `start` (so the true place of query q is start + q).
  void build(uint64_t seed, uint32_t start, uint32_t alias_period = 0) {
    static World world;
    world.generate(seed, kPlaces * 2 + 64, 8, alias_period);
    ASSERT_EQ(
        images.ram.configure(kPixels, Span<uint8_t>(library_storage.pixels, kPlaces * kPixels)),
        Status::kOk);
    ASSERT_EQ(library.configure(kSize, images, PlaceLibraryBuffers{}), Status::kOk);
    test::Rng rng(seed + 1);
    uint8_t img[kPixels];
    for (uint32_t p = 0; p < kPlaces; ++p) {
      world.render(p, 2, 0, 16, 256, 0, 3, rng, img);
      ASSERT_EQ(library.add(ImageView{img, kSize}, Pose2{}, p), Status::kOk);
    }
    for (uint32_t q = 0; q < kQueries; ++q)
      world.render(start + q, 2, rng.range(-1, 1), 16, 200, 20, 6, rng, queries[q]);
    ASSERT_EQ(history_storage.attach(history, kPixels), Status::kOk);
  }
};

SequenceConfig scan_config() {
  SequenceConfig c;
  c.seq_len = kSeq;
  c.window = 20;
  c.exclusion = 6;
  return c;
}

// The diagonal matcher's answer at `anchor`, reset S - 1 steps before it, rows matched
// against `places(step)` library places.
template <typename Places>
Match reference(Rig& rig, uint32_t anchor, Places places) {
  DiagonalMatcher m;
  EXPECT_EQ(m.configure(scan_config(), kPixels, rig.matcher_storage.buffers()), Status::kOk);
  Match out;
  for (uint32_t step = anchor + 1 - kSeq; step <= anchor; ++step) {
    const uint32_t n = places(step);
    EXPECT_EQ(rig.library.differences(ImageView{rig.queries[step], kSize}, n, rig.differences),
              Status::kOk);
    EXPECT_EQ(m.step(Span<const uint32_t>(rig.differences, n), &out), Status::kOk);
  }
  return out;
}

// Every field but `query`: the scan reports its anchor step, the freshly reset reference S - 1.
void expect_same(const Match& a, const Match& b) {
  EXPECT_EQ(a.place, b.place);
  EXPECT_EQ(a.cost, b.cost);
  EXPECT_EQ(a.runner_up, b.runner_up);
  EXPECT_EQ(a.runner_up_cost, b.runner_up_cost);
  EXPECT_EQ(a.confidence.raw(), b.confidence.raw());
  EXPECT_EQ(a.localised, b.localised);
}

TEST(SequenceScan, EqualsTheDiagonalMatcherAtTheAnchorForAnyBudget) {
  static Rig rig;
  rig.build(51, 70);
  for (uint32_t q = 0; q < kQueries; ++q)
    ASSERT_EQ(rig.history.put(q, rig.queries[q], kPlaces), Status::kOk);
  SequenceScan scan;
  ASSERT_EQ(scan.configure(scan_config(), kPixels, rig.scan_storage.buffers()), Status::kOk);
  uint32_t localised = 0;
  const uint32_t anchors[] = {kSeq - 1u, 25u, 40u, kQueries - 1u};
  for (uint32_t anchor : anchors) {
    const Match want = reference(rig, anchor, [](uint32_t) { return kPlaces; });
    if (want.localised) ++localised;
    const uint32_t budgets[] = {1u, 7u, 32u, 1000u};
    for (uint32_t budget : budgets) {
      ASSERT_EQ(scan.start(anchor, rig.history), Status::kOk);
      uint32_t calls = 0;
      while (scan.running()) {
        const ScanResult partial = scan.result();
        EXPECT_FALSE(partial.complete);
        EXPECT_FALSE(partial.match.localised) << "an incomplete scan is never a fix";
        uint32_t streamed = 0;
        ASSERT_EQ(scan.advance(rig.library, rig.history, budget, &streamed), Status::kOk);
        EXPECT_LE(streamed, budget);
        ++calls;
      }
      ASSERT_TRUE(scan.complete());
      EXPECT_EQ(calls, (kPlaces + budget - 1) / budget) << "budget " << budget;
      const ScanResult r = scan.result();
      EXPECT_TRUE(r.complete);
      EXPECT_EQ(r.scanned, kPlaces);
      EXPECT_EQ(r.match.query, anchor);
      expect_same(r.match, want);
    }
  }
  // The planted pass is found: the data is not trivially unanswerable.
  EXPECT_GT(localised, 0u);
}

// With room for the query images (the head board's 12x10 default), the scan reads them from
// the history once, in its first call (which streams nothing), and then never again: the
// answer is the same for any budget, and a history that no longer holds the rows does not
// matter once they are loaded. Rows overwritten before the load abandon the scan.
TEST(SequenceScan, QueryImagesInRamAreReadOnceAndGiveTheSameAnswer) {
  static Rig rig;
  rig.build(54, 70);
  for (uint32_t q = 0; q < kQueries; ++q)
    ASSERT_EQ(rig.history.put(q, rig.queries[q], kPlaces), Status::kOk);
  SequenceScan scan;
  ASSERT_EQ(scan.configure(scan_config(), kPixels, rig.ram_scan_storage.buffers()), Status::kOk);
  static RamQueryHistory empty;  // never configured: every read fails
  const uint32_t anchors[] = {kSeq - 1u, 40u, kQueries - 1u};
  for (uint32_t anchor : anchors) {
    const Match want = reference(rig, anchor, [](uint32_t) { return kPlaces; });
    const uint32_t budgets[] = {1u, 32u, 1000u};
    for (uint32_t budget : budgets) {
      ASSERT_EQ(scan.start(anchor, rig.history), Status::kOk);
      uint32_t streamed = 99;
      ASSERT_EQ(scan.advance(rig.library, rig.history, budget, &streamed), Status::kOk);
      EXPECT_EQ(streamed, 0u) << "the first call loads the query images";
      uint32_t calls = 0;
      while (scan.running()) {
        ASSERT_EQ(scan.advance(rig.library, empty, budget), Status::kOk);
        ++calls;
      }
      EXPECT_EQ(calls, (kPlaces + budget - 1) / budget);
      expect_same(scan.result().match, want);
    }
  }
  // The rows overwritten before the first call: kNotFound, the scan abandoned.
  ASSERT_EQ(scan.start(kSeq - 1, rig.history), Status::kOk);
  for (uint32_t q = kQueries; q < kQueries + 3; ++q)
    ASSERT_EQ(rig.history.put(q, rig.queries[q % kQueries], kPlaces), Status::kOk);
  EXPECT_EQ(scan.advance(rig.library, rig.history, 5), Status::kNotFound);
  EXPECT_FALSE(scan.running());
  EXPECT_FALSE(scan.complete());
}

TEST(SequenceScan, RowsOfGrowingLibrariesAsInLoopClosureMode) {
  static Rig rig;
  rig.build(52, 10, 61);  // the strip repeats every 61 columns: aliasing
  // Step s was matched against 90 + s places, capped at kPlaces (the library grew each step
  // until it was full).
  const auto places = [](uint32_t step) { return 90 + step < kPlaces ? 90 + step : kPlaces; };
  for (uint32_t q = 0; q < kQueries; ++q)
    ASSERT_EQ(rig.history.put(q, rig.queries[q], places(q)), Status::kOk);
  SequenceScan scan;
  ASSERT_EQ(scan.configure(scan_config(), kPixels, rig.scan_storage.buffers()), Status::kOk);
  const uint32_t anchors[] = {kSeq - 1u, 33u, kQueries - 1u};
  for (uint32_t anchor : anchors) {
    ASSERT_EQ(scan.start(anchor, rig.history), Status::kOk);
    while (scan.running())
      ASSERT_EQ(scan.advance(rig.library, rig.history, 9), Status::kOk);
    expect_same(scan.result().match, reference(rig, anchor, places));
  }
}

TEST(SequenceScan, ALibraryReadErrorIsRetriedAHistoryErrorAbandons) {
  static Rig rig;
  rig.build(53, 40);
  for (uint32_t q = 0; q < kQueries; ++q)
    ASSERT_EQ(rig.history.put(q, rig.queries[q], kPlaces), Status::kOk);
  SequenceScan scan;
  ASSERT_EQ(scan.configure(scan_config(), kPixels, rig.scan_storage.buffers()), Status::kOk);
  const Match want = reference(rig, 30, [](uint32_t) { return kPlaces; });
  ASSERT_EQ(scan.start(30, rig.history), Status::kOk);
  rig.images.views = 0;
  rig.images.fail_at = 2;  // the third chunk's read fails once
  rig.images.failure = Status::kDataLoss;
  const uint32_t chunk = kMaxScanChunk;  // one view of the image store a call
  ASSERT_EQ(scan.advance(rig.library, rig.history, chunk), Status::kOk);
  ASSERT_EQ(scan.advance(rig.library, rig.history, chunk), Status::kOk);
  uint32_t streamed = 99;
  EXPECT_EQ(scan.advance(rig.library, rig.history, chunk, &streamed), Status::kDataLoss);
  EXPECT_EQ(streamed, 0u);
  EXPECT_TRUE(scan.running());
  while (scan.running())
    ASSERT_EQ(scan.advance(rig.library, rig.history, chunk), Status::kOk);
  expect_same(scan.result().match, want);

  // The robot drove on so far that the anchor's first rows were overwritten (the history
  // keeps kQueries steps): the scan is abandoned with kNotFound.
  ASSERT_EQ(scan.start(kSeq - 1, rig.history), Status::kOk);
  ASSERT_EQ(scan.advance(rig.library, rig.history, 5), Status::kOk);
  for (uint32_t q = kQueries; q < kQueries + 3; ++q)
    ASSERT_EQ(rig.history.put(q, rig.queries[q % kQueries], kPlaces), Status::kOk);
  EXPECT_EQ(scan.advance(rig.library, rig.history, 5), Status::kNotFound);
  EXPECT_FALSE(scan.running());
  EXPECT_FALSE(scan.complete());
  EXPECT_EQ(scan.advance(rig.library, rig.history, 5), Status::kFailedPrecondition);
  EXPECT_EQ(scan.start(kSeq - 1, rig.history), Status::kNotFound);
}

// Differences above 16 bits (black against white images at 32x16: up to 255 x 512) go through
// the packed ring (kScanHighBits) unchanged: the scan still equals the diagonal matcher.
TEST(SequenceScan, DifferencesAboveSixteenBits) {
  constexpr uint32_t kBig = 40;
  const ImageSize size{32, 16};
  static uint8_t lib[kBig][512];
  static uint8_t qry[kSeq][512];
  test::Rng rng(55);
  for (uint32_t p = 0; p < kBig; ++p) {
    for (uint32_t i = 0; i < 512; ++i)
      lib[p][i] = rng.below(2) ? 255 : static_cast<uint8_t>(rng.below(4));
  }
  for (uint32_t q = 0; q < kSeq; ++q) {
    for (uint32_t i = 0; i < 512; ++i)
      qry[q][i] = (i + q) % 7 < 3 ? lib[(q + 20) % kBig][i] : static_cast<uint8_t>(255 - lib[q][i]);
  }
  static PlaceLibraryStorage<kBig, 512> storage;
  PlaceLibrary library;
  ASSERT_EQ(storage.attach(library, size), Status::kOk);
  for (uint32_t p = 0; p < kBig; ++p)
    ASSERT_EQ(library.add(ImageView{lib[p], size}, Pose2{}, p), Status::kOk);
  static RamQueryHistoryStorage<kSeq, 512> hs;
  RamQueryHistory history;
  ASSERT_EQ(hs.attach(history, 512), Status::kOk);
  static DiagonalMatcherStorage<kBig, kSeq> ms;
  DiagonalMatcher m;
  ASSERT_EQ(m.configure(scan_config(), 512, ms.buffers()), Status::kOk);
  uint32_t d[kBig];
  uint32_t above = 0;
  Match want;
  for (uint32_t q = 0; q < kSeq; ++q) {
    ASSERT_EQ(history.put(q, qry[q], kBig), Status::kOk);
    ASSERT_EQ(library.differences(ImageView{qry[q], size}, kBig, d), Status::kOk);
    for (uint32_t p = 0; p < kBig; ++p)
      above += d[p] >= 65536u ? 1u : 0u;
    ASSERT_EQ(m.step(Span<const uint32_t>(d, kBig), &want), Status::kOk);
  }
  EXPECT_GT(above, 100u);  // the data really has differences above 16 bits
  static SequenceScanStorage<kSeq, 20, 6> ss;
  SequenceScan scan;
  ASSERT_EQ(scan.configure(scan_config(), 512, ss.buffers()), Status::kOk);
  ASSERT_EQ(scan.start(kSeq - 1, history), Status::kOk);
  while (scan.running())
    ASSERT_EQ(scan.advance(library, history, 13), Status::kOk);
  ASSERT_GE(want.place, 0);
  expect_same(scan.result().match, want);
}

TEST(SequenceScan, BadConfigurationAndStart) {
  static Rig rig;
  rig.build(54, 0);
  SequenceScan scan;
  EXPECT_EQ(scan.start(20, rig.history), Status::kFailedPrecondition);
  EXPECT_EQ(scan.advance(rig.library, rig.history, 5), Status::kFailedPrecondition);
  SequenceConfig c = scan_config();
  c.seq_len = 0;
  EXPECT_EQ(scan.configure(c, kPixels, rig.scan_storage.buffers()), Status::kOutOfRange);
  c = scan_config();
  EXPECT_EQ(scan.configure(c, 0, rig.scan_storage.buffers()), Status::kOutOfRange);
  // Buffers sized for a shorter sequence, a narrower window, a smaller exclusion.
  c.seq_len = kSeq + 1;
  EXPECT_EQ(scan.configure(c, kPixels, rig.scan_storage.buffers()), Status::kResourceExhausted);
  c = scan_config();
  c.window = 40;
  EXPECT_EQ(scan.configure(c, kPixels, rig.scan_storage.buffers()), Status::kResourceExhausted);
  c = scan_config();
  c.exclusion = 7;
  EXPECT_EQ(scan.configure(c, kPixels, rig.scan_storage.buffers()), Status::kResourceExhausted);
  ASSERT_EQ(scan.configure(scan_config(), kPixels, rig.scan_storage.buffers()), Status::kOk);
  EXPECT_EQ(scan.start(kSeq - 2, rig.history), Status::kOutOfRange);
  EXPECT_EQ(scan.start(kSeq - 1, rig.history), Status::kNotFound);  // nothing stored yet
  for (uint32_t q = 0; q < kSeq; ++q)
    ASSERT_EQ(rig.history.put(q, rig.queries[q], 0), Status::kOk);  // an empty library
  ASSERT_EQ(scan.start(kSeq - 1, rig.history), Status::kOk);
  EXPECT_TRUE(scan.complete());
  EXPECT_EQ(scan.result().match.place, -1);
  // The history refuses steps out of order and null images.
  EXPECT_EQ(rig.history.put(kSeq + 5, rig.queries[0], 1), Status::kFailedPrecondition);
  EXPECT_EQ(rig.history.put(kSeq, nullptr, 1), Status::kInvalidArgument);
  const uint8_t* px = nullptr;
  uint32_t n = 0;
  EXPECT_EQ(rig.history.get(kSeq + 1, &px, &n), Status::kNotFound);
  EXPECT_EQ(rig.history.get(0, nullptr, &n), Status::kInvalidArgument);
}

}  // namespace
}  // namespace seqslam
