#include "seqslam_sim/world.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace seqslam::sim {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kTMin = 1e-6;

double axis_of(const Vec3& v, int axis) {
  return axis == 0 ? v.x : axis == 1 ? v.y : v.z;
}
}  // namespace

int World::add(const Box& b) {
  if (boxes_.empty()) {
    min_x_ = b.lo.x;
    min_y_ = b.lo.y;
    max_x_ = b.hi.x;
    max_y_ = b.hi.y;
  }
  min_x_ = std::min(min_x_, b.lo.x);
  min_y_ = std::min(min_y_, b.lo.y);
  max_x_ = std::max(max_x_, b.hi.x);
  max_y_ = std::max(max_y_, b.hi.y);
  boxes_.push_back(b);
  return static_cast<int>(boxes_.size() - 1);
}

bool World::inside_areas(double x, double y) const {
  for (const Area& a : areas_) {
    if (x >= a.x0 && x < a.x1 && y >= a.y0 && y < a.y1) return true;
  }
  return false;
}

void World::finalize(double cell) {
  cell_ = cell;
  min_x_ -= cell;
  min_y_ -= cell;
  max_x_ += cell;
  max_y_ += cell;
  nx_ = static_cast<int>(std::ceil((max_x_ - min_x_) / cell_));
  ny_ = static_cast<int>(std::ceil((max_y_ - min_y_) / cell_));
  const size_t cells = static_cast<size_t>(nx_) * static_cast<size_t>(ny_);
  std::vector<std::vector<uint32_t>> lists(cells);
  for (size_t i = 0; i < boxes_.size(); ++i) {
    const Box& b = boxes_[i];
    const int x0 = std::max(0, static_cast<int>(std::floor((b.lo.x - min_x_) / cell_)));
    const int x1 = std::min(nx_ - 1, static_cast<int>(std::floor((b.hi.x - min_x_) / cell_)));
    const int y0 = std::max(0, static_cast<int>(std::floor((b.lo.y - min_y_) / cell_)));
    const int y1 = std::min(ny_ - 1, static_cast<int>(std::floor((b.hi.y - min_y_) / cell_)));
    for (int y = y0; y <= y1; ++y) {
      for (int x = x0; x <= x1; ++x) {
        lists[raster_index(x, y, nx_)].push_back(static_cast<uint32_t>(i));
      }
    }
  }
  cell_start_.assign(cells + 1, 0);
  cell_boxes_.clear();
  for (size_t c = 0; c < cells; ++c) {
    cell_start_[c] = static_cast<uint32_t>(cell_boxes_.size());
    cell_boxes_.insert(cell_boxes_.end(), lists[c].begin(), lists[c].end());
  }
  cell_start_[cells] = static_cast<uint32_t>(cell_boxes_.size());
}

// Slab test: the entry distance of the ray into box `index`, if it lies in (t_min, t_max).
bool World::hit_box(int index, const Vec3& o, const Vec3& inv, double t_min, double t_max,
                    double* t, int* axis) const {
  const Box& b = boxes_[static_cast<size_t>(index)];
  double enter = -kInf;
  double leave = kInf;
  int enter_axis = -1;
  for (int a = 0; a < 3; ++a) {
    const double oa = axis_of(o, a);
    const double ia = axis_of(inv, a);
    const double lo = axis_of(b.lo, a);
    const double hi = axis_of(b.hi, a);
    if (std::isinf(ia)) {  // parallel to this slab
      if (oa < lo || oa > hi) return false;
      continue;
    }
    double t0 = (lo - oa) * ia;
    double t1 = (hi - oa) * ia;
    if (t0 > t1) std::swap(t0, t1);
    if (t0 > enter) {
      enter = t0;
      enter_axis = a;
    }
    leave = std::min(leave, t1);
    if (enter > leave) return false;
  }
  if (enter_axis < 0 || enter <= t_min || enter >= t_max) return false;
  *t = enter;
  *axis = enter_axis;
  return true;
}

