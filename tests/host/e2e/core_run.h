// The core run directly on a list of images - what the firmware's results must equal - and
// the place images of a recording. Shared by the end-to-end tests and e2e_disk.
#pragma once

#include <memory>
#include <vector>

#include "app.h"
#include "seqslam/localiser.h"
#include "seqslam/storage/dream.h"

namespace seqslam::test {

using Image = std::vector<uint8_t>;

// A Localiser with a RAM library of up to kPlaces places and the given configuration (e.g. a
// run configuration's localiser(), any matcher). As the
// firmware application configures it (app.cpp, configure_localiser): the heuristic, or the
// route search with the application's capacities (its query history in RAM here, on the card
// there: the same images). `loop_closure`: teach + repeat in one run, whose route search
// starts unknown as the application's does.
template <uint32_t kPlaces>
class CoreRun {
 public:
  explicit CoreRun(const LocaliserConfig& config, bool loop_closure = false) : config_(config) {
    if (loop_closure) config_.route.start = -1;
    ok_ = storage_->attach(library_, config_.image_size) == Status::kOk &&
          history_storage_->attach(history_, config_.image_size.pixels()) == Status::kOk;
    if (!ok_) return;
    if (config_.matcher == LocaliserMatcher::kHeuristic) {
      // A budgeted scan reads its first image back from the history, as on the card.
      ok_ = localiser_
                .configure(config_, library_, *heuristic_,
                           config_.heuristic.scan_places != 0 ? &history_ : nullptr)
                .ok();
    } else {
      ok_ = localiser_.configure(config_, library_, *route_, route_storage_->buffers(), history_)
                .ok();
    }
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
  bool observe(const Image& img, uint32_t capture, Match* out) {
    return localiser_.observe(ImageView{img.data(), config_.image_size}, Pose2{}, capture, out) ==
           Status::kOk;
  }
  const Localiser& localiser() const { return localiser_; }
  // The library's image of place i, as taught (preprocessed).
  bool library_image(uint32_t i, ImageView* out) { return library_.image(i, out) == Status::kOk; }

 private:
  LocaliserConfig config_{};
  std::unique_ptr<PlaceLibraryStorage<kPlaces, 512>> storage_ =
      std::make_unique<PlaceLibraryStorage<kPlaces, 512>>();
  std::unique_ptr<HeuristicMatcher> heuristic_ = std::make_unique<HeuristicMatcher>();
  std::unique_ptr<profile::RouteStorage> route_storage_ = std::make_unique<profile::RouteStorage>();
  std::unique_ptr<RouteSearch> route_ = std::make_unique<RouteSearch>();
  std::unique_ptr<RamQueryHistoryStorage<profile::kQuerySteps, 512>> history_storage_ =
      std::make_unique<RamQueryHistoryStorage<profile::kQuerySteps, 512>>();
  RamQueryHistory history_;
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
