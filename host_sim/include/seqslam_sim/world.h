// The simulated world: axis-aligned boxes in a room with a floor and a ceiling, and a ray
// caster over them.
//
// Everything in the lab is a box (walls, window panes, desks, monitors, chairs, cabinets,
// posters, people), which keeps ray casting exact and cheap: a 2-D uniform grid over the floor
// plan lists the boxes overlapping each cell, and a ray walks the cells it crosses (3-D ray,
// 2-D traversal, as every box stands on or above the floor). Units: metres; x east, y north,
// z up; the floor is z = 0 and the ceiling z = ceiling_height inside the building.
#pragma once

#include <cstddef>
#include <cstdint>
#include <vector>

namespace seqslam::sim {

// Row-major index of (x, y) in a width-wide raster (all three non-negative).
inline size_t raster_index(int x, int y, int width) {
  return static_cast<size_t>(y) * static_cast<size_t>(width) + static_cast<size_t>(x);
}

struct Vec3 {
  double x = 0.0;
  double y = 0.0;
  double z = 0.0;
};
inline Vec3 operator+(Vec3 a, Vec3 b) {
  return {a.x + b.x, a.y + b.y, a.z + b.z};
}
inline Vec3 operator-(Vec3 a, Vec3 b) {
  return {a.x - b.x, a.y - b.y, a.z - b.z};
}
inline Vec3 operator*(Vec3 a, double s) {
  return {a.x * s, a.y * s, a.z * s};
}
inline double dot(Vec3 a, Vec3 b) {
  return a.x * b.x + a.y * b.y + a.z * b.z;
}

// How a surface looks: a grey albedo (0..1) modulated by a procedural pattern in the face's
// own coordinates (metres from the box's corner), so identical objects look identical - the
// repetitive desks and chairs of the thesis's lab.
struct Texture {
  enum class Pattern : uint8_t {
    kPlain,    // albedo
    kNoise,    // albedo * (1 + contrast * smooth noise of feature size `scale`)
    kTiles,    // a grid of `scale`-metre tiles with darker joints (floor, ceiling)
    kBlocks,   // blocks of `scale` metres with random albedo: posters, bookshelves, notices
    kStripes,  // vertical stripes `scale` wide with random albedo (binders, blinds)
  };
  Pattern pattern = Pattern::kPlain;
  double albedo = 0.8;
  double contrast = 0.0;
  double scale = 1.0;
  uint32_t seed = 0;
};

enum class Surface : uint8_t {
  kMatte,   // lit by the lamps, the sky through the windows and the sun
  kWindow,  // glass: the camera sees the sky's radiance; sunlight passes through
  kLamp,    // a ceiling lamp: emits when the lamps are on
  kScreen,  // a monitor screen: emits when switched on (differs between runs)
};

struct Box {
  Vec3 lo;
  Vec3 hi;
  Texture texture;
  Surface surface = Surface::kMatte;
  bool on = false;       // kScreen: switched on in this run
  bool solid_ir = true;  // seen by the infrared sensors and in the true map
};

struct Hit {
  double t = 0.0;
  Vec3 point;
  Vec3 normal;
  int box = -1;  // index into World::boxes(); -1 for the floor or the ceiling
  enum class Plane : uint8_t { kNone, kFloor, kCeiling } plane = Plane::kNone;
};

// An axis-aligned floor area (for the true map: cells inside any area are "free" unless a
// box occupies them).
struct Area {
  double x0, y0, x1, y1;
};

class World {
 public:
  explicit World(double ceiling_height = 3.0) : ceiling_(ceiling_height) {}

  int add(const Box& b);
  void add_area(const Area& a) { areas_.push_back(a); }
  // Builds the acceleration grid; call after the last add() and before cast().
  void finalize(double cell = 0.5);

  // The nearest surface along origin + t * dir for 1e-6 < t < t_max (dir need not be unit
  // length; t is in its units): a box, the floor (z = 0) or the ceiling.
  bool cast(const Vec3& origin, const Vec3& dir, double t_max, Hit* hit) const;
  // True when the sky is visible along dir from origin: the ray reaches a window pane, or
  // leaves everything without meeting the floor or the ceiling. Used for sunlight.
  bool sky_visible(const Vec3& origin, const Vec3& dir) const;

  const std::vector<Box>& boxes() const { return boxes_; }
  std::vector<Box>& boxes() { return boxes_; }
  const std::vector<Area>& areas() const { return areas_; }
  double ceiling_height() const { return ceiling_; }
  // Bounds of everything added (x0, y0, x1, y1).
  Area bounds() const { return {min_x_, min_y_, max_x_, max_y_}; }
  bool inside_areas(double x, double y) const;

 private:
  bool hit_box(int index, const Vec3& o, const Vec3& inv, double t_min, double t_max, double* t,
               int* axis) const;

  double ceiling_;
  std::vector<Box> boxes_;
  std::vector<Area> areas_;
  double min_x_ = 0.0, min_y_ = 0.0, max_x_ = 0.0, max_y_ = 0.0;
  double cell_ = 0.5;
  int nx_ = 0, ny_ = 0;
  std::vector<uint32_t> cell_start_;  // CSR lists of box indices per cell
  std::vector<uint32_t> cell_boxes_;
};

}  // namespace seqslam::sim