bool World::cast(const Vec3& o, const Vec3& d, double t_max, Hit* hit) const {
  double best = t_max;
  Hit::Plane plane = Hit::Plane::kNone;
  if (d.z < 0.0) {
    const double t = -o.z / d.z;
    if (t > kTMin && t < best) {
      best = t;
      plane = Hit::Plane::kFloor;
    }
  } else if (d.z > 0.0) {
    const double t = (ceiling_ - o.z) / d.z;
    if (t > kTMin && t < best) {
      best = t;
      plane = Hit::Plane::kCeiling;
    }
  }
  const Vec3 inv{d.x != 0.0 ? 1.0 / d.x : kInf, d.y != 0.0 ? 1.0 / d.y : kInf,
                 d.z != 0.0 ? 1.0 / d.z : kInf};
  int best_box = -1;
  int best_axis = 0;

  // 2-D DDA over the grid from the ray's entry into the grid's rectangle.
  double t_enter = 0.0;
  double t_exit = best;
  const double bx[2] = {min_x_, min_x_ + nx_ * cell_};
  const double by[2] = {min_y_, min_y_ + ny_ * cell_};
  if (d.x != 0.0) {
    double t0 = (bx[0] - o.x) * inv.x;
    double t1 = (bx[1] - o.x) * inv.x;
    if (t0 > t1) std::swap(t0, t1);
    t_enter = std::max(t_enter, t0);
    t_exit = std::min(t_exit, t1);
  } else if (o.x < bx[0] || o.x >= bx[1]) {
    t_exit = -1.0;
  }
  if (d.y != 0.0) {
    double t0 = (by[0] - o.y) * inv.y;
    double t1 = (by[1] - o.y) * inv.y;
    if (t0 > t1) std::swap(t0, t1);
    t_enter = std::max(t_enter, t0);
    t_exit = std::min(t_exit, t1);
  } else if (o.y < by[0] || o.y >= by[1]) {
    t_exit = -1.0;
  }
  if (t_enter < t_exit && nx_ > 0) {
    const double px = o.x + d.x * t_enter;
    const double py = o.y + d.y * t_enter;
    int ix = std::clamp(static_cast<int>(std::floor((px - min_x_) / cell_)), 0, nx_ - 1);
    int iy = std::clamp(static_cast<int>(std::floor((py - min_y_) / cell_)), 0, ny_ - 1);
    const int step_x = d.x > 0.0 ? 1 : -1;
    const int step_y = d.y > 0.0 ? 1 : -1;
    double next_x = kInf;
    double next_y = kInf;
    double delta_x = kInf;
    double delta_y = kInf;
    if (d.x != 0.0) {
      const double edge = min_x_ + (ix + (step_x > 0 ? 1 : 0)) * cell_;
      next_x = (edge - o.x) * inv.x;
      delta_x = cell_ * std::fabs(inv.x);
    }
    if (d.y != 0.0) {
      const double edge = min_y_ + (iy + (step_y > 0 ? 1 : 0)) * cell_;
      next_y = (edge - o.y) * inv.y;
      delta_y = cell_ * std::fabs(inv.y);
    }
    double cell_enter = t_enter;
    for (;;) {
      if (cell_enter > best) break;
      const size_t c = raster_index(ix, iy, nx_);
      for (uint32_t k = cell_start_[c]; k < cell_start_[c + 1]; ++k) {
        double t = 0.0;
        int axis = 0;
        if (hit_box(static_cast<int>(cell_boxes_[k]), o, inv, kTMin, best, &t, &axis)) {
          best = t;
          best_box = static_cast<int>(cell_boxes_[k]);
          best_axis = axis;
        }
      }
      const double cell_leave = std::min(next_x, next_y);
      if (best <= cell_leave || cell_leave >= t_exit) break;
      if (next_x < next_y) {
        ix += step_x;
        if (ix < 0 || ix >= nx_) break;
        cell_enter = next_x;
        next_x += delta_x;
      } else {
        iy += step_y;
        if (iy < 0 || iy >= ny_) break;
        cell_enter = next_y;
        next_y += delta_y;
      }
    }
  }
  if (best_box < 0 && plane == Hit::Plane::kNone) return false;
  hit->t = best;
  hit->point = o + d * best;
  hit->box = best_box;
  if (best_box >= 0) {
    hit->plane = Hit::Plane::kNone;
    Vec3 n;
    const double s = axis_of(d, best_axis) > 0.0 ? -1.0 : 1.0;
    if (best_axis == 0) n.x = s;
    if (best_axis == 1) n.y = s;
    if (best_axis == 2) n.z = s;
    hit->normal = n;
  } else {
    hit->plane = plane;
    hit->normal = Vec3{0.0, 0.0, plane == Hit::Plane::kFloor ? 1.0 : -1.0};
  }
  return true;
}

bool World::sky_visible(const Vec3& origin, const Vec3& dir) const {
  Hit h;
  if (!cast(origin, dir, 1e3, &h)) return true;
  return h.box >= 0 && boxes_[static_cast<size_t>(h.box)].surface == Surface::kWindow;
}

}  // namespace seqslam::sim
