// Test fixtures for the seqslam command-line tests (tests/host/cli), made without the tool:
//
//   cli_fixtures reduce INPUT W H OUTDIR
//       every image of INPUT reduced to WxH by tools::load_sequence and written as
//       OUTDIR/place_NNNNNN.pgm: the reference for the images -> dream -> images round trip;
//   cli_fixtures results OUT N EXPECTED_CSV
//       a standalone results log of N results with awkward values (ties, extremes, negative
//       and wrapping numbers) and the CSV the tool must print for it, formatted here
//       independently with long double printf;
//   cli_fixtures results-list OUT SPEC
//       a standalone results log with one result per line of the text file SPEC, "capture
//       place confidence_raw localised" (UQ16.16 raw confidence, localised 0/1); the step is
//       the line's index: known results for scoring against a ground truth;
//   cli_fixtures results-route OUT EXPECTED_CSV
//       a standalone results log whose results carry route-search flags (RunResult::route:
//       each bit alone, combinations, none, and bits no version defines) and the CSV the tool
//       must print for it, the letters spelt out here (docs/seqslam_cli.md);
//   cli_fixtures config-version OUT VERSION
//       a 2-block file whose header is a run-configuration log of another format VERSION (an
//       older card's config);
//   cli_fixtures config-raw OUT [KEY=VALUE...]
//       a 2-block run configuration as storage::write_run_config writes it (the format's
//       checks, not the firmware's): RunConfig's defaults with the settings given, keys
//       seq_len, window, exclusion, route_window, scan_seq_len, max_shift, spacing_mm, modes
//       (RunMode bits), matcher (0 diagonal, 1 heuristic) - what `seqslam config write`
//       refuses for the firmware, to show that the firmware refuses it alike;
//   cli_fixtures full-dream OUT [FIRST]
//       a full recording: snapshots FIRST..FIRST+10 (default 100; the 32-bit bus sequence
//       wraps after 4294967295) without FIRST+3 (one missed), places after snapshots FIRST+2,
//       FIRST+5 and FIRST+9, two infrared sensors, 8x4 images;
//   cli_fixtures reduced-dream-times OUT T...
//       a reduced 8x4 recording of one place per timestamp T (microseconds, in the order
//       given: e.g. backwards);
//   cli_fixtures dream-edit IN OUT truth-x|pose-x PLACE METRES
//       a copy of the recording IN (record by record, through DreamWriter) with the x of
//       place PLACE's true pose (truth-x) or recorded odometry pose (pose-x) set to METRES (a
//       damaged or foreign record, e.g. -1073741824);
//   cli_fixtures library META IMAGES
//       a stored place library of 5 places, 32x16, HE: metadata and images files of 16
//       blocks each.
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include "seqslam/hal/file_block_device.h"
#include "seqslam/place_library.h"
#include "seqslam/storage/dream.h"
#include "seqslam/storage/library_store.h"
#include "seqslam/storage/run_files.h"
#include "seqslam_tools/dataset.h"
#include "seqslam_tools/image_io.h"

