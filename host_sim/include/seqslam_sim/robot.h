// The Myon wheeled base in simulation: a differential drive following a route with the
// deviations of a person steering it, 4096-tick wheel encoders whose true wheel constants
// differ from the ones the firmware is configured with (systematic odometry error) plus random
// slip, infrared distance sensors, all sampled on the 10 ms SpinalCord clock.
#pragma once

#include <cstdint>
#include <vector>

#include "seqslam/hal/spinal_cord.h"
#include "seqslam_sim/lab.h"
#include "seqslam_sim/rng.h"
#include "seqslam_sim/world.h"

namespace seqslam::sim {

// The physical wheels. The firmware's OdometryConfig defaults are the thesis's remeasured
// constants (left 53.2 cm, right 53.227 cm, track 47.4 cm); the simulated robot's true wheels
// differ from those by the amounts below, as a real robot's do until it is recalibrated.
struct WheelParams {
  double circumference_left = 0.5320 * (1.0 + 0.0008);
  double circumference_right = 0.53227 * (1.0 + 0.0005);
  double track = 0.474 * (1.0 + 0.005);
  uint32_t ticks_per_revolution = 4096;
};

struct InfraredSensor {
  double x = 0.0;  // mount on the base, robot frame: x forward, y left (metres)
  double y = 0.0;
  double angle = 0.0;  // pointing direction, radians counter-clockwise from forward
  double min_m = 0.2;  // Sharp GP2Y0A02-like range
  double max_m = 1.5;
};
// Six sensors: front, front-left/right at 45 degrees, left, right, rear; 12 cm above floor.
std::vector<InfraredSensor> default_infrared();
inline constexpr double kInfraredHeight = 0.12;

// A route leg: a polyline of waypoints driven with rounded corners. A leg that starts with
// `teleport` begins by lifting the robot to its first waypoint (the kidnapped robot): the
// encoders do not see the move.
struct Leg {
  std::vector<Point2> waypoints;
  bool teleport = false;
};

struct DriveOptions {
  WheelParams wheels{};
  double deviation_m = 0.5;  // amplitude bound of the lateral deviation from the route
  double speed_min = 0.15;   // m/s, the speed varies smoothly between these
  double speed_max = 0.35;
  double slip_sigma = 0.01;  // random slip: relative error of each wheel's rotation per 10 ms
  double corner_radius = 1.2;
  std::vector<InfraredSensor> infrared = default_infrared();
};

struct TruePose {
  double x = 0.0;
  double y = 0.0;
  double heading = 0.0;  // radians, unwrapped
};

struct DriveTick {
  hal::SensorSnapshot snapshot;
  TruePose truth;
  double lateral_deviation = 0.0;  // signed distance from the route's centre line (m)
  double heading_deviation = 0.0;  // heading minus the route's direction (radians)
};

// Drives the legs in order and returns one tick per 10 ms snapshot.
std::vector<DriveTick> drive(const std::vector<Leg>& legs, const DriveOptions& options,
                             const World& world, Rng& rng);

// The length of the route's centre line with rounded corners (metres).
double route_length(const std::vector<Leg>& legs, double corner_radius);

}  // namespace seqslam::sim
