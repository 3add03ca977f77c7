#include "seqslam_sim/robot.h"

#include <algorithm>
#include <cmath>

namespace seqslam::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kDt = 0.01;   // the SpinalCord period
constexpr int kSubsteps = 10;  // physics at 1 ms

double wrap_pi(double a) {
  while (a > kPi)
    a -= 2 * kPi;
  while (a < -kPi)
    a += 2 * kPi;
  return a;
}

// A dense path (5 cm) along the waypoints, corners rounded by quadratic Bezier arcs.
struct Path {
  std::vector<Point2> p;
  std::vector<double> s;        // arc length at each point
  std::vector<double> heading;  // tangent direction
  double length() const { return s.empty() ? 0.0 : s.back(); }
};

Path make_path(const std::vector<Point2>& w, double radius) {
  std::vector<Point2> coarse;
  const double step = 0.05;
  auto line = [&](Point2 a, Point2 b) {
    const double len = std::hypot(b.x - a.x, b.y - a.y);
    const int n = std::max(1, static_cast<int>(len / step));
    for (int i = 0; i < n; ++i) {
      const double t = static_cast<double>(i) / n;
      coarse.push_back(Point2{a.x + (b.x - a.x) * t, a.y + (b.y - a.y) * t});
    }
  };
  Point2 from = w.front();
  for (size_t i = 1; i + 1 < w.size(); ++i) {
    const Point2 c = w[i];
    const double l0 = std::hypot(c.x - from.x, c.y - from.y);
    const double l1 = std::hypot(w[i + 1].x - c.x, w[i + 1].y - c.y);
    const double r = std::min({radius, 0.45 * l0, 0.45 * l1});
    const Point2 a{c.x + (from.x - c.x) * r / l0, c.y + (from.y - c.y) * r / l0};
    const Point2 b{c.x + (w[i + 1].x - c.x) * r / l1, c.y + (w[i + 1].y - c.y) * r / l1};
    line(from, a);
    const int n = std::max(2, static_cast<int>(2.0 * r / step));
    for (int k = 0; k < n; ++k) {
      const double t = static_cast<double>(k) / n;
      const double u = 1.0 - t;
      coarse.push_back(Point2{u * u * a.x + 2 * u * t * c.x + t * t * b.x,
                              u * u * a.y + 2 * u * t * c.y + t * t * b.y});
    }
    from = b;
  }
  line(from, w.back());
  coarse.push_back(w.back());
  Path path;
  double s = 0.0;
  for (size_t i = 0; i < coarse.size(); ++i) {
    if (i > 0) {
      const double d = std::hypot(coarse[i].x - coarse[i - 1].x, coarse[i].y - coarse[i - 1].y);
      if (d < 1e-9) continue;
      s += d;
    }
    path.p.push_back(coarse[i]);
    path.s.push_back(s);
  }
  path.heading.resize(path.p.size());
  for (size_t i = 0; i < path.p.size(); ++i) {
    const size_t a = i == 0 ? 0 : i - 1;
    const size_t b = std::min(path.p.size() - 1, i + 1);
    path.heading[i] = std::atan2(path.p[b].y - path.p[a].y, path.p[b].x - path.p[a].x);
  }
  return path;
}

// A smooth random function of arc length with |f| <= 1: a sum of three sinusoids of
// wavelengths 15..40 m, faded in over the first metres.
struct Wander {
  double amp[3], wave[3], phase[3];
  explicit Wander(Rng& rng) {
    double total = 0.0;
    for (int k = 0; k < 3; ++k) {
      amp[k] = rng.uniform(0.3, 1.0);
      wave[k] = rng.uniform(15.0, 40.0);
      phase[k] = rng.uniform(0.0, 2 * kPi);
      total += amp[k];
    }
    for (double& a : amp)
      a /= total;
  }
  double operator()(double s) const {
    double v = 0.0;
    for (int k = 0; k < 3; ++k)
      v += amp[k] * std::sin(2 * kPi * s / wave[k] + phase[k]);
    return v * std::min(1.0, s / 3.0);
  }
};

