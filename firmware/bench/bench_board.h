// The head board's localiser as it ships, per step (seqslam_bench, section "board"): the
// firmware application's route search and heuristic matcher with its capacities (app.h),
// the library and the query history on an SD card, one result record written per step as
// the application does. The card, its counting and its time: bench_card.h.
// docs/performance.md explains the figures.
#pragma once

#include <stdint.h>

#include "bench_card.h"

namespace seqslam::bench {

struct BoardFigures {
  uint32_t places = 0;
  uint64_t teach_instructions_per_place = 0;
  uint64_t load_instructions = 0;  // loading (checking) the library at start
  uint64_t load_ns = 0;
  StepStats tracking;  // localised steps (route search, window only)
  uint32_t tracking_correct = 0;
  StepStats relocalising;          // from a kidnap to the first correct fix (window + scan)
  uint32_t relocalised_after = 0;  // places from the kidnap to that fix (0: never)
  uint32_t scans = 0;              // scans completed meanwhile
  StepStats heuristic;             // the heuristic matcher, two sequences
  // The route search's work between places (its scan's share, in slices after snapshots as
  // the application streams it), over the tracking and relocalising steps:
  StepStats slices;                 // each slice (kScanSlicePlaces library places at most)
  StepStats place_total;            // a place's step and all its slices together
  uint64_t streamed = 0;            // library places the slices streamed
  uint64_t slice_ns = 0;            // ... in this time (the scan rate)
  uint32_t pieces_over_period = 0;  // steps or slices longer than a snapshot period (10 ms)
  uint32_t slices_over_period = 0;  // ... of them slices
  int32_t heuristic_place = -1;    // its last sequence's answer (sanity)
  uint32_t heuristic_truth = 0;
};

// Static RAM of the localiser as the application allocates it (independent of the library).
uint32_t board_localiser_ram_bytes();
// The largest library whose relocalisation scan finishes before the query history forgets
// its anchor: (history steps - scan length) x scan places a step, at the default settings.
uint32_t board_capacity_places();

// Teaches `places` places onto the card, loads them as the application does and measures.
bool run_board(uint32_t places, BoardFigures* out);

void print_board(const BoardFigures& f);
// One member of the summary's "board" array.
void print_board_json(const BoardFigures& f, bool last);

}  // namespace seqslam::bench
