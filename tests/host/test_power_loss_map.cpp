// Power cuts in the explore mode's two card files (issue 15: "a card failing during a tile or
// graph write loses nothing already saved"), swept like test_power_loss.cpp sweeps a
// recording: every card write of a run is journalled, and the power is cut after every write,
// in the middle of every write, on both sides of the byte that completes each record, and at
// every byte of the writes that start a log (commit slot, header) and of the last writes.
// After each cut the card is read back with the read-only loaders.
//
// `map` (MapStore): an OccupancyGrid with 3 RAM tiles scans its way round a 5 x 3 tile world
// (24 scans, 18 a loop), so tiles are paged out and saved again and again, then clear()s (a new log
// session, as the explore mode's rebuild does) and scans on, then flushes; an older map (another
// grid origin, other contents, more records) lies on the card behind every write. After a cut,
// MapStore::open must open the map with exactly the tiles of the last session whose header is
// on the card, each at the record of its latest save completed before the cut (contents
// compared through MapStore::load); nothing of another session and no record cut short may be
// visible. A cut inside a new header (only in this byte-level model: a card writes a sector
// whole) may instead leave a damaged header, which open() must refuse with a status. (This
// sweep found that open() refused the whole map when the cut interrupted a tile record.)
//
// `graph` (write_graph, GraphReader): a 30-node graph written over an older 40-node one. The
// file has two slots (map_store.h): the new graph goes into the slot the old one is not in,
// so after any cut the reader must return the complete old graph until the new one's last
// record is on the card, and the complete new one from then on: never a refusal, never a
// partial graph, never a mix. (Before the two slots, the rewrite in place left no readable
// graph for 1 232 of these cuts.)
//
// Figures (printed as "[ figure ]" lines): map 5 210 cuts over 455 writes (112 tile saves, 83
// of them of a tile saved before in the same session), graph 2 414 cuts over 128 writes (61
// records; 1 757 read the old graph, 657 the new); about 1.4 s in the host build.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include "journal_device.h"
#include "seqslam/hal/fake_block_device.h"
#include "seqslam/occupancy_grid.h"
#include "seqslam/pose_graph.h"
#include "seqslam/storage/map_store.h"

namespace seqslam::storage {
namespace {

using test::JournalDevice;

constexpr uint32_t kBlockBytes = hal::kBlockSize;
constexpr uint32_t kTileRecordBytes = kRecordOverhead + kMapTilePayload;  // 1048
constexpr uint32_t kGraphRecordBytes = kRecordOverhead + 28;              // node or edge

// Where a write lands completely: write `write` (journal index) with its first `bytes` bytes.
struct Point {
  size_t write = 0;
  uint32_t bytes = 0;
};
// Is `p` on the card after a cut at byte `cut` of write `w` (writes before w complete)?
bool landed(Point p, size_t w, uint32_t cut) {
  return p.write < w || (p.write == w && p.bytes <= cut);
}

// The cuts of a sweep for write w: 0 (after the previous write), 255 (torn in the middle),
// both sides of every record end that lands in this write, every byte when `every_byte`.
std::vector<uint32_t> cuts_for(size_t w, const std::vector<Point>& ends, bool every_byte) {
  std::vector<uint32_t> cuts;
  if (every_byte) {
    for (uint32_t c = 0; c < kBlockBytes; ++c)
      cuts.push_back(c);
    return cuts;
  }
  cuts = {0, 255};
  for (const Point& p : ends) {
    if (p.write != w) continue;
    cuts.push_back(p.bytes - 1);
    if (p.bytes < kBlockBytes) cuts.push_back(p.bytes);  // 512: the next write's cut 0
  }
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
  return cuts;
}

bool same_block0(const std::vector<uint8_t>& a, const std::vector<uint8_t>& b) {
  return std::equal(a.begin(), a.begin() + kBlockBytes, b.begin());
}

// ---------------------------------------------------------------------------------------
// Map

constexpr uint32_t kMapBlocks = 200;  // the older map's 90 records reach block 187
constexpr uint32_t kOldMapSaves = 90;
constexpr uint32_t kScansBeforeClear = 24;
constexpr uint32_t kScansAfterClear = 12;
constexpr uint32_t kIndexTiles = 32;

GridConfig map_grid(int32_t origin_mm) {
  GridConfig g;
  g.origin_x = Q31_32::from_ratio(origin_mm, 1000);
  g.origin_y = Q31_32::from_ratio(origin_mm, 1000);
  g.width = 160;  // 5 x 3 tiles of 32 cells (1.6 m)
  g.height = 96;
  return g;
}

struct Save {
  uint32_t session = 0;  // 0: the older map on the card; 1: the run's create(); 2: its clear()
  GridTile tile{};
  uint32_t offset = 0;  // where the record starts in the file
  std::vector<int8_t> cells;
  Point complete{};  // where the record's last byte lands
};

// The grid's store: MapStore on the journalled card, noting every completed save and every
// new session (the journal index of its header write).
class JournalledMap final : public TileStore {
 public:
  JournalledMap(MapStore& map, const JournalDevice& device) : map_(map), device_(device) {}
  std::vector<Save> saves;
  std::vector<size_t> headers;  // headers[k]: the header write of session k + 1

