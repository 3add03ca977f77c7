// seqslam slam: replays a full dream recording as the robot would explore (docs/mapping.md):
// per place Localiser::observe (the run against its own older places), the loop-closure gate
// (loop_closure.h), a pose-graph node per place with the odometry step as its edge, accepted
// closures as closure edges, a fixed budget of optimise_step work per place, and at the end
// the occupancy grid rebuilt from every infrared snapshot at the optimised poses. With true
// poses in the recording it scores the result: trajectory RMSE of dead reckoning and of the
// corrected poses, false closures, map accuracy against the simulator's true map and its
// occupied-cell precision and recall near the true path, places to relocalise after a kidnap
// or after re-entering known ground.
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
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "cli_common.h"
#include "reference.h"
#include "seqslam/difference.h"
#include "seqslam/explorer.h"
#include "seqslam/localiser.h"
#include "seqslam/odometry.h"
#include "seqslam/place_library.h"
#include "seqslam/preprocess.h"
#include "seqslam/hal/file_block_device.h"
#include "seqslam/session/session.h"
#include "seqslam/storage/dream.h"
#include "seqslam/storage/dream_replay.h"
#include "seqslam/storage/run_files.h"
#include "seqslam_tools/cli_numbers.h"
#include "seqslam_tools/graph_csv.h"
#include "seqslam_tools/host_session.h"
#include "seqslam_tools/grid_export.h"
#include "seqslam_tools/image_io.h"
#include "seqslam_tools/outcome.h"
#include "seqslam_tools/output_file.h"
#include "seqslam_tools/pose_graph_export.h"
#include "seqslam_tools/q_format.h"
#include "seqslam_tools/ram_tile_store.h"
#include "seqslam_tools/slam_figures.h"
#include "seqslam_tools/settings_cli.h"
#include "slam_calibration.h"

