// tools::run_route (seqslam_tools/core_run.h), the route search behind `seqslam run / eval
// --search route`, against the firmware's configuration of the same search: the end-to-end
// tests' CoreRun (tests/host/e2e/core_run.h: a Localiser configured as firmware/app configures
// it, which the firmware's own results are tested against):
//  - step for step the same answers (place, runner-up, confidence, localised) and the same
//    route flags, on the corridor with a kidnap (a scan, a jump, carried answers, probation),
//    with the defaults and with other settings (which do change the answers);
//  - the same with and without the library's per-place RAM;
//  - what the firmware cannot run is refused, naming the setting.
#include <cstdint>
#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "core_run.h"  // tests/host/e2e: the firmware's configuration
#include "seqslam/seqslam.h"
#include "seqslam_tools/core_run.h"
#include "seqslam_tools/evaluation.h"
#include "test_util.h"

namespace seqslam::tools {
namespace {

using ::testing::HasSubstr;

constexpr uint32_t kCorridorImages = 111;

class RouteRun : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    const ImageSize size = LocaliserConfig{}.image_size;  // the corridor at the default size
    auto lib = load_input(test::corridor_dir() + "/ref", size.width, size.height);
    auto qry = load_input(test::corridor_dir() + "/query", size.width, size.height);
    ASSERT_TRUE(lib.ok()) << lib.error();
    ASSERT_TRUE(qry.ok()) << qry.error();
    ASSERT_EQ(lib.value().images.size(), kCorridorImages);
    ASSERT_EQ(qry.value().images.size(), kCorridorImages);
    library_ = new std::vector<GrayImage>(lib.value().images);
    // The query run with a kidnap: places 0..70, then lifted back to place 20 and on to the
    // end (162 queries): the window loses the route, a scan finds it again.
    kidnapped_ = new std::vector<GrayImage>();
    for (uint32_t i = 0; i <= 70; ++i)
      kidnapped_->push_back(qry.value().images[i]);
    for (uint32_t i = 20; i < kCorridorImages; ++i)
      kidnapped_->push_back(qry.value().images[i]);
  }
  static void TearDownTestSuite() {
    delete library_;
    delete kidnapped_;
    library_ = nullptr;
    kidnapped_ = nullptr;
  }

  // The firmware's configuration of the same run (CoreRun), step by step.
  struct FirmwareStep {
    Match match;
    RouteStepInfo info;
  };
  static std::vector<FirmwareStep> firmware_steps(const LocaliserConfig& config) {
    auto run = std::make_unique<seqslam::test::CoreRun<kCorridorImages>>(config);
    EXPECT_TRUE(run->ok());
    std::vector<seqslam::test::Image> lib;
    for (const GrayImage& g : *library_)
      lib.push_back(g.pixels);
    EXPECT_TRUE(run->teach(lib));
    std::vector<FirmwareStep> out;
    for (const GrayImage& g : *kidnapped_) {
      FirmwareStep s;
      EXPECT_TRUE(run->localise(g.pixels, &s.match));
      s.info = run->localiser().route_step();
      out.push_back(s);
    }
    return out;
  }

