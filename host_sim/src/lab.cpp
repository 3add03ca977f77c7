#include "seqslam_sim/lab.h"

#include <cmath>

#include "seqslam_sim/rng.h"

namespace seqslam::sim {

namespace {

constexpr double kWallHeight = 3.0;
constexpr double kWall = 0.2;  // wall thickness
constexpr double kSill = 0.9;
constexpr double kLintel = 2.6;

using P = Texture::Pattern;

Texture plain(double albedo) {
  return Texture{P::kPlain, albedo, 0.0, 1.0, 0};
}
Texture noisy(double albedo, double contrast, double scale, uint32_t seed) {
  return Texture{P::kNoise, albedo, contrast, scale, seed};
}
Texture blocks(double albedo, double contrast, double scale, uint32_t seed) {
  return Texture{P::kBlocks, albedo, contrast, scale, seed};
}
Texture stripes(double albedo, double contrast, double scale, uint32_t seed) {
  return Texture{P::kStripes, albedo, contrast, scale, seed};
}

const Texture kWhiteWall = noisy(0.80, 0.04, 0.7, 11);

class Builder {
 public:
  explicit Builder(World* w) : w_(w) {}

  void box(double x0, double y0, double z0, double x1, double y1, double z1, Texture t,
           Surface s = Surface::kMatte, bool solid_ir = true) {
    Box b;
    b.lo = Vec3{x0, y0, z0};
    b.hi = Vec3{x1, y1, z1};
    b.texture = t;
    b.surface = s;
    b.solid_ir = solid_ir;
    w_->add(b);
  }

  // A wall along x (from x0 to x1, occupying y0..y1) with window openings centred at `xs`.
  void window_wall_x(double x0, double x1, double y0, double y1, const std::vector<double>& xs,
                     double width, bool outside_south) {
    box(x0, y0, 0.0, x1, y1, kSill, kWhiteWall);
    box(x0, y0, kLintel, x1, y1, kWallHeight, kWhiteWall);
    double from = x0;
    for (double c : xs) {
      const double a = c - width / 2;
      const double b = c + width / 2;
      box(from, y0, kSill, a, y1, kLintel, kWhiteWall);
      // Glass in the outer half, a mullion and a frame inside the opening.
      const double gy0 = outside_south ? y0 : y1 - 0.05;
      const double gy1 = outside_south ? y0 + 0.05 : y1;
      box(a, gy0, kSill, b, gy1, kLintel, plain(0.0), Surface::kWindow, false);
      box(c - 0.03, y0 + 0.05, kSill, c + 0.03, y1 - 0.05, kLintel, plain(0.35));
      box(a, y0 + 0.05, kLintel - 0.06, b, y1 - 0.05, kLintel, plain(0.4));
      from = b;
    }
    box(from, y0, kSill, x1, y1, kLintel, kWhiteWall);
  }

  // A wall along y (x0..x1 thick) with door openings [ya, yb] up to 2.1 m.
  void wall_y(double x0, double x1, double y0, double y1,
              const std::vector<std::pair<double, double>>& doors) {
    double from = y0;
    for (const auto& d : doors) {
      box(x0, from, 0.0, x1, d.first, kWallHeight, kWhiteWall);
      box(x0, d.first, 2.1, x1, d.second, kWallHeight, kWhiteWall);
      from = d.second;
    }
    box(x0, from, 0.0, x1, y1, kWallHeight, kWhiteWall);
  }

