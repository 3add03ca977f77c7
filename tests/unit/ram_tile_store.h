// The occupancy grid's tile store for the core's tests (host and target: no heap, no libc):
// up to kCapacity tiles in RAM, every call counted, a chosen load or save made to fail like a
// card. The host tools' store (tools/common ram_tile_store.h) keeps any number of tiles.
#pragma once

#include <stdint.h>

#include "seqslam/occupancy_grid.h"

namespace seqslam::test {

template <uint32_t kCapacity>
class RamTileStore final : public TileStore {
 public:
  GridTile keys[kCapacity];
  int8_t data[kCapacity][kGridTileCells];
  uint32_t used = 0;
  uint32_t loads = 0;
  uint32_t saves = 0;
  uint32_t clears = 0;
  uint32_t fail_load_at = 0xFFFFFFFFu;  // call number of load / save that fails
  uint32_t fail_save_at = 0xFFFFFFFFu;
  bool fail_clear = false;

  void reset() {
    used = loads = saves = clears = 0;
    fail_load_at = fail_save_at = 0xFFFFFFFFu;
    fail_clear = false;
  }
  int32_t find(GridTile t) const {
    for (uint32_t i = 0; i < used; ++i) {
      if (keys[i].x == t.x && keys[i].y == t.y) return static_cast<int32_t>(i);
    }
    return -1;
  }

 private:
  Status do_load(GridTile tile, Span<int8_t> cells) override {
    if (loads++ == fail_load_at) return Status::kUnavailable;
    const int32_t i = find(tile);
    if (i < 0) return Status::kNotFound;
    for (uint32_t k = 0; k < kGridTileCells; ++k)
      cells[k] = data[i][k];
    return Status::kOk;
  }
  Status do_save(GridTile tile, Span<const int8_t> cells) override {
    if (saves++ == fail_save_at) return Status::kDataLoss;
    int32_t i = find(tile);
    if (i < 0) {
      if (used == kCapacity) return Status::kResourceExhausted;
      i = static_cast<int32_t>(used++);
      keys[i] = tile;
    }
    for (uint32_t k = 0; k < kGridTileCells; ++k)
      data[i][k] = cells[k];
    return Status::kOk;
  }
  Status do_clear() override {
    if (fail_clear) return Status::kUnavailable;
    ++clears;
    used = 0;
    return Status::kOk;
  }
};

}  // namespace seqslam::test
