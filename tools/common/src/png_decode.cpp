// PNG decoding through libpng with every checksum verified (issue 17): the CRC of every chunk,
// critical and ancillary, and the zlib stream's Adler-32. stb_image checks neither, so a
// corrupted PNG used to load with changed pixels.
//
// libpng's simplified API (png_image_begin_read_*) is not used: it reads with benign errors as
// warnings and the default CRC action (a bad ancillary CRC discards the chunk with a warning),
// and a bad Adler-32 that libpng only meets after the last row is a benign error, so it would
// pass. The full API is used with
//   * png_set_crc_action(PNG_CRC_ERROR_QUIT, PNG_CRC_ERROR_QUIT): a CRC error in any chunk is
//     an error;
//   * png_set_benign_errors(0): "benign" errors are errors, among them a bad Adler-32 or extra
//     data after the zlib stream (both found only while finishing the IDAT stream), extra image
//     data, a palette index past the palette, a non-empty IEND;
//   * png_set_keep_unknown_chunks(NEVER, all): the ancillary chunks libpng knows (gAMA, iCCP,
//     text, ...) except tRNS are skipped unparsed, so a quirk in metadata the loader ignores
//     anyway (stb_image ignores it too) does not become an error now that benign errors are
//     fatal; their CRC is still checked. Unknown critical chunks remain errors.
// PNG_IGNORE_ADLER32 is left at libpng's default (checked).
//
// libpng reports errors with png_longjmp. The two functions that call setjmp (read_header and
// read_rows) own nothing with a destructor, the callbacks neither throw nor own anything, and
// every C++ object (the buffers, the image, the png_struct guard) lives in decode_png, which
// no longjmp crosses.
//
// The grey conversion is the one stb_image's path applied (image_io.cpp): samples expanded to
// 8 bits (1/2/4-bit grey scaled by 255, 85, 17; palette entries to RGB), 16-bit samples
// reduced to their high byte (png_set_strip_16, as stb's 16-to-8 conversion), alpha ignored,
// RGB to luma(). A palette index past the end of the palette is an error (stb_image read
// whatever followed the palette).
#include <png.h>
#include <setjmp.h>
#include <stdio.h>
#include <string.h>

#include <new>
#include <string>
#include <utility>
#include <vector>

#include "formats.h"

