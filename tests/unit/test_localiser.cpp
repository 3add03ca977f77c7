// The localiser end to end on synthetic routes: teach and repeat under an illumination
// change, loop closure in a single run, and configuration errors that name the problem.
#include "seqslam/localiser.h"

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

TEST(Localiser, ConfigurationErrorsNameTheSetting) {
  static Rig rig;
  struct Case {
    LocaliserConfig config;
    Status status;
    ConfigIssue issue;
  };
  LocaliserConfig c = test_config();
  Case cases[12];
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
  for (int i = 0; i < n; ++i) {
    const ConfigCheck check = check_localiser_config(cases[i].config);
    EXPECT_EQ(check.status, cases[i].status) << "case " << i;
    EXPECT_EQ(check.issue, cases[i].issue) << "case " << i;
    EXPECT_TRUE(config_issue_text(check.issue)[0] != '\0');
  }
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

}  // namespace
}  // namespace seqslam
