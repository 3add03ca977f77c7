#include "seqslam/storage/map_store.h"

#include "codec.h"
#include "seqslam/messages.h"
#include "seqslam/storage/bytes.h"

namespace seqslam::storage {

namespace {

constexpr uint8_t kTileRecord = 1;
constexpr uint8_t kNodeRecord = 1;
constexpr uint8_t kEdgeRecord = 2;
constexpr uint32_t kGridHeaderBytes = 28;
constexpr uint32_t kGraphHeaderBytes = 20;
constexpr uint32_t kNodeBytes = 28;
constexpr uint32_t kEdgeBytes = 28;

Status fail(MapProblem* problem, MapProblem p, Status s) {
  if (problem != nullptr) *problem = p;
  return s;
}

uint32_t encode_grid(const GridConfig& g, uint8_t* out, uint32_t capacity) {
  ByteWriter w(out, capacity);
  w.i64(g.origin_x.raw());
  w.i64(g.origin_y.raw());
  w.u16(g.cell_mm);
  w.u16(g.width);
  w.u16(g.height);
  w.u8(static_cast<uint8_t>(g.hit));
  w.u8(static_cast<uint8_t>(g.miss));
  w.u8(static_cast<uint8_t>(g.limit));
  w.u8(static_cast<uint8_t>(g.occupied_threshold));
  w.u8(static_cast<uint8_t>(g.free_threshold));
  w.u8(0);
  return w.ok() ? static_cast<uint32_t>(w.position()) : 0;
}

bool decode_grid(const uint8_t* data, uint32_t size, GridConfig* out) {
  if (size != kGridHeaderBytes) return false;
  ByteReader r(data, size);
  GridConfig g;
  g.origin_x = Q31_32::from_raw(r.i64());
  g.origin_y = Q31_32::from_raw(r.i64());
  g.cell_mm = r.u16();
  g.width = r.u16();
  g.height = r.u16();
  g.hit = static_cast<int8_t>(r.u8());
  g.miss = static_cast<int8_t>(r.u8());
  g.limit = static_cast<int8_t>(r.u8());
  g.occupied_threshold = static_cast<int8_t>(r.u8());
  g.free_threshold = static_cast<int8_t>(r.u8());
  if (!r.ok() || check_grid_config(g) != Status::kOk) return false;
  *out = g;
  return true;
}

uint32_t tiles_along(uint16_t cells) {
  return (static_cast<uint32_t>(cells) + kGridTileSide - 1) >> kGridTileShift;
}

}  // namespace

const char* map_problem_text(MapProblem p) {
#if !SEQSLAM_MESSAGE_TEXTS
  return message_code("MP", static_cast<uint32_t>(p));
#endif
  switch (p) {
    case MapProblem::kNone:
      return "ok";
    case MapProblem::kLog:
      return "not a readable log of this kind (see the log problem)";
    case MapProblem::kBadHeader:
      return "header settings out of range";
    case MapProblem::kBadRecord:
      return "a record of an unknown type, size, order or content";
    case MapProblem::kDamaged:
      return "a damaged record (checksum or length), or a damaged end";
    case MapProblem::kTruncated:
      return "fewer records than the header announces (cut short)";
    case MapProblem::kExtraRecord:
      return "more records than the header announces";
    case MapProblem::kIndexFull:
      return "more distinct tiles than the index holds";
  }
  return "unknown map problem";
}

// ---------------------------------------------------------------------------------------
// Tiles

Status MapStore::create(hal::BlockDevice& device, const GridConfig& grid,
                        Span<MapTileIndexEntry> index, MapProblem* problem) {
  open_ = false;
  writable_ = false;
  if (check_grid_config(grid) != Status::kOk || index.empty()) {
    return fail(problem, MapProblem::kBadHeader, Status::kInvalidArgument);
  }
  device_ = &device;
  index_ = index;
  grid_ = grid;
  const Status s = do_clear();
  return fail(problem, s == Status::kOk ? MapProblem::kNone : MapProblem::kLog, s);
}

Status MapStore::do_clear() {
  if (device_ == nullptr || (open_ && !writable_)) return Status::kFailedPrecondition;
  open_ = false;
  tiles_ = 0;
  uint8_t header[kGridHeaderBytes];
  const uint32_t size = encode_grid(grid_, header, sizeof header);
  // A new session: what the earlier sessions wrote is invisible to readers from now on.
  Status s = writer_.create(*device_, kMapKind, header, size, &log_problem_);
  if (s == Status::kOk) {
    s = reader_.open(*device_, kMapKind, nullptr, 0, nullptr, Span<uint8_t>(), &log_problem_);
  }
  if (s != Status::kOk) return s;
  open_ = true;
  writable_ = true;
  return Status::kOk;
}

Status MapStore::open(hal::BlockDevice& device, Span<MapTileIndexEntry> index, Span<uint8_t> buffer,
                      GridConfig* grid, MapProblem* problem) {
  open_ = false;
  writable_ = false;
  tiles_ = 0;
  if (grid == nullptr || buffer.size() < kMapReadBuffer) {
    return fail(problem, MapProblem::kNone, Status::kInvalidArgument);
  }
  uint8_t header[kGridHeaderBytes];
  uint32_t size = 0;
  Status s = reader_.open(device, kMapKind, header, sizeof header, &size, buffer, &log_problem_);
  if (s != Status::kOk) return fail(problem, MapProblem::kLog, s);
  GridConfig g;
  if (!decode_grid(header, size, &g)) {
    return fail(problem, MapProblem::kBadHeader, Status::kDataLoss);
  }
  device_ = &device;
  index_ = index;
  grid_ = g;
  const uint32_t tiles_x = tiles_along(g.width);
  const uint32_t tiles_y = tiles_along(g.height);
  for (;;) {
    RecordView v;
    s = reader_.next(&v);
    if (s == Status::kOutOfRange) break;
    if (s == Status::kDataLoss) return fail(problem, MapProblem::kDamaged, s);
    if (s == Status::kResourceExhausted) {
      return fail(problem, MapProblem::kBadRecord, Status::kDataLoss);
    }
    if (s != Status::kOk) return fail(problem, MapProblem::kLog, s);
    if (v.type != kTileRecord || v.payload_size != kMapTilePayload) {
      return fail(problem, MapProblem::kBadRecord, Status::kDataLoss);
    }
    ByteReader r(v.payload, 4);
    GridTile t;
    t.x = r.u16();
    t.y = r.u16();
    if (t.x >= tiles_x || t.y >= tiles_y) {
      return fail(problem, MapProblem::kBadRecord, Status::kDataLoss);
    }
    int32_t i = find(t);
    if (i < 0) {
      if (tiles_ >= index_.size()) {
        return fail(problem, MapProblem::kIndexFull, Status::kResourceExhausted);
      }
      i = static_cast<int32_t>(tiles_++);
      index_[static_cast<uint32_t>(i)].x = t.x;
      index_[static_cast<uint32_t>(i)].y = t.y;
    }
    index_[static_cast<uint32_t>(i)].offset = static_cast<uint32_t>(v.offset);
  }
  log_problem_ = reader_.end_problem();
  // A damaged tail is the one tile record a power cut interrupted (past the last commit, so
  // never a saved tile): the map is every save completed before it, as a recording or a
  // library keeps its records before a damaged tail. Refusing it lost the whole map to a cut
  // during any tile write (tests/host/test_power_loss_map.cpp).
  if (log_problem_ != LogProblem::kEndClean && log_problem_ != LogProblem::kEndDamagedTail) {
    return fail(problem, MapProblem::kDamaged, Status::kDataLoss);
  }
  *grid = g;
  open_ = true;
  return fail(problem, MapProblem::kNone, Status::kOk);
}

int32_t MapStore::find(GridTile tile) const {
  for (uint32_t i = 0; i < tiles_; ++i) {
    if (index_[i].x == tile.x && index_[i].y == tile.y) return static_cast<int32_t>(i);
  }
  return -1;
}

Status MapStore::do_load(GridTile tile, Span<int8_t> cells) {
  if (!open_) return Status::kFailedPrecondition;
  const int32_t i = find(tile);
  if (i < 0) return Status::kNotFound;
  uint8_t coords[4];
  uint8_t type = 0;
  const Status s =
      reader_.read_at(index_[static_cast<uint32_t>(i)].offset, &type, Span<uint8_t>(coords, 4),
                      Span<uint8_t>(reinterpret_cast<uint8_t*>(cells.data()), cells.size()));
  if (s != Status::kOk) return s;
  ByteReader r(coords, sizeof coords);
  const uint16_t x = r.u16();
  const uint16_t y = r.u16();
  if (type != kTileRecord || x != tile.x || y != tile.y) return Status::kDataLoss;
  return Status::kOk;
}

Status MapStore::do_save(GridTile tile, Span<const int8_t> cells) {
  if (!open_ || !writable_) return Status::kFailedPrecondition;
  int32_t i = find(tile);
  if (i < 0 && tiles_ >= index_.size()) return Status::kResourceExhausted;
  const uint64_t at = writer_.end_offset();
  uint8_t coords[4];
  ByteWriter w(coords, sizeof coords);
  w.u16(tile.x);
  w.u16(tile.y);
  const ByteSpan parts[2] = {{coords, sizeof coords},
                             {reinterpret_cast<const uint8_t*>(cells.data()), cells.size()}};
  SEQSLAM_TRY(writer_.append(kTileRecord, parts, 2, &log_problem_));
  if (i < 0) {
    i = static_cast<int32_t>(tiles_++);
    index_[static_cast<uint32_t>(i)].x = tile.x;
    index_[static_cast<uint32_t>(i)].y = tile.y;
  }
  index_[static_cast<uint32_t>(i)].offset = static_cast<uint32_t>(at);
  return Status::kOk;
}

// ---------------------------------------------------------------------------------------
// Graph

namespace {

// The file's two slots: its first and second half.
Region graph_slot(hal::BlockDevice& device, uint32_t slot) {
  const uint32_t half = device.block_count() / 2;
  return Region(device, slot * half, half);
}

}  // namespace

Status write_graph(hal::BlockDevice& device, const PoseGraph& graph, LogProblem* problem) {
  // Into the slot that does not hold the newest complete graph, one generation above it.
  uint32_t target = 0;
  uint32_t generation = 1;
  GraphReader current;
  if (current.open(device) == Status::kOk) {
    target = 1 - current.slot();
    generation = current.header().generation + 1;
  }
  Region slot = graph_slot(device, target);
  const uint32_t nodes = graph.node_count();
  const uint32_t edges = graph.edge_count();
  uint8_t header[kGraphHeaderBytes];
  ByteWriter h(header, sizeof header);
  h.u32(nodes);
  h.u32(edges);
  h.u32(graph.closure_count());
  h.u8(graph.converged() ? 1 : 0);
  h.zeros(3);
  h.u32(generation);
  LogWriter log;
  Status s = log.create(slot, kGraphKind, header, kGraphHeaderBytes, problem);
  for (uint32_t i = 0; i < nodes && s == Status::kOk; ++i) {
    uint8_t buf[kNodeBytes];
    ByteWriter w(buf, sizeof buf);
    w.u32(i);
    w.u32(graph.place(i).value());
    codec::put_pose(w, graph.pose(i).value());
    const ByteSpan part{buf, w.position()};
    s = log.append(kNodeRecord, &part, 1, problem);
  }
  for (uint32_t i = 0; i < edges && s == Status::kOk; ++i) {
    const PoseGraphEdge e = graph.edge(i).value();
    uint8_t buf[kEdgeBytes];
    ByteWriter w(buf, sizeof buf);
    w.u16(e.from);
    w.u16(e.to);
    w.i32(e.dx.raw());
    w.i32(e.dy.raw());
    w.u32(e.dtheta.bam);
    w.u32(e.info_xy.raw());
    w.u32(e.info_heading.raw());
    w.u8(i + 1 >= nodes ? 1 : 0);  // closures follow the nodes - 1 odometry edges
    w.zeros(3);
    const ByteSpan part{buf, w.position()};
    s = log.append(kEdgeRecord, &part, 1, problem);
  }
  return s;
}

Status GraphReader::fail(MapProblem p) {
  problem_ = p;
  return Status::kDataLoss;
}

Status GraphReader::open(hal::BlockDevice& device, MapProblem* problem) {
  // Each slot read through: the newest whole graph wins. Failing that, the problem of the
  // slot whose header is newest (the graph being written when the card failed), or of the
  // first slot.
  int32_t best = -1;
  uint32_t best_generation = 0;
  int32_t blamed = -1;
  uint32_t blamed_generation = 0;
  Status blamed_status = Status::kOk;
  MapProblem blamed_problem = MapProblem::kNone;
  for (uint32_t k = 0; k < 2; ++k) {
    slot_ = graph_slot(device, k);
    const Status s = read_whole();
    const bool has_header = open_;
    const uint32_t generation = header_.generation;
    if (s == Status::kOk && (best < 0 || generation > best_generation)) {
      best = static_cast<int32_t>(k);
      best_generation = generation;
    } else if (s != Status::kOk && (blamed < 0 || (has_header && generation > blamed_generation))) {
      blamed = static_cast<int32_t>(k);
      blamed_generation = has_header ? generation : 0;
      blamed_status = s;
      blamed_problem = problem_;
    }
  }
  Status s = Status::kOk;
  if (best >= 0) {
    slot_ = graph_slot(device, static_cast<uint32_t>(best));
    slot_index_ = static_cast<uint32_t>(best);
    s = open_slot(slot_);
  } else {
    open_ = false;
    problem_ = blamed_problem;
    s = blamed_status;
  }
  if (problem != nullptr) *problem = problem_;
  return s;
}

// Reads the current slot's graph to its end (open_slot, every record, finish).
Status GraphReader::read_whole() {
  Status s = open_slot(slot_);
  for (uint32_t i = 0; s == Status::kOk && i < header_.nodes; ++i) {
    GraphFileNode n;
    s = next_node(&n);
  }
  for (uint32_t i = 0; s == Status::kOk && i < header_.edges; ++i) {
    PoseGraphEdge e;
    bool closure = false;
    s = next_edge(&e, &closure);
  }
  if (s == Status::kOk) s = finish();
  return s;
}

Status GraphReader::open_slot(hal::BlockDevice& slot) {
  open_ = false;
  nodes_read_ = 0;
  edges_read_ = 0;
  header_ = GraphFileHeader{};
  problem_ = MapProblem::kNone;
  uint8_t header[kGraphHeaderBytes];
  uint32_t size = 0;
  const Status s = reader_.open(slot, kGraphKind, header, sizeof header, &size,
                                Span<uint8_t>(buffer_, sizeof buffer_));
  if (s != Status::kOk) {
    problem_ = MapProblem::kLog;
    return s;
  }
  ByteReader r(header, sizeof header);
  GraphFileHeader g;
  g.nodes = r.u32();
  g.edges = r.u32();
  g.closures = r.u32();
  const uint8_t converged = r.u8();
  g.converged = converged == 1;
  r.skip(3);
  g.generation = r.u32();
  // Edges are odometry edges (nodes - 1) plus closures, all within PoseGraph's limits.
  const bool counts_ok = size == kGraphHeaderBytes && converged <= 1 &&
                         g.nodes <= kMaxPoseGraphNodes && g.edges <= kMaxPoseGraphEdges &&
                         g.closures <= g.edges &&
                         g.edges == (g.nodes > 0 ? g.nodes - 1 : 0) + g.closures;
  if (!counts_ok) return fail(MapProblem::kBadHeader);
  header_ = g;
  open_ = true;
  return Status::kOk;
}

Status GraphReader::read(uint8_t type, uint32_t size, const uint8_t** payload) {
  RecordView v;
  const Status s = reader_.next(&v);
  if (s == Status::kOutOfRange) {
    return fail(reader_.end_problem() == LogProblem::kEndClean ? MapProblem::kTruncated
                                                               : MapProblem::kDamaged);
  }
  if (s == Status::kDataLoss) {  // a damaged record, or the file cut before its committed end
    return fail(reader_.end_problem() == LogProblem::kEndTruncated ? MapProblem::kTruncated
                                                                   : MapProblem::kDamaged);
  }
  if (s == Status::kResourceExhausted) return fail(MapProblem::kBadRecord);
  if (s != Status::kOk) {
    problem_ = MapProblem::kLog;
    return s;
  }
  if (v.type != type || v.payload_size != size) return fail(MapProblem::kBadRecord);
  *payload = v.payload;
  return Status::kOk;
}

Status GraphReader::next_node(GraphFileNode* out) {
  if (!open_ || nodes_read_ >= header_.nodes || out == nullptr) {
    return Status::kFailedPrecondition;
  }
  const uint8_t* p = nullptr;
  SEQSLAM_TRY(read(kNodeRecord, kNodeBytes, &p));
  ByteReader r(p, kNodeBytes);
  GraphFileNode n;
  n.index = r.u32();
  n.place = r.u32();
  n.pose = codec::get_pose(r);
  if (n.index != nodes_read_) return fail(MapProblem::kBadRecord);
  ++nodes_read_;
  *out = n;
  return Status::kOk;
}

Status GraphReader::next_edge(PoseGraphEdge* out, bool* closure) {
  if (!open_ || nodes_read_ < header_.nodes || edges_read_ >= header_.edges || out == nullptr ||
      closure == nullptr) {
    return Status::kFailedPrecondition;
  }
  const uint8_t* p = nullptr;
  SEQSLAM_TRY(read(kEdgeRecord, kEdgeBytes, &p));
  ByteReader r(p, kEdgeBytes);
  // The file keeps the along and heading weights (its format predates the full information,
  // issue 35); the other terms read as 0.
  PoseGraphEdge e{};
  e.from = r.u16();
  e.to = r.u16();
  e.dx = Q7_24::from_raw(r.i32());
  e.dy = Q7_24::from_raw(r.i32());
  e.dtheta = Angle{r.u32()};
  e.info_xy = UQ16_16::from_raw(r.u32());
  e.info_heading = UQ16_16::from_raw(r.u32());
  const uint8_t kind = r.u8();
  const uint32_t i = edges_read_;
  const bool odometry = i + 1 < header_.nodes;
  if (odometry) {
    if (kind != 0 || e.from != i || e.to != i + 1) return fail(MapProblem::kBadRecord);
  } else if (kind != 1 || e.from >= header_.nodes || e.to >= header_.nodes || e.from == e.to) {
    return fail(MapProblem::kBadRecord);
  }
  ++edges_read_;
  *out = e;
  *closure = !odometry;
  return Status::kOk;
}

Status GraphReader::finish() {
  if (!open_ || nodes_read_ < header_.nodes || edges_read_ < header_.edges) {
    return Status::kFailedPrecondition;
  }
  RecordView v;
  const Status s = reader_.next(&v);
  if (s == Status::kOutOfRange) {
    return reader_.end_problem() == LogProblem::kEndClean ? Status::kOk
                                                          : fail(MapProblem::kDamaged);
  }
  if (s == Status::kOk || s == Status::kResourceExhausted) return fail(MapProblem::kExtraRecord);
  if (s == Status::kDataLoss) return fail(MapProblem::kDamaged);
  problem_ = MapProblem::kLog;
  return s;
}

}  // namespace seqslam::storage
