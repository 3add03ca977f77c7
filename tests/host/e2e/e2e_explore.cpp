// The firmware's explore mode end to end on a simulated run (docs/firmware.md, "Explore").
//
//   e2e_explore prepare DREAM IMAGE - formats a volume: `replay` = DREAM (a full recording
//                                     with ground truth, e.g. seqslam-sim's explore-short),
//                                     `config` = explore with the defaults, and empty library,
//                                     results, map and graph files.
//   e2e_explore prefix DREAM OUT N  - OUT = DREAM's first N snapshots with their places and
//                                     truth (a run stopped there; the continuation test).
//   e2e_explore run IMAGE DREAM     - runs the application in this process on IMAGE, then:
//       * it made loop closures, and every closure joins two places that are truly within
//         1.5 m of each other (the simulator's ground truth; the false-closure gate of
//         docs/mapping.md);
//       * the optimised trajectory is closer to the truth than dead reckoning (RMSE, aligned at
//         the first place): the closures corrected it;
//       * the graph file reloads (GraphReader) to exactly the application's graph: every node's
//         place and pose, every edge;
//       * the map file reloads (MapStore::open) to exactly the application's grid, tile by tile,
//         and the map is not empty.
// Exit 0 on success, 1 with a message otherwise.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <iterator>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "app.h"
#include "seqslam/hal/file_block_device.h"
#include "seqslam/storage/dream.h"
#include "seqslam/storage/map_store.h"
#include "seqslam_tools/q_format.h"

namespace {

using namespace seqslam;

constexpr double kFalseClosureMetres = 1.5;

int fail(const std::string& what) {
  std::fprintf(stderr, "e2e_explore: %s\n", what.c_str());
  return 1;
}

void quiet(const char*) {}

struct P {
  double x = 0, y = 0, h = 0;
};

P to_p(const Pose2& p) {
  return {tools::to_double(p.x), tools::to_double(p.y), tools::to_radians(p.heading)};
}

P compose(const P& a, const P& b) {
  const double c = std::cos(a.h), s = std::sin(a.h);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, a.h + b.h};
}

P between(const P& a, const P& b) {
  const double c = std::cos(a.h), s = std::sin(a.h);
  const double dx = b.x - a.x, dy = b.y - a.y;
  return {c * dx + s * dy, -s * dx + c * dy, b.h - a.h};
}

// The dream recording's places: timestamp -> true pose.
bool read_truth(const std::string& path, std::map<uint32_t, P>* truth) {
  hal::FileBlockDevice file;
  if (file.open(path, false) != Status::kOk) return false;
  std::vector<uint8_t> buffer(storage::kDreamRecordMax);
  storage::DreamReader reader;
  if (reader.open(file, Span<uint8_t>(buffer.data(), buffer.size())) != Status::kOk) return false;
  std::vector<uint32_t> stamps;
  for (;;) {
    storage::DreamItem item;
    const Status s = reader.next(&item);
    if (s == Status::kOutOfRange) break;
    if (s != Status::kOk) return false;
    if (item.type == storage::DreamRecord::kPlace) stamps.push_back(item.place.timestamp_us);
    if (item.type == storage::DreamRecord::kTruth && item.truth.place_index < stamps.size()) {
      (*truth)[stamps[item.truth.place_index]] = to_p(item.truth.pose);
    }
  }
  return !truth->empty();
}

