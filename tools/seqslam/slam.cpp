// seqslam slam: replays a full dream recording as the robot would explore (docs/mapping.md):
// per place Localiser::observe (the run against its own older places), the loop-closure gate
// (loop_closure.h), a pose-graph node per place with the odometry step as its edge, accepted
// closures as closure edges, a fixed budget of optimise_step work per place, and at the end
// the occupancy grid rebuilt from every infrared snapshot at the optimised poses. With true
// poses in the recording it scores the result: trajectory RMSE of dead reckoning and of the
// corrected poses, false closures, map accuracy against the simulator's true map, places to
// relocalise after a kidnap or after re-entering known ground.
//
// Earlier runs given with --prior are replayed first into the same library, graph and map
// (a robot that explored before); each run's odometry starts at the origin, which is the
// same start pose for the simulator's runs, so the step from one run's last place to the
// next run's first is its odometry edge (it carries the first run's end drift, weighted as
// a step of that length).
#include <CLI/CLI.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "cli_common.h"
#include "reference.h"
#include "seqslam/closure_align.h"
#include "seqslam/difference.h"
#include "seqslam/localiser.h"
#include "seqslam/loop_closure.h"
#include "seqslam/occupancy_grid.h"
#include "seqslam/odometry.h"
#include "seqslam/place_library.h"
#include "seqslam/pose_graph.h"
#include "seqslam/preprocess.h"
#include "seqslam/storage/dream.h"
#include "seqslam_tools/cli_numbers.h"
#include "seqslam_tools/grid_export.h"
#include "seqslam_tools/image_io.h"
#include "seqslam_tools/outcome.h"

