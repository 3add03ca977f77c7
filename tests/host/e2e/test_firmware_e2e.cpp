// End to end on the host: the firmware application (the same code as on the board) teaches
// on one recorded run and repeats on a second; its results equal running the core directly on
// the same images, and its recording equals what it replayed.
#include <algorithm>
#include <cstdio>
#include <memory>
#include <vector>

#include <gtest/gtest.h>

#include "app.h"
#include "core_run.h"
#include "seqslam/hal/fake_block_device.h"
#include "seqslam/hal/fake_sensors.h"
#include "seqslam/storage/run_files.h"
#include "synthetic_run.h"

namespace seqslam {
namespace {

constexpr uint32_t kPlaces = 70;  // fits the firmware's place capacity (profile::kMaxPlaces)
static_assert(kPlaces <= profile::kMaxPlaces, "the runs must fit the firmware");

struct Disk {
  std::vector<uint8_t> bytes = std::vector<uint8_t>(8u << 20, 0xEE);
  hal::FakeBlockDevice device{Span<uint8_t>(bytes.data(), bytes.size())};
  storage::Volume volume;

  void format() {
    const storage::VolumeFile files[] = {
        {"config", 0, 2},        {"replay", 0, 4096}, {"library", 0, 64},
        {"library.img", 0, 256}, {"record", 0, 4096}, {"results", 0, 64},
        {"queries", 0, 512},
    };
    ASSERT_EQ(storage::Volume::format(device, files, 7), Status::kOk);
    ASSERT_EQ(volume.mount(device), Status::kOk);
  }
  storage::Region file(const char* name) {
    storage::Region r;
    EXPECT_EQ(volume.open(name, &r), Status::kOk);
    return r;
  }
};

std::string g_console;
void capture_console(const char* text) {
  g_console += text;
}

test::RunOptions run_a() {
  test::RunOptions o;
  o.places = kPlaces;
  return o;
}
test::RunOptions run_b() {  // the same route in other light, with noise and a lossy bus
  test::RunOptions o;
  o.places = kPlaces;
  o.gain_q8 = 190;
  o.offset = 25;
  o.noise = 6;
  o.noise_seed = 2;
  o.start_count = 0x00001234u;
  o.drop_every = 97;
  return o;
}

Status run_app(Disk& disk, storage::RunConfig config, app::Stats* stats) {
  storage::Region c = disk.file("config");
  EXPECT_EQ(storage::write_run_config(c, config), Status::kOk);
  auto application = std::make_unique<app::Application>();
  g_console.clear();
  Status s = application->start(disk.volume, nullptr, nullptr, capture_console);
  if (s == Status::kOk) s = application->run();
  *stats = application->stats();
  return s;
}

Status run_app(Disk& disk, uint8_t modes, app::Stats* stats) {
  storage::RunConfig config = test::synthetic_run_config(modes);
  return run_app(disk, config, stats);
}

using test::place_images;

TEST(FirmwareE2E, TeachThenRepeatEqualsTheCoreOnTheSameImages) {
  auto world = std::make_unique<test::RunWorld>();
  world->generate(4242, 2048, 16);
  auto disk = std::make_unique<Disk>();
  disk->format();

  // Teach on run A.
  storage::Region replay = disk->file("replay");
  ASSERT_EQ(test::write_synthetic_run(replay, *world, run_a()), kPlaces);
  app::Stats stats;
  ASSERT_EQ(run_app(*disk, storage::kModeTeach, &stats), Status::kOk) << g_console;
  EXPECT_EQ(stats.taught, kPlaces);
  EXPECT_EQ(stats.captures, kPlaces);
  EXPECT_EQ(stats.no_frame, 0u);
  const auto images_a = place_images(replay);

  // Repeat (and record) on run B.
  ASSERT_EQ(test::write_synthetic_run(replay, *world, run_b()), kPlaces);
  ASSERT_EQ(run_app(*disk, storage::kModeRepeat | storage::kModeRecord, &stats), Status::kOk)
      << g_console;
  EXPECT_EQ(stats.library_loaded, kPlaces);
  EXPECT_EQ(stats.captures, kPlaces);
  EXPECT_EQ(stats.steps, kPlaces);
  EXPECT_GT(stats.missed_snapshots, 10u);  // the lossy bus was noticed
  EXPECT_EQ(stats.storage_errors, 0u);
  const auto images_b = place_images(replay);
  ASSERT_EQ(images_b.size(), kPlaces);

  // The core, directly, on the same images.
  test::CoreRun<kPlaces> core(test::synthetic_run_config(storage::kModeRepeat).localiser());
  ASSERT_TRUE(core.ok());
  ASSERT_TRUE(core.teach(images_a));
  storage::Region results_file = disk->file("results");
  storage::ResultsReader results;
  ASSERT_EQ(results.open(results_file), Status::kOk);
  uint32_t compared = 0, correct = 0;
  for (const auto& img : images_b) {
    Match m;
    ASSERT_TRUE(core.localise(img, &m));
    storage::RunResult r;
    ASSERT_EQ(results.next(&r), Status::kOk);
    EXPECT_EQ(r.step, m.query);
    EXPECT_EQ(r.place, m.place);
    EXPECT_EQ(r.runner_up, m.runner_up);
    EXPECT_EQ(r.cost, m.cost);
    EXPECT_EQ(r.confidence.raw(), m.confidence.raw());
    EXPECT_EQ(r.localised, m.localised);
    ++compared;
    const int32_t err = m.place - static_cast<int32_t>(r.capture);
    if (m.place >= 0 && err >= -1 && err <= 1) ++correct;
  }
  storage::RunResult extra;
  EXPECT_EQ(results.next(&extra), Status::kOutOfRange);
  EXPECT_EQ(compared, kPlaces);
  EXPECT_GE(correct, (kPlaces - 29) * 9 / 10) << "sanity: the runs are the same route";

  // The recording written in record mode holds the replayed run's places.
  storage::Region record = disk->file("record");
  const auto recorded = place_images(record);
  ASSERT_EQ(recorded.size(), images_b.size());
  for (size_t i = 0; i < recorded.size(); ++i)
    EXPECT_EQ(recorded[i], images_b[i]) << i;
}

TEST(FirmwareE2E, RepeatWithTheHeuristicMatcherEqualsTheCore) {
  // The run configuration selects the heuristic matcher (with S above the diagonal matcher's
  // kMaxSeqLen of this firmware: the heuristic's state does not grow with S); every result
  // record equals the core's Localiser with the same settings, in the unchanged format.
  if (!profile::kHeuristicMatcher) GTEST_SKIP() << "built without the heuristic matcher";
  auto world = std::make_unique<test::RunWorld>();
  world->generate(4343, 2048, 16);
  auto disk = std::make_unique<Disk>();
  disk->format();
  storage::Region replay = disk->file("replay");
  ASSERT_EQ(test::write_synthetic_run(replay, *world, run_a()), kPlaces);
  app::Stats stats;
  ASSERT_EQ(run_app(*disk, storage::kModeTeach, &stats), Status::kOk) << g_console;
  const auto images_a = place_images(replay);

  ASSERT_EQ(test::write_synthetic_run(replay, *world, run_b()), kPlaces);
  storage::RunConfig config = test::synthetic_run_config(storage::kModeRepeat);
  config.sequence.seq_len = 35;
  config.sequence.threshold = UQ16_16::from_ratio(1, 2);
  config.matcher = LocaliserMatcher::kHeuristic;
  config.heuristic.candidates = 4;
  config.heuristic.guard = 4;
  config.heuristic.threshold = UQ8_8::from_int(80);
  ASSERT_EQ(run_app(*disk, config, &stats), Status::kOk) << g_console;
  EXPECT_NE(g_console.find("app: sequence matcher: heuristic"), std::string::npos) << g_console;
  EXPECT_EQ(stats.steps, kPlaces);
  const auto images_b = place_images(replay);
  ASSERT_EQ(images_b.size(), kPlaces);

  test::CoreRun<kPlaces> core(config.localiser());
  ASSERT_TRUE(core.ok());
  ASSERT_TRUE(core.teach(images_a));
  storage::Region results_file = disk->file("results");
  storage::ResultsReader results;
  ASSERT_EQ(results.open(results_file), Status::kOk);
  uint32_t correct = 0, localised = 0;
  for (const auto& img : images_b) {
    Match m;
    ASSERT_TRUE(core.localise(img, &m));
    storage::RunResult r;
    ASSERT_EQ(results.next(&r), Status::kOk);
    EXPECT_EQ(r.step, m.query);
    EXPECT_EQ(r.place, m.place);
    EXPECT_EQ(r.runner_up, m.runner_up);
    EXPECT_EQ(r.cost, m.cost);
    EXPECT_EQ(r.runner_up_cost, m.runner_up_cost);
    EXPECT_EQ(r.confidence.raw(), m.confidence.raw());
    EXPECT_EQ(r.localised, m.localised);
    const int32_t err = m.place - static_cast<int32_t>(r.capture);
    if (m.place >= 0 && err >= -1 && err <= 1) ++correct;
    if (m.localised) ++localised;
  }
  storage::RunResult extra;
  EXPECT_EQ(results.next(&extra), Status::kOutOfRange);
  // Sanity: the same route, found from the first step of each sequence on.
  EXPECT_GE(correct, kPlaces * 9 / 10);
  EXPECT_GE(localised, 1u);
}

TEST(FirmwareE2E, RefusesALibraryBuiltForAnotherConfiguration) {
  auto world = std::make_unique<test::RunWorld>();
  world->generate(7, 2048, 16);
  auto disk = std::make_unique<Disk>();
  disk->format();
  storage::Region replay = disk->file("replay");
  ASSERT_EQ(test::write_synthetic_run(replay, *world, run_a()), kPlaces);
  app::Stats stats;
  ASSERT_EQ(run_app(*disk, storage::kModeTeach, &stats), Status::kOk) << g_console;
  // Repeat with patch normalisation: the stored library was built with HE.
  storage::RunConfig config = test::synthetic_run_config(storage::kModeRepeat);
  config.preprocess.method = Preprocessing::kPatchNorm;
  storage::Region c = disk->file("config");
  ASSERT_EQ(storage::write_run_config(c, config), Status::kOk);
  auto application = std::make_unique<app::Application>();
  g_console.clear();
  EXPECT_EQ(application->start(disk->volume, nullptr, nullptr, capture_console),
            Status::kFailedPrecondition);
  EXPECT_NE(g_console.find("other preprocessing"), std::string::npos) << g_console;
}

// What the application cannot run it refuses at start with storage::check_run_config's issue
// and status (the check `seqslam config write` makes), before it writes anything; at its
// limits it runs.
TEST(FirmwareE2E, RefusesWhatCheckRunConfigRefusesBeforeWritingAnything) {
  auto world = std::make_unique<test::RunWorld>();
  world->generate(7, 2048, 16);
  auto disk = std::make_unique<Disk>();
  disk->format();
  storage::Region replay = disk->file("replay");
  ASSERT_EQ(test::write_synthetic_run(replay, *world, run_a()), kPlaces);
  storage::RunConfig base;
  base.modes = storage::kModeTeach | storage::kModeRepeat | storage::kModeRecord;
  base.mapping = hal::PipelineMapping::reduction(32, 16);
  std::vector<storage::RunConfig> refused(8, base);
  refused[0].sequence.seq_len = profile::kMaxSeqLen + 1;
  refused[1].sequence.window = profile::kMaxNormWindow + 1;
  refused[2].sequence.exclusion = profile::kMaxExclusion + 1;
  refused[3].route.window = profile::kWindowSlots + 2;
  refused[4].route.scan_seq_len = profile::kMaxScanSeqLen + 1;
  refused[5].max_shift = 1;
  refused[6].modes = storage::kModeTeach | storage::kModeRepeat | storage::kModeExplore;
  refused[6].matcher = LocaliserMatcher::kHeuristic;
  refused[7].modes = storage::kModeRecord;  // no route search, but the diagonal matcher's S
  refused[7].sequence.seq_len = profile::kMaxSeqLen + 1;
  // A spacing beyond the trigger's range is outside the settings table's range: no card
  // carries it (write_run_config refuses it, and a card with it reads as damaged).
  storage::RunConfig far = base;
  far.spacing = Q31_32::from_raw(SpatialTrigger::kMaxSpacing.raw() + 1);
  storage::Region far_file = disk->file("config");
  EXPECT_EQ(storage::write_run_config(far_file, far), Status::kInvalidArgument);
  for (const storage::RunConfig& config : refused) {
    const storage::RunCheck check = storage::check_run_config(config, profile::kRunLimits);
    ASSERT_FALSE(check.ok());
    storage::Region c = disk->file("config");
    ASSERT_EQ(storage::write_run_config(c, config), Status::kOk);
    const std::vector<uint8_t> written = disk->bytes;
    auto application = std::make_unique<app::Application>();
    g_console.clear();
    EXPECT_EQ(application->start(disk->volume, nullptr, nullptr, capture_console), check.status);
    const std::string reason = std::string("app: configuration: ") + status_name(check.status) +
                               " - " + storage::run_issue_text(check.issue) + "\n";
    EXPECT_NE(g_console.find(reason), std::string::npos) << g_console;
    EXPECT_TRUE(disk->bytes == written) << "the card changed: " << reason;
  }
  // At every limit at once: the application runs (teach + repeat, the route search).
  storage::RunConfig limits = base;
  limits.sequence.seq_len = profile::kMaxSeqLen;
  limits.sequence.window = profile::kMaxNormWindow;
  limits.sequence.exclusion = profile::kMaxExclusion;
  limits.route.window = profile::kWindowSlots;
  limits.route.scan_seq_len = profile::kMaxScanSeqLen;
  ASSERT_TRUE(storage::check_run_config(limits, profile::kRunLimits).ok());
  app::Stats stats;
  EXPECT_EQ(run_app(*disk, limits, &stats), Status::kOk) << g_console;
  EXPECT_EQ(stats.taught, kPlaces);
  EXPECT_EQ(stats.steps, kPlaces);
}

// Issue 34: a refused start changes nothing. Every refusal of the firmware's start-up, on a
// card that holds a taught library, results and a recording (what a refusal could cost the
// robot): the start fails with the reason printed, and the card is byte for byte what it was.
struct StartRefusal {
  const char* what;
  uint8_t modes;
  const char* missing;  // a volume file the card lacks (nullptr: all there)
  const char* reason;   // in the console
  void (*adjust)(storage::RunConfig*);
  uint32_t queries_blocks = 512;  // the query history's size (one 32x16 image a block)
};

void no_change(storage::RunConfig*) {}

// A card with every file, after a teach + record run on A and a repeat run on B: library,
// results and recording full.
std::unique_ptr<Disk> working_card(const test::RunWorld& world, const char* missing,
                                   uint32_t queries_blocks = 512) {
  auto disk = std::make_unique<Disk>();
  const storage::VolumeFile all[] = {
      {"config", 0, 2},    {"replay", 0, 4096}, {"library", 0, 64}, {"library.img", 0, 256},
      {"record", 0, 4096}, {"results", 0, 64},  {"queries", 0, queries_blocks}, {"map", 0, 512},
      {"graph", 0, 256},   {"state", 0, 512}};
  std::vector<storage::VolumeFile> files;
  for (const storage::VolumeFile& f : all) {
    if (missing == nullptr || std::string(f.name) != missing) files.push_back(f);
  }
  EXPECT_EQ(storage::Volume::format(disk->device, files.data(),
                                    static_cast<uint32_t>(files.size())),
            Status::kOk);
  EXPECT_EQ(disk->volume.mount(disk->device), Status::kOk);
  storage::Region replay;
  if (disk->volume.open("replay", &replay) == Status::kOk) {
    EXPECT_EQ(test::write_synthetic_run(replay, world, run_a()), kPlaces);
  }
  app::Stats stats;
  // What can be made on this card (a missing file stops the run that needs it).
  if (missing == nullptr || std::string(missing) == "queries" ||
      std::string(missing) == "results" || std::string(missing) == "map") {
    EXPECT_EQ(run_app(*disk, storage::kModeTeach | storage::kModeRecord, &stats), Status::kOk)
        << g_console;
  }
  return disk;
}

TEST(FirmwareE2E, EveryStartRefusalLeavesTheCardAsItWas) {
  auto world = std::make_unique<test::RunWorld>();
  world->generate(11, 2048, 16);
  const uint8_t teach = storage::kModeTeach;
  const uint8_t repeat = storage::kModeRepeat;
  const uint8_t record = storage::kModeRecord;
  const uint8_t explore = storage::kModeTeach | storage::kModeRepeat | storage::kModeExplore;
  const StartRefusal cases[] = {
      {"no replay and no live sensors", repeat, "replay", "app: no sensors", no_change},
      {"no library files", repeat, "library", "app: library files: NOT_FOUND", no_change},
      {"no results file", repeat, "results", "app: results file: NOT_FOUND", no_change},
      {"no query history", repeat, "queries", "app: query history: NOT_FOUND", no_change},
      {"no record file", teach | record, "record", "app: record file: NOT_FOUND", no_change},
      {"record-colour from a grey replay", teach | repeat | record, nullptr,
       "app: configuration: FAILED_PRECONDITION", [](storage::RunConfig* c) {
         c->trigger = storage::TriggerMode::kEveryFrame;
         c->record_colour = true;
       }},
      {"a mapping the replay was not made with", repeat, nullptr,
       "app: pixel pipeline", [](storage::RunConfig* c) {
         c->mapping = hal::PipelineMapping::reduction(25, 20);
       }},
      {"a library made for another preprocessing", repeat, nullptr, "app: library:",
       [](storage::RunConfig* c) { c->preprocess.method = Preprocessing::kPatchNorm; }},
      {"the firmware's limits", teach | repeat, nullptr, "app: configuration: OUT_OF_RANGE",
       [](storage::RunConfig* c) { c->sequence.seq_len = profile::kMaxSeqLen + 1; }},
      // 5 steps < the scan's 10 images: no scan could ever run.
      {"a query history shorter than the scan", repeat, nullptr,
       "app: query history: OUT_OF_RANGE", no_change, 5},
      // 12 steps: a scan of 16 places a step reaches (12 - 10 + 1) x 16 = 48 < 70 places, so
      // from an unknown start every scan would be abandoned.
      {"a query history too small for a scan over the library", repeat, nullptr,
       "app: query history: OUT_OF_RANGE",
       [](storage::RunConfig* c) {
         c->route.start = -1;
         c->route.scan_places = 16;
       },
       12},
#if SEQSLAM_APP_MAPPING
      {"explore without the map files", explore, "map", "app: opening the map files",
       no_change},
      {"continue with record mode", explore | storage::kModeContinue | record, nullptr,
       "app: configuration: FAILED_PRECONDITION", no_change},
      {"continue without a saved state", explore | storage::kModeContinue, nullptr,
       "app: reading the saved run", no_change},
#endif
  };
  for (const StartRefusal& r : cases) {
    SCOPED_TRACE(r.what);
    auto disk = working_card(*world, r.missing, r.queries_blocks);
    storage::RunConfig config = test::synthetic_run_config(r.modes);
    r.adjust(&config);
    storage::Region c = disk->file("config");
    ASSERT_EQ(storage::write_run_config(c, config), Status::kOk);
    const std::vector<uint8_t> before = disk->bytes;
    auto application = std::make_unique<app::Application>();
    g_console.clear();
    EXPECT_NE(application->start(disk->volume, nullptr, nullptr, capture_console), Status::kOk);
    EXPECT_NE(g_console.find(r.reason), std::string::npos) << g_console;
    EXPECT_TRUE(disk->bytes == before) << "the refused start changed the card";
  }
}

TEST(FirmwareE2E, AShortQueryHistoryStillTracksFromAKnownStart) {
  // The query history that refuses an unknown start (12 steps: scans reach 48 of 70 places)
  // is enough for tracking from place 0, and the check says which case it is.
  auto world = std::make_unique<test::RunWorld>();
  world->generate(11, 2048, 16);
  auto disk = working_card(*world, nullptr, 12);
  storage::RunConfig config = test::synthetic_run_config(storage::kModeRepeat);
  config.route.scan_places = 16;  // a scan of 70 places takes 5 steps
  EXPECT_EQ(storage::query_history_fit(12, scan_seq_len(config.route, config.sequence), kPlaces,
                                       config.route.scan_places),
            storage::QueryFit::kTooFewForLibrary);
  ASSERT_EQ(config.route.start, 0);
  app::Stats stats;
  EXPECT_EQ(run_app(*disk, config, &stats), Status::kOk) << g_console;
  EXPECT_EQ(stats.steps, kPlaces);
  EXPECT_GT(stats.localised, kPlaces / 2);
}

TEST(FirmwareE2E, LoopClosureWhileTeachingInOneRun) {
  // A 6 m corridor (30 places; the world wraps around) driven three times: with teach + repeat
  // the later laps are localised against the earlier laps' places while the library is being
  // built. The route search starts unknown here, so its fixes come from relocalisation scans
  // (the full search at an anchor, a few steps late) and from the window once a scan has
  // confirmed where it is: every result equals the core's Localiser on the same images.
  constexpr uint32_t kLap = 30;
  auto world = std::make_unique<test::RunWorld>();
  world->generate(99, kLap * 2, 16);
  auto disk = std::make_unique<Disk>();
  disk->format();
  storage::Region replay = disk->file("replay");
  test::RunOptions o = run_a();
  o.places = 3 * kLap;
  ASSERT_EQ(test::write_synthetic_run(replay, *world, o), o.places);
  storage::RunConfig config =
      test::synthetic_run_config(storage::kModeTeach | storage::kModeRepeat);
  config.sequence.seq_len = 10;
  config.sequence.window = 20;
  config.recent_exclusion = 20;
  config.route.scan_places = 8;
  app::Stats stats;
  ASSERT_EQ(run_app(*disk, config, &stats), Status::kOk) << g_console;
  EXPECT_EQ(stats.taught, o.places);
  EXPECT_EQ(stats.steps, o.places);
  EXPECT_GT(stats.relocalisation_scans, 2u);
  const auto images = place_images(replay);
  ASSERT_EQ(images.size(), o.places);
  test::CoreRun<3 * kLap> core(config.localiser(), true);
  ASSERT_TRUE(core.ok());
  storage::Region results_file = disk->file("results");
  storage::ResultsReader results;
  ASSERT_EQ(results.open(results_file), Status::kOk);
  storage::RunResult r;
  uint32_t closures = 0, wrong = 0;
  for (uint32_t k = 0; k < o.places; ++k) {
    Match m;
    ASSERT_TRUE(core.observe(images[k], k, &m));
    ASSERT_EQ(results.next(&r), Status::kOk);
    EXPECT_EQ(r.place, m.place) << k;
    EXPECT_EQ(r.confidence.raw(), m.confidence.raw()) << k;
    EXPECT_EQ(r.localised, m.localised) << k;
    if (!r.localised) continue;
    const int32_t lap_offset =
        static_cast<int32_t>(r.capture % kLap) - (r.place % static_cast<int32_t>(kLap));
    const bool ok = lap_offset >= -1 && lap_offset <= 1;
    ok ? ++closures : ++wrong;
  }
  EXPECT_EQ(wrong, 0u);
  EXPECT_GE(closures, 5u);
}

TEST(FirmwareE2E, RecordingsWithoutOdometryAreOneFramePerStep) {
  // Public datasets become reduced recordings (images only): the firmware takes every frame
  // as a place (trigger every-frame) and gives the same results as the core.
  auto world = std::make_unique<test::RunWorld>();
  world->generate(11, 2048, 16);
  std::vector<std::vector<uint8_t>> a, b;
  test::Rng rng(3);
  for (uint32_t p = 0; p < kPlaces; ++p) {
    std::vector<uint8_t> img(512);
    world->render(p * 2, 1, 0, 32, 256, 0, 3, rng, img.data());
    a.push_back(img);
    world->render(p * 2, 1, 0, 32, 200, 10, 5, rng, img.data());
    b.push_back(img);
  }
  auto disk = std::make_unique<Disk>();
  disk->format();
  auto write_reduced = [&](const std::vector<std::vector<uint8_t>>& images) {
    storage::Region replay = disk->file("replay");
    storage::DreamHeader h;
    h.variant = storage::DreamVariant::kReduced;
    h.mapping = hal::PipelineMapping::reduction(32, 16);
    storage::DreamWriter w;
    ASSERT_EQ(w.create(replay, h), Status::kOk);
    for (uint32_t i = 0; i < images.size(); ++i) {
      storage::DreamPlace p;
      p.index = i;
      p.timestamp_us = i * 500000u;
      p.size = ImageSize{32, 16};
      p.gray = images[i].data();
      ASSERT_EQ(w.place(p), Status::kOk);
    }
  };
  auto run = [&](uint8_t modes) {
    storage::RunConfig config = test::synthetic_run_config(modes);
    config.trigger = storage::TriggerMode::kEveryFrame;
    storage::Region c = disk->file("config");
    ASSERT_EQ(storage::write_run_config(c, config), Status::kOk);
    auto application = std::make_unique<app::Application>();
    g_console.clear();
    ASSERT_EQ(application->start(disk->volume, nullptr, nullptr, capture_console), Status::kOk)
        << g_console;
    ASSERT_EQ(application->run(), Status::kOk) << g_console;
    EXPECT_EQ(application->stats().captures, kPlaces);
  };
  write_reduced(a);
  run(storage::kModeTeach);
  write_reduced(b);
  run(storage::kModeRepeat);

  test::CoreRun<kPlaces> core(test::synthetic_run_config(storage::kModeRepeat).localiser());
  ASSERT_TRUE(core.ok());
  ASSERT_TRUE(core.teach(a));
  storage::Region results_file = disk->file("results");
  storage::ResultsReader results;
  ASSERT_EQ(results.open(results_file), Status::kOk);
  for (const auto& img : b) {
    Match m;
    ASSERT_TRUE(core.localise(img, &m));
    storage::RunResult r;
    ASSERT_EQ(results.next(&r), Status::kOk);
    EXPECT_EQ(r.place, m.place);
    EXPECT_EQ(r.confidence.raw(), m.confidence.raw());
  }
}

// The application with live (fake) sensors instead of a replay: a lossy bus (every 50th
// snapshot dropped, one damaged, one "not ready yet"), an encoder glitch, and a camera that
// renders the scene at the position the bus reports and fails every 13th capture.
struct LiveScene {
  const test::RunWorld* world;
  const hal::FakeSpinalCord* bus;
  test::Rng rng{5};
};

bool render_live(void* context, uint32_t /*frame*/, ImageSize size, uint8_t* gray) {
  auto* scene = static_cast<LiveScene*>(context);
  // Ticks since the start -> metres -> world columns (10 cm each).
  const uint32_t ticks = scene->bus->current().encoder_left - 0xFFFFF000u;
  const uint32_t column = static_cast<uint32_t>(static_cast<uint64_t>(ticks) * 532 / 4096 / 100);
  scene->world->render(column, 1, 0, size.width, 256, 0, 3, scene->rng, gray);
  return true;
}

TEST(FirmwareE2E, LiveSensorsWithFaultsAreCountedNotInvented) {
  auto world = std::make_unique<test::RunWorld>();
  world->generate(5, 2048, 16);
  std::vector<hal::SensorSnapshot> script(2000);
  for (uint32_t i = 0; i < script.size(); ++i) {
    hal::SensorSnapshot& s = script[i];
    s.sequence = i;
    s.timestamp_us = i * 10000u;
    s.flags = hal::SensorSnapshot::kHasEncoders;
    s.encoder_left = 0xFFFFF000u + 23u * i;  // wraps after ~180 snapshots
    s.encoder_right = 0xFFFFF000u + 23u * i;
  }
  script[700].encoder_left += 100000;  // a corrupted reading: skipped as a glitch
  hal::SensorFaults faults;
  faults.drop_every = 50;
  faults.damaged_index = 1234;
  faults.not_ready_before = 10;
  hal::FakeSpinalCord bus(Span<const hal::SensorSnapshot>(script.data(), script.size()), faults);
  LiveScene scene{world.get(), &bus};
  std::vector<uint8_t> frame(512);
  hal::FakePixelBuffer camera(render_live, &scene, Span<uint8_t>(frame.data(), frame.size()), 13);

  auto disk = std::make_unique<Disk>();
  disk->format();
  storage::RunConfig config =
      test::synthetic_run_config(storage::kModeTeach | storage::kModeRecord);
  storage::Region c = disk->file("config");
  ASSERT_EQ(storage::write_run_config(c, config), Status::kOk);
  auto application = std::make_unique<app::Application>();
  g_console.clear();
  ASSERT_EQ(application->start(disk->volume, &bus, &camera, capture_console), Status::kOk)
      << g_console;
  Status s = application->run();
  EXPECT_EQ(s, Status::kUnavailable);  // the bus had nothing yet: call again
  s = application->run();
  ASSERT_EQ(s, Status::kOk) << g_console;
  const app::Stats& st = application->stats();
  // The dropped ones and the damaged one show up as gaps - except the very last snapshot of
  // the script (index 1999), whose loss no later snapshot can reveal.
  EXPECT_EQ(bus.dropped(), 40u);
  EXPECT_EQ(st.missed_snapshots, bus.dropped() - 1u + 1u);
  EXPECT_EQ(st.damaged_snapshots, 1u);
  EXPECT_EQ(application->session().stats().odometry_glitches, 1u);
  EXPECT_EQ(application->session().stats().odometry_resyncs, 0u);
  // 2000 snapshots x 23 ticks x 0.532 / 4096 m = 5.97 m: about 29 captures, 1 in 13 refused.
  EXPECT_GE(st.captures + st.no_frame, 28u);
  EXPECT_GE(st.no_frame, 2u);
  EXPECT_EQ(st.taught, st.captures);
  EXPECT_EQ(st.recorded_places, st.captures);
}

}  // namespace
}  // namespace seqslam