  // A workstation against a window wall: desk, legs, monitor(s) (screens towards the
  // room), keyboard, the chair in front, and what people leave on desks. `facing` = +1 when
  // the room is to the north of the desk. `fixed` draws the lab's own variety (the same in
  // every run); `run` draws what changes between runs.
  void workstation(double x, double wall_y, int facing, Rng& fixed, Rng& run, const LabOptions& o) {
    const auto span = [&](double a, double b, double* lo, double* hi) {
      *lo = std::min(wall_y + facing * a, wall_y + facing * b);
      *hi = std::max(wall_y + facing * a, wall_y + facing * b);
    };
    double ylo = 0, yhi = 0;
    span(0.15, 0.95, &ylo, &yhi);
    box(x, ylo, 0.72, x + 1.6, yhi, 0.75, noisy(0.82, 0.02, 0.5, 21));
    for (double lx : {x + 0.05, x + 1.5}) {
      for (double ly : {ylo + 0.05, yhi - 0.1})
        box(lx, ly, 0.0, lx + 0.05, ly + 0.05, 0.72, plain(0.55));
    }
    const int monitors = fixed.chance(0.3) ? 2 : 1;
    const double mw = fixed.chance(0.5) ? 0.55 : 0.62;
    for (int k = 0; k < monitors; ++k) {
      const double mx = x + (monitors == 1 ? 0.55 : 0.2 + k * 0.65);
      double a = 0, b = 0;
      span(0.35, 0.40, &a, &b);
      box(mx, a, 0.9, mx + mw, b, 1.25, plain(0.06));  // body
      span(0.25, 0.35, &a, &b);
      box(mx + mw / 2 - 0.05, a, 0.75, mx + mw / 2 + 0.05, b, 0.9, plain(0.1));  // stand
      Box screen;
      span(0.40, 0.41, &a, &b);
      screen.lo = Vec3{mx + 0.025, a, 0.92};
      screen.hi = Vec3{mx + mw - 0.025, b, 1.23};
      screen.texture = blocks(0.05, 0.6, 0.06, static_cast<uint32_t>(fixed.next()));
      screen.surface = Surface::kScreen;
      screen.on = o.screens_vary ? run.chance(0.4) : false;
      screen.solid_ir = false;
      w_->add(screen);
    }
    double a = 0, b = 0;
    span(0.6, 0.75, &a, &b);
    box(x + 0.6, a, 0.75, x + 1.05, b, 0.77, plain(0.15));  // keyboard
    // Things on the desk: the lab's own clutter, and a little that comes and goes.
    if (fixed.chance(0.5)) {  // a box, files or a printer-sized device
      const double bw = fixed.uniform(0.2, 0.5);
      const double bh = fixed.uniform(0.1, 0.45);
      const double bx = fixed.chance(0.5) ? x + 0.05 : x + 1.55 - bw;
      span(0.2, 0.2 + fixed.uniform(0.2, 0.4), &a, &b);
      box(bx, a, 0.75, bx + bw, b, 0.75 + bh,
          blocks(fixed.uniform(0.2, 0.8), 0.4, 0.1, static_cast<uint32_t>(fixed.next())));
    }
    if (fixed.chance(0.4)) {  // papers
      span(0.5, 0.8, &a, &b);
      box(x + 1.15, a, 0.75, x + 1.5, b, 0.76, plain(0.92));
    }
    if (fixed.chance(0.2)) {  // desk lamp
      span(0.2, 0.3, &a, &b);
      box(x + 1.4, a, 0.75, x + 1.45, b, 1.2, plain(0.3));
      box(x + 1.3, a, 1.15, x + 1.5, b + 0.05, 1.22, plain(0.85));
    }
    if (run.chance(0.3)) {  // a bag, a cup, a bottle: today only
      span(0.5, 0.7, &a, &b);
      const double cx = x + run.uniform(0.1, 1.3);
      box(cx, a, 0.75, cx + run.uniform(0.08, 0.3), b, 0.75 + run.uniform(0.1, 0.3),
          plain(run.uniform(0.1, 0.7)));
    }
    // Chair in front of the desk.
    double cx = x + 0.55;
    double cy = wall_y + facing * 1.25;
    if (o.move_chairs) {
      cx += run.uniform(-0.25, 0.25);
      cy += facing * run.uniform(-0.1, 0.35);
    }
    const double shade = fixed.chance(0.7) ? 0.08 : fixed.uniform(0.15, 0.4);
    const double cy0 = std::min(cy, cy + facing * 0.5);
    const double cy1 = std::max(cy, cy + facing * 0.5);
    box(cx, cy0, 0.42, cx + 0.5, cy1, 0.5, plain(shade));  // seat
    const double by = facing > 0 ? cy1 - 0.08 : cy0;       // back rest
    box(cx + 0.03, by, 0.5, cx + 0.47, by + 0.08, fixed.uniform(0.9, 1.15),
        noisy(shade, 0.3, 0.2, 5));
    box(cx + 0.22, (cy0 + cy1) / 2 - 0.03, 0.08, cx + 0.28, (cy0 + cy1) / 2 + 0.03, 0.42,
        plain(0.2));                                                            // post
    box(cx - 0.03, cy0 - 0.03, 0.03, cx + 0.53, cy1 + 0.03, 0.08, plain(0.1));  // base
  }

