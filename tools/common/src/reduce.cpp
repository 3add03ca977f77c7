#include "seqslam_tools/reduce.h"

#include <stdint.h>

#include <string>
#include <utility>
#include <vector>

#include "seqslam/limits.h"
#include "seqslam/pixel_pipeline.h"
#include "seqslam/span.h"
#include "seqslam/status.h"

namespace seqslam::tools {
namespace {

std::string dims(int64_t w, int64_t h) {
  return std::to_string(w) + "x" + std::to_string(h);
}

Error failure(const std::string& what, seqslam::Status status, const std::string& sentence) {
  return Error{what + ": " + seqslam::status_name(status) + ": " + sentence};
}

std::string too_many_pixels(int64_t w, int64_t h) {
  return "the target has " + std::to_string(w * h) + " pixels, more than the core's capacity " +
         "kMaxPixels = " + std::to_string(seqslam::kMaxPixels) +
         " (the CMake cache variable SEQSLAM_MAX_PIXELS)";
}

Outcome<seqslam::ImageSize> check_target(const std::string& what, int width, int height) {
  if (width <= 0 || height <= 0) {
    return failure(what, seqslam::Status::kInvalidArgument,
                   "the target width and height must be positive");
  }
  // A side beyond 16 bits cannot be an ImageSize; it is certainly beyond kMaxPixels too.
  if (width > 65535 || height > 65535) {
    return failure(what, seqslam::Status::kOutOfRange, too_many_pixels(width, height));
  }
  seqslam::ImageSize size;
  size.width = static_cast<uint16_t>(width);
  size.height = static_cast<uint16_t>(height);
  const seqslam::Status status = seqslam::check_image_size(size);
  if (status == seqslam::Status::kOutOfRange) {
    return failure(what, status, too_many_pixels(width, height));
  }
  if (status != seqslam::Status::kOk) {
    return failure(what, status, "the core rejects the target size");
  }
  return size;
}

}  // namespace

Outcome<seqslam::ImageSize> check_reduce_target(int width, int height) {
  return check_target("cannot reduce to " + dims(width, height), width, height);
}

ReducedImage reduce_to(const GrayImage& src, int width, int height) {
  const std::string what =
      "cannot reduce " + dims(src.width, src.height) + " to " + dims(width, height);
  if (!src.valid()) {
    return failure(what, seqslam::Status::kInvalidArgument,
                   "the source image is empty or inconsistent (" +
                       std::to_string(src.pixels.size()) + " pixel bytes)");
  }
  Outcome<seqslam::ImageSize> target = check_target(what, width, height);
  if (!target) return Error{target.error()};

  GrayImage out;
  out.width = width;
  out.height = height;
  const uint32_t n = target.value().pixels();
  out.pixels.resize(n);
  std::vector<uint32_t> scratch(size_t{2} * n);
  seqslam::MutableImageView dst;
  dst.pixels = out.pixels.data();
  dst.size = target.value();
  const seqslam::Status status = seqslam::area_reduce(
      src.view(), dst, seqslam::Span<uint32_t>(scratch.data(), scratch.size()));
  switch (status) {
    case seqslam::Status::kOk:
      return Outcome<GrayImage>(std::move(out));
    case seqslam::Status::kInvalidArgument:
      if (width > src.width || height > src.height) {
        return failure(what, status,
                       "the pixel pipeline only reduces; the target is larger than the source "
                       "in at least one dimension (upscaling is not supported)");
      }
      return failure(what, status, "the core rejects the arguments");
    case seqslam::Status::kOutOfRange:
      if (static_cast<uint64_t>(src.width) * static_cast<uint64_t>(src.height) > (1u << 24)) {
        return failure(what, status,
                       "the source has more than 2^24 pixels, the pixel pipeline's limit");
      }
      return failure(what, status, too_many_pixels(width, height));
    default:
      return failure(what, status, "unexpected failure of seqslam::area_reduce");
  }
}

}  // namespace seqslam::tools