namespace seqslam::cli {

namespace {

constexpr double kTwoPi = 6.283185307179586;
constexpr uint32_t kMaxPlaces = 4000;  // library and graph capacity of the replay
constexpr uint16_t kMaxSeq = 100;
constexpr double kFalseClosureMetres = 1.5;  // the pair ground truth's gate (simulator.md)

struct SlamOptions {
  std::string input;
  std::vector<std::string> priors;
  std::string out;
  std::string true_map;  // default: lab_map.yaml beside the input, if there
  std::string json;
  std::string preprocess = "he";
  int seq_len = 30;
  int window = 50;
  int exclusion = 10;
  std::string threshold = "0.85";
  int recent = 50;
  double drift_base = 1.0;
  double drift_rate = 0.05;
  double heading_base = 30.0;
  double heading_rate = 0.1;
  double near = 1.5;
  int confirm = 3;
  int max_advance = 3;
  int relocalise = 0;
  double relocalise_turn = 45.0;
  double max_image_rank = 0.9;
  double closure_weight = 1.0;
  double closure_heading_weight = 1.0;
  std::string closure_heading = "image";  // image | none
  double hfov = 50.0;  // degrees: the effective field of view for shift -> heading (mapping.md)
  int max_shift = 6;   // columns searched for the closure's image shift
  // Closure alignment along the pass (align_closure, docs/mapping.md): places compared, 0 off.
  int align_length = 15;
  int align_range = 5;  // places searched each way of the matched one
  int align_shift = 2;  // columns each image pair may be shifted
  // Wheel constants "LEFT,RIGHT,TRACK" (metres: circumferences, track width) to replay the
  // encoders with instead of the recording's; empty: the recording's place poses.
  std::string wheels;
  int budget = 2000;
  bool quiet = false;
  bool reference = false;
};

// ---------------------------------------------------------------------------------------
// Conversions (host: double precision for scoring only; the replay itself is the core's).

struct P {
  double x = 0, y = 0, h = 0;  // metres, radians
};

P to_p(const Pose2& p) {
  return {static_cast<double>(p.x.raw()) / 4294967296.0,
          static_cast<double>(p.y.raw()) / 4294967296.0,
          static_cast<int32_t>(p.heading.bam) / 4294967296.0 * kTwoPi};
}

Pose2 to_pose2(const P& p) {
  double turns = p.h / kTwoPi;
  turns -= std::floor(turns);
  return Pose2{
      Q31_32::from_raw(static_cast<int64_t>(std::llround(p.x * 4294967296.0))),
      Q31_32::from_raw(static_cast<int64_t>(std::llround(p.y * 4294967296.0))),
      Angle{static_cast<uint32_t>(static_cast<uint64_t>(std::llround(turns * 4294967296.0)))}};
}

double wrap(double a) {
  return std::remainder(a, kTwoPi);
}

// a * b (b in a's frame).
P compose_d(const P& a, const P& b) {
  const double c = std::cos(a.h), s = std::sin(a.h);
  return {a.x + c * b.x - s * b.y, a.y + s * b.x + c * b.y, wrap(a.h + b.h)};
}

// a^-1 * b.
P between_d(const P& a, const P& b) {
  const double c = std::cos(a.h), s = std::sin(a.h);
  const double dx = b.x - a.x, dy = b.y - a.y;
  return {c * dx + s * dy, -s * dx + c * dy, wrap(b.h - a.h)};
}

double dist(const P& a, const P& b) {
  return std::hypot(a.x - b.x, a.y - b.y);
}

// ---------------------------------------------------------------------------------------
// Input.

struct Scan {
  uint32_t place = 0;  // index within the session of the place it hangs from
  Pose2 odometry{};    // the session's odometry pose at this snapshot
  uint8_t count = 0;
  uint16_t mm[hal::kMaxInfrared] = {};
};

struct Session {
  std::string path;
  storage::DreamHeader header;
  std::vector<tools::GrayImage> images;
  std::vector<Pose2> odometry;  // per place, from the place records
  std::vector<Pose2> truth;     // per place when has_truth
  bool has_truth = false;
  std::vector<Scan> scans;
};

// `wheels` non-null: the encoders are replayed with its circumferences and track width (the
// rest as the recording's header) and the places take the odometry pose of their snapshot;
// else the places keep the pose the recording gives them.
tools::Outcome<Session> load_session(const std::string& path, const OdometryConfig* wheels) {
  LogSource source;
  std::string e = source.open(path, nullptr);
  if (!e.empty()) return tools::Error{e};
  if (warn_if_truncated(source)) return tools::Error{path + ": the recording is cut short"};
  storage::DreamReader reader;
  std::vector<uint8_t> buffer;
  e = open_dream(source, reader, buffer);
  if (!e.empty()) return tools::Error{e};
  Session s;
  s.path = path;
  s.header = reader.header();
  if (s.header.variant != storage::DreamVariant::kFull) {
    return tools::Error{path +
                        ": a reduced recording has no odometry or infrared readings; seqslam "
                        "slam needs a full recording (the robot's or seqslam-sim's)"};
  }
  OdometryConfig constants = s.header.wheels;
  if (wheels != nullptr) {
    constants.circumference_left = wheels->circumference_left;
    constants.circumference_right = wheels->circumference_right;
    constants.track_width = wheels->track_width;
  }
  Odometry odometry;
  if (odometry.configure(constants) != Status::kOk) {
    return tools::Error{path + (wheels != nullptr
                                    ? ": the --wheels constants do not suit its encoders"
                                    : ": the header's wheel constants are invalid")};
  }
  bool started = false;
  size_t truths = 0;
  for (;;) {
    storage::DreamItem item;
    const Status st = reader.next(&item);
    if (st == Status::kOutOfRange) {
      if (reader.log_problem() != storage::LogProblem::kEndClean) {
        return tools::Error{path + ": the recording ends in a damaged record (" +
                            storage::log_problem_text(reader.log_problem()) + ")"};
      }
      break;
    }
    if (st != Status::kOk) {
      return tools::Error{path + ": damaged or invalid record after place " +
                          std::to_string(s.images.size()) + " (" +
                          (reader.problem() == storage::DreamProblem::kLog
                               ? std::string(storage::log_problem_text(reader.log_problem())) +
                                     ", " + std::to_string(reader.lost_records()) + " records lost"
                               : std::string(storage::dream_problem_text(reader.problem()))) +
                          ")"};
    }
    if (item.type == storage::DreamRecord::kSnapshot) {
      const hal::SensorSnapshot& sn = item.snapshot;
      if ((sn.flags & hal::SensorSnapshot::kHasEncoders) == 0) continue;
      if (!started) {
        odometry.reset(Pose2{}, sn.encoder_left, sn.encoder_right);
        started = true;
      } else if (odometry.update(sn.encoder_left, sn.encoder_right) != Status::kOk) {
        odometry.resync(sn.encoder_left, sn.encoder_right);
      }
      if ((sn.flags & hal::SensorSnapshot::kHasInfrared) == 0) continue;
      Scan scan;
      scan.place = s.images.empty() ? 0 : static_cast<uint32_t>(s.images.size() - 1);
      scan.odometry = odometry.pose();
      scan.count = sn.infrared_count;
      for (uint32_t k = 0; k < sn.infrared_count && k < hal::kMaxInfrared; ++k)
        scan.mm[k] = sn.infrared_mm[k];
      s.scans.push_back(scan);
    } else if (item.type == storage::DreamRecord::kPlace) {
      tools::GrayImage img;
      img.width = item.place.size.width;
      img.height = item.place.size.height;
      img.pixels.assign(item.place.gray, item.place.gray + item.place.size.pixels());
      s.images.push_back(std::move(img));
      s.odometry.push_back(wheels != nullptr ? odometry.pose() : item.place.pose);
      s.truth.push_back(Pose2{});
    } else if (item.type == storage::DreamRecord::kTruth) {
      if (item.truth.place_index < s.truth.size()) {
        s.truth[item.truth.place_index] = item.truth.pose;
        ++truths;
      }
    }
  }
  if (s.images.empty()) return tools::Error{path + ": the recording has no places"};
  s.has_truth = truths == s.images.size();
  return s;
}

// ---------------------------------------------------------------------------------------
// A RAM tile store for the grid (the robot pages to its card; the PC keeps every tile).

class RamTileStore final : public TileStore {
 private:
  Status do_load(GridTile tile, Span<int8_t> cells) override {
    const auto it = tiles_.find(key(tile));
    if (it == tiles_.end()) return Status::kNotFound;
    std::copy(it->second.begin(), it->second.end(), cells.data());
    return Status::kOk;
  }
  Status do_save(GridTile tile, Span<const int8_t> cells) override {
    tiles_[key(tile)].assign(cells.data(), cells.data() + cells.size());
    return Status::kOk;
  }
  Status do_clear() override {
    tiles_.clear();
    return Status::kOk;
  }
  static uint32_t key(GridTile t) { return static_cast<uint32_t>(t.x) << 16 | t.y; }
  std::map<uint32_t, std::vector<int8_t>> tiles_;
};

// The sensors from the recording's header (mounting in mm, direction in 1/65536 turn).
std::vector<RangeSensor> sensors_of(const storage::DreamHeader& h) {
  std::vector<RangeSensor> out;
  for (uint32_t k = 0; k < h.infrared_count; ++k) {
    const storage::InfraredMount& m = h.infrared[k];
    RangeSensor r;
    r.x = Q31_32::from_ratio(m.x_mm, 1000);
    r.y = Q31_32::from_ratio(m.y_mm, 1000);
    r.angle = Angle{static_cast<uint32_t>(m.angle) << 16};
    r.min_mm = m.min_mm;
    r.max_mm = m.max_mm;
    r.no_echo_mm = m.max_mm > 100 ? static_cast<uint16_t>(m.max_mm - 100) : 0;
    out.push_back(r);
  }
  return out;
}

struct GridResult {
  tools::OccupancyMapImage map;
  uint64_t scans = 0;
  uint64_t rejected = 0;  // readings out of range, rays starting outside the bounds
};

// Rebuilds a grid from every scan at the given world poses of the places (scans hang from
// their place by the odometry between them). `use[g]` false: the place's scans are left out.
tools::Outcome<GridResult> build_grid(const std::vector<Session>& sessions,
                                      const std::vector<P>& world, const std::vector<bool>& use,
                                      const tools::OccupancyMapImage& frame) {
  RamTileStore store;
  static OccupancyGridStorage<8> ram;
  GridConfig gc;
  gc.origin_x = Q31_32::from_raw(static_cast<int64_t>(std::llround(frame.origin_x * 4294967296.0)));
  gc.origin_y = Q31_32::from_raw(static_cast<int64_t>(std::llround(frame.origin_y * 4294967296.0)));
  gc.cell_mm = static_cast<uint16_t>(std::lround(frame.resolution * 1000));
  gc.width = static_cast<uint16_t>(std::min(frame.width, static_cast<int>(kMaxGridSide)));
  gc.height = static_cast<uint16_t>(std::min(frame.height, static_cast<int>(kMaxGridSide)));
  OccupancyGrid grid;
  GridIssue issue = GridIssue::kNone;
  if (grid.configure(gc, ram.buffers(), store, &issue) != Status::kOk) {
    return tools::Error{std::string("grid: ") + grid_issue_text(issue)};
  }
  GridResult r;
  size_t base = 0;
  for (const Session& s : sessions) {
    const std::vector<RangeSensor> sensors = sensors_of(s.header);
    for (const Scan& scan : s.scans) {
      const size_t g = base + scan.place;
      if (!use[g]) continue;
      const P rel = between_d(to_p(s.odometry[scan.place]), to_p(scan.odometry));
      const Pose2 pose = to_pose2(compose_d(world[g], rel));
      for (uint32_t k = 0; k < scan.count && k < sensors.size(); ++k) {
        if (grid.insert_reading(pose, sensors[k], scan.mm[k]) != Status::kOk) ++r.rejected;
      }
      ++r.scans;
    }
    base += s.images.size();
  }
  auto map = tools::grid_map(grid);
  if (!map) return tools::Error{map.error()};
  r.map = std::move(map.value());
  return r;
}

// ---------------------------------------------------------------------------------------

struct PlaceRecord {
  uint32_t session = 0;
  LoopClosureDecision decision;
  Match match;
  P odometry;  // the session's raw odometry (dead reckoning)
  P online;    // the graph's estimate right after this place's optimise slice
  bool reliable = true;
};

struct Closure {
  uint32_t a = 0, b = 0;    // the closure's nodes: matched (after alignment), current
  uint32_t gate_place = 0;  // the matcher's answer the gate accepted
  double along_m = 0;       // the edge's dx: the alignment's fraction x the place spacing
  double true_distance = -1;
  double shift_px = 0;          // image shift of the current place against the matched one
  double heading_deg = 0;       // the closure's heading offset (0 with --closure-heading none)
  double true_heading_deg = 0;  // the true one (with truth)
};

std::string fmt(double v, int decimals = 4) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

// The outputs (--out's files, --json) must be none of the inputs (the recordings, the true
// map). Returns kExitOk or the usage error's status.
int refuse_slam_outputs(const SlamOptions& o) {
  tools::InputFiles inputs;
  inputs.add(o.input);
  for (const std::string& prior : o.priors)
    inputs.add(prior);
  inputs.add_map(o.true_map.empty()
                     ? (std::filesystem::path(o.input).parent_path() / "lab_map.yaml").string()
                     : o.true_map);
  std::vector<std::string> outputs = {o.json};
  if (!o.out.empty()) {
    for (const char* name : {"trajectory.csv", "closures.csv", "map.pgm", "map.yaml",
                             "map_odometry.pgm", "map_odometry.yaml"}) {
      outputs.push_back(o.out + "/" + name);
    }
  }
  for (const std::string& output : outputs) {
    if (const int rc = refuse_inputs_as_outputs(inputs, {output}); rc != kExitOk) return rc;
  }
  return kExitOk;
}

int run_slam(const SlamOptions& o) {
  if (const int rc = refuse_slam_outputs(o); rc != kExitOk) return rc;
  // Configuration.
  LocaliserConfig lc;
  if (!parse_preprocessing(o.preprocess, &lc.preprocess.method))
    return usage_error("--preprocess: unknown method '" + o.preprocess + "'");
  lc.sequence.seq_len = static_cast<uint16_t>(o.seq_len);
  lc.sequence.window = static_cast<uint16_t>(o.window);
  lc.sequence.exclusion = static_cast<uint16_t>(o.exclusion);
  std::string e = parse_threshold(o.threshold, &lc.sequence.threshold);
  if (!e.empty()) return usage_error("--threshold: " + e);
  lc.recent_exclusion = static_cast<uint16_t>(o.recent);

  LoopClosureConfig gc;
  gc.drift_base = Q31_32::from_ratio(std::llround(o.drift_base * 1e6), 1000000);
  gc.drift_rate = UQ16_16::from_ratio(std::llround(o.drift_rate * 1e6), 1000000);
  gc.heading_base = Angle::from_degrees(std::llround(o.heading_base * 1000), 1000);
  gc.heading_rate = Angle::from_degrees(std::llround(o.heading_rate * 1000), 1000);
  gc.near_radius = Q31_32::from_ratio(std::llround(o.near * 1e6), 1000000);
  gc.confirm = static_cast<uint16_t>(o.confirm);
  gc.max_advance = static_cast<uint16_t>(o.max_advance);
  gc.relocalise = static_cast<uint16_t>(o.relocalise);
  gc.max_image_rank = UQ16_16::from_ratio(std::llround(o.max_image_rank * 10000), 10000);
  gc.relocalise_turn = Angle::from_degrees(std::llround(o.relocalise_turn * 1000), 1000);
  LoopClosureGate gate;
  if (gate.configure(gc) != Status::kOk)
    return usage_error("a loop-closure setting is out of range");

  // Input.
  OdometryConfig wheels{};
  if (!o.wheels.empty()) {
    double v[3] = {0, 0, 0};
    char tail = 0;
    if (std::sscanf(o.wheels.c_str(), "%lf,%lf,%lf%c", &v[0], &v[1], &v[2], &tail) != 3 ||
        !(v[0] > 0 && v[1] > 0 && v[2] > 0 && v[0] < 16 && v[1] < 16 && v[2] < 100)) {
      return usage_error(
          "--wheels wants LEFT,RIGHT,TRACK in metres: circumferences above 0 and below 16, "
          "the track above 0 and below 100 (e.g. 0.532,0.53227,0.474)");
    }
    wheels.circumference_left = Q31_32::from_ratio(std::llround(v[0] * 1e9), 1000000000);
    wheels.circumference_right = Q31_32::from_ratio(std::llround(v[1] * 1e9), 1000000000);
    wheels.track_width = Q31_32::from_ratio(std::llround(v[2] * 1e9), 1000000000);
  }
  std::vector<Session> sessions;
  for (const std::string& path : o.priors) {
    auto s = load_session(path, o.wheels.empty() ? nullptr : &wheels);
    if (!s) return fail(s.error());
    sessions.push_back(std::move(s.value()));
  }
  {
    auto s = load_session(o.input, o.wheels.empty() ? nullptr : &wheels);
    if (!s) return fail(s.error());
    sessions.push_back(std::move(s.value()));
  }
  size_t total = 0;
  bool has_truth = true;
  for (const Session& s : sessions) {
    total += s.images.size();
    has_truth = has_truth && s.has_truth;
    const ImageSize size = s.header.image_size();
    if (size.width != sessions.front().header.image_size().width ||
        size.height != sessions.front().header.image_size().height) {
      return fail(s.path + ": its images are of another size than the first run's");
    }
  }
  if (total > kMaxPlaces) {
    return fail("the runs have " + std::to_string(total) + " places; at most " +
                std::to_string(kMaxPlaces) + " are supported");
  }
  lc.image_size = sessions.front().header.image_size();

  // The core's objects, with static-capacity storage on the heap of the PC.
  auto lib_storage = std::make_unique<PlaceLibraryStorage<kMaxPlaces, kMaxPixels>>();
  auto matcher_storage = std::make_unique<DiagonalMatcherStorage<kMaxPlaces, kMaxSeq>>();
  std::vector<uint32_t> differences(kMaxPlaces);
  PlaceLibrary library;
  if (lib_storage->attach(library, lc.image_size) != Status::kOk) {
    return fail("the image size does not fit the library storage");
  }
  DiagonalMatcherBuffers mb = matcher_storage->buffers();
  mb.ring = mb.ring.subspan(0, static_cast<size_t>(kMaxPlaces) * lc.sequence.seq_len);
  Localiser localiser;
  const ConfigCheck check =
      localiser.configure(lc, library, mb, Span<uint32_t>(differences.data(), differences.size()));
  if (!check.ok()) return usage_error(config_issue_text(check.issue));

  auto graph_storage = std::make_unique<PoseGraphStorage<kMaxPlaces, 3 * kMaxPlaces>>();
  PoseGraph graph;
  if (graph.configure(PoseGraphConfig{}, graph_storage->buffers()) != Status::kOk) {
    return fail("pose graph configuration failed");
  }
  const EdgeInformation info{
      UQ16_16::from_ratio(std::llround(o.closure_weight * 1000), 1000),
      UQ16_16::from_ratio(std::llround(o.closure_heading_weight * 1000), 1000)};
  const uint32_t budget = static_cast<uint32_t>(o.budget);
  const Angle hfov = Angle::from_degrees(std::llround(o.hfov * 1000), 1000);
  if (o.closure_heading == "image" && o.max_shift >= static_cast<int>(lc.image_size.width)) {
    return usage_error("--max-shift must be less than the image width");
  }
  const ClosureAlignConfig align{static_cast<uint8_t>(o.align_length),
                                 static_cast<uint8_t>(o.align_range),
                                 static_cast<uint8_t>(o.align_shift)};
  if (o.align_length > 0 && o.align_shift >= static_cast<int>(lc.image_size.width)) {
    return usage_error("--align-shift must be less than the image width");
  }
  std::vector<uint8_t> align_scratch(lc.image_size.pixels());

  // The replay.
  std::vector<PlaceRecord> places;
  std::vector<Closure> closures;
  uint64_t work = 0;
  uint32_t slices = 0;            // optimise_step calls that did work
  uint32_t solve_places = 0;      // places from a closure to convergence, current solve
  uint32_t max_solve_places = 0;  // the largest of them
  bool solving = false;
  uint32_t relocalisations = 0;
  for (uint32_t si = 0; si < sessions.size(); ++si) {
    const Session& s = sessions[si];
    localiser.reset_sequence();  // a sequence never spans two runs
    bool rebased = false;
    P rebase_from{}, rebase_to{};  // after a relocalisation: raw odometry -> graph frame
    uint32_t last_fix = static_cast<uint32_t>(places.size());  // first node of the run
    for (uint32_t i = 0; i < s.images.size(); ++i) {
      const uint32_t g = static_cast<uint32_t>(places.size());
      PlaceRecord rec;
      rec.session = si;
      rec.odometry = to_p(s.odometry[i]);
      const P odo_graph =
          rebased ? compose_d(rebase_to, between_d(rebase_from, rec.odometry)) : rec.odometry;
      Match m;
      const ImageView view{s.images[i].pixels.data(), lc.image_size};
      const Status os = localiser.observe(view, to_pose2(rec.odometry), g, &m);
      if (os != Status::kOk) {
        return fail(s.path + ": place " + std::to_string(i) + ": observe failed (" +
                    status_name(os) + ")");
      }
      const Result<uint32_t> node = graph.add_node(to_pose2(odo_graph), g);
      if (!node.ok())
        return fail("pose graph add_node failed: " + std::string(status_name(node.status())));
      LoopClosureQuery q;
      q.match = m;
      q.node = node.value();
      q.matched_node = m.place;  // library place == graph node == global place index
      q.known_nodes = g > static_cast<uint32_t>(o.recent) ? g - static_cast<uint32_t>(o.recent) : 0;
      // The gate keeps its own odometry (distance driven, the pose at its last fix) in the
      // recording's raw frame: a relocalisation re-anchors the graph's frame below, not its.
      q.odometry = to_pose2(rec.odometry);
      if (m.place >= 0) {
        q.closer_places = count_closer(Span<const uint32_t>(differences.data(), g), q.known_nodes,
                                       static_cast<uint32_t>(m.place));
      }
      LoopClosureDecision d;
      if (gate.decide(graph, q, &d) != Status::kOk) return fail("loop-closure gate failed");
      if (d.kind == LoopClosureClass::kClosure) {
        // Where along the matched pass the current place lies: the edge joins the aligned
        // place, dx the remaining fraction of a place (with alignment off: the matched place,
        // "same position").
        uint32_t target = static_cast<uint32_t>(m.place);
        RelativePose2 rel{};
        if (o.align_length > 0) {
          ClosureAlignment al;
          const Status as =
              align_closure(library, g, target, q.known_nodes, align,
                            Span<uint8_t>(align_scratch.data(), align_scratch.size()), &al);
          if (as != Status::kOk) return fail("align_closure: " + std::string(status_name(as)));
          target = al.place;
          rel.dx = along_route(al.fraction, sessions[places[target].session].header.spacing);
        }
        // The closure's heading offset from the images.
        Q15_16 shift{};
        if (o.closure_heading == "image") {
          // The library's (preprocessed) images, what the robot keeps: the matched place's and
          // the current one's, appended by observe().
          ImageView matched_image{}, current_image{};
          if (library.image(target, &matched_image) != Status::kOk ||
              library.image(g, &current_image) != Status::kOk) {
            return fail("the library lost an image");
          }
          const Result<Q15_16> sh =
              subpixel_shift(matched_image, current_image, static_cast<uint8_t>(o.max_shift));
          if (!sh.ok()) return fail("subpixel_shift: " + std::string(status_name(sh.status())));
          shift = sh.value();
          rel.dtheta = shift_to_heading(shift, hfov, lc.image_size.width);
        }
        const Status cs = graph.add_loop_closure(target, node.value(), rel, info);
        if (cs != Status::kOk) return fail("add_loop_closure: " + std::string(status_name(cs)));
        Closure c;
        c.a = target;
        c.b = node.value();
        c.gate_place = static_cast<uint32_t>(m.place);
        c.along_m = static_cast<double>(rel.dx.raw()) / 4294967296.0;
        c.shift_px = static_cast<double>(shift.raw()) / 65536.0;
        c.heading_deg = static_cast<int32_t>(rel.dtheta.bam) / 4294967296.0 * 360.0;
        closures.push_back(c);
        if (!solving) solve_places = 0;
        solving = true;
        last_fix = g;
      } else if (d.kind == LoopClosureClass::kRelocalised) {
        // Odometry was broken since the last fix: from here on its poses are re-anchored at the
        // matched place (the next odometry edge takes the jump, weighted by its length), and
        // the places since the last fix are not trusted for the map.
        ++relocalisations;
        const P matched = to_p(graph.pose(static_cast<uint32_t>(m.place)).value());
        rebase_from = rec.odometry;
        rebase_to = matched;
        rebased = true;
        for (uint32_t k = last_fix + 1; k < g; ++k)
          places[k].reliable = false;
        rec.reliable = false;
        last_fix = g;
      }
      PoseGraphProgress progress;
      if (graph.optimise_step(budget, &progress) == Status::kOk && progress.work > 0) {
        work += progress.work;
        ++slices;
      }
      if (solving) {
        ++solve_places;
        if (progress.converged) {
          max_solve_places = std::max(max_solve_places, solve_places);
          solving = false;
        }
      }
      rec.decision = d;
      rec.match = m;
      rec.online = to_p(graph.pose(node.value()).value());
      places.push_back(rec);
    }
  }
  // Finish the optimisation after the last place (as the robot would while standing).
  uint32_t final_slices = 0;
  for (;;) {
    PoseGraphProgress progress;
    if (graph.optimise_step(budget, &progress) != Status::kOk) return fail("optimise_step failed");
    if (progress.converged) break;
    work += progress.work;
    ++final_slices;
    if (final_slices > 1000000) return fail("the pose graph did not converge");
  }
  std::vector<P> corrected(total);
  for (uint32_t g = 0; g < total; ++g)
    corrected[g] = to_p(graph.pose(g).value());
  // --reference: the same graph solved in double precision, LAGO directly and the full
  // nonlinear problem (tools/reference), to tell the solver's part from the model's.
  std::vector<P> ref_linear, ref_nonlinear;
  if (o.reference) {
    std::vector<reference::PoseEdgeRef> edges;
    for (uint32_t k = 0; k < graph.edge_count(); ++k) {
      const PoseGraphEdge ed = graph.edge(k).value();
      reference::PoseEdgeRef r;
      r.from = ed.from;
      r.to = ed.to;
      r.dx = static_cast<double>(ed.dx.raw()) / 16777216.0;
      r.dy = static_cast<double>(ed.dy.raw()) / 16777216.0;
      r.dtheta = static_cast<int32_t>(ed.dtheta.bam) / 4294967296.0 * kTwoPi;
      r.info_xy = static_cast<double>(ed.info_xy.raw()) / 65536.0;
      r.info_heading = static_cast<double>(ed.info_heading.raw()) / 65536.0;
      edges.push_back(r);
    }
    const P a = corrected[0];
    const auto lin = reference::pose_graph_linear(static_cast<int>(total), edges, {a.x, a.y, a.h});
    std::vector<reference::PoseRef> init;
    for (const auto& p : lin)
      init.push_back({p.x, p.y, p.theta});
    const auto nl = reference::pose_graph_gauss_newton(edges, init, 1e-4, 1e-4);
    for (const auto& p : lin)
      ref_linear.push_back({p.x, p.y, p.theta});
    for (const auto& p : nl)
      ref_nonlinear.push_back({p.x, p.y, p.theta});
  }

  // Scoring and output (world frame: aligned at the first place's true pose when known).
  std::vector<P> truth(total), dead(total), online(total), fixed(total);
  std::vector<uint32_t> session_start;
  {
    size_t g = 0;
    for (const Session& s : sessions) {
      session_start.push_back(static_cast<uint32_t>(g));
      for (size_t i = 0; i < s.images.size(); ++i, ++g)
        truth[g] = s.has_truth ? to_p(s.truth[i]) : P{};
    }
  }
  const P anchor = has_truth ? truth[0] : P{};
  for (uint32_t g = 0; g < total; ++g) {
    dead[g] = compose_d(anchor, between_d(places[0].odometry, places[g].odometry));
    online[g] = compose_d(anchor, between_d(corrected[0], places[g].online));
    fixed[g] = compose_d(anchor, between_d(corrected[0], corrected[g]));
  }
  double se_dead = 0, se_fixed = 0, se_online = 0, max_dead = 0, max_fixed = 0;
  uint32_t false_closures = 0;
  double worst_closure = 0;
  double se_heading = 0, se_same_heading = 0, rms_heading = 0, rms_same_heading = 0;
  // Along the route: the edge's dx against the true one, and the matcher's place's error.
  double se_along = 0, se_along_gate = 0, rms_along = 0, rms_along_gate = 0;
  uint32_t realigned = 0;
  for (const Closure& c : closures)
    if (c.a != c.gate_place) ++realigned;
  if (has_truth) {
    for (uint32_t g = 0; g < total; ++g) {
      const double ed = dist(dead[g], truth[g]), ef = dist(fixed[g], truth[g]);
      se_dead += ed * ed;
      se_fixed += ef * ef;
      se_online += std::pow(dist(online[g], truth[g]), 2);
      max_dead = std::max(max_dead, ed);
      max_fixed = std::max(max_fixed, ef);
    }
    for (Closure& c : closures) {
      c.true_distance = dist(truth[c.a], truth[c.b]);
      worst_closure = std::max(worst_closure, c.true_distance);
      if (c.true_distance > kFalseClosureMetres) ++false_closures;
      c.true_heading_deg = wrap(truth[c.b].h - truth[c.a].h) * 360.0 / kTwoPi;
      // How far the closure's heading is off, and how far "the same heading" would be.
      se_heading += (c.heading_deg - c.true_heading_deg) * (c.heading_deg - c.true_heading_deg);
      se_same_heading += c.true_heading_deg * c.true_heading_deg;
      const double along = between_d(truth[c.a], truth[c.b]).x;
      const double along_gate = between_d(truth[c.gate_place], truth[c.b]).x;
      se_along += (c.along_m - along) * (c.along_m - along);
      se_along_gate += along_gate * along_gate;
    }
    if (!closures.empty()) {
      const double nc = static_cast<double>(closures.size());
      rms_heading = std::sqrt(se_heading / nc);
      rms_same_heading = std::sqrt(se_same_heading / nc);
      rms_along = std::sqrt(se_along / nc);
      rms_along_gate = std::sqrt(se_along_gate / nc);
    }
  }
  const double n = static_cast<double>(total);
  const double rmse_dead = std::sqrt(se_dead / n), rmse_fixed = std::sqrt(se_fixed / n),
               rmse_online = std::sqrt(se_online / n);

  // Relocalisation events (true poses only): a kidnap (the true pose jumps more than 1 m
  // between two places of a run) or a return to known ground (a place within 1.5 m and 60
  // degrees of an older place, outside the recent exclusion, after 10 places that were not).
  struct Event {
    uint32_t place;
    std::string kind;
    int32_t relocalised_after = -1;  // places until the first correct closure / relocalisation
  };
  std::vector<Event> events;
  if (has_truth) {
    std::vector<bool> on_known(total, false);
    for (uint32_t g = 0; g < total; ++g) {
      for (uint32_t k = 0; k + static_cast<uint32_t>(o.recent) < g && !on_known[g]; ++k) {
        on_known[g] = dist(truth[k], truth[g]) <= kFalseClosureMetres &&
                      std::fabs(wrap(truth[k].h - truth[g].h)) <= kTwoPi / 6;
      }
    }
    uint32_t away = 0;
    for (uint32_t g = 1; g < total; ++g) {
      const bool same_run = places[g].session == places[g - 1].session;
      if (same_run && dist(truth[g], truth[g - 1]) > 1.0) {
        events.push_back({g, "kidnap", -1});
      } else if (on_known[g] && away >= 10) {
        events.push_back({g, "known ground again", -1});
      }
      away = on_known[g] ? 0 : away + 1;
    }
    for (Event& ev : events) {
      for (uint32_t g = ev.place; g < total; ++g) {
        const LoopClosureClass k = places[g].decision.kind;
        if ((k == LoopClosureClass::kClosure || k == LoopClosureClass::kRelocalised) &&
            dist(truth[static_cast<uint32_t>(places[g].match.place)], truth[g]) <=
                kFalseClosureMetres) {
          ev.relocalised_after = static_cast<int32_t>(g - ev.place);
          break;
        }
      }
    }
  }

  // The map: the true map's frame when there is one, else a box round the trajectory.
  std::string true_map = o.true_map;
  if (true_map.empty()) {
    const std::filesystem::path beside =
        std::filesystem::path(o.input).parent_path() / "lab_map.yaml";
    if (std::filesystem::exists(beside)) true_map = beside.string();
  }
  tools::OccupancyMapImage frame;
  tools::OccupancyMapImage truth_map;
  const bool have_map = !true_map.empty();
  if (have_map) {
    auto m = tools::load_map(true_map);
    if (!m) return fail(m.error());
    truth_map = std::move(m.value());
    frame = truth_map;
  } else {
    double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
    for (const P& p : fixed) {
      x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x),
      y1 = std::max(y1, p.y);
    }
    frame.resolution = 0.05;
    frame.origin_x = std::floor(x0 - 3.0);
    frame.origin_y = std::floor(y0 - 3.0);
    frame.width = static_cast<int>(std::ceil((x1 - frame.origin_x + 3.0) / 0.05));
    frame.height = static_cast<int>(std::ceil((y1 - frame.origin_y + 3.0) / 0.05));
  }
  std::vector<bool> use(total), use_all(total, true);
  uint32_t unreliable = 0;
  for (uint32_t g = 0; g < total; ++g) {
    use[g] = places[g].reliable;
    if (!places[g].reliable) ++unreliable;
  }
  auto grid_fixed = build_grid(sessions, fixed, use, frame);
  if (!grid_fixed) return fail(grid_fixed.error());
  auto grid_dead = build_grid(sessions, dead, use_all, frame);
  if (!grid_dead) return fail(grid_dead.error());
  tools::MapComparison cmp_fixed, cmp_dead;
  if (have_map) {
    auto c1 = tools::compare_maps(grid_fixed.value().map, truth_map);
    if (!c1) return fail(c1.error());
    cmp_fixed = c1.value();
    auto c2 = tools::compare_maps(grid_dead.value().map, truth_map);
    if (!c2) return fail(c2.error());
    cmp_dead = c2.value();
  }