  // What stands in the gap between two groups of desks along a window wall.
  void gap_item(double x0, double x1, double wall_y, int facing, Rng& fixed) {
    const double w = x1 - x0;
    double a = 0, b = 0;
    const auto span = [&](double p, double q) {
      a = std::min(wall_y + facing * p, wall_y + facing * q);
      b = std::max(wall_y + facing * p, wall_y + facing * q);
    };
    switch (fixed.below(6)) {
      case 0:  // low cabinet with binders
        span(0.1, 0.55);
        box(x0 + 0.1, a, 0.0, x1 - 0.1, b, fixed.uniform(0.7, 1.2),
            stripes(0.5, 0.6, 0.07, static_cast<uint32_t>(fixed.next())));
        break;
      case 1:  // tall grey cabinet
        span(0.1, 0.55);
        box(x0 + 0.1, a, 0.0, std::min(x1 - 0.1, x0 + 1.0), b, 1.95, noisy(0.6, 0.05, 0.4, 41));
        break;
      case 2:  // plant
        span(0.2, 0.7);
        box(x0 + w / 2 - 0.25, a, 0.0, x0 + w / 2 + 0.25, b, fixed.uniform(0.9, 1.6),
            noisy(0.22, 0.5, 0.08, 42));
        break;
      case 3:  // coat stand with coats
        span(0.3, 0.6);
        box(x0 + w / 2 - 0.2, a, 0.8, x0 + w / 2 + 0.2, b, 1.75, noisy(0.15, 0.4, 0.1, 43));
        box(x0 + w / 2 - 0.03, a, 0.0, x0 + w / 2 + 0.03, b, 0.8, plain(0.2));
        break;
      case 4:  // stacked boxes
        span(0.1, 0.7);
        box(x0 + 0.2, a, 0.0, std::min(x1 - 0.1, x0 + 1.0), b, fixed.uniform(0.4, 1.0),
            blocks(0.6, 0.3, 0.3, static_cast<uint32_t>(fixed.next())));
        break;
      default:  // nothing
        break;
    }
  }

  // Tall cabinet against a wall face at y = wall_y, towards the room by `facing`.
  void cabinet(double x, double width, double wall_y, int facing, double height, Texture t) {
    const double y0 = wall_y;
    const double y1 = wall_y + facing * 0.45;
    box(x, std::min(y0, y1), 0.0, x + width, std::max(y0, y1), height, t);
    // Handles / door gap: a dark vertical line in the middle.
    const double fy = y1;
    box(x + width / 2 - 0.01, std::min(fy, fy + facing * 0.01), 0.1, x + width / 2 + 0.01,
        std::max(fy, fy + facing * 0.01), height - 0.1, plain(0.1));
  }

  // A flat item (poster, door, whiteboard, notice) on a wall face at y = wall_y.
  void on_wall_y(double x0, double x1, double z0, double z1, double wall_y, int facing, Texture t,
                 double depth = 0.02) {
    const double y1 = wall_y + facing * depth;
    box(x0, std::min(wall_y, y1), z0, x1, std::max(wall_y, y1), z1, t, Surface::kMatte,
        depth > 0.05);
  }
  void on_wall_x(double y0, double y1, double z0, double z1, double wall_x, int facing, Texture t,
                 double depth = 0.02) {
    const double x1 = wall_x + facing * depth;
    box(std::min(wall_x, x1), y0, z0, std::max(wall_x, x1), y1, z1, t, Surface::kMatte,
        depth > 0.05);
  }

  void door_y(double x, double wall_y, int facing) {
    on_wall_y(x - 0.06, x + 1.06, 0.0, 2.16, wall_y, facing, plain(0.5), 0.03);  // frame
    on_wall_y(x, x + 1.0, 0.0, 2.1, wall_y, facing, noisy(0.32, 0.08, 0.15, 7), 0.04);
    on_wall_y(x + 0.82, x + 0.95, 1.0, 1.05, wall_y, facing, plain(0.7), 0.09);  // handle
  }

  void lamp(double x, double y) {
    box(x - 0.6, y - 0.15, kWallHeight - 0.03, x + 0.6, y + 0.15, kWallHeight, plain(0.9),
        Surface::kLamp, false);
  }

