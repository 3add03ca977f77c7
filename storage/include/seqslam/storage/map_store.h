// The mapping outputs of the firmware's explore mode on the volume (docs/firmware.md,
// "Explore"): the occupancy grid's tiles and the pose graph. Both are record logs
// (record_log.h) like every other seqslam file: a header with kind, version and checksum,
// records with a CRC each, so a damaged, cut or foreign file is recognised, never misread.
//
// Map tiles (`map`, kind SQMAPTL1): the header holds the grid's configuration (frame, cell
// size, bounds, log-odds settings); each record is one tile (u16 x, u16 y, 1024 int8 log-odds
// cells, layout of occupancy_grid.h). MapStore is the OccupancyGrid's TileStore on the card:
// a save appends the tile, a load reads the tile's latest record back (random access through
// a RAM index of tile -> record offset, a few bytes a tile; the cells themselves never stay
// in RAM), clear() starts a new session of the log (the records of older sessions are then
// invisible to every reader: the lazy clear occupancy_grid.h asks for). The latest record of
// a tile in the file's last session is the tile's content.
//
// Graph (`graph`, kind SQGRAPH1, version 2): the file is two slots, its first and second half,
// each a graph log: the header holds the counts and a generation; then one record per node in
// index order (place, estimated pose) and one per edge (odometry edges first, node k-1 to k,
// then the loop closures in the order added), as PoseGraph::edge() lists them. A graph is
// written into the slot that does not hold the newest complete graph, with the next
// generation, and read from the slot whose complete graph is newest: a card that fails while
// a graph is written (a power cut) keeps the previous graph readable. (Version 1, before
// issue 15, was one log over the whole file: it is refused as another version.)
#pragma once

#include <stdint.h>

#include "seqslam/hal/block_device.h"
#include "seqslam/occupancy_grid.h"
#include "seqslam/pose_graph.h"
#include "seqslam/span.h"
#include "seqslam/storage/record_log.h"
#include "seqslam/storage/volume.h"

namespace seqslam::storage {

inline constexpr LogKind kMapKind{{'S', 'Q', 'M', 'A', 'P', 'T', 'L', '1'}, 1};
inline constexpr LogKind kGraphKind{{'S', 'Q', 'G', 'R', 'A', 'P', 'H', '1'}, 2};

inline constexpr const char* kMapFile = "map";
inline constexpr const char* kGraphFile = "graph";

// A tile record's payload: tile x, tile y, the cells.
inline constexpr uint32_t kMapTilePayload = 4 + kGridTileCells;
// Buffer MapStore::open needs to walk an existing map log.
inline constexpr uint32_t kMapReadBuffer = kRecordOverhead + kMapTilePayload;

// What is wrong with a map or graph file (map_problem_text gives the sentence).
enum class MapProblem : uint8_t {
  kNone = 0,
  kLog,          // see log_problem(): device error, wrong kind, version, damaged header
  kBadHeader,    // header fields out of range (grid settings, counts)
  kBadRecord,    // a record of an unknown type, size, order or content (tile outside the grid,
                 // an edge to a missing node)
  kDamaged,      // a damaged record in the middle, or the file ends in a damaged record
  kTruncated,    // fewer records than the header announces (graph)
  kExtraRecord,  // more records than the header announces (graph)
  kIndexFull,    // more distinct tiles than the caller's index holds
};
const char* map_problem_text(MapProblem p);

// One entry of MapStore's RAM index: where the latest record of tile (x, y) starts.
struct MapTileIndexEntry {
  uint16_t x = 0;
  uint16_t y = 0;
  uint32_t offset =
      0;  // byte offset in the map file (records start at kFirstRecordOffset or later)
};
static_assert(sizeof(MapTileIndexEntry) == 8, "map index budget: 8 bytes a tile");

class MapStore final : public TileStore {
 public:
  // Starts an empty map log on `device` for a grid of `grid` (check_grid_config must pass;
  // else kInvalidArgument with kBadHeader). `index` (caller-owned) bounds the distinct tiles
  // the map can hold. Statuses of LogWriter::create (kLog).
  Status create(hal::BlockDevice& device, const GridConfig& grid, Span<MapTileIndexEntry> index,
                MapProblem* problem = nullptr);

