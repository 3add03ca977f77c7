// libFuzzer target: arbitrary bytes as an explore run's map (tile log) and pose-graph file
// (storage/map_store.h; the first byte says where the split is). Loading must end with a
// status in bounded calls, never crash or read out of bounds (ASan/UBSan), and what it
// accepts must be consistent: a reopened map's tiles load or fail with a status; a graph
// that reads to finish() has exactly the counts its header states. The container's damage
// properties (nothing misread, every loss reported) are fuzz_record_log's.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "seqslam/hal/fake_block_device.h"
#include "seqslam/storage/map_store.h"

namespace {

std::vector<uint8_t> as_card(const uint8_t* data, size_t size) {
  std::vector<uint8_t> card((size / seqslam::hal::kBlockSize + 4) * seqslam::hal::kBlockSize, 0);
  for (size_t i = 0; i < size; ++i)
    card[i] = data[i];
  return card;
}

[[noreturn]] void violated(const char* what, uint32_t a, uint32_t b) {
  std::fprintf(stderr, "map/graph property violated: %s (%u, %u)\n", what, a, b);
  std::abort();
}

void fuzz_map(std::vector<uint8_t>& bytes) {
  using namespace seqslam;
  hal::FakeBlockDevice device(Span<uint8_t>(bytes.data(), bytes.size()));
  static storage::MapTileIndexEntry index[64];
  static std::vector<uint8_t> buffer(storage::kMapReadBuffer);
  storage::MapStore store;
  GridConfig grid;
  if (store.open(device, Span<storage::MapTileIndexEntry>(index, 64),
                 Span<uint8_t>(buffer.data(), buffer.size()), &grid) != Status::kOk) {
    return;
  }
  if (store.tile_count() > 64) violated("more tiles than the index holds", store.tile_count(), 64);
  static int8_t cells[kGridTileCells];
  for (uint32_t i = 0; i < store.tile_count(); ++i) {
    const storage::MapTileIndexEntry& e = store.entry(i);
    (void)store.load(GridTile{e.x, e.y}, Span<int8_t>(cells, kGridTileCells));
  }
}

void fuzz_graph(std::vector<uint8_t>& bytes) {
  using namespace seqslam;
  hal::FakeBlockDevice device(Span<uint8_t>(bytes.data(), bytes.size()));
  storage::GraphReader reader;
  if (reader.open(device) != Status::kOk) return;
  const storage::GraphFileHeader h = reader.header();
  uint32_t nodes = 0, edges = 0, closures = 0;
  for (uint32_t i = 0; i < h.nodes; ++i) {
    storage::GraphFileNode n;
    if (reader.next_node(&n) != Status::kOk) return;
    if (n.index != i) violated("a node out of order", n.index, i);
    ++nodes;
  }
  for (uint32_t i = 0; i < h.edges; ++i) {
    PoseGraphEdge e;
    bool closure = false;
    if (reader.next_edge(&e, &closure) != Status::kOk) return;
    ++edges;
    closures += closure ? 1u : 0u;
  }
  if (reader.finish() == Status::kOk &&
      (nodes != h.nodes || edges != h.edges || closures != h.closures)) {
    violated("a graph accepted with counts other than its header's", nodes, edges);
  }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  if (size < 1) return 0;
  const size_t split = 1 + (static_cast<size_t>(data[0]) * (size - 1)) / 255u;
  std::vector<uint8_t> map = as_card(data + 1, split - 1);
  std::vector<uint8_t> graph = as_card(data + split, size - split);
  fuzz_map(map);
  fuzz_graph(graph);
  return 0;
}
