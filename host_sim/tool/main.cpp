// seqslam-sim: generates simulated runs of Myon through the lab (dream recordings with
// ground truth), renders single views, and evaluates the core on generated pairs.
// docs/simulator.md describes the world, the scenarios and the files.
#include <CLI/CLI.hpp>

#include <algorithm>
#include <climits>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "evaluate.h"
#include "seqslam/hal/host_file.h"
#include "seqslam/storage/run_config.h"
#include "seqslam_sim/pipeline.h"
#include "seqslam_sim/scenario.h"
#include "seqslam_sim/true_map.h"
#include "seqslam_tools/cli_numbers.h"
#include "seqslam_tools/dream_images.h"
#include "seqslam_tools/image_io.h"
#include "seqslam_tools/output_file.h"
#include "seqslam_tools/q_format.h"
#include "seqslam_tools/settings_cli.h"
#include "seqslam_tools/wxh.h"

namespace fs = std::filesystem;
using namespace seqslam;
using namespace seqslam::sim;

namespace {

// The robot's default image size as its option writes it (the settings table's): what the
// pixel pipeline delivers unless a run is configured otherwise.
std::string default_size() {
  return cli::setting_value_text(storage::RunConfig{}, "size");
}

constexpr const char* kDefaultLibraryLight = "noon-lamps";

struct GenerateOptions {
  std::string scenario = "default";
  std::string out = "sim";
  uint64_t seed = 1;
  std::string size = default_size();
  std::vector<std::string> lights;
  std::string library_light = kDefaultLibraryLight;
  std::string query_light;  // default: morning-lamps; perspective: the library's light
  unsigned jobs = 2;
  double deviation = DriveOptions{}.deviation_m;
  std::string rotation = "-35:35:0.5";
  std::string shift_x;
  std::string scale;
  std::string query_world = "same";  // perspective: the library's people and chairs, or other
};

bool parse_size(const std::string& text, hal::PipelineMapping* m, std::string* error) {
  uint32_t w = 0;
  uint32_t h = 0;
  if (!tools::split_wxh(text, &w, &h) || w == 0 || h == 0 || w > hal::kCameraWidth ||
      h > hal::kCameraHeight) {
    *error = "--size: expected WxH within 346x271, got '" + text + "'";
    return false;
  }
  *m = hal::PipelineMapping::reduction(static_cast<uint16_t>(w), static_cast<uint16_t>(h));
  if (hal::check_mapping(*m) != Status::kOk) {
    *error = "--size: " + text + " exceeds the pixel buffer (W * H <= 512)";
    return false;
  }
  return true;
}

// "a:b:step" -> values a, a+step, ..., b; "" -> {}. Finite numbers, step > 0, b >= a, at most
// 10000 steps; with `positive` (a zoom) a > 0.
bool parse_range(const std::string& text, std::vector<double>* out, std::string* error,
                 bool positive = false) {
  if (text.empty()) return true;
  double a = 0, b = 0, step = 0;
  char c1 = 0, c2 = 0;
  if (std::sscanf(text.c_str(), "%lf%c%lf%c%lf", &a, &c1, &b, &c2, &step) != 5 || c1 != ':' ||
      c2 != ':' || !std::isfinite(a) || !std::isfinite(b) || !std::isfinite(step) || step <= 0 ||
      b < a || (b - a) / step > 10000 || (positive && a <= 0)) {
    *error = "expected FROM:TO:STEP (finite numbers, " + std::string(positive ? "FROM > 0, " : "") +
             "TO >= FROM, STEP > 0, at most 10000 steps), got '" + text + "'";
    return false;
  }
  const long n = std::lround(std::floor((b - a) / step + 1e-9));
  for (long i = 0; i <= n; ++i)
    out->push_back(a + static_cast<double>(i) * step);
  return true;
}

uint64_t run_seed(uint64_t seed, uint64_t k) {
  return Rng(seed).derive(1000 + k).next();
}

// A library/query pair: indices into the scenario's runs; the query file defaults to the
// query run's recording (perspective sets name one recording per transform).
struct PairSpec {
  size_t library = 0;
  size_t query = 0;
  std::string description;
  std::string query_file;
};

int fail(const std::string& message) {
  std::fprintf(stderr, "seqslam-sim: %s\n", message.c_str());
  return 1;
}

// A usage error (status 2): an output that is an input, options that cannot work together.
int refuse(const std::string& message) {
  std::fprintf(stderr, "seqslam-sim: %s\n", message.c_str());
  return 2;
}

std::string write_runs_table(const std::string& path, const std::vector<RunSummary>& runs) {
  tools::OutputFile f;  // a temporary renamed over the file: every write checked
  const std::string error = f.open(path);
  if (!error.empty()) return error;
  f.print(
      "run,light,places,snapshots,length_m,odometry_end_error_m,"
      "odometry_end_heading_error_deg,max_lateral_deviation_m,"
      "max_heading_deviation_deg\n");
  for (const RunSummary& r : runs) {
    f.print("%s,%s,%zu,%u,%.2f,%.3f,%.2f,%.2f,%.1f\n", r.name.c_str(), r.light.c_str(),
            r.places.size(), r.snapshots, r.length_m, r.end_error_m, r.end_heading_error_deg,
            r.max_lateral_m, r.max_heading_dev_deg);
  }
  return f.commit();
}

void print_run(const RunSummary& r) {
  std::printf(
      "  %-28s %-14s %4zu places  %6.1f m  dead reckoning off by %.2f m / %.1f deg at the end"
      "  (deviation up to %.2f m, %.0f deg; %.1f s)\n",
      r.name.c_str(), r.light.c_str(), r.places.size(), r.length_m, r.end_error_m,
      r.end_heading_error_deg, r.max_lateral_m, r.max_heading_dev_deg, r.seconds);
}

// Adds a run of --scenario to `specs`: its seed from --seed and its index. Returns the index.
size_t add_spec(const GenerateOptions& o, const hal::PipelineMapping& mapping,
                const std::string& name, const std::string& light, std::vector<Leg> legs,
                std::vector<RunSpec>* specs) {
  RunSpec s;
  s.name = name;
  s.light = light;
  s.seed = run_seed(o.seed, specs->size());
  s.legs = std::move(legs);
  s.mapping = mapping;
  s.threads = o.jobs;
  s.drive.deviation_m = o.deviation;
  specs->push_back(s);
  return specs->size() - 1;
}

// The runs and pairs of --scenario: specs to generate, pairs to write ground truth for (the
// perspective scenario adds its runs and pairs when it generates them). "" or the message.
std::string plan_runs(const GenerateOptions& o, const hal::PipelineMapping& mapping,
                      std::vector<RunSpec>* out_specs, std::vector<PairSpec>* out_pairs) {
  std::vector<RunSpec>& specs = *out_specs;
  std::vector<PairSpec>& pairs = *out_pairs;
  const auto add_run = [&](const std::string& name, const std::string& light,
                           std::vector<Leg> legs) {
    return add_spec(o, mapping, name, light, std::move(legs), &specs);
  };
  const std::string library_name = "loop_" + o.library_light;
  if (o.scenario == "default" || o.scenario == "lights") {
    std::vector<std::string> lights = o.lights;
    if (lights.empty()) {
      if (o.scenario == "default") {
        lights = {"morning-lamps", "low-sun", "bright-sun", "dim"};
      } else {
        // All six, the library's own light included (a second drive without a light change:
        // the reference the other pairs are compared with).
        for (const LightCondition& c : light_conditions())
          lights.push_back(c.name);
      }
    }
    const size_t library = add_run(library_name, o.library_light, routes::loop());
    for (const std::string& l : lights) {
      if (find_light(l) == nullptr) return ("unknown light condition '" + l + "'");
      // The library's own light again: a second drive, the reference without a light change.
      const std::string name = l == o.library_light ? "loop_" + l + "_again" : "loop_" + l;
      const size_t query = add_run(name, l, routes::loop());
      // Every query run drives the same track (one drive seed): the pairs then differ in the
      // light (and the people, chairs and noise of the day), not in how the robot was driven.
      specs.back().drive_seed = run_seed(o.seed, 1);
      pairs.push_back({library, query, o.library_light + " -> " + l, ""});
    }
  } else if (o.scenario == "jump" || o.scenario == "kidnapped" || o.scenario == "novelty") {
    const size_t library = add_run(library_name, o.library_light, routes::loop());
    const size_t query = add_run(o.scenario + "_" + o.query_light, o.query_light,
                                 o.scenario == "jump"        ? routes::jump()
                                 : o.scenario == "kidnapped" ? routes::kidnapped()
                                                             : routes::novelty());
    pairs.push_back(
        {library, query, o.scenario + ": " + o.library_light + " -> " + o.query_light, ""});
  } else if (o.scenario == "short") {
    // A 12 m stretch of the south side (~60 places): for tests and quick looks.
    const std::vector<Leg> legs = {Leg{{{6.0, lab::kSouthLane}, {18.0, lab::kSouthLane}}, false}};
    const size_t library = add_run("short_" + o.library_light, o.library_light, legs);
    const size_t query =
        add_run("short_" + o.query_light + (o.query_light == o.library_light ? "_again" : ""),
                o.query_light, legs);
    pairs.push_back({library, query, "short: " + o.library_light + " -> " + o.query_light, ""});
  } else if (o.scenario == "explore" || o.scenario == "calibrate") {
    // SLAM (seqslam slam): one run per light, each two laps of its route (its own drive), so
    // the second lap closes loops with the first. explore: the lab's loop; calibrate: a
    // figure of eight (both turning directions, for the wheel calibration). No pairs: each
    // run is used on its own.
    const bool eight = o.scenario == "calibrate";
    std::vector<std::string> lights = o.lights;
    if (lights.empty()) {
      for (const LightCondition& c : light_conditions())
        lights.push_back(c.name);
    }
    for (const std::string& l : lights) {
      if (find_light(l) == nullptr) return ("unknown light condition '" + l + "'");
      add_run(o.scenario + "_" + l, l, eight ? routes::calibrate() : routes::explore());
    }
  } else if (o.scenario == "explore-short") {
    // The western half loop and 12 m of it again (~65 m, ~330 places): tests of seqslam slam.
    add_run("explore_short_" + o.library_light, o.library_light, routes::explore_short());
  } else if (o.scenario == "route") {
    // Teach/repeat over a whole route (~1 km, ~5 000 places per run; generating takes
    // minutes): the library and each query drive routes::route_1km(). As in `default`, the
    // queries share one drive seed (one track), the library has its own drive.
    std::vector<std::string> lights = o.lights;
    if (lights.empty()) lights = {o.query_light};
    const size_t library =
        add_run("route_" + o.library_light, o.library_light, routes::route_1km());
    for (const std::string& l : lights) {
      if (find_light(l) == nullptr) return ("unknown light condition '" + l + "'");
      const std::string name = l == o.library_light ? "route_" + l + "_again" : "route_" + l;
      const size_t query = add_run(name, l, routes::route_1km());
      specs.back().drive_seed = run_seed(o.seed, 1);
      pairs.push_back({library, query, "route: " + o.library_light + " -> " + l, ""});
    }
  } else if (o.scenario != "perspective") {
    return ("unknown scenario '" + o.scenario +
            "' (default, lights, jump, kidnapped, novelty, perspective, short, explore, "
            "explore-short, calibrate, route)");
  }

  return {};
}

// The perspective scenario: the library's tour and its query tour once per transformation
// (--rotation, --shift-x, --scale). "" or the message.
std::string generate_perspective(const GenerateOptions& o, const hal::PipelineMapping& mapping,
                                 std::vector<RunSpec>* out_specs, std::vector<PairSpec>* out_pairs,
                                 std::vector<RunSummary>* out_summaries) {
  std::vector<RunSpec>& specs = *out_specs;
  std::vector<PairSpec>& pairs = *out_pairs;
  std::vector<RunSummary>& summaries = *out_summaries;
  std::string error;
  std::vector<double> rotations, shifts, scales;
  if (!parse_range(o.rotation, &rotations, &error) || !parse_range(o.shift_x, &shifts, &error) ||
      !parse_range(o.scale, &scales, &error, true)) {
    return (error);
  }
  std::vector<PerspectiveTransform> transforms;
  for (double r : rotations)
    transforms.push_back({r, 0.0, 0.0, 1.0});
  for (double x : shifts)
    transforms.push_back({0.0, x, 0.0, 1.0});
  for (double s : scales)
    transforms.push_back({0.0, 0.0, 0.0, s});
  // Each transformation once (the identity may be in several ranges): one file each.
  std::vector<PerspectiveTransform> unique;
  for (const PerspectiveTransform& t : transforms) {
    bool seen = false;
    for (const PerspectiveTransform& u : unique)
      seen = seen || u.label() == t.label();
    if (!seen) unique.push_back(t);
  }
  transforms.swap(unique);
  if (transforms.empty()) return ("perspective: no transforms (--rotation/--shift-x/--scale)");
  // The query drives the library's track again (same drive seed). By default it also sees
  // the library's people and chairs (same world seed), so what differs is the sensor noise,
  // the exposure of the larger canvas - and the transformation, as in [A 4.3.1] where the
  // queries were the database images transformed. --query-world other adds the day's
  // changes on top.
  add_spec(o, mapping, "tour_" + o.library_light, o.library_light, routes::long_tour(), &specs);
  add_spec(o, mapping, "tour_query_" + o.query_light, o.query_light, routes::long_tour(), &specs);
  specs[1].drive_seed = specs[0].seed;
  if (o.query_world == "same") specs[1].world_seed = specs[0].seed;
  summaries.resize(2);
  error = generate_run(specs[0], o.out, &summaries[0]);
  if (error.empty()) {
    error = generate_perspective_set(specs[1], transforms, o.out, &summaries[1]);
  }
  if (!error.empty()) return (error);
  for (const PerspectiveTransform& t : transforms) {
    pairs.push_back({0, 1, "perspective " + t.label(), specs[1].name + "_" + t.label() + ".dream"});
  }
  return {};
}

// pairs.csv with a ground truth per pair, runs.csv and the lab's true map. "" or the message.
std::string write_pairs(const GenerateOptions& o, const std::vector<RunSpec>& specs,
                        const std::vector<PairSpec>& pairs,
                        const std::vector<RunSummary>& summaries) {
  std::string error;
  // Ground truth for every pair, from the true poses.
  tools::OutputFile f;  // a temporary renamed over pairs.csv: every write checked
  error = f.open(o.out + "/pairs.csv");
  if (!error.empty()) return error;
  f.print("library,query,ground_truth,description\n");
  for (const PairSpec& p : pairs) {
    const std::string lib = specs[p.library].name + ".dream";
    const std::string qry = p.query_file.empty() ? specs[p.query].name + ".dream" : p.query_file;
    const std::string gt = qry.substr(0, qry.size() - 6) + ".gt.csv";
    // The perspective tour passes some places twice (the cross-corridor lap runs along the
    // loop), the 1 km route most places several times: a match to another pass is the right
    // place too.
    TruthRule rule;
    rule.every_pass = o.scenario == "perspective" || o.scenario == "route";
    error = write_truth_csv(
        o.out + "/" + gt, pair_truth(summaries[p.library].places, summaries[p.query].places, rule));
    if (!error.empty()) return error;
    f.print("%s,%s,%s,%s\n", lib.c_str(), qry.c_str(), gt.c_str(), p.description.c_str());
  }
  error = f.commit();
  if (!error.empty()) return error;
  error = write_runs_table(o.out + "/runs.csv", summaries);
  if (!error.empty()) return error;
  // The true map of the static lab (no people), 5 cm cells at the infrared sensors' height.
  LabOptions still;
  still.people = false;
  still.move_chairs = false;
  error = save_map(true_map(build_lab(0, still), 0.05, kInfraredHeight), o.out + "/lab_map");
  if (!error.empty()) return error;
  std::printf("wrote %zu recordings, %zu pairs (%s/pairs.csv), runs.csv, lab_map.pgm/.yaml\n",
              summaries.size() + (o.scenario == "perspective" ? pairs.size() - 1 : 0), pairs.size(),
              o.out.c_str());
  return {};
}

int generate(GenerateOptions o) {
  if (o.query_light.empty()) {
    o.query_light = o.scenario == "perspective" ? o.library_light : "morning-lamps";
  }
  hal::PipelineMapping mapping;
  std::string error;
  if (!parse_size(o.size, &mapping, &error)) return refuse(error);
  for (const std::string* l : {&o.library_light, &o.query_light}) {
    if (find_light(*l) == nullptr)
      return fail("unknown light condition '" + *l + "' (see `seqslam-sim lights`)");
  }
  std::error_code ec;
  fs::create_directories(o.out, ec);
  if (ec) return fail(o.out + ": cannot create: " + ec.message());

  std::vector<RunSpec> specs;
  std::vector<PairSpec> pairs;
  error = plan_runs(o, mapping, &specs, &pairs);
  if (!error.empty()) return fail(error);
  std::printf("seqslam-sim: scenario %s, seed %llu, %s images, into %s/\n", o.scenario.c_str(),
              static_cast<unsigned long long>(o.seed), o.size.c_str(), o.out.c_str());
  std::vector<RunSummary> summaries;
  if (o.scenario == "perspective") {
    error = generate_perspective(o, mapping, &specs, &pairs, &summaries);
    if (!error.empty()) return fail(error);
  } else {
    // One run after the other, each rendered on all --jobs threads (balances better than a
    // run per thread).
    summaries.resize(specs.size());
    for (size_t i = 0; i < specs.size(); ++i) {
      error = generate_run(specs[i], o.out, &summaries[i]);
      if (!error.empty()) return fail(error);
      print_run(summaries[i]);
    }
  }
  if (o.scenario == "perspective") {
    for (const RunSummary& r : summaries)
      print_run(r);
  }

  error = write_pairs(o, specs, pairs, summaries);
  if (!error.empty()) return fail(error);
  return 0;
}

struct RenderOptions {
  std::string light = kDefaultLibraryLight;
  double x = 6.0, y = 3.2, heading = 0.0;
  uint64_t seed = 1;
  std::string size = default_size();
  std::string out = "view";
  double roll = 0.0;
};

int render(const RenderOptions& o) {
  const LightCondition* light = find_light(o.light);
  if (light == nullptr) return fail("unknown light condition '" + o.light + "'");
  hal::PipelineMapping mapping;
  std::string error;
  if (!parse_size(o.size, &mapping, &error)) return refuse(error);
  const World world = build_lab(o.seed);
  CameraModel cam;
  cam.roll_deg = o.roll;
  const auto radiance =
      render_radiance(world, *light, cam, CameraPose{o.x, o.y, o.heading * M_PI / 180, 0.0});
  Exposure exposure(light->exposure_bias);
  Rng noise(o.seed);
  tools::GrayImage frame;
  frame.width = cam.width;
  frame.height = cam.height;
  frame.pixels = exposure.expose(radiance, cam.width, cam.height, noise);
  tools::GrayImage small;
  small.width = mapping.xmax;
  small.height = mapping.ymax;
  small.pixels = apply_pipeline(frame.pixels.data(), cam.width, cam.height, mapping).pixels;
  for (const auto& [img, suffix] :
       {std::pair{&frame, std::string("_camera.png")}, std::pair{&small, "_" + o.size + ".png"}}) {
    if (!tools::save_png(o.out + suffix, *img, &error)) return fail(error);
    std::printf("wrote %s%s\n", o.out.c_str(), suffix.c_str());
  }
  return 0;
}

struct DriftOptions {
  uint32_t runs = 10;
  uint64_t seed = 1;
};

// Dead-reckoning error at the end of the loop over several drives (no rendering).
int drift(const DriftOptions& o) {
  std::vector<double> errors;
  std::printf("run  seed                  length_m  end_error_m  heading_error_deg\n");
  for (uint32_t k = 0; k < o.runs; ++k) {
    RunSpec spec;
    spec.name = "drift";
    spec.seed = run_seed(o.seed, k);
    spec.legs = routes::loop();
    RunSummary s;
    const std::string error = simulate_drive(spec, &s);
    if (!error.empty()) return fail(error);
    std::printf("%3u  %20llu  %8.2f  %11.3f  %17.2f\n", k,
                static_cast<unsigned long long>(spec.seed), s.length_m, s.end_error_m,
                s.end_heading_error_deg);
    errors.push_back(s.end_error_m);
  }
  std::sort(errors.begin(), errors.end());
  std::printf("end error over %u loops: min %.3f m, median %.3f m, max %.3f m\n", o.runs,
              errors.front(), errors[errors.size() / 2], errors.back());
  return 0;
}

struct TruthOptions {
  std::string library;
  std::string query;
  TruthRule rule;
  std::string out;
};

std::vector<PlaceTruth> truth_of(const tools::DreamPlaces& d) {
  std::vector<PlaceTruth> out;
  for (size_t i = 0; i < d.truth.size(); ++i) {
    PlaceTruth p;
    p.index = static_cast<uint32_t>(i);
    p.truth.x = tools::to_double(d.truth[i].x);
    p.truth.y = tools::to_double(d.truth[i].y);
    p.truth.heading = tools::to_unsigned_radians(d.truth[i].heading);
    out.push_back(p);
  }
  return out;
}

// Ground truth for any pair of recordings that carry true poses.
int truth(const TruthOptions& o) {
  tools::InputFiles inputs;
  inputs.add(o.library);
  inputs.add(o.query);
  const std::string clash = inputs.clash(o.out);
  if (!clash.empty()) return refuse("--out " + clash);
  const auto lib = tools::load_dream_places(o.library);
  if (!lib) return fail(lib.error());
  const auto qry = tools::load_dream_places(o.query);
  if (!qry) return fail(qry.error());
  for (const auto* d : {&lib, &qry}) {
    if (!d->value().has_truth) {
      return fail((d == &lib ? o.library : o.query) +
                  ": no ground-truth poses (only simulated recordings have them)");
    }
  }
  const std::string error =
      write_truth_csv(o.out, pair_truth(truth_of(lib.value()), truth_of(qry.value()), o.rule));
  if (!error.empty()) return fail(error);
  std::printf("wrote %s\n", o.out.c_str());
  return 0;
}

struct MontageOptions {
  std::vector<std::string> inputs;
  uint32_t first = 0;
  uint32_t count = 16;
  uint32_t step = 1;
  int zoom = 4;
  std::string out = "montage.png";
};

// The sheet's rows: --count, but no more than the places from --first on (every --step) of
// the longest recording. Returns "" or what is wrong.
std::string montage_rows(const MontageOptions& o, const std::vector<tools::DreamPlaces>& runs,
                         int row_height, int width, uint32_t* rows) {
  size_t places = 0;
  for (const tools::DreamPlaces& r : runs)
    places = std::max(places, r.images.size());
  if (o.first >= places) {
    return "--first " + std::to_string(o.first) + ": the recordings have " +
           std::to_string(places) + " places (0.." + std::to_string(places - 1) + ")";
  }
  const uint64_t left = places - o.first;
  const uint64_t available = o.step == 0 ? o.count : (left + o.step - 1) / o.step;
  *rows = static_cast<uint32_t>(std::min<uint64_t>(o.count, available));
  // The sheet's size in pixels must fit an int per side and a sane amount of memory.
  constexpr uint64_t kMaxPixels = uint64_t{1} << 28;
  const uint64_t height = uint64_t{*rows} * static_cast<uint64_t>(row_height);
  if (height > static_cast<uint64_t>(INT32_MAX) ||
      height * static_cast<uint64_t>(width) > kMaxPixels) {
    return "--count " + std::to_string(o.count) + ": a sheet of " + std::to_string(*rows) +
           " rows would be " + std::to_string(width) + "x" + std::to_string(height) +
           " pixels (at most " + std::to_string(kMaxPixels) + "): give a smaller --count or --zoom";
  }
  return {};
}

// A contact sheet: one column per recording, one row per place, images enlarged.
int montage(const MontageOptions& o) {
  tools::InputFiles inputs;
  for (const std::string& in : o.inputs)
    inputs.add(in);
  const std::string clash = inputs.clash(o.out);
  if (!clash.empty()) return refuse("--out " + clash);
  std::vector<tools::DreamPlaces> runs;
  for (const std::string& in : o.inputs) {
    auto loaded = tools::load_dream_places(in);
    if (!loaded) return fail(loaded.error());
    if (loaded.value().images.empty()) return fail(in + ": no places");
    runs.push_back(std::move(loaded).value());
  }
  const int w = runs[0].images[0].width * o.zoom;
  const int h = runs[0].images[0].height * o.zoom;
  const int gap = 4;
  tools::GrayImage sheet;
  sheet.width = static_cast<int>(runs.size()) * (w + gap);
  uint32_t rows = 0;
  const std::string too_many = montage_rows(o, runs, h + gap, sheet.width, &rows);
  if (!too_many.empty()) return refuse(too_many);
  sheet.height = static_cast<int>(rows) * (h + gap);
  sheet.pixels.assign(raster_index(0, sheet.height, sheet.width), 255);
  for (size_t c = 0; c < runs.size(); ++c) {
    for (uint32_t r = 0; r < rows; ++r) {
      const size_t index = o.first + static_cast<size_t>(r) * o.step;
      if (index >= runs[c].images.size()) continue;
      const tools::GrayImage& img = runs[c].images[index];
      if (img.width * o.zoom != w || img.height * o.zoom != h) {
        return fail(o.inputs[c] + ": place " + std::to_string(index) + " is " +
                    std::to_string(img.width) + "x" + std::to_string(img.height) + ", " +
                    o.inputs[0] + "'s images are " + std::to_string(runs[0].images[0].width) + "x" +
                    std::to_string(runs[0].images[0].height) +
                    ": the recordings of a montage must have one image size");
      }
      for (int y = 0; y < h; ++y) {
        for (int x = 0; x < w; ++x) {
          sheet.pixels[raster_index(static_cast<int>(c) * (w + gap) + x,
                                    static_cast<int>(r) * (h + gap) + y, sheet.width)] =
              img.pixels[raster_index(x / o.zoom, y / o.zoom, img.width)];
        }
      }
    }
  }
  std::string error;
  if (!tools::save_png(o.out, sheet, &error)) return fail(error);
  std::printf("wrote %s\n", o.out.c_str());
  return 0;
}

// seqslam-sim generate and its options.
CLI::App* add_generate(CLI::App& app, GenerateOptions* g) {
  CLI::App* gen = app.add_subcommand("generate", "Simulate a scenario's runs into a directory");
  gen->add_option(
         "--scenario", g->scenario,
         "default (the demo's set: one library run and four light conditions), lights "
         "(all six), jump, kidnapped, novelty, perspective, short (12 m, for tests), explore (two "
         "laps per light, for seqslam slam), explore-short (~65 m, for tests), calibrate (a figure "
         "of eight twice per light, for seqslam slam --calibrate), route (~1 km, "
         "~5 000 places per run, for teach/repeat of a whole route; takes minutes)")
      ->capture_default_str();
  gen->add_option("--out", g->out, "Output directory")->capture_default_str();
  gen->add_option("--seed", g->seed, "Random seed: the same seed gives byte-identical files")
      ->check(tools::whole_of<uint64_t>())
      ->capture_default_str();
  gen->add_option("--size", g->size, "Image size after the pixel pipeline, W*H <= 512")
      ->capture_default_str();
  gen->add_option("--lights", g->lights,
                  "Query light conditions (default/lights/route scenarios; explore: the runs' "
                  "lights)")
      ->delimiter(',');
  gen->add_option("--library-light", g->library_light, "Light of the library run")
      ->capture_default_str();
  gen->add_option("--query-light", g->query_light,
                  "Light of the query run (jump, kidnapped, novelty, short, route: default "
                  "morning-lamps; perspective: default the library's)");
  gen->add_option("--deviation", g->deviation,
                  "Largest lateral deviation from the route's centre line (m)")
      ->check(tools::real(0.0, 1.0))
      ->capture_default_str();
  gen->add_option("--jobs", g->jobs, "Rendering threads (the files do not depend on it)")
      ->check(tools::whole_of<unsigned>())
      ->capture_default_str();
  // FROM:TO:STEP ranges, checked as the perspective scenario reads them.
  const auto steps = [](bool positive) {
    return CLI::Validator(
        [positive](std::string& text) {
          std::vector<double> values;
          std::string error;
          return parse_range(text, &values, &error, positive) ? std::string() : error;
        },
        "");
  };
  gen->add_option("--rotation", g->rotation, "Perspective: head roll FROM:TO:STEP degrees")
      ->check(steps(false))
      ->capture_default_str();
  gen->add_option("--shift-x", g->shift_x, "Perspective: horizontal shift FROM:TO:STEP pixels")
      ->check(steps(false));
  gen->add_option("--scale", g->scale, "Perspective: zoom FROM:TO:STEP (FROM > 0)")
      ->check(steps(true));
  gen->add_option("--query-world", g->query_world,
                  "Perspective: the query sees the library's people and chairs (same) or "
                  "its own (other)")
      ->check(CLI::IsMember({"same", "other"}))
      ->capture_default_str();
  return gen;
}

// seqslam-sim render and its options.
CLI::App* add_render(CLI::App& app, RenderOptions* r) {
  CLI::App* ren = app.add_subcommand("render", "Render one camera view to PNG (full and reduced)");
  ren->add_option("--light", r->light, "Light condition")->capture_default_str();
  ren->add_option("--x", r->x, "Robot x (m)")->check(tools::finite())->capture_default_str();
  ren->add_option("--y", r->y, "Robot y (m)")->check(tools::finite())->capture_default_str();
  ren->add_option("--heading", r->heading, "Heading (degrees, 0 = east)")
      ->check(tools::real(-360.0, 360.0))
      ->capture_default_str();
  ren->add_option("--roll", r->roll, "Camera roll (degrees)")
      ->check(tools::real(-180.0, 180.0))
      ->capture_default_str();
  ren->add_option("--seed", r->seed, "Per-run lab variation seed")
      ->check(tools::whole_of<uint64_t>())
      ->capture_default_str();
  ren->add_option("--size", r->size, "Reduced size")->capture_default_str();
  ren->add_option("--out", r->out, "Output prefix")->capture_default_str();
  return ren;
}

// seqslam-sim montage and its options.
CLI::App* add_montage(CLI::App& app, MontageOptions* m) {
  CLI::App* mon = app.add_subcommand("montage", "Contact sheet of places from recordings (PNG)");
  mon->add_option("inputs", m->inputs, "Dream recordings, one column each")->required();
  mon->add_option("--first", m->first, "First place")
      ->check(tools::whole_of<uint32_t>())
      ->capture_default_str();
  mon->add_option("--count", m->count, "Places (rows)")
      ->check(tools::whole_of<uint32_t>())
      ->capture_default_str();
  mon->add_option("--step", m->step, "Place step")
      ->check(tools::whole_of<uint32_t>())
      ->capture_default_str();
  mon->add_option("--zoom", m->zoom, "Enlargement")
      ->check(tools::whole<int>(1, 16))
      ->capture_default_str();
  mon->add_option("--out", m->out, "PNG file")->capture_default_str();
  return mon;
}

// seqslam-sim truth and its options.
CLI::App* add_truth(CLI::App& app, TruthOptions* t) {
  CLI::App* tru = app.add_subcommand(
      "truth", "Ground truth (query_index,matching_reference_indices) for two recordings");
  tru->add_option("library", t->library, "Library recording")->required();
  tru->add_option("query", t->query, "Query recording")->required();
  tru->add_option("--gate", t->rule.gate_m, "Farthest a match may be (m)")
      ->check(tools::real(0.001, 1000.0))
      ->capture_default_str();
  tru->add_option("--tolerance", t->rule.tolerance, "Places either side of the nearest")
      ->check(tools::whole_of<uint32_t>())
      ->capture_default_str();
  tru->add_option("--max-heading", t->rule.max_heading_deg, "Largest heading difference (deg)")
      ->check(tools::real(0.0, 180.0))
      ->capture_default_str();
  tru->add_flag("--every-pass", t->rule.every_pass,
                "Every pass of the library near the query counts (libraries that pass a place "
                "twice), not only the nearest");
  tru->add_option("--out", t->out, "CSV file")->required();
  return tru;
}

}  // namespace

