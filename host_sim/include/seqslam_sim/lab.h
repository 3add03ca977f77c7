// The simulated lab: a floor plan after the 2025 thesis's section 3 (the neurorobotics lab):
// a 46 m x 14 m hall with windows along the north and south walls, white walls, rows of
// identical workstations (white desk, black chair, black monitor) along both window walls,
// a central block of offices around which the route loops, split by a cross corridor, and two
// side rooms behind the east wall that the route normally never enters (novelty). Rare
// distinctive objects - a red fire extinguisher, blue cabinets, posters, a kitchenette, a
// printer - break the repetition only here and there.
//
// build_lab() makes the static lab plus what differs between runs (people standing about,
// chairs pushed elsewhere, monitors on or off), drawn from `run_seed`; the same seed gives
// the same lab. docs/simulator.md has the plan with coordinates.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "seqslam_sim/world.h"

namespace seqslam::sim {

struct Point2 {
  double x = 0.0;
  double y = 0.0;
};

struct LabOptions {
  bool people = true;        // people standing in the room (not on the route's centre line)
  bool move_chairs = true;   // chairs displaced by up to +-25 cm per run
  bool screens_vary = true;  // monitors switched on at random per run
};

// Builds the lab; `run_seed` draws the per-run differences.
World build_lab(uint64_t run_seed, const LabOptions& options = {});

// Landmarks of the floor plan used by the routes (metres).
namespace lab {
inline constexpr double kHallLength = 46.0;
inline constexpr double kHallWidth = 14.0;
inline constexpr double kSouthLane = 3.2;   // the route's centre line along the south side
inline constexpr double kNorthLane = 10.8;  // ... along the north side
inline constexpr double kWestLane = 4.5;
inline constexpr double kEastLane = 42.5;
inline constexpr double kCrossCorridor = 23.5;  // x of the corridor through the central block
}  // namespace lab

}  // namespace seqslam::sim
