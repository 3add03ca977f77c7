// The occupancy grid's tile store in the PC's memory (the robot pages tiles to its card's `map`
// file, storage/map_store.h): every tile kept, none ever lost. For the host tools and tests;
// counts its calls so a test can see the paging.
#pragma once

#include <stdint.h>

#include <algorithm>
#include <map>
#include <vector>

#include "seqslam/occupancy_grid.h"

namespace seqslam::tools {

class RamTileStore final : public TileStore {
 public:
  size_t tile_count() const { return tiles_.size(); }
  uint32_t loads = 0;
  uint32_t saves = 0;
  uint32_t clears = 0;

 private:
  Status do_load(GridTile tile, Span<int8_t> cells) override {
    ++loads;
    const auto it = tiles_.find(key(tile));
    if (it == tiles_.end()) return Status::kNotFound;
    if (cells.size() < it->second.size()) return Status::kInvalidArgument;
    std::copy(it->second.begin(), it->second.end(), cells.data());
    return Status::kOk;
  }
  Status do_save(GridTile tile, Span<const int8_t> cells) override {
    ++saves;
    tiles_[key(tile)].assign(cells.data(), cells.data() + cells.size());
    return Status::kOk;
  }
  Status do_clear() override {
    ++clears;
    tiles_.clear();
    return Status::kOk;
  }
  static uint32_t key(GridTile t) { return static_cast<uint32_t>(t.x) << 16 | t.y; }
  std::map<uint32_t, std::vector<int8_t>> tiles_;
};

}  // namespace seqslam::tools
