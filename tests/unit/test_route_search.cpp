// The route search (the head board's localiser, route_search.h) through the Localiser, with a
// library that keeps no per-place RAM: while tracking it gives the full search's answers where
// the full search is sure; it recovers from a kidnap and an unknown start with the
// relocalisation scan; storage failures change nothing; it runs off the library's end safely;
// bad settings are named.
#include "seqslam/localiser.h"

#include "counting_images.h"
#include "synthetic.h"
#include "test.h"

namespace seqslam {
namespace {

constexpr uint32_t kPlaces = 240;
constexpr uint32_t kStep = 2;  // columns the camera moves per place
const ImageSize kSize{32, 16};
constexpr uint16_t kSeq = 10;

using World = test::SyntheticWorld<kPlaces * kStep + 64, 16>;

LocaliserConfig test_config() {
  LocaliserConfig c;
  c.image_size = kSize;
  c.preprocess.method = Preprocessing::kHistEq;  // as written (the default before issue 33)
  c.sequence.seq_len = kSeq;
  c.sequence.window = 20;
  c.route.window = 25;  // R = 10: the smallest window with a runner-up is 23
  c.route.lost_after = 12;
  c.route.scan_places = 24;
  return c;
}

// Two localisers on one library: the route search (no per-place RAM, images counted) and the
// full search (the reference).
struct Rig {
  PlaceLibraryStorage<kPlaces, 512> library_storage;
  test::CountingImages images;
  PlaceLibrary library;
  RouteSearchStorage<31, kSeq, kSeq, 20, 10> route_storage;
  RamQueryHistoryStorage<64, 512> history_storage;
  RamQueryHistory history;
  RouteSearch route;
  Localiser localiser;
  DiagonalMatcherStorage<kPlaces, kSeq> full_storage;
  uint32_t differences[kPlaces];
  Localiser full;

