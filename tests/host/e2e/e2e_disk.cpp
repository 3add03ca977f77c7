// Prepares and checks the disk image of the end-to-end run on the emulated board.
//
//   e2e_disk prepare IMAGE   - formats a volume, teaches a library from a synthetic run A with
//                              the host build of the application, then puts run B (another
//                              light, noise, a lossy bus) in `replay` and a repeat + record
//                              configuration in `config`: ready for the board.
//   e2e_disk check IMAGE     - reads the results and the recording the application wrote and
//                              checks them against the core run directly on the same images
//                              (run A rendered again, B's images from the replay) with the
//                              localiser settings of the image's run configuration (whichever
//                              matcher it names): the library on the card equal to the core's,
//                              every result equal, the recording equal to the replay.
// Exit 0 on success, 1 with a message otherwise.
#include <algorithm>
#include <cstdio>
#include <cstring>
#include <memory>
#include <string>
#include <vector>

#include "app.h"
#include "core_run.h"
#include "seqslam/hal/fake_block_device.h"
#include "seqslam/hal/file_block_device.h"
#include "synthetic_run.h"

namespace {

using namespace seqslam;

constexpr uint32_t kPlaces = 70;

int fail(const std::string& what) {
  std::fprintf(stderr, "e2e_disk: %s\n", what.c_str());
  return 1;
}

void quiet(const char*) {}

bool open_file(storage::Volume& v, const char* name, storage::Region* r) {
  return v.open(name, r) == Status::kOk;
}

std::unique_ptr<test::RunWorld> make_world() {
  auto world = std::make_unique<test::RunWorld>();
  world->generate(4242, 2048, 16);
  return world;
}

test::RunOptions run_a() {
  test::RunOptions a;
  a.places = kPlaces;
  return a;
}

// Run A's place images, rendered again as prepare recorded them.
std::vector<test::Image> run_a_images(const test::RunWorld& world) {
  std::vector<uint8_t> bytes(4096u * 512u, 0);
  hal::FakeBlockDevice device{Span<uint8_t>(bytes.data(), bytes.size())};
  if (test::write_synthetic_run(device, world, run_a()) != kPlaces) return {};
  return test::place_images(device);
}

int prepare(const std::string& path) {
  hal::FileBlockDevice disk;
  if (disk.create(path, 2 * 4096 + 2 + 64 + 256 + 64 + 512 + 1) != Status::kOk) {
    return fail(disk.error());
  }
  const storage::VolumeFile files[] = {
      {"config", 0, 2},        {"replay", 0, 4096}, {"library", 0, 64},
      {"library.img", 0, 256}, {"record", 0, 4096}, {"results", 0, 64},
      {"queries", 0, 512},
  };
  storage::Volume volume;
  if (storage::Volume::format(disk, files, 7) != Status::kOk || volume.mount(disk) != Status::kOk) {
    return fail("cannot format the volume");
  }
  const auto world = make_world();
  storage::Region replay, config;
  if (!open_file(volume, "replay", &replay) || !open_file(volume, "config", &config)) {
    return fail("volume files missing");
  }
  if (test::write_synthetic_run(replay, *world, run_a()) != kPlaces) {
    return fail("cannot write run A");
  }
  storage::RunConfig rc = test::synthetic_run_config(storage::kModeTeach);
  if (storage::write_run_config(config, rc) != Status::kOk) return fail("cannot write config");
  auto application = std::make_unique<app::Application>();
  if (application->start(volume, nullptr, nullptr, quiet) != Status::kOk ||
      application->run() != Status::kOk || application->stats().taught != kPlaces) {
    return fail("teaching run A failed");
  }
  test::RunOptions b;
  b.places = kPlaces;
  b.gain_q8 = 190;
  b.offset = 25;
  b.noise = 6;
  b.noise_seed = 2;
  b.start_count = 0x00001234u;
  b.drop_every = 97;
  if (test::write_synthetic_run(replay, *world, b) != kPlaces) return fail("cannot write run B");
  rc.modes = storage::kModeRepeat | storage::kModeRecord;
  if (storage::write_run_config(config, rc) != Status::kOk) return fail("cannot write config");
  std::printf("e2e_disk: %s ready: library of %u places (run A), replay = run B, repeat + record\n",
              path.c_str(), kPlaces);
  return 0;
}

int check(const std::string& path) {
  hal::FileBlockDevice disk;
  if (disk.open(path, false) != Status::kOk) return fail(disk.error());
  storage::Volume volume;
  if (volume.mount(disk) != Status::kOk) return fail(path + ": not a volume");
  storage::Region replay, record, results_file, library_file, images_file, config_file;
  if (!open_file(volume, "config", &config_file) || !open_file(volume, "replay", &replay) ||
      !open_file(volume, "record", &record) || !open_file(volume, "results", &results_file) ||
      !open_file(volume, "library", &library_file) ||
      !open_file(volume, "library.img", &images_file)) {
    return fail("volume files missing");
  }
  // The settings the application ran with (prepare's, or as rewritten by `seqslam config`).
  storage::RunConfig rc;
  if (storage::read_run_config(config_file, &rc) != Status::kOk) return fail("no run config");
  const LocaliserConfig config = rc.localiser();
  if (config.image_size != ImageSize{32, 16}) return fail("the run config is not for 32x16");
  // The library as stored on the card, read back with the storage code's checks.
  auto info = std::make_unique<PlaceInfo[]>(kPlaces);
  auto sums = std::make_unique<uint32_t[]>(kPlaces);
  std::vector<uint8_t> cache(4096);
  storage::StoredPlaceImages stored;
  PlaceLibrary stored_library;
  storage::LibraryConfig lc;
  lc.image_size = config.image_size;
  lc.preprocess = rc.preprocess;
  lc.mapping = rc.mapping;
  const PlaceLibraryBuffers lb{Span<PlaceInfo>(info.get(), kPlaces),
                               Span<uint32_t>(sums.get(), kPlaces)};
  if (stored.load(library_file, images_file, lc, Span<uint8_t>(cache.data(), cache.size()), lb,
                  stored_library) != Status::kOk) {
    return fail("the library on the card does not load");
  }
  // The core directly: teach run A's images, then run B's.
  const auto world = make_world();
  test::CoreRun<kPlaces> core(config);
  if (!core.ok() || !core.teach(run_a_images(*world))) return fail("core setup failed");
  if (stored_library.size() != kPlaces) return fail("the card's library is not run A");
  for (uint32_t i = 0; i < kPlaces; ++i) {
    ImageView card, taught;
    if (stored_library.image(i, &card) != Status::kOk || !core.library_image(i, &taught)) {
      return fail("cannot read a library image");
    }
    if (!std::equal(card.pixels, card.pixels + card.size.pixels(), taught.pixels)) {
      return fail("the card's library image " + std::to_string(i) + " differs from the core's");
    }
  }
  const auto queries = test::place_images(replay);
  storage::ResultsReader results;
  if (results.open(results_file) != Status::kOk) return fail("no results on the card");
  uint32_t steps = 0, localised = 0;
  for (const auto& img : queries) {
    Match m;
    if (!core.localise(img, &m)) return fail("core localise failed");
    storage::RunResult r;
    if (results.next(&r) != Status::kOk) return fail("fewer results than replayed places");
    if (r.step != m.query || r.place != m.place || r.runner_up != m.runner_up || r.cost != m.cost ||
        r.confidence.raw() != m.confidence.raw() || r.localised != m.localised) {
      return fail("result of step " + std::to_string(steps) + " differs from the core");
    }
    ++steps;
    localised += m.localised ? 1 : 0;
  }
  storage::RunResult extra;
  if (results.next(&extra) != Status::kOutOfRange) return fail("more results than places");
  if (test::place_images(record) != queries) return fail("the recording differs from the replay");
  std::printf(
      "e2e_disk: %s: %u results equal to the core, %s matcher (%u localised), recording equal "
      "to the replay (%zu places)\n",
      path.c_str(), steps,
      config.matcher == LocaliserMatcher::kHeuristic ? "heuristic" : "diagonal", localised,
      queries.size());
  return steps == kPlaces ? 0 : fail("not every place produced a result");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 3 && std::strcmp(argv[1], "prepare") == 0) return prepare(argv[2]);
  if (argc == 3 && std::strcmp(argv[1], "check") == 0) return check(argv[2]);
  std::fprintf(stderr, "usage: e2e_disk prepare|check IMAGE\n");
  return 2;
}
