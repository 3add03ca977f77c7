// PNG test files for the image loader's tests and fuzz target (host only, header only):
//   * write(): a PNG of any colour type, bit depth, palette, tRNS and interlacing, written by
//     libpng from known samples, and expected_gray(): what the loader must make of it,
//     computed from the samples alone (image_io.h: samples to 8 bits, 16-bit to the high byte,
//     alpha ignored, colour to luma());
//   * stb_gray(): the loader's PNG path before libpng (stb_image and the same grey conversion),
//     the reference for "the pixels of valid files did not change";
//   * chunk helpers to corrupt files: the chunk list, CRC recomputation, the zlib stream.
// Links PNG::PNG (and ZLIB::ZLIB) and seqslam_stb.
#pragma once

#include <png.h>
#include <setjmp.h>
#include <stb_image.h>
#include <stddef.h>
#include <stdint.h>
#include <zlib.h>

#include <string>
#include <utility>
#include <vector>

#include "seqslam_tools/image_io.h"

namespace seqslam::test_png {

struct Spec {
  uint32_t width = 1;
  uint32_t height = 1;
  int colour_type = PNG_COLOR_TYPE_GRAY;
  int bit_depth = 8;
  bool interlaced = false;
  // width * height * channels() samples, row-major, each below 2^bit_depth; palette images:
  // one index per pixel, below palette.size().
  std::vector<uint16_t> samples;
  std::vector<png_color> palette;      // palette images
  std::vector<uint8_t> palette_alpha;  // tRNS of a palette image (may be shorter than palette)
  bool has_key = false;                // tRNS of a grey or RGB image: one transparent colour
  png_color_16 key{};