  // Files.
  if (!o.out.empty()) {
    std::error_code ec;
    std::filesystem::create_directories(o.out, ec);
    if (ec) return fail(o.out + ": cannot create: " + ec.message());
    const std::string tpath = o.out + "/trajectory.csv";
    tools::OutputFile f;  // a temporary renamed over the file: every write checked
    e = f.open(tpath);
    if (!e.empty()) return fail(e);
    f.print(
        "place,run,true_x,true_y,true_heading_deg,odo_x,odo_y,odo_heading_deg,online_x,"
        "online_y,corrected_x,corrected_y,corrected_heading_deg,decision,matched,"
        "confidence,reliable\n");
    for (uint32_t g = 0; g < total; ++g) {
      const PlaceRecord& r = places[g];
      f.print("%u,%u,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%d,%.4f,%d\n", g, r.session,
              has_truth ? fmt(truth[g].x).c_str() : "", has_truth ? fmt(truth[g].y).c_str() : "",
              has_truth ? fmt(truth[g].h * 360 / kTwoPi, 2).c_str() : "", fmt(dead[g].x).c_str(),
              fmt(dead[g].y).c_str(), fmt(dead[g].h * 360 / kTwoPi, 2).c_str(),
              fmt(online[g].x).c_str(), fmt(online[g].y).c_str(), fmt(fixed[g].x).c_str(),
              fmt(fixed[g].y).c_str(), fmt(fixed[g].h * 360 / kTwoPi, 2).c_str(),
              loop_closure_class_name(r.decision.kind), r.match.place,
              static_cast<double>(r.match.confidence.raw()) / 65536.0, r.reliable ? 1 : 0);
    }
    e = f.commit();
    if (!e.empty()) return fail(e);
    const std::string cpath = o.out + "/closures.csv";
    e = f.open(cpath);
    if (!e.empty()) return fail(e);
    f.print(
        "matched_place,place,true_distance_m,image_shift_px,heading_offset_deg,"
        "true_heading_offset_deg,gate_place,along_offset_m\n");
    for (const Closure& c : closures) {
      f.print("%u,%u,%s,%s,%s,%s,%u,%s\n", c.a, c.b, has_truth ? fmt(c.true_distance).c_str() : "",
              fmt(c.shift_px).c_str(), fmt(c.heading_deg, 3).c_str(),
              has_truth ? fmt(c.true_heading_deg, 3).c_str() : "", c.gate_place,
              fmt(c.along_m).c_str());
    }
    e = f.commit();
    if (!e.empty()) return fail(e);
    if (!tools::save_map(grid_fixed.value().map, o.out + "/map", &e)) return fail(e);
    if (!tools::save_map(grid_dead.value().map, o.out + "/map_odometry", &e)) return fail(e);
  }