namespace {

using namespace seqslam;

int usage() {
  std::fprintf(
      stderr,
      "usage: cli_fixtures reduce INPUT W H OUTDIR | results OUT N EXPECTED_CSV | "
      "results-list OUT SPEC | results-route OUT EXPECTED_CSV | config-version OUT VERSION | "
      "config-raw OUT [KEY=VALUE...] | full-dream OUT [FIRST] | reduced-dream-times OUT T... | "
      "dream-edit IN OUT truth-x|pose-x PLACE METRES | library META IMAGES\n");
  return 2;
}

int reduce(const std::string& input, int w, int h, const std::string& outdir) {
  const tools::LoadedSequence seq = tools::load_sequence(input, w, h);
  if (!seq) {
    std::fprintf(stderr, "%s\n", seq.error().c_str());
    return 1;
  }
  for (size_t i = 0; i < seq.value().images.size(); ++i) {
    char name[64];
    std::snprintf(name, sizeof name, "/place_%06zu.pgm", i);
    std::string error;
    if (!tools::save_pgm(outdir + name, seq.value().images[i], &error)) {
      std::fprintf(stderr, "%s\n", error.c_str());
      return 1;
    }
  }
  return 0;
}

long double ld(int64_t v) {
  return static_cast<long double>(v);
}

int results(const std::string& out, uint32_t n, const std::string& expected) {
  hal::FileBlockDevice device;
  if (device.create(out, 64) != Status::kOk) {
    std::fprintf(stderr, "%s\n", device.error().c_str());
    return 1;
  }
  storage::ResultsWriter writer;
  if (writer.create(device) != Status::kOk) return 1;
  std::FILE* csv = std::fopen(expected.c_str(), "w");
  if (csv == nullptr) return 1;
  std::fprintf(csv,
               "step,capture,timestamp_us,x_m,y_m,heading_deg,place,runner_up,cost,"
               "runner_up_cost,confidence,localised\n");
  // 2^21 / 2^32 m and 2^31 * 360 / 2^32 degrees... hit decimal rounding ties.
  const int64_t xs[] = {0,         1,         -1,        int64_t{1} << 21, -(int64_t{1} << 21),
                        858993459, INT64_MAX, INT64_MIN, 123456789012345,  -98765432109876};
  const uint32_t headings[] = {0,           1,           0x80000000u, 0x7FFFFFFFu, 0x40000000u,
                               0xFFFFFFFFu, 0x9E3779B9u, 1u << 7,     0xC0000000u, 12345};
  const uint32_t confidences[] = {0, 65536, 1, 32768, 65535, 55705, 55706, 16, 8, 131072};
  for (uint32_t i = 0; i < n; ++i) {
    storage::RunResult r;
    r.step = i;
    r.capture = i + 5;
    r.timestamp_us = 4294000000u + i * 250000u;  // wraps
    r.pose.x = Q31_32::from_raw(xs[i % 10]);
    r.pose.y = Q31_32::from_raw(xs[(i + 3) % 10] / 3);
    r.pose.heading = Angle{headings[i % 10]};
    r.place = i < 3 ? -1 : static_cast<int32_t>(i - 3);
    r.runner_up = i < 3 ? -1 : static_cast<int32_t>(i + 7);
    r.cost = i * 1000u + 7u;
    r.runner_up_cost = i * 2000u + 11u;
    r.confidence = UQ16_16::from_raw(confidences[i % 10]);
    r.localised = r.place >= 0 && r.confidence.raw() < 55706;
    if (writer.append(r) != Status::kOk) return 1;
    const long double two32 = 4294967296.0L;
    std::fprintf(csv, "%u,%u,%u,%.10Lf,%.10Lf,%.8Lf,%d,%d,%u,%u,%.6Lf,%d\n", r.step, r.capture,
                 r.timestamp_us, ld(r.pose.x.raw()) / two32, ld(r.pose.y.raw()) / two32,
                 ld(static_cast<int32_t>(r.pose.heading.bam)) * 360.0L / two32, r.place,
                 r.runner_up, r.cost, r.runner_up_cost, ld(r.confidence.raw()) / 65536.0L,
                 r.localised ? 1 : 0);
  }
  return std::fclose(csv) == 0 ? 0 : 1;
}

int results_list(const std::string& out, const std::string& spec) {
  std::FILE* in = std::fopen(spec.c_str(), "r");
  if (in == nullptr) {
    std::fprintf(stderr, "%s: cannot open\n", spec.c_str());
    return 1;
  }
  hal::FileBlockDevice device;
  if (device.create(out, 64) != Status::kOk) {
    std::fprintf(stderr, "%s\n", device.error().c_str());
    std::fclose(in);
    return 1;
  }
  storage::ResultsWriter writer;
  int code = writer.create(device) == Status::kOk ? 0 : 1;
  unsigned capture = 0;
  int place = 0;
  unsigned confidence = 0;
  int localised = 0;
  for (uint32_t step = 0;
       code == 0 && std::fscanf(in, "%u %d %u %d", &capture, &place, &confidence, &localised) == 4;
       ++step) {
    storage::RunResult r;
    r.step = step;
    r.capture = capture;
    r.timestamp_us = step * 10000u;
    r.place = place;
    r.runner_up = place >= 0 ? place + 20 : -1;
    r.cost = confidence;
    r.runner_up_cost = 65536;
    r.confidence = UQ16_16::from_raw(confidence);
    r.localised = localised != 0;
    if (writer.append(r) != Status::kOk) code = 1;
  }
  if (code == 0 && !std::feof(in)) {
    std::fprintf(stderr, "%s: not 'capture place confidence_raw localised' lines\n", spec.c_str());
    code = 1;
  }
  std::fclose(in);
  return code;
}

int results_route(const std::string& out, const std::string& expected) {
  // The route byte and how the tool spells it: T tracking, P probation, S scan running,
  // s scan completed, J jumped, C carried, in that order; ? for undefined bits; - for none.
  struct Case {
    uint8_t route;
    const char* letters;
  };
  const Case cases[] = {
      {0x00, "-"},      {0x20, "T"},  {0x10, "P"},   {0x02, "S"},   {0x04, "s"},   {0x08, "J"},
      {0x01, "C"},      {0x22, "TS"}, {0x26, "TSs"}, {0x0E, "SsJ"}, {0x31, "TPC"}, {0x32, "TPS"},
      {0x3F, "TPSsJC"}, {0x40, "?"},  {0xA1, "TC?"}, {0x20, "T"},
  };
  hal::FileBlockDevice device;
  if (device.create(out, 64) != Status::kOk) {
    std::fprintf(stderr, "%s\n", device.error().c_str());
    return 1;
  }
  storage::ResultsWriter writer;
  if (writer.create(device) != Status::kOk) return 1;
  std::FILE* csv = std::fopen(expected.c_str(), "w");
  if (csv == nullptr) return 1;
  std::fprintf(csv,
               "step,capture,timestamp_us,x_m,y_m,heading_deg,place,runner_up,cost,"
               "runner_up_cost,confidence,localised,route\n");
  uint32_t i = 0;
  for (const Case& c : cases) {
    storage::RunResult r;
    r.step = i;
    r.capture = i;
    r.timestamp_us = i * 10000u;
    r.place = i < 2 ? -1 : static_cast<int32_t>(i + 40);
    r.runner_up = i < 2 ? -1 : static_cast<int32_t>(i + 60);
    r.cost = 1000u + i;
    r.runner_up_cost = 2000u;
    r.confidence = UQ16_16::from_raw(32768u + i);
    r.localised = c.route == 0x20 && r.place >= 0;
    r.route = c.route;
    if (writer.append(r) != Status::kOk) return 1;
    std::fprintf(csv, "%u,%u,%u,0.0000000000,0.0000000000,0.00000000,%d,%d,%u,%u,%.6Lf,%d,%s\n",
                 r.step, r.capture, r.timestamp_us, r.place, r.runner_up, r.cost, r.runner_up_cost,
                 ld(r.confidence.raw()) / 65536.0L, r.localised ? 1 : 0, c.letters);
    ++i;
  }
  return std::fclose(csv) == 0 ? 0 : 1;
}

int config_version(const std::string& out, uint16_t version) {
  hal::FileBlockDevice device;
  if (device.create(out, 2) != Status::kOk) {
    std::fprintf(stderr, "%s\n", device.error().c_str());
    return 1;
  }
  storage::LogKind kind = storage::kRunConfigKind;
  kind.version = version;
  const uint8_t payload[120] = {};
  storage::LogWriter writer;
  return writer.create(device, kind, payload, sizeof payload) == Status::kOk ? 0 : 1;
}

int config_raw(const std::string& out, int argc, char** argv) {
  storage::RunConfig c;
  for (int i = 0; i < argc; ++i) {
    const std::string kv = argv[i];
    const size_t eq = kv.find('=');
    const std::string key = kv.substr(0, eq);
    const long v = eq == std::string::npos ? -1 : std::strtol(kv.c_str() + eq + 1, nullptr, 10);
    if (key == "seq_len") {
      c.sequence.seq_len = static_cast<uint16_t>(v);
    } else if (key == "window") {
      c.sequence.window = static_cast<uint16_t>(v);
    } else if (key == "exclusion") {
      c.sequence.exclusion = static_cast<uint16_t>(v);
    } else if (key == "route_window") {
      c.route.window = static_cast<uint16_t>(v);
    } else if (key == "scan_seq_len") {
      c.route.scan_seq_len = static_cast<uint16_t>(v);
    } else if (key == "max_shift") {
      c.max_shift = static_cast<uint8_t>(v);
    } else if (key == "spacing_mm") {
      c.spacing = Q31_32::from_ratio(v, 1000);
    } else if (key == "modes") {
      c.modes = static_cast<uint8_t>(v);
    } else if (key == "matcher") {
      c.matcher = static_cast<LocaliserMatcher>(v);
    } else {
      std::fprintf(stderr, "config-raw: unknown setting '%s'\n", kv.c_str());
      return 2;
    }
  }
  hal::FileBlockDevice device;
  if (device.create(out, 2) != Status::kOk) {
    std::fprintf(stderr, "%s\n", device.error().c_str());
    return 1;
  }
  const Status s = storage::write_run_config(device, c);
  if (s != Status::kOk) std::fprintf(stderr, "config-raw: %s\n", status_name(s));
  return s == Status::kOk ? 0 : 1;
}

int full_dream(const std::string& out, uint32_t first) {
  hal::FileBlockDevice device;
  if (device.create(out, 32) != Status::kOk) {
    std::fprintf(stderr, "%s\n", device.error().c_str());
    return 1;
  }
  storage::DreamHeader h;
  h.variant = storage::DreamVariant::kFull;
  h.mapping = hal::PipelineMapping::reduction(8, 4);
  h.infrared_count = 2;
  h.infrared[0] = storage::InfraredMount{120, 40, 8192, 40, 300};
  h.infrared[1] = storage::InfraredMount{120, -40, 57344, 40, 300};
  storage::DreamWriter writer;
  storage::DreamProblem problem = storage::DreamProblem::kNone;
  if (writer.create(device, h, &problem) != Status::kOk) {
    std::fprintf(stderr, "create: %s\n", storage::dream_problem_text(problem));
    return 1;
  }
  uint8_t pixels[32];
  uint32_t places = 0;
  for (uint32_t k = 0; k <= 10; ++k) {
    if (k == 3) continue;            // a snapshot the bus dropped
    const uint32_t seq = first + k;  // wraps like the bus's counter
    hal::SensorSnapshot s;
    s.sequence = seq;
    s.timestamp_us = (100 + k) * 10000;
    s.flags = hal::SensorSnapshot::kHasEncoders | hal::SensorSnapshot::kHasInfrared;
    s.infrared_count = 2;
    s.encoder_left = (100 + k) * 7;
    s.encoder_right = (100 + k) * 9;
    s.infrared_mm[0] = 250;
    s.infrared_mm[1] = 0;
    if (writer.snapshot(s, &problem) != Status::kOk) return 1;
    if (k == 2 || k == 5 || k == 9) {
      for (uint32_t i = 0; i < sizeof pixels; ++i)
        pixels[i] = static_cast<uint8_t>(i * 8 + places * 50);
      storage::DreamPlace p;
      p.index = places++;
      p.bus_sequence = seq;
      p.timestamp_us = s.timestamp_us;
      p.encoder_left = s.encoder_left;
      p.encoder_right = s.encoder_right;
      p.infrared_count = 2;
      p.size = ImageSize{8, 4};
      p.gray = pixels;
      if (writer.place(p, &problem) != Status::kOk) {
        std::fprintf(stderr, "place: %s\n", storage::dream_problem_text(problem));
        return 1;
      }
    }
  }
  return 0;
}

int reduced_dream_times(const std::string& out, int count, char** times) {
  hal::FileBlockDevice device;
  if (device.create(out, 32) != Status::kOk) {
    std::fprintf(stderr, "%s\n", device.error().c_str());
    return 1;
  }
  storage::DreamHeader h;
  h.variant = storage::DreamVariant::kReduced;
  h.mapping = hal::PipelineMapping::reduction(8, 4);
  storage::DreamWriter writer;
  if (writer.create(device, h) != Status::kOk) return 1;
  uint8_t pixels[32] = {};
  for (int i = 0; i < count; ++i) {
    storage::DreamPlace p;
    p.index = static_cast<uint32_t>(i);
    p.timestamp_us = static_cast<uint32_t>(std::strtoul(times[i], nullptr, 10));
    p.size = ImageSize{8, 4};
    p.gray = pixels;
    if (writer.place(p) != Status::kOk) return 1;
  }
  return 0;
}

// Copies `in` to `out` record by record, the x of one place's true or recorded pose replaced.
int dream_edit(const std::string& in, const std::string& out, const std::string& what,
               uint32_t place, double metres) {
  if (what != "truth-x" && what != "pose-x") return usage();
  hal::FileBlockDevice source;
  hal::FileBlockDevice target;
  if (source.open(in, false) != Status::kOk ||
      target.create(out, source.block_count()) != Status::kOk) {
    std::fprintf(stderr, "%s%s\n", source.error().c_str(), target.error().c_str());
    return 1;
  }
  std::vector<uint8_t> buffer(storage::kDreamRecordMax);
  storage::DreamReader reader;
  storage::DreamWriter writer;
  if (reader.open(source, Span<uint8_t>(buffer.data(), buffer.size())) != Status::kOk ||
      writer.create(target, reader.header()) != Status::kOk) {
    return 1;
  }
  const Q31_32 x = Q31_32::from_raw(static_cast<int64_t>(metres * 4294967296.0));
  for (;;) {
    storage::DreamItem item;
    const Status s = reader.next(&item);
    if (s == Status::kOutOfRange) return 0;
    if (s != Status::kOk) return 1;
    Status w = Status::kOk;
    if (item.type == storage::DreamRecord::kSnapshot) {
      w = writer.snapshot(item.snapshot);
    } else if (item.type == storage::DreamRecord::kTruth) {
      if (what == "truth-x" && item.truth.place_index == place) item.truth.pose.x = x;
      w = writer.truth(item.truth);
    } else {
      if (what == "pose-x" && item.place.index == place) item.place.pose.x = x;
      w = writer.place(item.place);
    }
    if (w != Status::kOk) return 1;
  }
}

int library(const std::string& meta_path, const std::string& images_path) {
  hal::FileBlockDevice meta;
  hal::FileBlockDevice images;
  if (meta.create(meta_path, 16) != Status::kOk || images.create(images_path, 16) != Status::kOk) {
    std::fprintf(stderr, "%s%s\n", meta.error().c_str(), images.error().c_str());
    return 1;
  }
  static storage::StoredPlaceImages stored;
  static uint8_t cache[2 * 512];
  static PlaceInfo info[16];
  static uint32_t sums[16];
  static PlaceLibrary places;
  storage::LibraryConfig config;  // 32x16, HE, the default mapping
  storage::LibraryProblem problem = storage::LibraryProblem::kNone;
  if (stored.create(meta, images, config, Span<uint8_t>(cache, sizeof cache), &problem) !=
      Status::kOk) {
    std::fprintf(stderr, "library: %s\n", storage::library_problem_text(problem));
    return 1;
  }
  if (places.configure(config.image_size, stored,
                       PlaceLibraryBuffers{Span<PlaceInfo>(info, 16), Span<uint32_t>(sums, 16)}) !=
      Status::kOk) {
    return 1;
  }
  uint8_t pixels[512];
  for (uint32_t p = 0; p < 5; ++p) {
    for (uint32_t k = 0; k < sizeof pixels; ++k)
      pixels[k] = static_cast<uint8_t>(k * 3 + p * 40);
    const Pose2 pose{Q31_32::from_ratio(p, 5), Q31_32::from_int(0), Angle{}};
    if (places.add(ImageView{pixels, config.image_size}, pose, p) != Status::kOk) return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2) return usage();
  const std::string what = argv[1];
  if (what == "reduce" && argc == 6) {
    return reduce(argv[2], std::atoi(argv[3]), std::atoi(argv[4]), argv[5]);
  }
  if (what == "results" && argc == 5) {
    return results(argv[2], static_cast<uint32_t>(std::strtoul(argv[3], nullptr, 10)), argv[4]);
  }
  if (what == "results-list" && argc == 4) return results_list(argv[2], argv[3]);
  if (what == "results-route" && argc == 4) return results_route(argv[2], argv[3]);
  if (what == "config-version" && argc == 4) {
    return config_version(argv[2], static_cast<uint16_t>(std::strtoul(argv[3], nullptr, 10)));
  }
  if (what == "config-raw" && argc >= 3) return config_raw(argv[2], argc - 3, argv + 3);
  if (what == "full-dream" && (argc == 3 || argc == 4)) {
    return full_dream(argv[2],
                      argc == 4 ? static_cast<uint32_t>(std::strtoul(argv[3], nullptr, 10)) : 100u);
  }
  if (what == "reduced-dream-times" && argc >= 4) {
    return reduced_dream_times(argv[2], argc - 3, argv + 3);
  }
  if (what == "dream-edit" && argc == 7) {
    return dream_edit(argv[2], argv[3], argv[4],
                      static_cast<uint32_t>(std::strtoul(argv[5], nullptr, 10)),
                      std::strtod(argv[6], nullptr));
  }
  if (what == "library" && argc == 4) return library(argv[2], argv[3]);
  return usage();
}
