#include "seqslam_sim/render.h"

#include "seqslam_tools/parallel.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <thread>

namespace seqslam::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDeg = kPi / 180.0;

double albedo_of(const Texture& t, double u, double v) {
  double a = t.albedo;
  switch (t.pattern) {
    case Texture::Pattern::kPlain:
      break;
    case Texture::Pattern::kNoise:
      a *= 1.0 +
           t.contrast * (0.7 * value_noise(u / t.scale, v / t.scale, t.seed) +
                         0.3 * value_noise(u / (0.3 * t.scale), v / (0.3 * t.scale), t.seed + 1));
      break;
    case Texture::Pattern::kTiles: {
      const double fu = u / t.scale - std::floor(u / t.scale);
      const double fv = v / t.scale - std::floor(v / t.scale);
      const double joint = 0.012 / t.scale;
      if (fu < joint || fv < joint) a *= 0.75;
      a *= 1.0 + t.contrast * value_noise(u / 0.4, v / 0.4, t.seed);
      break;
    }
    case Texture::Pattern::kBlocks: {
      const double h = lattice_hash(static_cast<int64_t>(std::floor(u / t.scale)),
                                    static_cast<int64_t>(std::floor(v / t.scale)), t.seed);
      a *= 1.0 + t.contrast * (2.0 * h - 1.0);
      break;
    }
    case Texture::Pattern::kStripes: {
      const double h = lattice_hash(static_cast<int64_t>(std::floor(u / t.scale)), 0, t.seed);
      a *= 1.0 + t.contrast * (2.0 * h - 1.0);
      break;
    }
  }
  return std::clamp(a, 0.0, 0.95);
}

// Lamp centres bucketed on a 1 m grid: each bucket lists the lamps within kReach of any
// point in it, so a point visits a dozen lamps instead of all of them.
class LampIndex {
 public:
  static constexpr double kReach = 5.0;  // metres; beyond this a lamp adds < 2 %

  LampIndex(const World& w, double ceiling) : ceiling_(ceiling) {
    std::vector<Vec3> lamps;
    for (const Box& b : w.boxes()) {
      if (b.surface == Surface::kLamp) {
        lamps.push_back(Vec3{(b.lo.x + b.hi.x) / 2, (b.lo.y + b.hi.y) / 2, b.lo.z});
      }
    }
    const Area a = w.bounds();
    x0_ = std::floor(a.x0);
    y0_ = std::floor(a.y0);
    nx_ = static_cast<int>(std::ceil(a.x1 - x0_)) + 1;
    ny_ = static_cast<int>(std::ceil(a.y1 - y0_)) + 1;
    buckets_.resize(raster_index(0, ny_, nx_));
    for (int y = 0; y < ny_; ++y) {
      for (int x = 0; x < nx_; ++x) {
        const double cx = x0_ + x + 0.5;
        const double cy = y0_ + y + 0.5;
        for (const Vec3& l : lamps) {
          if (std::hypot(l.x - cx, l.y - cy) < kReach + 0.75) {
            buckets_[raster_index(x, y, nx_)].push_back(l);
          }
        }
      }
    }
  }
  // Irradiance from the lamps at p with normal n (no occlusion; the caller dims covered
  // points).
  double irradiance(const Vec3& p, const Vec3& n) const {
    const int bx = std::clamp(static_cast<int>(p.x - x0_), 0, nx_ - 1);
    const int by = std::clamp(static_cast<int>(p.y - y0_), 0, ny_ - 1);
    double e = 0.0;
    const double dz = ceiling_ - p.z;
    for (const Vec3& l : buckets_[raster_index(bx, by, nx_)]) {
      const double dx = l.x - p.x;
      const double dy = l.y - p.y;
      const double r2 = dx * dx + dy * dy + dz * dz;
      const double along = n.x * dx + n.y * dy + n.z * dz;
      if (along <= 0.0) continue;
      // cos(surface) * cos(lamp) / (r^2 + 0.5), with both cosines over r.
      e += along * dz / (r2 * (r2 + 0.5));
    }
    return e;
  }

 private:
  double ceiling_;
  double x0_ = 0.0, y0_ = 0.0;
  int nx_ = 0, ny_ = 0;
  std::vector<std::vector<Vec3>> buckets_;
};

struct Shader {
  const World& world;
  const LightCondition& light;
  LampIndex lamps;
  Vec3 sun;