  // Equal answers and flags; returns how often each flag occurred (to show the comparison
  // covered them).
  struct Seen {
    size_t places = 0, localised = 0, scans = 0, jumps = 0, carried = 0, probation = 0;
  };
  static Seen expect_same(const std::vector<RouteCoreMatch>& tool,
                          const std::vector<FirmwareStep>& firmware, const std::string& what) {
    Seen seen;
    EXPECT_EQ(tool.size(), firmware.size()) << what;
    for (size_t q = 0; q < tool.size() && q < firmware.size(); ++q) {
      const Match& a = tool[q].match;
      const Match& b = firmware[q].match;
      EXPECT_EQ(a.query, b.query) << what << " q=" << q;
      EXPECT_EQ(a.place, b.place) << what << " q=" << q;
      EXPECT_EQ(a.runner_up, b.runner_up) << what << " q=" << q;
      EXPECT_EQ(a.cost, b.cost) << what << " q=" << q;
      EXPECT_EQ(a.runner_up_cost, b.runner_up_cost) << what << " q=" << q;
      EXPECT_EQ(a.confidence.raw(), b.confidence.raw()) << what << " q=" << q;
      EXPECT_EQ(a.localised, b.localised) << what << " q=" << q;
      const RouteStepInfo& x = tool[q].info;
      const RouteStepInfo& y = firmware[q].info;
      EXPECT_EQ(x.tracking, y.tracking) << what << " q=" << q;
      EXPECT_EQ(x.probation, y.probation) << what << " q=" << q;
      EXPECT_EQ(x.prediction, y.prediction) << what << " q=" << q;
      EXPECT_EQ(x.search_radius, y.search_radius) << what << " q=" << q;
      EXPECT_EQ(x.fix, y.fix) << what << " q=" << q;
      EXPECT_EQ(x.carried, y.carried) << what << " q=" << q;
      EXPECT_EQ(x.scan_running, y.scan_running) << what << " q=" << q;
      EXPECT_EQ(x.scan_completed, y.scan_completed) << what << " q=" << q;
      EXPECT_EQ(x.scan_jumped, y.scan_jumped) << what << " q=" << q;
      EXPECT_EQ(x.scan_streamed, y.scan_streamed) << what << " q=" << q;
      EXPECT_EQ(x.scan_status, Status::kOk) << what << " q=" << q;
      seen.places += a.place >= 0;
      seen.localised += a.localised;
      seen.scans += x.scan_completed;
      seen.jumps += x.scan_jumped;
      seen.carried += x.carried;
      seen.probation += x.probation;
    }
    return seen;
  }

  static std::vector<GrayImage>* library_;
  static std::vector<GrayImage>* kidnapped_;
};
std::vector<GrayImage>* RouteRun::library_ = nullptr;
std::vector<GrayImage>* RouteRun::kidnapped_ = nullptr;

TEST_F(RouteRun, EqualsTheFirmwaresConfigurationWithTheDefaults) {
  const LocaliserConfig config;  // the defaults, route search's too
  const auto tool = run_route(*library_, *kidnapped_, config);
  ASSERT_TRUE(tool.ok()) << tool.error();
  const Seen seen = expect_same(tool.value(), firmware_steps(config), "defaults");
  // Not vacuous: the kidnap needed a scan and a jump; answers were carried and on probation,
  // and the route was found again (localised answers after the kidnap).
  EXPECT_GT(seen.localised, 0u);
  EXPECT_GT(seen.scans, 0u);
  EXPECT_GT(seen.jumps, 0u);
  EXPECT_GT(seen.carried, 0u);
  EXPECT_GT(seen.probation, 0u);
  size_t localised_after = 0;
  for (size_t q = 71; q < tool.value().size(); ++q)
    localised_after += tool.value()[q].match.localised;
  EXPECT_GT(localised_after, 0u);
}

TEST_F(RouteRun, EqualsTheFirmwaresConfigurationWithOtherSettings) {
  LocaliserConfig config;
  config.sequence.seq_len = 20;
  config.route.window = 25;
  config.route.slack = 3;
  config.route.growth = UQ8_8::from_ratio(1, 10);
  config.route.lost_after = 12;
  config.route.scan_places = 5;
  config.route.scan_seq_len = 8;
  config.route.start = -1;  // unknown: a scan first
  const auto tool = run_route(*library_, *kidnapped_, config);
  ASSERT_TRUE(tool.ok()) << tool.error();
  const Seen seen = expect_same(tool.value(), firmware_steps(config), "other settings");
  EXPECT_GT(seen.scans, 1u);
  EXPECT_GT(seen.jumps, 0u);
  // The settings reached the search: the answers differ from the defaults'.
  const auto defaults = run_route(*library_, *kidnapped_, LocaliserConfig{});
  ASSERT_TRUE(defaults.ok());
  size_t differ = 0;
  for (size_t q = 0; q < tool.value().size(); ++q) {
    differ += tool.value()[q].match.place != defaults.value()[q].match.place ||
              tool.value()[q].info.scan_running != defaults.value()[q].info.scan_running;
  }
  EXPECT_GT(differ, 10u);
  // The unknown start: nothing before the first scan completed.
  EXPECT_FALSE(tool.value()[0].info.tracking);
}

