// seqslam tune's selection (seqslam_tools/tune.h): leave-one-pair-out choice on constructed
// figures, and the sweep-file reader on bad input.
#include "seqslam_tools/tune.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "test_util.h"

namespace seqslam::tools {
namespace {

using ::testing::HasSubstr;

// The rule before issue 33: recall at 100 % precision, each setting's own figure, a plain mean.
const TuneRule kRecallRule{TuneObjective::kMean, TuneMeasure::kRecallAt100, false, false};
// Issue 33's measure, smoothing and balance with the mean as the objective.
const TuneRule kMeanRule{TuneObjective::kMean, TuneMeasure::kAucPr, true, true};

// Three pairs, three settings. A is best on p1 and p2, B on p3 by far, C never.
std::vector<TuneRow> rows() {
  return {
      {"p1", "A", 0.90, 0.9, 0.9}, {"p2", "A", 0.80, 0.9, 0.9}, {"p3", "A", 0.10, 0.5, 0.5},
      {"p1", "B", 0.50, 0.9, 0.9}, {"p2", "B", 0.50, 0.9, 0.9}, {"p3", "B", 0.95, 0.9, 0.9},
      {"p1", "C", 0.20, 0.9, 0.9}, {"p2", "C", 0.20, 0.9, 0.9}, {"p3", "C", 0.20, 0.9, 0.9},
  };
}

TEST(Tune, EachPairIsScoredWithTheSettingChosenOnTheOthers) {
  const auto r = tune(rows(), "C", kRecallRule);
  ASSERT_TRUE(r.ok()) << r.error();
  const TuneReport& t = r.value();
  ASSERT_EQ(t.folds.size(), 3u);
  // Held out p1: on p2, p3 A averages 0.45, B 0.725 -> B, scored on p1 (0.50).
  EXPECT_EQ(t.folds[0].held_out, "p1");
  EXPECT_EQ(t.folds[0].chosen, "B");
  EXPECT_DOUBLE_EQ(t.folds[0].chosen_recall, 0.50);
  // Held out p2: likewise B (0.925 against 0.50).
  EXPECT_EQ(t.folds[1].chosen, "B");
  // Held out p3: on p1, p2 A (0.85) beats B (0.50); scored on p3 it gets 0.10 - never B's
  // 0.95 on the pair it is scored on.
  EXPECT_EQ(t.folds[2].chosen, "A");
  EXPECT_DOUBLE_EQ(t.folds[2].chosen_recall, 0.10);
  ASSERT_TRUE(t.folds[2].has_default);
  EXPECT_DOUBLE_EQ(t.folds[2].default_recall, 0.20);
  // Over all pairs B is best (0.65 against A's 0.60), chosen in 2 of 3 folds.
  EXPECT_EQ(t.overall, "B");
  EXPECT_EQ(t.overall_folds, 2u);
  EXPECT_EQ(t.distinct_choices, 2u);
  const std::string md = tune_markdown(t, "C");
  EXPECT_THAT(md, HasSubstr("| p3 | . | A | 10.0 | 10.0 | 20.0 | 20.0 | -10.0 |"));
  EXPECT_THAT(md, HasSubstr("B, was chosen in 2 of 3"));
  EXPECT_THAT(md, HasSubstr("Worst held-out difference against the default (recall at 100 % P, "
                            "points): . -10.0 (more than 2 points lost on a held-out pair of: .)"));
}

TEST(Tune, TiesGoToAucThenTop1) {
  std::vector<TuneRow> r = {
      {"p1", "A", 0.5, 0.6, 0.9},
      {"p2", "A", 0.5, 0.6, 0.9},  //
      {"p1", "B", 0.5, 0.7, 0.1},
      {"p2", "B", 0.5, 0.7, 0.1},  //
  };
  auto t = tune(r, "A", kRecallRule);
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_EQ(t.value().overall, "B");  // same recall, better AUC
  r[2].auc_pr = r[3].auc_pr = 0.6;
  t = tune(r, "A", kRecallRule);
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_EQ(t.value().overall, "A");  // same recall and AUC, better top-1
  r[2].top1 = r[3].top1 = 0.95;
  t = tune(r, "A", kRecallRule);
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_EQ(t.value().overall, "B");  // not the first in order: the better top-1
  // Under AUC first, recall at 100 % precision breaks a tie.
  r = {{"p1", "A", 0.4, 0.6, 0.9},
       {"p2", "A", 0.4, 0.6, 0.9},
       {"p1", "B", 0.5, 0.6, 0.1},
       {"p2", "B", 0.5, 0.6, 0.1}};
  t = tune(r, "A");
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_EQ(t.value().overall, "B");
}

// Issue 33's rule. Settings in the sweep's columns, S and W swept 10, 20, 30.
std::string setting(int s, int w) {
  return "32x16,pn," + std::to_string(s) + "," + std::to_string(w) + ",10,0.85,0,diagonal,mad";
}

TEST(TuneRule, OneConfidentWrongAnswerCannotFlipTheChoice) {
  // Recall at 100 % precision swings with one answer; AUC does not. Setting X's recall is 0 on
  // p2 (one confident wrong answer) though its AUC is the best there; Y has a higher recall
  // with a worse AUC everywhere.
  const std::vector<TuneRow> r = {
      {"d/a/p1", "X", 0.60, 0.90, 0.9}, {"d/a/p2", "X", 0.00, 0.88, 0.9},
      {"d/a/p3", "X", 0.55, 0.90, 0.9}, {"d/a/p1", "Y", 0.40, 0.70, 0.9},
      {"d/a/p2", "Y", 0.45, 0.70, 0.9}, {"d/a/p3", "Y", 0.40, 0.70, 0.9},
  };
  auto by_recall = tune(r, "X", kRecallRule);
  ASSERT_TRUE(by_recall.ok()) << by_recall.error();
  EXPECT_EQ(by_recall.value().overall, "Y");  // 0.417 against 0.383
  auto by_auc = tune(r, "X", kMeanRule);
  ASSERT_TRUE(by_auc.ok()) << by_auc.error();
  EXPECT_EQ(by_auc.value().overall, "X");
  EXPECT_EQ(by_auc.value().overall_folds, 3u);
}

TEST(TuneRule, ASettingMustHoldOnBothSidesInSAndW) {
  // W 20 at S 20 is the best alone (a knife edge: its W and S neighbours are poor); W 10..30 at
  // S 30 are all good. Smoothed, S 30 wins; unsmoothed the edge does.
  std::vector<TuneRow> r;
  for (const char* pair : {"d/a/p1", "d/a/p2"}) {
    for (int s : {10, 20, 30}) {
      for (int w : {10, 20, 30}) {
        double auc = s == 30 ? 0.80 : 0.30;
        if (s == 20 && w == 20) auc = 0.95;
        if (s == 30 && w == 20) auc = 0.85;
        r.push_back({pair, setting(s, w), 0.5, auc, 0.5});
      }
    }
  }
  auto smooth = tune(r, setting(30, 20), kMeanRule);
  ASSERT_TRUE(smooth.ok()) << smooth.error();
  EXPECT_EQ(smooth.value().overall, setting(30, 20));
  auto plain =
      tune(r, setting(30, 20), TuneRule{TuneObjective::kMean, TuneMeasure::kAucPr, false, true});
  ASSERT_TRUE(plain.ok()) << plain.error();
  EXPECT_EQ(plain.value().overall, setting(20, 20));
}

TEST(TuneRule, EachDatasetWeighsTheSame) {
  // Three simulated pairs prefer A a little, one real pair prefers B by far. Balanced, the two
  // datasets weigh the same and B wins; a plain mean over pairs picks A.
  std::vector<TuneRow> r;
  for (const char* pair :
       {"sim/lights-s1/p1.dream,q,g", "sim/lights-s2/p2.dream,q,g", "sim/lights-s3/p3.dream,q,g"}) {
    r.push_back({pair, "A", 0.5, 0.85, 0.5});
    r.push_back({pair, "B", 0.5, 0.70, 0.5});
  }
  r.push_back({"data/corridor/ref,data/corridor/query,g", "A", 0.5, 0.40, 0.5});
  r.push_back({"data/corridor/ref,data/corridor/query,g", "B", 0.5, 0.80, 0.5});
  auto balanced = tune(r, "A", kMeanRule);
  ASSERT_TRUE(balanced.ok()) << balanced.error();
  EXPECT_EQ(balanced.value().overall, "B");  // (0.70 + 0.80) / 2 against (0.85 + 0.40) / 2
  auto plain = tune(r, "A", TuneRule{TuneObjective::kMean, TuneMeasure::kAucPr, true, false});
  ASSERT_TRUE(plain.ok()) << plain.error();
  EXPECT_EQ(plain.value().overall, "A");  // (3 x 0.85 + 0.40) / 4 against (3 x 0.70 + 0.80) / 4
}

TEST(TuneRule, TheDefaultChangesOnlyForASettingThatMakesNoPairWorse) {
  // D is the default. G gains a lot on two pairs and loses 0.20 on the third; H gains a little
  // everywhere. The mean picks G; the worst gain over the default picks H.
  const std::vector<TuneRow> r = {
      {"a/x/p1", "D", 0.5, 0.60, 0.5}, {"a/x/p2", "D", 0.5, 0.60, 0.5},
      {"a/x/p3", "D", 0.5, 0.90, 0.5}, {"a/x/p1", "G", 0.5, 0.95, 0.5},
      {"a/x/p2", "G", 0.5, 0.95, 0.5}, {"a/x/p3", "G", 0.5, 0.70, 0.5},
      {"a/x/p1", "H", 0.5, 0.65, 0.5}, {"a/x/p2", "H", 0.5, 0.65, 0.5},
      {"a/x/p3", "H", 0.5, 0.91, 0.5},
  };
  auto mean = tune(r, "D", kMeanRule);
  ASSERT_TRUE(mean.ok()) << mean.error();
  EXPECT_EQ(mean.value().overall, "G");
  auto worst = tune(r, "D");
  ASSERT_TRUE(worst.ok()) << worst.error();
  EXPECT_EQ(worst.value().overall, "H");
  EXPECT_THAT(tune_markdown(worst.value(), "D"), HasSubstr("the best worst gain over the default"));
  // Without the default swept there is no baseline: the worst figure itself (H's 0.65 against
  // G's 0.70: G).
  auto no_base = tune(r, "none");
  ASSERT_TRUE(no_base.ok()) << no_base.error();
  EXPECT_EQ(no_base.value().overall, "G");
}

TEST(TuneRule, DatasetOfAPair) {
  EXPECT_EQ(dataset_of("tests/data/corridor/ref,tests/data/corridor/query,gt.csv"), "corridor");
  EXPECT_EQ(dataset_of("/d/gardens_point/day_left/,/d/gardens_point/night_right,gt.csv"),
            "gardens_point");
  EXPECT_EQ(dataset_of("build/sim/lights-s2/loop_noon-lamps.dream,x.dream,gt.csv"), "lights");
  EXPECT_EQ(dataset_of("build/sim/lights-sx/a.dream,x.dream,gt.csv"), "lights-sx");
  EXPECT_EQ(dataset_of("a.dream,b.dream,gt.csv"), ".");
}

TEST(Tune, IncompleteSettingsAreLeftOutAndBadSetsRefused) {
  std::vector<TuneRow> r = rows();
  r.push_back({"p1", "D", 1.0, 1.0, 1.0});  // swept on one pair only
  auto t = tune(r, "none");
  ASSERT_TRUE(t.ok()) << t.error();
  EXPECT_EQ(t.value().incomplete_settings, 1u);
  EXPECT_FALSE(t.value().folds[0].has_default);
  EXPECT_THAT(tune_markdown(t.value(), "none"), HasSubstr("not swept"));
  // One pair: nothing to hold out.
  t = tune({{"p1", "A", 0.5, 0.5, 0.5}}, "A");
  ASSERT_FALSE(t.ok());
  EXPECT_THAT(t.error(), HasSubstr("at least two pairs"));
  // The same pair and setting with other figures: two versions mixed.
  r = rows();
  r.push_back({"p1", "A", 0.3, 0.9, 0.9});
  t = tune(r, "A");
  ASSERT_FALSE(t.ok());
  EXPECT_THAT(t.error(), HasSubstr("two rows with different figures"));
  // No setting on every pair.
  t = tune({{"p1", "A", 0.5, 0.5, 0.5}, {"p2", "B", 0.5, 0.5, 0.5}}, "A");
  ASSERT_FALSE(t.ok());
  EXPECT_THAT(t.error(), HasSubstr("no setting was swept on every pair"));
}

class TuneFile : public ::testing::Test {
 protected:
  // In a directory of this test's own (mkdtemp): ctest runs this suite's tests in parallel
  // processes, which must not overwrite each other's file.
  std::string write(const std::string& body) {
    const std::string path = dir_.file("tune_rows.csv");
    std::ofstream(path, std::ios::binary) << body;
    return path;
  }
  test::TempDir dir_;
  static std::string row(const std::string& fields) {
    // 12 key columns, then queries, top1, recall, auc, and 7 more figures.
    return fields + ",0.1,0.2,0.3,5,0.5,0.6,0.7\n";
  }
};

TEST_F(TuneFile, ReadsRowsWithQuotedPaths) {
  const std::string path =
      write(std::string(kSweepHeader) + "\n" +
            row("\"a,b.dream\",q.dream,gt.csv,32x16,he,30,50,10,0.85,0,diagonal,mad,100,0.9,0.5,"
                "0.7"));
  const auto r = read_sweep_rows(path);
  ASSERT_TRUE(r.ok()) << r.error();
  ASSERT_EQ(r.value().size(), 1u);
  EXPECT_EQ(r.value()[0].pair, "a,b.dream,q.dream,gt.csv");
  EXPECT_EQ(r.value()[0].setting, "32x16,he,30,50,10,0.85,0,diagonal,mad");
  EXPECT_DOUBLE_EQ(r.value()[0].top1, 0.9);
  EXPECT_DOUBLE_EQ(r.value()[0].recall_at_100_precision, 0.5);
  EXPECT_DOUBLE_EQ(r.value()[0].auc_pr, 0.7);
}

TEST_F(TuneFile, BadFilesNameFileAndLine) {
  const std::string good = "l,q,g,32x16,he,30,50,10,0.85,0,diagonal,mad,100,0.9,0.5,0.7";
  struct Case {
    std::string body;
    std::string message;
  };
  const Case cases[] = {
      {"", "empty"},
      {"library,query\n", ":1: not a sweep results file"},
      {std::string(kSweepHeader) + "\n" + row(good) + "l,q,g,32x16\n", ":3: expected 23"},
      {std::string(kSweepHeader) + "\n" +
           row("\"l,q,g,32x16,he,30,50,10,0.85,0,diagonal,mad,1,1,1,1"),
       ":2: an unterminated quote"},
      {std::string(kSweepHeader) + "\n" +
           row("l,q,g,32x16,he,30,50,10,0.85,0,diagonal,mad,10,x,1,1"),
       ":2: top1 'x' is not a number within 0..1"},
      {std::string(kSweepHeader) + "\n" +
           row("l,q,g,32x16,he,30,50,10,0.85,0,diagonal,mad,10,1,1.5,1"),
       ":2: recall_at_100_precision '1.5' is not a number within 0..1"},
      {std::string(kSweepHeader) + "\n" +
           row("l,q,g,32x16,he,30,50,10,0.85,0,diagonal,mad,10,1,nan,1"),
       ":2: recall_at_100_precision 'nan' is not a number within 0..1"},
      // Issue 34: every field, as sweep's resume checks it.
      {std::string(kSweepHeader) + "\n" +
           row("l,q,g,32x16,he,30,50,10,0.85,0,diagonal,mad,100,0.9,0.5,7"),
       ":2: auc_pr '7' is not a number within 0..1"},
      {std::string(kSweepHeader) + "\n" +
           row("l,q,g,32x16,he,0,50,10,0.85,0,diagonal,mad,100,0.9,0.5,0.7"),
       ":2: seq_len: '0' is not within 1..100 places"},
      {std::string(kSweepHeader) + "\n" +
           row("l,q,g,32x16,he,30,50,10,1.5,0,diagonal,mad,100,0.9,0.5,0.7"),
       ":2: threshold: '1.5' is not within 0..1"},
      {std::string(kSweepHeader) + "\n" +
           row("l,q,g,32x16,xx,30,50,10,0.85,0,diagonal,mad,100,0.9,0.5,0.7"),
       ":2: preprocess: 'xx' is not one of none, he"},
      {std::string(kSweepHeader) + "\n" +
           row("l,q,g,32x16,he,30,50,10,0.85,0,diagonal,sad,100,0.9,0.5,0.7"),
       ":2: metric 'sad': not mad, td or td-noscale"},
      {std::string(kSweepHeader) + "\n" +
           row("l,q,,32x16,he,30,50,10,0.85,0,diagonal,mad,100,0.9,0.5,0.7"),
       ":2: field 3 (a path) is empty"},
      {std::string(kSweepHeader) + "\n" +
           row(std::string("l,q,g,32x16,he,30,50,10,0.85,0,diag") + '\0' +
               "nal,mad,100,0.9,0.5,0.7"),
       ":2: field 11 'diag\\x00nal' holds a control byte"},
      {std::string(kSweepHeader) + "\n" +
           row("l,q,g,32x16,he,30,50,10,0.85,0,diagonal,mad,3,0.9,0.5,0.7"),
       ":2: accepted '5' is not a whole number within 0..3 (the queries)"},
  };
  for (const Case& c : cases) {
    const std::string path = write(c.body);
    const auto r = read_sweep_rows(path);
    ASSERT_FALSE(r.ok()) << c.message;
    EXPECT_THAT(r.error(), HasSubstr(path)) << c.message;
    EXPECT_THAT(r.error(), HasSubstr(c.message));
  }
  const auto missing = read_sweep_rows(::testing::TempDir() + "no_such_rows.csv");
  ASSERT_FALSE(missing.ok());
  EXPECT_THAT(missing.error(), HasSubstr("no such file"));
  // Regular files only: /dev/zero never ends a line.
  const auto device = read_sweep_rows("/dev/zero");
  ASSERT_FALSE(device.ok());
  EXPECT_THAT(device.error(), HasSubstr("/dev/zero: is not a regular file"));
}

TEST(TuneSetting, OnlyWhatSweepRuns) {
  EXPECT_EQ(check_sweep_setting("32x16,he,30,50,10,0.85,0,diagonal,mad"), "");
  EXPECT_EQ(check_sweep_setting("16x8,igk-pn,100,0,15,1,15,heuristic,td-noscale"), "");
  EXPECT_THAT(check_sweep_setting("32x16,he,30"), HasSubstr("is not 9 comma-separated values"));
  EXPECT_THAT(check_sweep_setting("32x16,he,30,50,10,nan,0,diagonal,mad"),
              HasSubstr("threshold: 'nan'"));
  EXPECT_THAT(check_sweep_setting("32x16,he,30,50,10,-0.5,0,diagonal,mad"),
              HasSubstr("threshold: '-0.5'"));
  EXPECT_THAT(check_sweep_setting("32x16,he,030,50,10,0.5,0,diagonal,mad"),
              HasSubstr("seq_len: '030'"));
  EXPECT_THAT(check_sweep_setting("32x16,he,101,50,10,0.5,0,diagonal,mad"),
              HasSubstr("seq_len: '101'"));
  EXPECT_THAT(check_sweep_setting("32x16,he,30,50,10,0.5,256,diagonal,mad"),
              HasSubstr("max_shift: '256'"));
  EXPECT_THAT(check_sweep_setting("32x16,he,30,50,10,0.5,0,greedy,mad"),
              HasSubstr("matcher: 'greedy'"));
  EXPECT_THAT(check_sweep_setting("0x16,he,30,50,10,0.5,0,diagonal,mad"),
              HasSubstr("size: '0x16'"));
  // Each value in range, the combination not (a window of 1): the core's sentence.
  EXPECT_THAT(check_sweep_setting("32x16,he,30,1,10,0.5,0,diagonal,mad"),
              HasSubstr("the setting is invalid: "));
}

}  // namespace
}  // namespace seqslam::tools
