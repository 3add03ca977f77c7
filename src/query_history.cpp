#include "seqslam/query_history.h"

namespace seqslam {

Status RamQueryHistory::configure(uint32_t pixels, Span<uint8_t> images, Span<uint32_t> places) {
  if (pixels == 0 || images.data() == nullptr) return Status::kInvalidArgument;
  size_t capacity = images.size() / pixels;
  if (places.size() < capacity) capacity = places.size();
  if (capacity == 0) return Status::kResourceExhausted;
  images_ = images;
  places_ = places;
  pixels_ = pixels;
  capacity_ = capacity > 0xFFFFFFu ? 0xFFFFFFu : static_cast<uint32_t>(capacity);
  clear();
  return Status::kOk;
}

Status RamQueryHistory::do_put(uint32_t slot, const uint8_t* pixels) {
  uint8_t* dst = images_.data() + static_cast<size_t>(slot) * pixels_;
  for (uint32_t i = 0; i < pixels_; ++i)
    dst[i] = pixels[i];
  return Status::kOk;
}

Status RamQueryHistory::do_get(uint32_t slot, const uint8_t** pixels) {
  *pixels = images_.data() + static_cast<size_t>(slot) * pixels_;
  return Status::kOk;
}

}  // namespace seqslam