  void session_started() {
    ASSERT_EQ(device_.journal.back().block, 0u);  // create(): commit slot 1, then the header
    headers.push_back(device_.journal.size() - 1);
  }

 private:
  Status do_load(GridTile tile, Span<int8_t> cells) override { return map_.load(tile, cells); }
  Status do_save(GridTile tile, Span<const int8_t> cells) override {
    const Status s = map_.save(tile, cells);
    if (s != Status::kOk) return s;
    const uint32_t end = kFirstRecordOffset + map_.records_written() * kTileRecordBytes;
    // An append writes the record's blocks, then its commit slot (block 1 or 2).
    const size_t n = device_.journal.size();
    EXPECT_TRUE(device_.journal[n - 1].block == 1 || device_.journal[n - 1].block == 2);
    EXPECT_EQ(device_.journal[n - 2].block, (end - 1) / kBlockBytes);
    Save save;
    save.session = static_cast<uint32_t>(headers.size());
    save.tile = tile;
    save.offset = end - kTileRecordBytes;
    save.cells.assign(cells.data(), cells.data() + cells.size());
    save.complete = {n - 2, (end - 1) % kBlockBytes + 1};
    saves.push_back(std::move(save));
    return s;
  }
  Status do_clear() override {
    const Status s = map_.clear();
    if (s == Status::kOk) session_started();
    return s;
  }