namespace seqslam::tools::detail {
namespace {

// Everything the callbacks touch: plain data.
struct PngInput {
  const uint8_t* data = nullptr;
  size_t size = 0;
  size_t pos = 0;
  char error[256] = {};
  char warning[256] = {};  // the first warning (libpng warns with the detail, then fails)
};

// The decoded layout after libpng's transformations: 8-bit samples, 1..4 channels; palette
// images one byte per pixel, the palette index.
struct PngLayout {
  png_uint_32 width = 0;
  png_uint_32 height = 0;
  size_t channels = 0;
  size_t row_bytes = 0;
  int passes = 1;
  png_colorp palette = nullptr;  // owned by the png_info; null unless a palette image
  int palette_size = 0;
};

[[noreturn]] void on_png_error(png_structp png, png_const_charp message) {
  auto* input = static_cast<PngInput*>(png_get_error_ptr(png));
  snprintf(input->error, sizeof input->error, "%s", message != nullptr ? message : "error");
  png_longjmp(png, 1);
}

void on_png_warning(png_structp png, png_const_charp message) {
  auto* input = static_cast<PngInput*>(png_get_error_ptr(png));
  if (input->warning[0] == '\0' && message != nullptr) {
    snprintf(input->warning, sizeof input->warning, "%s", message);
  }
}

void read_png_bytes(png_structp png, png_bytep out, size_t count) {
  auto* input = static_cast<PngInput*>(png_get_io_ptr(png));
  if (count > input->size - input->pos) png_error(png, "unexpected end of file");
  memcpy(out, input->data + input->pos, count);
  input->pos += count;
}

// Reads the chunks up to the first IDAT and sets up the transformations. False after a libpng
// error (the message is in the PngInput).
bool read_header(png_structp png, png_infop info, PngLayout* layout) {
  if (setjmp(png_jmpbuf(png)) != 0) return false;
  png_set_crc_action(png, PNG_CRC_ERROR_QUIT, PNG_CRC_ERROR_QUIT);
  png_set_benign_errors(png, 0);
  png_set_keep_unknown_chunks(png, PNG_HANDLE_CHUNK_NEVER, nullptr, -1);
  // Skipped chunks are not buffered, so no limit on their size (the default 8 MB limit is a
  // "benign" error, now fatal). The image size is limited as the other formats are.
  png_set_chunk_malloc_max(png, 0);
  png_set_user_limits(png, kMaxLoadSide, kMaxLoadSide);
  png_read_info(png, info);

  if (png_get_color_type(png, info) == PNG_COLOR_TYPE_PALETTE) {
    // Indices, one per byte, looked up here: libpng's expansion turns an index past the end of
    // the palette into black without an error (its check runs only on unexpanded rows).
    png_set_packing(png);
    if (png_get_PLTE(png, info, &layout->palette, &layout->palette_size) == 0) {
      png_error(png, "no palette");
    }
  } else {
    png_set_expand(png);  // grey 1/2/4 -> 8 bits (scaled), tRNS -> alpha
  }
  png_set_strip_16(png);  // 16 -> 8 bits: the high byte
  layout->passes = png_set_interlace_handling(png);
  png_read_update_info(png, info);
  layout->width = png_get_image_width(png, info);
  layout->height = png_get_image_height(png, info);
  layout->channels = png_get_channels(png, info);
  layout->row_bytes = png_get_rowbytes(png, info);
  return true;
}

// 1 = grey, 2 = grey + alpha, 3 = RGB, 4 = RGBA; alpha is ignored. Palette images: the
// luma of the entry. False at an index past the end of the palette.
bool row_to_gray(const uint8_t* row, const PngLayout& layout, uint8_t* gray) {
  if (layout.palette != nullptr) {
    for (png_uint_32 x = 0; x < layout.width; ++x) {
      if (row[x] >= layout.palette_size) return false;
      const png_color& c = layout.palette[row[x]];
      gray[x] = luma(c.red, c.green, c.blue);
    }
    return true;
  }
  const size_t step = layout.channels;
  for (png_uint_32 x = 0; x < layout.width; ++x) {
    const uint8_t* px = row + size_t{x} * step;
    gray[x] = step >= 3 ? luma(px[0], px[1], px[2]) : px[0];
  }
  return true;
}

[[noreturn]] void bad_palette_index(png_structp png, const PngLayout& layout) {
  char message[96];
  snprintf(message, sizeof message, "a palette index is past the end of the %d-entry palette",
           layout.palette_size);
  png_error(png, message);
}

// Decodes the rows into `gray` (width * height) and reads the rest of the file up to IEND,
// which finishes (and checks) the zlib stream and the CRCs of the chunks after the image data.
// `rows` holds one row, or the whole image when interlaced (passes > 1). False after a libpng
// error.
bool read_rows(png_structp png, png_infop info, const PngLayout& layout, uint8_t* rows,
               uint8_t* gray) {
  if (setjmp(png_jmpbuf(png)) != 0) return false;
  const bool whole_image = layout.passes > 1;
  for (int pass = 0; pass < layout.passes; ++pass) {
    for (png_uint_32 y = 0; y < layout.height; ++y) {
      uint8_t* row = rows + (whole_image ? size_t{y} * layout.row_bytes : 0);
      png_read_row(png, row, nullptr);
      if (!whole_image && !row_to_gray(row, layout, gray + size_t{y} * layout.width)) {
        bad_palette_index(png, layout);
      }
    }
  }
  if (whole_image) {
    for (png_uint_32 y = 0; y < layout.height; ++y) {
      if (!row_to_gray(rows + size_t{y} * layout.row_bytes, layout,
                       gray + size_t{y} * layout.width)) {
        bad_palette_index(png, layout);
      }
    }
  }
  png_read_end(png, info);
  return true;
}

// Owns the libpng read structures.
class PngReadGuard {
 public:
  explicit PngReadGuard(PngInput* input) {
    png_ = png_create_read_struct(PNG_LIBPNG_VER_STRING, input, on_png_error, on_png_warning);
    if (png_ != nullptr) info_ = png_create_info_struct(png_);
    if (info_ != nullptr) png_set_read_fn(png_, input, read_png_bytes);
  }
  ~PngReadGuard() {
    if (png_ != nullptr)
      png_destroy_read_struct(&png_, info_ != nullptr ? &info_ : nullptr, nullptr);
  }
  PngReadGuard(const PngReadGuard&) = delete;
  PngReadGuard& operator=(const PngReadGuard&) = delete;

  png_structp png() const { return png_; }
  png_infop info() const { return info_; }

 private:
  png_structp png_ = nullptr;
  png_infop info_ = nullptr;
};

Error png_error_from(const PngInput& input) {
  std::string reason = input.error[0] != '\0' ? input.error : "unknown libpng error";
  // libpng warns with the detail of some errors first ("Invalid bit depth in IHDR", then the
  // error "Invalid IHDR data").
  if (input.warning[0] != '\0') reason += std::string(" (") + input.warning + ")";
  return Error{"not a valid PNG: " + reason};
}

}  // namespace

Outcome<GrayImage> decode_png(const uint8_t* data, size_t size) {
  PngInput input;
  input.data = data;
  input.size = size;
  PngReadGuard reader(&input);
  if (reader.info() == nullptr) return Error{"not a valid PNG: libpng could not start"};

  PngLayout layout;
  if (!read_header(reader.png(), reader.info(), &layout)) return png_error_from(input);
  std::string error;
  if (!check_dimensions(layout.width, layout.height, &error)) return Error{error};
  if (layout.channels < 1 || layout.channels > 4 ||
      layout.row_bytes != size_t{layout.width} * layout.channels) {
    return Error{"not a valid PNG: unexpected decoded layout (" + std::to_string(layout.channels) +
                 " channels, " + std::to_string(layout.row_bytes) + " bytes per row)"};
  }

  GrayImage image;
  std::vector<uint8_t> rows;
  try {
    rows.resize(layout.row_bytes * (layout.passes > 1 ? size_t{layout.height} : 1));
    image.pixels.resize(size_t{layout.width} * layout.height);
  } catch (const std::bad_alloc&) {
    return Error{"out of memory decoding a " + std::to_string(layout.width) + "x" +
                 std::to_string(layout.height) + " PNG"};
  }
  if (!read_rows(reader.png(), reader.info(), layout, rows.data(), image.pixels.data())) {
    return png_error_from(input);
  }
  image.width = static_cast<int>(layout.width);
  image.height = static_cast<int>(layout.height);
  return Outcome<GrayImage>(std::move(image));
}

}  // namespace seqslam::tools::detail
