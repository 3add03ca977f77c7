// The localiser end to end on synthetic routes: teach and repeat under an illumination
// change, loop closure in a single run, and configuration errors that name the problem. With
// the heuristic matcher selected: localise() and observe() equal the HeuristicMatcher run
// directly over the same preprocessed images, step by step, and compute only the distances
// it asks for.
#include "seqslam/localiser.h"

#include "counting_images.h"
#include "ram_state.h"
#include "synthetic.h"
#include "test.h"

namespace seqslam {
namespace {

constexpr uint32_t kPlaces = 200;
constexpr uint32_t kStep = 2;  // columns the camera moves per place
const ImageSize kSize{32, 16};

using World = test::SyntheticWorld<kPlaces * kStep + 64, 16>;

struct Rig {
  PlaceLibraryStorage<kPlaces, 512> library_storage;
  DiagonalMatcherStorage<kPlaces, 30> matcher_storage;
  uint32_t differences[kPlaces];
  PlaceLibrary library;
  Localiser localiser;

  ConfigCheck setup(const LocaliserConfig& config) {
    EXPECT_EQ(library_storage.attach(library, config.image_size), Status::kOk);
    return localiser.configure(config, library, matcher_storage.buffers(),
                               Span<uint32_t>(differences, kPlaces));
  }
};

LocaliserConfig test_config() {
  LocaliserConfig c;
  c.image_size = kSize;
  c.preprocess.method = Preprocessing::kHistEq;  // as written (the default before issue 33)
  c.sequence.seq_len = 10;
  c.sequence.window = 20;
  c.recent_exclusion = 30;
  return c;
}

TEST(Localiser, TeachAndRepeatUnderIlluminationChange) {
  static World world;
  static Rig rig;
  world.generate(40, kPlaces * kStep + 64, 16);
  ASSERT_TRUE(rig.setup(test_config()).ok());
  test::Rng rng(41);
  uint8_t img[512];
  for (uint32_t p = 0; p < kPlaces; ++p) {
    world.render(p, kStep, 0, 32, 256, 0, 3, rng, img);
    ASSERT_EQ(rig.localiser.teach(ImageView{img, kSize}, Pose2{}, p), Status::kOk);
  }
  EXPECT_EQ(rig.library.size(), kPlaces);
  uint32_t answered = 0, correct = 0, localised_wrong = 0;
  Match m;
  for (uint32_t q = 0; q < kPlaces; ++q) {
    // Darker, offset, noisier, and up to one column off.
    world.render(q, kStep, rng.range(-1, 1), 32, 180, 30, 6, rng, img);
    ASSERT_EQ(rig.localiser.localise(ImageView{img, kSize}, &m), Status::kOk);
    if (q < 9) {
      EXPECT_EQ(m.place, -1);
      continue;
    }
    ++answered;
    const int32_t err = m.place - static_cast<int32_t>(q);
    const bool ok = err >= -1 && err <= 1;
    correct += ok ? 1u : 0u;
    if (m.localised && !ok) ++localised_wrong;
  }
  EXPECT_GE(correct, answered * 95 / 100) << correct << " of " << answered;
  EXPECT_EQ(localised_wrong, 0u);
}

TEST(Localiser, LoopClosureInOneRun) {
  static World world;
  static Rig rig;
  world.generate(42, 100 * kStep + 64, 16);
  ASSERT_TRUE(rig.setup(test_config()).ok());
  test::Rng rng(43);
  uint8_t img[512];
  Match m;
  uint32_t closures = 0, second_lap = 0;
  for (uint32_t k = 0; k < kPlaces; ++k) {
    const uint32_t place = k % 100;  // the route is driven twice
    world.render(place, kStep, 0, 32, k < 100 ? 256 : 220, k < 100 ? 0 : 15, 4, rng, img);
    ASSERT_EQ(rig.localiser.observe(ImageView{img, kSize}, Pose2{}, k, &m), Status::kOk);
    if (k < 100) {
      // First lap: nothing to close against but the run's own older places, which are
      // different places.
      EXPECT_FALSE(m.localised && m.place >= 0 && (m.place % 100) == static_cast<int32_t>(place))
          << k;
      continue;
    }
    if (k < 100 + 10) continue;  // the sequence must be in the second lap entirely
    ++second_lap;
    const int32_t err = m.place - static_cast<int32_t>(place);
    if (m.localised) {
      EXPECT_TRUE(err >= -1 && err <= 1) << "lap 2 place " << place << " matched " << m.place;
      ++closures;
    }
  }
  EXPECT_EQ(rig.library.size(), kPlaces);
  EXPECT_GE(closures, second_lap * 8 / 10) << closures << " of " << second_lap;
}

// Continuing a stopped run (state_io.h): a loop-closing localiser saved in the second lap and
// restored into another one (its library taught the same places, its sequences empty) gives
// exactly the same matches for the rest of the run. A state cut short is refused and leaves
// the matcher without history, as reset_sequence() does.
TEST(Localiser, ContinuesExactlyFromASavedState) {
  static World world;
  static Rig a, b;
  static test::RamState<16384> saved;
  world.generate(42, 100 * kStep + 64, 16);
  ASSERT_TRUE(a.setup(test_config()).ok());
  ASSERT_TRUE(b.setup(test_config()).ok());
  uint8_t img[512];
  const auto render = [&](uint32_t k) {
    test::Rng rng(1000 + k);  // each image its own noise, so either rig can render it
    world.render(k % 100, kStep, 0, 32, k < 100 ? 256 : 220, k < 100 ? 0 : 15, 4, rng, img);
  };
  constexpr uint32_t kStop = 130;
  Match ma, mb;
  for (uint32_t k = 0; k < kStop; ++k) {
    render(k);
    ASSERT_EQ(a.localiser.observe(ImageView{img, kSize}, Pose2{}, k, &ma), Status::kOk);
    ASSERT_EQ(b.localiser.teach(ImageView{img, kSize}, Pose2{}, k), Status::kOk);
  }
  StateOut out(saved);
  a.localiser.state(out);
  ASSERT_EQ(out.status(), Status::kOk);
  StateIn in(saved);
  b.localiser.state(in);
  ASSERT_EQ(in.status(), Status::kOk);
  // The first answers after the stop already need the restored history: without it the
  // matcher would have no full sequence for S - 1 more steps.
  uint32_t localised = 0;
  for (uint32_t k = kStop; k < kPlaces; ++k) {
    render(k);
    ASSERT_EQ(a.localiser.observe(ImageView{img, kSize}, Pose2{}, k, &ma), Status::kOk);
    ASSERT_EQ(b.localiser.observe(ImageView{img, kSize}, Pose2{}, k, &mb), Status::kOk);
    EXPECT_EQ(mb.place, ma.place) << k;
    EXPECT_EQ(mb.confidence.raw(), ma.confidence.raw()) << k;
    EXPECT_EQ(mb.localised, ma.localised) << k;
    localised += ma.localised ? 1 : 0;
  }
  EXPECT_GT(localised, 50u);
  saved.truncate(saved.size() / 2);
  StateIn short_in(saved);
  b.localiser.state(short_in);
  EXPECT_EQ(short_in.status(), Status::kDataLoss);
  EXPECT_EQ(b.localiser.matcher().steps(), 0u);
}

TEST(Localiser, ConfigurationErrorsNameTheSetting) {
  static Rig rig;
  struct Case {
    LocaliserConfig config;
    Status status;
    ConfigIssue issue;
  };
  LocaliserConfig c = test_config();
  Case cases[16];
  int n = 0;
  c.image_size = ImageSize{0, 16};
  cases[n++] = {c, Status::kInvalidArgument, ConfigIssue::kImageSizeZero};
  c = test_config();
  c.image_size = ImageSize{static_cast<uint16_t>(kMaxPixels), 2};
  cases[n++] = {c, Status::kOutOfRange, ConfigIssue::kImageTooLarge};
  c = test_config();
  c.sequence.seq_len = 0;
  cases[n++] = {c, Status::kOutOfRange, ConfigIssue::kSeqLenOutOfRange};
  c = test_config();
  c.sequence.seq_len = 101;
  cases[n++] = {c, Status::kOutOfRange, ConfigIssue::kSeqLenOutOfRange};
  c = test_config();
  c.sequence.window = 1;
  cases[n++] = {c, Status::kOutOfRange, ConfigIssue::kWindowOutOfRange};
  c = test_config();
  c.sequence.sigma_min = UQ8_8::from_int(0);
  cases[n++] = {c, Status::kInvalidArgument, ConfigIssue::kSigmaMinZero};
  c = test_config();
  c.sequence.threshold = UQ16_16::from_int(2);
  cases[n++] = {c, Status::kOutOfRange, ConfigIssue::kThresholdOutOfRange};
  c = test_config();
  c.max_shift = 32;
  cases[n++] = {c, Status::kOutOfRange, ConfigIssue::kMaxShiftOutOfRange};
  c = test_config();
  c.recent_exclusion = 0;
  cases[n++] = {c, Status::kInvalidArgument, ConfigIssue::kRecentExclusionZero};
  c = test_config();
  c.preprocess.method = Preprocessing::kPatchNorm;
  c.preprocess.patch.patch_height = 0;
  cases[n++] = {c, Status::kInvalidArgument, ConfigIssue::kPreprocessingInvalid};
  c = test_config();
  c.matcher = static_cast<LocaliserMatcher>(3);
  cases[n++] = {c, Status::kOutOfRange, ConfigIssue::kMatcherUnknown};
  // The heuristic's settings are checked whichever matcher is selected.
  c = test_config();
  c.heuristic.candidates = 0;
  cases[n++] = {c, Status::kOutOfRange, ConfigIssue::kHeuristicCandidatesOutOfRange};
  c = test_config();
  c.matcher = LocaliserMatcher::kHeuristic;
  c.heuristic.candidates = kMaxHeuristicCandidates + 1;
  cases[n++] = {c, Status::kOutOfRange, ConfigIssue::kHeuristicCandidatesOutOfRange};
  c = test_config();
  c.matcher = LocaliserMatcher::kHeuristic;
  c.heuristic.guard = 0;
  cases[n++] = {c, Status::kInvalidArgument, ConfigIssue::kHeuristicGuardZero};
  c = test_config();
  c.matcher = LocaliserMatcher::kHeuristic;
  c.sequence.seq_len = 101;  // the heuristic's S is the sequence's
  cases[n++] = {c, Status::kOutOfRange, ConfigIssue::kSeqLenOutOfRange};
  for (int i = 0; i < n; ++i) {
    const ConfigCheck check = check_localiser_config(cases[i].config);
    EXPECT_EQ(check.status, cases[i].status) << "case " << i;
    EXPECT_EQ(check.issue, cases[i].issue) << "case " << i;
    EXPECT_TRUE(config_issue_text(check.issue)[0] != '\0');
  }
  // Valid corners: k 1 and 16, guard 1, a candidate threshold of 0 (accepts nothing).
  c = test_config();
  c.matcher = LocaliserMatcher::kHeuristic;
  c.heuristic.candidates = 1;
  c.heuristic.guard = 1;
  c.heuristic.threshold = UQ8_8::from_int(0);
  EXPECT_TRUE(check_localiser_config(c).ok());
  c.heuristic.candidates = kMaxHeuristicCandidates;
  EXPECT_TRUE(check_localiser_config(c).ok());
  // The storage checks need a library.
  ASSERT_EQ(rig.library_storage.attach(rig.library, kSize), Status::kOk);
  LocaliserConfig other = test_config();
  other.image_size = ImageSize{25, 20};
  ConfigCheck check = rig.localiser.configure(other, rig.library, rig.matcher_storage.buffers(),
                                              Span<uint32_t>(rig.differences, kPlaces));
  EXPECT_EQ(check.issue, ConfigIssue::kLibraryMismatch);
  check = rig.localiser.configure(test_config(), rig.library, rig.matcher_storage.buffers(),
                                  Span<uint32_t>(rig.differences, kPlaces - 1));
  EXPECT_EQ(check.status, Status::kResourceExhausted);
  EXPECT_EQ(check.issue, ConfigIssue::kStorageTooSmall);
  // Unconfigured after a failed configure.
  uint8_t img[512] = {};
  Match m;
  EXPECT_EQ(rig.localiser.localise(ImageView{img, kSize}, &m), Status::kFailedPrecondition);
  // The heuristic needs its matcher state: the overload without one refuses it (and leaves
  // the localiser unconfigured, even after a good configuration).
  ASSERT_TRUE(rig.setup(test_config()).ok());
  LocaliserConfig h = test_config();
  h.matcher = LocaliserMatcher::kHeuristic;
  check = rig.localiser.configure(h, rig.library, rig.matcher_storage.buffers(),
                                  Span<uint32_t>(rig.differences, kPlaces));
  EXPECT_EQ(check.status, Status::kResourceExhausted);
  EXPECT_EQ(check.issue, ConfigIssue::kHeuristicMatcherMissing);
  EXPECT_TRUE(config_issue_text(check.issue)[0] != '\0');
  EXPECT_EQ(rig.localiser.localise(ImageView{img, kSize}, &m), Status::kFailedPrecondition);
  // ... and with one it needs no diagonal buffers or difference scratch.
  static HeuristicMatcher heuristic;
  check = rig.localiser.configure(h, rig.library, heuristic);
  EXPECT_TRUE(check.ok()) << config_issue_text(check.issue);
  EXPECT_TRUE(rig.localiser.heuristic() == &heuristic);
  EXPECT_EQ(heuristic.config().seq_len, h.sequence.seq_len);
  EXPECT_EQ(heuristic.config().exclusion, h.sequence.exclusion);
  // Each overload configures one search: the heuristic's refuses the diagonal matcher (and
  // leaves the localiser unconfigured), the diagonal one works again after it.
  check = rig.localiser.configure(test_config(), rig.library, heuristic);
  EXPECT_EQ(check.status, Status::kInvalidArgument);
  EXPECT_EQ(check.issue, ConfigIssue::kHeuristicNotSelected);
  EXPECT_EQ(rig.localiser.localise(ImageView{img, kSize}, &m), Status::kFailedPrecondition);
  check = rig.localiser.configure(test_config(), rig.library, rig.matcher_storage.buffers(),
                                  Span<uint32_t>(rig.differences, kPlaces));
  EXPECT_TRUE(check.ok());
  EXPECT_TRUE(rig.localiser.heuristic() == nullptr);
}

TEST(Localiser, FullLibraryAndWrongImages) {
  static Rig rig;
  ASSERT_TRUE(rig.setup(test_config()).ok());
  uint8_t img[512] = {};
  for (uint32_t p = 0; p < kPlaces; ++p) {
    img[p % 512] = static_cast<uint8_t>(p);
    ASSERT_EQ(rig.localiser.teach(ImageView{img, kSize}, Pose2{}, p), Status::kOk);
  }
  EXPECT_EQ(rig.localiser.teach(ImageView{img, kSize}, Pose2{}, 999), Status::kResourceExhausted);
  EXPECT_EQ(rig.library.size(), kPlaces);
  Match m;
  EXPECT_EQ(rig.localiser.localise(ImageView{img, ImageSize{16, 32}}, &m),
            Status::kInvalidArgument);
  EXPECT_EQ(rig.localiser.localise(ImageView{nullptr, kSize}, &m), Status::kInvalidArgument);
  // observe() on a full library still reports the match, then says the place was not stored.
  EXPECT_EQ(rig.localiser.observe(ImageView{img, kSize}, Pose2{}, 1000, &m),
            Status::kResourceExhausted);
}

// ---------------------------------------------------------------------------------------
// The heuristic matcher behind the Localiser.

constexpr uint32_t kHPlaces = 120;
constexpr uint32_t kHQueries = 60;

// The hand-made reference: distances between preprocessed images kept in tables here (the
// query of step i since reset is query[i % kHQueries], a ring of the latest queries),
// computed as the diagonal path does.
class TableDistance final : public PlaceDistance {
 public:
  uint8_t library[kHPlaces + kHQueries][512] = {};
  uint8_t query[kHQueries][512] = {};
  uint8_t max_shift = 0;