int prepare(const std::string& dream, const std::string& image) {
  hal::FileBlockDevice source;
  if (source.open(dream, false) != Status::kOk) return fail(source.error());
  const uint32_t replay_blocks = source.block_count();
  const storage::VolumeFile files[] = {
      {"config", 0, 2},         {"replay", 0, replay_blocks}, {"library", 0, 256},
      {"library.img", 0, 2048}, {"results", 0, 512},          {"map", 0, 16384},
      {"graph", 0, 512},        {"state", 0, 1024},
  };
  uint32_t blocks = 1;
  for (const storage::VolumeFile& f : files)
    blocks += f.block_count;
  hal::FileBlockDevice disk;
  if (disk.create(image, blocks) != Status::kOk) return fail(disk.error());
  storage::Volume volume;
  if (storage::Volume::format(disk, files, static_cast<uint32_t>(std::size(files))) !=
          Status::kOk ||
      volume.mount(disk) != Status::kOk) {
    return fail("cannot format the volume");
  }
  storage::Region replay, config;
  if (volume.open("replay", &replay) != Status::kOk ||
      volume.open("config", &config) != Status::kOk) {
    return fail("volume files missing");
  }
  std::vector<uint8_t> block(hal::kBlockSize);
  for (uint32_t b = 0; b < replay_blocks; ++b) {
    if (source.read(b, 1, block.data()) != Status::kOk ||
        replay.write(b, 1, block.data()) != Status::kOk) {
      return fail("cannot copy the recording");
    }
  }
  storage::RunConfig rc;
  rc.modes = storage::kModeTeach | storage::kModeRepeat | storage::kModeExplore;
  if (storage::write_run_config(config, rc) != Status::kOk) return fail("cannot write config");
  std::printf("e2e_explore: %s ready: replay = %s, explore\n", image.c_str(), dream.c_str());
  return 0;
}

// The records of DREAM up to (not including) its snapshot number n, copied into a new
// recording OUT with the same header: the recording of a run stopped after n snapshots.
int prefix(const std::string& dream, const std::string& out, uint32_t n) {
  hal::FileBlockDevice source;
  if (source.open(dream, false) != Status::kOk) return fail(source.error());
  storage::LogReader reader;
  std::vector<uint8_t> header(storage::kLogHeaderPayloadMax);
  std::vector<uint8_t> buffer(storage::kDreamRecordMax + storage::kRecordOverhead);
  uint32_t header_size = 0;
  if (reader.open(source, storage::kDreamKind, header.data(), static_cast<uint32_t>(header.size()),
                  &header_size, Span<uint8_t>(buffer.data(), buffer.size())) != Status::kOk) {
    return fail(dream + ": not a recording");
  }
  hal::FileBlockDevice target;
  if (target.create(out, source.block_count()) != Status::kOk) return fail(target.error());
  storage::LogWriter writer;
  if (writer.create(target, storage::kDreamKind, header.data(), header_size) != Status::kOk) {
    return fail(out + ": cannot write");
  }
  uint32_t snapshots = 0;
  storage::RecordView v;
  while (reader.next(&v) == Status::kOk) {
    if (v.type == static_cast<uint8_t>(storage::DreamRecord::kSnapshot) && snapshots++ == n) break;
    const storage::ByteSpan part{v.payload, v.payload_size};
    if (writer.append(v.type, &part, 1) != Status::kOk) return fail(out + ": cannot write");
  }
  if (snapshots <= n) return fail(dream + ": fewer snapshots than asked for");
  std::printf("e2e_explore: %s = the first %u snapshots of %s\n", out.c_str(), n, dream.c_str());
  return 0;
}

