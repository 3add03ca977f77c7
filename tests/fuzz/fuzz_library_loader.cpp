// libFuzzer target: arbitrary bytes as the two files of a stored place library (metadata log
// and images; the first two bytes say where the split is) and as a run configuration and a
// volume. Loading must refuse damage with a status, never crash, hang or read out of bounds.
#include <cstddef>
#include <cstdint>
#include <vector>

#include "seqslam/hal/fake_block_device.h"
#include "seqslam/storage/library_store.h"
#include "seqslam/storage/run_files.h"
#include "seqslam/storage/volume.h"

namespace {

std::vector<uint8_t> as_card(const uint8_t* data, size_t size) {
  std::vector<uint8_t> card((size / seqslam::hal::kBlockSize + 2) * seqslam::hal::kBlockSize, 0);
  for (size_t i = 0; i < size; ++i)
    card[i] = data[i];
  return card;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size) {
  using namespace seqslam;
  if (size < 2) return 0;
  const size_t split = 2 + ((static_cast<size_t>(data[0]) << 8 | data[1]) % (size - 1));
  std::vector<uint8_t> meta = as_card(data + 2, split - 2);
  std::vector<uint8_t> images = as_card(data + split, size - split);
  hal::FakeBlockDevice meta_device(Span<uint8_t>(meta.data(), meta.size()));
  hal::FakeBlockDevice image_device(Span<uint8_t>(images.data(), images.size()));

  static PlaceInfo info[64];
  static uint32_t sums[64];
  std::vector<uint8_t> cache(2048);
  storage::StoredPlaceImages store;
  PlaceLibrary library;
  storage::LibraryConfig config;
  config.mapping = hal::PipelineMapping::reduction(32, 16);
  if (store.load(meta_device, image_device, config, Span<uint8_t>(cache.data(), cache.size()),
                 PlaceLibraryBuffers{Span<PlaceInfo>(info, 64), Span<uint32_t>(sums, 64)},
                 library) == Status::kOk) {
    // A loaded library must be readable in full.
    uint32_t out[64];
    uint8_t query[512] = {};
    (void)library.differences(ImageView{query, ImageSize{32, 16}}, library.size(), out);
  }
  // The same bytes as a run configuration, a results file and a volume.
  storage::RunConfig rc;
  (void)storage::read_run_config(meta_device, &rc);
  storage::ResultsReader results;
  if (results.open(meta_device) == Status::kOk) {
    storage::RunResult r;
    for (int i = 0; i < 100000 && results.next(&r) != Status::kOutOfRange; ++i) {
    }
  }
  storage::Volume volume;
  if (volume.mount(image_device) == Status::kOk) {
    storage::Region region;
    (void)volume.open("library", &region);
  }
  return 0;
}