 private:
  Status do_distance(uint32_t q, uint32_t place, uint32_t* out) override {
    if (place >= kHPlaces + kHQueries) return Status::kOutOfRange;
    const ImageView a{query[q % kHQueries], kSize};
    const ImageView b{library[place], kSize};
    const Result<uint32_t> d = max_shift == 0 ? sad(a, b) : shift_tolerant_sad(a, b, max_shift);
    if (!d.ok()) return d.status();
    *out = d.value();
    return Status::kOk;
  }
};

struct HeuristicRig {
  uint8_t pixels[(kHPlaces + kHQueries) * 512];
  test::CountingImages images;
  PlaceInfo info[kHPlaces + kHQueries];
  uint32_t sums[kHPlaces + kHQueries];
  PlaceLibrary library;
  Localiser localiser;
  HeuristicMatcher heuristic;
  HeuristicMatcher reference;
  TableDistance table;
  RamQueryHistoryStorage<kHQueries, 512> history_storage;
  RamQueryHistory history;

  ConfigCheck setup(const LocaliserConfig& config) {
    images.views = 0;
    images.fail_at = 0xFFFFFFFFu;
    EXPECT_EQ(
        images.ram.configure(config.image_size.pixels(), Span<uint8_t>(pixels, sizeof pixels)),
        Status::kOk);
    const PlaceLibraryBuffers buffers{Span<PlaceInfo>(info, kHPlaces + kHQueries),
                                      Span<uint32_t>(sums, kHPlaces + kHQueries)};
    EXPECT_EQ(library.configure(config.image_size, images, buffers), Status::kOk);
    // No diagonal buffers or difference scratch: the heuristic does not use them. A query
    // history only for a budgeted scan (its first image is read back from it).
    EXPECT_EQ(history_storage.attach(history, config.image_size.pixels()), Status::kOk);
    const ConfigCheck check = localiser.configure(
        config, library, heuristic, config.heuristic.scan_places != 0 ? &history : nullptr);
    HeuristicConfig hc = config.heuristic;
    hc.seq_len = config.sequence.seq_len;
    hc.exclusion = config.sequence.exclusion;
    EXPECT_EQ(reference.configure(hc, config.image_size.pixels()), Status::kOk);
    table.max_shift = config.max_shift;
    return check;
  }
};

LocaliserConfig heuristic_config(uint8_t max_shift) {
  LocaliserConfig c = test_config();
  c.matcher = LocaliserMatcher::kHeuristic;
  c.heuristic.candidates = 4;
  c.heuristic.guard = 4;
  c.heuristic.threshold = UQ8_8::from_int(80);
  c.sequence.seq_len = 8;
  c.sequence.exclusion = 6;
  // Raw distance sums are less decisive than normalised costs (heuristic_matcher.h): a lower
  // decision threshold than the diagonal matcher's 0.85.
  c.sequence.threshold = UQ16_16::from_ratio(1, 2);
  c.max_shift = max_shift;
  c.recent_exclusion = 20;
  return c;
}

// What the Localiser must report for the reference matcher's answer.
void expect_same(const Match& m, const HeuristicMatch& h, UQ16_16 threshold, uint32_t step) {
  EXPECT_EQ(m.query, h.query) << "step " << step;
  EXPECT_EQ(m.place, h.place) << "step " << step;
  EXPECT_EQ(m.cost, h.sum) << "step " << step;
  EXPECT_EQ(m.runner_up, h.runner_up) << "step " << step;
  EXPECT_EQ(m.runner_up_cost, h.runner_up_sum) << "step " << step;
  EXPECT_EQ(m.confidence.raw(), h.confidence.raw()) << "step " << step;
  EXPECT_EQ(m.localised, h.place >= 0 && !h.scanning && h.confidence < threshold)
      << "step " << step;
}

// Teach and repeat: every step equals the HeuristicMatcher over the same preprocessed images,
// and the library is read exactly as often as the matcher asks for distances (M at the first
// step of a sequence, one per live trail afterwards).
void heuristic_repeat(uint8_t max_shift, uint16_t scan_places = 0) {
  static World world;
  static HeuristicRig rig;
  world.generate(44, kPlaces * kStep + 64, 16);
  LocaliserConfig config = heuristic_config(max_shift);
  config.heuristic.scan_places = scan_places;
  const ConfigCheck check = rig.setup(config);
  ASSERT_TRUE(check.ok()) << config_issue_text(check.issue);
  test::Rng rng(45);
  uint8_t img[512];
  for (uint32_t p = 0; p < kHPlaces; ++p) {
    world.render(p, kStep, 0, 32, 256, 0, 3, rng, img);
    ASSERT_EQ(rig.localiser.teach(ImageView{img, kSize}, Pose2{}, p), Status::kOk);
    ASSERT_EQ(preprocess(config.preprocess, ImageView{img, kSize},
                         MutableImageView{rig.table.library[p], kSize}),
              Status::kOk);
  }
  uint32_t answered = 0, correct = 0, localised = 0;
  for (uint32_t q = 0; q < kHQueries; ++q) {
    const uint32_t truth = 30 + q;
    world.render(truth, kStep, rng.range(-1, 1), 32, 190, 25, 5, rng, img);
    ASSERT_EQ(preprocess(config.preprocess, ImageView{img, kSize},
                         MutableImageView{rig.table.query[q], kSize}),
              Status::kOk);
    const uint32_t views = rig.images.views;
    Match m;
    ASSERT_EQ(rig.localiser.localise(ImageView{img, kSize}, &m), Status::kOk);
    HeuristicMatch h;
    ASSERT_EQ(rig.reference.step(rig.table, kHPlaces, &h), Status::kOk);
    expect_same(m, h, config.sequence.threshold, q);
    // The greedy scan streams the library 16 places a view with the plain SAD (the
    // shift-tolerant one goes place by place); a trail step reads one place per candidate.
    const uint32_t scan_views = max_shift == 0 ? (kHPlaces + 15) / 16 : kHPlaces;
    if (scan_places == 0) {
      EXPECT_EQ(rig.images.views - views, h.offset == 0 ? scan_views : h.candidates)
          << "step " << q;
    } else {  // bounded work per step: the budget (in 16-place views) and the trails
      EXPECT_LE(rig.images.views - views, (scan_places + 15u) / 16u + h.candidates) << "step " << q;
    }
    if (h.complete) {
      ++answered;
      const int32_t err = m.place - static_cast<int32_t>(truth);
      correct += err >= -1 && err <= 1 ? 1u : 0u;
      localised += m.localised ? 1u : 0u;
    }
  }
  // Not a vacuous comparison: the sequences were found.
  if (scan_places == 0) {
    EXPECT_EQ(answered, kHQueries / 8);
  } else {
    EXPECT_GE(answered, 3u);
  }
  EXPECT_GE(correct, answered - 1) << correct << " of " << answered;
  EXPECT_GE(localised, 1u);
}

TEST(LocaliserHeuristic, RepeatEqualsTheMatcherStepByStep) {
  heuristic_repeat(0);
}

TEST(LocaliserHeuristic, RepeatWithShiftToleranceEqualsTheMatcher) {
  heuristic_repeat(2);
}

// The head board's form: the first image's scan spread over steps (32 places a step), its
// image read back from the query history: still the matcher step for step.
TEST(LocaliserHeuristic, ABudgetedScanEqualsTheMatcherStepByStep) {
  heuristic_repeat(0, 32);
}

TEST(LocaliserHeuristic, ABudgetedScanNeedsAHistory) {
  static HeuristicRig rig;
  LocaliserConfig config = heuristic_config(0);
  ASSERT_TRUE(rig.setup(config).ok());
  config.heuristic.scan_places = 32;
  EXPECT_EQ(rig.localiser.configure(config, rig.library, rig.heuristic).issue,
            ConfigIssue::kHeuristicHistoryMissing);
  // ... of its image size.
  RamQueryHistoryStorage<4, 512> small;
  RamQueryHistory other;
  ASSERT_EQ(small.attach(other, 100), Status::kOk);
  EXPECT_EQ(rig.localiser.configure(config, rig.library, rig.heuristic, &other).issue,
            ConfigIssue::kHeuristicHistoryMissing);
  EXPECT_TRUE(rig.localiser.configure(config, rig.library, rig.heuristic, &rig.history).ok());
}

// Loop closure: the matched part of the library (places older than recent_exclusion) grows
// by one place a step, and the heuristic's trails follow it.
TEST(LocaliserHeuristic, ObserveEqualsTheMatcherStepByStep) {
  static World world;
  static HeuristicRig rig;
  world.generate(46, 100 * kStep + 64, 16);
  const LocaliserConfig config = heuristic_config(0);
  ASSERT_TRUE(rig.setup(config).ok());
  test::Rng rng(47);
  uint8_t img[512];
  uint32_t closures = 0;
  for (uint32_t k = 0; k < kHQueries * 3; ++k) {
    const uint32_t place = k % 60;  // a 60-place route driven three times
    world.render(place, kStep, 0, 32, k < 60 ? 256 : 215, k < 60 ? 0 : 15, 4, rng, img);
    // The reference sees the query as step k since reset, and the place as library place k.
    uint8_t* pre = rig.table.query[k % kHQueries];
    ASSERT_EQ(preprocess(config.preprocess, ImageView{img, kSize}, MutableImageView{pre, kSize}),
              Status::kOk);
    const uint32_t older =
        k > config.recent_exclusion ? k - config.recent_exclusion : 0;  // library size is k
    Match m;
    ASSERT_EQ(rig.localiser.observe(ImageView{img, kSize}, Pose2{}, k, &m), Status::kOk);
    HeuristicMatch h;
    ASSERT_EQ(rig.reference.step(rig.table, older, &h), Status::kOk);
    expect_same(m, h, config.sequence.threshold, k);
    for (uint32_t i = 0; i < 512; ++i)
      rig.table.library[k][i] = pre[i];
    if (m.localised && h.complete) {
      const int32_t err = m.place % 60 - static_cast<int32_t>(place);
      EXPECT_TRUE(err >= -1 && err <= 1)
          << "step " << k << " place " << place << " matched " << m.place;
      ++closures;
    }
  }
  EXPECT_EQ(rig.library.size(), kHQueries * 3);
  EXPECT_GE(closures, 5u);
}

// A failing read of the library (a card error) passes through and leaves the matcher where
// it was; the step can be taken again. reset_sequence() starts a new sequence.
TEST(LocaliserHeuristic, StorageErrorsPassThroughAndResetStartsANewSequence) {
  static World world;
  static HeuristicRig rig;
  world.generate(48, kPlaces * kStep + 64, 16);
  const LocaliserConfig config = heuristic_config(0);
  ASSERT_TRUE(rig.setup(config).ok());
  test::Rng rng(49);
  uint8_t img[512];
  for (uint32_t p = 0; p < kHPlaces; ++p) {
    world.render(p, kStep, 0, 32, 256, 0, 3, rng, img);
    ASSERT_EQ(rig.localiser.teach(ImageView{img, kSize}, Pose2{}, p), Status::kOk);
  }
  world.render(40, kStep, 0, 32, 200, 20, 4, rng, img);
  Match m;
  m.place = 12345;
  rig.images.fail_at = rig.images.views + 3;  // the scan's fourth view of the library
  EXPECT_EQ(rig.localiser.localise(ImageView{img, kSize}, &m), Status::kUnavailable);
  EXPECT_EQ(m.place, 12345);  // untouched
  EXPECT_EQ(rig.heuristic.query(), 0u);
  ASSERT_EQ(rig.localiser.localise(ImageView{img, kSize}, &m), Status::kOk);
  EXPECT_EQ(m.query, 0u);
  EXPECT_EQ(rig.heuristic.next_offset(), 1u);
  uint32_t views = rig.images.views;
  ASSERT_EQ(rig.localiser.localise(ImageView{img, kSize}, &m), Status::kOk);
  EXPECT_LE(rig.images.views - views, 4u);  // at most k distances inside a sequence
  rig.localiser.reset_sequence();
  EXPECT_EQ(rig.heuristic.query(), 0u);
  EXPECT_EQ(rig.heuristic.next_offset(), 0u);
  views = rig.images.views;
  ASSERT_EQ(rig.localiser.localise(ImageView{img, kSize}, &m), Status::kOk);
  EXPECT_EQ(m.query, 0u);
  EXPECT_EQ(rig.images.views - views, (kHPlaces + 15) / 16);  // a new greedy scan
}

}  // namespace
}  // namespace seqslam