int run(const std::string& image, const std::string& dream) {
  std::map<uint32_t, P> truth;
  if (!read_truth(dream, &truth)) return fail(dream + ": no ground truth");
  hal::FileBlockDevice disk;
  if (disk.open(image, true) != Status::kOk) return fail(disk.error());
  storage::Volume volume;
  if (volume.mount(disk) != Status::kOk) return fail(image + ": not a volume");
  auto application = std::make_unique<app::Application>();
  if (application->start(volume, nullptr, nullptr, quiet) != Status::kOk) {
    return fail("the application did not start");
  }
  if (application->run() != Status::kOk) return fail("the explore run failed");
  const app::Application& a = *application;
  const PoseGraph& graph = a.explorer().graph();
  const app::Stats& st = a.stats();
  const ExplorerStats& ex = a.explorer().stats();
  if (graph.node_count() == 0 || graph.node_count() != st.captures) {
    return fail("not every captured place became a node (" + std::to_string(graph.node_count()) +
                " of " + std::to_string(st.captures) + ")");
  }
  if (!graph.converged()) return fail("the graph was not optimised to convergence");
  if (ex.rebuild_places != graph.node_count()) return fail("the rebuild lost places");
  if (ex.closures == 0 || graph.closure_count() != ex.closures) return fail("no loop closure");

  // The places' timestamps and odometry from the results file (one result per place).
  storage::Region results_file, graph_file, map_file;
  if (volume.open("results", &results_file) != Status::kOk ||
      volume.open("graph", &graph_file) != Status::kOk ||
      volume.open("map", &map_file) != Status::kOk) {
    return fail("volume files missing");
  }
  storage::ResultsReader results;
  if (results.open(results_file) != Status::kOk) return fail("no results");
  std::vector<P> odometry, world_truth;
  for (;;) {
    storage::RunResult r;
    const Status s = results.next(&r);
    if (s == Status::kOutOfRange) break;
    if (s != Status::kOk) return fail("damaged results");
    const auto t = truth.find(r.timestamp_us);
    if (t == truth.end()) return fail("a place without ground truth");
    odometry.push_back(to_p(r.pose));
    world_truth.push_back(t->second);
  }
  if (odometry.size() != graph.node_count()) return fail("results and nodes differ in number");

  // Closures: true distance between the two places.
  uint32_t false_closures = 0;
  double worst = 0;
  for (uint32_t k = graph.node_count() - 1; k < graph.edge_count(); ++k) {
    const PoseGraphEdge e = graph.edge(k).value();
    const double d = std::hypot(world_truth[e.from].x - world_truth[e.to].x,
                                world_truth[e.from].y - world_truth[e.to].y);
    worst = std::max(worst, d);
    if (d > kFalseClosureMetres) ++false_closures;
  }
  // RMSE against the truth, both aligned at the first place's true pose.
  const P anchor = world_truth[0];
  const P first = to_p(graph.pose(0).value());
  double se_dead = 0, se_fixed = 0;
  for (uint32_t i = 0; i < graph.node_count(); ++i) {
    const P dead = compose(anchor, between(odometry[0], odometry[i]));
    const P fixed = compose(anchor, between(first, to_p(graph.pose(i).value())));
    se_dead += std::pow(dead.x - world_truth[i].x, 2) + std::pow(dead.y - world_truth[i].y, 2);
    se_fixed += std::pow(fixed.x - world_truth[i].x, 2) + std::pow(fixed.y - world_truth[i].y, 2);
  }
  const double n = graph.node_count();
  const double rmse_dead = std::sqrt(se_dead / n), rmse_fixed = std::sqrt(se_fixed / n);
  std::printf(
      "e2e_explore: %u places, %u closures (%u false, worst %.3f m apart), RMSE dead reckoning "
      "%.3f m, corrected %.3f m\n",
      graph.node_count(), ex.closures, false_closures, worst, rmse_dead, rmse_fixed);
  if (false_closures != 0) return fail("false loop closures");
  if (!(rmse_fixed < rmse_dead)) return fail("the closures did not correct the trajectory");

  // The graph file against the application's graph.
  storage::GraphReader gr;
  if (gr.open(graph_file) != Status::kOk) return fail("the graph file does not open");
  if (gr.header().nodes != graph.node_count() || gr.header().edges != graph.edge_count() ||
      gr.header().closures != graph.closure_count() || !gr.header().converged) {
    return fail("the graph file's header differs from the graph");
  }
  for (uint32_t i = 0; i < graph.node_count(); ++i) {
    storage::GraphFileNode node;
    if (gr.next_node(&node) != Status::kOk) return fail("graph file: node unreadable");
    const Pose2 p = graph.pose(i).value();
    if (node.place != graph.place(i).value() || node.pose.x != p.x || node.pose.y != p.y ||
        node.pose.heading.bam != p.heading.bam) {
      return fail("graph file: node " + std::to_string(i) + " differs");
    }
  }
  for (uint32_t i = 0; i < graph.edge_count(); ++i) {
    PoseGraphEdge e;
    bool closure = false;
    if (gr.next_edge(&e, &closure) != Status::kOk) return fail("graph file: edge unreadable");
    const PoseGraphEdge g = graph.edge(i).value();
    if (e.from != g.from || e.to != g.to || e.dx.raw() != g.dx.raw() || e.dy.raw() != g.dy.raw() ||
        e.dtheta.bam != g.dtheta.bam || e.info_xy.raw() != g.info_xy.raw() ||
        e.info_heading.raw() != g.info_heading.raw() || closure != (i + 1 >= graph.node_count())) {
      return fail("graph file: edge " + std::to_string(i) + " differs");
    }
  }
  if (gr.finish() != Status::kOk) return fail("graph file: does not end after the last edge");

  // The map file against the application's grid, tile by tile.
  std::vector<storage::MapTileIndexEntry> index(1u << 16);
  std::vector<uint8_t> buffer(storage::kMapReadBuffer);
  auto store = std::make_unique<storage::MapStore>();
  GridConfig gc;
  if (store->open(map_file, Span<storage::MapTileIndexEntry>(index.data(), index.size()),
                  Span<uint8_t>(buffer.data(), buffer.size()), &gc) != Status::kOk) {
    return fail("the map file does not open");
  }
  auto ram = std::make_unique<OccupancyGridStorage<3>>();
  OccupancyGrid reloaded;
  if (reloaded.configure(gc, ram->buffers(), *store) != Status::kOk) {
    return fail("the map file's grid settings are refused");
  }
  const OccupancyGrid& grid = a.explorer().grid();
  if (reloaded.tiles_x() != grid.tiles_x() || reloaded.tiles_y() != grid.tiles_y()) {
    return fail("the map file's bounds differ from the grid's");
  }
  std::vector<int8_t> x(kGridTileCells), y(kGridTileCells);
  uint64_t known = 0;
  for (uint16_t ty = 0; ty < grid.tiles_y(); ++ty) {
    for (uint16_t tx = 0; tx < grid.tiles_x(); ++tx) {
      const GridTile t{tx, ty};
      if (grid.copy_tile(t, Span<int8_t>(x.data(), x.size())) != Status::kOk ||
          reloaded.copy_tile(t, Span<int8_t>(y.data(), y.size())) != Status::kOk) {
        return fail("a tile could not be read");
      }
      if (x != y)
        return fail("map file: tile " + std::to_string(tx) + "," + std::to_string(ty) +
                    " differs from the grid");
      for (const int8_t c : x)
        known += c != 0 ? 1 : 0;
    }
  }
  if (store->tile_count() == 0 || known == 0) return fail("the map is empty");
  std::printf(
      "e2e_explore: graph file = graph (%u nodes, %u edges); map file = grid (%u tiles, %llu "
      "cells observed)\n",
      graph.node_count(), graph.edge_count(), store->tile_count(),
      static_cast<unsigned long long>(known));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 4 && std::strcmp(argv[1], "prepare") == 0) return prepare(argv[2], argv[3]);
  if (argc == 4 && std::strcmp(argv[1], "run") == 0) return run(argv[2], argv[3]);
  if (argc == 5 && std::strcmp(argv[1], "prefix") == 0) {
    return prefix(argv[2], argv[3], static_cast<uint32_t>(std::strtoul(argv[4], nullptr, 10)));
  }
  std::fprintf(stderr,
               "usage: e2e_explore prepare DREAM IMAGE | run IMAGE DREAM | prefix DREAM OUT N\n");
  return 2;
}
