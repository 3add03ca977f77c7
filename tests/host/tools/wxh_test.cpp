// seqslam_tools/wxh.h: the "WxH" option syntax every tool reads (--size, --grid-size).
#include "seqslam_tools/wxh.h"

#include <gtest/gtest.h>

#include <string>

namespace seqslam::tools {
namespace {

TEST(SplitWxh, ReadsTwoWholeNumbers) {
  uint32_t w = 0;
  uint32_t h = 0;
  ASSERT_TRUE(split_wxh("32x16", &w, &h));
  EXPECT_EQ(w, 32u);
  EXPECT_EQ(h, 16u);
  ASSERT_TRUE(split_wxh("12X10", &w, &h));
  EXPECT_EQ(w, 12u);
  EXPECT_EQ(h, 10u);
  ASSERT_TRUE(split_wxh("999999x0", &w, &h));  // zero and range: the caller's
  EXPECT_EQ(w, 999999u);
  EXPECT_EQ(h, 0u);
}

TEST(SplitWxh, RefusesEverythingElseAndLeavesTheOutputs) {
  const std::string bads[] = {"", "x", "32", "32x", "x16", "32x16x", "32x16junk", "32x16 ", " 32x16", "+32x16",
        "-1x5", "3.5x2", "32 x 16", "32*16", "1234567x1", "1x1234567", "99999999999x16",
        "0x10x2", std::string("32\0x16", 6)};
  for (const std::string& bad : bads) {
    uint32_t w = 7;
    uint32_t h = 9;
    EXPECT_FALSE(split_wxh(bad, &w, &h)) << "'" << bad << "'";
    EXPECT_EQ(w, 7u) << bad;
    EXPECT_EQ(h, 9u) << bad;
  }
}

}  // namespace
}  // namespace seqslam::tools