  // Opens an existing map log read-only (a reload): checks the header (into *grid), walks the
  // last session's records with `buffer` (>= kMapReadBuffer bytes) and indexes the latest
  // record of every tile. Returns
  //   log statuses (kLog: kDataLoss for a wrong kind or damaged header, kFailedPrecondition
  //                for another version, device errors);
  //   kDataLoss          - kBadHeader, kBadRecord, kDamaged (a damaged record anywhere, or
  //                        committed records missing): the file is not what was written;
  //   kResourceExhausted - kIndexFull;
  //   kInvalidArgument   - a buffer smaller than kMapReadBuffer or a null `grid`.
  // On any failure the store is unusable (loads fail with kFailedPrecondition). A damaged
  // tail (the tile record a power cut interrupted) is no failure: the map is the records
  // before it, and log_problem() says kEndDamagedTail.
  Status open(hal::BlockDevice& device, Span<MapTileIndexEntry> index, Span<uint8_t> buffer,
              GridConfig* grid, MapProblem* problem = nullptr);

  // Distinct tiles in the map.
  uint32_t tile_count() const { return tiles_; }
  // Tile records appended since create() (saves; a tile may be saved several times).
  uint32_t records_written() const { return writer_.records(); }
  bool writable() const { return writable_; }
  const GridConfig& grid() const { return grid_; }
  LogProblem log_problem() const { return log_problem_; }
  // Index entry i < tile_count() (export: which tiles exist).
  const MapTileIndexEntry& entry(uint32_t i) const { return index_[i]; }

 private:
  Status do_load(GridTile tile, Span<int8_t> cells) override;
  Status do_save(GridTile tile, Span<const int8_t> cells) override;
  Status do_clear() override;
  int32_t find(GridTile tile) const;

  hal::BlockDevice* device_ = nullptr;
  Span<MapTileIndexEntry> index_{};
  GridConfig grid_{};
  uint32_t tiles_ = 0;
  bool open_ = false;
  bool writable_ = false;
  LogProblem log_problem_ = LogProblem::kNone;
  LogWriter writer_{};
  LogReader reader_{};
};

// The graph file's header.
struct GraphFileHeader {
  uint32_t nodes = 0;
  uint32_t edges = 0;  // odometry edges (nodes - 1) + closures
  uint32_t closures = 0;
  bool converged = false;   // the estimates solved the graph when it was written
  uint32_t generation = 0;  // 1 for the file's first graph, one more for each rewrite
};

struct GraphFileNode {
  uint32_t index = 0;
  uint32_t place = 0;
  Pose2 pose{};  // the estimate when written
};

// Writes `graph` (every node's current estimate and every edge) into the slot of `device`
// that does not hold the newest complete graph (see the top of this file). Log statuses
// (kResourceExhausted when the slot, half the file, is full).
Status write_graph(hal::BlockDevice& device, const PoseGraph& graph, LogProblem* problem = nullptr);

// Reads a graph file back, checking it record by record: open(), then next_node() for
// header().nodes nodes, then next_edge() for header().edges edges, then finish().
class GraphReader {
 public:
  // Opens the newest complete graph of the two slots (each is read through once to know).
  // Without one: the problem of the slot whose header is newest (or of the first slot), with
  // its status: log statuses (kLog); kDataLoss (kBadHeader) for counts that do not fit a
  // PoseGraph or disagree (edges != nodes - 1 + closures); kDataLoss (kTruncated, kDamaged,
  // kBadRecord, kExtraRecord) for a graph that is not whole.
  Status open(hal::BlockDevice& device, MapProblem* problem = nullptr);
  const GraphFileHeader& header() const { return header_; }
  // The next node / edge. kDataLoss with problem(): kDamaged, kTruncated, kBadRecord (out of
  // order, an edge whose nodes do not exist or that is not the expected odometry edge);
  // kFailedPrecondition when called out of turn. Nothing is written to *out on failure.
  Status next_node(GraphFileNode* out);
  Status next_edge(PoseGraphEdge* out, bool* closure);
  // After the last edge: kOk if the file ends cleanly there, kDataLoss (kExtraRecord,
  // kDamaged) otherwise.
  Status finish();
  MapProblem problem() const { return problem_; }
  LogProblem log_problem() const { return reader_.end_problem(); }
  // The slot the graph was read from (0: the file's first half, 1: its second).
  uint32_t slot() const { return slot_index_; }

 private:
  Status open_slot(hal::BlockDevice& slot);
  Status read_whole();
  Status read(uint8_t type, uint32_t size, const uint8_t** payload);
  Status fail(MapProblem p);

  Region slot_{};
  LogReader reader_{};
  GraphFileHeader header_{};
  uint32_t nodes_read_ = 0;
  uint32_t edges_read_ = 0;
  uint32_t slot_index_ = 0;
  MapProblem problem_ = MapProblem::kNone;
  bool open_ = false;
  uint8_t buffer_[kRecordOverhead + 40] = {};
};

}  // namespace seqslam::storage