  MapStore& map_;
  const JournalDevice& device_;
};

// The older map: every tile of the grid saved six times, with contents no run produces.
std::vector<Save> write_old_map(std::vector<uint8_t>& card) {
  hal::FakeBlockDevice device(Span<uint8_t>(card.data(), card.size()));
  MapTileIndexEntry index[kIndexTiles];
  MapStore map;
  EXPECT_EQ(map.create(device, map_grid(-700), Span<MapTileIndexEntry>(index)), Status::kOk);
  std::vector<Save> saves;
  for (uint32_t i = 0; i < kOldMapSaves; ++i) {
    Save save;
    save.tile = GridTile{static_cast<uint16_t>(i % 5), static_cast<uint16_t>(i / 5 % 3)};
    save.offset = kFirstRecordOffset + i * kTileRecordBytes;
    save.cells.resize(kGridTileCells);
    for (uint32_t c = 0; c < kGridTileCells; ++c)
      save.cells[c] = static_cast<int8_t>(static_cast<int32_t>((c * 13u + i * 71u) % 120u) - 60);
    EXPECT_EQ(map.save(save.tile, Span<const int8_t>(save.cells.data(), kGridTileCells)),
              Status::kOk);
    saves.push_back(std::move(save));
  }
  return saves;
}

// One scan of the six infrared sensors at step k of a loop round the world's centre.
void scan(OccupancyGrid& grid, uint32_t k) {
  const double a = 2.0 * M_PI * k / 18.0;  // 18 scans a loop
  const double x = 4.0 + 2.6 * std::cos(a);
  const double y = 2.4 + 1.3 * std::sin(a);
  const Pose2 pose{Q31_32::from_ratio(std::lround(x * 1000), 1000),
                   Q31_32::from_ratio(std::lround(y * 1000), 1000),
                   Angle::from_degrees(static_cast<int64_t>(k * 20 + 90))};
  uint16_t readings[kMyonInfraredCount];
  for (uint32_t i = 0; i < kMyonInfraredCount; ++i)  // 0 (no echo) or 0.3..1.47 m
    readings[i] = static_cast<uint16_t>((k + i) % 7 == 3 ? 0 : 300 + (k * 137 + i * 211) % 1170);
  ASSERT_EQ(grid.insert_scan(pose, Span<const RangeSensor>(kMyonInfrared, kMyonInfraredCount),
                             Span<const uint16_t>(readings, kMyonInfraredCount)),
            Status::kOk);
}

struct MapTally {
  uint32_t cuts = 0;
  uint32_t opened = 0;
  uint32_t refused_torn_header = 0;
  uint32_t failures = 0;  // a cut whose reading differs from what was saved
};

void map_failure(MapTally* t, size_t w, uint32_t cut, const char* what) {
  if (++t->failures <= 8)
    ADD_FAILURE() << "map, cut at byte " << cut << " of write " << w << ": " << what;
}

// Reopens `card` read-only and checks it against the saves of `session` completed by the cut
// (w, cut); with `refuse`, the header is torn and open() must refuse.
void check_map(std::vector<uint8_t>& card, const std::vector<Save>& saves, uint32_t session,
               int32_t origin_mm, bool refuse, size_t w, uint32_t cut, MapTally* t) {
  ++t->cuts;
  std::map<std::pair<uint16_t, uint16_t>, const Save*> expected;
  for (const Save& s : saves) {
    if (s.session == session && landed(s.complete, w, cut)) expected[{s.tile.x, s.tile.y}] = &s;
  }
  hal::FakeBlockDevice device(Span<uint8_t>(card.data(), card.size()));
  MapTileIndexEntry index[kIndexTiles];
  uint8_t buffer[kMapReadBuffer];
  GridConfig grid;
  MapProblem problem = MapProblem::kNone;
  MapStore map;
  const Status s =
      map.open(device, Span<MapTileIndexEntry>(index), Span<uint8_t>(buffer), &grid, &problem);
  if (refuse) {
    if (s == Status::kOk || problem != MapProblem::kLog) {
      map_failure(t, w, cut, "a torn header must be refused");
    }
    ++t->refused_torn_header;
    return;
  }
  if (s != Status::kOk) {
    map_failure(t, w, cut, map_problem_text(problem));
    return;
  }
  ++t->opened;
  if (grid.origin_x.raw() != Q31_32::from_ratio(origin_mm, 1000).raw()) {
    map_failure(t, w, cut, "another session's header");
    return;
  }
  if (map.tile_count() != expected.size()) {
    map_failure(t, w, cut, "another number of tiles than saved");
    return;
  }
  int8_t cells[kGridTileCells];
  for (uint32_t i = 0; i < map.tile_count(); ++i) {
    const MapTileIndexEntry& e = map.entry(i);
    const auto it = expected.find({e.x, e.y});
    if (it == expected.end()) {
      map_failure(t, w, cut, "a tile that was not saved in this session");
      return;
    }
    if (e.offset != it->second->offset) {
      map_failure(t, w, cut, "not the latest completed save of a tile");
      return;
    }
    if (map.load(GridTile{e.x, e.y}, Span<int8_t>(cells, kGridTileCells)) != Status::kOk ||
        !std::equal(cells, cells + kGridTileCells, it->second->cells.begin())) {
      map_failure(t, w, cut, "a tile's contents differ from its save");
      return;
    }
  }
}

TEST(PowerLossMap, ACutLosesNoCompletedTileSave) {
  std::vector<uint8_t> initial(kMapBlocks * kBlockBytes, 0xEE);
  std::vector<Save> saves = write_old_map(initial);

  JournalDevice device(initial);
  MapStore map;
  JournalledMap store(map, device);
  MapTileIndexEntry index[kIndexTiles];
  ASSERT_EQ(map.create(device, map_grid(0), Span<MapTileIndexEntry>(index)), Status::kOk);
  ASSERT_NO_FATAL_FAILURE(store.session_started());
  OccupancyGridStorage<3> ram;
  OccupancyGrid grid;
  ASSERT_EQ(grid.configure(map_grid(0), ram.buffers(), store), Status::kOk);
  for (uint32_t k = 0; k < kScansBeforeClear; ++k)
    ASSERT_NO_FATAL_FAILURE(scan(grid, k));
  ASSERT_EQ(grid.clear(), Status::kOk);  // the rebuild's new session
  for (uint32_t k = 0; k < kScansAfterClear; ++k)
    ASSERT_NO_FATAL_FAILURE(scan(grid, k + 5));
  ASSERT_EQ(grid.flush(), Status::kOk);
  ASSERT_EQ(store.headers.size(), 2u);
  saves.insert(saves.end(), store.saves.begin(), store.saves.end());
  const uint32_t run_saves = static_cast<uint32_t>(store.saves.size());
  uint32_t resaves = 0;  // saves of a tile saved before in the same session
  for (size_t i = 0; i < store.saves.size(); ++i) {
    for (size_t j = 0; j < i; ++j) {
      if (store.saves[j].session == store.saves[i].session &&
          store.saves[j].tile.x == store.saves[i].tile.x &&
          store.saves[j].tile.y == store.saves[i].tile.y) {
        ++resaves;
        break;
      }
    }
  }
  EXPECT_GT(resaves, run_saves / 2);  // tiles go out and come back many times

  std::vector<Point> ends;
  for (const Save& s : store.saves)
    ends.push_back(s.complete);
  const size_t writes = device.journal.size();
  const size_t last_save_first_write = store.saves[store.saves.size() - 2].complete.write + 2;
  const int32_t origins[3] = {-700, 0, 0};  // of sessions 0, 1, 2
  std::vector<uint8_t> disk = initial;      // the card with writes [0, w) applied
  std::vector<uint8_t> trial;
  MapTally tally;
  for (size_t w = 0; w < writes; ++w) {
    const JournalDevice::Write& write = device.journal[w];
    // Every byte of each create()'s two writes and of the last save's writes.
    bool every_byte = w >= last_save_first_write;
    for (const size_t h : store.headers)
      every_byte = every_byte || w == h || w + 1 == h;
    // The session whose header is on the card before this write.
    uint32_t session = 0;
    bool header_write = false;
    for (size_t k = 0; k < store.headers.size(); ++k) {
      if (store.headers[k] < w) session = static_cast<uint32_t>(k + 1);
      header_write = header_write || store.headers[k] == w;
    }
    for (const uint32_t cut : cuts_for(w, ends, every_byte)) {
      trial = disk;
      test::apply_write(trial, write, cut);
      // A torn header: unchanged (the cut came before its first new byte) or damaged.
      const bool refuse = header_write && cut > 0 && !same_block0(trial, disk);
      check_map(trial, saves, session, origins[session], refuse, w, cut, &tally);
    }
    test::apply_write(disk, write);
  }
  check_map(disk, saves, 2, 0, false, writes, 0, &tally);  // every write done: the whole map

  std::printf(
      "[ figure   ] map power cuts %u over %zu writes (%u tile saves, %u of them re-saves, a "
      "clear() between): opened %u, torn header refused %u, failures %u\n",
      tally.cuts, writes, run_saves, resaves, tally.opened, tally.refused_torn_header,
      tally.failures);
  EXPECT_EQ(tally.failures, 0u);
  EXPECT_GT(tally.cuts, 2u * writes);
}

// ---------------------------------------------------------------------------------------
// Graph

// Two slots of 16 blocks (map_store.h): the older graph's 82 records reach block 10 of the
// first.
constexpr uint32_t kGraphBlocks = 32;
constexpr uint32_t kSlotBlocks = kGraphBlocks / 2;

struct GraphStorage {
  PoseGraphNode nodes[64];
  PoseGraphEdge edges[80];
  PoseGraphSolverSlot solver[64];
};

// `nodes` nodes round a loop, a closure every 10 nodes back to the start, optimised a little.
void make_graph(PoseGraph& graph, GraphStorage& storage, uint32_t nodes, int32_t salt) {
  const PoseGraphBuffers b{Span<PoseGraphNode>(storage.nodes), Span<PoseGraphEdge>(storage.edges),
                           Span<PoseGraphSolverSlot>(storage.solver)};
  ASSERT_EQ(graph.configure(PoseGraphConfig{}, b), Status::kOk);
  for (uint32_t i = 0; i < nodes; ++i) {
    const int32_t k = static_cast<int32_t>(i % 10);
    const Pose2 p{Q31_32::from_ratio(k * 500 + salt, 1000),
                  Q31_32::from_ratio(static_cast<int32_t>(i / 10) * 30 + salt, 1000),
                  Angle::from_degrees(static_cast<int64_t>(i) * 7 + salt)};
    ASSERT_TRUE(graph.add_node(p, 100 + i).ok());
    if (i >= 10 && i % 10 == 0) {
      ASSERT_EQ(graph.add_loop_closure(i - 10, i, RelativePose2{},
                                       EdgeInformation{UQ16_16::from_int(1), UQ16_16::from_int(1)}),
                Status::kOk);
    }
  }
  PoseGraphProgress progress;
  ASSERT_EQ(graph.optimise_step(300, &progress), Status::kOk);
}

struct GraphImage {
  GraphFileHeader header;
  std::vector<GraphFileNode> nodes;
  std::vector<std::pair<PoseGraphEdge, bool>> edges;
};

GraphImage image_of(const PoseGraph& graph) {
  GraphImage g;
  g.header.nodes = graph.node_count();
  g.header.edges = graph.edge_count();
  g.header.closures = graph.closure_count();
  g.header.converged = graph.converged();
  for (uint32_t i = 0; i < graph.node_count(); ++i)
    g.nodes.push_back({i, graph.place(i).value(), graph.pose(i).value()});
  for (uint32_t i = 0; i < graph.edge_count(); ++i)
    g.edges.push_back({graph.edge(i).value(), i + 1 >= graph.node_count()});
  return g;
}

bool same(const GraphImage& a, const GraphImage& b) {
  if (a.header.nodes != b.header.nodes || a.header.edges != b.header.edges ||
      a.header.closures != b.header.closures || a.header.converged != b.header.converged ||
      a.nodes.size() != b.nodes.size() || a.edges.size() != b.edges.size()) {
    return false;
  }
  for (size_t i = 0; i < a.nodes.size(); ++i) {
    const GraphFileNode& x = a.nodes[i];
    const GraphFileNode& y = b.nodes[i];
    if (x.index != y.index || x.place != y.place || x.pose.x.raw() != y.pose.x.raw() ||
        x.pose.y.raw() != y.pose.y.raw() || x.pose.heading.bam != y.pose.heading.bam) {
      return false;
    }
  }
  for (size_t i = 0; i < a.edges.size(); ++i) {
    const PoseGraphEdge& x = a.edges[i].first;
    const PoseGraphEdge& y = b.edges[i].first;
    if (a.edges[i].second != b.edges[i].second || x.from != y.from || x.to != y.to ||
        x.dx.raw() != y.dx.raw() || x.dy.raw() != y.dy.raw() || x.dtheta.bam != y.dtheta.bam ||
        x.info_xy.raw() != y.info_xy.raw() || x.info_heading.raw() != y.info_heading.raw()) {
      return false;
    }
  }
  return true;
}

// Reads the whole graph file as an explorer of the card would: kOk only for a complete graph
// (every node and edge the header announces, and a clean end).
Status read_graph(std::vector<uint8_t>& card, GraphImage* out, MapProblem* problem) {
  hal::FakeBlockDevice device(Span<uint8_t>(card.data(), card.size()));
  GraphReader r;
  *problem = MapProblem::kNone;
  Status s = r.open(device, problem);
  if (s != Status::kOk) return s;
  out->header = r.header();
  for (uint32_t i = 0; s == Status::kOk && i < r.header().nodes; ++i) {
    GraphFileNode n;
    s = r.next_node(&n);
    if (s == Status::kOk) out->nodes.push_back(n);
  }
  for (uint32_t i = 0; s == Status::kOk && i < r.header().edges; ++i) {
    PoseGraphEdge e;
    bool closure = false;
    s = r.next_edge(&e, &closure);
    if (s == Status::kOk) out->edges.push_back({e, closure});
  }
  if (s == Status::kOk) s = r.finish();
  *problem = r.problem();
  return s;
}

TEST(PowerLossGraph, ACutReadsTheWholeOldGraphOrTheWholeNewOne) {
  std::vector<uint8_t> initial(kGraphBlocks * kBlockBytes, 0xEE);
  static GraphStorage old_storage, new_storage;
  PoseGraph old_graph, new_graph;
  ASSERT_NO_FATAL_FAILURE(make_graph(old_graph, old_storage, 40, 11));
  ASSERT_NO_FATAL_FAILURE(make_graph(new_graph, new_storage, 30, 0));
  const GraphImage old_image = image_of(old_graph);
  const GraphImage new_image = image_of(new_graph);
  {
    hal::FakeBlockDevice card(Span<uint8_t>(initial.data(), initial.size()));
    ASSERT_EQ(write_graph(card, old_graph), Status::kOk);  // slot 0, generation 1
  }
  JournalDevice device(initial);
  ASSERT_EQ(write_graph(device, new_graph), Status::kOk);  // slot 1, generation 2
  const size_t writes = device.journal.size();

  // The journal, in the second slot: commit slot 1, header, then per record its blocks and a
  // commit slot.
  ASSERT_EQ(device.journal[0].block, kSlotBlocks + 1);
  ASSERT_EQ(device.journal[1].block, kSlotBlocks);
  std::vector<Point> ends;
  size_t last_data = 0;
  for (size_t w = 2; w < writes; ++w) {
    if (device.journal[w].block >= kSlotBlocks + 3) {
      last_data = w;
      continue;
    }
    const uint32_t end =
        kFirstRecordOffset + static_cast<uint32_t>(ends.size() + 1) * kGraphRecordBytes;
    ASSERT_EQ(device.journal[last_data].block, kSlotBlocks + (end - 1) / kBlockBytes);
    ends.push_back({last_data, (end - 1) % kBlockBytes + 1});
  }
  const uint32_t records = new_image.header.nodes + new_image.header.edges;
  ASSERT_EQ(ends.size(), records);
  const Point new_complete = ends.back();
  const size_t last_record_first_write = ends[ends.size() - 2].write + 2;

  std::vector<uint8_t> disk = initial;
  std::vector<uint8_t> trial;
  uint32_t tried = 0, read_old = 0, read_new = 0, failures = 0;
  for (size_t w = 0; w <= writes; ++w) {
    const bool every_byte = w <= 1 || w >= last_record_first_write;
    const std::vector<uint32_t> cuts =
        w == writes ? std::vector<uint32_t>{0} : cuts_for(w, ends, every_byte);
    for (const uint32_t cut : cuts) {
      trial = disk;
      if (w < writes) test::apply_write(trial, device.journal[w], cut);
      ++tried;
      GraphImage got;
      MapProblem problem = MapProblem::kNone;
      const Status s = read_graph(trial, &got, &problem);
      const char* wrong = nullptr;
      if (landed(new_complete, w, cut)) {
        if (s != Status::kOk || !same(got, new_image)) wrong = "the new graph must read whole";
        ++read_new;
      } else {
        if (s != Status::kOk || !same(got, old_image)) wrong = "the old graph must read whole";
        ++read_old;
      }
      if (wrong != nullptr && ++failures <= 8) {
        ADD_FAILURE() << "graph, cut at byte " << cut << " of write " << w << ": " << wrong << " ("
                      << map_problem_text(problem) << ")";
      }
    }
    if (w < writes) test::apply_write(disk, device.journal[w]);
  }
  std::printf(
      "[ figure   ] graph power cuts %u over %zu writes (%u records over an older graph of "
      "%u): old graph read whole %u, new graph read whole %u, failures %u\n",
      tried, writes, records, old_image.header.nodes + old_image.header.edges, read_old, read_new,
      failures);
  EXPECT_EQ(failures, 0u);
  EXPECT_GT(read_old, 0u);
  EXPECT_GT(read_new, 0u);
}

}  // namespace
}  // namespace seqslam::storage
