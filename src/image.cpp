#include "seqslam/image.h"

namespace seqslam {

Status check_image_size(ImageSize size) {
  if (size.width == 0 || size.height == 0) return Status::kInvalidArgument;
  if (size.pixels() > kMaxPixels) return Status::kOutOfRange;
  return Status::kOk;
}

}  // namespace seqslam
