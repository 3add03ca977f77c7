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
  SEQSLAM_TRY(check_image_size(size));
  size_t capacity = images.capacity();
  if (!buffers.info.empty() && buffers.info.size() < capacity) capacity = buffers.info.size();
  if (!buffers.sums.empty() && buffers.sums.size() < capacity) capacity = buffers.sums.size();
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
  SEQSLAM_TRY(images_->append(size_, image.pixels, info, sum));
  return adopt(info, sum);
}

Status PlaceLibrary::adopt(const PlaceInfo& info, uint32_t sum) {
  if (images_ == nullptr) return Status::kFailedPrecondition;
  if (size_ == capacity_) return Status::kResourceExhausted;
  if (!buffers_.info.empty()) buffers_.info[size_] = info;
  if (!buffers_.sums.empty()) buffers_.sums[size_] = sum;
  ++size_;
  return Status::kOk;
}

Status PlaceLibrary::info(uint32_t i, PlaceInfo* out) const {
  if (out == nullptr) return Status::kInvalidArgument;
  if (i >= size_) return Status::kOutOfRange;
  if (buffers_.info.empty()) return Status::kFailedPrecondition;
  *out = buffers_.info[i];
  return Status::kOk;
}

Status PlaceLibrary::image(uint32_t i, ImageView* out) {
  if (out == nullptr) return Status::kInvalidArgument;
  if (i >= size_) return Status::kOutOfRange;
  const uint8_t* pixels = nullptr;
  uint32_t available = 0;
  SEQSLAM_TRY(images_->view(i, 1, &pixels, &available));
  *out = ImageView{pixels, image_size_};
  return Status::kOk;
}

Status PlaceLibrary::view(uint32_t first, uint32_t count, const uint8_t** pixels,
                          uint32_t* available) {
  if (images_ == nullptr) return Status::kFailedPrecondition;
  if (pixels == nullptr || available == nullptr || count == 0) return Status::kInvalidArgument;
  if (first >= size_ || count > size_ - first) return Status::kOutOfRange;
  return images_->view(first, count, pixels, available);
}

Status PlaceLibrary::differences(ImageView query, uint32_t first, uint32_t count, uint32_t* out) {
  const uint32_t pixels = image_size_.pixels();
  const uint32_t end = first + count;
  uint32_t next = first;
  while (next < end) {
    const uint8_t* images = nullptr;
    uint32_t available = 0;
    SEQSLAM_TRY(images_->view(next, end - next, &images, &available));
    uint32_t* dst = out + (next - first);
    if (!buffers_.sums.empty()) {
      sad_many(query.pixels, images, buffers_.sums.data() + next, available, pixels, dst);
    } else {
      // No sums in RAM: each image's sum as it streams past, a few images at a time.
      constexpr uint32_t kBatch = 8;
      uint32_t sums[kBatch];
      for (uint32_t k = 0; k < available; k += kBatch) {
        const uint32_t n = available - k < kBatch ? available - k : kBatch;
        const uint8_t* batch = images + static_cast<size_t>(k) * pixels;
        for (uint32_t b = 0; b < n; ++b)
          sums[b] = seqslam::pixel_sum(batch + static_cast<size_t>(b) * pixels, pixels);
        sad_many(query.pixels, batch, sums, n, pixels, dst + k);
      }
    }
    next += available;
  }
  return Status::kOk;
}

}  // namespace seqslam
