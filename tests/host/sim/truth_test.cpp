// Ground truth for library/query pairs (scenario.h pair_truth, write_truth_csv) on synthetic
// true poses, and the CSV read back by the tools' loader.
#include <cmath>
#include <cstdint>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "seqslam_sim/scenario.h"
#include "seqslam_tools/ground_truth.h"
#include "sim_test_util.h"

namespace seqslam::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;

PlaceTruth at(uint32_t index, double x, double y, double heading) {
  PlaceTruth p;
  p.index = index;
  p.truth = TruePose{x, y, heading};
  p.odometry = p.truth;
  return p;
}

// An outward leg along y = 0 (heading 0, x = 0, 0.2, ..., 4.0: places 0..20) and the way
// back along y = 0.3 (heading pi, x = 4.0 ... 0: places 21..41).
std::vector<PlaceTruth> out_and_back() {
  std::vector<PlaceTruth> lib;
  for (uint32_t i = 0; i <= 20; ++i)
    lib.push_back(at(i, 0.2 * i, 0.0, 0.0));
  for (uint32_t i = 0; i <= 20; ++i)
    lib.push_back(at(21 + i, 4.0 - 0.2 * i, 0.3, kPi));
  return lib;
}

using Sets = std::vector<std::vector<uint32_t>>;

TEST(SimTruth, NearestWithinGateAndNeighbours) {
  const std::vector<PlaceTruth> lib = out_and_back();
  std::vector<PlaceTruth> q;
  q.push_back(at(0, 2.01, 0.02, 0.0));  // nearest 10 -> 9 10 11
  q.push_back(at(1, 0.05, 0.0, 0.1));   // nearest 0 -> clipped at the start: 0 1
  q.push_back(at(2, 4.3, -0.1, -0.2));  // nearest 20 -> 19 20 21 (clipped at the library ends only)
  q.push_back(at(3, 2.0, 2.0, 0.0));    // 2 m off: beyond the 1.5 m gate -> none
  q.push_back(at(4, 1.0, 0.25, 0.0));   // heading 0 near the return leg: the outward 5
  q.push_back(at(5, 1.0, 0.05, kPi));   // heading pi near the outward leg: the return 36
  q.push_back(at(6, 2.0, 0.0, 0.5 * kPi));           // 90 degrees off both legs -> none
  q.push_back(at(7, 2.0, 1.4, 0.0));                 // 1.4 m off place 10: inside the gate
  q.push_back(at(8, 2.0, -1.6, 0.0));                // 1.6 m off: outside
  q.push_back(at(9, 1.6, 0.0, 59.0 * kPi / 180));    // 59 degrees: a candidate
  q.push_back(at(10, 1.6, 0.0, -61.0 * kPi / 180));  // 61 degrees: not
  q.push_back(at(11, 3.0, 0.0, 2 * kPi + 0.1));      // heading unwrapped past a turn: same
  q.push_back(at(12, 0.0, 0.3, -kPi));               // -pi is pi: the return leg's last, 41
  const Sets truth = pair_truth(lib, q);
  ASSERT_EQ(truth.size(), q.size());
  const Sets expected = {{9, 10, 11}, {0, 1}, {19, 20, 21}, {}, {4, 5, 6},    {35, 36, 37}, {},
                         {9, 10, 11}, {},     {7, 8, 9},    {}, {14, 15, 16}, {40, 41}};
  for (size_t i = 0; i < q.size(); ++i)
    EXPECT_EQ(truth[i], expected[i]) << "query " << i;
}