  const LoopClosureStats& st = gate.stats();
  auto count = [&](LoopClosureClass c) { return st.decisions[static_cast<uint32_t>(c)]; };
  if (!o.quiet) {
    std::printf("%zu places in %zu run(s); library and graph: %u nodes, %u closures\n", total,
                sessions.size(), graph.node_count(), graph.closure_count());
    std::printf(
        "decisions: closure %u, pending %u, rejected (inconsistent) %u [position %u, heading "
        "%u, image %u], aliasing %u, novelty %u, no sequence %u, relocalised %u\n",
        count(LoopClosureClass::kClosure), count(LoopClosureClass::kPending),
        count(LoopClosureClass::kRejectedInconsistent), st.rejected_position, st.rejected_heading,
        st.rejected_image, count(LoopClosureClass::kAliasing), count(LoopClosureClass::kNovelty),
        count(LoopClosureClass::kNoSequence), count(LoopClosureClass::kRelocalised));
    std::printf(
        "optimiser: %llu work units in %u slices of <= %u during the run (+%u at the end); "
        "a solve took at most %u places\n",
        static_cast<unsigned long long>(work), slices, budget, final_slices, max_solve_places);
    if (has_truth && o.reference) {
      for (const auto* ref : {&ref_linear, &ref_nonlinear}) {
        double se = 0, dmax = 0;
        for (uint32_t g = 0; g < total; ++g) {
          const P w = compose_d(anchor, between_d((*ref)[0], (*ref)[g]));
          se += std::pow(dist(w, truth[g]), 2);
          dmax = std::max(dmax, dist(to_p(graph.pose(g).value()), (*ref)[g]));
        }
        std::printf("reference %s: RMSE %.3f m; fixed point differs by at most %.4f m\n",
                    ref == &ref_linear ? "LAGO (double)" : "Gauss-Newton (double)",
                    std::sqrt(se / n), dmax);
      }
    }
    if (has_truth) {
      std::printf(
          "trajectory RMSE: dead reckoning %.3f m (max %.3f), corrected %.3f m (max %.3f), "
          "online %.3f m; corrected / dead reckoning = %.3f\n",
          rmse_dead, max_dead, rmse_fixed, max_fixed, rmse_online,
          rmse_dead > 0 ? rmse_fixed / rmse_dead : 0.0);
      std::printf(
          "false closures (true distance > %.1f m): %u of %zu accepted (largest true "
          "distance %.2f m)\n",
          kFalseClosureMetres, false_closures, closures.size(), worst_closure);
      if (!closures.empty()) {
        std::printf(
            "closure heading offsets (%s): RMS error %.2f deg (the same heading would be off by "
            "%.2f deg RMS)\n",
            o.closure_heading.c_str(), rms_heading, rms_same_heading);
        std::printf(
            "closure offsets along the route: RMS error %.3f m (the matcher's places: %.3f m); "
            "%u of %zu closures moved by the alignment\n",
            rms_along, rms_along_gate, realigned, closures.size());
      }
      for (const Event& ev : events) {
        std::printf("%s at place %u: ", ev.kind.c_str(), ev.place);
        if (ev.relocalised_after >= 0) {
          std::printf("relocalised after %d places\n", ev.relocalised_after);
        } else {
          std::printf("not relocalised\n");
        }
      }
    }
    if (have_map) {
      std::printf(
          "map vs %s: corrected %.1f %% of %llu cells right (phantom %llu, missed %llu); "
          "dead reckoning %.1f %% of %llu; %u places left out as unreliable\n",
          true_map.c_str(), 100 * cmp_fixed.accuracy(),
          static_cast<unsigned long long>(cmp_fixed.scored()),
          static_cast<unsigned long long>(cmp_fixed.free_occupied),
          static_cast<unsigned long long>(cmp_fixed.occupied_free), 100 * cmp_dead.accuracy(),
          static_cast<unsigned long long>(cmp_dead.scored()), unreliable);
    }
  }
  if (!o.json.empty()) {
    tools::OutputFile f;  // a temporary renamed over the file: every write checked
    e = f.open(o.json);
    if (!e.empty()) return fail(e);
    f.print("{\n  \"places\": %zu,\n  \"runs\": %zu,\n", total, sessions.size());
    f.print("  \"decisions\": {");
    for (uint32_t c = 0; c < kLoopClosureClasses; ++c) {
      f.print("%s\"%s\": %u", c ? ", " : "",
              loop_closure_class_name(static_cast<LoopClosureClass>(c)), st.decisions[c]);
    }
    f.print(
        "},\n  \"rejected_position\": %u,\n  \"rejected_heading\": %u,\n"
        "  \"rejected_image\": %u,\n",
        st.rejected_position, st.rejected_heading, st.rejected_image);
    f.print(
        "  \"closures\": %zu,\n  \"optimiser_work\": %llu,\n  \"slices\": %u,\n"
        "  \"final_slices\": %u,\n  \"max_solve_places\": %u,\n",
        closures.size(), static_cast<unsigned long long>(work), slices, final_slices,
        max_solve_places);
    f.print("  \"wheels\": \"%s\",\n", o.wheels.c_str());
    f.print("  \"closure_heading\": \"%s\",\n  \"hfov_deg\": %.3f,\n", o.closure_heading.c_str(),
            o.hfov);
    f.print(
        "  \"align_length\": %d,\n  \"align_range\": %d,\n  \"align_shift\": %d,\n"
        "  \"closures_realigned\": %u,\n",
        o.align_length, o.align_range, o.align_shift, realigned);
    f.print("  \"has_truth\": %s,\n", has_truth ? "true" : "false");
    if (has_truth) {
      f.print(
          "  \"rmse_dead_reckoning_m\": %.6f,\n  \"rmse_corrected_m\": %.6f,\n"
          "  \"rmse_online_m\": %.6f,\n  \"max_error_dead_reckoning_m\": %.6f,\n"
          "  \"max_error_corrected_m\": %.6f,\n  \"false_closures\": %u,\n"
          "  \"largest_closure_true_distance_m\": %.6f,\n"
          "  \"closure_heading_error_rms_deg\": %.6f,\n"
          "  \"closure_same_heading_error_rms_deg\": %.6f,\n"
          "  \"closure_along_error_rms_m\": %.6f,\n"
          "  \"closure_gate_along_error_rms_m\": %.6f,\n",
          rmse_dead, rmse_fixed, rmse_online, max_dead, max_fixed, false_closures, worst_closure,
          rms_heading, rms_same_heading, rms_along, rms_along_gate);
      f.print("  \"events\": [");
      for (size_t k = 0; k < events.size(); ++k) {
        f.print("%s{\"place\": %u, \"kind\": \"%s\", \"relocalised_after\": %d}", k ? ", " : "",
                events[k].place, events[k].kind.c_str(), events[k].relocalised_after);
      }
      f.print("],\n");
    }
    f.print("  \"has_map\": %s,\n", have_map ? "true" : "false");
    if (have_map) {
      f.print(
          "  \"map_accuracy_corrected\": %.6f,\n  \"map_cells_corrected\": %llu,\n"
          "  \"map_accuracy_dead_reckoning\": %.6f,\n  \"map_cells_dead_reckoning\": %llu,\n",
          cmp_fixed.accuracy(), static_cast<unsigned long long>(cmp_fixed.scored()),
          cmp_dead.accuracy(), static_cast<unsigned long long>(cmp_dead.scored()));
    }
    f.print("  \"unreliable_places\": %u,\n  \"relocalisations\": %u\n}\n", unreliable,
            relocalisations);
    e = f.commit();
    if (!e.empty()) return fail(e);
  }
  return kExitOk;
}

}  // namespace

