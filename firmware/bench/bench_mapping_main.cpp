// Mapping benchmark firmware (seqslam_bench_mapping, issue 7): retired instructions of the
// mapping kernels on the RV32IMC board: the occupancy grid (rays, snapshots, tile paging), the
// pose graph (bench_pose_graph.cpp: optimiser slices on a test loop), the mapping step per
// place as it ships (bench_pose_graph.cpp: the core's Explorer with the library and the map on
// an SD card, bench_card.h: instructions, card bytes and requests, time at 72 MHz with the
// card) and a loop closure's alignment along the matched pass (align_closure).
// The localisation figures are in the other image, seqslam_bench (bench_main.cpp); the two
// did not fit the 65 456-byte RAM together.
//
// Everything large (grid tiles and stores, the pose graph's storage, the place library the
// closure alignment reads, the mapping step's card) lives in the board's external memory
// region; code, data and stack are in the RAM. Instruction counts come from minstret under
// QEMU with -icount shift=0: deterministic.
//
// Output: human-readable lines, then a JSON summary between BEGIN_SUMMARY_JSON and
// END_SUMMARY_JSON that scripts/run-bench.sh writes to build/bench/mapping/summary.json.
#include "bench_pose_graph.h"
#include "bench_report.h"
#include "scene.h"
#include "seqslam/board/board.h"
#include "seqslam/seqslam.h"

namespace {

using namespace seqslam;
using bench::now;
using bench::print;
using bench::print_u;
using firmware::render_scene;

// The occupancy grid at 5 cm cells. The grid's tile slots and the tile store live in external
// memory here (on the board the slots would be RAM: 6 x 1036 bytes), so the image's RAM
// report stays that of the code and the harness.
struct GridFigures {
  uint64_t ray_mean;  // one 1.5 m ray with a hit, its tiles resident, mean over 36 directions
  uint64_t ray_max;
  uint64_t ray_cells;    // cells per ray (mean)
  uint64_t geometry;     // of which sensor_ray (mean)
  uint64_t walk;         // of which insert_ray (mean)
  uint64_t short_ray;    // insert_ray of a 0.2 m ray (mean): the fixed part
  uint64_t short_cells;  // its cells
  uint64_t scan_mean;    // one six-sensor snapshot (insert_scan: 4 echoes, 2 no-echo rays)
  uint64_t miss_ray;     // a 1.5 m ray whose tile is not resident: save a dirty tile, load one
};

constexpr uint32_t kBenchStoreTiles = 40;
SEQSLAM_BOARD_EXTMEM int8_t g_store_cells[kBenchStoreTiles][kGridTileCells];
SEQSLAM_BOARD_EXTMEM OccupancyGridStorage<9> g_grid_ram9;
SEQSLAM_BOARD_EXTMEM OccupancyGridStorage<1> g_grid_ram1;

// Tiles in external memory, looked up linearly (the copy is what a card would cost in DMA).
class BenchTileStore final : public TileStore {
 public:
  GridTile keys[kBenchStoreTiles];
  uint32_t used = 0;

