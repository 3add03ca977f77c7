// The ray caster (host_sim/include/seqslam_sim/world.h) against a brute-force slab test over
// every box plus the floor and ceiling planes, and against hand-computed cases.
//
// Stated bounds: the same surface (box index, floor or ceiling, or none) for every ray, and
// the distance t within 1e-9 relative; the analytic cases within 1e-12 m.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "seqslam_sim/rng.h"
#include "seqslam_sim/world.h"
#include "test_log.h"

namespace seqslam::sim {
namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kTMin = 1e-6;  // World::cast ignores hits at t <= 1e-6
constexpr double kRelTol = 1e-9;
constexpr double kInf = std::numeric_limits<double>::infinity();

struct RefHit {
  bool hit = false;
  double t = 0.0;
  int box = -1;
  Hit::Plane plane = Hit::Plane::kNone;
  int axis = -1;  // entry axis of the box
};

double component(const Vec3& v, int axis) {
  return axis == 0 ? v.x : axis == 1 ? v.y : v.z;
}

// The definition: the nearest of the floor (z = 0), the ceiling and every box's entry point
// with kTMin < t < t_max, by division (not the caster's reciprocals) and without the grid.
RefHit brute_force(const World& w, const Vec3& o, const Vec3& d, double t_max) {
  RefHit r;
  double best = t_max;
  if (d.z != 0.0) {
    const double plane_z = d.z < 0.0 ? 0.0 : w.ceiling_height();
    const double t = (plane_z - o.z) / d.z;
    if (t > kTMin && t < best) {
      best = t;
      r.hit = true;
      r.plane = d.z < 0.0 ? Hit::Plane::kFloor : Hit::Plane::kCeiling;
    }
  }
  for (size_t i = 0; i < w.boxes().size(); ++i) {
    const Box& b = w.boxes()[i];
    double enter = -kInf;
    double leave = kInf;
    int axis = -1;
    bool miss = false;
    for (int a = 0; a < 3 && !miss; ++a) {
      const double da = component(d, a);
      const double oa = component(o, a);
      const double lo = component(b.lo, a);
      const double hi = component(b.hi, a);
      if (da == 0.0) {
        miss = oa < lo || oa > hi;
        continue;
      }
      const double t0 = std::min((lo - oa) / da, (hi - oa) / da);
      const double t1 = std::max((lo - oa) / da, (hi - oa) / da);
      if (t0 > enter) {
        enter = t0;
        axis = a;
      }
      leave = std::min(leave, t1);
    }
    if (miss || axis < 0 || enter > leave || enter <= kTMin || enter >= best) continue;
    best = enter;
    r.hit = true;
    r.box = static_cast<int>(i);
    r.plane = Hit::Plane::kNone;
    r.axis = axis;
  }
  r.t = best;
  return r;
}

// Compares World::cast with the brute force for one ray; returns "" or what differs.
std::string compare_ray(const World& w, const Vec3& o, const Vec3& d, double t_max,
                        RefHit* ref_out = nullptr) {
  const RefHit ref = brute_force(w, o, d, t_max);
  if (ref_out != nullptr) *ref_out = ref;
  Hit h;
  const bool hit = w.cast(o, d, t_max, &h);
  char where[256];
  std::snprintf(where, sizeof where, "ray o=(%.17g, %.17g, %.17g) d=(%.17g, %.17g, %.17g) tmax=%g",
                o.x, o.y, o.z, d.x, d.y, d.z, t_max);
  if (hit != ref.hit) {
    return std::string(where) + ": cast " + (hit ? "hits" : "misses") + ", brute force " +
           (ref.hit ? "hits box " + std::to_string(ref.box) + " at t=" + std::to_string(ref.t)
                    : "misses");
  }
  if (!hit) return "";
  if (h.box != ref.box || h.plane != ref.plane) {
    return std::string(where) + ": cast hit box " + std::to_string(h.box) + " plane " +
           std::to_string(static_cast<int>(h.plane)) + " at t=" + std::to_string(h.t) +
           ", brute force box " + std::to_string(ref.box) + " plane " +
           std::to_string(static_cast<int>(ref.plane)) + " at t=" + std::to_string(ref.t);
  }
  if (std::fabs(h.t - ref.t) > kRelTol * ref.t) {
    return std::string(where) + ": t " + std::to_string(h.t) + " vs " + std::to_string(ref.t);
  }
  const Vec3 p = o + d * h.t;
  if (std::fabs(p.x - h.point.x) > 1e-9 || std::fabs(p.y - h.point.y) > 1e-9 ||
      std::fabs(p.z - h.point.z) > 1e-9) {
    return std::string(where) + ": hit point is not origin + t * dir";
  }
  // The normal: -sign(d) along the entry axis for a box, +z for the floor, -z for the ceiling.
  Vec3 n;
  if (ref.box >= 0) {
    const double s = component(d, ref.axis) > 0.0 ? -1.0 : 1.0;
    if (ref.axis == 0) n.x = s;
    if (ref.axis == 1) n.y = s;
    if (ref.axis == 2) n.z = s;
  } else {
    n.z = ref.plane == Hit::Plane::kFloor ? 1.0 : -1.0;
  }
  if (h.normal.x != n.x || h.normal.y != n.y || h.normal.z != n.z) {
    return std::string(where) + ": wrong normal";
  }
  return "";
}

Box make_box(Vec3 lo, Vec3 hi, Surface s = Surface::kMatte) {
  Box b;
  b.lo = lo;
  b.hi = hi;
  b.surface = s;
  return b;
}

// A few hundred random boxes over 20 m x 12 m, standing on the floor or floating (shelves,
// monitors), some thin as posters.
World random_world(uint64_t seed, int count) {
  World w(3.0);
  Rng rng(seed);
  for (int i = 0; i < count; ++i) {
    const double x = rng.uniform(0.0, 20.0);
    const double y = rng.uniform(0.0, 12.0);
    const double sx = rng.chance(0.2) ? rng.uniform(0.01, 0.05) : rng.uniform(0.05, 1.5);
    const double sy = rng.chance(0.2) ? rng.uniform(0.01, 0.05) : rng.uniform(0.05, 1.5);
    const double z0 = rng.chance(0.5) ? 0.0 : rng.uniform(0.0, 2.5);
    const double z1 = std::min(3.0, z0 + rng.uniform(0.05, 1.5));
    w.add(make_box(Vec3{x, y, z0}, Vec3{x + sx, y + sy, z1}));
  }
  w.finalize(0.5);
  return w;
}

Vec3 random_direction(Rng& rng) {
  const double z = rng.uniform(-1.0, 1.0);
  const double a = rng.uniform(0.0, 2 * kPi);
  const double r = std::sqrt(1.0 - z * z);
  return Vec3{r * std::cos(a), r * std::sin(a), z};
}

TEST(SimWorld, RandomRaysMatchBruteForce) {
  const World w = random_world(0x3A7B, 300);
  Rng rng(20250601);
  int box_hits = 0, floor_hits = 0, ceiling_hits = 0, misses = 0, failures = 0;
  const int kRays = 20000;
  for (int i = 0; i < kRays; ++i) {
    Vec3 o{rng.uniform(-1.0, 21.0), rng.uniform(-1.0, 13.0), rng.uniform(0.02, 2.98)};
    if (rng.chance(0.2)) {  // far outside the grid
      o.x = rng.uniform(-30.0, 50.0);
      o.y = rng.chance(0.5) ? rng.uniform(-30.0, -2.0) : rng.uniform(14.0, 40.0);
    }
    Vec3 d = random_direction(rng);
    if (rng.chance(0.5)) {  // aim at a point inside a random box (many box hits)
      const Box& b = w.boxes()[rng.below(static_cast<uint32_t>(w.boxes().size()))];
      const Vec3 target{rng.uniform(b.lo.x, b.hi.x), rng.uniform(b.lo.y, b.hi.y),
                        rng.uniform(b.lo.z, b.hi.z)};
      d = (target - o) * rng.uniform(0.1, 3.0);  // not unit length: t is in d's units
    }
    switch (rng.below(10)) {  // zero components: along axes, horizontal, vertical
      case 0:
        d.x = 0.0;
        break;
      case 1:
        d.y = 0.0;
        break;
      case 2:
        d.z = 0.0;
        break;
      case 3:
        d.x = 0.0;
        d.y = 0.0;
        break;
      default:
        break;
    }
    if (d.x == 0.0 && d.y == 0.0 && d.z == 0.0) d.z = 1.0;
    const double t_max = rng.chance(0.2) ? rng.uniform(0.1, 10.0) : 1e3;
    RefHit ref;
    const std::string e = compare_ray(w, o, d, t_max, &ref);
    if (!e.empty()) {
      ADD_FAILURE() << e;
      if (++failures > 10) break;
    }
    if (!ref.hit)
      ++misses;
    else if (ref.box >= 0)
      ++box_hits;
    else if (ref.plane == Hit::Plane::kFloor)
      ++floor_hits;
    else
      ++ceiling_hits;
  }
  seqslam::test::log_figure("sim.world.random_rays.box_hits", box_hits);
  seqslam::test::log_figure("sim.world.random_rays.floor_hits", floor_hits);
  seqslam::test::log_figure("sim.world.random_rays.ceiling_hits", ceiling_hits);
  seqslam::test::log_figure("sim.world.random_rays.misses", misses);
  // The sample exercises every outcome.
  EXPECT_GT(box_hits, kRays / 4);
  EXPECT_GT(floor_hits, 500);
  EXPECT_GT(ceiling_hits, 500);
  EXPECT_GT(misses, 100);
}

// Faces on the grid's cell boundaries and rays running exactly along them (zero direction
// components, origins on cell edges, inside and outside the grid, both directions).
TEST(SimWorld, AxisRaysAlongFacesAndCellEdges) {
  World w(3.0);
  // Bounds start at x = 0, y = 0, so after finalize(0.5) the cell edges are at k / 2 - 0.5,
  // exactly representable, and these faces lie on them.
  w.add(make_box(Vec3{0.0, 0.0, 0.0}, Vec3{0.5, 0.5, 1.0}));
  w.add(make_box(Vec3{2.0, 1.0, 0.0}, Vec3{3.0, 1.5, 2.0}));
  w.add(make_box(Vec3{4.5, 1.5, 0.5}, Vec3{5.0, 3.0, 3.0}));
  w.add(make_box(Vec3{1.0, 3.0, 1.0}, Vec3{1.5, 4.0, 1.5}));
  w.add(make_box(Vec3{6.0, 0.0, 0.0}, Vec3{6.5, 5.0, 0.08}));  // skirting
  w.add(make_box(Vec3{3.25, 2.25, 0.0}, Vec3{3.75, 2.75, 2.5}));
  w.finalize(0.5);
  int checked = 0, hits = 0;
  const double lines[] = {-3.0, -0.5, 0.0,  0.25, 0.5, 1.0, 1.5,
                          2.25, 2.5,  2.75, 3.0,  4.0, 5.0, 7.5};
  const double heights[] = {0.04, 0.5, 1.0, 1.25, 2.0, 2.9};
  for (double a : lines) {
    for (double b : lines) {
      for (double z : heights) {
        for (double s : {-1.0, 1.0}) {
          const Vec3 dirs[] = {{s, 0.0, 0.0}, {0.0, s, 0.0}, {0.0, 0.0, s}, {s, 0.0, 0.5}};
          for (const Vec3& d : dirs) {
            RefHit ref;
            const std::string e = compare_ray(w, Vec3{a, b, z}, d, 1e3, &ref);
            EXPECT_TRUE(e.empty()) << e;
            ++checked;
            if (ref.box >= 0) ++hits;
          }
        }
      }
    }
  }
  EXPECT_GT(hits, checked / 10);
}

// Rays from far outside the grid aimed at boxes, and rays that pass the grid by.
TEST(SimWorld, RaysFromOutsideTheGrid) {
  const World w = random_world(0x51DE, 200);
  Rng rng(77);
  int hits = 0;
  for (int i = 0; i < 2000; ++i) {
    const double a = rng.uniform(0.0, 2 * kPi);
    const Vec3 o{10.0 + 60.0 * std::cos(a), 6.0 + 60.0 * std::sin(a), rng.uniform(0.1, 2.9)};
    const Box& b = w.boxes()[rng.below(static_cast<uint32_t>(w.boxes().size()))];
    Vec3 target{(b.lo.x + b.hi.x) / 2, (b.lo.y + b.hi.y) / 2, o.z};
    if (i % 4 == 0) target = Vec3{rng.uniform(-40.0, 60.0), rng.uniform(-40.0, 50.0), o.z};
    const Vec3 d = target - o;
    RefHit ref;
    const std::string e = compare_ray(w, o, d, 1e3, &ref);
    EXPECT_TRUE(e.empty()) << e;
    if (ref.box >= 0) ++hits;
  }
  EXPECT_GT(hits, 1000);
}

TEST(SimWorld, VerticalRays) {
  const World w = random_world(0xF00D, 300);
  Rng rng(5);
  int box_hits = 0;
  for (int i = 0; i < 3000; ++i) {
    const Vec3 o{rng.uniform(-1.0, 21.0), rng.uniform(-1.0, 13.0), rng.uniform(0.02, 2.98)};
    const Vec3 d{0.0, 0.0, rng.chance(0.5) ? 1.0 : -1.0};
    RefHit ref;
    const std::string e = compare_ray(w, o, d, 1e3, &ref);
    EXPECT_TRUE(e.empty()) << e;
    if (ref.box >= 0) ++box_hits;
  }
  EXPECT_GT(box_hits, 300);
  // Straight down from 1.15 m with nothing below: the floor at t = 1.15.
  World empty(3.0);
  empty.add(make_box(Vec3{5.0, 5.0, 0.0}, Vec3{6.0, 6.0, 1.0}));
  empty.finalize(0.5);
  Hit h;
  ASSERT_TRUE(empty.cast(Vec3{1.0, 1.0, 1.15}, Vec3{0.0, 0.0, -1.0}, 1e3, &h));
  EXPECT_EQ(h.plane, Hit::Plane::kFloor);
  EXPECT_NEAR(h.t, 1.15, 1e-12);
  ASSERT_TRUE(empty.cast(Vec3{1.0, 1.0, 1.15}, Vec3{0.0, 0.0, 1.0}, 1e3, &h));
  EXPECT_EQ(h.plane, Hit::Plane::kCeiling);
  EXPECT_NEAR(h.t, 1.85, 1e-12);
  // Down onto the top of the box.
  ASSERT_TRUE(empty.cast(Vec3{5.5, 5.5, 2.0}, Vec3{0.0, 0.0, -1.0}, 1e3, &h));
  EXPECT_EQ(h.box, 0);
  EXPECT_NEAR(h.t, 1.0, 1e-12);
  EXPECT_EQ(h.normal.z, 1.0);
}

TEST(SimWorld, AnalyticCases) {
  // A wall 2 m ahead of an origin at 1.15 m height.
  World wall(3.0);
  wall.add(make_box(Vec3{2.0, -5.0, 0.0}, Vec3{2.2, 5.0, 3.0}));
  wall.finalize(0.5);
  Hit h;
  ASSERT_TRUE(wall.cast(Vec3{0.0, 0.0, 1.15}, Vec3{1.0, 0.0, 0.0}, 100.0, &h));
  EXPECT_EQ(h.box, 0);
  EXPECT_NEAR(h.t, 2.0, 1e-12);
  EXPECT_NEAR(h.point.x, 2.0, 1e-12);
  EXPECT_EQ(h.normal.x, -1.0);
  // t is in the direction's units.
  ASSERT_TRUE(wall.cast(Vec3{0.0, 0.0, 1.15}, Vec3{4.0, 0.0, 0.0}, 100.0, &h));
  EXPECT_NEAR(h.t, 0.5, 1e-12);
  // ... and t_max limits it.
  EXPECT_FALSE(wall.cast(Vec3{0.0, 0.0, 1.15}, Vec3{1.0, 0.0, 0.0}, 1.99, &h));
  // 45 degrees to the left: 2 * sqrt(2) along a unit direction.
  const double c = std::sqrt(0.5);
  ASSERT_TRUE(wall.cast(Vec3{0.0, 0.0, 1.15}, Vec3{c, c, 0.0}, 100.0, &h));
  EXPECT_NEAR(h.t, 2.0 * std::sqrt(2.0), 1e-12);
  EXPECT_NEAR(h.point.y, 2.0, 1e-12);

  // The floor from the camera's height looking 10 degrees down: t = 1.15 / sin(10 deg), at
  // 1.15 / tan(10 deg) = 6.522 m ahead.
  World open(3.0);
  open.add(make_box(Vec3{0.0, 3.0, 0.0}, Vec3{20.0, 3.2, 3.0}));  // a side wall, not in the way
  open.finalize(0.5);
  const double tilt = 10.0 * kPi / 180.0;
  ASSERT_TRUE(
      open.cast(Vec3{0.0, 0.0, 1.15}, Vec3{std::cos(tilt), 0.0, -std::sin(tilt)}, 200.0, &h));
  EXPECT_EQ(h.box, -1);
  EXPECT_EQ(h.plane, Hit::Plane::kFloor);
  EXPECT_NEAR(h.t, 1.15 / std::sin(tilt), 1e-12);
  EXPECT_NEAR(h.point.x, 1.15 / std::tan(tilt), 1e-12);
  EXPECT_NEAR(h.point.z, 0.0, 1e-12);
  EXPECT_EQ(h.normal.z, 1.0);
  // Nothing at all along a level ray that passes the wall: no hit.
  EXPECT_FALSE(open.cast(Vec3{0.0, 0.0, 1.15}, Vec3{1.0, 0.0, 0.0}, 200.0, &h));
}

TEST(SimWorld, SkyVisibleThroughWindowsOnly) {
  World w(3.0);
  // A window pane 5 m east (glass from 0.9 to 2.6 m), an opaque cabinet south-east.
  w.add(make_box(Vec3{5.0, -2.0, 0.9}, Vec3{5.05, 2.0, 2.6}, Surface::kWindow));
  w.add(make_box(Vec3{5.0, -2.0, 0.0}, Vec3{5.05, 2.0, 0.9}));  // the wall under the sill
  w.add(make_box(Vec3{2.0, -3.0, 0.0}, Vec3{2.5, -1.0, 2.5}));  // cabinet
  w.finalize(0.5);
  const Vec3 o{0.0, 0.0, 1.5};
  // Through the pane (rising 0.1 per metre: z = 2.0 at the glass).
  EXPECT_TRUE(w.sky_visible(o, Vec3{1.0, 0.0, 0.1}));
  // The same direction from behind the cabinet: blocked.
  EXPECT_FALSE(w.sky_visible(Vec3{0.0, -2.0, 1.5}, Vec3{1.0, 0.0, 0.1}));
  // Below the sill: the wall.
  EXPECT_FALSE(w.sky_visible(o, Vec3{1.0, 0.0, -0.15}));
  // Straight up: the ceiling.
  EXPECT_FALSE(w.sky_visible(o, Vec3{0.0, 0.0, 1.0}));
  // Down: the floor.
  EXPECT_FALSE(w.sky_visible(o, Vec3{0.0, 0.0, -1.0}));
  // Level and past everything (no floor, no ceiling, no box): open sky.
  EXPECT_TRUE(w.sky_visible(o, Vec3{-1.0, 0.0, 0.0}));
}

}  // namespace
}  // namespace seqslam::sim
