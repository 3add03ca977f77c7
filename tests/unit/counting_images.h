// A place-image store for tests: images in RAM, every read counted, and one chosen read made
// to fail like a card (the status is the test's choice). Shared by the localiser's and the
// closure alignment's tests.
#pragma once

#include <stdint.h>

#include "seqslam/place_library.h"

namespace seqslam::test {

class CountingImages final : public PlaceImages {
 public:
  RamPlaceImages ram;
  uint32_t views = 0;
  uint32_t fail_at = 0xFFFFFFFFu;  // the read (value of `views` before it) that fails
  Status failure = Status::kUnavailable;

 private:
  uint32_t do_capacity() const override { return ram.capacity(); }
  Status do_append(uint32_t index, const uint8_t* pixels, const PlaceInfo& info,
                   uint32_t pixel_sum) override {
    return ram.append(index, pixels, info, pixel_sum);
  }
  Status do_view(uint32_t first, uint32_t count, const uint8_t** pixels,
                 uint32_t* available) override {
    if (views++ == fail_at) return failure;
    return ram.view(first, count, pixels, available);
  }
};

}  // namespace seqslam::test