  Shader(const World& w, const LightCondition& l)
      : world(w), light(l), lamps(w, w.ceiling_height()) {
    const double az = l.sun_azimuth_deg * kDeg;
    const double el = l.sun_elevation_deg * kDeg;
    sun = Vec3{std::cos(el) * std::cos(az), std::cos(el) * std::sin(az), std::sin(el)};
  }

  // Covered points (under a desk, a shelf) get less of the diffuse light.
  double cover(const Vec3& p) const {
    Hit h;
    if (!world.cast(p, Vec3{0.0, 0.0, 1.0}, world.ceiling_height(), &h)) return 1.0;
    return h.box >= 0 ? 0.35 : 1.0;
  }

  double irradiance(const Vec3& p, const Vec3& n) const {
    const double covered = (n.z < 0.5 || p.z < 2.9) ? cover(p + n * 1e-4) : 1.0;
    double e = light.ambient;
    if (light.lamps > 0.0) e += light.lamps * lamps.irradiance(p, n) * covered;
    // Daylight through the south (y = 0) and north (y = 14) windows.
    const double to_south = std::max(0.0, -n.y);
    const double to_north = std::max(0.0, n.y);
    const double y = std::clamp(p.y, 0.0, 14.0);
    e += covered *
         (light.sky_south * std::exp(-y / 4.0) * (0.5 + 0.5 * to_south + 0.3 * n.z) +
          light.sky_north * std::exp(-(14.0 - y) / 4.0) * (0.5 + 0.5 * to_north + 0.3 * n.z));
    if (light.sun > 0.0) {
      const double c = dot(n, sun);
      if (c > 0.0 && world.sky_visible(p + n * 1e-4, sun)) e += light.sun * c;
    }
    return e;
  }

  double radiance(const Vec3& origin, const Vec3& dir) const {
    Hit h;
    if (!world.cast(origin, dir, 200.0, &h)) return light.sky_radiance;
    double u = 0.0;
    double v = 0.0;
    if (h.box < 0) {
      // Floor: grey linoleum tiles; ceiling: acoustic tiles.
      const Texture floor{Texture::Pattern::kTiles, 0.38, 0.08, 0.5, 31};
      const Texture ceiling{Texture::Pattern::kTiles, 0.8, 0.03, 0.625, 32};
      const Texture& t = h.plane == Hit::Plane::kFloor ? floor : ceiling;
      return albedo_of(t, h.point.x, h.point.y) * irradiance(h.point, h.normal);
    }
    const Box& b = world.boxes()[static_cast<size_t>(h.box)];
    if (h.normal.x != 0.0) {
      u = h.point.y - b.lo.y;
      v = h.point.z - b.lo.z;
    } else if (h.normal.y != 0.0) {
      u = h.point.x - b.lo.x;
      v = h.point.z - b.lo.z;
    } else {
      u = h.point.x - b.lo.x;
      v = h.point.y - b.lo.y;
    }
    switch (b.surface) {
      case Surface::kWindow:
        // Brighter towards the top of the pane; the sunny side brighter still.
        return light.sky_radiance * (0.8 + 0.25 * (h.point.z - 0.9)) *
               (1.0 + (dot(dir, sun) > 0.0 ? 0.5 * light.sun : 0.0));
      case Surface::kLamp:
        if (light.lamps > 0.0) return 6.0 * light.lamps;
        break;
      case Surface::kScreen:
        if (b.on) return 0.25 + 4.0 * albedo_of(b.texture, u, v);  // lit screen content
        break;
      case Surface::kMatte:
        break;
    }
    return albedo_of(b.texture, u, v) * irradiance(h.point, h.normal);
  }
};

}  // namespace

void parallel_for(size_t count, unsigned threads, const std::function<void(size_t)>& job) {
  tools::parallel_for(count, threads == 0 ? 1 : threads, job);
}

const std::vector<LightCondition>& light_conditions() {
  static const std::vector<LightCondition> kConditions = {
      {"low-sun", "morning, sunny, low sun through the south windows, lamps off (set 1)", 0.03, 0.0,
       0.35, 0.15, 3.0, 1.6, -25.0, 10.0, 0.85},
      {"noon-lamps", "noon, sunny with a few clouds, lamps on (set 2)", 0.06, 1.0, 0.45, 0.3, 3.5,
       0.9, -90.0, 32.0, 1.0},
      {"morning-lamps", "morning, sunny, lamps on (set 3)", 0.05, 1.0, 0.3, 0.15, 2.6, 1.2, -35.0,
       14.0, 1.0},
      {"bright-sun", "morning, very bright sunlight, lamps off (set 4)", 0.05, 0.0, 0.8, 0.35, 6.0,
       3.0, -45.0, 20.0, 1.15},
      {"dim", "an hour after sunrise, overcast and dim, lamps off (set 5)", 0.015, 0.0, 0.08, 0.05,
       0.5, 0.0, -60.0, 5.0, 0.6},
      {"lamps-only", "evening, lamps on, dark outside (set 6, reference)", 0.05, 1.0, 0.0, 0.0,
       0.05, 0.0, 0.0, -10.0, 1.0},
  };
  return kConditions;
}

