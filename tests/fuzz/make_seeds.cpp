// Writes seed inputs for the fuzzers: a valid full and reduced dream recording, the same with
// ground-truth poses, a valid stored library (metadata + images in the split format of
// fuzz_library_loader), and a valid run configuration with the heuristic matcher (read by
// fuzz_library_loader from the same bytes as the library metadata).
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "seqslam/hal/fake_block_device.h"
#include "seqslam/storage/dream.h"
#include "seqslam/storage/library_store.h"
#include "seqslam/storage/run_files.h"

namespace {

using namespace seqslam;

std::vector<uint8_t> used(const std::vector<uint8_t>& card, uint64_t end) {
  return std::vector<uint8_t>(card.begin(), card.begin() + static_cast<long>(end));
}

void save(const std::string& path, const std::vector<uint8_t>& bytes) {
  std::ofstream(path, std::ios::binary)
      .write(reinterpret_cast<const char*>(bytes.data()),
             static_cast<std::streamsize>(bytes.size()));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3) {
    std::fprintf(stderr, "usage: make_seeds DREAM_DIR LIBRARY_DIR\n");
    return 2;
  }
  std::filesystem::create_directories(argv[1]);
  std::filesystem::create_directories(argv[2]);
  std::vector<uint8_t> gray(512);
  for (int seed = 0; seed < 4; ++seed) {
    const int variant = 1 + seed % 2;
    const bool truths = seed >= 2;
    std::vector<uint8_t> card(64 * hal::kBlockSize, 0);
    hal::FakeBlockDevice device(Span<uint8_t>(card.data(), card.size()));
    storage::DreamHeader h;
    h.variant = static_cast<storage::DreamVariant>(variant);
    h.mapping = hal::PipelineMapping::reduction(32, 16);
    h.infrared_count = 2;
    storage::DreamWriter w;
    if (w.create(device, h) != Status::kOk) return 1;
    for (uint32_t p = 0; p < 5; ++p) {
      hal::SensorSnapshot s;
      s.sequence = p * 3;
      s.infrared_count = 2;
      if (variant == 1 && w.snapshot(s) != Status::kOk) return 1;
      for (uint32_t k = 0; k < 512; ++k)
        gray[k] = static_cast<uint8_t>(p + k);
      storage::DreamPlace place;
      place.index = p;
      place.bus_sequence = s.sequence;
      place.size = ImageSize{32, 16};
      place.gray = gray.data();
      place.infrared_count = 2;
      if (w.place(place) != Status::kOk) return 1;
      storage::DreamTruth truth;
      truth.place_index = p;
      truth.pose = Pose2{Q31_32::from_ratio(p, 5), Q31_32::from_ratio(-static_cast<int64_t>(p), 7),
                         Angle{0xF0000000u + p * 0x08000000u}};
      if (truths && p != 2 && w.truth(truth) != Status::kOk) return 1;
    }
    save(std::string(argv[1]) + "/dream_" + std::to_string(variant) + (truths ? "_truth" : ""),
         used(card, w.log().end_offset()));
  }
  std::vector<uint8_t> meta(16 * hal::kBlockSize, 0), images(16 * hal::kBlockSize, 0);
  hal::FakeBlockDevice md(Span<uint8_t>(meta.data(), meta.size()));
  hal::FakeBlockDevice id(Span<uint8_t>(images.data(), images.size()));
  storage::StoredPlaceImages store;
  std::vector<uint8_t> cache(2048);
  storage::LibraryConfig config;
  config.mapping = hal::PipelineMapping::reduction(32, 16);
  if (store.create(md, id, config, Span<uint8_t>(cache.data(), cache.size())) != Status::kOk)
    return 1;
  PlaceLibrary library;
  static PlaceInfo info[8];
  static uint32_t sums[8];
  if (library.configure(ImageSize{32, 16}, store,
                        PlaceLibraryBuffers{Span<PlaceInfo>(info, 8), Span<uint32_t>(sums, 8)}) !=
      Status::kOk) {
    return 1;
  }
  for (uint32_t p = 0; p < 3; ++p) {
    for (uint32_t k = 0; k < 512; ++k)
      gray[k] = static_cast<uint8_t>(3 * p + k);
    if (library.add(ImageView{gray.data(), ImageSize{32, 16}}, Pose2{}, p) != Status::kOk) return 1;
  }
  // Split format: two bytes = metadata length (as the fuzzer decodes it), then both files.
  const size_t meta_len = 2 * hal::kBlockSize;  // header + records
  const size_t images_len = hal::kBlockSize + 3 * 512;
  std::vector<uint8_t> seed = {static_cast<uint8_t>(meta_len >> 8), static_cast<uint8_t>(meta_len)};
  seed.insert(seed.end(), meta.begin(), meta.begin() + static_cast<long>(meta_len));
  seed.insert(seed.end(), images.begin(), images.begin() + static_cast<long>(images_len));
  save(std::string(argv[2]) + "/library_1", seed);

  // A run configuration (format version 2) selecting the heuristic matcher: one header block.
  std::vector<uint8_t> config_card(2 * hal::kBlockSize, 0);
  hal::FakeBlockDevice cd(Span<uint8_t>(config_card.data(), config_card.size()));
  storage::RunConfig rc;
  rc.modes = storage::kModeTeach | storage::kModeRepeat;
  rc.matcher = LocaliserMatcher::kHeuristic;
  rc.heuristic.candidates = 7;
  rc.heuristic.guard = 3;
  if (storage::write_run_config(cd, rc) != Status::kOk) return 1;
  const size_t config_len = hal::kBlockSize;
  std::vector<uint8_t> config_seed = {static_cast<uint8_t>(config_len >> 8),
                                      static_cast<uint8_t>(config_len)};
  config_seed.insert(config_seed.end(), config_card.begin(),
                     config_card.begin() + static_cast<long>(config_len));
  save(std::string(argv[2]) + "/config_2", config_seed);
  return 0;
}
