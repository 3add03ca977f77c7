#include "seqslam_tools/ground_truth.h"

#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "test_util.h"

namespace seqslam::tools {
namespace {

using ::testing::ElementsAre;
using ::testing::HasSubstr;
using ::testing::IsEmpty;

constexpr const char* kHeader = "query_index,matching_reference_indices\n";

TEST(GroundTruth, ParsesTheCorridorFile) {
  const std::string path = test::corridor_dir() + "/ground_truth.csv";
  const LoadedGroundTruth gt = load_ground_truth(path);
  ASSERT_TRUE(gt.ok()) << gt.error();
  ASSERT_EQ(gt.value().matches.size(), 111u);
  EXPECT_THAT(gt.value().matches[0], ElementsAre(0u, 1u, 2u));
  EXPECT_THAT(gt.value().matches[1], ElementsAre(0u, 1u, 2u, 3u));
  EXPECT_THAT(gt.value().matches[50], ElementsAre(48u, 49u, 50u, 51u, 52u));
  EXPECT_THAT(gt.value().matches[110], ElementsAre(108u, 109u, 110u));
  EXPECT_TRUE(gt.value().is_correct(5, 3));
  EXPECT_TRUE(gt.value().is_correct(5, 7));
  EXPECT_FALSE(gt.value().is_correct(5, 8));
  EXPECT_FALSE(gt.value().is_correct(5, 2));
  EXPECT_FALSE(gt.value().is_correct(111, 110));  // beyond the file
  for (uint32_t q = 0; q < 111; ++q)
    EXPECT_TRUE(gt.value().has_match(q)) << q;
}

TEST(GroundTruth, ToleratesCrlfWhitespaceBomAndOrder) {
  const std::string text =
      "\xEF\xBB\xBF  query_index , matching_reference_indices  \r\n"
      " 2 , 5\t4  4 \r\n"
      "\r\n"
      "0,\r\n"
      "   \n"
      "4,  9\r\n";
  const LoadedGroundTruth gt = parse_ground_truth(text, "mem.csv");
  ASSERT_TRUE(gt.ok()) << gt.error();
  ASSERT_EQ(gt.value().matches.size(), 5u);
  EXPECT_THAT(gt.value().matches[0], IsEmpty());            // explicit "no correct match"
  EXPECT_THAT(gt.value().matches[1], IsEmpty());            // absent from the file
  EXPECT_THAT(gt.value().matches[2], ElementsAre(4u, 5u));  // sorted, duplicate dropped
  EXPECT_THAT(gt.value().matches[3], IsEmpty());
  EXPECT_THAT(gt.value().matches[4], ElementsAre(9u));
  EXPECT_FALSE(gt.value().has_match(0));
  EXPECT_TRUE(gt.value().has_match(2));
  EXPECT_FALSE(gt.value().is_correct(0, 0));
  EXPECT_TRUE(gt.value().is_correct(4, 9));
}

TEST(GroundTruth, HeaderOnlyAndLargeNumbers) {
  const LoadedGroundTruth empty = parse_ground_truth(kHeader, "h.csv");
  ASSERT_TRUE(empty.ok()) << empty.error();
  EXPECT_TRUE(empty.value().matches.empty());
  EXPECT_FALSE(empty.value().is_correct(0, 0));

  const LoadedGroundTruth big =
      parse_ground_truth(std::string(kHeader) + "10000,4294967295 0\n", "b.csv");
  ASSERT_TRUE(big.ok()) << big.error();
  EXPECT_EQ(big.value().matches.size(), 10001u);
  EXPECT_TRUE(big.value().is_correct(10000, 4294967295u));
}

struct BadCase {
  const char* name;
  std::string text;
  const char* location;  // "bad.csv:N:"
  const char* what;
};

TEST(GroundTruth, MalformedFilesNameTheLine) {
  const std::string h = kHeader;
  const std::vector<BadCase> cases = {
      {"empty file", "", "bad.csv:1:", "missing header"},
      {"blank first line", "\n0,1\n", "bad.csv:1:", "missing header"},
      {"wrong header", "query,refs\n0,1\n", "bad.csv:1:", "bad header"},
      {"header without comma", "query_index matching_reference_indices\n",
       "bad.csv:1:", "bad header"},
      {"no header", "0,1 2\n", "bad.csv:1:", "bad header"},
      {"non-numeric query", h + "0,1\nx,2\n", "bad.csv:3:", "not a non-negative decimal"},
      {"empty query", h + ",2\n", "bad.csv:2:", "query index is empty"},
      {"non-numeric reference", h + "0,1\n1,2 b 3\n", "bad.csv:3:", "reference index 'b'"},
      {"decimal point", h + "0,1.5\n", "bad.csv:2:", "not a non-negative decimal"},
      {"plus sign", h + "+1,2\n", "bad.csv:2:", "not a non-negative decimal"},
      {"negative query", h + "0,1\n1,2\n-3,4\n", "bad.csv:4:", "negative"},
      {"negative reference", h + "0,-1\n", "bad.csv:2:", "negative"},
      {"query overflow", h + "4294967296,1\n", "bad.csv:2:", "does not fit in 32 bits"},
      {"reference overflow", h + "0,99999999999999999999\n",
       "bad.csv:2:", "does not fit in 32 bits"},
      {"duplicate query", h + "0,1\n1,2\n\n0,3\n", "bad.csv:5:", "duplicate query index 0"},
      {"one field", h + "0,1\n7\n", "bad.csv:3:", "found 1"},
      {"three fields", h + "0,1,2\n", "bad.csv:2:", "found 3"},
      {"absurd query", h + "10000001,1\n", "bad.csv:2:", "absurd"},
      {"binary junk", h + std::string("0,\0\x01\n", 5), "bad.csv:2:", "reference index"},
  };
  for (const BadCase& c : cases) {
    const LoadedGroundTruth gt = parse_ground_truth(c.text, "bad.csv");
    EXPECT_FALSE(gt.ok()) << c.name;
    EXPECT_THAT(gt.error(), HasSubstr(c.location)) << c.name;
    EXPECT_THAT(gt.error(), HasSubstr(c.what)) << c.name;
    EXPECT_TRUE(gt.value().matches.empty()) << c.name;
  }
  // The duplicate message also points back at the first definition.
  EXPECT_THAT(parse_ground_truth(h + "0,1\n1,2\n\n0,3\n", "bad.csv").error(),
              HasSubstr("first given on line 2"));
}

TEST(GroundTruth, LoadErrorsNameTheFile) {
  test::TempDir dir;
  const LoadedGroundTruth missing = load_ground_truth(dir.file("gt.csv"));
  EXPECT_FALSE(missing.ok());
  EXPECT_THAT(missing.error(), HasSubstr(dir.file("gt.csv")));
  test::write_file(dir.file("bad.csv"), "query_index,matching_reference_indices\r\n0,1\r\n0,2\r\n");
  const LoadedGroundTruth bad = load_ground_truth(dir.file("bad.csv"));
  EXPECT_FALSE(bad.ok());
  EXPECT_THAT(bad.error(), HasSubstr(dir.file("bad.csv") + ":3:"));
}

TEST(GroundTruth, IdentityWithTolerance) {
  // 6 queries, 4 references, tolerance 1.
  const GroundTruth gt = identity_ground_truth(6, 4, 1);
  ASSERT_EQ(gt.matches.size(), 6u);
  EXPECT_THAT(gt.matches[0], ElementsAre(0u, 1u));
  EXPECT_THAT(gt.matches[1], ElementsAre(0u, 1u, 2u));
  EXPECT_THAT(gt.matches[2], ElementsAre(1u, 2u, 3u));
  EXPECT_THAT(gt.matches[3], ElementsAre(2u, 3u));
  EXPECT_THAT(gt.matches[4], ElementsAre(3u));  // 4 - 1 = 3 is the last reference
  EXPECT_THAT(gt.matches[5], IsEmpty());
  EXPECT_TRUE(gt.is_correct(2, 3));
  EXPECT_FALSE(gt.is_correct(2, 0));

  const GroundTruth exact = identity_ground_truth(3, 3, 0);
  EXPECT_THAT(exact.matches[0], ElementsAre(0u));
  EXPECT_THAT(exact.matches[2], ElementsAre(2u));

  EXPECT_TRUE(identity_ground_truth(0, 5, 2).matches.empty());
  const GroundTruth no_refs = identity_ground_truth(2, 0, 3);
  ASSERT_EQ(no_refs.matches.size(), 2u);
  EXPECT_THAT(no_refs.matches[0], IsEmpty());

  // A huge tolerance does not overflow.
  const GroundTruth wide = identity_ground_truth(2, 3, 0xffffffffu);
  EXPECT_THAT(wide.matches[1], ElementsAre(0u, 1u, 2u));
}

}  // namespace
}  // namespace seqslam::tools
