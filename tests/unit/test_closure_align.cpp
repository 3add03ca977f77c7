// align_closure(): against a double-precision reference of the profile and its vertex; the
// true place recovered on a synthetic route when the matcher's answer is off by up to three
// places, and the fraction's direction; candidates kept inside the known places; bad input and
// storage errors.
#include "seqslam/closure_align.h"

#include "counting_images.h"
#include "synthetic.h"
#include "test.h"

namespace seqslam {
namespace {

constexpr uint32_t kW = 32;
constexpr uint32_t kH = 16;
constexpr uint32_t kStep = 4;  // world columns per place: a place is 4 columns along the strip
constexpr uint32_t kFirstPass = 60;
constexpr uint32_t kSecondPass = 30;
constexpr uint32_t kPlaces = kFirstPass + kSecondPass;

struct Route {
  test::SyntheticWorld<kPlaces * kStep + kW, kH> world;
  PlaceLibraryStorage<kPlaces, kW * kH> storage;
  PlaceLibrary library;
  uint8_t image[kW * kH];
  uint8_t scratch[kW * kH];
};

Route g_route;

// First pass: world places 0..59. Second pass (library places 60..89): world places
// start, start + 1, ... rendered `along` columns further along the strip (a fraction of a
// place: kStep columns make one), under another light (gain, offset) and with more noise.
void build(uint32_t start, int32_t along) {
  Route& r = g_route;
  r.world.generate(11, kPlaces * kStep + kW, kH);
  ASSERT_EQ(r.storage.attach(r.library, ImageSize{kW, kH}), Status::kOk);
  test::Rng rng(3);
  for (uint32_t p = 0; p < kFirstPass; ++p) {
    r.world.render(p, kStep, 0, kW, 256, 0, 2, rng, r.image);
    ASSERT_EQ(r.library.add(ImageView{r.image, ImageSize{kW, kH}}, Pose2{}, p), Status::kOk);
  }
  for (uint32_t i = 0; i < kSecondPass; ++i) {
    r.world.render(start + i, kStep, along, kW, 232, 10, 3, rng, r.image);
    ASSERT_EQ(r.library.add(ImageView{r.image, ImageSize{kW, kH}}, Pose2{}, kFirstPass + i),
              Status::kOk);
  }
}

// The double reference: per pair the smallest mean absolute difference over the overlap of
// the shifts in [-max_shift, max_shift], times the width (unrounded); the same candidates,
// order and tie-break; the vertex in double.
struct Reference {
  double offset = 0;
  uint32_t place = 0;
};

double pair_difference(const uint8_t* a, const uint8_t* b, int max_shift) {
  double best = 1e300;
  for (int dx = -max_shift; dx <= max_shift; ++dx) {
    double sum = 0;
    int cols = 0;
    for (int x = 0; x < static_cast<int>(kW); ++x) {
      const int xa = x + dx;
      if (xa < 0 || xa >= static_cast<int>(kW)) continue;
      ++cols;
      for (uint32_t y = 0; y < kH; ++y) {
        const int d = a[y * kW + static_cast<uint32_t>(xa)] - b[y * kW + static_cast<uint32_t>(x)];
        sum += d < 0 ? -d : d;
      }
    }
    const double mean = sum / cols;
    if (mean < best) best = mean;
  }
  return best * kW;
}

Reference reference(uint32_t current, uint32_t matched, uint32_t known,
                    const ClosureAlignConfig& c) {
  Route& r = g_route;
  uint32_t length = c.length;
  if (length > current + 1) length = current + 1;
  if (length > matched + 1) length = matched + 1;
  const int reach = c.max_offset;
  double profile[2 * kMaxAlignOffset + 1] = {};
  bool valid[2 * kMaxAlignOffset + 1] = {};
  for (int k = -reach; k <= reach; ++k) {
    const int p = static_cast<int>(matched) + k;
    valid[k + reach] = p - static_cast<int>(length) + 1 >= 0 && p < static_cast<int>(known);
    if (!valid[k + reach]) continue;
    for (uint32_t t = 0; t < length; ++t) {
      ImageView a{}, b{};
      EXPECT_EQ(r.library.image(static_cast<uint32_t>(p) - t, &a), Status::kOk);
      for (uint32_t i = 0; i < kW * kH; ++i)
        r.scratch[i] = a.pixels[i];
      EXPECT_EQ(r.library.image(current - t, &b), Status::kOk);
      profile[k + reach] += pair_difference(r.scratch, b.pixels, c.max_shift);
    }
  }
  int best = 0;
  for (int k = 1; k <= reach; ++k)
    for (int sign = -1; sign <= 1; sign += 2)
      if (valid[sign * k + reach] && profile[sign * k + reach] < profile[best + reach])
        best = sign * k;
  double fraction = 0;
  if (best > -reach && best < reach && valid[best - 1 + reach] && valid[best + 1 + reach]) {
    const double l = profile[best - 1 + reach], m = profile[best + reach],
                 rr = profile[best + 1 + reach];
    if (l - 2 * m + rr > 0) fraction = (l - rr) / (2 * (l - 2 * m + rr));
  }
  return Reference{best + fraction, static_cast<uint32_t>(static_cast<int>(matched) + best)};
}

double places(Q15_16 v) {
  return static_cast<double>(v.raw()) / static_cast<double>(Q15_16::from_int(1).raw());
}

TEST(ClosureAlign, MatchesDoubleReference) {
  // Error bound: each pair's difference is rounded to an integer (<= 1/2 off the exact
  // mean x width, against thousands per pair), so a profile value is off by at most L/2 and
  // the vertex by far less than 1e-3 place (measured: 5e-6, the Q15.16 rounding); the place
  // agrees exactly.
  struct Case {
    uint32_t start;
    int32_t along;
    uint32_t current;
    uint32_t matched;
    ClosureAlignConfig config;
  };
  const Case cases[] = {
      {20, 0, 80, 37, {15, 5, 2}},  {20, 3, 80, 40, {15, 5, 2}},  {20, 5, 85, 45, {8, 3, 1}},
      {20, -2, 89, 46, {30, 8, 0}}, {5, 4, 70, 12, {15, 5, 2}},   {5, 0, 62, 6, {15, 5, 2}},
      {30, 6, 89, 58, {1, 4, 3}},   {30, -6, 75, 44, {64, 8, 2}},
  };
  for (const Case& c : cases) {
    build(c.start, c.along);
    ClosureAlignment got;
    ASSERT_EQ(align_closure(g_route.library, c.current, c.matched, kFirstPass, c.config,
                            Span<uint8_t>(g_route.scratch), &got),
              Status::kOk);
    const Reference want = reference(c.current, c.matched, kFirstPass, c.config);
    EXPECT_EQ(got.place, want.place);
    EXPECT_NEAR(places(got.offset), want.offset, 1e-3);
    EXPECT_NEAR(places(got.offset),
                static_cast<double>(got.place) - c.matched + places(got.fraction), 1e-9);
    EXPECT_LE(got.fraction.raw(), 32768);
    EXPECT_GE(got.fraction.raw(), -32768);
  }
}

TEST(ClosureAlign, FindsTheTruePlaceWhenTheMatcherLags) {
  // The second pass starts at world place 20: library place 60 + i is world place 20 + i.
  // A matcher answer three places off either way is moved back to the true place.
  build(20, 0);
  const uint32_t current = kFirstPass + 20;  // world place 40
  for (int32_t lag = -3; lag <= 3; ++lag) {
    ClosureAlignment a;
    const uint32_t matched = static_cast<uint32_t>(40 + lag);
    ASSERT_EQ(align_closure(g_route.library, current, matched, kFirstPass, ClosureAlignConfig{},
                            Span<uint8_t>(g_route.scratch), &a),
              Status::kOk);
    EXPECT_EQ(a.place, 40u);
    EXPECT_NEAR(places(a.offset), -lag, 0.15);
    EXPECT_EQ(a.compared, 15u);
    EXPECT_EQ(a.candidates, 11u);
  }
  // A lag beyond max_offset cannot be corrected: the answer stays within max_offset places.
  ClosureAlignment far;
  ASSERT_EQ(align_closure(g_route.library, current, 33, kFirstPass, ClosureAlignConfig{},
                          Span<uint8_t>(g_route.scratch), &far),
            Status::kOk);
  EXPECT_GE(far.place, 28u);
  EXPECT_LE(far.place, 38u);
}

TEST(ClosureAlign, TheFractionPointsTowardsTheNextPlace) {
  // The second pass rendered a quarter place (1 of 4 columns) further along the route: the
  // nearest place is the true one and the fraction is positive (towards place + 1); a
  // quarter place back gives a negative fraction. Plain differences (max_shift 0) so the
  // along-route offset is not absorbed as a sideways shift. The parabola through a V-shaped
  // profile underestimates the offset: measured 0.05..0.14 place for the true 0.25.
  const ClosureAlignConfig plain{15, 5, 0};
  for (int32_t along = -1; along <= 1; along += 2) {
    build(20, along);
    for (uint32_t i = 10; i < kSecondPass; ++i) {
      ClosureAlignment a;
      ASSERT_EQ(align_closure(g_route.library, kFirstPass + i, 20 + i, kFirstPass, plain,
                              Span<uint8_t>(g_route.scratch), &a),
                Status::kOk);
      EXPECT_EQ(a.place, 20 + i);
      EXPECT_GT(places(a.fraction) * along, 0.03);
      EXPECT_LT(places(a.fraction) * along, 0.25);
    }
  }
}

TEST(ClosureAlign, CandidatesStayInsideTheKnownPlaces) {
  build(20, 0);
  // Places from 41 on are not known (the current run's recent places, say): the true place
  // 40 is found, without a fraction since its upper neighbour did not qualify.
  ClosureAlignment a;
  ASSERT_EQ(align_closure(g_route.library, kFirstPass + 20, 37, 41, ClosureAlignConfig{},
                          Span<uint8_t>(g_route.scratch), &a),
            Status::kOk);
  EXPECT_EQ(a.place, 40u);
  EXPECT_EQ(a.fraction.raw(), 0);
  EXPECT_EQ(a.candidates, 9u);  // 32..40
  // Near the library's start the sequence is shortened to the matched place's history, and
  // candidates whose sequence would begin before place 0 are left out.
  ClosureAlignment b;
  ASSERT_EQ(align_closure(g_route.library, kFirstPass + 1, 3, kFirstPass, ClosureAlignConfig{},
                          Span<uint8_t>(g_route.scratch), &b),
            Status::kOk);
  EXPECT_EQ(b.compared, 4u);    // min(15, current + 1 = 62, matched + 1 = 4)
  EXPECT_EQ(b.candidates, 6u);  // places 3..8: 0..2 would need places before 0
  EXPECT_GE(b.place, 3u);
}

TEST(ClosureAlign, BadInputAndStorageErrors) {
  build(20, 0);
  PlaceLibrary& lib = g_route.library;
  const Span<uint8_t> scratch(g_route.scratch);
  ClosureAlignment out;
  out.place = 12345;
  const ClosureAlignConfig ok{};
  EXPECT_EQ(align_closure(lib, 80, 40, 60, ok, scratch, nullptr), Status::kInvalidArgument);
  EXPECT_EQ(align_closure(lib, 80, 40, 60, ClosureAlignConfig{0, 5, 2}, scratch, &out),
            Status::kInvalidArgument);
  EXPECT_EQ(align_closure(lib, 80, 40, 60, ClosureAlignConfig{65, 5, 2}, scratch, &out),
            Status::kInvalidArgument);
  EXPECT_EQ(align_closure(lib, 80, 40, 60, ClosureAlignConfig{15, 9, 2}, scratch, &out),
            Status::kInvalidArgument);
  EXPECT_EQ(align_closure(lib, 80, 40, 60, ClosureAlignConfig{15, 5, kW}, scratch, &out),
            Status::kInvalidArgument);
  EXPECT_EQ(align_closure(lib, 80, 40, 60, ok, Span<uint8_t>(g_route.scratch, kW * kH - 1), &out),
            Status::kInvalidArgument);
  EXPECT_EQ(align_closure(lib, 80, 40, 60, ok, Span<uint8_t>(), &out), Status::kInvalidArgument);
  EXPECT_EQ(align_closure(lib, kPlaces, 40, 60, ok, scratch, &out), Status::kOutOfRange);
  EXPECT_EQ(align_closure(lib, 80, 40, 81, ok, scratch, &out), Status::kOutOfRange);
  EXPECT_EQ(align_closure(lib, 80, 60, 60, ok, scratch, &out), Status::kOutOfRange);
  PlaceLibrary empty;
  EXPECT_EQ(align_closure(empty, 0, 0, 0, ok, scratch, &out), Status::kOutOfRange);
  EXPECT_EQ(out.place, 12345u);  // untouched by every error

  // A card read that fails midway: its status comes back, the output stays untouched.
  static test::CountingImages failing;
  static uint8_t ram[kPlaces * kW * kH];
  static PlaceInfo info[kPlaces];
  static uint32_t sums[kPlaces];
  ASSERT_EQ(failing.ram.configure(kW * kH, Span<uint8_t>(ram)), Status::kOk);
  PlaceLibrary lib2;
  ASSERT_EQ(lib2.configure(ImageSize{kW, kH}, failing,
                           PlaceLibraryBuffers{Span<PlaceInfo>(info), Span<uint32_t>(sums)}),
            Status::kOk);
  for (uint32_t p = 0; p < kPlaces; ++p) {
    ImageView v{};
    ASSERT_EQ(lib.image(p, &v), Status::kOk);
    for (uint32_t i = 0; i < kW * kH; ++i)
      g_route.image[i] = v.pixels[i];
    ASSERT_EQ(lib2.add(ImageView{g_route.image, ImageSize{kW, kH}}, Pose2{}, p), Status::kOk);
  }
  failing.failure = Status::kDataLoss;
  const uint32_t fail_at[] = {0, 1, 7, 100};  // a profile needs 15 x 12 = 180 reads
  for (const uint32_t read : fail_at) {
    failing.views = 0;
    failing.fail_at = read;
    EXPECT_EQ(align_closure(lib2, 80, 40, 60, ok, scratch, &out), Status::kDataLoss);
    EXPECT_EQ(out.place, 12345u);
  }
  failing.fail_at = 0xFFFFFFFFu;
  EXPECT_EQ(align_closure(lib2, 80, 40, 60, ok, scratch, &out), Status::kOk);
  EXPECT_EQ(out.place, 40u);
}

}  // namespace
}  // namespace seqslam