 private:
  World* w_;
};

// The central block of offices and the cross corridor through it (x, y extents).
constexpr double cb0 = 9.0, cb1 = 38.0, cy0 = 5.8, cy1 = 8.2;
constexpr double cc0 = lab::kCrossCorridor - 1.0, cc1 = lab::kCrossCorridor + 1.0;
constexpr double L = lab::kHallLength;
constexpr double H = lab::kHallWidth;

// The hall's walls with windows north and south, radiators and skirting. Returns the
// windows' x.
std::vector<double> build_shell(Builder& b) {
  std::vector<double> windows;
  for (double x = 2.5; x < L - 1.0; x += 3.5)
    windows.push_back(x);
  b.window_wall_x(-kWall, L + kWall, -kWall, 0.0, windows, 2.0, true);
  b.window_wall_x(-kWall, L + kWall, H, H + kWall, windows, 2.0, false);
  b.wall_y(-kWall, 0.0, 0.0, H, {});
  b.wall_y(L, L + kWall, 0.0, H, {{2.6, 4.2}, {9.8, 11.4}});
  // Radiators under the windows (repetitive, slatted).
  for (double x : windows) {
    b.box(x - 0.8, 0.0, 0.15, x + 0.8, 0.1, 0.7, stripes(0.78, 0.15, 0.04, 3));
    b.box(x - 0.8, H - 0.1, 0.15, x + 0.8, H, 0.7, stripes(0.78, 0.15, 0.04, 3));
  }
  // Skirting boards along the long walls.
  b.box(0.0, 0.0, 0.0, L, 0.02, 0.08, plain(0.25));
  b.box(0.0, H - 0.02, 0.0, L, H, 0.08, plain(0.25));
  return windows;
}

// The block of offices: walls, doors, what hangs on them, cabinets and plants (fixed).
void build_central_block(Builder& b) {
  b.box(cb0, cy0, 0.0, cc0, cy1, kWallHeight, kWhiteWall);
  b.box(cc1, cy0, 0.0, cb1, cy1, kWallHeight, kWhiteWall);
  b.box(cb0, cy0 - 0.02, 0.0, cb1, cy0, 0.08, plain(0.25), Surface::kMatte, false);
  b.box(cb0, cy1, 0.0, cb1, cy1 + 0.02, 0.08, plain(0.25), Surface::kMatte, false);
  // Office doors along both faces, posters, notice boards, whiteboards.
  for (double x : {10.5, 14.0, 18.5, 26.0, 30.5, 35.0})
    b.door_y(x, cy0, -1);
  for (double x : {11.0, 16.5, 20.0, 27.5, 33.0})
    b.door_y(x, cy1, +1);
  b.on_wall_y(15.6, 16.6, 1.2, 1.9, cy0, -1, blocks(0.5, 0.8, 0.12, 101));  // poster
  b.on_wall_y(28.0, 29.6, 0.9, 2.0, cy0, -1, noisy(0.9, 0.05, 0.3, 102));   // whiteboard
  b.on_wall_y(28.0, 29.6, 0.85, 0.9, cy0, -1, plain(0.4), 0.08);            // its tray
  b.on_wall_y(13.0, 13.6, 1.3, 1.7, cy1, +1, blocks(0.6, 0.6, 0.08, 103));  // notice
  b.on_wall_y(24.8, 26.4, 1.1, 1.9, cy1, +1, blocks(0.45, 0.9, 0.2, 104));  // poster
  b.on_wall_y(35.5, 36.5, 1.2, 2.0, cy1, +1, blocks(0.55, 0.7, 0.1, 105));  // poster
  // Fire extinguisher (red: dark in grey) with its sign, by the cross corridor.
  b.box(cc1 + 0.4, cy0 - 0.16, 0.12, cc1 + 0.58, cy0, 0.72, noisy(0.2, 0.1, 0.05, 9));
  b.on_wall_y(cc1 + 0.35, cc1 + 0.63, 1.5, 1.78, cy0, -1, blocks(0.5, 0.8, 0.07, 106));
  // Blue cabinets (dark in grey) along the block: rare landmarks.
  b.cabinet(31.6, 2.0, cy0, -1, 1.95, noisy(0.18, 0.05, 0.4, 12));
  b.cabinet(36.5, 1.0, cy1, +1, 1.95, noisy(0.18, 0.05, 0.4, 12));
  b.cabinet(12.4, 1.0, cy0, -1, 1.1, stripes(0.5, 0.6, 0.07, 13));  // binders
  // Plants (dark, bushy).
  b.box(21.7, 5.2, 0.0, 22.2, 5.7, 1.3, noisy(0.22, 0.5, 0.08, 14));
  b.box(8.0, 8.4, 0.0, 8.5, 8.9, 1.4, noisy(0.22, 0.5, 0.08, 15));
}

// Workstations, blinds and the block's irregular notices: the lab's own variety, fixed by
// `layout` (what is on the desks differs between runs: `rng`).
void build_furnishings(Builder& b, const std::vector<double>& windows, Rng& layout, Rng& rng,
                       const LabOptions& o) {
  // Workstations along both window walls, in groups of two to five with different things
  // in the gaps (the lab's own variety, fixed by `layout`).
  for (int side = 0; side < 2; ++side) {
    const double wall_y = side == 0 ? 0.0 : H;
    const int facing = side == 0 ? +1 : -1;
    double x = 1.0 + layout.uniform(0.0, 0.8);
    while (x + 1.6 < L - 0.8) {
      const int group = 2 + static_cast<int>(layout.below(4));
      for (int k = 0; k < group && x + 1.6 < L - 0.8; ++k) {
        b.workstation(x, wall_y, facing, layout, rng, o);
        x += 1.8;
      }
      const double gap = layout.uniform(0.8, 2.8);
      b.gap_item(x, std::min(x + gap - 0.2, L - 0.5), wall_y, facing, layout);
      x += gap;
    }
  }
  // Blinds: some windows have theirs partly down (fixed), which also shades the sun.
  for (double wx : windows) {
    for (int side = 0; side < 2; ++side) {
      if (!layout.chance(0.3)) continue;
      const double bottom = layout.uniform(1.2, 2.3);
      const double y0 = side == 0 ? 0.0 : H - 0.04;
      b.box(wx - 1.0, y0, bottom, wx + 1.0, y0 + 0.04, kLintel, stripes(0.7, 0.1, 0.05, 44));
    }
  }
  // More on the central block's faces: notices and posters at irregular places, a
  // wood-panelled stretch, glazed office fronts (dark rooms behind).
  for (int face = 0; face < 2; ++face) {
    const double fy = face == 0 ? cy0 : cy1;
    const int facing = face == 0 ? -1 : +1;
    for (int k = 0; k < 5; ++k) {
      const double x = layout.uniform(cb0 + 0.5, cb1 - 1.5);
      if (x > cc0 - 1.5 && x < cc1 + 0.5) continue;
      const double width = layout.uniform(0.4, 1.2);
      const double z = layout.uniform(1.0, 1.5);
      b.on_wall_y(x, x + width, z, z + layout.uniform(0.3, 0.9), fy, facing,
                  blocks(layout.uniform(0.3, 0.7), 0.8, layout.uniform(0.05, 0.2),
                         static_cast<uint32_t>(layout.next())));
    }
  }
  b.on_wall_y(cb0 + 0.2, cb0 + 3.8, 0.0, 1.1, cy0, -1, stripes(0.42, 0.15, 0.12, 45), 0.015);
  b.on_wall_y(30.0, 33.5, 0.0, 1.1, cy1, +1, stripes(0.42, 0.15, 0.12, 46), 0.015);
  b.on_wall_y(17.0, 18.3, 0.9, 2.4, cy1, +1, noisy(0.15, 0.2, 0.3, 47), 0.01);  // glazed front
  b.on_wall_y(26.8, 28.1, 0.9, 2.4, cy0, -1, noisy(0.15, 0.2, 0.3, 48), 0.01);
}

// The hall's ends, the side rooms behind the east wall (novelty), and the ceiling lamps.
void build_ends_and_rooms(Builder& b, Rng& layout) {
  // West end: whiteboard on the west wall, kitchenette, meeting table.
  b.on_wall_x(4.0, 6.5, 0.9, 2.0, 0.0, +1, noisy(0.92, 0.04, 0.3, 107));
  b.box(0.0, 7.0, 0.0, 0.6, 9.5, 0.9, stripes(0.7, 0.2, 0.6, 16));     // counter
  b.box(0.0, 7.0, 1.5, 0.35, 9.5, 2.2, stripes(0.75, 0.15, 0.6, 17));  // wall cupboards
  b.box(0.1, 9.6, 0.0, 0.7, 10.2, 1.8, plain(0.85));                   // fridge
  b.box(2.0, 6.2, 0.72, 4.4, 7.4, 0.76, plain(0.6));                   // meeting table
  for (double lx : {2.1, 4.25}) {
    for (double ly : {6.3, 7.25})
      b.box(lx, ly, 0.0, lx + 0.05, ly + 0.05, 0.72, plain(0.3));
  }
  // East end: shelves with boxes, a printer.
  b.box(L - 0.45, 5.0, 0.0, L, 8.8, 2.0, blocks(0.55, 0.5, 0.3, 18));
  b.box(44.0, 7.6, 0.0, 44.7, 8.2, 1.05, noisy(0.62, 0.05, 0.2, 19));
  b.on_wall_x(0.8, 2.2, 1.0, 1.8, L, -1, blocks(0.5, 0.8, 0.15, 108));  // poster on east wall

  // Side rooms behind the east wall (novelty): a workshop and a store room.
  const double rx0 = L + kWall;
  const double rx1 = rx0 + 7.8;
  b.wall_y(rx1, rx1 + kWall, 0.0, H, {});
  b.box(rx0, 6.9, 0.0, rx1, 7.1, kWallHeight, kWhiteWall);
  std::vector<double> room_windows = {rx0 + 2.0, rx0 + 5.5};
  b.window_wall_x(rx0, rx1 + kWall, -kWall, 0.0, room_windows, 2.0, true);
  b.window_wall_x(rx0, rx1 + kWall, H, H + kWall, room_windows, 2.0, false);
  // Workshop: two long benches with equipment.
  for (double y : {1.0, 5.2}) {
    b.box(rx0 + 1.5, y, 0.85, rx0 + 6.5, y + 0.8, 0.9, plain(0.45));
    b.box(rx0 + 1.5, y, 0.0, rx0 + 6.5, y + 0.8, 0.2, plain(0.3));
    for (int k = 0; k < 5; ++k) {
      const double ex = rx0 + 1.7 + k * 0.95;
      const double h = 0.9 + layout.uniform(0.15, 0.45);
      b.box(ex, y + 0.15, 0.9, ex + 0.55, y + 0.6, h,
            blocks(0.4, 0.9, 0.1, static_cast<uint32_t>(200 + k)));
    }
  }
  b.on_wall_x(2.0, 5.0, 0.9, 2.2, rx1, -1, blocks(0.5, 0.9, 0.25, 109));  // tool wall
  // Store room: shelf rows.
  for (double y : {8.6, 10.4, 12.2}) {
    b.box(rx0 + 1.0, y, 0.0, rx0 + 6.0, y + 0.5, 2.2, blocks(0.45, 0.8, 0.25, 300));
  }

  // Ceiling lamps: rows along the lanes; the side rooms have their own.
  for (double x = 1.5; x < L; x += 2.4) {
    for (double y : {1.8, 4.2, 9.8, 12.2})
      b.lamp(x, y);
  }
  for (double x : {rx0 + 2.0, rx0 + 5.5}) {
    for (double y : {3.5, 10.5})
      b.lamp(x, y);
  }
}

// People (differ between runs): standing by the desks and in the open ends, never on the
// route's centre lines.
void add_people(Builder& b, Rng& rng) {
  const int n = 3 + static_cast<int>(rng.below(6));
  for (int i = 0; i < n; ++i) {
    double x = rng.uniform(1.0, L - 1.0);
    double y = 0.0;
    switch (rng.below(3)) {
      case 0:
        y = rng.uniform(1.4, 2.2);
        break;
      case 1:
        y = rng.uniform(11.8, 12.6);
        break;
      default:
        y = rng.uniform(4.6, 5.4);
        break;
    }
    const double shade = rng.uniform(0.1, 0.6);
    const double height = rng.uniform(1.6, 1.9);
    b.box(x, y, 0.0, x + 0.35, y + 0.25, 0.85, plain(rng.uniform(0.1, 0.4)));  // legs
    b.box(x - 0.05, y - 0.03, 0.85, x + 0.4, y + 0.28, height - 0.25,
          noisy(shade, 0.2, 0.1, static_cast<uint32_t>(400 + i)));
    b.box(x + 0.07, y + 0.02, height - 0.25, x + 0.28, y + 0.23, height, plain(0.45));  // head
  }
}

}  // namespace

World build_lab(uint64_t run_seed, const LabOptions& o) {
  World w(kWallHeight);
  Builder b(&w);
  Rng rng(run_seed);
  Rng layout(0x5EED1AB5ull);  // the fixed lab: the same for every run

  w.add_area(Area{0.0, 0.0, L, H});
  w.add_area(Area{L + kWall, 0.0, L + kWall + 7.8, 6.9});
  w.add_area(Area{L + kWall, 7.1, L + kWall + 7.8, H});
  const std::vector<double> windows = build_shell(b);
  build_central_block(b);
  build_furnishings(b, windows, layout, rng, o);
  build_ends_and_rooms(b, layout);
  if (o.people) add_people(b, rng);
  w.finalize(0.5);
  return w;
}

}  // namespace seqslam::sim