  int channels() const {
    switch (colour_type) {
      case PNG_COLOR_TYPE_GRAY_ALPHA:
        return 2;
      case PNG_COLOR_TYPE_RGB:
        return 3;
      case PNG_COLOR_TYPE_RGB_ALPHA:
        return 4;
      default:
        return 1;
    }
  }
};

// The bit depths PNG allows for a colour type.
inline std::vector<int> depths_of(int colour_type) {
  switch (colour_type) {
    case PNG_COLOR_TYPE_GRAY:
      return {1, 2, 4, 8, 16};
    case PNG_COLOR_TYPE_PALETTE:
      return {1, 2, 4, 8};
    default:
      return {8, 16};
  }
}

// A deterministic spec with pseudo-random samples; with_trns adds tRNS (palette alpha or a
// key colour).
inline Spec make_spec(int colour_type, int bit_depth, bool interlaced, uint32_t width,
                      uint32_t height, uint32_t seed, bool with_trns) {
  Spec s;
  s.width = width;
  s.height = height;
  s.colour_type = colour_type;
  s.bit_depth = bit_depth;
  s.interlaced = interlaced;
  uint32_t state = seed * 2654435761u + 1u;
  auto next = [&state] {
    state = state * 1103515245u + 12345u;
    return state >> 8;
  };
  const uint32_t levels = bit_depth == 16 ? 65536u : (1u << bit_depth);
  if (colour_type == PNG_COLOR_TYPE_PALETTE) {
    const uint32_t entries = 1 + next() % levels;
    for (uint32_t i = 0; i < entries; ++i) {
      s.palette.push_back(png_color{static_cast<png_byte>(next()), static_cast<png_byte>(next()),
                                    static_cast<png_byte>(next())});
    }
    if (with_trns) s.palette_alpha.assign(1 + next() % entries, 128);
  } else if (with_trns &&
             (colour_type == PNG_COLOR_TYPE_GRAY || colour_type == PNG_COLOR_TYPE_RGB)) {
    s.has_key = true;
    s.key.gray = static_cast<png_uint_16>(next() % levels);
    s.key.red = static_cast<png_uint_16>(next() % levels);
    s.key.green = static_cast<png_uint_16>(next() % levels);
    s.key.blue = static_cast<png_uint_16>(next() % levels);
  }
  const size_t count = size_t{width} * height * static_cast<size_t>(s.channels());
  const uint32_t limit =
      colour_type == PNG_COLOR_TYPE_PALETTE ? static_cast<uint32_t>(s.palette.size()) : levels;
  for (size_t i = 0; i < count; ++i)
    s.samples.push_back(static_cast<uint16_t>(next() % limit));
  // Make the key colour occur when there is one.
  if (s.has_key && !s.samples.empty()) {
    s.samples[0] = colour_type == PNG_COLOR_TYPE_GRAY ? s.key.gray : s.key.red;
    if (colour_type == PNG_COLOR_TYPE_RGB) {
      s.samples[1] = s.key.green;
      s.samples[2] = s.key.blue;
    }
  }
  return s;
}

// One sample scaled to 8 bits as PNG decoders (and stb_image) do.
inline uint8_t to8(uint32_t v, int bit_depth) {
  switch (bit_depth) {
    case 16:
      return static_cast<uint8_t>(v >> 8);
    case 4:
      return static_cast<uint8_t>(v * 0x11);
    case 2:
      return static_cast<uint8_t>(v * 0x55);
    case 1:
      return static_cast<uint8_t>(v * 0xff);
    default:
      return static_cast<uint8_t>(v);
  }
}

// What load_gray must return for write(s).
inline std::vector<uint8_t> expected_gray(const Spec& s) {
  const size_t n = static_cast<size_t>(s.channels());
  std::vector<uint8_t> out(size_t{s.width} * s.height);
  for (size_t i = 0; i < out.size(); ++i) {
    const uint16_t* px = s.samples.data() + i * n;
    if (s.colour_type == PNG_COLOR_TYPE_PALETTE) {
      const png_color& c = s.palette[px[0]];
      out[i] = tools::luma(c.red, c.green, c.blue);
    } else if (n >= 3) {
      out[i] =
          tools::luma(to8(px[0], s.bit_depth), to8(px[1], s.bit_depth), to8(px[2], s.bit_depth));
    } else {
      out[i] = to8(px[0], s.bit_depth);
    }
  }
  return out;
}

// The packed rows of s (PNG sample layout: big-endian 16-bit, sub-byte samples MSB first).
inline std::vector<uint8_t> pack_rows(const Spec& s, size_t* row_bytes) {
  const size_t per_row = size_t{s.width} * static_cast<size_t>(s.channels());
  *row_bytes = (per_row * static_cast<size_t>(s.bit_depth) + 7) / 8;
  std::vector<uint8_t> rows(*row_bytes * s.height, 0);
  for (size_t y = 0; y < s.height; ++y) {
    uint8_t* row = rows.data() + y * *row_bytes;
    for (size_t k = 0; k < per_row; ++k) {
      const uint32_t v = s.samples[y * per_row + k];
      if (s.bit_depth == 16) {
        row[2 * k] = static_cast<uint8_t>(v >> 8);
        row[2 * k + 1] = static_cast<uint8_t>(v);
      } else if (s.bit_depth == 8) {
        row[k] = static_cast<uint8_t>(v);
      } else {
        const size_t bit = k * static_cast<size_t>(s.bit_depth);
        const size_t shift = 8 - static_cast<size_t>(s.bit_depth) - bit % 8;
        row[bit / 8] = static_cast<uint8_t>(row[bit / 8] | (v << shift));
      }
    }
  }
  return rows;
}

namespace detail {

struct Sink {
  std::vector<uint8_t>* out = nullptr;
  bool failed = false;
};

inline void sink_write(png_structp png, png_bytep data, size_t size) {
  auto* sink = static_cast<Sink*>(png_get_io_ptr(png));
  try {
    sink->out->insert(sink->out->end(), data, data + size);
  } catch (...) {
    sink->failed = true;
  }
  if (sink->failed) png_error(png, "out of memory");
}

inline void sink_flush(png_structp) {}

[[noreturn]] inline void quiet_error(png_structp png, png_const_charp) {
  png_longjmp(png, 1);
}

inline void quiet_warning(png_structp, png_const_charp) {}

// The setjmp frame: nothing with a destructor.
inline bool write_png(png_structp png, png_infop info, const Spec& s, png_bytepp rows) {
  if (setjmp(png_jmpbuf(png)) != 0) return false;
  png_set_IHDR(png, info, s.width, s.height, s.bit_depth, s.colour_type,
               s.interlaced ? PNG_INTERLACE_ADAM7 : PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  if (!s.palette.empty()) {
    png_set_PLTE(png, info, s.palette.data(), static_cast<int>(s.palette.size()));
  }
  if (!s.palette_alpha.empty()) {
    png_set_tRNS(png, info, s.palette_alpha.data(), static_cast<int>(s.palette_alpha.size()),
                 nullptr);
  }
  if (s.has_key) png_set_tRNS(png, info, nullptr, 0, &s.key);
  png_write_info(png, info);
  png_write_image(png, rows);
  png_write_end(png, info);
  return true;
}

}  // namespace detail

// The PNG of s written by libpng; empty if libpng refused the spec.
inline std::vector<uint8_t> write(const Spec& s) {
  size_t row_bytes = 0;
  std::vector<uint8_t> rows = pack_rows(s, &row_bytes);
  std::vector<png_bytep> row_pointers(s.height);
  for (size_t y = 0; y < s.height; ++y)
    row_pointers[y] = rows.data() + y * row_bytes;
  std::vector<uint8_t> out;
  detail::Sink sink;
  sink.out = &out;
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, detail::quiet_error,
                                            detail::quiet_warning);
  png_infop info = png != nullptr ? png_create_info_struct(png) : nullptr;
  bool ok = false;
  if (info != nullptr) {
    png_set_write_fn(png, &sink, detail::sink_write, detail::sink_flush);
    ok = detail::write_png(png, info, s, row_pointers.data());
  }
  png_destroy_write_struct(&png, &info);
  if (!ok) out.clear();
  return out;
}

// The loader's PNG path before libpng: stb_image, then the same grey conversion. False when
// stb_image refuses the file.
inline bool stb_gray(const std::vector<uint8_t>& bytes, int* width, int* height,
                     std::vector<uint8_t>* gray) {
  int n = 0;
  stbi_uc* decoded =
      stbi_load_from_memory(bytes.data(), static_cast<int>(bytes.size()), width, height, &n, 0);
  if (decoded == nullptr) return false;
  const size_t count = static_cast<size_t>(*width) * static_cast<size_t>(*height);
  const size_t step = static_cast<size_t>(n);
  gray->resize(count);
  for (size_t i = 0; i < count; ++i) {
    const stbi_uc* px = decoded + i * step;
    (*gray)[i] = step >= 3 ? tools::luma(px[0], px[1], px[2]) : px[0];
  }
  stbi_image_free(decoded);
  return true;
}

inline uint32_t be32(const uint8_t* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | p[3];
}

inline void put_be32(uint8_t* p, uint32_t v) {
  p[0] = static_cast<uint8_t>(v >> 24);
  p[1] = static_cast<uint8_t>(v >> 16);
  p[2] = static_cast<uint8_t>(v >> 8);
  p[3] = static_cast<uint8_t>(v);
}

// One chunk: `offset` is where its length field starts; type and data follow from offset + 4,
// the CRC from offset + 8 + length.
struct Chunk {
  size_t offset = 0;
  uint32_t length = 0;
  std::string type;
  size_t data() const { return offset + 8; }
  size_t crc() const { return offset + 8 + length; }
  size_t end() const { return offset + 12 + length; }
};

// The chunks after the signature, up to the first that does not fit in the file.
inline std::vector<Chunk> chunks(const std::vector<uint8_t>& png) {
  std::vector<Chunk> list;
  size_t pos = 8;
  while (pos <= png.size() && png.size() - pos >= 12) {
    Chunk c;
    c.offset = pos;
    c.length = be32(png.data() + pos);
    c.type.assign(reinterpret_cast<const char*>(png.data() + pos + 4), 4);
    if (png.size() - pos - 12 < c.length) break;
    list.push_back(c);
    pos = c.end();
  }
  return list;
}

// The CRC-32 of a chunk's type and data.
inline uint32_t chunk_crc(const std::vector<uint8_t>& png, const Chunk& c) {
  return static_cast<uint32_t>(
      crc32(0, png.data() + c.offset + 4, static_cast<uInt>(c.length) + 4u));
}

inline void fix_crc(std::vector<uint8_t>* png, const Chunk& c) {
  put_be32(png->data() + c.crc(), chunk_crc(*png, c));
}

// Recomputes the CRC of every chunk that fits in the file.
inline void fix_all_crcs(std::vector<uint8_t>* png) {
  for (const Chunk& c : chunks(*png))
    fix_crc(png, c);
}

// Replaces the data of chunk `index` (length and CRC recomputed).
inline void replace_chunk_data(std::vector<uint8_t>* png, size_t index,
                               const std::vector<uint8_t>& data) {
  const Chunk c = chunks(*png).at(index);
  std::vector<uint8_t> out(png->begin(), png->begin() + static_cast<ptrdiff_t>(c.offset));
  out.resize(out.size() + 8);
  put_be32(out.data() + c.offset, static_cast<uint32_t>(data.size()));
  for (size_t k = 0; k < 4; ++k)
    out[c.offset + 4 + k] = static_cast<uint8_t>(c.type[k]);
  out.insert(out.end(), data.begin(), data.end());
  out.resize(out.size() + 4);
  out.insert(out.end(), png->begin() + static_cast<ptrdiff_t>(c.end()), png->end());
  *png = std::move(out);
  fix_crc(png, chunks(*png).at(index));
}

// Inserts a chunk (CRC computed) before chunk `index`.
inline void insert_chunk(std::vector<uint8_t>* png, size_t index, const std::string& type,
                         const std::vector<uint8_t>& data) {
  const size_t at = chunks(*png).at(index).offset;
  std::vector<uint8_t> chunk(8);
  put_be32(chunk.data(), static_cast<uint32_t>(data.size()));
  for (size_t k = 0; k < 4; ++k)
    chunk[4 + k] = static_cast<uint8_t>(type[k]);
  chunk.insert(chunk.end(), data.begin(), data.end());
  chunk.resize(chunk.size() + 4);
  png->insert(png->begin() + static_cast<ptrdiff_t>(at), chunk.begin(), chunk.end());
  fix_crc(png, chunks(*png).at(index));
}

}  // namespace seqslam::test_png
