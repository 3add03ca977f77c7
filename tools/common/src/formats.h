// Internal: container-level checks and the PNM and PNG decoders behind load_gray.
// Messages here do not name the file; load_gray/decode_gray prefix it.
#pragma once

#include <stddef.h>
#include <stdint.h>

#include <string>

#include "seqslam_tools/image_io.h"
#include "seqslam_tools/outcome.h"

namespace seqslam::tools::detail {

struct Dims {
  int64_t width = 0;
  int64_t height = 0;
};

// False (and a message) for zero/negative sides or a side above kMaxLoadSide.
bool check_dimensions(int64_t width, int64_t height, std::string* error);

// Walk the file structure without decoding pixels; return the header dimensions (already
// checked with check_dimensions).
//  PNG:  signature, IHDR first, every chunk inside the file, IDAT present, IEND reached,
//        enough compressed bytes for the IHDR size at deflate's best ratio.
//  JPEG: SOI, marker segments inside the file, a frame header (SOF), at least one scan whose
//        entropy-coded data ends in a marker, and EOI; for Huffman frames at least one bit of
//        scan data per 8x8 block of the largest component.
//  BMP:  file and info header present, uncompressed or bitfields, and the pixel array
//        (row stride * |height| bytes from the data offset) inside the file.
Outcome<Dims> check_png_structure(const uint8_t* data, size_t size);
Outcome<Dims> check_jpeg_structure(const uint8_t* data, size_t size);
Outcome<Dims> check_bmp_structure(const uint8_t* data, size_t size);

// libjpeg's verdict on a whole JPEG (jpeg_check.cpp): "" when it decodes to the end without a
// warning, else "corrupt JPEG (libjpeg: <its message>)". libjpeg's corrupt-data warnings
// (damaged entropy-coded data, which it decodes to made-up pixels) count as errors.
std::string jpeg_problem(const uint8_t* data, size_t size);

// Decodes P2, P3, P5 and P6 (see image_io.h for the accepted syntax and scaling).
Outcome<GrayImage> decode_pnm(const uint8_t* data, size_t size);

// Decodes a PNG with libpng, verifying every chunk CRC and the zlib Adler-32 (png_decode.cpp);
// errors read "not a valid PNG: <libpng's reason>". Grey conversion as image_io.h describes.
Outcome<GrayImage> decode_png(const uint8_t* data, size_t size);

}  // namespace seqslam::tools::detail