int main(int argc, char** argv) {
  hal::ignore_file_size_signal();  // ulimit -f: a write error with a message, not a death
  CLI::App app{
      "seqslam-sim: a simulated lab and Myon robot producing dream recordings with "
      "ground truth (docs/simulator.md)"};
  app.require_subcommand(1);

  GenerateOptions g;
  CLI::App* gen = add_generate(app, &g);
  RenderOptions r;
  CLI::App* ren = add_render(app, &r);
  EvaluateOptions e;
  CLI::App* ev = app.add_subcommand(
      "evaluate", "Precision/recall of the core on every pair of a generated scenario");
  ev->add_option("dir", e.dir, "Scenario directory (with pairs.csv)")->required();
  ev->add_option("--methods", e.methods, "Preprocessing methods")
      ->delimiter(',')
      ->capture_default_str();
  cli::SettingOptions<>::Selection sequence;
  sequence.scopes = storage::kScopeSequence;
  sequence.except = {"threshold", "sigma-min"};
  e.settings.add(ev, storage::RunConfig{}, sequence);
  ev->add_option("--markdown", e.markdown, "Also write the table to this file");
  ev->add_option("--jobs", e.jobs, "Threads")
      ->check(tools::whole_of<unsigned>())
      ->capture_default_str();

  MontageOptions m;
  CLI::App* mon = add_montage(app, &m);
  TruthOptions t;
  CLI::App* tru = add_truth(app, &t);
  DriftOptions dr;
  CLI::App* dri = app.add_subcommand(
      "drift", "Dead-reckoning end error of the loop over several drives (no images)");
  dri->add_option("--runs", dr.runs, "Drives")
      ->check(tools::whole<int>(1, 1000))
      ->capture_default_str();
  dri->add_option("--seed", dr.seed, "Seed")
      ->check(tools::whole_of<uint64_t>())
      ->capture_default_str();

  app.add_subcommand("lights", "List the light conditions");

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& error) {
    const int status = app.exit(error);
    return status == 0 ? 0 : 2;  // a usage error (CLI11's own codes are 100 and above)
  }
  int code = 0;
  if (gen->parsed()) {
    code = generate(g);
  } else if (ren->parsed()) {
    code = render(r);
  } else if (ev->parsed()) {
    e.settings.apply(&e.run);
    code = evaluate(e);
  } else if (mon->parsed()) {
    code = montage(m);
  } else if (tru->parsed()) {
    code = truth(t);
  } else if (dri->parsed()) {
    code = drift(dr);
  } else {
    for (const LightCondition& c : light_conditions()) {
      std::printf("%-14s %s\n", c.name.c_str(), c.description.c_str());
    }
  }
  // What went to standard output must have arrived (a full disk, /dev/full): else status 1.
  const std::string lost = tools::finish_stdout();
  if (!lost.empty()) {
    fail(lost);
    if (code == 0) code = 1;
  }
  return code;
}