namespace seqslam::cli {

namespace {

constexpr double kTwoPi = 6.283185307179586;
constexpr uint32_t kMaxPlaces = 4000;  // library and graph capacity of the replay
constexpr uint16_t kMaxSeq = 100;
constexpr double kFalseClosureMetres = 1.5;  // the pair ground truth's gate (simulator.md)

// A default shown in --help: rounded to 6 decimals (a binary angle's degrees are not exact).
double shown(double v) {
  return std::round(v * 1e6) / 1e6;
}

// The run configuration `seqslam slam` runs: explore (teach + repeat against the run's own
// places, and mapping) with the settings table's defaults, so `seqslam slam` without options
// is the robot's explore mode. The image size, the spacing and (without --wheels) the wheel
// constants come from the recording.
storage::RunConfig slam_defaults() {
  storage::RunConfig c;
  c.modes = storage::kModeTeach | storage::kModeRepeat | storage::kModeExplore;
  return c;
}

struct SlamOptions {
  std::string input;
  std::vector<std::string> priors;
  std::string out;
  std::string true_map;  // default: lab_map.yaml beside the input, if there
  std::string json;
  std::string g2o;  // the explorer's graph as g2o; empty: none
  // The localiser's and the explorer's settings: the settings table's options.
  SettingOptions<> settings;
  // Wheel constants "LEFT,RIGHT,TRACK" (metres: circumferences, track width) to replay the
  // encoders with instead of the recording's; empty: the recording's.
  std::string wheels;
  // The true wheel constants, LEFT,RIGHT,TRACK, to report the calibration against; empty: none.
  std::string true_wheels;
  // Where to write the calibrated constants (LEFT,RIGHT,TRACK, what --wheels reads); empty: no
  // file. Written only when the calibration is accepted.
  std::string calibration_out;
  // Obstacles near the path: the band round the true path the maps are scored in, metres.
  double path_band = 1.0;
  bool quiet = false;
  bool reference = false;
};

// ---------------------------------------------------------------------------------------
// Conversions (host: double precision for scoring only; the replay itself is the core's).

struct P {
  double x = 0, y = 0, h = 0;  // metres, radians
};

std::string fmt(double v, int decimals = 4) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", decimals, v);
  return buf;
}

P to_p(const Pose2& p) {
  return {tools::to_double(p.x), tools::to_double(p.y), tools::to_radians(p.heading)};
}

Pose2 to_pose2(const P& p) {
  return Pose2{tools::from_double<Q31_32>(p.x), tools::from_double<Q31_32>(p.y),
               tools::angle_from_radians(p.h)};
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
  uint32_t places_before = 0;  // places of the session recorded before it (0: before the first)
  // The place it hangs from (the session's first for snapshots before any place).
  uint32_t place() const { return places_before > 0 ? places_before - 1 : 0; }
  Pose2 odometry{};  // the session's odometry pose at this snapshot
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

// `base` with the wheel constants (circumferences, track) of `wheels`.
OdometryConfig apply_wheels(OdometryConfig base, const OdometryConfig& wheels) {
  base.circumference_left = wheels.circumference_left;
  base.circumference_right = wheels.circumference_right;
  base.track_width = wheels.track_width;
  return base;
}

// `wheels` non-null: the encoders are replayed with its circumferences and track width (the
// rest as the recording's header) and the places take the odometry pose of their snapshot;
// else the places keep the pose the recording gives them.
// A true pose farther from the run's first one than the odometry has travelled by then, plus a
// margin, is not a pose of this run (a damaged or foreign truth record): scored against, it
// gives absurd figures (an RMSE of 138 619 474 m for a record at x = -2^30 m). The margin
// covers odometry drift and a robot carried elsewhere (the simulator's kidnaps and jumps move
// it within the lab, tens of metres). "" or the message.
constexpr double kTruthMarginMetres = 1000.0;

std::string check_truth(const Session& s) {
  if (!s.has_truth || s.truth.empty()) return {};
  const P first = to_p(s.truth[0]);
  double travelled = 0;
  for (size_t i = 0; i < s.truth.size(); ++i) {
    if (i > 0) {
      const P a = to_p(s.odometry[i - 1]);
      const P b = to_p(s.odometry[i]);
      travelled += std::hypot(b.x - a.x, b.y - a.y);
    }
    const P t = to_p(s.truth[i]);
    const double d = std::hypot(t.x - first.x, t.y - first.y);
    if (d > travelled + kTruthMarginMetres) {
      return s.path + ": place " + std::to_string(i) + "'s true pose (" + fmt(t.x, 3) + ", " +
             fmt(t.y, 3) + ") m is " + fmt(d, 3) + " m from place 0's, but the odometry has " +
             "travelled only " + fmt(travelled, 3) + " m by then (+" + fmt(kTruthMarginMetres, 0) +
             " m allowed): not a true pose of this run (a damaged or foreign truth record)";
    }
  }
  return {};
}

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
  const OdometryConfig constants =
      wheels != nullptr ? apply_wheels(s.header.wheels, *wheels) : s.header.wheels;
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
      scan.places_before = static_cast<uint32_t>(s.images.size());
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
      // The encoders' pose, as the session computes it (the pose the place record holds is
      // what the recording run computed: an output, not an input).
      s.odometry.push_back(odometry.pose());
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
  e = check_truth(s);
  if (!e.empty()) return tools::Error{e};
  return s;
}

// ---------------------------------------------------------------------------------------
// The sensors from the recording's header, as the robot's explore mode takes them.
std::vector<RangeSensor> sensors_of(const storage::DreamHeader& h) {
  std::vector<RangeSensor> out;
  for (uint32_t k = 0; k < h.infrared_count && k < hal::kMaxInfrared; ++k)
    out.push_back(storage::range_sensor_of(h.infrared[k]));
  return out;
}

struct GridResult {
  tools::OccupancyMapImage map;
  uint64_t scans = 0;
  uint64_t rejected = 0;  // readings out of range, rays starting outside the bounds
};

// Rebuilds a grid from every scan at the given world poses of the places. A scan hangs from
// its place by the odometry between them, composed with the core's fixed-point compose() and
// relative_pose() as Explorer::scan() does; the rays are the core grid's (insert_reading), so
// only the world pose of each place (the graph's, aligned to the truth in double) is the
// host's. `use[g]` false: the place's scans are left out.
tools::Outcome<GridResult> build_grid(const std::vector<Session>& sessions,
                                      const std::vector<P>& world, const std::vector<bool>& use,
                                      const tools::OccupancyMapImage& frame) {
  tools::RamTileStore store;
  static OccupancyGridStorage<8> ram;
  GridConfig gc;
  gc.origin_x = tools::from_double<Q31_32>(frame.origin_x);
  gc.origin_y = tools::from_double<Q31_32>(frame.origin_y);
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
      const size_t g = base + scan.place();
      if (!use[g]) continue;
      const Pose2 pose =
          compose(to_pose2(world[g]), relative_pose(s.odometry[scan.place()], scan.odometry));
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
  std::vector<std::string> outputs = {o.json, o.calibration_out, o.g2o};
  if (!o.out.empty()) {
    for (const char* name : {"trajectory.csv", "closures.csv", "map.pgm", "map.yaml",
                             "map_odometry.pgm", "map_odometry.yaml", "explorer_map.pgm",
                             "explorer_map.yaml", "graph_nodes.csv", "graph_edges.csv"}) {
      outputs.push_back(o.out + "/" + name);
    }
  }
  for (const std::string& output : outputs) {
    if (const int rc = refuse_inputs_as_outputs(inputs, {output}); rc != kExitOk) return rc;
  }
  return kExitOk;
}

// The run's settings from the options.
struct SlamSetup {
  storage::RunConfig run = slam_defaults();
  bool use_wheels = false;
  OdometryConfig wheels{};
  std::optional<OdometryConfig> true_wheels;
};

// kExitOk, or the usage error's status (its message printed).
int slam_setup(const SlamOptions& o, SlamSetup* out) {
  o.settings.apply(&out->run);
  const storage::SettingsCheck check = storage::check_run_settings(out->run);
  if (!check.ok()) {
    return usage_error("a setting is out of range: --" + setting_name(check.setting));
  }
  const char* kWheelsHelp =
      " wants LEFT,RIGHT,TRACK in metres: circumferences above 0 and below 16, the track above "
      "0 and below 100 (e.g. 0.532,0.53227,0.474)";
  if (!o.wheels.empty()) {
    if (!parse_wheel_constants(o.wheels, &out->wheels))
      return usage_error(std::string("--wheels") + kWheelsHelp);
    out->use_wheels = true;
  }
  if (!o.true_wheels.empty()) {
    OdometryConfig truth;
    if (!parse_wheel_constants(o.true_wheels, &truth))
      return usage_error(std::string("--true-wheels") + kWheelsHelp);
    out->true_wheels = truth;
  }
  return kExitOk;
}

// The runs (priors first, then the input); "" or what is wrong. They must share the image
// size and the capture spacing (one library, one closure scale).
std::string load_sessions(const SlamOptions& o, const SlamSetup& setup,
                          std::vector<Session>* sessions) {
  std::vector<std::string> paths = o.priors;
  paths.push_back(o.input);
  size_t total = 0;
  for (const std::string& path : paths) {
    auto s = load_session(path, setup.use_wheels ? &setup.wheels : nullptr);
    if (!s) return s.error();
    const storage::DreamHeader& first =
        sessions->empty() ? s.value().header : sessions->front().header;
    if (s.value().header.image_size().width != first.image_size().width ||
        s.value().header.image_size().height != first.image_size().height) {
      return path + ": its images are of another size than the first run's";
    }
    if (s.value().header.spacing != first.spacing) {
      return path + ": its capture spacing differs from the first run's";
    }
    total += s.value().images.size();
    sessions->push_back(std::move(s.value()));
  }
  if (total > kMaxPlaces) {
    return "the runs have " + std::to_string(total) + " places; at most " +
           std::to_string(kMaxPlaces) + " are supported";
  }
  return {};
}

// What the replay saw per place and per closure.
struct Replay {
  std::vector<PlaceRecord> places;
  std::vector<Closure> closures;
  uint32_t max_solve_places = 0;  // places from a closure to convergence, the largest solve
};

// The robot's explore mode over recorded runs: the session (the firmware's pipeline, storage
// on the PC's heap) fed each recording's snapshots and frames through the dream replay, the
// HAL stand-in the firmware replays from on the PC and on the emulated board. A recording's
// places are its captures: the replay latches the frame recorded after a snapshot, where the
// firmware's trigger fires with the recording's own wheels and spacing (with other --wheels
// the places stay the recording's and take the odometry of their snapshot).
class ExploreReplay {
 public:
  std::string configure(const SlamSetup& setup, const std::vector<Session>& sessions);
  std::string run(const std::vector<Session>& sessions, Replay* out);
  // The robot's map again at the optimised poses: every run's snapshots and places in
  // recording order through the session's rebuild, as the firmware does after its last place.
  std::string rebuild_map(const std::vector<Session>& sessions);
  const Explorer& explorer() const { return host_.session().explorer(); }

