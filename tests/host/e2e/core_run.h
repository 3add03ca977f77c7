// The core run directly on a list of images - what the firmware's results must equal - and
// the place images of a recording. Shared by the end-to-end tests and e2e_disk.
#pragma once

#include <memory>
#include <vector>

#include "seqslam/localiser.h"
#include "seqslam/storage/dream.h"

namespace seqslam::test {

using Image = std::vector<uint8_t>;

// A Localiser with a RAM library of up to kPlaces places: 32x16 images and default settings,
// or the given configuration (e.g. a run configuration's localiser(), any matcher).
template <uint32_t kPlaces>
class CoreRun {
 public:
  CoreRun() : CoreRun(default_config()) {}
  explicit CoreRun(const LocaliserConfig& config) : config_(config) {
    ok_ = storage_->attach(library_, config_.image_size) == Status::kOk &&
          localiser_
              .configure(config_, library_, matcher_->buffers(),
                         Span<uint32_t>(differences_.data(), kPlaces), *heuristic_)
              .ok();
  }
  bool ok() const { return ok_; }
  bool teach(const std::vector<Image>& images) {
    for (const Image& img : images) {
      if (localiser_.teach(ImageView{img.data(), config_.image_size}, Pose2{}, 0) != Status::kOk) {
        return false;
      }
    }
    return true;
  }
  bool localise(const Image& img, Match* out) {
    return localiser_.localise(ImageView{img.data(), config_.image_size}, out) == Status::kOk;
  }

 private:
  static LocaliserConfig default_config() {
    LocaliserConfig c;
    c.image_size = ImageSize{32, 16};
    return c;
  }

  LocaliserConfig config_{};
  std::unique_ptr<PlaceLibraryStorage<kPlaces, 512>> storage_ =
      std::make_unique<PlaceLibraryStorage<kPlaces, 512>>();
  std::unique_ptr<DiagonalMatcherStorage<kPlaces, 30>> matcher_ =
      std::make_unique<DiagonalMatcherStorage<kPlaces, 30>>();
  std::unique_ptr<HeuristicMatcher> heuristic_ = std::make_unique<HeuristicMatcher>();
  std::vector<uint32_t> differences_ = std::vector<uint32_t>(kPlaces);
  PlaceLibrary library_;
  Localiser localiser_;
  bool ok_ = false;
};

// The grey images of every place of a recording, in order (empty if it does not open).
inline std::vector<Image> place_images(hal::BlockDevice& device) {
  std::vector<uint8_t> buffer(storage::kDreamRecordMax);
  storage::DreamReader r;
  std::vector<Image> images;
  if (r.open(device, Span<uint8_t>(buffer.data(), buffer.size())) != Status::kOk) return images;
  storage::DreamItem item;
  while (r.next(&item) == Status::kOk) {
    if (item.type == storage::DreamRecord::kPlace ||
        item.type == storage::DreamRecord::kReducedPlace) {
      images.emplace_back(item.place.gray, item.place.gray + item.place.size.pixels());
    }
  }
  return images;
}

}  // namespace seqslam::test