// The lateral offset a person steering the robot keeps from the route's centre line: they
// hold a line (a level in [-0.5, 0.5], a third of the time in [-1, 1]) for 6..20 m, then drift to
// another over 3..7 m (a smoothstep), so the heading mostly stays parallel to the corridor and
// deviates only while changing lines and in corners. Starts on the centre line.
class Drift {
 public:
  Drift(Rng& rng, double length) {
    double s = 0.0;
    double level = 0.0;
    while (s < length + 50.0) {
      const double hold = rng.uniform(6.0, 20.0);
      const double change = rng.uniform(3.0, 7.0);
      // Mostly near the centre line; now and then out to the full deviation.
      const double next = rng.chance(0.35) ? rng.uniform(-1.0, 1.0) : rng.uniform(-0.5, 0.5);
      knots_.push_back(Knot{s + hold, s + hold + change, level, next});
      s += hold + change;
      level = next;
    }
  }
  double operator()(double s) const {
    for (const Knot& k : knots_) {
      if (s < k.start) return k.from;
      if (s < k.end) {
        double t = (s - k.start) / (k.end - k.start);
        t = t * t * (3.0 - 2.0 * t);
        return k.from + (k.to - k.from) * t;
      }
    }
    return knots_.empty() ? 0.0 : knots_.back().to;
  }

 private:
  struct Knot {
    double start, end, from, to;
  };
  std::vector<Knot> knots_;
};

size_t nearest_index(const Path& path, double x, double y, size_t hint) {
  size_t best = hint;
  double best_d = 1e18;
  const size_t lo = hint > 40 ? hint - 40 : 0;
  const size_t hi = std::min(path.p.size(), hint + 120);
  for (size_t i = lo; i < hi; ++i) {
    const double d = std::hypot(path.p[i].x - x, path.p[i].y - y);
    if (d < best_d) {
      best_d = d;
      best = i;
    }
  }
  return best;
}

size_t index_at(const Path& path, double s) {
  const auto it = std::lower_bound(path.s.begin(), path.s.end(), s);
  return std::min(path.p.size() - 1, static_cast<size_t>(it - path.s.begin()));
}

uint16_t measure_infrared(const World& world, const InfraredSensor& ir, const TruePose& pose,
                          Rng& rng) {
  const double c = std::cos(pose.heading);
  const double s = std::sin(pose.heading);
  const Vec3 origin{pose.x + c * ir.x - s * ir.y, pose.y + s * ir.x + c * ir.y, kInfraredHeight};
  const double a = pose.heading + ir.angle;
  const Vec3 dir{std::cos(a), std::sin(a), 0.0};
  Hit h;
  if (!world.cast(origin, dir, ir.max_m * 1.2, &h)) return 0;
  double d = h.t + rng.normal() * (0.004 + 0.012 * h.t);
  if (d < ir.min_m || d > ir.max_m) return 0;
  return static_cast<uint16_t>(std::lround(d * 1000.0));
}

}  // namespace

std::vector<InfraredSensor> default_infrared() {
  return {
      {0.20, 0.00, 0.0, 0.2, 1.5},       {0.17, 0.12, kPi / 4, 0.2, 1.5},
      {0.17, -0.12, -kPi / 4, 0.2, 1.5}, {0.00, 0.20, kPi / 2, 0.2, 1.5},
      {0.00, -0.20, -kPi / 2, 0.2, 1.5}, {-0.20, 0.00, kPi, 0.2, 1.5},
  };
}

double route_length(const std::vector<Leg>& legs, double corner_radius) {
  double total = 0.0;
  for (const Leg& leg : legs)
    total += make_path(leg.waypoints, corner_radius).length();
  return total;
}

