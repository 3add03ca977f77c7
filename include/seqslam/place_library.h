// The library of places: preprocessed images with their odometry poses.
//
// The images - the bulk, M x A bytes - live behind the PlaceImages interface: in RAM
// (RamPlaceImages, below), or on the SD card with a bounded cache (storage/, for libraries
// larger than the head board's memory). The difference kernel streams through them in
// contiguous chunks, so both work the same.
//
// Per-place metadata in RAM is optional (PlaceLibraryBuffers): the pose and capture index
// (16 bytes a place) and the pixel sum (4 bytes) the difference kernel needs. A library
// without them keeps no per-place RAM at all - what the head board does for a whole route
// (docs/firmware.md): the sums are then computed from the images as they stream through
// (one add per library pixel) and the poses stay on the card.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include "seqslam/image.h"
#include "seqslam/odometry.h"
#include "seqslam/span.h"
#include "seqslam/status.h"

namespace seqslam {

// What the library keeps in RAM per place besides the pixel sum: 16 bytes. The odometry pose
// at capture in Q15.16 metres (resolution 15 um, range +-32 km: places are 20 cm apart; RAM is
// what limits the library on the head board) and the capture index.
struct PlaceInfo {
  Q15_16 x;
  Q15_16 y;
  Angle heading;
  uint32_t capture = 0;  // capture index in the run that produced the place

  static PlaceInfo from(const Pose2& pose, uint32_t capture) {
    return PlaceInfo{narrow_sat<Q15_16>(pose.x), narrow_sat<Q15_16>(pose.y), pose.heading, capture};
  }
  Pose2 pose() const { return Pose2{narrow_sat<Q31_32>(x), narrow_sat<Q31_32>(y), heading}; }
};

// Where the library's images live. Images are numbered 0, 1, ... in the order they were
// appended; all have the library's image size.
class PlaceImages {
 public:
  // Room for how many images (of the configured size).
  uint32_t capacity() const { return do_capacity(); }

  // Stores image number `index`, which is the number of images stored so far (append only),
  // with the place's metadata (a persistent store records it; RAM ignores it).
  // kResourceExhausted when full; kDataLoss / kUnavailable from a storage device.
  Status append(uint32_t index, const uint8_t* pixels, const PlaceInfo& info, uint32_t pixel_sum) {
    if (pixels == nullptr) return Status::kInvalidArgument;
    if (index >= do_capacity()) return Status::kResourceExhausted;
    return do_append(index, pixels, info, pixel_sum);
  }

  // Makes images [first, first + count) readable back to back: on kOk, *pixels points at
  // image `first` and *available (1..count) images follow it contiguously. The view stays
  // valid until the next call. kInvalidArgument for count 0 or null outputs, kOutOfRange
  // beyond capacity(); kDataLoss / kUnavailable from a storage device.
  Status view(uint32_t first, uint32_t count, const uint8_t** pixels, uint32_t* available) {
    if (pixels == nullptr || available == nullptr || count == 0) return Status::kInvalidArgument;
    const uint32_t cap = do_capacity();
    if (first >= cap || count > cap - first) return Status::kOutOfRange;
    return do_view(first, count, pixels, available);
  }

 protected:
  PlaceImages() = default;
  ~PlaceImages() = default;
  PlaceImages(const PlaceImages&) = default;
  PlaceImages& operator=(const PlaceImages&) = default;

 private:
  virtual uint32_t do_capacity() const = 0;
  virtual Status do_append(uint32_t index, const uint8_t* pixels, const PlaceInfo& info,
                           uint32_t pixel_sum) = 0;
  virtual Status do_view(uint32_t first, uint32_t count, const uint8_t** pixels,
                         uint32_t* available) = 0;
};

// Images in a caller-owned RAM (or external-memory) block, back to back.
class RamPlaceImages final : public PlaceImages {
 public:
  // Uses `storage` for images of `pixels_per_image` pixels. kInvalidArgument for 0 pixels;
  // kResourceExhausted if not even one image fits.
  Status configure(uint32_t pixels_per_image, Span<uint8_t> storage);

 private:
  uint32_t do_capacity() const override { return capacity_; }
  Status do_append(uint32_t index, const uint8_t* pixels, const PlaceInfo& info,
                   uint32_t pixel_sum) override;
  Status do_view(uint32_t first, uint32_t count, const uint8_t** pixels,
                 uint32_t* available) override;

