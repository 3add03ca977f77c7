// The FPGA's area-averaging reduction, against a hand example and a double formula.
#include "seqslam/pixel_pipeline.h"

#include "ref_math.h"
#include "synthetic.h"
#include "test.h"

namespace seqslam {
namespace {

TEST(PixelPipeline, HandComputedReduction) {
  // 5x2 -> 2x1: columns 0,1,2 -> u=0 (x*2/5 = 0,0,0) and 3,4 -> u=1.
  const uint8_t src[10] = {10, 20, 30, 40, 50, 11, 21, 31, 41, 51};
  uint8_t dst[2];
  uint32_t scratch[4];
  ASSERT_EQ(area_reduce(ImageView{src, ImageSize{5, 2}}, MutableImageView{dst, ImageSize{2, 1}},
                        Span<uint32_t>(scratch, 4)),
            Status::kOk);
  EXPECT_EQ(dst[0], 21);  // (10+20+30+11+21+31)/6 = 20.5 -> 21 (ties up)
  EXPECT_EQ(dst[1], 46);  // (40+50+41+51)/4 = 45.5 -> 46
}

TEST(PixelPipeline, CameraToStandardResolutionMatchesDoubleMeans) {
  // 346x271 camera frame to 32x16, as the robot's FPGA does.
  static uint8_t src[346 * 271];
  test::Rng rng(50);
  for (uint8_t& p : src)
    p = static_cast<uint8_t>(rng.below(256));
  uint8_t dst[512];
  static uint32_t scratch[1024];
  ASSERT_EQ(area_reduce(ImageView{src, ImageSize{346, 271}},
                        MutableImageView{dst, ImageSize{32, 16}}, Span<uint32_t>(scratch, 1024)),
            Status::kOk);
  for (uint32_t v = 0; v < 16; ++v) {
    for (uint32_t u = 0; u < 32; ++u) {
      double sum = 0.0, n = 0.0;
      for (uint32_t y = 0; y < 271; ++y) {
        if (y * 16 / 271 != v) continue;
        for (uint32_t x = 0; x < 346; ++x) {
          if (x * 32 / 346 != u) continue;
          sum += src[y * 346 + x];
          n += 1.0;
        }
      }
      ASSERT_EQ(static_cast<double>(dst[v * 32 + u]), test::ref_floor(sum / n + 0.5));
    }
  }
}

TEST(PixelPipeline, BadInput) {
  uint8_t src[16] = {}, dst[16];
  uint32_t scratch[32];
  const Span<uint32_t> s(scratch, 32);
  EXPECT_EQ(area_reduce(ImageView{src, ImageSize{4, 4}}, MutableImageView{dst, ImageSize{8, 2}}, s),
            Status::kInvalidArgument);  // upscaling
  EXPECT_EQ(
      area_reduce(ImageView{nullptr, ImageSize{4, 4}}, MutableImageView{dst, ImageSize{2, 2}}, s),
      Status::kInvalidArgument);
  EXPECT_EQ(area_reduce(ImageView{src, ImageSize{4, 4}}, MutableImageView{dst, ImageSize{0, 2}}, s),
            Status::kInvalidArgument);
  EXPECT_EQ(area_reduce(ImageView{src, ImageSize{4, 4}}, MutableImageView{dst, ImageSize{4, 4}},
                        Span<uint32_t>(scratch, 31)),
            Status::kResourceExhausted);
}

}  // namespace
}  // namespace seqslam
