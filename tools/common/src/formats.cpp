// Container walks for PNG, JPEG and BMP. They do not decode pixels; they make sure the file is
// complete and its header sane before stb_image (which pads missing data with zeros for some
// formats) is allowed to decode it.
#include <algorithm>
#include <string>

#include "file_util.h"
#include "formats.h"

namespace seqslam::tools::detail {
namespace {

uint32_t be16(const uint8_t* p) {
  return (uint32_t{p[0]} << 8) | p[1];
}
uint32_t be32(const uint8_t* p) {
  return (uint32_t{p[0]} << 24) | (uint32_t{p[1]} << 16) | (uint32_t{p[2]} << 8) | p[3];
}
uint32_t le16(const uint8_t* p) {
  return (uint32_t{p[1]} << 8) | p[0];
}
uint32_t le32(const uint8_t* p) {
  return (uint32_t{p[3]} << 24) | (uint32_t{p[2]} << 16) | (uint32_t{p[1]} << 8) | p[0];
}

std::string at_byte(size_t pos) {
  return " at byte " + std::to_string(pos);
}

std::string hex_byte(uint32_t b) {
  static constexpr char kHex[] = "0123456789ABCDEF";
  std::string s = "0xFF";
  s += kHex[(b >> 4) & 0xf];
  s += kHex[b & 0xf];
  return s;
}

// Deflate's best case: one 258-byte match per 2-bit code, about 1032:1; rounded up.
constexpr uint64_t kMaxDeflateRatio = 1100;

bool is_sof_marker(uint32_t m) {
  return m >= 0xC0 && m <= 0xCF && m != 0xC4 && m != 0xC8 && m != 0xCC;
}

}  // namespace

bool check_dimensions(int64_t width, int64_t height, std::string* error) {
  const std::string size = std::to_string(width) + "x" + std::to_string(height);
  if (width <= 0 || height <= 0) {
    *error = "image width or height is zero or negative (" + size + ")";
    return false;
  }
  if (width > kMaxLoadSide || height > kMaxLoadSide) {
    *error = "image dimensions " + size + " are absurd (more than " + std::to_string(kMaxLoadSide) +
             " pixels per side); the header is probably corrupt";
    return false;
  }
  return true;
}

Outcome<Dims> check_png_structure(const uint8_t* data, size_t size) {
  static constexpr uint8_t kSignature[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
  for (size_t i = 0; i < 8; ++i) {
    if (i >= size) return Error{"truncated PNG: the file ends inside the signature"};
    if (data[i] != kSignature[i]) return Error{"not a PNG file (bad signature)"};
  }
  Dims dims;
  bool first = true;
  bool have_idat = false;
  uint64_t idat_bytes = 0;
  uint64_t raw_bytes = 0;  // filtered scanlines the IHDR promises (without interlacing)
  size_t pos = 8;
  for (;;) {
    if (pos >= size) {
      return Error{"truncated PNG: no IEND chunk (the file ends after " + std::to_string(size) +
                   " bytes)"};
    }
    if (size - pos < 8) return Error{"truncated PNG: chunk header cut off" + at_byte(pos)};
    const uint32_t length = be32(data + pos);
    const std::string type(reinterpret_cast<const char*>(data + pos + 4), 4);
    if (length > 0x7fffffffu) {
      return Error{"corrupt PNG: chunk '" + printable(type) + "'" + at_byte(pos) +
                   " has an impossible length " + std::to_string(length)};
    }
    if (uint64_t{size - pos - 8} < uint64_t{length} + 4) {
      return Error{"truncated PNG: chunk '" + printable(type) + "'" + at_byte(pos) + " needs " +
                   std::to_string(uint64_t{length} + 12) + " bytes, only " +
                   std::to_string(size - pos) + " left"};
    }
    if (first) {
      if (type != "IHDR" || length != 13) {
        return Error{"corrupt PNG: the first chunk is not a 13-byte IHDR"};
      }
      const uint32_t w = be32(data + pos + 8);
      const uint32_t h = be32(data + pos + 12);
      std::string error;
      if (!check_dimensions(w, h, &error)) return Error{error};
      dims.width = w;
      dims.height = h;
      const uint32_t depth = data[pos + 16];
      const uint32_t colour_type = data[pos + 17];
      const uint32_t channels = colour_type == 2   ? 3
                                : colour_type == 4 ? 2
                                : colour_type == 6 ? 4
                                                   : 1;
      raw_bytes = (uint64_t{w} * depth * channels + 7) / 8 * h + h;
      first = false;
    }
    if (type == "IDAT") {
      have_idat = true;
      idat_bytes += length;
    }
    if (type == "IEND") break;
    pos += 12 + size_t{length};
  }
  if (!have_idat) return Error{"corrupt PNG: no IDAT chunk (no image data)"};
  // Deflate cannot compress better than about 1032:1. Far less data than that means missing
  // image data, and refusing here spares stb_image allocating the full image for nothing.
  if (idat_bytes * kMaxDeflateRatio + 1024 < raw_bytes) {
    return Error{"corrupt PNG: " + std::to_string(idat_bytes) +
                 " bytes of compressed data cannot hold a " + std::to_string(dims.width) + "x" +
                 std::to_string(dims.height) + " image"};
  }
  return dims;
}

Outcome<Dims> check_jpeg_structure(const uint8_t* data, size_t size) {
  if (size < 2 || data[0] != 0xFF || data[1] != 0xD8) return Error{"not a JPEG file (no SOI)"};
  Dims dims;
  bool have_frame = false;
  bool have_scan = false;
  bool huffman_frame = false;  // SOF0/1/2: the kinds stb_image decodes
  uint64_t min_scan_bits = 0;  // lower bound on the entropy-coded data of the frame
  uint64_t scan_bytes = 0;
  size_t pos = 2;
  for (;;) {
    // Next marker: tolerate stray bytes before it (as libjpeg does) and 0xFF fill bytes.
    while (pos < size && data[pos] != 0xFF)
      ++pos;
    while (pos < size && data[pos] == 0xFF)
      ++pos;
    if (pos >= size) {
      return Error{"truncated JPEG: no end-of-image (EOI) marker (the file ends after " +
                   std::to_string(size) + " bytes)"};
    }
    const uint32_t marker = data[pos];
    const size_t marker_pos = pos - 1;
    ++pos;
    if (marker == 0xD9) break;  // EOI
    // Standalone markers: TEM, RSTn, SOI, and a stuffed 0xFF00 outside a scan (junk).
    if (marker == 0x00 || marker == 0x01 || (marker >= 0xD0 && marker <= 0xD8)) continue;
    if (size - pos < 2) {
      return Error{"truncated JPEG: segment " + hex_byte(marker) + at_byte(marker_pos) +
                   " is cut off"};
    }
    const uint32_t length = be16(data + pos);
    if (length < 2) {
      return Error{"corrupt JPEG: segment " + hex_byte(marker) + at_byte(marker_pos) +
                   " has length " + std::to_string(length)};
    }
    if (size - pos < length) {
      return Error{"truncated JPEG: segment " + hex_byte(marker) + at_byte(marker_pos) + " needs " +
                   std::to_string(length) + " bytes, only " + std::to_string(size - pos) + " left"};
    }
    if (is_sof_marker(marker) && !have_frame) {
      if (length < 8) return Error{"corrupt JPEG: frame header too short"};
      const uint32_t h = be16(data + pos + 3);
      const uint32_t w = be16(data + pos + 5);
      std::string error;
      if (!check_dimensions(w, h, &error)) return Error{error};
      dims.width = w;
      dims.height = h;
      have_frame = true;
      huffman_frame = marker <= 0xC2;
      // Every 8x8 block of every component is coded with at least one bit (a 1-bit Huffman
      // code for DC difference 0); the component with the most blocks bounds the data.
      const uint32_t components = data[pos + 7];
      if (length < 8 + 3 * components || components == 0) {
        return Error{"corrupt JPEG: bad frame header"};
      }
      uint32_t h_max = 1;
      uint32_t v_max = 1;
      for (size_t c = 0; c < components; ++c) {
        const uint32_t sampling = data[pos + 9 + 3 * c];
        h_max = std::max(h_max, sampling >> 4);
        v_max = std::max(v_max, sampling & 15u);
      }
      for (size_t c = 0; c < components; ++c) {
        const uint32_t sampling = data[pos + 9 + 3 * c];
        const uint64_t hc = std::max(1u, sampling >> 4);
        const uint64_t vc = std::max(1u, sampling & 15u);
        const uint64_t cw = (w * hc + h_max - 1) / h_max;
        const uint64_t ch = (h * vc + v_max - 1) / v_max;
        min_scan_bits = std::max(min_scan_bits, ((cw + 7) / 8) * ((ch + 7) / 8));
      }
    }
    pos += length;
    if (marker == 0xDA) {  // SOS: entropy-coded data follows, up to the next real marker
      if (!have_frame)
        return Error{"corrupt JPEG: scan" + at_byte(marker_pos) + " before any frame header"};
      have_scan = true;
      const size_t scan_start = pos;
      for (;;) {
        if (size - pos < 2) {
          return Error{"truncated JPEG: the scan data" + at_byte(marker_pos) +
                       " runs to the end of the file (no EOI marker)"};
        }
        if (data[pos] != 0xFF) {
          ++pos;
          continue;
        }
        const uint8_t next = data[pos + 1];
        if (next == 0x00 || (next >= 0xD0 && next <= 0xD7)) {
          pos += 2;  // stuffed byte or restart marker: still entropy-coded data
        } else if (next == 0xFF) {
          ++pos;  // fill byte
        } else {
          break;  // a real marker starts at pos
        }
      }
      scan_bytes += pos - scan_start;
    }
  }
  if (!have_frame) return Error{"corrupt JPEG: no frame header (SOF)"};
  if (!have_scan) return Error{"corrupt JPEG: no image data (SOS)"};
  // Far too little data for the frame: reject before stb_image allocates (and decodes) a
  // full-size image from padding.
  if (huffman_frame && scan_bytes * 8 < min_scan_bits) {
    return Error{"corrupt JPEG: " + std::to_string(scan_bytes) +
                 " bytes of scan data cannot hold a " + std::to_string(dims.width) + "x" +
                 std::to_string(dims.height) + " image"};
  }
  return dims;
}

Outcome<Dims> check_bmp_structure(const uint8_t* data, size_t size) {
  if (size < 2 || data[0] != 'B' || data[1] != 'M') return Error{"not a BMP file"};
  if (size < 18) return Error{"truncated BMP: the file header is cut off"};
  const uint32_t data_offset = le32(data + 10);
  const uint32_t header_size = le32(data + 14);
  int64_t width = 0;
  int64_t height = 0;
  uint32_t bits = 0;
  uint32_t compression = 0;
  if (header_size == 12) {
    if (size < 26) return Error{"truncated BMP: the info header is cut off"};
    width = le16(data + 18);
    height = le16(data + 20);
    bits = le16(data + 24);
  } else if (header_size >= 40 && header_size <= 4096) {
    if (size < 14 + size_t{40}) return Error{"truncated BMP: the info header is cut off"};
    width = static_cast<int32_t>(le32(data + 18));
    height = static_cast<int32_t>(le32(data + 22));
    bits = le16(data + 28);
    compression = le32(data + 30);
  } else {
    return Error{"corrupt BMP: unsupported info header size " + std::to_string(header_size)};
  }
  if (height < 0) height = -height;  // top-down rows; int64 holds -INT32_MIN
  std::string error;
  if (!check_dimensions(width, height, &error)) return Error{error};
  // stb_image reads BI_RGB and BI_BITFIELDS only; for both the pixel array size is known.
  if (compression != 0 && compression != 3) {
    return Error{"unsupported BMP compression " + std::to_string(compression) +
                 " (only uncompressed and bitfield BMPs are read)"};
  }
  {
    if (bits != 1 && bits != 4 && bits != 8 && bits != 16 && bits != 24 && bits != 32) {
      return Error{"corrupt BMP: unsupported " + std::to_string(bits) + " bits per pixel"};
    }
    const uint64_t stride = (static_cast<uint64_t>(width) * bits + 31) / 32 * 4;
    const uint64_t needed = stride * static_cast<uint64_t>(height);
    if (data_offset > size || size - data_offset < needed) {
      return Error{"truncated BMP: the pixel data needs " + std::to_string(needed) +
                   " bytes from offset " + std::to_string(data_offset) + ", the file has " +
                   std::to_string(size) + " bytes"};
    }
  }
  Dims dims;
  dims.width = width;
  dims.height = height;
  return dims;
}

}  // namespace seqslam::tools::detail