const LightCondition* find_light(const std::string& name) {
  for (const LightCondition& c : light_conditions()) {
    if (c.name == name) return &c;
  }
  return nullptr;
}

double CameraModel::focal_px() const {
  return zoom * (width / 2.0) / std::tan(hfov_deg * kDeg / 2.0);
}

std::vector<float> render_radiance(const World& world, const LightCondition& light,
                                   const CameraModel& cam, const CameraPose& pose,
                                   unsigned threads) {
  const Shader shader(world, light);
  const double psi = pose.heading + pose.pan;
  const double th = cam.tilt_deg * kDeg;
  const Vec3 fwd{std::cos(th) * std::cos(psi), std::cos(th) * std::sin(psi), -std::sin(th)};
  const Vec3 right{std::sin(psi), -std::cos(psi), 0.0};
  const Vec3 down{-std::sin(th) * std::cos(psi), -std::sin(th) * std::sin(psi), -std::cos(th)};
  const Vec3 origin{pose.x + cam.forward_m * std::cos(pose.heading),
                    pose.y + cam.forward_m * std::sin(pose.heading), cam.height_m};
  const double f = cam.focal_px();
  const double cr = std::cos(cam.roll_deg * kDeg);
  const double sr = std::sin(cam.roll_deg * kDeg);
  const double cx = cam.width / 2.0 + cam.shift_x_px;
  const double cy = cam.height / 2.0 + cam.shift_y_px;
  std::vector<float> out(raster_index(0, cam.height, cam.width));
  // Rows are independent: split them over the threads (each pixel's value does not depend
  // on the split, so the image is the same for any thread count).
  const auto rows = [&](size_t v_index) {
    const int v = static_cast<int>(v_index);
    for (int u = 0; u < cam.width; ++u) {
      const double px = (u + 0.5 - cx) / f;
      const double py = (v + 0.5 - cy) / f;
      // Rolling the camera by +roll turns the image by -roll.
      const double rx = cr * px + sr * py;
      const double ry = -sr * px + cr * py;
      const Vec3 d = fwd + right * rx + down * ry;
      out[raster_index(u, v, cam.width)] = static_cast<float>(shader.radiance(origin, d));
    }
  };
  parallel_for(static_cast<size_t>(cam.height), threads, rows);
  return out;
}

std::vector<uint8_t> Exposure::expose(const std::vector<float>& radiance, int width, int height,
                                      Rng& noise) {
  constexpr double kGamma = 0.45;
  constexpr double kGainMin = 0.05;
  constexpr double kGainMax = 6.0;
  constexpr double kAdapt = 0.35;  // fraction of the way to the metered gain per frame
  double sum = 0.0;
  for (float r : radiance)
    sum += std::pow(std::max(0.0f, r), kGamma);
  const double mean = std::max(1e-6, sum / static_cast<double>(radiance.size()));
  const double target = 0.42 * bias_;
  const double ideal = std::clamp(std::pow(target / mean, 1.0 / kGamma), kGainMin, kGainMax);
  gain_ =
      gain_ < 0.0 ? ideal : std::exp((1.0 - kAdapt) * std::log(gain_) + kAdapt * std::log(ideal));
  std::vector<uint8_t> out(radiance.size());
  const double hx = width / 2.0;
  const double hy = height / 2.0;
  const double corner2 = hx * hx + hy * hy;
  for (int v = 0; v < height; ++v) {
    for (int u = 0; u < width; ++u) {
      const size_t i = raster_index(u, v, width);
      const double dx = u + 0.5 - hx;
      const double dy = v + 0.5 - hy;
      const double vignette = 1.0 - 0.3 * (dx * dx + dy * dy) / corner2;
      const double e = std::clamp(gain_ * static_cast<double>(radiance[i]) * vignette, 0.0, 1.0);
      double value = 255.0 * std::pow(e, kGamma);
      value += noise.normal() * (1.2 + 0.01 * value);
      out[i] = static_cast<uint8_t>(std::clamp(std::lround(value), 0L, 255L));
    }
  }
  return out;
}

}  // namespace seqslam::sim