void add_slam_command(CLI::App& app, Command* chosen) {
  auto o = std::make_shared<SlamOptions>();
  CLI::App* c = app.add_subcommand(
      "slam",
      "Replay a full dream recording as the robot exploring: loop closures in the run, pose "
      "graph, occupancy grid; with true poses: trajectory RMSE, false closures, map accuracy "
      "(docs/mapping.md)");
  c->add_option("recording", o->input, "Full dream recording (seqslam-sim or the robot's)")
      ->required();
  c->add_option("--prior", o->priors,
                "Earlier runs replayed first into the same library, graph and map");
  c->add_option("--out", o->out,
                "Directory for trajectory.csv, closures.csv, map.pgm/.yaml (corrected) and "
                "map_odometry.pgm/.yaml (dead reckoning)");
  c->add_option("--true-map", o->true_map,
                "True map YAML to score against (default: lab_map.yaml beside the recording)");
  c->add_option("--json", o->json, "Write the figures as JSON");
  c->add_option("--preprocess", o->preprocess, "Preprocessing")
      ->check(CLI::IsMember(preprocessing_names()))
      ->capture_default_str();
  c->add_option("--seq-len", o->seq_len, "Sequence length S")
      ->check(tools::whole<int>(1, kMaxSeq))
      ->capture_default_str();
  c->add_option("--window", o->window, "Local normalisation window W (0 = off)")
      ->check(tools::whole<int>(0, kMaxWindow))
      ->capture_default_str();
  c->add_option("--exclusion", o->exclusion, "Runner-up exclusion R")
      ->check(tools::whole<int>(0, 65535))
      ->capture_default_str();
  c->add_option("--threshold", o->threshold, "Confidence threshold (0..1)")
      ->check(CLI::Validator(
          [](std::string& v) {
            UQ16_16 ignored;
            return parse_threshold(v, &ignored);
          },
          ""))
      ->capture_default_str();
  c->add_option("--recent", o->recent, "Newest places not matched against")
      ->check(tools::whole<int>(1, 65535))
      ->capture_default_str();
  c->add_option("--drift-base", o->drift_base, "Gate: position bound at a fix, metres")
      ->check(tools::real(0.0, 1000.0))
      ->capture_default_str();
  c->add_option("--drift-rate", o->drift_rate, "Gate: bound growth per metre driven")
      ->check(tools::real(0.0, 1.0))
      ->capture_default_str();
  c->add_option("--heading-base", o->heading_base, "Gate: heading bound at a fix, degrees")
      ->check(tools::real(0.0, 180.0))
      ->capture_default_str();
  c->add_option("--heading-rate", o->heading_rate, "Gate: heading bound growth, degrees per metre")
      ->check(tools::real(0.0, 10.0))
      ->capture_default_str();
  c->add_option("--near", o->near, "Gate: aliasing radius, metres (plus the drift bound)")
      ->check(tools::real(0.0, 1000.0))
      ->capture_default_str();
  c->add_option("--confirm", o->confirm, "Gate: consecutive consistent matches for a closure")
      ->check(tools::whole<int>(1, 1000))
      ->capture_default_str();
  c->add_option("--max-advance", o->max_advance, "Gate: matched-place step between matches")
      ->check(tools::whole<int>(0, 1000))
      ->capture_default_str();
  c->add_option("--relocalise", o->relocalise,
                "Gate: confident, self-consistent matches odometry cannot explain before "
                "relocalising (0 = never)")
      ->check(tools::whole<int>(0, 1000))
      ->capture_default_str();
  c->add_option("--relocalise-turn", o->relocalise_turn,
                "Gate: turn (degrees) the relocalising run must include, seen alike by odometry "
                "and by the matched places (0 = none)")
      ->check(tools::real(0.0, 180.0))
      ->capture_default_str();
  c->add_option("--max-image-rank", o->max_image_rank,
                "Gate: reject a confident match when more than this fraction of the known places "
                "are closer to the current image than the matched place (1 = never)")
      ->check(tools::real(0.0, 1.0))
      ->capture_default_str();
  c->add_option("--closure-weight", o->closure_weight,
                "Closure edge position information (1 = as sure as 1 m of odometry)")
      ->check(tools::real(0.001, 1000.0))
      ->capture_default_str();
  c->add_option("--closure-heading-weight", o->closure_heading_weight,
                "Closure edge heading information")
      ->check(tools::real(0.0, 1000.0))
      ->capture_default_str();
  c->add_option("--closure-heading", o->closure_heading,
                "Closure heading offset: image (from the horizontal shift between the two "
                "places' images) or none (the same heading)")
      ->check(CLI::IsMember({"image", "none"}))
      ->capture_default_str();
  c->add_option("--hfov", o->hfov,
                "Effective horizontal field of view, degrees, that turns the image shift into a "
                "heading (--closure-heading image; calibrated on the simulator, docs/mapping.md)")
      ->check(tools::real(1.0, 179.0))
      ->capture_default_str();
  c->add_option("--max-shift", o->max_shift,
                "Columns searched each way for the image shift (--closure-heading image)")
      ->check(tools::whole<int>(1, kMaxSubpixelShift))
      ->capture_default_str();
  c->add_option("--align-length", o->align_length,
                "Closure alignment along the matched pass: places compared (0 = off: the closure "
                "joins the matched place, same position; docs/mapping.md)")
      ->check(tools::whole<int>(0, kMaxAlignLength))
      ->capture_default_str();
  c->add_option("--align-range", o->align_range,
                "Closure alignment: places searched each way of the matched one")
      ->check(tools::whole<int>(0, kMaxAlignOffset))
      ->capture_default_str();
  c->add_option("--align-shift", o->align_shift,
                "Closure alignment: columns each image pair may be shifted (heading differences)")
      ->check(tools::whole<int>(0, 16))
      ->capture_default_str();
  c->add_option("--wheels", o->wheels,
                "Replay the encoders with these wheel constants, LEFT,RIGHT,TRACK in metres "
                "(circumferences and track width; e.g. the simulator's true ones), instead of "
                "the recording's place poses");
  c->add_option("--budget", o->budget, "Optimiser work units per place")
      ->check(tools::whole<int>(1, 10000000))
      ->capture_default_str();
  c->add_flag("--quiet", o->quiet, "No summary on stdout");
  c->add_flag("--reference", o->reference,
              "Also solve the final graph in double precision (LAGO and Gauss-Newton) and "
              "print their RMSE");
  c->callback([o, chosen] { *chosen = [o] { return run_slam(*o); }; });
}

}  // namespace seqslam::cli