  Span<uint8_t> storage_{};
  uint32_t pixels_ = 0;
  uint32_t capacity_ = 0;
};

// Either span may be empty: then that metadata is not kept in RAM (see the header comment).
struct PlaceLibraryBuffers {
  Span<PlaceInfo> info;  // one per place, or empty
  Span<uint32_t> sums;   // pixel sum of each image, or empty (computed while streaming)
};

class PlaceLibrary {
 public:
  // Adopts the image store and metadata buffers for images of `size` and empties the
  // library. Capacity is the smallest of the image store's and the non-empty buffers'.
  // Returns check_image_size's statuses, or kResourceExhausted if not a single place fits.
  Status configure(ImageSize size, PlaceImages& images, const PlaceLibraryBuffers& buffers);

  // Appends a place (the image must already be preprocessed). kFailedPrecondition before
  // configure(), kInvalidArgument for a null image or a different size, kResourceExhausted
  // when full (nothing is stored then); storage errors pass through.
  Status add(ImageView image, const Pose2& pose, uint32_t capture);

  // Registers a place whose image is already in the image store at index size() (loading a
  // stored library). Same statuses as add(), without touching the image store.
  Status adopt(const PlaceInfo& info, uint32_t pixel_sum);

  void clear() { size_ = 0; }
  uint32_t size() const { return size_; }
  uint32_t capacity() const { return capacity_; }
  bool full() const { return size_ == capacity_; }
  ImageSize image_size() const { return image_size_; }
  // Whether poses are kept in RAM (PlaceLibraryBuffers::info given).
  bool keeps_info() const { return !buffers_.info.empty(); }
  // The pose and capture index of place i: kOutOfRange for i >= size(), kFailedPrecondition
  // when the library keeps no poses in RAM.
  Status info(uint32_t i, PlaceInfo* out) const;

  // Image of place i < size(), valid until the next access to the image store.
  Status image(uint32_t i, ImageView* out);

  // Images of places [first, first + count) back to back, as PlaceImages::view: *available
  // (1..count) of them from *pixels, valid until the next access to the image store.
  // kOutOfRange unless first + count <= size(); kInvalidArgument for count 0 or null outputs;
  // kFailedPrecondition before configure(); storage errors pass through.
  Status view(uint32_t first, uint32_t count, const uint8_t** pixels, uint32_t* available);

  // out[k] = SAD(query, place first + k) for k < count, streaming the images through
  // sad_many in the chunks the image store provides. The caller guarantees
  // first + count <= size() and a query of image_size(). Storage errors pass through (out
  // is then incomplete).
  Status differences(ImageView query, uint32_t first, uint32_t count, uint32_t* out);
  // The same for places [0, count).
  Status differences(ImageView query, uint32_t count, uint32_t* out) {
    return differences(query, 0, count, out);
  }

 private:
  PlaceImages* images_ = nullptr;
  PlaceLibraryBuffers buffers_{};
  ImageSize image_size_{};
  uint32_t capacity_ = 0;
  uint32_t size_ = 0;
};

// Static RAM storage for kPlaces places of up to kPixels pixels each. Deliberately without
// initialisers: instances are meant to be static (zeroed with .bss) or in external memory.
//   static PlaceLibraryStorage<450, 512> storage;
//   storage.attach(library, ImageSize{32, 16});
template <uint32_t kPlaces, uint32_t kPixels = kMaxPixels>
struct PlaceLibraryStorage {  // NOLINT(cppcoreguidelines-pro-type-member-init)
  static_assert(kPlaces > 0 && kPixels > 0 && kPixels <= kMaxPixels, "bad library capacity");
  static constexpr size_t kBytes = sizeof(uint8_t) * kPlaces * kPixels +
                                   (sizeof(PlaceInfo) + sizeof(uint32_t)) * kPlaces +
                                   sizeof(RamPlaceImages);
  uint8_t pixels[kPlaces * kPixels];
  PlaceInfo info[kPlaces];
  uint32_t sums[kPlaces];
  RamPlaceImages images;

  PlaceLibraryBuffers buffers() {
    return {Span<PlaceInfo>(info, kPlaces), Span<uint32_t>(sums, kPlaces)};
  }
  // Configures the RAM image store for `size` and the library on top of it.
  Status attach(PlaceLibrary& library, ImageSize size) {
    const Status s = images.configure(size.pixels(), Span<uint8_t>(pixels, kPlaces * kPixels));
    return s != Status::kOk ? s : library.configure(size, images, buffers());
  }
};

}  // namespace seqslam