TEST_F(RouteRun, TheLibrarysPerPlaceRamChangesNothing) {
  LocaliserConfig config;
  config.route.lost_after = 10;
  RouteRunOptions ram;
  ram.library_ram = true;
  const auto with = run_route(*library_, *kidnapped_, config, ram);
  const auto without = run_route(*library_, *kidnapped_, config);
  ASSERT_TRUE(with.ok()) << with.error();
  ASSERT_TRUE(without.ok()) << without.error();
  std::vector<FirmwareStep> as_steps;
  for (const RouteCoreMatch& m : with.value())
    as_steps.push_back(FirmwareStep{m.match, m.info});
  const Seen seen = expect_same(without.value(), as_steps, "library RAM");
  EXPECT_GT(seen.jumps, 0u);
}

TEST_F(RouteRun, RefusesWhatTheFirmwareCannotRun) {
  const auto refused = [&](const LocaliserConfig& c, const std::string& part) {
    EXPECT_THAT(route_search_refusal(c), HasSubstr(part));
    const auto r = run_route(*library_, *kidnapped_, c);
    ASSERT_FALSE(r.ok()) << part;
    EXPECT_THAT(r.error(), HasSubstr(part));
  };
  const RouteCapacity cap = route_capacity();
  EXPECT_EQ(cap.max_seq_len, 30u);
  EXPECT_EQ(cap.query_steps, 512u);
  LocaliserConfig c;
  EXPECT_EQ(route_search_refusal(c), "");
  c.matcher = LocaliserMatcher::kHeuristic;
  refused(c, "diagonal matcher only");
  c = LocaliserConfig{};
  c.max_shift = 2;
  refused(c, "max_shift must be 0 (it is 2)");
  c = LocaliserConfig{};
  c.sequence.seq_len = 31;
  refused(c,
          "sequence.seq_len above this firmware's kMaxSeqLen (the diagonal matcher) (it is "
          "31, at most 30");
  c = LocaliserConfig{};
  c.sequence.window = 60;
  refused(c,
          "sequence.window above this firmware's kMaxNormWindow (the route search) "
          "(it is 60, at most 50");
  c = LocaliserConfig{};
  c.sequence.exclusion = 11;
  c.route.window = 25;
  refused(c,
          "sequence.exclusion above this firmware's kMaxExclusion (the route search) "
          "(it is 11, at most 10");
  c = LocaliserConfig{};
  c.route.window = 27;
  refused(c,
          "route.window above this firmware's kWindowSlots (the route search) (it is 27, "
          "at most 25");
  c = LocaliserConfig{};
  c.route.scan_seq_len = 11;
  refused(c, "kMaxScanSeqLen (the route search) (it is 11, at most 10");
  // The scan's sequence is at most S: a long scan_seq_len with a short S is fine.
  c.sequence.seq_len = 10;
  EXPECT_EQ(route_search_refusal(c), "");
  // Invalid settings as check_localiser_config names them.
  c = LocaliserConfig{};
  c.route.lost_after = 0;
  const auto r = run_route(*library_, *kidnapped_, c);
  ASSERT_FALSE(r.ok());
  EXPECT_THAT(r.error(), HasSubstr("lost_after"));
  const auto empty = run_route({}, *kidnapped_, LocaliserConfig{});
  ASSERT_FALSE(empty.ok());
  EXPECT_THAT(empty.error(), HasSubstr("no images"));
}

}  // namespace
}  // namespace seqslam::tools
