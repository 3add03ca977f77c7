// The library of places: preprocessed images with their odometry poses, in caller-owned
// memory. Images are stored back to back (place j at pixels + j * A) so the difference kernel
// streams through them; on the robot this block may sit in external memory.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/image.h"
#include "seqslam/odometry.h"
#include "seqslam/span.h"
#include "seqslam/status.h"

namespace seqslam {

struct PlaceInfo {
  Pose2 pose;            // odometry pose at capture
  uint32_t capture = 0;  // capture index in the run that produced the place
};

struct PlaceLibraryBuffers {
  Span<uint8_t> pixels;  // images back to back
  Span<PlaceInfo> info;  // one per place
  Span<uint32_t> sums;   // pixel sum of each image (the difference kernel needs them)
};

// Static storage for kPlaces places of up to kPixels pixels each. Deliberately without
// initialisers: instances are meant to be static (zeroed with .bss) or in external memory.
template <uint32_t kPlaces, uint32_t kPixels = kMaxPixels>
struct PlaceLibraryStorage {  // NOLINT(cppcoreguidelines-pro-type-member-init)
  static_assert(kPlaces > 0 && kPixels > 0 && kPixels <= kMaxPixels, "bad library capacity");
  static constexpr size_t kBytes =
      sizeof(uint8_t) * kPlaces * kPixels + (sizeof(PlaceInfo) + sizeof(uint32_t)) * kPlaces;
  uint8_t pixels[kPlaces * kPixels];
  PlaceInfo info[kPlaces];
  uint32_t sums[kPlaces];

  PlaceLibraryBuffers buffers() {
    return {Span<uint8_t>(pixels, kPlaces * kPixels), Span<PlaceInfo>(info, kPlaces),
            Span<uint32_t>(sums, kPlaces)};
  }
};

class PlaceLibrary {
 public:
  // Adopts the storage for images of `size` and empties the library. Capacity is
  // min(pixels.size() / A, info.size(), sums.size()). Returns check_image_size's statuses,
  // or kResourceExhausted if the storage cannot hold a single place.
  Status configure(ImageSize size, const PlaceLibraryBuffers& buffers);

  // Appends a place (the image must already be preprocessed). Returns kFailedPrecondition
  // before configure(), kInvalidArgument for a null image or a different size,
  // kResourceExhausted when full (nothing is stored then).
  Status add(ImageView image, const Pose2& pose, uint32_t capture);

  void clear() { size_ = 0; }
  // Keeps the first `count` places (count <= size()).
  void truncate(uint32_t count) { size_ = count < size_ ? count : size_; }

  uint32_t size() const { return size_; }
  uint32_t capacity() const { return capacity_; }
  bool full() const { return size_ == capacity_; }
  ImageSize image_size() const { return image_size_; }
  // Place i < size().
  ImageView image(uint32_t i) const {
    return ImageView{buffers_.pixels.data() + static_cast<size_t>(i) * image_size_.pixels(),
                     image_size_};
  }
  const PlaceInfo& info(uint32_t i) const { return buffers_.info[i]; }
  // All images back to back (for persistence and streaming).
  const uint8_t* pixels() const { return buffers_.pixels.data(); }

  // out[j] = SAD(query, place j) for j < count, via sad_many. The caller guarantees
  // count <= size() and a query of image_size().
  void differences(ImageView query, uint32_t count, uint32_t* out) const;

 private:
  PlaceLibraryBuffers buffers_{};
  ImageSize image_size_{};
  uint32_t capacity_ = 0;
  uint32_t size_ = 0;
};

}  // namespace seqslam
