// The FPGA pixel pipeline and its frame buffer ("superpixels").
//
// The head camera (346x271, YUV, gamma 0.45) streams into the FPGA, which maps every camera
// pixel (x, y) through a 2x2 matrix A and offsets (bx, by):
//   (x', y') = floor(A (x, y)),   stored at xmax * (y' + by) + (x' + bx)
// when 0 <= x' + bx < xmax and 0 <= y' + by < ymax, averaging all camera pixels that land on
// the same superpixel. The buffer holds at most 512 superpixels (xmax * ymax <= 512).
// A diagonal A of (w / 346, h / 271) is the plain area reduction to w x h (pixel_pipeline.h).
#pragma once

#include <stdint.h>

#include "seqslam/fixed.h"
#include "seqslam/image.h"
#include "seqslam/status.h"

namespace seqslam::hal {

inline constexpr uint32_t kPixelBufferCapacity = 512;
inline constexpr uint16_t kCameraWidth = 346;
inline constexpr uint16_t kCameraHeight = 271;

struct PipelineMapping {
  Q15_16 a11 = Q15_16::from_ratio(32, kCameraWidth);  // default: 346x271 -> 32x16
  Q15_16 a12 = Q15_16::from_int(0);
  Q15_16 a21 = Q15_16::from_int(0);
  Q15_16 a22 = Q15_16::from_ratio(16, kCameraHeight);
  int16_t bx = 0;
  int16_t by = 0;
  uint16_t xmax = 32;
  uint16_t ymax = 16;

  // The plain reduction of the camera frame to width x height.
  static constexpr PipelineMapping reduction(uint16_t width, uint16_t height) {
    PipelineMapping m;
    m.a11 = Q15_16::from_ratio(width, kCameraWidth);
    m.a22 = Q15_16::from_ratio(height, kCameraHeight);
    m.xmax = width;
    m.ymax = height;
    return m;
  }
  constexpr ImageSize size() const { return ImageSize{xmax, ymax}; }
  friend bool operator==(const PipelineMapping& a, const PipelineMapping& b) {
    return a.a11 == b.a11 && a.a12 == b.a12 && a.a21 == b.a21 && a.a22 == b.a22 && a.bx == b.bx &&
           a.by == b.by && a.xmax == b.xmax && a.ymax == b.ymax;
  }
  friend bool operator!=(const PipelineMapping& a, const PipelineMapping& b) { return !(a == b); }
};

// kInvalidArgument for xmax or ymax 0 or a singular matrix; kOutOfRange for
// xmax * ymax > 512 (the buffer) or a matrix entry beyond +-16.
inline Status check_mapping(const PipelineMapping& m) {
  if (m.xmax == 0 || m.ymax == 0) return Status::kInvalidArgument;
  if (static_cast<uint32_t>(m.xmax) * m.ymax > kPixelBufferCapacity) return Status::kOutOfRange;
  const Q15_16 limit = Q15_16::from_int(16);
  const Q15_16 entries[4] = {m.a11, m.a12, m.a21, m.a22};
  for (const Q15_16 a : entries) {
    if (a > limit || a < -limit) return Status::kOutOfRange;
  }
  // det(A) in Q.32: the products of Q15.16 entries below 16 fit an int64.
  const int64_t det = static_cast<int64_t>(m.a11.raw()) * m.a22.raw() -
                      static_cast<int64_t>(m.a12.raw()) * m.a21.raw();
  if (det == 0) return Status::kInvalidArgument;
  return Status::kOk;
}

struct Frame {
  uint32_t sequence = 0;      // frame counter of the pipeline
  uint32_t timestamp_us = 0;  // when the frame was latched (SpinalCord time base)
  ImageSize size;
  const uint8_t* gray = nullptr;  // xmax * ymax luminance bytes, row-major
  const uint8_t* yuv = nullptr;   // YUV 4:2:2 (2 bytes per pixel), or null where not available
};

class PixelBuffer {
 public:
  // Programs the mapping. Statuses of check_mapping(); kFailedPrecondition if this buffer
  // cannot produce the mapping (e.g. a recording made with another one).
  Status configure(const PipelineMapping& mapping) {
    const Status s = check_mapping(mapping);
    return s != Status::kOk ? s : do_configure(mapping);
  }
  // Latches the next frame. kFailedPrecondition before configure(); kUnavailable if no frame
  // can be latched now (e.g. a replay has no frame recorded at this moment).
  Status capture() { return do_capture(); }
  // The latched frame; valid until the next capture(). kUnavailable if none was latched.
  Status read(Frame* out) {
    if (out == nullptr) return Status::kInvalidArgument;
    return do_read(out);
  }

 protected:
  PixelBuffer() = default;
  ~PixelBuffer() = default;
  PixelBuffer(const PixelBuffer&) = default;
  PixelBuffer& operator=(const PixelBuffer&) = default;

 private:
  virtual Status do_configure(const PipelineMapping& mapping) = 0;
  virtual Status do_capture() = 0;
  virtual Status do_read(Frame* out) = 0;
};

}  // namespace seqslam::hal