 private:
  int32_t find(GridTile t) const {
    for (uint32_t i = 0; i < used; ++i) {
      if (keys[i].x == t.x && keys[i].y == t.y) return static_cast<int32_t>(i);
    }
    return -1;
  }
  Status do_load(GridTile tile, Span<int8_t> cells) override {
    const int32_t i = find(tile);
    if (i < 0) return Status::kNotFound;
    for (uint32_t k = 0; k < kGridTileCells; ++k)
      cells[k] = g_store_cells[i][k];
    return Status::kOk;
  }
  Status do_save(GridTile tile, Span<const int8_t> cells) override {
    int32_t i = find(tile);
    if (i < 0) {
      if (used == kBenchStoreTiles) return Status::kResourceExhausted;
      i = static_cast<int32_t>(used++);
      keys[i] = tile;
    }
    for (uint32_t k = 0; k < kGridTileCells; ++k)
      g_store_cells[i][k] = cells[k];
    return Status::kOk;
  }
  Status do_clear() override {
    used = 0;
    return Status::kOk;
  }
};

// In external memory since issue 35 (the pose graph's code took its RAM; docs/performance.md).
SEQSLAM_BOARD_EXTDATA BenchTileStore g_tile_store;

// Positions and angles as compile-time constants or integer steps: the run-time from_ratio and
// from_turn_ratio (128-bit division) would cost the image 2 KB of code.
constexpr Q31_32 kCentreM = Q31_32::from_ratio(8050, 1000);
constexpr Q31_32 kTileOneM = Q31_32::from_ratio(1650, 1000);
constexpr Q31_32 kTileTwoM = Q31_32::from_ratio(3250, 1000);
constexpr uint32_t kBamPerDegree = 11930465;  // 2^32 / 360, rounded down
Angle degrees(uint32_t d) {
  return Angle{d * kBamPerDegree};
}

bool run_grid(GridFigures* f) {
  GridConfig config;   // 5 cm cells, default log-odds
  config.width = 320;  // 16 m x 16 m
  config.height = 320;
  OccupancyGrid grid;
  if (grid.configure(config, g_grid_ram9.buffers(), g_tile_store) != Status::kOk) return false;
  // 36 rays of 1.5 m from (8.05, 8.05) m, every 10 degrees; once to page the 9 tiles in.
  Pose2 centre{kCentreM, kCentreM, Angle{}};
  RangeSensor sensor;  // at the centre, 0.2..1.5 m
  sensor.x = Q31_32::from_raw(0);
  sensor.y = Q31_32::from_raw(0);
  for (int32_t k = 0; k < 36; ++k) {
    sensor.angle = degrees(static_cast<uint32_t>(10 * k));
    if (grid.insert_reading(centre, sensor, 1500) != Status::kOk) return false;
  }
  const uint32_t loads = grid.stats().tile_loads;
  const uint32_t cells = grid.stats().cells;
  f->ray_mean = 0;
  f->ray_max = 0;
  for (int32_t k = 0; k < 36; ++k) {
    sensor.angle = degrees(static_cast<uint32_t>(10 * k + 5));
    const uint64_t t0 = now();
    if (grid.insert_reading(centre, sensor, 1500) != Status::kOk) return false;
    const uint64_t t = now() - t0;
    f->ray_mean += t;
    f->ray_max = t > f->ray_max ? t : f->ray_max;
  }
  f->ray_mean /= 36;
  f->ray_cells = (grid.stats().cells - cells) / 36;
  // The split: sensor_ray (pose and mounting to metres: two sincos, Q31.32 products) and
  // insert_ray (metres to cells, the tile list, the walk and the cell updates).
  f->geometry = 0;
  f->walk = 0;
  for (int32_t k = 0; k < 36; ++k) {
    sensor.angle = degrees(static_cast<uint32_t>(10 * k + 5));
    SensorRay ray;
    uint64_t t0 = now();
    if (sensor_ray(centre, sensor, 1500, &ray) != Status::kOk) return false;
    f->geometry += now() - t0;
    t0 = now();
    if (grid.insert_ray(ray) != Status::kOk) return false;
    f->walk += now() - t0;
  }
  f->geometry /= 36;
  f->walk /= 36;
  // Cost per cell: the same directions at 0.2 m (the sensors' minimum range) against 1.5 m.
  uint64_t short_total = 0;
  const uint32_t short_cells = grid.stats().cells;
  for (int32_t k = 0; k < 36; ++k) {
    sensor.angle = degrees(static_cast<uint32_t>(10 * k + 5));
    SensorRay ray;
    if (sensor_ray(centre, sensor, 200, &ray) != Status::kOk) return false;
    const uint64_t t0 = now();
    if (grid.insert_ray(ray) != Status::kOk) return false;
    short_total += now() - t0;
  }
  const uint64_t short_cells_mean = (grid.stats().cells - short_cells) / 36;
  f->short_ray = short_total / 36;
  f->short_cells = short_cells_mean;
  if (grid.stats().tile_loads != loads) return false;  // all resident, as intended
  // Six-sensor snapshots at 16 headings.
  const uint16_t readings[kMyonInfraredCount] = {900, 1200, 0, 700, 650, 0};
  f->scan_mean = 0;
  for (int32_t k = 0; k < 16; ++k) {
    centre.heading = degrees(static_cast<uint32_t>(22 * k + 3));
    const uint64_t t0 = now();
    if (grid.insert_scan(centre, Span<const RangeSensor>(kMyonInfrared),
                         Span<const uint16_t>(readings)) != Status::kOk) {
      return false;
    }
    f->scan_mean += now() - t0;
  }
  f->scan_mean /= 16;
  // One slot, rays alternating between two tiles: every ray saves the dirty tile and loads.
  OccupancyGrid small;
  if (small.configure(config, g_grid_ram1.buffers(), g_tile_store) != Status::kOk) return false;
  sensor.angle = Angle{};
  uint64_t total = 0;
  for (int32_t k = 0; k < 8; ++k) {
    const Pose2 p{k % 2 == 0 ? kTileOneM : kTileTwoM, kTileOneM,
                  Angle{}};  // tiles (1, 1) and (2, 1)
    const uint64_t t0 = now();
    if (small.insert_reading(p, sensor, 1400) != Status::kOk) return false;
    if (k >= 2) total += now() - t0;
  }
  f->miss_ray = total / 6;
  return small.stats().tile_saves >= 6;
}

// A loop closure's alignment along the matched pass, as the explore mode runs it (L = 15,
// +-5 places, +-2 columns), on a library of 450 places taught like the localisation image's
// M = 450 library (bench_main.cpp, run(): the same corridor, HE; here added to the library
// directly, without a Localiser). Its cost does not depend on the images' content beyond the
// shift-tolerant SAD's branches.
constexpr uint32_t kAlignPlaces = 450;
const ImageSize kSize{32, 16};
constexpr uint32_t kPixels = 512;

SEQSLAM_BOARD_EXTMEM PlaceLibraryStorage<kAlignPlaces, kPixels> g_library_storage;
SEQSLAM_BOARD_EXTMEM uint8_t g_align_scratch[kPixels];  // align_closure's copy of an image
PlaceLibrary g_library;

// The current place 449 against place 300, places below 400 known: every candidate qualifies.
bool run_align(uint64_t* instructions) {
  if (g_library_storage.attach(g_library, kSize) != Status::kOk) return false;
  uint8_t raw[kPixels];
  uint8_t image[kPixels];
  const PreprocessConfig pre;  // HE, the localiser's default
  for (uint32_t p = 0; p < kAlignPlaces; ++p) {
    render_scene(p * 2, kSize, 256, 0, 11, raw);
    if (preprocess(pre, ImageView{raw, kSize}, MutableImageView{image, kSize}) != Status::kOk ||
        g_library.add(ImageView{image, kSize}, Pose2{}, p) != Status::kOk) {
      return false;
    }
  }
  ClosureAlignment al;
  const uint64_t t0 = now();
  if (align_closure(g_library, 449, 300, 400, ClosureAlignConfig{15, 5, 2},
                    Span<uint8_t>(g_align_scratch), &al) != Status::kOk) {
    return false;
  }
  *instructions = now() - t0;
  return al.candidates == 11 && al.compared == 15;
}

}  // namespace

