#include "seqslam/place_library.h"

#include "seqslam/difference.h"

namespace seqslam {

Status RamPlaceImages::configure(uint32_t pixels_per_image, Span<uint8_t> storage) {
  if (pixels_per_image == 0 || storage.data() == nullptr) return Status::kInvalidArgument;
  const size_t capacity = storage.size() / pixels_per_image;
  if (capacity == 0) return Status::kResourceExhausted;
  storage_ = storage;
  pixels_ = pixels_per_image;
  capacity_ = capacity > 0x7FFFFFFFu ? 0x7FFFFFFFu : static_cast<uint32_t>(capacity);
  return Status::kOk;
}

Status RamPlaceImages::do_append(uint32_t index, const uint8_t* pixels, const PlaceInfo& /*info*/,
                                 uint32_t /*pixel_sum*/) {
  uint8_t* dst = storage_.data() + static_cast<size_t>(index) * pixels_;
  for (uint32_t i = 0; i < pixels_; ++i)
    dst[i] = pixels[i];
  return Status::kOk;
}

Status RamPlaceImages::do_view(uint32_t first, uint32_t count, const uint8_t** pixels,
                               uint32_t* available) {
  *pixels = storage_.data() + static_cast<size_t>(first) * pixels_;
  *available = count;
  return Status::kOk;
}

Status PlaceLibrary::configure(ImageSize size, PlaceImages& images,
                               const PlaceLibraryBuffers& buffers) {
  const Status s = check_image_size(size);
  if (s != Status::kOk) return s;
  size_t capacity = images.capacity();
  if (buffers.info.size() < capacity) capacity = buffers.info.size();
  if (buffers.sums.size() < capacity) capacity = buffers.sums.size();
  if (capacity == 0) return Status::kResourceExhausted;
  images_ = &images;
  buffers_ = buffers;
  image_size_ = size;
  capacity_ = static_cast<uint32_t>(capacity);
  size_ = 0;
  return Status::kOk;
}

Status PlaceLibrary::add(ImageView image, const Pose2& pose, uint32_t capture) {
  if (images_ == nullptr) return Status::kFailedPrecondition;
  if (image.pixels == nullptr || image.size != image_size_) return Status::kInvalidArgument;
  if (size_ == capacity_) return Status::kResourceExhausted;
  const PlaceInfo info = PlaceInfo::from(pose, capture);
  const uint32_t sum = seqslam::pixel_sum(image.pixels, image_size_.pixels());
  const Status s = images_->append(size_, image.pixels, info, sum);
  if (s != Status::kOk) return s;
  return adopt(info, sum);
}

Status PlaceLibrary::adopt(const PlaceInfo& info, uint32_t sum) {
  if (images_ == nullptr) return Status::kFailedPrecondition;
  if (size_ == capacity_) return Status::kResourceExhausted;
  buffers_.info[size_] = info;
  buffers_.sums[size_] = sum;
  ++size_;
  return Status::kOk;
}

Status PlaceLibrary::image(uint32_t i, ImageView* out) {
  if (out == nullptr) return Status::kInvalidArgument;
  if (i >= size_) return Status::kOutOfRange;
  const uint8_t* pixels = nullptr;
  uint32_t available = 0;
  const Status s = images_->view(i, 1, &pixels, &available);
  if (s != Status::kOk) return s;
  *out = ImageView{pixels, image_size_};
  return Status::kOk;
}

Status PlaceLibrary::differences(ImageView query, uint32_t count, uint32_t* out) {
  uint32_t first = 0;
  while (first < count) {
    const uint8_t* pixels = nullptr;
    uint32_t available = 0;
    const Status s = images_->view(first, count - first, &pixels, &available);
    if (s != Status::kOk) return s;
    sad_many(query.pixels, pixels, buffers_.sums.data() + first, available, image_size_.pixels(),
             out + first);
    first += available;
  }
  return Status::kOk;
}

}  // namespace seqslam