std::vector<DriveTick> drive(const std::vector<Leg>& legs, const DriveOptions& o,
                             const World& world, Rng& rng) {
  std::vector<DriveTick> ticks;
  // Sensor noise from its own stream: how many draws it takes depends on what the sensors
  // see (people differ between runs), and must not change the drive itself.
  Rng sensor_noise = rng.derive(0x1F);
  TruePose pose;
  bool placed = false;
  // Encoders start near the wrap so every run exercises the counters' modular arithmetic.
  double rev_left = 0.0;
  double rev_right = 0.0;
  const uint32_t start_left = 0xFFFFFFFFu - rng.below(200000);
  const uint32_t start_right = 0xFFFFFFFFu - rng.below(200000);
  uint32_t sequence = 1 + rng.below(1000);
  uint32_t time_us = rng.below(1000000);
  double v = 0.0;
  double omega = 0.0;
  const Wander speed_wander(rng);
  double s_total = 0.0;

  for (const Leg& leg : legs) {
    if (leg.waypoints.size() < 2) continue;
    const Path path = make_path(leg.waypoints, o.corner_radius);
    const Drift lateral(rng, path.length());
    if (!placed || leg.teleport) {
      pose = TruePose{path.p[0].x, path.p[0].y, path.heading[0]};
      v = 0.0;
      placed = true;
    }
    // The offset path the driver actually aims for.
    auto target = [&](double s) {
      const size_t i = index_at(path, s);
      const double off = o.deviation_m * lateral(s);
      const double h = path.heading[i];
      return Point2{path.p[i].x - std::sin(h) * off, path.p[i].y + std::cos(h) * off};
    };
    size_t near = 0;
    for (;;) {
      near = nearest_index(path, pose.x, pose.y, near);
      const double s = path.s[near];
      if (s >= path.length() - 0.05) break;
      // Pure pursuit on the offset path, 0.6 m ahead.
      const double look = 0.6;
      const Point2 t = target(std::min(path.length(), s + look));
      const double alpha = wrap_pi(std::atan2(t.y - pose.y, t.x - pose.x) - pose.heading);
      const double dist = std::max(0.2, std::hypot(t.x - pose.x, t.y - pose.y));
      const double kappa = 2.0 * std::sin(alpha) / dist;
      double v_want =
          o.speed_min + (o.speed_max - o.speed_min) * (0.5 + 0.5 * speed_wander(s_total + s));
      v_want /= 1.0 + 1.5 * std::fabs(kappa);
      // Slow down to stop at the end of the route.
      v_want = std::min(v_want, std::max(0.05, 0.8 * (path.length() - s)));
      const double accel = 0.4 * kDt;
      v = std::clamp(v_want, v - accel, v + accel);
      omega = std::clamp(v * kappa, -1.0, 1.0);
      // Physics at 1 ms: exact unicycle motion; the wheels turn by the ground distance over
      // their true circumference, disturbed by slip.
      const double slip_l = o.slip_sigma * rng.normal();
      const double slip_r = o.slip_sigma * rng.normal();
      for (int k = 0; k < kSubsteps; ++k) {
        const double dt = kDt / kSubsteps;
        const double dl = (v - omega * o.wheels.track / 2) * dt;
        const double dr = (v + omega * o.wheels.track / 2) * dt;
        rev_left += dl / o.wheels.circumference_left * (1.0 + slip_l);
        rev_right += dr / o.wheels.circumference_right * (1.0 + slip_r);
        const double dh = omega * dt;
        const double mid = pose.heading + dh / 2;
        pose.x += v * dt * std::cos(mid);
        pose.y += v * dt * std::sin(mid);
        pose.heading += dh;
      }
      DriveTick tick;
      hal::SensorSnapshot& snap = tick.snapshot;
      snap.sequence = sequence++;
      time_us += hal::kSnapshotPeriodUs;
      snap.timestamp_us = time_us;
      snap.flags = hal::SensorSnapshot::kHasEncoders | hal::SensorSnapshot::kHasInfrared |
                   hal::SensorSnapshot::kHasHead;
      snap.encoder_left = start_left + static_cast<uint32_t>(static_cast<int64_t>(
                                           std::floor(rev_left * o.wheels.ticks_per_revolution)));
      snap.encoder_right = start_right + static_cast<uint32_t>(static_cast<int64_t>(std::floor(
                                             rev_right * o.wheels.ticks_per_revolution)));
      snap.infrared_count =
          static_cast<uint8_t>(std::min<size_t>(o.infrared.size(), hal::kMaxInfrared));
      for (uint32_t i = 0; i < snap.infrared_count; ++i) {
        snap.infrared_mm[i] = measure_infrared(world, o.infrared[i], pose, sensor_noise);
      }
      tick.truth = pose;
      const size_t i = nearest_index(path, pose.x, pose.y, near);
      const double h = path.heading[i];
      tick.lateral_deviation =
          -(pose.x - path.p[i].x) * std::sin(h) + (pose.y - path.p[i].y) * std::cos(h);
      tick.heading_deviation = wrap_pi(pose.heading - h);
      ticks.push_back(tick);
      if (ticks.size() > 4'000'000) return ticks;  // a runaway route: give up (caller checks)
    }
    s_total += path.length();
  }
  return ticks;
}

}  // namespace seqslam::sim