int main() {
  print("seqslam benchmark, mapping image (seqslam_bench_mapping): occupancy grid, pose graph,\n");
  print("mapping step, closure alignment (RV32IMC under QEMU, -icount); grid tiles, graph,\n");
  print("place library and SD card in EXTERNAL memory, code, data and stack in the 65456-byte\n");
  print("RAM\n\n");
  GridFigures grid{};
  if (!run_grid(&grid)) {
    print("benchmark setup (occupancy grid) failed\n");
    return 1;
  }
  print("occupancy grid 5 cm: a 1.5 m ray (");
  print_u(grid.ray_cells);
  print(" cells, tiles resident) ");
  print_u(grid.ray_mean);
  print(" instructions (max ");
  print_u(grid.ray_max);
  print(": sensor_ray ");
  print_u(grid.geometry);
  print(" + insert_ray ");
  print_u(grid.walk);
  print("; a 0.2 m ray (");
  print_u(grid.short_cells);
  print(" cells) insert_ray ");
  print_u(grid.short_ray);
  print("), a six-sensor snapshot ");
  print_u(grid.scan_mean);
  print(", a ray with a tile miss (save + load from a RAM store) ");
  print_u(grid.miss_ray);
  print("\n");
  bench::PoseGraphFigures pose_graph{};
  if (!bench::run_pose_graph(64, &pose_graph)) {
    print("benchmark setup (pose graph) failed\n");
    return 1;
  }
  bench::print_pose_graph(pose_graph);
  bench::MappingStepFigures mapping{};
  if (!bench::run_mapping_step(&mapping)) {
    print("benchmark setup (mapping step) failed\n");
    return 1;
  }
  bench::print_mapping_step(mapping);
  uint64_t align = 0;
  if (!run_align(&align)) {
    print("benchmark setup (closure alignment) failed\n");
    return 1;
  }
  print("closure alignment (L=15, +-5 places, +-2 columns, 165 shift-tolerant SADs, 450-place ");
  print("library): ");
  print_u(align);
  print(" instructions\n");
  const bench::MemoryReport mem = bench::memory_report();
  bench::print_memory(mem);
  print(" (mapping step's SD card ");
  print_u(bench::mapping_card_bytes());
  print(", place library ");
  print_u(decltype(g_library_storage)::kBytes);
  print("; the rest: grid tiles and stores, pose graph)\n");

  bench::print_json_begin();
  bench::print_json_config_end();
  print(",\n  \"occupancy_grid\": {\"cell_mm\": 50, \"ray_m\": 1.5, \"ray_cells\": ");
  print_u(grid.ray_cells);
  print(", \"ray_instructions\": ");
  print_u(grid.ray_mean);
  print(", \"ray_instructions_max\": ");
  print_u(grid.ray_max);
  print(", \"sensor_ray_instructions\": ");
  print_u(grid.geometry);
  print(", \"insert_ray_instructions\": ");
  print_u(grid.walk);
  print(", \"short_ray_cells\": ");
  print_u(grid.short_cells);
  print(", \"short_insert_ray_instructions\": ");
  print_u(grid.short_ray);
  print(", \"snapshot_instructions\": ");
  print_u(grid.scan_mean);
  print(", \"tile_miss_ray_instructions\": ");
  print_u(grid.miss_ray);
  print(", \"grid_object_bytes\": ");
  print_u(sizeof(OccupancyGrid));
  print(", \"slot_bytes\": ");
  print_u(kGridTileCells + sizeof(GridSlot));
  print("},\n  \"pose_graph\": ");
  bench::print_pose_graph_json(pose_graph);
  print("},\n  \"mapping_step\": ");
  bench::print_mapping_step_json(mapping);
  print("},\n  \"closure_align\": {\"length\": 15, \"max_offset\": 5, \"max_shift\": 2, ");
  print("\"instructions\": ");
  print_u(align);
  print("},\n  ");
  bench::print_memory_json(
      mem,
      "the mapping step's SD card, grid tiles and stores, pose graph and place library model "
      "external storage");
  bench::print_json_end();
  return 0;
}
