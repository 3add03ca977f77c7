// What Myon's head camera sees: a pinhole camera 346x271 pixels with about 60 degrees
// horizontal field of view, tilted 10 degrees down, rendered by ray casting the lab, lit by
// the ceiling lamps, the sky through the windows and direct sun; then the camera's exposure
// control, its internal gamma of 0.45, sensor noise, and 8-bit quantisation.
//
// Light conditions follow the six data sets of the 2025 thesis (Table 2): low morning sun,
// noon with lamps on, morning sun with lamps on, very bright sun, dim early morning, lamps
// only. Each sets sky and sun radiance, the sun's direction (which decides where sunlit
// patches fall through the windows), the lamps, and the camera's exposure behaviour.
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include "seqslam_sim/rng.h"
#include "seqslam_sim/world.h"

namespace seqslam::sim {

struct LightCondition {
  std::string name;
  std::string description;
  double ambient = 0.05;   // uniform indirect light
  double lamps = 0.0;      // ceiling lamps' irradiance scale (0 = off)
  double sky_south = 0.3;  // daylight through the south / north windows (diffuse)
  double sky_north = 0.2;
  double sky_radiance = 2.0;       // what the camera sees through a window
  double sun = 0.0;                // direct sun irradiance (0 = overcast / none)
  double sun_azimuth_deg = 120.0;  // compass-like: 0 = +x (east), 90 = +y (north)
  double sun_elevation_deg = 15.0;
  double exposure_bias = 1.0;  // the auto-exposure's target brightness scale
};

// The six conditions; names: low-sun, noon-lamps, morning-lamps, bright-sun, dim, lamps-only.
const std::vector<LightCondition>& light_conditions();
// nullptr for an unknown name.
const LightCondition* find_light(const std::string& name);

struct CameraModel {
  int width = 346;
  int height = 271;
  double hfov_deg = 60.0;
  double tilt_deg = 10.0;   // downwards
  double height_m = 1.15;   // above the floor (Myon's head on the wheeled base)
  double forward_m = 0.05;  // ahead of the base's centre
  // Image-plane transformation of the view (perspective sets): roll about the optical axis,
  // principal-point shift in pixels, zoom (focal length scale).
  double roll_deg = 0.0;
  double shift_x_px = 0.0;
  double shift_y_px = 0.0;
  double zoom = 1.0;
  double focal_px() const;
};

struct CameraPose {
  double x = 0.0;
  double y = 0.0;
  double heading = 0.0;  // radians, counter-clockwise from +x
  double pan = 0.0;      // head pan, radians (positive = left)
};

// Runs job(0) .. job(count - 1) on up to `threads` threads; the jobs must be independent.
void parallel_for(size_t count, unsigned threads, const std::function<void(size_t)>& job);

// Scene radiance (linear, arbitrary units) for every pixel, row-major, computed on up to
// `threads` threads (the result does not depend on the count).
std::vector<float> render_radiance(const World& world, const LightCondition& light,
                                   const CameraModel& camera, const CameraPose& pose,
                                   unsigned threads = 1);

// The camera's exposure control: a slow auto-exposure that meters the mean of the frame's
// gamma-encoded brightness against a target, clamped to its range. One instance per run;
// frames are exposed in order.
class Exposure {
 public:
  explicit Exposure(double bias = 1.0) : bias_(bias) {}
  // Exposes, gamma-encodes (0.45) and quantises `radiance` into 8-bit grey, adding sensor
  // noise from `noise` and lens vignetting.
  std::vector<uint8_t> expose(const std::vector<float>& radiance, int width, int height,
                              Rng& noise);
  double gain() const { return gain_; }

 private:
  double bias_;
  double gain_ = -1.0;  // < 0 until the first frame has been metered
};

}  // namespace seqslam::sim