TEST(SimTruth, RuleParameters) {
  const std::vector<PlaceTruth> lib = out_and_back();
  const std::vector<PlaceTruth> q = {at(0, 2.01, 0.0, 0.0), at(1, 0.0, 0.9, 0.0),
                                     at(2, 1.0, 0.0, 1.2)};
  TruthRule rule;
  rule.tolerance = 2;
  rule.gate_m = 0.5;
  rule.max_heading_deg = 90.0;
  const Sets truth = pair_truth(lib, q, rule);
  ASSERT_EQ(truth.size(), 3u);
  EXPECT_EQ(truth[0], (std::vector<uint32_t>{8, 9, 10, 11, 12}));
  EXPECT_TRUE(truth[1].empty());  // 0.9 m from place 0 with a 0.5 m gate
  EXPECT_EQ(truth[2], (std::vector<uint32_t>{3, 4, 5, 6, 7}));  // 69 degrees off, allowed
  rule.tolerance = 0;
  EXPECT_EQ(pair_truth(lib, q, rule)[0], (std::vector<uint32_t>{10}));
  // An empty library: nothing is correct.
  const Sets none = pair_truth({}, q);
  ASSERT_EQ(none.size(), 3u);
  for (const auto& s : none)
    EXPECT_TRUE(s.empty());
}

TEST(SimTruth, EveryPassCountsEachPassOfTheLibrary) {
  // Out (places 0..20 along y = 0), back (21..41 along y = 0.3) and out again (42..62, y = 0.1).
  std::vector<PlaceTruth> lib = out_and_back();
  for (uint32_t i = 0; i <= 20; ++i)
    lib.push_back(at(42 + i, 0.2 * i, 0.1, 0.0));
  const std::vector<PlaceTruth> q = {at(0, 2.01, 0.08, 0.0), at(1, 3.0, 2.0, 0.0),
                                     at(2, 1.0, 0.3, kPi), at(3, 3.95, 0.1, 0.0)};
  TruthRule rule;
  // The nearest only: the second outward pass (y = 0.1) is nearer than the first for q0.
  EXPECT_EQ(pair_truth(lib, q, rule)[0], (std::vector<uint32_t>{51, 52, 53}));
  rule.every_pass = true;
  const Sets truth = pair_truth(lib, q, rule);
  ASSERT_EQ(truth.size(), q.size());
  EXPECT_EQ(truth[0], (std::vector<uint32_t>{9, 10, 11, 51, 52, 53}));
  EXPECT_TRUE(truth[1].empty());                                     // 2 m off every pass
  EXPECT_EQ(truth[2], (std::vector<uint32_t>{35, 36, 37}));          // only the return leg heads pi
  EXPECT_EQ(truth[3], (std::vector<uint32_t>{19, 20, 21, 61, 62}));  // passes meet the ends
}

TEST(SimTruth, CsvReadsBackWithTheToolsLoader) {
  const std::vector<PlaceTruth> lib = out_and_back();
  std::vector<PlaceTruth> q;
  for (uint32_t i = 0; i < 30; ++i) {
    // Out along the lane, then three metres off it (no match), alternately.
    q.push_back(at(i, 0.15 * i, i % 4 == 3 ? 3.0 : 0.05, i % 7 == 6 ? kPi : 0.0));
  }
  const Sets truth = pair_truth(lib, q);
  size_t empty = 0, nonempty = 0;
  for (const auto& s : truth)
    (s.empty() ? empty : nonempty)++;
  EXPECT_GT(empty, 3u);
  EXPECT_GT(nonempty, 10u);

  test::ScratchDir dir;
  const std::string path = dir.path() + "/pair.csv";
  ASSERT_EQ(write_truth_csv(path, truth), "");
  const tools::LoadedGroundTruth loaded = tools::load_ground_truth(path);
  ASSERT_TRUE(loaded.ok()) << loaded.error();
  ASSERT_EQ(loaded.value().matches.size(), truth.size());
  for (size_t i = 0; i < truth.size(); ++i) {
    EXPECT_EQ(loaded.value().matches[i], truth[i]) << "query " << i;
    EXPECT_EQ(loaded.value().has_match(static_cast<uint32_t>(i)), !truth[i].empty());
  }
  // A directory that does not exist: an error, not a crash.
  EXPECT_NE(write_truth_csv(dir.path() + "/missing/pair.csv", truth), "");
}

}  // namespace
}  // namespace seqslam::sim