 private:
  // Calls place(frame, capture) for every recorded place of `s` (rebuild: the rebuild's
  // snapshots), after the session has taken the snapshot before it.
  template <typename OnPlace>
  std::string replay(const Session& s, bool rebuild, OnPlace place);

  tools::HostSession host_;
  std::vector<uint8_t> buffer_ = std::vector<uint8_t>(storage::kDreamRecordMax);
};

std::string ExploreReplay::configure(const SlamSetup& setup,
                                     const std::vector<Session>& sessions) {
  const storage::DreamHeader& header = sessions.back().header;
  storage::RunConfig run = setup.run;
  run.mapping = header.mapping;
  run.spacing = header.spacing;
  run.odometry = setup.use_wheels ? apply_wheels(header.wheels, setup.wheels) : header.wheels;
  const uint16_t width = header.image_size().width;
  if (run.explore.closure_shift >= width) return "--closure-shift must be less than the image width";
  if (run.explore.align.length > 0 && run.explore.align.max_shift >= width) {
    return "--align-shift must be less than the image width";
  }
  tools::HostSessionOptions o;
  o.search = session::Search::kFull;
  for (const Session& s : sessions)
    o.places += static_cast<uint32_t>(s.images.size());
  o.sensors = sensors_of(header);
  return host_.configure(run, o);
}

template <typename OnPlace>
std::string ExploreReplay::replay(const Session& s, bool rebuild, OnPlace place) {
  session::Session& session = host_.session();
  hal::FileBlockDevice file;
  if (file.open(s.path, false) != Status::kOk) return s.path + ": " + file.error();
  storage::DreamReplay replay;
  storage::DreamProblem dp = storage::DreamProblem::kNone;
  Status st = replay.open(file, Span<uint8_t>(buffer_.data(), buffer_.size()), &dp);
  if (st == Status::kOk) st = replay.configure(s.header.mapping);
  if (st != Status::kOk) return s.path + ": " + storage::dream_problem_text(dp);
  uint32_t capture = 0;
  for (;;) {
    hal::SensorSnapshot snap;
    st = replay.next(&snap);
    if (st == Status::kOutOfRange) break;
    if (st != Status::kOk) return s.path + ": a damaged record (" + status_name(st) + ")";
    if (rebuild) {
      (void)session.rebuild_snapshot(snap);
    } else {
      (void)session.snapshot(snap);
    }
    hal::Frame frame;
    st = replay.capture();
    if (st == Status::kOk) st = replay.read(&frame);
    if (st == Status::kUnavailable) continue;
    if (st != Status::kOk) return s.path + ": a frame could not be read (" + status_name(st) + ")";
    const std::string e = place(frame, capture++);
    if (!e.empty()) return e;
  }
  if (capture != s.images.size()) {
    return s.path + ": the replay gave " + std::to_string(capture) + " places of " +
           std::to_string(s.images.size());
  }
  return {};
}

// Why the graph took no node for place `i` of `s`: it is full, or the place's odometry (the
// encoders') is farther from the previous node's than an edge holds (Q7.24: 128 m), which is
// no "full graph".
std::string node_refused(const Session& s, uint32_t i, const PoseGraph& graph) {
  const uint32_t nodes = graph.node_count();
  if (nodes >= graph.node_capacity()) {
    return "the pose graph is full (" + std::to_string(nodes) + " nodes, its capacity)";
  }
  std::string from = "the previous run's last place";
  double jump = 0;
  if (i > 0) {
    from = "place " + std::to_string(i - 1);
    const P a = to_p(s.odometry[i - 1]);
    const P b = to_p(s.odometry[i]);
    jump = std::hypot(b.x - a.x, b.y - a.y);
  }
  return s.path + ": place " + std::to_string(i) + ": its odometry pose is " +
         (i > 0 ? fmt(jump / 1000.0, 3) + " km from " + from + "'s"
                : "too far from " + from + "'s") +
         ", beyond what one pose-graph edge holds (128 m): the recording's encoders jump (damaged "
         "or not one run)";
}

std::string ExploreReplay::run(const std::vector<Session>& sessions, Replay* out) {
  session::Session& session = host_.session();
  uint32_t solve_places = 0;
  bool solving = false;
  for (uint32_t si = 0; si < sessions.size(); ++si) {
    const Session& s = sessions[si];
    session.begin_run();  // a sequence never spans two runs; the odometry starts afresh
    const std::string e = replay(s, false, [&](const hal::Frame& frame, uint32_t i) {
      const uint32_t g = static_cast<uint32_t>(out->places.size());
      const Pose2 pose = session.pose();
      PlaceRecord rec;
      rec.session = si;
      rec.odometry = to_p(pose);
      session::PlaceStep step;
      const Status os = session.place(ImageView{frame.gray, frame.size}, pose, g, &step);
      if (os != Status::kOk) {
        return s.path + ": place " + std::to_string(i) + ": observe failed (" + status_name(os) +
               ")";
      }
      if (step.explore_status != Status::kOk) {
        return std::string("explorer: ") + status_name(step.explore_status);
      }
      if (!step.explored || step.explore.node < 0) {
        return node_refused(s, i, session.explorer().graph());
      }
      rec.match = step.match;
      const ExplorerStep& x = step.explore;
      if (x.closure_to >= 0) {
        Closure c;
        c.a = static_cast<uint32_t>(x.closure_to);
        c.b = static_cast<uint32_t>(x.node);
        c.gate_place = x.gate_place;
        c.along_m = tools::to_double(x.closure.dx);
        c.shift_px = tools::to_double(x.shift);
        c.heading_deg = tools::to_degrees(x.closure.dtheta);
        out->closures.push_back(c);
        if (!solving) solve_places = 0;
        solving = true;
      }
      if (solving) {
        ++solve_places;
        if (x.progress.converged) {
          out->max_solve_places = std::max(out->max_solve_places, solve_places);
          solving = false;
        }
      }
      rec.decision = x.decision;
      rec.online = to_p(session.explorer().graph().pose(static_cast<uint32_t>(x.node)).value());
      out->places.push_back(rec);
      return std::string();
    });
    if (!e.empty()) return e;
  }
  // Finish the optimisation after the last place (as the robot does while standing).
  if (session.finish(1000000) != Status::kOk) return "the pose graph did not converge";
  for (uint32_t g = 0; g < out->places.size(); ++g)
    out->places[g].reliable = session.explorer().trusted(g);
  return {};
}

std::string ExploreReplay::rebuild_map(const std::vector<Session>& sessions) {
  session::Session& session = host_.session();
  Status st = session.begin_rebuild();
  if (st != Status::kOk) return std::string("rebuilding the explorer's map: ") + status_name(st);
  uint32_t base = 0;
  for (const Session& s : sessions) {
    session.begin_run();
    const std::string e = replay(s, true, [&](const hal::Frame&, uint32_t i) {
      session.rebuild_place(base + i);
      return std::string();
    });
    if (!e.empty()) return e;
    base += static_cast<uint32_t>(s.images.size());
  }
  session.end_rebuild();
  st = session.explorer().flush_map();
  if (st != Status::kOk) return std::string("rebuilding the explorer's map: ") + status_name(st);
  return {};
}

// The graph solved in double precision (tools/reference): LAGO directly and the full
// nonlinear problem, to tell the solver's part from the model's (--reference).
void reference_solutions(const PoseGraph& graph, const P& first, std::vector<P>* linear,
                         std::vector<P>* nonlinear) {
  const std::vector<reference::PoseEdgeRef> edges = reference::pose_edges_of(graph);
  const auto lin = reference::pose_graph_linear(static_cast<int>(graph.node_count()), edges,
                                                {first.x, first.y, first.h});
  std::vector<reference::PoseRef> init;
  for (const auto& p : lin)
    init.push_back({p.x, p.y, p.theta});
  const auto nl = reference::pose_graph_gauss_newton(edges, init, 1e-4, 1e-4);
  for (const auto& p : lin)
    linear->push_back({p.x, p.y, p.theta});
  for (const auto& p : nl)
    nonlinear->push_back({p.x, p.y, p.theta});
}

// The trajectories in the world frame (aligned at the first place's true pose when known).
struct Trajectories {
  size_t total = 0;
  bool has_truth = true;
  P anchor;
  std::vector<P> truth, dead, online, fixed;
};

Trajectories trajectories(const std::vector<Session>& sessions, const Replay& replay,
                          const PoseGraph& graph) {
  Trajectories t;
  for (const Session& s : sessions) {
    t.has_truth = t.has_truth && s.has_truth;
    for (size_t i = 0; i < s.images.size(); ++i)
      t.truth.push_back(s.has_truth ? to_p(s.truth[i]) : P{});
  }
  t.total = t.truth.size();
  t.anchor = t.has_truth ? t.truth[0] : P{};
  const P first = to_p(graph.pose(0).value());
  for (uint32_t g = 0; g < t.total; ++g) {
    t.dead.push_back(
        compose_d(t.anchor, between_d(replay.places[0].odometry, replay.places[g].odometry)));
    t.online.push_back(compose_d(t.anchor, between_d(first, replay.places[g].online)));
    t.fixed.push_back(compose_d(t.anchor, between_d(first, to_p(graph.pose(g).value()))));
  }
  return t;
}

struct Event {
  uint32_t place;
  std::string kind;
  int32_t relocalised_after = -1;  // places until the first correct closure / relocalisation
};

struct Scores {
  double rmse_dead = 0, rmse_fixed = 0, rmse_online = 0, max_dead = 0, max_fixed = 0;
  uint32_t false_closures = 0;
  double worst_closure = 0;
  double rms_heading = 0, rms_same_heading = 0;  // closure headings against the truth
  double rms_along = 0, rms_along_gate = 0;      // the edge's dx and the matcher's place
  uint32_t realigned = 0;
  std::vector<Event> events;
};

// Relocalisation events (true poses only): a kidnap (the true pose jumps more than 1 m
// between two places of a run) or a return to known ground (a place within 1.5 m and 60
// degrees of an older place, outside the recent exclusion, after 10 places that were not).
std::vector<Event> relocalisation_events(const Trajectories& t, const Replay& replay,
                                         uint32_t recent) {
  std::vector<Event> events;
  std::vector<bool> on_known(t.total, false);
  for (uint32_t g = 0; g < t.total; ++g) {
    for (uint32_t k = 0; k + recent < g && !on_known[g]; ++k) {
      on_known[g] = dist(t.truth[k], t.truth[g]) <= kFalseClosureMetres &&
                    std::fabs(wrap(t.truth[k].h - t.truth[g].h)) <= kTwoPi / 6;
    }
  }
  uint32_t away = 0;
  for (uint32_t g = 1; g < t.total; ++g) {
    const bool same_run = replay.places[g].session == replay.places[g - 1].session;
    if (same_run && dist(t.truth[g], t.truth[g - 1]) > 1.0) {
      events.push_back({g, "kidnap", -1});
    } else if (on_known[g] && away >= 10) {
      events.push_back({g, "known ground again", -1});
    }
    away = on_known[g] ? 0 : away + 1;
  }
  for (Event& ev : events) {
    for (uint32_t g = ev.place; g < t.total; ++g) {
      const LoopClosureClass k = replay.places[g].decision.kind;
      if ((k == LoopClosureClass::kClosure || k == LoopClosureClass::kRelocalised) &&
          dist(t.truth[static_cast<uint32_t>(replay.places[g].match.place)], t.truth[g]) <=
              kFalseClosureMetres) {
        ev.relocalised_after = static_cast<int32_t>(g - ev.place);
        break;
      }
    }
  }
  return events;
}

// The trajectory's and the closures' errors against the truth (fills each closure's truth).
Scores score(const Trajectories& t, Replay* replay, uint32_t recent) {
  Scores sc;
  for (const Closure& c : replay->closures)
    if (c.a != c.gate_place) ++sc.realigned;
  if (!t.has_truth) return sc;
  double se_dead = 0, se_fixed = 0, se_online = 0;
  for (uint32_t g = 0; g < t.total; ++g) {
    const double ed = dist(t.dead[g], t.truth[g]), ef = dist(t.fixed[g], t.truth[g]);
    se_dead += ed * ed;
    se_fixed += ef * ef;
    se_online += std::pow(dist(t.online[g], t.truth[g]), 2);
    sc.max_dead = std::max(sc.max_dead, ed);
    sc.max_fixed = std::max(sc.max_fixed, ef);
  }
  const double n = static_cast<double>(t.total);
  sc.rmse_dead = std::sqrt(se_dead / n);
  sc.rmse_fixed = std::sqrt(se_fixed / n);
  sc.rmse_online = std::sqrt(se_online / n);
  double se_heading = 0, se_same_heading = 0, se_along = 0, se_along_gate = 0;
  for (Closure& c : replay->closures) {
    c.true_distance = dist(t.truth[c.a], t.truth[c.b]);
    sc.worst_closure = std::max(sc.worst_closure, c.true_distance);
    if (c.true_distance > kFalseClosureMetres) ++sc.false_closures;
    c.true_heading_deg = wrap(t.truth[c.b].h - t.truth[c.a].h) * 360.0 / kTwoPi;
    // How far the closure's heading is off, and how far "the same heading" would be.
    se_heading += (c.heading_deg - c.true_heading_deg) * (c.heading_deg - c.true_heading_deg);
    se_same_heading += c.true_heading_deg * c.true_heading_deg;
    const double along = between_d(t.truth[c.a], t.truth[c.b]).x;
    const double along_gate = between_d(t.truth[c.gate_place], t.truth[c.b]).x;
    se_along += (c.along_m - along) * (c.along_m - along);
    se_along_gate += along_gate * along_gate;
  }
  if (!replay->closures.empty()) {
    const double nc = static_cast<double>(replay->closures.size());
    sc.rms_heading = std::sqrt(se_heading / nc);
    sc.rms_same_heading = std::sqrt(se_same_heading / nc);
    sc.rms_along = std::sqrt(se_along / nc);
    sc.rms_along_gate = std::sqrt(se_along_gate / nc);
  }
  sc.events = relocalisation_events(t, *replay, recent);
  return sc;
}

// The scored maps: built from the corrected and the dead-reckoning poses in the true map's
// frame (a box round the trajectory without one), for scoring against the true map.
struct Maps {
  bool have_map = false;
  std::string true_map;
  tools::OccupancyMapImage truth_map;
  GridResult fixed, dead;
  tools::MapComparison cmp_fixed, cmp_dead;
  std::optional<tools::SlamNearPathFigures> near_path;  // true map and true poses
  uint32_t unreliable = 0;
};

// Both maps against the true map near the true path (compare_maps_near_path): the band of
// `band` metres round the true poses, a new piece at each run and each jump.
tools::Outcome<tools::SlamNearPathFigures> score_near_path(const Maps& m, const Trajectories& t,
                                                           const Replay& replay, double band) {
  std::vector<tools::PathPoint> path;
  for (uint32_t g = 0; g < t.total; ++g)
    path.push_back({t.truth[g].x, t.truth[g].y, replay.places[g].session});
  tools::SlamNearPathFigures n;
  n.band_m = band;
  auto fixed = tools::compare_maps_near_path(m.fixed.map, m.truth_map, path, band);
  if (!fixed) return tools::Error{fixed.error()};
  n.corrected = fixed.value();
  auto dead = tools::compare_maps_near_path(m.dead.map, m.truth_map, path, band);
  if (!dead) return tools::Error{dead.error()};
  n.dead_reckoning = dead.value();
  return n;
}

tools::Outcome<Maps> build_maps(const SlamOptions& o, const std::vector<Session>& sessions,
                                const Trajectories& t, const Replay& replay) {
  Maps m;
  m.true_map = o.true_map;
  if (m.true_map.empty()) {
    const std::filesystem::path beside =
        std::filesystem::path(o.input).parent_path() / "lab_map.yaml";
    if (std::filesystem::exists(beside)) m.true_map = beside.string();
  }
  tools::OccupancyMapImage frame;
  m.have_map = !m.true_map.empty();
  if (m.have_map) {
    auto loaded = tools::load_map(m.true_map);
    if (!loaded) return tools::Error{loaded.error()};
    m.truth_map = std::move(loaded.value());
    frame = m.truth_map;
  } else {
    double x0 = 1e9, y0 = 1e9, x1 = -1e9, y1 = -1e9;
    for (const P& p : t.fixed) {
      x0 = std::min(x0, p.x), y0 = std::min(y0, p.y), x1 = std::max(x1, p.x),
      y1 = std::max(y1, p.y);
    }
    frame.resolution = 0.05;
    frame.origin_x = std::floor(x0 - 3.0);
    frame.origin_y = std::floor(y0 - 3.0);
    frame.width = static_cast<int>(std::ceil((x1 - frame.origin_x + 3.0) / 0.05));
    frame.height = static_cast<int>(std::ceil((y1 - frame.origin_y + 3.0) / 0.05));
  }
  std::vector<bool> use(t.total), use_all(t.total, true);
  for (uint32_t g = 0; g < t.total; ++g) {
    use[g] = replay.places[g].reliable;
    if (!use[g]) ++m.unreliable;
  }
  auto fixed = build_grid(sessions, t.fixed, use, frame);
  if (!fixed) return tools::Error{fixed.error()};
  m.fixed = std::move(fixed.value());
  auto dead = build_grid(sessions, t.dead, use_all, frame);
  if (!dead) return tools::Error{dead.error()};
  m.dead = std::move(dead.value());
  if (m.have_map) {
    auto c1 = tools::compare_maps(m.fixed.map, m.truth_map);
    if (!c1) return tools::Error{c1.error()};
    m.cmp_fixed = c1.value();
    auto c2 = tools::compare_maps(m.dead.map, m.truth_map);
    if (!c2) return tools::Error{c2.error()};
    m.cmp_dead = c2.value();
  }
  if (m.have_map && t.has_truth) {
    auto near = score_near_path(m, t, replay, o.path_band);
    if (!near) return tools::Error{near.error()};
    m.near_path = near.value();
  }
  return m;
}

// --out: the trajectory and closures (CSV), the scored maps, and what the robot would save:
// its map (the explorer's grid, the odometry frame) and its graph, in the files `seqslam disk
// map` writes from the card, so the two can be compared byte for byte.
std::string write_out_dir(const SlamOptions& o, const Trajectories& t, const Replay& replay,
                          const Maps& maps, const Explorer& explorer) {
  std::error_code ec;
  std::filesystem::create_directories(o.out, ec);
  if (ec) return o.out + ": cannot create: " + ec.message();
  tools::OutputFile f;  // a temporary renamed over the file: every write checked
  std::string e = f.open(o.out + "/trajectory.csv");
  if (!e.empty()) return e;
  f.print(
      "place,run,true_x,true_y,true_heading_deg,odo_x,odo_y,odo_heading_deg,online_x,"
      "online_y,corrected_x,corrected_y,corrected_heading_deg,decision,matched,"
      "confidence,reliable\n");
  const bool truth = t.has_truth;
  for (uint32_t g = 0; g < t.total; ++g) {
    const PlaceRecord& r = replay.places[g];
    f.print("%u,%u,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%s,%d,%.4f,%d\n", g, r.session,
            truth ? fmt(t.truth[g].x).c_str() : "", truth ? fmt(t.truth[g].y).c_str() : "",
            truth ? fmt(t.truth[g].h * 360 / kTwoPi, 2).c_str() : "", fmt(t.dead[g].x).c_str(),
            fmt(t.dead[g].y).c_str(), fmt(t.dead[g].h * 360 / kTwoPi, 2).c_str(),
            fmt(t.online[g].x).c_str(), fmt(t.online[g].y).c_str(), fmt(t.fixed[g].x).c_str(),
            fmt(t.fixed[g].y).c_str(), fmt(t.fixed[g].h * 360 / kTwoPi, 2).c_str(),
            loop_closure_class_name(r.decision.kind), r.match.place,
            tools::to_double(r.match.confidence), r.reliable ? 1 : 0);
  }
  e = f.commit();
  if (!e.empty()) return e;
  e = f.open(o.out + "/closures.csv");
  if (!e.empty()) return e;
  f.print(
      "matched_place,place,true_distance_m,image_shift_px,heading_offset_deg,"
      "true_heading_offset_deg,gate_place,along_offset_m\n");
  for (const Closure& c : replay.closures) {
    f.print("%u,%u,%s,%s,%s,%s,%u,%s\n", c.a, c.b, truth ? fmt(c.true_distance).c_str() : "",
            fmt(c.shift_px).c_str(), fmt(c.heading_deg, 3).c_str(),
            truth ? fmt(c.true_heading_deg, 3).c_str() : "", c.gate_place, fmt(c.along_m).c_str());
  }
  e = f.commit();
  if (!e.empty()) return e;
  if (!tools::save_map(maps.fixed.map, o.out + "/map", &e)) return e;
  if (!tools::save_map(maps.dead.map, o.out + "/map_odometry", &e)) return e;
  auto robot = tools::grid_map(explorer.grid());
  if (!robot) return robot.error();
  if (!tools::save_map(robot.value(), o.out + "/explorer_map", &e)) return e;
  e = tools::write_output(o.out + "/graph_nodes.csv", tools::graph_nodes_csv(explorer.graph()));
  if (!e.empty()) return e;
  return tools::write_output(o.out + "/graph_edges.csv", tools::graph_edges_csv(explorer.graph()));
}

// One line per map: occupied precision and recall (strict and within one cell), balanced
// accuracy, and the counts they come from.
void print_near_path(const tools::SlamNearPathFigures& n) {
  const std::pair<const char*, const tools::NearPathComparison*> maps[] = {
      {"corrected", &n.corrected}, {"dead reckoning", &n.dead_reckoning}};
  for (const auto& [name, c] : maps) {
    std::printf(
        "obstacles within %.2f m of the true path, %s map: occupied precision %.3f, recall "
        "%.3f (within one cell %.3f, %.3f), balanced accuracy %.3f; %llu cells, %llu truly "
        "occupied, %llu called occupied, %llu both, %llu unknown to the map\n",
        n.band_m, name, c->precision(), c->recall(), c->precision_within_cell(),
        c->recall_within_cell(), c->balanced_accuracy(), static_cast<unsigned long long>(c->cells),
        static_cast<unsigned long long>(c->truth_occupied),
        static_cast<unsigned long long>(c->grid_occupied),
        static_cast<unsigned long long>(c->occupied_occupied),
        static_cast<unsigned long long>(c->grid_unknown()));
  }
}

// How the JSON and the summary name the closure heading.
const char* closure_heading_name(const storage::RunConfig& run) {
  return run.explore.closure_shift > 0 ? "image" : "none";
}

void print_summary(const storage::RunConfig& run, const std::vector<Session>& sessions,
                   const Trajectories& t, const Replay& replay, const Scores& sc, const Maps& maps,
                   const Explorer& explorer) {
  const PoseGraph& graph = explorer.graph();
  const ExplorerStats& ex = explorer.stats();
  const LoopClosureStats& st = explorer.gate().stats();
  auto count = [&](LoopClosureClass c) { return st.decisions[static_cast<uint32_t>(c)]; };
  std::printf("%zu places in %zu run(s); library and graph: %u nodes, %u closures\n", t.total,
              sessions.size(), graph.node_count(), graph.closure_count());
  std::printf(
      "decisions: closure %u, pending %u, rejected (inconsistent) %u [position %u, heading "
      "%u, image %u], aliasing %u, novelty %u, no sequence %u, relocalised %u\n",
      count(LoopClosureClass::kClosure), count(LoopClosureClass::kPending),
      count(LoopClosureClass::kRejectedInconsistent), st.rejected_position, st.rejected_heading,
      st.rejected_image, count(LoopClosureClass::kAliasing), count(LoopClosureClass::kNovelty),
      count(LoopClosureClass::kNoSequence), count(LoopClosureClass::kRelocalised));
  std::printf(
      "optimiser: %llu work units, %u slices of <= %u during the run and %u at the end; a "
      "solve took at most %u places\n",
      static_cast<unsigned long long>(ex.optimise_work), ex.slices, run.explore.optimise_budget, ex.final_slices,
      replay.max_solve_places);
  if (t.has_truth) {
    std::printf(
        "trajectory RMSE: dead reckoning %.3f m (max %.3f), corrected %.3f m (max %.3f), "
        "online %.3f m; corrected / dead reckoning = %.3f\n",
        sc.rmse_dead, sc.max_dead, sc.rmse_fixed, sc.max_fixed, sc.rmse_online,
        sc.rmse_dead > 0 ? sc.rmse_fixed / sc.rmse_dead : 0.0);
    std::printf(
        "false closures (true distance > %.1f m): %u of %zu accepted (largest true "
        "distance %.2f m)\n",
        kFalseClosureMetres, sc.false_closures, replay.closures.size(), sc.worst_closure);
    if (!replay.closures.empty()) {
      std::printf(
          "closure heading offsets (%s): RMS error %.2f deg (the same heading would be off by "
          "%.2f deg RMS)\n",
          closure_heading_name(run), sc.rms_heading, sc.rms_same_heading);
      std::printf(
          "closure offsets along the route: RMS error %.3f m (the matcher's places: %.3f m); "
          "%u of %zu closures moved by the alignment\n",
          sc.rms_along, sc.rms_along_gate, sc.realigned, replay.closures.size());
    }
    for (const Event& ev : sc.events) {
      std::printf("%s at place %u: ", ev.kind.c_str(), ev.place);
      if (ev.relocalised_after >= 0) {
        std::printf("relocalised after %d places\n", ev.relocalised_after);
      } else {
        std::printf("not relocalised\n");
      }
    }
  }
  if (ex.align_failures + ex.heading_failures > 0) {
    std::printf("closures measured without the images: alignment %u, heading %u\n",
                ex.align_failures, ex.heading_failures);
  }
  if (maps.have_map) {
    std::printf(
        "map vs %s: corrected %.1f %% of %llu cells right (phantom %llu, missed %llu); "
        "dead reckoning %.1f %% of %llu; %u places left out as unreliable\n",
        maps.true_map.c_str(), 100 * maps.cmp_fixed.accuracy(),
        static_cast<unsigned long long>(maps.cmp_fixed.scored()),
        static_cast<unsigned long long>(maps.cmp_fixed.free_occupied),
        static_cast<unsigned long long>(maps.cmp_fixed.occupied_free),
        100 * maps.cmp_dead.accuracy(), static_cast<unsigned long long>(maps.cmp_dead.scored()),
        maps.unreliable);
  }
  if (maps.near_path) print_near_path(*maps.near_path);
}


tools::SlamFigures figures(const SlamOptions& o, const storage::RunConfig& run,
                           const std::vector<Session>& sessions,
                           const Trajectories& t, const Replay& replay, const Scores& sc,
                           const Maps& maps, const Explorer& explorer) {
  const ExplorerStats& ex = explorer.stats();
  const LoopClosureStats& st = explorer.gate().stats();
  tools::SlamFigures f;
  f.places = static_cast<uint32_t>(t.total);
  f.runs = static_cast<uint32_t>(sessions.size());
  for (uint32_t c = 0; c < kLoopClosureClasses; ++c)
    f.decisions[c] = st.decisions[c];
  f.rejected_position = st.rejected_position;
  f.rejected_heading = st.rejected_heading;
  f.rejected_image = st.rejected_image;
  f.closures = static_cast<uint32_t>(replay.closures.size());
  f.optimiser_work = ex.optimise_work;
  f.slices = ex.slices;
  f.final_slices = ex.final_slices;
  f.max_solve_places = replay.max_solve_places;
  f.wheels = o.wheels;
  f.closure_heading = closure_heading_name(run);
  f.hfov_deg = shown(tools::to_degrees(run.explore.hfov));
  // The lateral weight to the option's resolution of 0.001 (the core's UQ16.16 3 % reads
  // 0.0299987).
  f.closure_lateral = std::round(tools::to_double(run.explore.closure_lateral) * 1000) / 1000;
  f.align_length = run.explore.align.length;
  f.align_range = run.explore.align.max_offset;
  f.align_shift = run.explore.align.max_shift;
  f.closures_realigned = sc.realigned;
  if (t.has_truth) {
    tools::SlamTruthFigures tf;
    tf.rmse_dead_reckoning_m = sc.rmse_dead;
    tf.rmse_corrected_m = sc.rmse_fixed;
    tf.rmse_online_m = sc.rmse_online;
    tf.max_error_dead_reckoning_m = sc.max_dead;
    tf.max_error_corrected_m = sc.max_fixed;
    tf.false_closures = sc.false_closures;
    tf.largest_closure_true_distance_m = sc.worst_closure;
    tf.closure_heading_error_rms_deg = sc.rms_heading;
    tf.closure_same_heading_error_rms_deg = sc.rms_same_heading;
    tf.closure_along_error_rms_m = sc.rms_along;
    tf.closure_gate_along_error_rms_m = sc.rms_along_gate;
    for (const Event& ev : sc.events)
      tf.events.push_back({ev.place, ev.kind, ev.relocalised_after});
    f.truth = tf;
  }
  if (maps.have_map) {
    f.map = tools::SlamMapFigures{maps.cmp_fixed.accuracy(), maps.cmp_fixed.scored(),
                                  maps.cmp_dead.accuracy(), maps.cmp_dead.scored(), maps.near_path};
  }
  f.unreliable_places = maps.unreliable;
  f.relocalisations = ex.relocalisations;
  f.align_failures = ex.align_failures;
  f.heading_failures = ex.heading_failures;
  return f;
}

void print_reference(const Trajectories& t, const PoseGraph& graph) {
  std::vector<P> linear, nonlinear;
  reference_solutions(graph, to_p(graph.pose(0).value()), &linear, &nonlinear);
  for (const auto* ref : {&linear, &nonlinear}) {
    double se = 0, dmax = 0;
    for (uint32_t g = 0; g < t.total; ++g) {
      const P w = compose_d(t.anchor, between_d((*ref)[0], (*ref)[g]));
      se += std::pow(dist(w, t.truth[g]), 2);
      dmax = std::max(dmax, dist(to_p(graph.pose(g).value()), (*ref)[g]));
    }
    std::printf("reference %s: RMSE %.3f m; fixed point differs by at most %.4f m\n",
                ref == &linear ? "LAGO (double)" : "Gauss-Newton (double)",
                std::sqrt(se / static_cast<double>(t.total)), dmax);
  }
}

int run_slam(const SlamOptions& o) {
  if (const int rc = refuse_slam_outputs(o); rc != kExitOk) return rc;
  SlamSetup setup;
  if (const int rc = slam_setup(o, &setup); rc != kExitOk) return rc;
  std::vector<Session> sessions;
  std::string e = load_sessions(o, setup, &sessions);
  if (!e.empty()) return fail(e);
  auto explore = std::make_unique<ExploreReplay>();
  e = explore->configure(setup, sessions);
  if (!e.empty()) return usage_error(e);
  Replay replay;
  e = explore->run(sessions, &replay);
  if (!e.empty()) return fail(e);
  const Explorer& explorer = explore->explorer();
  if (!o.out.empty()) {
    e = explore->rebuild_map(sessions);
    if (!e.empty()) return fail(e);
  }
  // The constants the (last) run's odometry ran with: the recording's, or --wheels.
  OdometryConfig ran = sessions.back().header.wheels;
  if (setup.use_wheels) ran = apply_wheels(ran, setup.wheels);
  const WheelCalibrationReport calibration =
      calibrate_run(explorer.graph(), ran, setup.true_wheels);
  if (!o.calibration_out.empty() && calibration.status == Status::kOk) {
    e = tools::write_output(o.calibration_out, wheel_constants_text(calibration.corrected) + "\n");
    if (!e.empty()) return fail(e);
  }
  const Trajectories t = trajectories(sessions, replay, explorer.graph());
  const Scores sc = score(t, &replay, setup.run.recent_exclusion);
  auto maps = build_maps(o, sessions, t, replay);
  if (!maps) return fail(maps.error());
  if (!o.out.empty()) {
    e = write_out_dir(o, t, replay, maps.value(), explorer);
    if (!e.empty()) return fail(e);
  }
  if (!o.quiet) {
    print_summary(setup.run, sessions, t, replay, sc, maps.value(), explorer);
    print_calibration(calibration);
    if (t.has_truth && o.reference) print_reference(t, explorer.graph());
  }
  if (!o.json.empty()) {
    tools::SlamFigures f = figures(o, setup.run, sessions, t, replay, sc, maps.value(), explorer);
    f.calibration = calibration_figures(calibration);
    e = tools::write_output(o.json, tools::slam_figures_json(f));
    if (!e.empty()) return fail(e);
  }
  if (!o.g2o.empty()) {
    // The robot's graph for other tools (and `seqslam graph`): its poses after the final solve
    // and its edges with the explorer's information (relative to 1 m of odometry, one unit
    // for position and heading).
    const PoseGraph& g = explorer.graph();
    e = tools::write_output(o.g2o, tools::g2o_text(tools::graph_poses_of(g),
                                                   tools::graph_edges_of(g, 1.0)));
    if (!e.empty()) return fail(e);
  }
  // Asked for the constants and none were accepted: a file there from before is not this
  // run's, and `config write --wheels $(cat FILE)` would put it on a robot. The run fails.
  if (!o.calibration_out.empty() && calibration.status != Status::kOk) {
    std::error_code ec;
    return fail(o.calibration_out + ": not written: the wheel calibration was " +
                calibration_verdict(calibration.status) +
                (std::filesystem::exists(o.calibration_out, ec)
                     ? "; the constants in the file are an earlier run's, not this one's"
                     : ""));
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
  c->add_option("--g2o", o->g2o,
                "Write the explorer's pose graph (final poses, edges with their information) "
                "as g2o");
  // The localiser's and the explorer's settings: the settings table's options (the image size
  // is the recording's; the localiser's --max-shift is not offered: explore's closures use
  // --closure-shift).
  SettingOptions<>::Selection settings;
  settings.scopes = storage::kScopeImage | storage::kScopeSequence | storage::kScopeLoop |
                    storage::kScopeExplore;
  settings.except = {"size"};
  o->settings.add(c, slam_defaults(), settings);
  c->add_option("--wheels", o->wheels,
                "Replay the encoders with these wheel constants, LEFT,RIGHT,TRACK in metres "
                "(circumferences and track width; e.g. the simulator's true ones), instead of "
                "the recording's place poses");
  c->add_option("--true-wheels", o->true_wheels,
                "Report the wheel calibration against these true constants, LEFT,RIGHT,TRACK in "
                "metres (the simulator's: host_sim robot.h WheelParams)");
  c->add_option("--calibration-out", o->calibration_out,
                "Write the calibrated wheel constants (LEFT,RIGHT,TRACK, what --wheels reads) "
                "here when the calibration is accepted");
  c->add_option("--path-band", o->path_band,
                "Obstacles near the path: score the maps' occupied cells within this many metres "
                "of the true path (precision, recall, balanced accuracy; docs/mapping.md)")
      ->check(tools::real(0.01, 100.0))
      ->capture_default_str();
  c->add_flag("--quiet", o->quiet, "No summary on stdout");
  c->add_flag("--reference", o->reference,
              "Also solve the final graph in double precision (LAGO and Gauss-Newton) and "
              "print their RMSE");
  c->callback([o, chosen] { *chosen = [o] { return run_slam(*o); }; });
}

}  // namespace seqslam::cli
