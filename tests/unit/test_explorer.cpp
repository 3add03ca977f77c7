// The explorer (explorer.h), the mapping step every caller shares: on a synthetic route driven
// twice, closures come exactly where the gate says and each edge is what its parts (the
// alignment, the image shift, the gate) give when called directly; a card read that fails
// during a closure falls back to the matched place and is counted; snapshots hang from the
// last place, and the rebuild redraws them at the optimised poses exactly as inserting them
// there does; a full graph stops closures, not the run; every bad setting is refused.
#include "seqslam/explorer.h"

#include "seqslam/difference.h"

#include "counting_images.h"
#include "ram_state.h"
#include "ram_tile_store.h"
#include "synthetic.h"
#include "test.h"

namespace seqslam {
namespace {

constexpr uint32_t kW = 32;
constexpr uint32_t kH = 8;
constexpr uint32_t kStep = 4;  // world columns per place
constexpr uint32_t kFirstPass = 60;
constexpr uint32_t kSecondPass = 30;
constexpr uint32_t kRevisitStart = 20;  // the second pass drives world places 20..49 again
constexpr uint32_t kPlaces = kFirstPass + kSecondPass;
constexpr uint32_t kRecent = 10;
constexpr uint16_t kTilesX = 4;
constexpr uint16_t kTilesY = 2;

struct Scene {
  test::SyntheticWorld<kPlaces * kStep + kW, kH> world;
  test::CountingImages images;
  uint8_t pixels[kPlaces * kW * kH];
  PlaceInfo info[kPlaces];
  uint32_t sums[kPlaces];
  PlaceLibrary library;
  PoseGraphStorage<kPlaces, 2 * kPlaces> graph;
  OccupancyGridStorage<3> grid;
  test::RamTileStore<8> tiles;
  uint8_t scratch[kW * kH];
  uint32_t differences[kPlaces];
  Pose2 odometry[kPlaces];
  Explorer explorer;
  // A second explorer that continues a saved run (ContinuesExactlyFromASavedState).
  PoseGraphStorage<kPlaces, 2 * kPlaces> graph2;
  OccupancyGridStorage<3> grid2;
  test::RamTileStore<8> tiles2;
  Explorer resumed;
  test::RamState<16384> saved;
};

Scene g_scene;

// World place w: 0.2 m along x; the second pass 3 cm to the side, its odometry 2 % long.
Pose2 pose_of(uint32_t place) {
  if (place < kFirstPass) return Pose2{Q31_32::from_ratio(place * 2, 10), Q31_32{}, Angle{}};
  const uint32_t w = kRevisitStart + place - kFirstPass;
  return Pose2{Q31_32::from_ratio(w * 2 * 102, 1000), Q31_32::from_ratio(3, 100), Angle{}};
}

ExplorerConfig config() {
  ExplorerConfig c;
  c.recent_exclusion = kRecent;
  c.grid.origin_x = Q31_32::from_int(-2);
  c.grid.origin_y = Q31_32::from_ratio(-32, 10);
  c.grid.cell_mm = 100;
  c.grid.width = kTilesX * kGridTileSide;  // 12.8 m x 6.4 m at 10 cm: 4 x 2 tiles
  c.grid.height = kTilesY * kGridTileSide;
  return c;
}

ExplorerBuffers buffers(Scene& s, uint32_t graph_nodes = kPlaces) {
  ExplorerBuffers b;
  b.graph = s.graph.buffers();
  b.graph.nodes = b.graph.nodes.subspan(0, graph_nodes);
  b.graph.solver = b.graph.solver.subspan(0, graph_nodes);
  b.grid = s.grid.buffers();
  b.tiles = &s.tiles;
  b.sensors = Span<const RangeSensor>(kMyonInfrared);
  b.scratch = Span<uint8_t>(s.scratch);
  return b;
}

// The library of both passes (the second under other light, a quarter place further along),
// the odometry, and a fresh explorer.
void build(Scene& s, uint32_t graph_nodes = kPlaces) {
  s.world.generate(5, kPlaces * kStep + kW, kH);
  s.images.views = 0;
  s.images.fail_at = 0xFFFFFFFFu;
  ASSERT_EQ(s.images.ram.configure(kW * kH, Span<uint8_t>(s.pixels)), Status::kOk);
  ASSERT_EQ(
      s.library.configure(ImageSize{kW, kH}, s.images,
                          PlaceLibraryBuffers{Span<PlaceInfo>(s.info), Span<uint32_t>(s.sums)}),
      Status::kOk);
  test::Rng rng(9);
  uint8_t image[kW * kH];
  for (uint32_t p = 0; p < kPlaces; ++p) {
    const bool second = p >= kFirstPass;
    const uint32_t w = second ? kRevisitStart + p - kFirstPass : p;
    s.world.render(w, kStep, second ? 1 : 0, kW, second ? 236 : 256, second ? 8 : 0, 2, rng, image);
    ASSERT_EQ(s.library.add(ImageView{image, ImageSize{kW, kH}}, pose_of(p), p), Status::kOk);
    s.odometry[p] = pose_of(p);
  }
  s.tiles.reset();
  ASSERT_TRUE(s.explorer.configure(config(), buffers(s, graph_nodes)).ok());
}

// The matcher's answer for place p: none on the first pass, then the revisited place one
// place behind (a lagging sequence), confident; the difference row ranks it first.
Match answer(uint32_t p) {
  Match m;
  m.query = p;
  if (p < kFirstPass) return m;
  m.place = static_cast<int32_t>(kRevisitStart + p - kFirstPass) - 1;
  m.confidence = UQ16_16::from_ratio(1, 2);
  m.localised = true;
  return m;
}

// Place p through the explorer with the matcher's answer and a difference row that ranks the
// answer first.
// `lost`: the matcher has no answer (no closure: the optimiser goes on with its stage).
Status explore(Scene& s, uint32_t p, ExplorerStep* step, Explorer* explorer = nullptr,
               bool lost = false) {
  Match m = answer(p);
  if (lost) m = Match{};
  for (uint32_t i = 0; i < kPlaces; ++i)
    s.differences[i] = static_cast<int32_t>(i) == m.place ? 100 : 1000 + i;
  Explorer& e = explorer != nullptr ? *explorer : s.explorer;
  return e.place(s.library, Span<const uint32_t>(s.differences), m, s.odometry[p], p, step);
}

TEST(Explorer, ClosuresAreWhatTheirPartsGive) {
  Scene& s = g_scene;
  build(s);
  LoopClosureGate gate;  // the reference gate, fed the same queries
  ASSERT_EQ(gate.configure(LoopClosureConfig{}), Status::kOk);
  uint32_t closures = 0, realigned = 0;
  for (uint32_t p = 0; p < kPlaces; ++p) {
    const Match m = answer(p);
    ExplorerStep step;
    ASSERT_EQ(explore(s, p, &step), Status::kOk);
    ASSERT_EQ(step.node, static_cast<int32_t>(p));
    LoopClosureQuery q;
    q.match = m;
    q.node = p;
    q.matched_node = m.place;
    q.known_nodes = p > kRecent ? p - kRecent : 0;
    q.odometry = s.odometry[p];
    LoopClosureDecision want;
    ASSERT_EQ(gate.decide(s.explorer.graph(), q, &want), Status::kOk);
    EXPECT_EQ(step.decision.kind, want.kind) << p;
    if (want.kind != LoopClosureClass::kClosure) {
      EXPECT_EQ(step.closure_to, -1);
      continue;
    }
    // The edge as the parts give it: the aligned place and its fraction, the image shift.
    ++closures;
    ClosureAlignment al;
    ASSERT_EQ(align_closure(s.library, p, static_cast<uint32_t>(m.place), q.known_nodes,
                            config().align, Span<uint8_t>(s.scratch), &al),
              Status::kOk);
    ASSERT_EQ(step.closure_to, static_cast<int32_t>(al.place));
    EXPECT_EQ(step.closure.dx.raw(), along_route(al.fraction, config().spacing).raw());
    ImageView a{}, b{};
    ASSERT_EQ(s.library.image(al.place, &a), Status::kOk);
    uint8_t copy[kW * kH];
    for (uint32_t i = 0; i < kW * kH; ++i)
      copy[i] = a.pixels[i];
    ASSERT_EQ(s.library.image(p, &b), Status::kOk);
    const Result<Q15_16> shift =
        subpixel_shift(ImageView{copy, ImageSize{kW, kH}}, b, config().max_shift);
    ASSERT_TRUE(shift.ok());
    EXPECT_EQ(step.shift.raw(), shift.value().raw());
    EXPECT_EQ(step.closure.dtheta.bam, shift_to_heading(shift.value(), config().hfov, kW).bam);
    realigned += al.place != static_cast<uint32_t>(m.place) ? 1 : 0;
  }
  // Confirmation: the first two confident answers are pending, every later one closes.
  EXPECT_EQ(closures, kSecondPass - 2);
  EXPECT_EQ(s.explorer.stats().closures, closures);
  EXPECT_EQ(s.explorer.stats().closures_realigned, realigned);
  EXPECT_GT(realigned, closures / 2);  // most lagging answers are moved
  EXPECT_EQ(s.explorer.graph().closure_count(), closures);
  EXPECT_EQ(s.explorer.stats().align_failures, 0u);
  EXPECT_GT(s.explorer.stats().optimise_work, 0u);
  EXPECT_EQ(s.explorer.finish(100000), Status::kOk);
  EXPECT_TRUE(s.explorer.graph().converged());
}

TEST(Explorer, ACardThatFailsDuringAClosureFallsBackAndIsCounted) {
  Scene& s = g_scene;
  build(s);
  ExplorerStep step;
  uint32_t p = 0;
  for (; p < kPlaces; ++p) {
    // The first closure's alignment meets a card error on its third read.
    if (p == kFirstPass + 2) {
      s.images.views = 0;
      s.images.fail_at = 2;
      s.images.failure = Status::kDataLoss;
    }
    ASSERT_EQ(explore(s, p, &step), Status::kOk);
    s.images.fail_at = 0xFFFFFFFFu;
    if (p == kFirstPass + 2) break;
  }
  ASSERT_EQ(step.decision.kind, LoopClosureClass::kClosure);
  EXPECT_EQ(step.align_status, Status::kDataLoss);
  EXPECT_EQ(step.closure_to, answer(p).place);  // the matched place, same position
  EXPECT_EQ(step.closure.dx.raw(), 0);
  EXPECT_EQ(step.heading_status, Status::kOk);  // the heading's reads came after the failure
  EXPECT_EQ(s.explorer.stats().align_failures, 1u);
  EXPECT_EQ(s.explorer.stats().closures, 1u);
}

// The reference map: every reading inserted by the grid itself at the pose it should hang from.
struct Reference {
  OccupancyGridStorage<3> ram;
  test::RamTileStore<8> tiles;
  OccupancyGrid grid;
};
Reference g_reference;

constexpr uint16_t kReadings[kMyonInfraredCount] = {900, 1200, 0, 700, 650, 0};

TEST(Explorer, SnapshotsHangFromTheLastPlaceAndTheRebuildUsesTheOptimisedPoses) {
  Scene& s = g_scene;
  build(s);
  Reference& r = g_reference;
  r.tiles.reset();
  ASSERT_EQ(r.grid.configure(config().grid, r.ram.buffers(), r.tiles), Status::kOk);
  const RelativePose2 ahead{Q31_32::from_ratio(1, 10), Q31_32{}, Angle{}};
  const Span<const uint16_t> readings(kReadings);
  // Before the first place the snapshot is at the odometry itself; then half-way to the next.
  ASSERT_EQ(s.explorer.scan(Pose2{}, readings), Status::kOk);
  for (uint32_t k = 0; k < kMyonInfraredCount; ++k)
    (void)r.grid.insert_reading(Pose2{}, kMyonInfrared[k], kReadings[k]);
  for (uint32_t p = 0; p < kPlaces; ++p) {
    ExplorerStep step;
    ASSERT_EQ(explore(s, p, &step), Status::kOk);
    if (p != 5) continue;
    const Pose2 odo = compose(s.odometry[p], ahead);
    ASSERT_EQ(s.explorer.scan(odo, readings), Status::kOk);
    const Pose2 at = compose(s.explorer.graph().pose(p).value(), relative_pose(s.odometry[p], odo));
    for (uint32_t k = 0; k < kMyonInfraredCount; ++k)
      (void)r.grid.insert_reading(at, kMyonInfrared[k], kReadings[k]);
  }
  int8_t x[kGridTileCells], y[kGridTileCells];
  for (uint16_t t = 0; t < kTilesX * kTilesY; ++t) {
    const GridTile tile{static_cast<uint16_t>(t % kTilesX), static_cast<uint16_t>(t / kTilesX)};
    ASSERT_EQ(s.explorer.grid().copy_tile(tile, Span<int8_t>(x)), Status::kOk);
    ASSERT_EQ(r.grid.copy_tile(tile, Span<int8_t>(y)), Status::kOk);
    for (uint32_t i = 0; i < kGridTileCells; ++i)
      ASSERT_EQ(x[i], y[i]) << "tile " << t << " cell " << i;
  }
  EXPECT_EQ(s.explorer.stats().scans, 2u);

  // After the solve the closures have moved the second pass: the rebuild hangs the snapshot
  // of place 75 from its optimised pose (and none from place 5 this time).
  ASSERT_EQ(s.explorer.finish(100000), Status::kOk);
  ASSERT_EQ(r.grid.clear(), Status::kOk);
  ASSERT_EQ(s.explorer.begin_rebuild(), Status::kOk);
  for (uint32_t p = 0; p < kPlaces; ++p) {
    s.explorer.rebuild_place(p, s.odometry[p]);
    if (p != 75) continue;
    const Pose2 odo = compose(s.odometry[p], ahead);
    ASSERT_EQ(s.explorer.scan(odo, readings), Status::kOk);
    const Pose2 at = compose(s.explorer.graph().pose(p).value(), relative_pose(s.odometry[p], odo));
    for (uint32_t k = 0; k < kMyonInfraredCount; ++k)
      (void)r.grid.insert_reading(at, kMyonInfrared[k], kReadings[k]);
  }
  s.explorer.end_rebuild();
  EXPECT_EQ(s.explorer.stats().rebuild_places, kPlaces);
  EXPECT_EQ(s.explorer.stats().rebuild_scans, 1u);
  EXPECT_NE(s.explorer.graph().pose(75).value().y.raw(), s.odometry[75].y.raw());  // it moved
  for (uint16_t t = 0; t < kTilesX * kTilesY; ++t) {
    const GridTile tile{static_cast<uint16_t>(t % kTilesX), static_cast<uint16_t>(t / kTilesX)};
    ASSERT_EQ(s.explorer.grid().copy_tile(tile, Span<int8_t>(x)), Status::kOk);
    ASSERT_EQ(r.grid.copy_tile(tile, Span<int8_t>(y)), Status::kOk);
    for (uint32_t i = 0; i < kGridTileCells; ++i)
      ASSERT_EQ(x[i], y[i]) << "tile " << t << " cell " << i;
  }
  EXPECT_EQ(s.explorer.flush_map(), Status::kOk);
  EXPECT_GT(s.tiles.used, 0u);
}

TEST(Explorer, AFullGraphStopsTheClosuresNotTheRun) {
  Scene& s = g_scene;
  build(s, kFirstPass + 5);
  uint32_t closures_before_full = 0;
  for (uint32_t p = 0; p < kPlaces; ++p) {
    ExplorerStep step;
    ASSERT_EQ(explore(s, p, &step), Status::kOk);
    if (p < kFirstPass + 5) {
      EXPECT_EQ(step.node, static_cast<int32_t>(p));
      closures_before_full += step.closure_to >= 0 ? 1 : 0;
    } else {
      EXPECT_EQ(step.node, -1);
      EXPECT_EQ(step.closure_to, -1);
    }
  }
  EXPECT_EQ(s.explorer.stats().graph_full, kSecondPass - 5);
  EXPECT_EQ(s.explorer.stats().nodes, kFirstPass + 5);
  EXPECT_EQ(s.explorer.stats().closures, closures_before_full);
  EXPECT_EQ(closures_before_full, 3u);
}

TEST(Explorer, RefusesBadSettings) {
  Scene& s = g_scene;
  Explorer e;
  ExplorerStep step;
  EXPECT_EQ(e.place(s.library, Span<const uint32_t>(), Match{}, Pose2{}, 0, &step),
            Status::kFailedPrecondition);
  EXPECT_EQ(e.scan(Pose2{}, Span<const uint16_t>()), Status::kFailedPrecondition);
  EXPECT_EQ(e.finish(1), Status::kFailedPrecondition);
  struct Case {
    void (*change)(ExplorerConfig*);
    ExplorerIssue issue;
  };
  const Case cases[] = {
      {[](ExplorerConfig* c) { c->gate.confirm = 0; }, ExplorerIssue::kGate},
      {[](ExplorerConfig* c) { c->graph.max_restarts = 0; }, ExplorerIssue::kGraph},
      {[](ExplorerConfig* c) { c->grid.cell_mm = 5; }, ExplorerIssue::kGrid},
      {[](ExplorerConfig* c) { c->align.length = kMaxAlignLength + 1; }, ExplorerIssue::kAlign},
      {[](ExplorerConfig* c) { c->align.max_offset = kMaxAlignOffset + 1; }, ExplorerIssue::kAlign},
      {[](ExplorerConfig* c) { c->max_shift = kMaxSubpixelShift + 1; }, ExplorerIssue::kHeading},
      {[](ExplorerConfig* c) { c->hfov = Angle{}; }, ExplorerIssue::kHeading},
      {[](ExplorerConfig* c) { c->optimise_budget = 0; }, ExplorerIssue::kBudget},
      {[](ExplorerConfig* c) { c->spacing = Q31_32{}; }, ExplorerIssue::kSpacing},
      {[](ExplorerConfig* c) { c->spacing = Q31_32::from_int(1001); }, ExplorerIssue::kSpacing},
  };
  for (const Case& c : cases) {
    ExplorerConfig bad = config();
    c.change(&bad);
    const ExplorerCheck check = e.configure(bad, buffers(s));
    EXPECT_FALSE(check.ok());
    EXPECT_EQ(check.issue, c.issue);
  }
  ExplorerConfig bad_grid = config();
  bad_grid.grid.cell_mm = 5;
  EXPECT_EQ(e.configure(bad_grid, buffers(s)).grid_issue, GridIssue::kCellSizeOutOfRange);
  // Without a tile store there is no map: snapshots are accepted and ignored.
  ExplorerBuffers no_map = buffers(s);
  no_map.tiles = nullptr;
  ASSERT_TRUE(e.configure(config(), no_map).ok());
  EXPECT_FALSE(e.has_map());
  EXPECT_EQ(e.scan(Pose2{}, Span<const uint16_t>(kReadings)), Status::kOk);
  EXPECT_EQ(e.stats().scans, 0u);
  EXPECT_EQ(e.place(s.library, Span<const uint32_t>(), Match{}, Pose2{}, 0, nullptr),
            Status::kInvalidArgument);
}

// Continuing a stopped run (state_io.h): an explorer saved in the middle of the second pass,
// with closures made and the optimiser in the middle of a stage (a small budget per place),
// and restored into another explorer, gives the same graph, estimates and counters as the
// run that never stopped. Around the stops come places without a match, over which the
// optimiser carries its stage from place to place (so a stop falls inside its conjugate-
// gradient iterations, and the restored optimiser state is used, not only the graph), then
// closures again. Every place of that stretch is tried as the stop, so the stop falls in
// every phase of an iteration.
constexpr uint32_t kLost = kFirstPass + 8;    // the matcher has no answer from here ...
constexpr uint32_t kFound = kFirstPass + 20;  // ... to here

void continue_from(Scene& s, uint32_t stop) {
  build(s);
  ExplorerConfig c = config();
  c.optimise_budget = 40;  // far less than a solve: every stage spans several places
  ASSERT_TRUE(s.explorer.configure(c, buffers(s)).ok());
  ExplorerStep step;
  for (uint32_t p = 0; p < stop; ++p) {
    ASSERT_EQ(explore(s, p, &step, nullptr, p >= kLost && p < kFound), Status::kOk);
  }
  ASSERT_GT(s.explorer.stats().closures, 0u);
  s.saved.truncate(0);
  StateOut out(s.saved);
  s.explorer.state(out);
  ASSERT_EQ(out.status(), Status::kOk);
  EXPECT_EQ(out.bytes(), s.saved.size());

  ExplorerBuffers b2 = buffers(s);
  b2.graph = s.graph2.buffers();
  b2.grid = s.grid2.buffers();
  b2.tiles = &s.tiles2;
  ASSERT_TRUE(s.resumed.configure(c, b2).ok());
  StateIn in(s.saved);
  s.resumed.state(in);
  ASSERT_EQ(in.status(), Status::kOk);
  EXPECT_EQ(s.resumed.graph().node_count(), stop);

  for (uint32_t p = stop; p < kPlaces; ++p) {
    ExplorerStep a, r;
    const bool lost = p >= kLost && p < kFound;
    ASSERT_EQ(explore(s, p, &a, nullptr, lost), Status::kOk);
    ASSERT_EQ(explore(s, p, &r, &s.resumed, lost), Status::kOk);
    EXPECT_EQ(r.decision.kind, a.decision.kind) << "place " << p;
    EXPECT_EQ(r.closure_to, a.closure_to) << "place " << p;
    EXPECT_EQ(r.progress.work, a.progress.work) << "place " << p;
    EXPECT_EQ(r.progress.stage, a.progress.stage) << "place " << p;
  }
  ASSERT_EQ(s.explorer.finish(100000), Status::kOk);
  ASSERT_EQ(s.resumed.finish(100000), Status::kOk);
  const PoseGraph& g = s.explorer.graph();
  const PoseGraph& h = s.resumed.graph();
  ASSERT_EQ(h.node_count(), g.node_count());
  ASSERT_EQ(h.edge_count(), g.edge_count());
  for (uint32_t i = 0; i < g.node_count(); ++i) {
    EXPECT_EQ(h.pose(i).value().x.raw(), g.pose(i).value().x.raw()) << "node " << i;
    EXPECT_EQ(h.pose(i).value().y.raw(), g.pose(i).value().y.raw()) << "node " << i;
    EXPECT_EQ(h.pose(i).value().heading.bam, g.pose(i).value().heading.bam) << "node " << i;
  }
  for (uint32_t i = 0; i < g.edge_count(); ++i) {
    EXPECT_EQ(h.edge(i).value().to, g.edge(i).value().to) << "edge " << i;
    EXPECT_EQ(h.edge(i).value().dx.raw(), g.edge(i).value().dx.raw()) << "edge " << i;
  }
  EXPECT_EQ(s.resumed.stats().closures, s.explorer.stats().closures);
  EXPECT_EQ(s.resumed.stats().optimise_work, s.explorer.stats().optimise_work);
  EXPECT_EQ(s.resumed.stats().final_slices, s.explorer.stats().final_slices);
  EXPECT_EQ(h.stats().iterations, g.stats().iterations);
  EXPECT_EQ(h.stats().restarts, g.stats().restarts);
  const auto closure = static_cast<uint32_t>(LoopClosureClass::kClosure);
  EXPECT_EQ(s.resumed.gate().stats().decisions[closure],
            s.explorer.gate().stats().decisions[closure]);
}

TEST(Explorer, ContinuesExactlyFromASavedState) {
  for (uint32_t stop = kLost + 1; stop < kFound; ++stop) {
    continue_from(g_scene, stop);
    if (::testing::Test::HasFailure()) {
      ADD_FAILURE() << "with the stop at place " << stop;
      return;
    }
  }
}

// A saved state that is cut short, damaged, or larger than the explorer's buffers is refused
// with kDataLoss and leaves an empty run, never a partial one; a state cannot be saved while
// the map is being rebuilt.
TEST(Explorer, RefusesADamagedOrForeignState) {
  Scene& s = g_scene;
  build(s);
  ExplorerStep step;
  for (uint32_t p = 0; p < kFirstPass + 12; ++p)
    ASSERT_EQ(explore(s, p, &step), Status::kOk);
  s.saved.truncate(0);
  StateOut out(s.saved);
  s.explorer.state(out);
  ASSERT_EQ(out.status(), Status::kOk);
  const uint32_t full = s.saved.size();

  ExplorerBuffers b2 = buffers(s);
  b2.graph = s.graph2.buffers();
  b2.grid = s.grid2.buffers();
  b2.tiles = &s.tiles2;
  const uint32_t cuts[] = {0, 3, full / 2, full - 1};
  for (const uint32_t cut : cuts) {
    ASSERT_TRUE(s.resumed.configure(config(), b2).ok());
    s.saved.truncate(cut);
    StateIn in(s.saved);
    s.resumed.state(in);
    EXPECT_EQ(in.status(), Status::kDataLoss) << "cut at " << cut;
    EXPECT_EQ(s.resumed.graph().node_count(), 0u) << "cut at " << cut;
    s.saved.truncate(0);
    StateOut again(s.saved);
    s.explorer.state(again);
  }
  // A damaged section tag: the graph's.
  uint32_t tag_at = 0;
  while (tag_at + 4 <= full &&
         !(s.saved.bytes[tag_at] == 'P' && s.saved.bytes[tag_at + 1] == 'G' &&
           s.saved.bytes[tag_at + 2] == 'R' && s.saved.bytes[tag_at + 3] == '4'))
    ++tag_at;
  ASSERT_LT(tag_at + 4, full);
  ASSERT_TRUE(s.resumed.configure(config(), b2).ok());
  s.saved.bytes[tag_at] ^= 0x01;
  s.saved.rewind();
  StateIn damaged(s.saved);
  s.resumed.state(damaged);
  EXPECT_EQ(damaged.status(), Status::kDataLoss);
  EXPECT_EQ(s.resumed.graph().node_count(), 0u);
  s.saved.bytes[tag_at] ^= 0x01;
  // A graph of 40 nodes cannot take a state of 72.
  ExplorerBuffers small = b2;
  small.graph.nodes = small.graph.nodes.subspan(0, 40);
  small.graph.solver = small.graph.solver.subspan(0, 40);
  ASSERT_TRUE(s.resumed.configure(config(), small).ok());
  s.saved.rewind();
  StateIn foreign(s.saved);
  s.resumed.state(foreign);
  EXPECT_EQ(foreign.status(), Status::kDataLoss);
  EXPECT_EQ(s.resumed.graph().node_count(), 0u);
  // Not while rebuilding.
  ASSERT_EQ(s.explorer.begin_rebuild(), Status::kOk);
  s.saved.truncate(0);
  StateOut rebuilding(s.saved);
  s.explorer.state(rebuilding);
  EXPECT_EQ(rebuilding.status(), Status::kFailedPrecondition);
  s.explorer.end_rebuild();
}

}  // namespace
}  // namespace seqslam
