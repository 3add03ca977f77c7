#include "seqslam_tools/reduce.h"

#include <string>
#include <vector>

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "seqslam/limits.h"
#include "seqslam_tools/image_io.h"
#include "test_util.h"

namespace seqslam::tools {
namespace {

using ::testing::HasSubstr;

GrayImage image(int width, int height, std::vector<uint8_t> pixels) {
  GrayImage out;
  out.width = width;
  out.height = height;
  out.pixels = std::move(pixels);
  return out;
}

TEST(Reduce, HandComputedThreeByThreeToTwoByTwo) {
  // u = floor(x * 2 / 3): x = 0, 1 -> 0; x = 2 -> 1. Same for rows.
  //   10 20 | 30        (0,0) = {10, 20, 40, 50} = 120 / 4 = 30
  //   40 50 | 60        (1,0) = {30, 60}         =  90 / 2 = 45
  //   ------+---        (0,1) = {70, 80}         = 150 / 2 = 75
  //   70 80 | 90        (1,1) = {90}             = 90
  const GrayImage src = image(3, 3, {10, 20, 30, 40, 50, 60, 70, 80, 90});
  const ReducedImage out = reduce_to(src, 2, 2);
  ASSERT_TRUE(out.ok()) << out.error();
  EXPECT_EQ(out.value().width, 2);
  EXPECT_EQ(out.value().height, 2);
  EXPECT_EQ(out.value().pixels, (std::vector<uint8_t>{30, 45, 75, 90}));
}

TEST(Reduce, RoundsToNearestTiesUp) {
  // 8x1 -> 4x1, pairs: {1,2} = 1.5 -> 2 (tie up); {0,1} = 0.5 -> 1; {2,2} = 2; {254,255} -> 255.
  const ReducedImage pairs = reduce_to(image(8, 1, {1, 2, 0, 1, 2, 2, 254, 255}), 4, 1);
  ASSERT_TRUE(pairs.ok()) << pairs.error();
  EXPECT_EQ(pairs.value().pixels, (std::vector<uint8_t>{2, 1, 2, 255}));
  // 4x1 -> 1x1: {1, 2, 2, 2} = 7 / 4 = 1.75 -> 2; {0, 0, 1, 2} = 0.75 -> 1;
  // {1, 1, 1, 2} = 1.25 -> 1.
  EXPECT_EQ(reduce_to(image(4, 1, {1, 2, 2, 2}), 1, 1).value().pixels, (std::vector<uint8_t>{2}));
  EXPECT_EQ(reduce_to(image(4, 1, {0, 0, 1, 2}), 1, 1).value().pixels, (std::vector<uint8_t>{1}));
  EXPECT_EQ(reduce_to(image(1, 4, {1, 1, 1, 2}), 1, 1).value().pixels, (std::vector<uint8_t>{1}));
}

TEST(Reduce, SameSizeIsACopy) {
  const GrayImage src = image(3, 2, {1, 2, 3, 4, 5, 6});
  const ReducedImage out = reduce_to(src, 3, 2);
  ASSERT_TRUE(out.ok()) << out.error();
  EXPECT_EQ(out.value().pixels, src.pixels);
}

TEST(Reduce, CorridorImageMatchesIndependentAverage) {
  const LoadedImage loaded = load_gray(test::corridor_dir() + "/ref/0000042.jpg");
  ASSERT_TRUE(loaded.ok()) << loaded.error();
  const GrayImage& src = loaded.value();
  const int w = 32;
  const int h = 24;
  const ReducedImage out = reduce_to(src, w, h);
  ASSERT_TRUE(out.ok()) << out.error();
  // 160 / 32 = 5 and 120 / 24 = 5: every superpixel is a 5x5 block.
  for (int v = 0; v < h; ++v) {
    for (int u = 0; u < w; ++u) {
      int sum = 0;
      for (int y = 5 * v; y < 5 * v + 5; ++y) {
        for (int x = 5 * u; x < 5 * u + 5; ++x)
          sum += src.at(x, y);
      }
      ASSERT_EQ(out.value().at(u, v), (sum + 12) / 25) << u << "," << v;
    }
  }
}

TEST(Reduce, UpscalingIsRejectedWithTheCoreStatus) {
  const GrayImage src = image(4, 4, std::vector<uint8_t>(16, 9));
  for (const auto& size : {std::pair<int, int>{8, 2}, {2, 5}, {5, 5}}) {
    const ReducedImage out = reduce_to(src, size.first, size.second);
    EXPECT_FALSE(out.ok());
    EXPECT_THAT(out.error(), HasSubstr("INVALID_ARGUMENT"));
    EXPECT_THAT(out.error(), HasSubstr("only reduces"));
    EXPECT_THAT(out.error(), HasSubstr("4x4"));
    EXPECT_TRUE(out.value().pixels.empty());
  }
}

TEST(Reduce, TargetBeyondCoreCapacityIsOutOfRange) {
  const GrayImage src = image(200, 200, std::vector<uint8_t>(40000, 1));
  // Just over kMaxPixels, inside the source in both dimensions.
  const int width = 200;
  const int height = static_cast<int>(seqslam::kMaxPixels / 200 + 1);
  ASSERT_LE(height, 200);
  const ReducedImage out = reduce_to(src, width, height);
  EXPECT_FALSE(out.ok());
  EXPECT_THAT(out.error(), HasSubstr("OUT_OF_RANGE"));
  EXPECT_THAT(out.error(), HasSubstr("kMaxPixels"));

  const ReducedImage huge = reduce_to(src, 100000, 1);
  EXPECT_FALSE(huge.ok());
  EXPECT_THAT(huge.error(), HasSubstr("OUT_OF_RANGE"));
}

TEST(Reduce, BadArguments) {
  const GrayImage src = image(4, 4, std::vector<uint8_t>(16, 9));
  for (const auto& size : {std::pair<int, int>{0, 2}, {2, 0}, {-1, 2}, {2, -7}}) {
    const ReducedImage out = reduce_to(src, size.first, size.second);
    EXPECT_FALSE(out.ok());
    EXPECT_THAT(out.error(), HasSubstr("INVALID_ARGUMENT"));
    EXPECT_THAT(out.error(), HasSubstr("positive"));
  }
  GrayImage broken = src;
  broken.pixels.resize(3);
  const ReducedImage out = reduce_to(broken, 2, 2);
  EXPECT_FALSE(out.ok());
  EXPECT_THAT(out.error(), HasSubstr("INVALID_ARGUMENT"));
  EXPECT_THAT(out.error(), HasSubstr("source image"));
  EXPECT_FALSE(reduce_to(GrayImage{}, 1, 1).ok());
}

TEST(Reduce, CheckReduceTarget) {
  const Outcome<seqslam::ImageSize> good = check_reduce_target(32, 16);
  ASSERT_TRUE(good.ok()) << good.error();
  EXPECT_EQ(good.value().width, 32);
  EXPECT_EQ(good.value().height, 16);
  EXPECT_THAT(check_reduce_target(0, 16).error(), HasSubstr("INVALID_ARGUMENT"));
  const Outcome<seqslam::ImageSize> big =
      check_reduce_target(static_cast<int>(seqslam::kMaxPixels), 2);
  EXPECT_FALSE(big.ok());
  EXPECT_THAT(big.error(), HasSubstr("OUT_OF_RANGE"));
  EXPECT_THAT(big.error(), HasSubstr(std::to_string(seqslam::kMaxPixels)));
}

}  // namespace
}  // namespace seqslam::tools
