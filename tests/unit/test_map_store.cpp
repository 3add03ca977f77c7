// The explore mode's files (storage/map_store.h): the card-backed TileStore (save, load,
// lazy clear, reload with the latest record of each tile winning, the OccupancyGrid paging
// through it) and the graph file (round trip of a PoseGraph), and both loaders on bad input:
// cut short, flipped bytes, another kind, another version, records that do not belong.
// Every refusal is a Status with the reason, never a crash, and the file is only read.
#include "seqslam/storage/map_store.h"

#include "seqslam/storage/bytes.h"
#include "seqslam/storage/record_log.h"
#include "storage_fixtures.h"
#include "test.h"

namespace seqslam::storage {
namespace {

constexpr uint32_t kTileRecordBytes = kRecordOverhead + kMapTilePayload;  // 1048
constexpr uint32_t kFirstRecord = kFirstRecordOffset;

test::FakeCard<48> g_card;
MapTileIndexEntry g_index[8];
uint8_t g_buffer[kMapReadBuffer];
int8_t g_tile[kGridTileCells];
int8_t g_back[kGridTileCells];

GridConfig grid_config() {
  GridConfig g;
  g.origin_x = Q31_32::from_ratio(-5, 2);
  g.origin_y = Q31_32::from_int(-1);
  g.width = 100;  // 4 x 2 tiles
  g.height = 40;
  return g;
}

void fill(int8_t* cells, uint32_t seed) {
  for (uint32_t i = 0; i < kGridTileCells; ++i)
    cells[i] = static_cast<int8_t>((i * 7u + seed * 31u) % 129u) - 64;
}

bool same(const int8_t* a, const int8_t* b) {
  for (uint32_t i = 0; i < kGridTileCells; ++i)
    if (a[i] != b[i]) return false;
  return true;
}

Span<int8_t> tile_span(int8_t* cells) {
  return Span<int8_t>(cells, kGridTileCells);
}

// A map with tile (1,0) saved twice (seeds 1 then 3) and tile (3,1) once (seed 2).
void write_map(MapStore& store) {
  ASSERT_EQ(store.create(g_card.device, grid_config(), Span<MapTileIndexEntry>(g_index)),
            Status::kOk);
  fill(g_tile, 1);
  ASSERT_EQ(store.save(GridTile{1, 0}, tile_span(g_tile)), Status::kOk);
  fill(g_tile, 2);
  ASSERT_EQ(store.save(GridTile{3, 1}, tile_span(g_tile)), Status::kOk);
  fill(g_tile, 3);
  ASSERT_EQ(store.save(GridTile{1, 0}, tile_span(g_tile)), Status::kOk);
}

Status reopen(MapProblem* problem) {
  MapStore store;
  GridConfig g;
  return store.open(g_card.device, Span<MapTileIndexEntry>(g_index),
                    Span<uint8_t>(g_buffer, sizeof g_buffer), &g, problem);
}

TEST(MapStore, SavesLoadsClearsAndReloads) {
  g_card.reset();
  MapStore store;
  write_map(store);
  EXPECT_EQ(store.tile_count(), 2u);
  EXPECT_EQ(store.records_written(), 3u);
  fill(g_tile, 3);
  ASSERT_EQ(store.load(GridTile{1, 0}, tile_span(g_back)), Status::kOk);
  EXPECT_TRUE(same(g_tile, g_back));  // the latest save
  fill(g_tile, 2);
  ASSERT_EQ(store.load(GridTile{3, 1}, tile_span(g_back)), Status::kOk);
  EXPECT_TRUE(same(g_tile, g_back));
  EXPECT_EQ(store.load(GridTile{0, 0}, tile_span(g_back)), Status::kNotFound);

  // Reloaded read-only: the same content and grid, saves refused.
  MapStore again;
  GridConfig g;
  MapProblem problem = MapProblem::kBadRecord;
  ASSERT_EQ(again.open(g_card.device, Span<MapTileIndexEntry>(g_index),
                       Span<uint8_t>(g_buffer, sizeof g_buffer), &g, &problem),
            Status::kOk);
  EXPECT_TRUE(problem == MapProblem::kNone);
  EXPECT_EQ(again.tile_count(), 2u);
  EXPECT_EQ(g.origin_x.raw(), grid_config().origin_x.raw());
  EXPECT_EQ(g.width, 100u);
  EXPECT_EQ(g.height, 40u);
  EXPECT_EQ(g.hit, grid_config().hit);
  fill(g_tile, 3);
  ASSERT_EQ(again.load(GridTile{1, 0}, tile_span(g_back)), Status::kOk);
  EXPECT_TRUE(same(g_tile, g_back));
  EXPECT_EQ(again.save(GridTile{0, 0}, tile_span(g_tile)), Status::kFailedPrecondition);
  EXPECT_EQ(again.clear(), Status::kFailedPrecondition);

  // clear(): a new session; nothing of the old one is visible, to this store or a reload.
  ASSERT_EQ(store.clear(), Status::kOk);
  EXPECT_EQ(store.tile_count(), 0u);
  EXPECT_EQ(store.load(GridTile{1, 0}, tile_span(g_back)), Status::kNotFound);
  fill(g_tile, 9);
  ASSERT_EQ(store.save(GridTile{2, 1}, tile_span(g_tile)), Status::kOk);
  ASSERT_EQ(again.open(g_card.device, Span<MapTileIndexEntry>(g_index),
                       Span<uint8_t>(g_buffer, sizeof g_buffer), &g),
            Status::kOk);
  EXPECT_EQ(again.tile_count(), 1u);
  EXPECT_EQ(again.load(GridTile{1, 0}, tile_span(g_back)), Status::kNotFound);
  ASSERT_EQ(again.load(GridTile{2, 1}, tile_span(g_back)), Status::kOk);
  EXPECT_TRUE(same(g_tile, g_back));
}

TEST(MapStore, TheGridPagesThroughItAndAReloadGivesTheSameMap) {
  g_card.reset();
  MapStore store;
  ASSERT_EQ(store.create(g_card.device, grid_config(), Span<MapTileIndexEntry>(g_index)),
            Status::kOk);
  static OccupancyGridStorage<3> ram;
  OccupancyGrid grid;
  ASSERT_EQ(grid.configure(grid_config(), ram.buffers(), store), Status::kOk);
  // Rays across all four tile columns: more tiles than slots, so tiles go to the card and back.
  for (int32_t k = 0; k < 12; ++k) {
    const Pose2 pose{Q31_32::from_ratio(k * 3 - 16, 10), Q31_32::from_ratio(1, 2),
                     Angle::from_degrees(k * 30)};
    ASSERT_EQ(grid.insert_reading(pose, kMyonInfrared[0], static_cast<uint16_t>(600 + 50 * k)),
              Status::kOk);
  }
  ASSERT_EQ(grid.flush(), Status::kOk);
  EXPECT_GE(grid.stats().tile_saves, 4u);
  MapStore reloaded_store;
  GridConfig g;
  ASSERT_EQ(reloaded_store.open(g_card.device, Span<MapTileIndexEntry>(g_index),
                                Span<uint8_t>(g_buffer, sizeof g_buffer), &g),
            Status::kOk);
  static OccupancyGridStorage<3> ram2;
  OccupancyGrid reloaded;
  ASSERT_EQ(reloaded.configure(g, ram2.buffers(), reloaded_store), Status::kOk);
  uint32_t observed = 0;
  for (uint16_t ty = 0; ty < grid.tiles_y(); ++ty) {
    for (uint16_t tx = 0; tx < grid.tiles_x(); ++tx) {
      ASSERT_EQ(grid.copy_tile(GridTile{tx, ty}, tile_span(g_tile)), Status::kOk);
      ASSERT_EQ(reloaded.copy_tile(GridTile{tx, ty}, tile_span(g_back)), Status::kOk);
      EXPECT_TRUE(same(g_tile, g_back));
      for (const int8_t c : g_tile)
        observed += c != 0 ? 1u : 0u;
    }
  }
  EXPECT_GT(observed, 100u);
}

TEST(MapStore, ALoadOfADamagedTileIsDataLoss) {
  g_card.reset();
  MapStore store;
  write_map(store);
  g_card.bytes[kFirstRecord + kTileRecordBytes + 300] ^= 0x10;  // tile (3,1)'s cells
  EXPECT_EQ(store.load(GridTile{3, 1}, tile_span(g_back)), Status::kDataLoss);
  fill(g_tile, 3);
  ASSERT_EQ(store.load(GridTile{1, 0}, tile_span(g_back)), Status::kOk);
  EXPECT_TRUE(same(g_tile, g_back));
}

TEST(MapStore, ReloadRefusesBadInputWithTheReason) {
  MapStore store;
  MapProblem problem = MapProblem::kNone;

  // A record damaged in the middle (a flipped byte).
  g_card.reset();
  write_map(store);
  g_card.bytes[kFirstRecord + 40] ^= 0x01;
  EXPECT_EQ(reopen(&problem), Status::kDataLoss);
  EXPECT_TRUE(problem == MapProblem::kDamaged);

  // Cut short: the last record incomplete.
  g_card.reset();
  write_map(store);
  for (uint32_t i = kFirstRecord + 2 * kTileRecordBytes + 600; i < sizeof g_card.bytes; ++i)
    g_card.bytes[i] = 0;
  EXPECT_EQ(reopen(&problem), Status::kDataLoss);
  EXPECT_TRUE(problem == MapProblem::kDamaged);

  // A damaged header block.
  g_card.reset();
  write_map(store);
  g_card.bytes[20] ^= 0x40;
  EXPECT_EQ(reopen(&problem), Status::kDataLoss);
  EXPECT_TRUE(problem == MapProblem::kLog);

  // Another kind of log (a graph file) and another version of this kind.
  g_card.reset();
  LogWriter w;
  ASSERT_EQ(w.create(g_card.device, kGraphKind, nullptr, 0), Status::kOk);
  EXPECT_EQ(reopen(&problem), Status::kDataLoss);
  EXPECT_TRUE(problem == MapProblem::kLog);
  uint8_t header[28] = {};
  LogKind v2 = kMapKind;
  v2.version = 2;
  g_card.reset();
  ASSERT_EQ(w.create(g_card.device, v2, header, sizeof header), Status::kOk);
  EXPECT_EQ(reopen(&problem), Status::kFailedPrecondition);
  EXPECT_TRUE(problem == MapProblem::kLog);

  // A header whose grid settings the grid refuses (all zero: cell 0 mm).
  g_card.reset();
  ASSERT_EQ(w.create(g_card.device, kMapKind, header, sizeof header), Status::kOk);
  EXPECT_EQ(reopen(&problem), Status::kDataLoss);
  EXPECT_TRUE(problem == MapProblem::kBadHeader);

  // Records that do not belong: a tile outside the grid, a record of another size or type.
  struct Bad {
    uint8_t type;
    uint16_t x;
    uint32_t size;
  };
  const Bad bad[] = {{1, 4, kMapTilePayload}, {1, 0, kMapTilePayload - 1}, {2, 0, kMapTilePayload}};
  for (const Bad& b : bad) {
    g_card.reset();
    uint8_t payload[kMapTilePayload] = {};
    ByteWriter pw(payload, 4);
    pw.u16(b.x);
    pw.u16(0);
    // The map's own header (as MapStore writes it), then the record that does not belong.
    LogWriter raw;
    uint8_t hdr[28];
    ByteWriter hw(hdr, sizeof hdr);
    const GridConfig gc = grid_config();
    hw.i64(gc.origin_x.raw());
    hw.i64(gc.origin_y.raw());
    hw.u16(gc.cell_mm);
    hw.u16(gc.width);
    hw.u16(gc.height);
    hw.u8(static_cast<uint8_t>(gc.hit));
    hw.u8(static_cast<uint8_t>(gc.miss));
    hw.u8(static_cast<uint8_t>(gc.limit));
    hw.u8(static_cast<uint8_t>(gc.occupied_threshold));
    hw.u8(static_cast<uint8_t>(gc.free_threshold));
    hw.u8(0);
    ASSERT_EQ(raw.create(g_card.device, kMapKind, hdr, sizeof hdr), Status::kOk);
    const ByteSpan part{payload, b.size};
    ASSERT_EQ(raw.append(b.type, &part, 1), Status::kOk);
    EXPECT_EQ(reopen(&problem), Status::kDataLoss);
    EXPECT_TRUE(problem == MapProblem::kBadRecord);
  }

  // More distinct tiles than the index holds.
  g_card.reset();
  write_map(store);
  MapStore small;
  GridConfig g;
  EXPECT_EQ(small.open(g_card.device, Span<MapTileIndexEntry>(g_index, 1),
                       Span<uint8_t>(g_buffer, sizeof g_buffer), &g, &problem),
            Status::kResourceExhausted);
  EXPECT_TRUE(problem == MapProblem::kIndexFull);
  // A buffer too small for a tile record.
  EXPECT_EQ(small.open(g_card.device, Span<MapTileIndexEntry>(g_index),
                       Span<uint8_t>(g_buffer, kMapReadBuffer - 1), &g, &problem),
            Status::kInvalidArgument);
  EXPECT_EQ(small.load(GridTile{1, 0}, tile_span(g_back)), Status::kFailedPrecondition);
  // The store's own index bounds the tiles it can save.
  g_card.reset();
  ASSERT_EQ(store.create(g_card.device, grid_config(), Span<MapTileIndexEntry>(g_index, 1)),
            Status::kOk);
  ASSERT_EQ(store.save(GridTile{0, 0}, tile_span(g_tile)), Status::kOk);
  EXPECT_EQ(store.save(GridTile{1, 0}, tile_span(g_tile)), Status::kResourceExhausted);
  EXPECT_EQ(store.save(GridTile{0, 0}, tile_span(g_tile)), Status::kOk);  // same tile: fine
}

// ---------------------------------------------------------------------------------------
// Graph file

PoseGraphNode g_nodes[8];
PoseGraphEdge g_edges[12];
PoseGraphSolverSlot g_solver[8];

// Five nodes along a square, one closure from node 4 back to node 0, optimised.
void make_graph(PoseGraph& graph) {
  const PoseGraphBuffers b{Span<PoseGraphNode>(g_nodes), Span<PoseGraphEdge>(g_edges),
                           Span<PoseGraphSolverSlot>(g_solver), Span<PoseGraphRefineSlot>()};
  ASSERT_EQ(graph.configure(PoseGraphConfig{}, b), Status::kOk);
  const int32_t xs[5] = {0, 2, 2, 0, 0};
  const int32_t ys[5] = {0, 0, 2, 2, 0};
  for (uint32_t i = 0; i < 5; ++i) {
    const Pose2 p{Q31_32::from_ratio(xs[i] * 101, 100), Q31_32::from_int(ys[i]),
                  Angle::from_degrees(static_cast<int32_t>(90 * i))};
    ASSERT_TRUE(graph.add_node(p, 10 + i).ok());
  }
  ASSERT_EQ(graph.add_loop_closure(0, 4, RelativePose2{},
                                   EdgeInformation{UQ16_16::from_int(1), UQ16_16::from_int(1)}),
            Status::kOk);
  PoseGraphProgress progress;
  for (uint32_t k = 0; k < 100 && !graph.converged(); ++k)
    ASSERT_EQ(graph.optimise_step(500, &progress), Status::kOk);
  ASSERT_TRUE(graph.converged());
}

// Reads the whole graph file; the first failing status.
Status read_all(MapProblem* problem) {
  GraphReader r;
  Status s = r.open(g_card.device, problem);
  if (s != Status::kOk) return s;
  for (uint32_t i = 0; i < r.header().nodes; ++i) {
    GraphFileNode n;
    s = r.next_node(&n);
    if (s != Status::kOk) break;
  }
  for (uint32_t i = 0; s == Status::kOk && i < r.header().edges; ++i) {
    PoseGraphEdge e;
    bool closure = false;
    s = r.next_edge(&e, &closure);
  }
  if (s == Status::kOk) s = r.finish();
  *problem = r.problem();
  return s;
}

TEST(GraphFile, RoundTripOfEveryNodeAndEdge) {
  g_card.reset();
  PoseGraph graph;
  make_graph(graph);
  ASSERT_EQ(write_graph(g_card.device, graph), Status::kOk);
  GraphReader r;
  ASSERT_EQ(r.open(g_card.device), Status::kOk);
  EXPECT_EQ(r.header().nodes, 5u);
  EXPECT_EQ(r.header().edges, 5u);
  EXPECT_EQ(r.header().closures, 1u);
  EXPECT_TRUE(r.header().converged);
  PoseGraphEdge e;
  bool closure = false;
  EXPECT_EQ(r.next_edge(&e, &closure), Status::kFailedPrecondition);  // nodes first
  for (uint32_t i = 0; i < 5; ++i) {
    GraphFileNode n;
    ASSERT_EQ(r.next_node(&n), Status::kOk);
    const Pose2 p = graph.pose(i).value();
    EXPECT_EQ(n.index, i);
    EXPECT_EQ(n.place, 10 + i);
    EXPECT_EQ(n.pose.x.raw(), p.x.raw());
    EXPECT_EQ(n.pose.y.raw(), p.y.raw());
    EXPECT_EQ(n.pose.heading.bam, p.heading.bam);
  }
  for (uint32_t i = 0; i < 5; ++i) {
    ASSERT_EQ(r.next_edge(&e, &closure), Status::kOk);
    const PoseGraphEdge g = graph.edge(i).value();
    EXPECT_EQ(e.from, g.from);
    EXPECT_EQ(e.to, g.to);
    EXPECT_EQ(e.dx.raw(), g.dx.raw());
    EXPECT_EQ(e.dy.raw(), g.dy.raw());
    EXPECT_EQ(e.dtheta.bam, g.dtheta.bam);
    EXPECT_EQ(e.info_xy.raw(), g.info_xy.raw());
    EXPECT_EQ(e.info_heading.raw(), g.info_heading.raw());
    EXPECT_EQ(closure, i == 4);
  }
  EXPECT_EQ(r.finish(), Status::kOk);
}

TEST(GraphFile, BadInputIsRefusedWithTheReason) {
  PoseGraph graph;
  make_graph(graph);
  MapProblem problem = MapProblem::kNone;
  constexpr uint32_t kEdgeRecordBytes = kRecordOverhead + 28;
  constexpr uint32_t kNodeRecordBytes = kRecordOverhead + 28;

  // Cut short after three nodes (the rest never written: a clean end too early).
  g_card.reset();
  ASSERT_EQ(write_graph(g_card.device, graph), Status::kOk);
  for (uint32_t i = kFirstRecord + 3 * kNodeRecordBytes; i < sizeof g_card.bytes; ++i)
    g_card.bytes[i] = 0;
  EXPECT_EQ(read_all(&problem), Status::kDataLoss);
  EXPECT_TRUE(problem == MapProblem::kTruncated);

  // Cut in the middle of the last edge: the log committed it, so the file was cut short.
  g_card.reset();
  ASSERT_EQ(write_graph(g_card.device, graph), Status::kOk);
  const uint32_t end = kFirstRecord + 5 * kNodeRecordBytes + 5 * kEdgeRecordBytes;
  for (uint32_t i = end - 10; i < sizeof g_card.bytes; ++i)
    g_card.bytes[i] = 0;
  EXPECT_EQ(read_all(&problem), Status::kDataLoss);
  EXPECT_TRUE(problem == MapProblem::kTruncated);

  // A flipped byte in a node record.
  g_card.reset();
  ASSERT_EQ(write_graph(g_card.device, graph), Status::kOk);
  g_card.bytes[kFirstRecord + kNodeRecordBytes + 25] ^= 0x80;
  EXPECT_EQ(read_all(&problem), Status::kDataLoss);
  EXPECT_TRUE(problem == MapProblem::kDamaged);

  // Another kind, another version (1: one log over the whole file, before the two slots).
  g_card.reset();
  LogWriter w;
  uint8_t header[20] = {};
  ASSERT_EQ(w.create(g_card.device, kMapKind, header, sizeof header), Status::kOk);
  EXPECT_EQ(read_all(&problem), Status::kDataLoss);
  EXPECT_TRUE(problem == MapProblem::kLog);
  LogKind v1 = kGraphKind;
  v1.version = 1;
  g_card.reset();
  ASSERT_EQ(w.create(g_card.device, v1, header, 16), Status::kOk);
  EXPECT_EQ(read_all(&problem), Status::kFailedPrecondition);
  EXPECT_TRUE(problem == MapProblem::kLog);

  // Counts that disagree (3 nodes, 5 edges, 1 closure).
  g_card.reset();
  ByteWriter hw(header, sizeof header);
  hw.u32(3);
  hw.u32(5);
  hw.u32(1);
  ASSERT_EQ(w.create(g_card.device, kGraphKind, header, sizeof header), Status::kOk);
  EXPECT_EQ(read_all(&problem), Status::kDataLoss);
  EXPECT_TRUE(problem == MapProblem::kBadHeader);

  // Records that do not fit the header: a closure to a node that does not exist, and one
  // record too many.
  for (int variant = 0; variant < 2; ++variant) {
    g_card.reset();
    uint8_t h2[20] = {};
    ByteWriter h(h2, sizeof h2);
    h.u32(2);
    h.u32(variant == 0 ? 2 : 1);
    h.u32(variant == 0 ? 1 : 0);
    ASSERT_EQ(w.create(g_card.device, kGraphKind, h2, sizeof h2), Status::kOk);
    for (uint32_t i = 0; i < 2; ++i) {
      uint8_t node[28] = {};
      ByteWriter nw(node, sizeof node);
      nw.u32(i);
      const ByteSpan part{node, sizeof node};
      ASSERT_EQ(w.append(1, &part, 1), Status::kOk);
    }
    uint8_t edge[28] = {};
    ByteWriter ew(edge, sizeof edge);
    ew.u16(0);
    ew.u16(1);
    const ByteSpan odometry{edge, sizeof edge};
    ASSERT_EQ(w.append(2, &odometry, 1), Status::kOk);
    edge[2] = 7;   // to node 7 of 2
    edge[24] = 1;  // a closure
    ASSERT_EQ(w.append(2, &odometry, 1), Status::kOk);
    EXPECT_EQ(read_all(&problem), Status::kDataLoss);
    EXPECT_TRUE(problem == (variant == 0 ? MapProblem::kBadRecord : MapProblem::kExtraRecord));
  }
}

// The two slots: each rewrite goes to the slot without the newest complete graph, one
// generation up, and the reader takes the newest complete graph; a rewrite that did not
// finish (the second slot's graph cut short) leaves the previous graph readable.
TEST(GraphFile, ARewriteKeepsThePreviousGraphUntilItIsComplete) {
  g_card.reset();
  PoseGraph graph;
  make_graph(graph);
  for (uint32_t generation = 1; generation <= 3; ++generation) {
    ASSERT_EQ(write_graph(g_card.device, graph), Status::kOk);
    GraphReader r;
    ASSERT_EQ(r.open(g_card.device), Status::kOk);
    EXPECT_EQ(r.header().generation, generation);
    EXPECT_EQ(r.slot(), (generation - 1) % 2);
  }
  // Generation 4 goes to slot 1; cut it after its header and two nodes.
  ASSERT_EQ(write_graph(g_card.device, graph), Status::kOk);
  const uint32_t half = static_cast<uint32_t>(sizeof g_card.bytes) / hal::kBlockSize / 2;
  const uint32_t slot1 = half * hal::kBlockSize;
  constexpr uint32_t kNodeRecordBytes = kRecordOverhead + 28;
  for (uint32_t i = slot1 + kFirstRecord + 2 * kNodeRecordBytes; i < sizeof g_card.bytes; ++i)
    g_card.bytes[i] = 0;
  GraphReader r;
  MapProblem problem = MapProblem::kLog;
  ASSERT_EQ(r.open(g_card.device, &problem), Status::kOk);
  EXPECT_EQ(problem, MapProblem::kNone);
  EXPECT_EQ(r.header().generation, 3u);
  EXPECT_EQ(r.slot(), 0u);
  // The next rewrite replaces the broken one (slot 1), not the readable one.
  ASSERT_EQ(write_graph(g_card.device, graph), Status::kOk);
  ASSERT_EQ(r.open(g_card.device), Status::kOk);
  EXPECT_EQ(r.header().generation, 4u);
  EXPECT_EQ(r.slot(), 1u);
}

}  // namespace
}  // namespace seqslam::storage
