// Loading and saving 8-bit grey-level images on the host.
//
// Supported inputs (detected from the file's signature, never from its extension):
//   PNG   (any bit depth, colour type and interlacing; 16-bit samples are reduced to 8 bits,
//         their high byte; 1/2/4-bit grey scaled to 0..255; palette entries to RGB),
//   JPEG  (baseline and progressive),
//   BMP   (uncompressed and bitfields; stb_image does not read RLE BMPs),
//   PGM / PPM, plain (P2, P3) and binary (P5, P6), comments allowed in the header and, for the
//         plain variants, between samples; maxval 1..65535 (two bytes per sample, big-endian,
//         when maxval > 255). Each sample is scaled to 8 bits as (v * 255 + maxval / 2) / maxval.
//         PBM (P1/P4) and PAM (P7) are rejected.
// PNG is decoded by libpng with every checksum verified: the CRC of every chunk (critical and
// ancillary) and the zlib stream's Adler-32; a mismatch, extra data after the zlib stream, a
// palette index past the palette or any other libpng error fails with "<path>: not a valid
// PNG: <libpng's reason>" (ancillary chunks are otherwise skipped unread). JPEG and BMP, which
// carry no checksums, are decoded by stb_image; PNM is parsed here because stb_image reads only
// the binary variants and only up to maxval 255 exactly. Before a decoder sees a file, its
// container structure is checked here (PNG chunks up to IEND, JPEG segments and scans up to
// EOI, BMP pixel array size) so truncated files are rejected rather than decoded with missing
// pixels, and a header claiming far more pixels than the compressed data could possibly hold
// (less than one bit per JPEG block, better than deflate's ~1032:1 for PNG) is rejected before
// the decoder allocates a full-size image.
//
// Colour is converted to luma with integer BT.601 weights,
//   Y = (77 R + 150 G + 29 B + 128) >> 8,
// applied to 8-bit samples; alpha is ignored (not composited).
#pragma once

#include <stdint.h>

#include <string>
#include <vector>

#include "seqslam/image.h"
#include "seqslam_tools/outcome.h"

namespace seqslam::tools {

// Largest accepted width or height of a loaded image. Anything larger is treated as a corrupt
// or hostile header (no camera this project meets comes close).
inline constexpr int kMaxLoadSide = 16384;
// Largest file load_gray reads (1 GiB).
inline constexpr uint64_t kMaxImageFileBytes = uint64_t{1} << 30;

// An owned 8-bit grey image, row-major, stride == width (the core's layout).
struct GrayImage {
  int width = 0;
  int height = 0;
  std::vector<uint8_t> pixels;  // row-major, width * height bytes

  // True when 1 <= width, height <= 65535 and pixels.size() == width * height.
  bool valid() const;
  // A view for the core. An invalid image gives an empty view (null pixels, size 0x0), which
  // every core function rejects with kInvalidArgument. The view borrows `pixels`.
  seqslam::ImageView view() const;
  // Pixel (x, y); the caller guarantees 0 <= x < width, 0 <= y < height.
  uint8_t at(int x, int y) const;
};

using LoadedImage = Outcome<GrayImage>;

// Reads and decodes the image file at `path` into grey levels.
// Errors (message starts with the path): missing, unreadable or non-regular file, empty file,
// unrecognised format, truncated or corrupt data, zero dimensions or a side > kMaxLoadSide.
LoadedImage load_gray(const std::string& path);

// Decodes an in-memory image file. `name` is used to start error messages (e.g. the path).
LoadedImage decode_gray(const std::vector<uint8_t>& bytes, const std::string& name);

// Writes `image` as binary PGM (P5, maxval 255). Returns false and sets *error (if non-null)
// to a message naming the file when the image is invalid or the file cannot be written.
bool save_pgm(const std::string& path, const GrayImage& image, std::string* error);

// Writes `image` as an 8-bit grey PNG (stb_image_write). Errors as save_pgm.
bool save_png(const std::string& path, const GrayImage& image, std::string* error);

// BT.601 integer luma of one 8-bit RGB pixel: (77 r + 150 g + 29 b + 128) >> 8.
constexpr uint8_t luma(uint8_t r, uint8_t g, uint8_t b) {
  return static_cast<uint8_t>((77u * r + 150u * g + 29u * b + 128u) >> 8);
}

}  // namespace seqslam::tools
