// Rendering sanity (host_sim/include/seqslam_sim/render.h): repeatability, thread
// independence, the place signal against run-to-run changes, and the light conditions.
// Renders are few and mostly small (a 346x271 frame costs 20-50 ms optimised, several times
// that under the sanitizers).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <vector>

#include <gtest/gtest.h>

#include "seqslam/hal/pixel_buffer.h"
#include "seqslam_sim/lab.h"
#include "seqslam_sim/pipeline.h"
#include "seqslam_sim/render.h"
#include "seqslam_sim/world.h"
#include "test_log.h"

namespace seqslam::sim {
namespace {

CameraModel small_camera() {
  CameraModel c;  // the default optics, a quarter of the pixels per side
  c.width = 87;
  c.height = 68;
  return c;
}

// Exposed (a fresh auto-exposure, seeded sensor noise) and reduced to 32x16.
std::vector<uint8_t> reduced_image(const World& world, const LightCondition& light,
                                   const CameraPose& pose, uint64_t noise_seed) {
  const CameraModel cam;
  const std::vector<float> radiance = render_radiance(world, light, cam, pose);
  Exposure exposure(light.exposure_bias);
  Rng noise(noise_seed);
  const std::vector<uint8_t> frame = exposure.expose(radiance, cam.width, cam.height, noise);
  return apply_pipeline(frame.data(), cam.width, cam.height,
                        hal::PipelineMapping::reduction(32, 16))
      .pixels;
}

double mean_abs_difference(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  EXPECT_EQ(a.size(), b.size());
  double sum = 0.0;
  for (size_t i = 0; i < a.size() && i < b.size(); ++i)
    sum += std::abs(int{a[i]} - int{b[i]});
  return sum / static_cast<double>(a.size());
}

double mean(const std::vector<float>& v) {
  double sum = 0.0;
  for (float x : v)
    sum += static_cast<double>(x);
  return sum / static_cast<double>(v.size());
}

TEST(SimRender, SamePoseRendersIdentically) {
  const World lab = build_lab(101);
  const World again = build_lab(101);
  ASSERT_EQ(lab.boxes().size(), again.boxes().size());
  for (size_t i = 0; i < lab.boxes().size(); ++i) {
    const Box& a = lab.boxes()[i];
    const Box& b = again.boxes()[i];
    ASSERT_TRUE(a.lo.x == b.lo.x && a.lo.y == b.lo.y && a.lo.z == b.lo.z && a.hi.x == b.hi.x &&
                a.hi.y == b.hi.y && a.hi.z == b.hi.z && a.on == b.on)
        << "box " << i;
  }
  const LightCondition* light = find_light("lamps-only");
  ASSERT_NE(light, nullptr);
  const CameraModel cam = small_camera();
  const CameraPose pose{12.0, lab::kSouthLane, 0.3, 0.0};
  const std::vector<float> r1 = render_radiance(lab, *light, cam, pose);
  const std::vector<float> r2 = render_radiance(again, *light, cam, pose);
  const std::vector<float> r3 = render_radiance(lab, *light, cam, pose, 2);  // two threads
  ASSERT_EQ(r1.size(), static_cast<size_t>(cam.width) * static_cast<size_t>(cam.height));
  EXPECT_TRUE(r1 == r2);
  EXPECT_TRUE(r1 == r3);
  Exposure e1(light->exposure_bias);
  Exposure e2(light->exposure_bias);
  Rng n1(42);
  Rng n2(42);
  const std::vector<uint8_t> f1 = e1.expose(r1, cam.width, cam.height, n1);
  const std::vector<uint8_t> f2 = e2.expose(r2, cam.width, cam.height, n2);
  EXPECT_TRUE(f1 == f2);
  EXPECT_EQ(e1.gain(), e2.gain());
  // Another noise stream changes the image (the noise is there).
  Exposure e3(light->exposure_bias);
  Rng n3(43);
  EXPECT_FALSE(e3.expose(r1, cam.width, cam.height, n3) == f1);
  // The image is an image: not flat.
  uint8_t lo = 255, hi = 0;
  for (uint8_t p : f1) {
    lo = std::min(lo, p);
    hi = std::max(hi, p);
  }
  EXPECT_GT(hi - lo, 60);
}

TEST(SimRender, SamePlaceAcrossRunsBeatsFiveMetresApart) {
  // Two runs (different seeds: people, chairs, screens differ) at the same pose, against the
  // first run five metres further along the lane.
  const World run_a = build_lab(11);
  const World run_b = build_lab(22);
  const LightCondition* light = find_light("lamps-only");
  ASSERT_NE(light, nullptr);
  const CameraPose here{14.0, lab::kSouthLane, 0.0, 0.0};
  const CameraPose ahead{19.0, lab::kSouthLane, 0.0, 0.0};
  const std::vector<uint8_t> a = reduced_image(run_a, *light, here, 1);
  const std::vector<uint8_t> b = reduced_image(run_b, *light, here, 2);
  const std::vector<uint8_t> c = reduced_image(run_a, *light, ahead, 3);
  const double same_place = mean_abs_difference(a, b);
  const double other_place = mean_abs_difference(a, c);
  seqslam::test::log_figure("sim.render.same_place_other_run.mad", same_place);
  seqslam::test::log_figure("sim.render.five_metres_apart.mad", other_place);
  EXPECT_GT(same_place, 0.0);  // the runs differ (noise at least)
  EXPECT_LT(same_place, other_place);
}

TEST(SimRender, DimIsDarkerThanNoonWithLamps) {
  const World lab = build_lab(5);
  const CameraModel cam = small_camera();
  const CameraPose pose{20.0, lab::kNorthLane, 3.14159265358979323846, 0.0};
  const LightCondition* dim = find_light("dim");
  const LightCondition* noon = find_light("noon-lamps");
  ASSERT_NE(dim, nullptr);
  ASSERT_NE(noon, nullptr);
  EXPECT_EQ(find_light("no-such-light"), nullptr);
  EXPECT_EQ(light_conditions().size(), 6u);
  const double dim_mean = mean(render_radiance(lab, *dim, cam, pose));
  const double noon_mean = mean(render_radiance(lab, *noon, cam, pose));
  seqslam::test::log_figure("sim.render.dim.mean_radiance", dim_mean);
  seqslam::test::log_figure("sim.render.noon_lamps.mean_radiance", noon_mean);
  EXPECT_GT(dim_mean, 0.0);
  EXPECT_LT(dim_mean, noon_mean);
}

}  // namespace
}  // namespace seqslam::sim