  ConfigCheck setup(const LocaliserConfig& c, uint64_t seed, World& world) {
    world.generate(seed, kPlaces * kStep + 64, 16);
    EXPECT_EQ(images.ram.configure(512, Span<uint8_t>(library_storage.pixels, kPlaces * 512)),
              Status::kOk);
    EXPECT_EQ(library.configure(kSize, images, PlaceLibraryBuffers{}), Status::kOk);
    EXPECT_EQ(history_storage.attach(history, 512), Status::kOk);
    const ConfigCheck check =
        localiser.configure(c, library, route, route_storage.buffers(), history);
    if (!check.ok()) return check;
    EXPECT_TRUE(
        full.configure(c, library, full_storage.buffers(), Span<uint32_t>(differences, kPlaces))
            .ok());
    test::Rng rng(seed + 1);
    uint8_t img[512];
    for (uint32_t p = 0; p < kPlaces; ++p) {
      world.render(p, kStep, 0, 32, 256, 0, 3, rng, img);
      EXPECT_EQ(localiser.teach(ImageView{img, kSize}, Pose2{}, p), Status::kOk);
    }
    return check;
  }
};

bool near(int32_t place, uint32_t truth) {
  const int32_t err = place - static_cast<int32_t>(truth);
  return err >= -1 && err <= 1;
}

TEST(RouteSearch, TrackingAgreesWithTheFullSearchWhereItIsSure) {
  static World world;
  static Rig rig;
  ASSERT_TRUE(rig.setup(test_config(), 61, world).ok());
  test::Rng rng(62);
  uint8_t img[512];
  uint32_t full_sure = 0, agree = 0, route_fix = 0, route_right = 0, full_right = 0, scans = 0;
  for (uint32_t q = 0; q < kPlaces; ++q) {
    // Darker, offset, noisier, and up to one column off.
    world.render(q, kStep, rng.range(-1, 1), 32, 180, 30, 6, rng, img);
    Match a;
    Match b;
    ASSERT_EQ(rig.localiser.localise(ImageView{img, kSize}, &a), Status::kOk);
    ASSERT_EQ(rig.full.localise(ImageView{img, kSize}, &b), Status::kOk);
    // The scan runs beside the window at every step (its verdicts agree or say nothing).
    const RouteStepInfo& info = rig.localiser.route_step();
    if (info.scan_completed) ++scans;
    EXPECT_FALSE(info.probation) << "step " << q << ": no candidate elsewhere";
    if (q + 1 < kSeq) {
      EXPECT_EQ(a.place, -1);
      continue;
    }
    if (b.localised) {
      ++full_sure;
      if (a.place == b.place) ++agree;
    }
    if (a.localised) {
      ++route_fix;
      EXPECT_TRUE(near(a.place, q)) << "step " << q << " fix at " << a.place;
    }
    if (near(a.place, q)) ++route_right;
    if (near(b.place, q)) ++full_right;
  }
  EXPECT_GT(full_sure, 100u);
  EXPECT_EQ(agree, full_sure);
  EXPECT_GE(route_right, full_right);
  EXPECT_GT(route_fix, 100u);
  EXPECT_GT(scans, 10u);
}

// A query pass that drives places 0..79, is lifted to place 160 and drives on to the end:
// the window (around 80..) finds nothing; the scan, which runs beside it at every step, finds
// the new place, a candidate followed beside the prediction (probation: the window's answers
// are not fixes, the prediction stays odometry's) until its evidence over its steps beats the
// prediction's over the same steps; then it wins (the jump's fix, "carried"), the prediction
// moves there and the window, re-seeded from the history, tracks there at once.
TEST(RouteSearch, AKidnapIsRecoveredByTheCandidateWinning) {
  static World world;
  static Rig rig;
  ASSERT_TRUE(rig.setup(test_config(), 63, world).ok());
  test::Rng rng(64);
  uint8_t img[512];
  uint32_t scans = 0, wins = 0, wrong_fixes = 0, probation_steps = 0, fixes_after = 0;
  int32_t before = 0;  // the prediction's diagonal before the lift
  int32_t first_fix_after = -1;
  const uint32_t kKidnap = 80, kTo = 160;
  for (uint32_t q = 0; q < kKidnap + (kPlaces - kTo); ++q) {
    const uint32_t truth = q < kKidnap ? q : kTo + (q - kKidnap);
    world.render(truth, kStep, rng.range(-1, 1), 32, 190, 25, 5, rng, img);
    Match m;
    ASSERT_EQ(rig.localiser.localise(ImageView{img, kSize}, &m), Status::kOk);
    const RouteStepInfo& info = rig.localiser.route_step();
    if (info.scan_completed) ++scans;
    if (info.probation) {
      ++probation_steps;
      EXPECT_GE(q, kKidnap) << "no candidate before the lift";
      // The candidate has not moved the prediction: the diagonal before the lift.
      EXPECT_EQ(info.prediction, before) << "step " << q;
      // The answer is the window's, never a fix, unless the candidate wins at this step.
      EXPECT_EQ(m.localised, info.carried) << "step " << q;
    }
    if (info.carried) {
      ++wins;
      EXPECT_TRUE(info.fix);
      EXPECT_TRUE(near(m.place, truth)) << "step " << q << ": the jump's fix at " << m.place;
    }
    if (q < kKidnap) before = info.prediction;
    // For S - 1 steps after the lift the sequence still holds mostly the old segment's images
    // and its diagonal stays the best (the full search does the same): not counted.
    if (m.localised && !near(m.place, truth) && (q < kKidnap || q >= kKidnap + kSeq - 1)) {
      ++wrong_fixes;
    }
    if (q >= kKidnap && m.localised && near(m.place, truth)) {
      if (first_fix_after < 0) first_fix_after = static_cast<int32_t>(q - kKidnap);
      ++fixes_after;
    }
  }
  EXPECT_EQ(wrong_fixes, 0u);
  EXPECT_GE(scans, 1u);
  EXPECT_EQ(wins, 1u);
  EXPECT_GT(probation_steps, 0u);
  // The scan's 10 images all after the lift, a scan over 240 places at 24 a step (10 steps),
  // then the candidate's S = 10 steps of evidence (caught up from the history) win at once.
  ASSERT_GE(first_fix_after, 0);
  EXPECT_LE(first_fix_after, 10 + 10 + 2);
  // The re-seeded window tracks from the jump on: most of the remaining places are fixes.
  EXPECT_GT(fixes_after, (kPlaces - kTo) / 2);
}

// Two lifts in quick succession (more candidates than the one the search follows): 0..79,
// lifted to 160 for 12 places, then to 30. The first candidate (160) is followed while later
// scans name other places (ignored: one candidate at a time); when the robot leaves 160 its
// evidence stops beating the prediction's and it is dropped, and the next scan's candidate
// (30..) wins. No fix is wrong at any time, and the search ends localised at the last place.
TEST(RouteSearch, ACandidateThatStopsMatchingIsDroppedAndTheNextOneWins) {
  static World world;
  static Rig rig;
  ASSERT_TRUE(rig.setup(test_config(), 91, world).ok());
  test::Rng rng(92);
  uint8_t img[512];
  uint32_t wrong_fixes = 0, wins = 0, fixes_at_end = 0;
  constexpr uint32_t kFirst = 80, kSecond = 92, kEnd = 160;
  for (uint32_t q = 0; q < kEnd; ++q) {
    const uint32_t truth = q < kFirst ? q : q < kSecond ? 160 + (q - kFirst) : 30 + (q - kSecond);
    world.render(truth, kStep, rng.range(-1, 1), 32, 190, 25, 5, rng, img);
    Match m;
    ASSERT_EQ(rig.localiser.localise(ImageView{img, kSize}, &m), Status::kOk);
    const RouteStepInfo& info = rig.localiser.route_step();
    if (info.carried) ++wins;
    const bool settling = (q >= kFirst && q < kFirst + kSeq - 1) ||
                          (q >= kSecond && q < kSecond + kSeq - 1);
    if (m.localised && !near(m.place, truth) && !settling) ++wrong_fixes;
    if (q >= kEnd - 20 && m.localised && near(m.place, truth)) ++fixes_at_end;
  }
  EXPECT_EQ(wrong_fixes, 0u);
  EXPECT_GE(wins, 1u);
  EXPECT_GT(fixes_at_end, 10u);
}

// The scan's share of a step streamed in slices between steps (as the firmware does after
// every snapshot), any number of them or none: every answer and every step's report is the
// same as when the next step streams it all. A kidnap makes the scans' verdicts matter.
TEST(RouteSearch, SlicingTheScanBetweenStepsChangesNoAnswer) {
  static World world;
  static Rig whole;
  static Rig sliced;
  LocaliserConfig c = test_config();
  c.route.scan_places = 100;  // a scan of 240 places takes three steps
  ASSERT_TRUE(whole.setup(c, 77, world).ok());
  ASSERT_TRUE(sliced.setup(c, 77, world).ok());
  test::Rng rng_a(78), rng_b(78), slices(79);
  uint8_t img_a[512], img_b[512];
  uint32_t completed = 0, jumps = 0, sliced_places = 0;
  for (uint32_t q = 0; q < 150; ++q) {
    const uint32_t truth = q < 60 ? q : q + 100;  // lifted from place 60 to 160
    world.render(truth, kStep, 0, 32, 190, 20, 5, rng_a, img_a);
    world.render(truth, kStep, 0, 32, 190, 20, 5, rng_b, img_b);
    Match a, b;
    ASSERT_EQ(whole.localiser.localise(ImageView{img_a, kSize}, &a), Status::kOk);
    ASSERT_EQ(sliced.localiser.localise(ImageView{img_b, kSize}, &b), Status::kOk);
    const RouteStepInfo& x = whole.localiser.route_step();
    const RouteStepInfo& y = sliced.localiser.route_step();
    ASSERT_EQ(a.place, b.place) << "step " << q;
    ASSERT_EQ(a.runner_up, b.runner_up) << "step " << q;
    ASSERT_EQ(a.confidence.raw(), b.confidence.raw()) << "step " << q;
    ASSERT_EQ(a.localised, b.localised) << "step " << q;
    ASSERT_EQ(x.prediction, y.prediction) << "step " << q;
    ASSERT_EQ(x.probation, y.probation) << "step " << q;
    ASSERT_EQ(x.scan_completed, y.scan_completed) << "step " << q;
    ASSERT_EQ(x.scan_jumped, y.scan_jumped) << "step " << q;
    ASSERT_EQ(x.scan_streamed, y.scan_streamed) << "step " << q;
    completed += x.scan_completed;
    jumps += x.scan_jumped;
    // 0 to 5 slices of 1 to 40 places: some steps leave part of the share to the next.
    const uint32_t n = static_cast<uint32_t>(slices.range(0, 5));
    for (uint32_t k = 0; k < n; ++k)
      sliced_places += sliced.localiser.work(static_cast<uint32_t>(slices.range(1, 40)));
  }
  EXPECT_GT(completed, 20u);
  EXPECT_GE(jumps, 1u);
  EXPECT_GT(sliced_places, 1000u);
}

// A won candidate's re-seeding replays the last S steps between places, in pieces of at most
// the slice's budget, before the step's scan share; the scan still streams its whole share
// (scan_places) after a win, so it keeps the pace the run checks count on.
TEST(RouteSearch, ReseedingIsSlicedAndLeavesTheScanItsShare) {
  static World world;
  static Rig rig;
  LocaliserConfig c = test_config();
  c.route.scan_places = 100;  // a scan of 240 places takes three steps
  ASSERT_TRUE(rig.setup(c, 77, world).ok());
  test::Rng rng(78);
  uint8_t img[512];
  uint32_t wins = 0, replayed_after_win = 0;
  bool after_win = false;
  uint32_t done = 0;  // places worked between the last step and this one
  for (uint32_t q = 0; q < 150; ++q) {
    const uint32_t truth = q < 60 ? q : q + 100;  // lifted from place 60 to 160
    world.render(truth, kStep, 0, 32, 190, 20, 5, rng, img);
    Match m;
    ASSERT_EQ(rig.localiser.localise(ImageView{img, kSize}, &m), Status::kOk);
    const RouteStepInfo& info = rig.localiser.route_step();
    if (after_win && !info.scan_completed) {
      // The scan streamed its share; everything else worked since the win was replaying.
      EXPECT_EQ(info.scan_streamed, 100u) << "step " << q;
      EXPECT_GT(done, info.scan_streamed) << "step " << q;
      replayed_after_win += done - info.scan_streamed;
    }
    after_win = info.carried;
    wins += info.carried;
    done = 0;
    while (rig.route.pending() > 0) {
      const uint32_t n = rig.localiser.work(24);
      EXPECT_LE(n, 24u);
      done += n;
    }
  }
  EXPECT_GE(wins, 1u);
  // S = 10 replayed steps, each its band of 45 places (window 25 + W 20), after every win.
  EXPECT_GE(replayed_after_win, wins * kSeq * 45u);
}

// A library larger than the scan can keep up with: at 2 places a step a scan of 240 places
// takes 120 steps, longer than the 64-step history keeps its anchor's images. Every scan is
// abandoned when they are overwritten (the step says so: kNotFound) and the next one starts;
// no step fails, nothing is a jump, and tracking goes on as without the scan.
TEST(RouteSearch, AScanThatCannotKeepUpIsAbandonedAndTrackingGoesOn) {
  static World world;
  static Rig slow;
  static Rig fast;
  LocaliserConfig c = test_config();
  c.route.scan_places = 2;
  ASSERT_TRUE(slow.setup(c, 81, world).ok());
  ASSERT_TRUE(fast.setup(test_config(), 81, world).ok());
  test::Rng rng_a(82), rng_b(82);
  uint8_t img_a[512], img_b[512];
  uint32_t abandoned = 0, completed = 0, jumps = 0, slow_right = 0, fast_right = 0;
  for (uint32_t q = 0; q < 200; ++q) {
    world.render(q, kStep, 0, 32, 190, 20, 5, rng_a, img_a);
    world.render(q, kStep, 0, 32, 190, 20, 5, rng_b, img_b);
    Match a, b;
    ASSERT_EQ(slow.localiser.localise(ImageView{img_a, kSize}, &a), Status::kOk) << q;
    ASSERT_EQ(fast.localiser.localise(ImageView{img_b, kSize}, &b), Status::kOk) << q;
    const RouteStepInfo& info = slow.localiser.route_step();
    if (info.scan_status == Status::kNotFound) ++abandoned;
    completed += info.scan_completed;
    jumps += info.scan_jumped;
    if (a.localised) {
      EXPECT_TRUE(near(a.place, q)) << "step " << q;
      ++slow_right;
    }
    if (b.localised && near(b.place, q)) ++fast_right;
  }
  EXPECT_GE(abandoned, 2u);
  EXPECT_EQ(completed, 0u);
  EXPECT_EQ(jumps, 0u);
  EXPECT_GT(slow_right, 100u);
  EXPECT_GE(slow_right + 10, fast_right);
}

TEST(RouteSearch, AnUnknownStartIsFoundByTheScan) {
  static World world;
  static Rig rig;
  LocaliserConfig c = test_config();
  c.route.start = -1;
  ASSERT_TRUE(rig.setup(c, 65, world).ok());
  test::Rng rng(66);
  uint8_t img[512];
  int32_t first_fix = -1;
  uint32_t wrong_fixes = 0;
  const uint32_t kFrom = 100;  // the query pass starts in the middle of the library
  for (uint32_t q = 0; q + kFrom < kPlaces; ++q) {
    world.render(kFrom + q, kStep, 0, 32, 200, 20, 5, rng, img);
    Match m;
    ASSERT_EQ(rig.localiser.localise(ImageView{img, kSize}, &m), Status::kOk);
    if (m.localised) {
      if (first_fix < 0) first_fix = static_cast<int32_t>(q);
      if (!near(m.place, kFrom + q)) ++wrong_fixes;
    }
  }
  EXPECT_EQ(wrong_fixes, 0u);
  ASSERT_GE(first_fix, 0);
  EXPECT_LE(first_fix, 2 * kSeq + 10 + 2);
}

// A library read that fails while tracking: the step reports the card's status and changes
// nothing, so retrying it gives exactly the answers of a run without the failure.
TEST(RouteSearch, AFailingCardReadWhileTrackingChangesNothing) {
  static World world;
  static Rig clean;
  static Rig failing;
  const LocaliserConfig c = test_config();
  ASSERT_TRUE(clean.setup(c, 67, world).ok());
  ASSERT_TRUE(failing.setup(c, 67, world).ok());
  test::Rng rng_a(68), rng_b(68);
  uint8_t img_a[512], img_b[512];
  uint32_t failures = 0;
  for (uint32_t q = 0; q < 120; ++q) {
    world.render(q, kStep, 0, 32, 190, 20, 5, rng_a, img_a);
    world.render(q, kStep, 0, 32, 190, 20, 5, rng_b, img_b);
    Match a, b;
    ASSERT_EQ(clean.localiser.localise(ImageView{img_a, kSize}, &a), Status::kOk);
    if (q % 7 == 3) {
      // The last step's share of the scan streamed first (as the firmware does between
      // snapshots; the clean rig leaves it to the step: the answers are the same), so the
      // step's first read is the window's.
      failing.localiser.work(0xFFFFFFFFu);
      failing.images.fail_at = failing.images.views;  // the step's first read fails
      failing.images.failure = Status::kDataLoss;
      EXPECT_EQ(failing.localiser.localise(ImageView{img_b, kSize}, &b), Status::kDataLoss);
      ++failures;
    }
    ASSERT_EQ(failing.localiser.localise(ImageView{img_b, kSize}, &b), Status::kOk) << q;
    EXPECT_EQ(a.place, b.place) << "step " << q;
    EXPECT_EQ(a.confidence.raw(), b.confidence.raw()) << "step " << q;
    EXPECT_EQ(a.localised, b.localised) << "step " << q;
  }
  EXPECT_GT(failures, 10u);
}

// A library read that fails while the scan runs does not fail the step (the answer is the
// carried prediction either way): the step says so, the chunk is read again at the next step,
// and the scan ends one step later with the same answer as without the failure.
TEST(RouteSearch, AFailingCardReadInTheScanDelaysItByAStep) {
  static World world;
  static Rig clean;
  static Rig failing;
  LocaliserConfig c = test_config();
  c.route.start = -1;  // the scan runs from step S - 1 on
  ASSERT_TRUE(clean.setup(c, 73, world).ok());
  ASSERT_TRUE(failing.setup(c, 73, world).ok());
  test::Rng rng_a(74), rng_b(74);
  uint8_t img_a[512], img_b[512];
  int32_t clean_done = -1, failing_done = -1;
  Match clean_fix, failing_fix;
  bool injected = false;
  for (uint32_t q = 0; q < 60 && (clean_done < 0 || failing_done < 0); ++q) {
    world.render(50 + q, kStep, 0, 32, 190, 20, 5, rng_a, img_a);
    world.render(50 + q, kStep, 0, 32, 190, 20, 5, rng_b, img_b);
    Match a, b;
    ASSERT_EQ(clean.localiser.localise(ImageView{img_a, kSize}, &a), Status::kOk);
    if (clean.localiser.route_step().scan_completed && clean_done < 0) {
      clean_done = static_cast<int32_t>(q);
      clean_fix = a;
    }
    const bool scan_step = q >= kSeq + 1;  // the scan started at S - 1 and is running
    if (scan_step && !injected) {
      failing.images.fail_at = failing.images.views;
      failing.images.failure = Status::kDataLoss;
      injected = true;
    }
    ASSERT_EQ(failing.localiser.localise(ImageView{img_b, kSize}, &b), Status::kOk) << q;
    if (q == kSeq + 1) {
      EXPECT_EQ(failing.localiser.route_step().scan_status, Status::kDataLoss);
    }
    if (failing.localiser.route_step().scan_completed && failing_done < 0) {
      failing_done = static_cast<int32_t>(q);
      failing_fix = b;
    }
  }
  ASSERT_GE(clean_done, 0);
  EXPECT_EQ(failing_done, clean_done + 1);
  // The same verdict, carried one place further.
  EXPECT_EQ(failing_fix.place, clean_fix.place + 1);
  EXPECT_EQ(failing_fix.confidence.raw(), clean_fix.confidence.raw());
  EXPECT_EQ(failing_fix.localised, clean_fix.localised);
}

// The query pass goes on past the library's last place (the route was longer this time) for
// 20 places, then comes back to its start (a loop): the window runs off the end, no answer
// leaves the library, nothing out there is a fix, and the scan finds the start again.
TEST(RouteSearch, RunningOffTheLibrarysEnd) {
  static World world;
  static Rig rig;
  ASSERT_TRUE(rig.setup(test_config(), 69, world).ok());
  test::Rng rng(70);
  uint8_t img[512];
  uint32_t wrong_fixes = 0, fixes_past_end = 0, fixes_after_loop = 0;
  constexpr uint32_t kBeyond = 20;
  for (uint32_t q = 0; q < kPlaces + kBeyond + 80; ++q) {
    const uint32_t truth = q % (kPlaces + kBeyond);
    world.render(truth, kStep, 0, 32, 200, 20, 5, rng, img);
    Match m;
    ASSERT_EQ(rig.localiser.localise(ImageView{img, kSize}, &m), Status::kOk);
    EXPECT_LT(m.place, static_cast<int32_t>(kPlaces));
    // S - 1 steps after each change the sequence still holds the previous images.
    const bool settled = q < kPlaces + kSeq - 1 || q >= kPlaces + kBeyond + kSeq - 1;
    if (m.localised && settled && !near(m.place, truth)) ++wrong_fixes;
    if (m.localised && truth >= kPlaces) ++fixes_past_end;
    if (m.localised && q >= kPlaces + kBeyond) ++fixes_after_loop;
  }
  EXPECT_EQ(wrong_fixes, 0u);
  EXPECT_LE(fixes_past_end, static_cast<uint32_t>(kSeq - 1));
  EXPECT_GT(fixes_after_loop, 0u);
}

// Loop closure (teach + repeat): the places searched are the library's older ones, none at
// first, then one more a step. No scan starts before there is a place to scan (it used to
// complete empty at its start and then fail its first advance, a false card error), and the
// scan runs once there are places.
TEST(RouteSearch, NoScanOfAnEmptyLibrary) {
  static World world;
  static Rig rig;
  LocaliserConfig c = test_config();
  c.route.start = -1;
  ASSERT_TRUE(rig.setup(c, 75, world).ok());
  test::Rng rng(76);
  uint8_t img[512];
  constexpr uint32_t kEmpty = 30;  // steps with nothing to search
  uint32_t scanned = 0;
  for (uint32_t q = 0; q < kEmpty + 40; ++q) {
    world.render(q, kStep, 0, 32, 200, 20, 5, rng, img);
    const uint32_t places = q < kEmpty ? 0 : q - kEmpty + 1;
    Match m;
    RouteStepInfo info;
    ASSERT_EQ(rig.route.step(rig.library, ImageView{img, kSize}, places, &m, &info), Status::kOk);
    EXPECT_EQ(info.scan_status, Status::kOk) << "step " << q;
    if (places == 0) {
      EXPECT_FALSE(info.scan_running) << "step " << q;
      EXPECT_FALSE(info.scan_completed) << "step " << q;
      EXPECT_EQ(m.place, -1) << "step " << q;
    }
    scanned += info.scan_streamed;
  }
  EXPECT_GT(scanned, 0u);
}

TEST(RouteSearch, SettingsAreCheckedAndNamed) {
  static World world;
  static Rig rig;
  struct Case {
    int window;
    int lost_after;
    int scan_places;
    int start;
    Status status;
    ConfigIssue issue;
  };
  const Case cases[] = {
      {24, 12, 24, 0, Status::kOutOfRange, ConfigIssue::kRouteWindowOutOfRange},  // even
      {21, 12, 24, 0, Status::kOutOfRange, ConfigIssue::kRouteWindowOutOfRange},  // < 2R + 3
      {33, 12, 24, 0, Status::kOutOfRange, ConfigIssue::kRouteWindowOutOfRange},  // > 31 slots
      {25, 0, 24, 0, Status::kInvalidArgument, ConfigIssue::kRouteLostAfterZero},
      {25, 12, 0, 0, Status::kInvalidArgument, ConfigIssue::kRouteScanPlacesZero},
      {25, 12, 24, -2, Status::kOutOfRange, ConfigIssue::kRouteStartOutOfRange},
  };
  for (const Case& k : cases) {
    LocaliserConfig c = test_config();
    c.route.window = static_cast<uint16_t>(k.window);
    c.route.lost_after = static_cast<uint16_t>(k.lost_after);
    c.route.scan_places = static_cast<uint16_t>(k.scan_places);
    c.route.start = k.start;
    const ConfigCheck check = rig.setup(c, 71, world);
    EXPECT_EQ(check.status, k.status) << config_issue_text(k.issue);
    EXPECT_EQ(check.issue, k.issue) << config_issue_text(check.issue);
  }
  // A normalisation window wider than the storage was sized for (band and scan rings).
  LocaliserConfig c = test_config();
  c.sequence.window = 30;
  EXPECT_EQ(rig.setup(c, 71, world).issue, ConfigIssue::kRouteStorageTooSmall);
  // The scan's sequence: at least one step (and never longer than S: a longer setting is S).
  c = test_config();
  c.route.scan_seq_len = 0;
  EXPECT_EQ(rig.setup(c, 71, world).issue, ConfigIssue::kRouteScanSeqLenOutOfRange);
  c.route.scan_seq_len = 99;
  ASSERT_TRUE(rig.setup(c, 71, world).ok());
  EXPECT_EQ(rig.route.scan().config().seq_len, kSeq);
  // A candidate needs at least one step of evidence (and never more than S: a longer setting
  // is S, as is a longer tail).
  c = test_config();
  c.route.jump_steps = 0;
  EXPECT_EQ(rig.setup(c, 71, world).issue, ConfigIssue::kRouteJumpStepsZero);
  c.route.jump_steps = 500;
  c.route.tail_steps = 500;
  EXPECT_TRUE(rig.setup(c, 71, world).ok());
  // The route search uses the plain SAD.
  c = test_config();
  c.max_shift = 2;
  EXPECT_EQ(rig.setup(c, 71, world).issue, ConfigIssue::kRouteMaxShift);
  // The heuristic is not a route search.
  c = test_config();
  c.matcher = LocaliserMatcher::kHeuristic;
  EXPECT_EQ(rig.setup(c, 71, world).issue, ConfigIssue::kRouteHeuristic);
  // Unconfigured: refused, not crashed.
  Localiser idle;
  Match m;
  uint8_t img[512] = {};
  EXPECT_EQ(idle.localise(ImageView{img, kSize}, &m), Status::kFailedPrecondition);
}

}  // namespace
}  // namespace seqslam
