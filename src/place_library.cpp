#include "seqslam/place_library.h"

#include "seqslam/difference.h"

namespace seqslam {

Status PlaceLibrary::configure(ImageSize size, const PlaceLibraryBuffers& buffers) {
  const Status s = check_image_size(size);
  if (s != Status::kOk) return s;
  size_t capacity = buffers.pixels.size() / size.pixels();
  if (buffers.info.size() < capacity) capacity = buffers.info.size();
  if (buffers.sums.size() < capacity) capacity = buffers.sums.size();
  if (capacity == 0) return Status::kResourceExhausted;
  if (capacity > 0x7FFFFFFFu) capacity = 0x7FFFFFFFu;
  buffers_ = buffers;
  image_size_ = size;
  capacity_ = static_cast<uint32_t>(capacity);
  size_ = 0;
  return Status::kOk;
}

Status PlaceLibrary::add(ImageView image, const Pose2& pose, uint32_t capture) {
  if (capacity_ == 0) return Status::kFailedPrecondition;
  if (image.pixels == nullptr || image.size != image_size_) return Status::kInvalidArgument;
  if (size_ == capacity_) return Status::kResourceExhausted;
  const uint32_t a = image_size_.pixels();
  uint8_t* dst = buffers_.pixels.data() + static_cast<size_t>(size_) * a;
  for (uint32_t i = 0; i < a; ++i)
    dst[i] = image.pixels[i];
  buffers_.info[size_] = PlaceInfo{pose, capture};
  buffers_.sums[size_] = pixel_sum(dst, a);
  ++size_;
  return Status::kOk;
}

void PlaceLibrary::differences(ImageView query, uint32_t count, uint32_t* out) const {
  sad_many(query.pixels, buffers_.pixels.data(), buffers_.sums.data(), count, image_size_.pixels(),
           out);
}

}  // namespace seqslam
